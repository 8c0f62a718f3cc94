//! ISO 10791-6 R-test data in the `mte-rtest/1` format, observed through mte-rtest's
//! measurement model: each reading `d = p_ball − p_nest` (machine coordinates), with the ball
//! centred in the nest at each setup's centring pose, so an error acts through its value at the
//! reading and at the centring ([`mte_rtest::RowSensitivity`]).

use mte_kinematics::{AxisKind, Machine};
use mte_linalg::{DMat, DVec};
use mte_rtest::model::NuisanceKind;

use super::machine::{
    ReferencePoses, SlotName, axis_variables, load_machine, location_names, slot_effects,
};
use crate::Result;
use crate::candidate::{BaseModelSpec, Candidate, SlotRole};
use crate::data::{Observations, Variable, VariableKind};
use crate::dataset::ManifestFile;
use crate::model::{DriftOf, Effects, ObservationModel};
use crate::term::{Family, Quantity, Term};

/// An R-test dataset with its machine and mte-rtest's sensitivities.
pub struct RTest {
    machine: Machine,
    data: mte_rtest::Dataset,
    sensitivity: Vec<mte_rtest::RowSensitivity>,
    observations: Observations,
}

impl RTest {
    /// Reads the dataset a manifest describes (the manifest's text as read, the CSV it names);
    /// `noise_um` is the stated noise (the format has no field for it).
    pub(crate) fn read(
        file: &ManifestFile,
        noise_um: Option<f64>,
    ) -> Result<(Self, Option<serde_json::Value>)> {
        let dataset_error = |e: mte_rtest::RtestError| file.error(e.to_string());
        let machine = load_machine(file, file.str_field("machine"))?;
        let rotary = |name: &str| {
            machine
                .axis_index(name)
                .is_some_and(|k| machine.axes()[k].kind == AxisKind::Rotary)
        };
        let data = mte_rtest::io::dataset_from_manifest(&file.path, &file.text, &file.dir, &rotary)
            .map_err(dataset_error)?;
        let model =
            mte_rtest::model::ObservationModel::new(&machine, &data).map_err(dataset_error)?;
        let sensitivity = model.sensitivity();
        let n = 3 * data.readings.len();
        let per_obs = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..n).map(|i| f(i / 3)).collect() };
        let axes: Vec<Vec<f64>> = (0..machine.axes().len())
            .map(|k| per_obs(&|r| data.readings[r].q[k]))
            .collect();
        let mut variables = axis_variables(&machine, &axes);
        variables.push(Variable {
            name: "t".into(),
            kind: VariableKind::Time,
            values: per_obs(&|r| data.readings[r].t_s),
        });
        let observations = Observations {
            values: DVec::from_fn(n, |i, _| data.readings[i / 3].d_mm[i % 3]),
            sigma: noise_um.map(|u| DVec::from_element(n, u * 1e-3)),
            variables,
            setup: (0..n).map(|i| data.readings[i / 3].setup).collect(),
            setup_names: data.setups.iter().map(|s| s.id.clone()).collect(),
            channel: (0..n).map(|i| i % 3).collect(),
            channel_names: vec!["dx".into(), "dy".into(), "dz".into()],
            setup_kind: "ball position".into(),
            quantity: Quantity::Length,
        };
        let base_model = file.value.get("base_model").cloned();
        Ok((
            RTest {
                machine,
                data,
                sensitivity,
                observations,
            },
            base_model,
        ))
    }
}

impl ObservationModel for RTest {
    fn observations(&self) -> &Observations {
        &self.observations
    }

    /// Every slot's effect at the reading and at the setup's centring pose; the sensor's zero
    /// in each setup (base) and the nest and ball centring offsets (candidates). The default
    /// base: the location errors of every rotary axis (position and orientation of its line)
    /// as IBS, KinematicsOpt and CYCLE996 identify them; the engine leaves out what the setups
    /// cannot separate, and says so.
    fn effects(&self) -> Effects {
        let (machine, data, sens) = (&self.machine, &self.data, &self.sensitivity);
        let n = self.observations.len();
        let n_slots = machine.n_slots();
        let mut at_row = DMat::zeros(n, n_slots);
        let mut at_ref = DMat::zeros(n, n_slots);
        for (r, rs) in sens.iter().enumerate() {
            for ch in 0..3 {
                at_row.row_mut(3 * r + ch).copy_from(&rs.at_row.row(ch));
                at_ref
                    .row_mut(3 * r + ch)
                    .copy_from(&rs.at_centring.row(ch));
            }
        }
        let per_obs = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..n).map(|i| f(i / 3)).collect() };
        let axes_at_centring: Vec<Vec<f64>> = (0..machine.axes().len())
            .map(|k| per_obs(&|r| data.setups[data.readings[r].setup].centring_q[k]))
            .collect();
        let centring_t_s = per_obs(&|r| data.setups[data.readings[r].setup].centring_t_s);
        let hint = |name: &SlotName| {
            match name.role {
            SlotRole::Constant { family: Family::Location } => Some(
                "a second ball position at another height or distance along the rotary axis (e.g. the ball turned to the other side of the table by C, or raised in Z)".to_string(),
            ),
            _ => None,
        }
        };
        let errors = slot_effects(
            machine,
            &at_row,
            &self.observations,
            Some(ReferencePoses {
                sensitivity: &at_ref,
                axes: &axes_at_centring,
                time_s: &centring_t_s,
            }),
            &hint,
        );
        let mut instrument: Vec<Term> = Vec::new();
        let mut candidates: Vec<Box<dyn Candidate>> = Vec::new();
        for (k, setup) in data.setups.iter().enumerate() {
            for (kind, what) in [
                (NuisanceKind::SensorZero, "sensor zero"),
                (NuisanceKind::NestOffset, "nest offset"),
                (NuisanceKind::BallOffset, "ball centring offset"),
            ] {
                for a in 0..3 {
                    let col = DVec::from_fn(n, |i, _| {
                        if data.readings[i / 3].setup == k {
                            sens[i / 3].nuisance(kind)[(i % 3, a)]
                        } else {
                            0.0
                        }
                    });
                    let axis = ['x', 'y', 'z'][a];
                    let family = if kind == NuisanceKind::SensorZero {
                        Family::Base
                    } else {
                        Family::Setup
                    };
                    let t = Term::single(
                        format!("{} {what} {axis}", setup.id),
                        format!("{what} in {axis} (setup {})", setup.id),
                        format!("the R-test's {what} in this setup"),
                        family,
                        col,
                        Quantity::Length,
                    )
                    .separated_by("a second nest length, or the ball position probed on the table");
                    if kind == NuisanceKind::SensorZero {
                        instrument.push(t);
                    } else {
                        candidates.push(Box::new(t));
                    }
                }
            }
        }
        Effects {
            errors,
            instrument,
            candidates,
            location: location_names(machine),
            default_base: BaseModelSpec {
                location: true,
                ..Default::default()
            },
            drift: DriftOf::WholeBase,
        }
    }

    fn title(&self) -> String {
        if self.data.note.is_empty() {
            format!("R-test on {}", self.machine.name())
        } else {
            format!("R-test on {} ({})", self.machine.name(), self.data.note)
        }
    }
}
