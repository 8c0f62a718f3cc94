//! Measured datasets on disk: a JSON manifest plus a CSV observation table (format in
//! `docs/formats.md`), turned into [`Observations`], a base model and the candidate library.

use std::path::{Path, PathBuf};

use mte_linalg::{DMat, DVec};
use serde::Deserialize;

use crate::candidate::{BaseModelSpec, Candidate, SlotEffect, SlotRole, physical_effects};
use crate::data::{Observations, Variable, VariableKind};
use crate::term::{Family, Quantity, Term};
use crate::{DiagnoseError, Result};

/// The manifest of a dataset (`"format": "mte-dataset/1"`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Format tag, `mte-dataset/1`.
    pub format: String,
    /// `axis`, `rtest` or `tracker`.
    pub kind: String,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// The observation table, relative to the manifest.
    pub data: String,
    /// Stated standard uncertainty of one observation, µm.
    #[serde(default)]
    pub noise_um: Option<f64>,
    /// Rotary-axis data: stated standard uncertainty of one angular reading, arcsec.
    #[serde(default)]
    pub noise_arcsec: Option<f64>,
    /// Axis data: the axis measured (`X`).
    #[serde(default)]
    pub axis: Option<String>,
    /// Library name or file of the machine (R-test and tracker data).
    #[serde(default)]
    pub machine: Option<String>,
    /// Setups (ball positions or tracker stations).
    #[serde(default)]
    pub setups: Vec<SetupSpec>,
    /// The base model the user believes in: a [`crate::BaseModelSpec`] object, or a list of
    /// term names; defaults per kind.
    #[serde(default)]
    pub base_model: Option<serde_json::Value>,
    /// Tracker: the targets table (`id`, commanded axes `<axis>_mm` / `<axis>_deg`, optional `t_s`).
    #[serde(default)]
    pub targets: Option<String>,
}

/// One setup of a dataset.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SetupSpec {
    /// Identifier used in the CSV `setup` column.
    pub id: String,
    /// R-test: ball centre in table (workpiece) coordinates, mm.
    #[serde(default)]
    pub ball_mm: Option<[f64; 3]>,
    /// Tracker: station position in machine coordinates, mm (nominal).
    #[serde(default)]
    pub station_mm: Option<[f64; 3]>,
}

/// A dataset ready to diagnose.
pub struct Prepared {
    /// The observations.
    pub observations: Observations,
    /// The base model.
    pub base: Vec<Term>,
    /// The candidate library.
    pub candidates: Vec<Box<dyn Candidate>>,
    /// A title for reports.
    pub title: String,
}

pub(crate) use mte_linalg::csv::CsvTable as Table;

/// Reads the CSV table at `path` (the workspace's one reader, [`mte_linalg::csv`]).
pub(crate) fn read_table(path: &Path) -> Result<Table> {
    let text = std::fs::read_to_string(path).map_err(|e| DiagnoseError::Dataset {
        path: path.display().to_string(),
        detail: e.to_string(),
    })?;
    Ok(Table::parse(&text, &path.display().to_string())?)
}

impl From<mte_linalg::csv::CsvError> for DiagnoseError {
    fn from(e: mte_linalg::csv::CsvError) -> Self {
        DiagnoseError::Dataset {
            path: e.source_name,
            detail: format!("line {}: {}", e.line, e.message),
        }
    }
}

