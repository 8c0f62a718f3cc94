//! Bidirectional positioning runs of one axis (laser interferometer, ISO 230-2 style).

use mte_linalg::{DMat, DVec};

use super::machine::{LINEAR_LIMIT_MM, ROTARY_LIMIT_DEG, read_times};
use crate::Result;
use crate::candidate::{SlotEffect, SlotRole};
use crate::data::{Observations, Variable, VariableKind};
use crate::dataset::{ManifestFile, dataset_manifest};
use crate::model::{DriftOf, Effects, ObservationModel};
use crate::term::{Family, Quantity, Summary, Term};

dataset_manifest!(
    /// The manifest of axis runs (`"kind": "axis"`).
    Manifest {
        noise_arcsec: Option<f64>,
        axis: Option<String>,
    }
);

/// Positioning runs of one axis: columns `run`, `direction` (+1/−1), `<axis>_mm` (or
/// `<axis>_deg` for a rotary axis), optional `t_s`, and `deviation_um` (measured minus
/// commanded position; `deviation_arcsec` for a rotary axis).
pub struct AxisRuns {
    observations: Observations,
    axis: String,
    title: String,
}

impl AxisRuns {
    /// Reads the runs a manifest names; `noise_um` applies where the manifest states none.
    pub(crate) fn read(
        file: &ManifestFile,
        noise_um: Option<f64>,
    ) -> Result<(Self, Option<serde_json::Value>)> {
        let mut manifest: Manifest = file.parse()?;
        if manifest.noise_um.is_none() && manifest.noise_arcsec.is_none() {
            manifest.noise_um = noise_um;
        }
        file.check_noise("noise_um", manifest.noise_um)?;
        file.check_noise("noise_arcsec", manifest.noise_arcsec)?;
        let table = file.table(&manifest.data)?;
        let axis = manifest
            .axis
            .clone()
            .ok_or_else(|| file.missing("axis", "the name of the axis measured, e.g. \"X\""))?;
        let lower = axis.to_lowercase();
        let (pos_col, rotary) = match (
            table.column(&format!("{lower}_mm")),
            table.column(&format!("{lower}_deg")),
        ) {
            (Some(c), _) => (c, false),
            (None, Some(c)) => (c, true),
            (None, None) => {
                return Err(table
                    .error(
                        table.header_line,
                        format!("missing column `{lower}_mm` (or `{lower}_deg`) with the commanded position of {axis}"),
                    )
                    .into());
            }
        };
        let n = table.len();
        if n == 0 {
            return Err(crate::DiagnoseError::Dataset {
                path: table.source_name.clone(),
                detail: "no observations".into(),
            });
        }
        let mut position = if rotary {
            table.numbers_within(
                pos_col,
                ROTARY_LIMIT_DEG,
                "a rotary axis command of 10⁶° or more is no machine position",
            )?
        } else {
            table.numbers_within(
                pos_col,
                LINEAR_LIMIT_MM,
                "a linear axis command of 10 km or more is no machine position",
            )?
        };
        if rotary {
            position.iter_mut().for_each(|p| *p = p.to_radians());
        }
        // Linear axes deviate in µm, rotary axes in arcsec (ISO 230-2 units); stored as mm / rad.
        let (deviation_column, to_internal) = if rotary {
            ("deviation_arcsec", (1.0f64 / 3600.0).to_radians())
        } else {
            ("deviation_um", 1e-3)
        };
        if rotary && table.column("deviation_um").is_some() {
            return Err(table
                .error(
                    table.header_line,
                    format!("column `deviation_um`: {axis} is rotary (`{lower}_deg`), so its deviations are angles: name the column `deviation_arcsec`"),
                )
                .into());
        }
        // 1 m (10⁶ µm) or 10⁶″ (about 280°) is no positioning deviation.
        let deviation = table.numbers_within(
            table.require(deviation_column)?,
            1e6,
            "a deviation of 10⁶ (1 m, or 280°) or more is not a measured positioning error",
        )?;
        let stated_noise = match (rotary, manifest.noise_um, manifest.noise_arcsec) {
            (false, noise, None) | (true, None, noise) => noise,
            (false, _, Some(_)) => {
                return Err(file.error(format!(
                    "field `noise_arcsec`: {axis} is linear (`{lower}_mm`); state its noise as `noise_um`"
                )));
            }
            (true, Some(_), _) => {
                return Err(file.error(format!(
                    "field `noise_um`: {axis} is rotary (`{lower}_deg`); state its noise as `noise_arcsec`"
                )));
            }
        };
        let dir_col = table.require("direction")?;
        let mut direction = Vec::with_capacity(n);
        for r in 0..n {
            direction.push(match table.text(r, dir_col) {
                "+" | "+1" | "1" => 1.0,
                "-" | "-1" => -1.0,
                other => {
                    return Err(table
                        .error(
                            table.line(r),
                            format!("column `direction`: `{other}`, expected + or -"),
                        )
                        .into());
                }
            });
        }
        let (setup_names, setup) = table.groups(table.require("run")?);
        let mut variables = vec![
            Variable {
                name: axis.clone(),
                kind: if rotary {
                    VariableKind::RotaryAxis
                } else {
                    VariableKind::LinearAxis
                },
                values: position,
            },
            Variable {
                name: "direction".into(),
                kind: VariableKind::Direction,
                values: direction,
            },
        ];
        if let Some(t) = read_times(&table)? {
            variables.push(Variable {
                name: "t".into(),
                kind: VariableKind::Time,
                values: t,
            });
        }
        let observations = Observations {
            values: DVec::from_iterator(n, deviation.iter().map(|d| d * to_internal)),
            sigma: stated_noise.map(|s| DVec::from_element(n, s * to_internal)),
            variables,
            setup,
            setup_names,
            channel: vec![0; n],
            channel_names: vec!["deviation".into()],
            setup_kind: "run".into(),
            quantity: if rotary {
                Quantity::Angle
            } else {
                Quantity::Length
            },
        };
        let title = manifest
            .description
            .clone()
            .unwrap_or_else(|| format!("{axis}-axis positioning runs"));
        Ok((
            AxisRuns {
                observations,
                axis,
                title,
            },
            manifest.base_model,
        ))
    }
}

