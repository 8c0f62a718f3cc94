//! Laser-tracker multilateration data (seed 004): interferometric lengths from several stations
//! to targets the machine visits. The network is first adjusted as a free network
//! (`mte-metrology`, datum on the nominal targets) to get the stations and dead paths; then the
//! lengths themselves are the observations, linearised there: station positions and dead paths
//! are the instrument's parameters, and the machine's errors enter through the target
//! positions, `δℓᵢⱼ = uᵢⱼ·(δPⱼ − δQᵢ) − δdᵢ` with uᵢⱼ the unit vector from station to target.
//! A target may state the reflector's offset `o` from the tool tip (tool frame): the reflector
//! then moves by the tip's translation plus the tool's rotation through the lever arm `R o`,
//! and the reflector holder's orientation in the spindle joins the instrument's parameters.
//! Working on the lengths keeps their independent noise, so the tests of significance are exact.

use mte_kinematics::Machine;
use mte_linalg::{DMat, DVec, Mat3, Vec3};
use serde::Deserialize;

use super::machine::{
    axis_variables, load_machine, read_axes, read_optional_vectors, read_times, slot_effects,
};
use crate::Result;
use crate::candidate::{SlotEffect, SlotRole};
use crate::data::{Observations, Variable, VariableKind};
use crate::dataset::{ManifestFile, dataset_manifest};
use crate::model::{Effects, ObservationModel};
use crate::term::{Family, Quantity, Term};

dataset_manifest!(
    /// The manifest of tracker data (`"kind": "tracker"`); `data` is the lengths table
    /// (`station`, `target`, `length_mm`).
    Manifest {
        machine: Option<String>,
        setups: Vec<Station>,
        /// The targets table: `id`, commanded axes `<axis>_mm` / `<axis>_deg`, optional `t_s`
        /// and the reflector's offset from the tool tip (`tool_x_mm`, `tool_y_mm`, `tool_z_mm`).
        targets: Option<String>,
    }
);

/// A station of the manifest: id and approximate position in machine coordinates, mm.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Station {
    id: String,
    #[serde(default)]
    station_mm: Option<[f64; 3]>,
}

/// Tracker lengths linearised at the adjusted network.
pub struct Tracker {
    machine: Machine,
    observations: Observations,
    /// Commanded axes per target.
    axes: Vec<Vec<f64>>,
    /// Per target, the tool's nominal orientation in the workpiece frame and the reflector's
    /// offset from the tool tip in the tool frame (mm): the lever arm through which the tool's
    /// angular errors move the reflector. `None` without offsets (the reflector at the tip).
    tool: Option<Vec<(Mat3, Vec3)>>,
    station_ids: Vec<String>,
    station_of: Vec<usize>,
    target_of: Vec<usize>,
    /// Unit vector from station to target, per length.
    line_of_sight: Vec<Vec3>,
    /// Nominal distance from station to target, per length.
    distance: Vec<f64>,
    title: String,
}