/// Reads a manifest and its table and prepares the diagnosis: an `mte-dataset/1` manifest
/// (axis or tracker data) or an `mte-rtest/1` manifest (R-test data). `noise_um` is the stated
/// standard uncertainty of one observation where the manifest states none (the R-test format
/// has no such field).
///
/// # Errors
/// [`DiagnoseError::Dataset`] naming the file, line and field for unreadable or malformed input.
pub fn load_with_noise(manifest_path: &Path, noise_um: Option<f64>) -> Result<Prepared> {
    let text = std::fs::read_to_string(manifest_path).map_err(|e| DiagnoseError::Dataset {
        path: manifest_path.display().to_string(),
        detail: e.to_string(),
    })?;
    let format = serde_json::from_str::<serde_json::Value>(&text)
        .ok()
        .and_then(|v| v.get("format").and_then(|f| f.as_str()).map(String::from));
    if format.as_deref() == Some("mte-rtest/1") {
        return crate::adapters::prepare_rtest(manifest_path, noise_um);
    }
    let mut manifest: Manifest =
        serde_json::from_str(&text).map_err(|e| DiagnoseError::Dataset {
            path: manifest_path.display().to_string(),
            detail: e.to_string(),
        })?;
    if manifest.noise_um.is_none() {
        manifest.noise_um = noise_um;
    }
    if manifest.format != "mte-dataset/1" {
        return Err(DiagnoseError::Dataset {
            path: manifest_path.display().to_string(),
            detail: format!(
                "field `format`: `{}`, expected `mte-dataset/1`",
                manifest.format
            ),
        });
    }
    for (field, value) in [
        ("noise_um", manifest.noise_um),
        ("noise_arcsec", manifest.noise_arcsec),
    ] {
        if let Some(n) = value.filter(|n| !(n.is_finite() && *n > 0.0)) {
            return Err(DiagnoseError::Dataset {
                path: manifest_path.display().to_string(),
                detail: format!("field `{field}`: {n} is not a positive uncertainty"),
            });
        }
    }
    let dir = manifest_path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let table = read_table(&dir.join(&manifest.data))?;
    match manifest.kind.as_str() {
        "axis" => prepare_axis(&manifest, &table, manifest_path),
        other => {
            crate::adapters::prepare_machine_dataset(other, &manifest, &table, &dir, manifest_path)
        }
    }
}

/// [`load_with_noise`] with the noise the dataset states.
///
/// # Errors
/// As [`load_with_noise`].
pub fn load(manifest_path: &Path) -> Result<Prepared> {
    load_with_noise(manifest_path, None)
}