impl ObservationModel for AxisRuns {
    fn observations(&self) -> &Observations {
        &self.observations
    }

    /// The axis' positioning error (its own component error, `EXX`) and the instrument's zero;
    /// with a time column, the library adds the drift of the zero and of the scale (thermal
    /// expansion growing in time).
    fn effects(&self) -> Effects {
        let obs = &self.observations;
        let (n, quantity, axis) = (obs.len(), obs.quantity, &self.axis);
        let iso = mte_errors::catalogue::positioning_error_name(axis);
        let offset = Term::single(
            format!("{iso} offset"),
            format!("zero offset of the {axis} measurement"),
            "constant offset between the instrument's zero and the axis' zero",
            Family::Base,
            DVec::from_element(n, 1.0),
            quantity,
        );
        let slot = SlotEffect {
            name: iso.clone(),
            label: format!("positioning error of the {axis} axis"),
            meaning: format!(
                "deviation of {axis} from its commanded position along its own direction"
            ),
            quantity,
            role: SlotRole::Component {
                axis: axis.clone(),
                positioning: true,
                straightness: false,
            },
            column: DVec::from_element(n, 1.0),
            separated_by: None,
            reference: None,
        };
        // Without times (many ISO 230-2 exports have none) a drift cannot be followed in time,
        // but the runs, taken one after another, show it as a zero that shifts from run to run.
        let mut candidates: Vec<Box<dyn crate::Candidate>> = Vec::new();
        let runs = obs.setup_names.len();
        if obs.variable_of_kind(VariableKind::Time).is_none() && runs >= 3 {
            candidates.push(Box::new(Term {
                name: format!("{iso} offset per run"),
                label: format!("zero of the {axis} measurement shifting from run to run"),
                meaning: String::from(
                    "the zero moves between runs: the machine or the laser's air drifting while the runs are taken. The table states no times: a drift during each run moves the − approach against the + one as a reversal does, so a reversal found beside this holds only if the zero stayed still during each run; a `t_s` column tells the two apart",
                ),
                family: Family::Setup,
                columns: DMat::from_fn(n, runs - 1, |i, k| {
                    if obs.setup[i] == k + 1 { 1.0 } else { 0.0 }
                }),
                coefficients: (1..runs)
                    .map(|k| {
                        (
                            format!(
                                "{iso} offset, run {} against run {}",
                                obs.setup_names[k], obs.setup_names[0]
                            ),
                            quantity,
                        )
                    })
                    .collect(),
                summary: Summary::EachCoefficient,
                exposed_by: Some("setup".into()),
                separated_by: Some("the time of each reading (`t_s`)".into()),
            }));
        }
        Effects {
            errors: vec![slot],
            instrument: vec![offset],
            candidates,
            drift: DriftOf::Instrument,
            ..Effects::default()
        }
    }

    fn title(&self) -> String {
        self.title.clone()
    }
}