impl Tracker {
    /// Reads the lengths and targets a manifest names and adjusts the network.
    pub(crate) fn read(
        file: &ManifestFile,
        noise_um: Option<f64>,
    ) -> Result<(Self, Option<serde_json::Value>)> {
        use mte_metrology::adjust::{AdjustParams, adjust};
        use mte_metrology::network::{DeadPath, LengthObservation, Network, Station, Target};
        let manifest: Manifest = file.parse()?;
        let noise_um = manifest.noise_um.or(noise_um).ok_or_else(|| {
            file.missing(
                "noise_um",
                "the standard uncertainty of one tracker length, µm",
            )
        })?;
        file.check_noise("noise_um", Some(noise_um))?;
        let machine = load_machine(file, manifest.machine.as_deref())?;
        let lengths = file.table(&manifest.data)?;
        let targets_file = manifest
            .targets
            .as_deref()
            .ok_or_else(|| file.missing("targets", "the targets table: id and commanded axes"))?;
        let targets = file.table(targets_file)?;
        let axes = read_axes(&machine, &targets)?;
        let id_col = targets.require("id")?;
        let ids: Vec<String> = (0..targets.len())
            .map(|r| targets.text(r, id_col).to_string())
            .collect();
        let zero = vec![0.0; machine.n_slots()];
        // The reflector's offset from the tool tip in the tool frame per target: several offsets
        // at one pose show the tool's angular errors apart from its translations, as in a
        // volumetric calibration.
        let offsets = read_optional_vectors(
            &targets,
            ["tool_x_mm", "tool_y_mm", "tool_z_mm"],
            1e4,
            "a reflector 10 m or more from the tool tip is not on the machine",
        )?;
        let (nominal, tool): (Vec<Vec3>, Vec<(Mat3, Vec3)>) = (0..targets.len())
            .map(|r| {
                let q: Vec<f64> = axes.iter().map(|a| a[r]).collect();
                let pose = machine.tool_in_workpiece(&q, &zero);
                let rotation = *pose.rotation.to_rotation_matrix().matrix();
                let offset = offsets.as_ref().map_or_else(Vec3::zeros, |o| o[r]);
                (
                    pose.translation.vector + rotation * offset,
                    (rotation, offset),
                )
            })
            .unzip();
        // (Offset columns of zeros are the reflector at the tip: no holder to orient.)
        let tool = offsets
            .is_some_and(|o| o.iter().any(|v| v.norm() > 0.0))
            .then_some(tool);
        if manifest.setups.len() < 4 {
            return Err(file.error(format!(
                "field `setups`: {} stations, a multilateration needs at least 4",
                manifest.setups.len()
            )));
        }
        let mut stations = Vec::new();
        for s in &manifest.setups {
            let p = s.station_mm.ok_or_else(|| {
                file.missing("setups[].station_mm", "approximate station position, mm")
            })?;
            stations.push(Station {
                id: s.id.clone(),
                position_mm: Vec3::new(p[0], p[1], p[2]),
                dead_path_mm: 0.0,
                dead_path: DeadPath::Free,
            });
        }
        let (cs, ct, cl) = (
            lengths.require("station")?,
            lengths.require("target")?,
            lengths.require("length_mm")?,
        );
        let mut observations = Vec::new();
        for r in 0..lengths.len() {
            let station = manifest
                .setups
                .iter()
                .position(|s| s.id == lengths.text(r, cs))
                .ok_or_else(|| {
                    lengths.error(
                        lengths.line(r),
                        format!(
                            "column `station`: `{}` is not a station of the manifest",
                            lengths.text(r, cs)
                        ),
                    )
                })?;
            let target = ids
                .iter()
                .position(|t| t == lengths.text(r, ct))
                .ok_or_else(|| {
                    lengths.error(
                        lengths.line(r),
                        format!(
                            "column `target`: `{}` is not in {targets_file}",
                            lengths.text(r, ct)
                        ),
                    )
                })?;
            observations.push(LengthObservation {
                station,
                target,
                length_mm: lengths.number_within(
                    r,
                    cl,
                    1e6,
                    "a tracker length of 1 km or more is not a measurement",
                )?,
                sigma_mm: noise_um * 1e-3,
            });
        }
        let network = Network {
            stations,
            targets: ids
                .iter()
                .zip(&nominal)
                .map(|(id, p)| Target {
                    id: id.clone(),
                    nominal_mm: *p,
                })
                .collect(),
            observations,
        };
        let adjustment = adjust(&network, &AdjustParams::default()).map_err(|e| {
            crate::DiagnoseError::Dataset {
                path: lengths.source_name.clone(),
                detail: format!("network adjustment: {e}"),
            }
        })?;
        let n = network.observations.len();
        let station_of: Vec<usize> = network.observations.iter().map(|o| o.station).collect();
        let target_of: Vec<usize> = network.observations.iter().map(|o| o.target).collect();
        let q: Vec<Vec3> = adjustment.stations.iter().map(|s| s.position_mm).collect();
        let d: Vec<f64> = adjustment.stations.iter().map(|s| s.dead_path_mm).collect();
        let sight = |k: usize| nominal[target_of[k]] - q[station_of[k]];
        let values = DVec::from_fn(n, |k, _| {
            network.observations[k].length_mm - (sight(k).norm() - d[station_of[k]])
        });
        let per_length: Vec<Vec<f64>> = axes
            .iter()
            .map(|v| target_of.iter().map(|&j| v[j]).collect())
            .collect();
        let mut variables = axis_variables(&machine, &per_length);
        if let Some(t) = read_times(&targets)? {
            variables.push(Variable {
                name: "t".into(),
                kind: VariableKind::Time,
                values: target_of.iter().map(|&j| t[j]).collect(),
            });
        }
        let observations = Observations {
            values,
            sigma: Some(DVec::from_element(n, noise_um * 1e-3)),
            variables,
            setup: station_of.clone(),
            setup_names: network.stations.iter().map(|s| s.id.clone()).collect(),
            channel: vec![0; n],
            channel_names: vec!["length".into()],
            setup_kind: "tracker station".into(),
            quantity: Quantity::Length,
        };
        let title = manifest
            .description
            .clone()
            .unwrap_or_else(|| format!("laser-tracker multilateration on {}", machine.name()));
        Ok((
            Tracker {
                observations,
                axes,
                tool,
                station_ids: network.stations.iter().map(|s| s.id.clone()).collect(),
                line_of_sight: (0..n).map(|k| sight(k).normalize()).collect(),
                distance: (0..n).map(|k| sight(k).norm()).collect(),
                station_of,
                target_of,
                machine,
                title,
            },
            manifest.base_model,
        ))
    }
}