/// Bidirectional positioning runs of one axis (laser interferometer, ISO 230-2 style).
/// Columns: `run`, `direction` (+1/−1), `<axis>_mm` (or `<axis>_deg` for a rotary axis),
/// optional `t_s`, and `deviation_um` (measured minus commanded position; `deviation_arcsec`
/// for a rotary axis).
fn prepare_axis(manifest: &Manifest, table: &Table, manifest_path: &Path) -> Result<Prepared> {
    let axis = manifest
        .axis
        .clone()
        .ok_or_else(|| DiagnoseError::Dataset {
            path: manifest_path.display().to_string(),
            detail: "field `axis`: missing (the name of the axis measured, e.g. \"X\")".into(),
        })?;
    let lower = axis.to_lowercase();
    let (pos_col, rotary) = match (table.column(&format!("{lower}_mm")), table.column(&format!("{lower}_deg"))) {
        (Some(c), _) => (c, false),
        (None, Some(c)) => (c, true),
        (None, None) => return Err(table.error(table.header_line, format!("missing column `{lower}_mm` (or `{lower}_deg`) with the commanded position of {axis}")).into()),
    };
    let n = table.len();
    if n == 0 {
        return Err(DiagnoseError::Dataset {
            path: table.source_name.clone(),
            detail: "no observations".into(),
        });
    }
    let mut position = table.numbers(pos_col)?;
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
    let deviation = table.numbers(table.require(deviation_column)?)?;
    let stated_noise = match (rotary, manifest.noise_um, manifest.noise_arcsec) {
        (false, noise, None) | (true, None, noise) => noise,
        (false, _, Some(_)) => {
            return Err(DiagnoseError::Dataset {
                path: manifest_path.display().to_string(),
                detail: format!(
                    "field `noise_arcsec`: {axis} is linear (`{lower}_mm`); state its noise as `noise_um`"
                ),
            });
        }
        (true, Some(_), _) => {
            return Err(DiagnoseError::Dataset {
                path: manifest_path.display().to_string(),
                detail: format!(
                    "field `noise_um`: {axis} is rotary (`{lower}_deg`); state its noise as `noise_arcsec`"
                ),
            });
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
    let run_col = table.require("run")?;
    let mut setup_names: Vec<String> = Vec::new();
    let mut setup = Vec::with_capacity(n);
    for r in 0..n {
        let id = table.text(r, run_col).to_string();
        let k = setup_names
            .iter()
            .position(|s| *s == id)
            .unwrap_or_else(|| {
                setup_names.push(id.clone());
                setup_names.len() - 1
            });
        setup.push(k);
    }
    let mut variables = vec![
        Variable {
            name: axis.clone(),
            kind: if rotary {
                VariableKind::RotaryAxis
            } else {
                VariableKind::LinearAxis
            },
            values: position.clone(),
        },
        Variable {
            name: "direction".into(),
            kind: VariableKind::Direction,
            values: direction,
        },
    ];
    if let Some(c) = table.column("t_s") {
        variables.push(Variable {
            name: "t".into(),
            kind: VariableKind::Time,
            values: table.numbers(c)?,
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
    observations.validate()?;
    let quantity = observations.quantity;
    let iso = format!("E{axis}{axis}");
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
        label: format!("positioning error of {axis}"),
        meaning: format!("deviation of {axis} from its commanded position along its own direction"),
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
    let spec = base_spec(
        manifest.base_model.as_ref(),
        manifest_path,
        BaseModelSpec::default(),
    )?;
    let slots = std::slice::from_ref(&slot);
    let mut base = vec![offset];
    let (terms, completions) = spec_terms(&spec, &observations, slots, &[], manifest_path)?;
    base.extend(terms);
    let drifting: Vec<&Term> = base.iter().take(1).collect();
    let mut candidates = physical_effects(&observations, slots, &drifting);
    candidates.extend(completions);
    if let Some(t) = observations.variable_of_kind(VariableKind::Time) {
        let t0 = t.values.iter().copied().fold(f64::INFINITY, f64::min);
        let col = DMat::from_fn(n, 1, |i, _| position[i] * (t.values[i] - t0));
        candidates.push(Box::new(Term {
            name: format!("{iso} scale drift"),
            label: format!("thermal expansion of {axis} growing in time"),
            meaning: format!("the scale of {axis} changes while the machine warms up (thermal expansion of the screw or scale)"),
            family: Family::Drift { time_constant_s: None },
            coefficients: vec![(format!("{iso} scale rate"), Quantity::RatioRate)],
            columns: col,
            summary: crate::term::Summary::EachCoefficient,
            exposed_by: Some("t".into()),
            separated_by: None,
        }));
    }
    let title = manifest
        .description
        .clone()
        .unwrap_or_else(|| format!("{axis}-axis positioning runs"));
    Ok(Prepared {
        observations,
        base,
        candidates,
        title,
    })
}

/// The base-model spec of a manifest's `base_model` field, `default` without one.
pub(crate) fn base_spec(
    value: Option<&serde_json::Value>,
    manifest_path: &Path,
    default: BaseModelSpec,
) -> Result<BaseModelSpec> {
    value.map_or(Ok(default), |v| {
        BaseModelSpec::from_json(v).map_err(|detail| DiagnoseError::Dataset {
            path: manifest_path.display().to_string(),
            detail: format!("field `base_model`: {detail}"),
        })
    })
}

/// A base model's terms and the completions of its component errors.
pub(crate) type BaseTerms = (Vec<Term>, Vec<Box<dyn Candidate>>);

/// The base terms of `spec` on these slots (named terms looked up in the slots' candidates),
/// and the completions of its component errors ([`BaseModelSpec::completions`]).
pub(crate) fn spec_terms(
    spec: &BaseModelSpec,
    obs: &Observations,
    slots: &[SlotEffect],
    location: &[String],
    manifest_path: &Path,
) -> Result<BaseTerms> {
    let named = if spec.terms.is_empty() {
        Vec::new()
    } else {
        physical_effects(obs, slots, &[])
    };
    let terms =
        spec.terms(obs, slots, location, &named)
            .map_err(|detail| DiagnoseError::Dataset {
                path: manifest_path.display().to_string(),
                detail: format!("field `base_model`: {detail}"),
            })?;
    Ok((terms, spec.completions(obs, slots)))
}