impl ObservationModel for Tracker {
    fn observations(&self) -> &Observations {
        &self.observations
    }

    /// The stations' positions and dead paths and, with tool offsets, the reflector holder's
    /// orientation (instrument); the reflector's errors along the line of sight (constant
    /// offsets of the machine are a rigid shift of all targets, which the stations absorb) and
    /// the tracker's scale. No base model by default: the user's
    /// volumetric model (component errors as polynomials, squareness) when asked for.
    fn effects(&self) -> Effects {
        let (machine, u) = (&self.machine, &self.line_of_sight);
        let n = self.observations.len();
        let mut instrument = Vec::new();
        for (i, id) in self.station_ids.iter().enumerate() {
            let on = |r: usize| self.station_of[r] == i;
            for (k, letter) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                instrument.push(Term::single(
                    format!("{id} {}", letter.to_ascii_lowercase()),
                    format!("station {id} position in {letter}"),
                    "tracker station coordinate",
                    Family::Base,
                    DVec::from_fn(n, |r, _| if on(r) { -u[r][k] } else { 0.0 }),
                    Quantity::Length,
                ));
            }
            instrument.push(Term::single(
                format!("{id} dead path"),
                format!("station {id} dead-path length"),
                "length from the tracker's origin to its interferometer zero",
                Family::Base,
                DVec::from_fn(n, |r, _| if on(r) { -1.0 } else { 0.0 }),
                Quantity::Length,
            ));
        }
        // The reflector holder's orientation in the spindle, which no drawing states to the
        // µrad: turned by δφ (tool frame) it moves a reflector at o by R (δφ × o).
        if let Some(tool) = &self.tool {
            for (k, letter) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                instrument.push(Term::single(
                    format!("tool orientation {letter}"),
                    format!("the reflector holder's orientation about the tool's {letter}"),
                    "how the reflectors' holder sits in the spindle: its turn moves each reflector in proportion to its offset from the tool tip",
                    Family::Base,
                    DVec::from_fn(n, |r, _| {
                        let (rotation, offset) = &tool[self.target_of[r]];
                        offset.cross(&(rotation.transpose() * u[r]))[k]
                    }),
                    Quantity::Angle,
                ));
            }
        }
        // The reflector's error at each commanded pose (the tool tip's translation, plus its
        // rotation acting through the reflector's lever arm), along the line of sight.
        let n_targets = self.axes.first().map_or(0, Vec::len);
        let mut tip = vec![DMat::zeros(3, machine.n_slots()); n_targets];
        let mut jac = DMat::zeros(6, machine.n_slots());
        for (r, t) in tip.iter_mut().enumerate() {
            let q: Vec<f64> = self.axes.iter().map(|a| a[r]).collect();
            machine.jacobian_into(&q, &mut jac);
            t.copy_from(&jac.rows(0, 3));
            if let Some(tool) = &self.tool {
                let (rotation, offset) = &tool[r];
                let arm = -mte_linalg::skew(&(rotation * offset));
                *t += arm * jac.rows(3, 3);
            }
        }
        let mut s = DMat::zeros(n, machine.n_slots());
        for k in 0..n {
            s.row_mut(k)
                .copy_from(&(u[k].transpose() * &tip[self.target_of[k]]));
        }
        let mut errors = slot_effects(machine, &s, &self.observations, None, &|_| None);
        errors.retain(|e| {
            !matches!(
                e.role,
                SlotRole::Constant {
                    family: Family::Setup | Family::Location
                }
            )
        });
        errors.push(SlotEffect {
            name: "tracker scale".into(),
            label: "scale error of the tracker's lengths".into(),
            meaning: "every interferometric length is too long or too short in proportion (wavelength or air-refraction compensation, tracker temperature)".into(),
            quantity: Quantity::Ratio,
            role: SlotRole::Constant { family: Family::Instrument },
            column: DVec::from_column_slice(&self.distance),
            separated_by: Some("a calibrated reference length (scale bar) measured by the tracker, or the machine's own scale checked with a laser interferometer: without one, every length too long in proportion reads the same as a common scale error of X, Y and Z (EXX, EYY, EZZ alike) with the stations' places scaled as well".into()),
            reference: None,
        });
        Effects {
            errors,
            instrument,
            ..Effects::default()
        }
    }

    fn title(&self) -> String {
        self.title.clone()
    }
}
