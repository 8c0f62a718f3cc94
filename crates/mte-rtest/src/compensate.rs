//! Compensation: the controller's kinematic description updated with identified location values,
//! and the BK4 test predicted before and after.

use crate::error::Result;
use crate::identify::{Fit, ParamKind};
use crate::model::ErrorField;
use crate::program::Program;
use crate::simulate::{PlanItem, SetupSpec, SimOptions, simulate};
use mte_kinematics::Machine;
use serde::{Deserialize, Serialize};

/// The controller's slot values after compensation: `before` with every kinematic parameter of
/// `fit` (or only those named in `only`) replaced by its estimate. Estimates are absolute slot
/// values (the observation model depends on the commanded axes only, not on the controller's
/// model that produced them), so they replace rather than add.
pub fn corrected_controller(
    before: &[f64],
    n_slots: usize,
    fit: &Fit,
    only: Option<&[&str]>,
) -> Vec<f64> {
    let mut c = if before.is_empty() {
        vec![0.0; n_slots]
    } else {
        before.to_vec()
    };
    for e in fit.kinematic() {
        if let ParamKind::Slot(ns) = &e.kind
            && only.is_none_or(|o| o.contains(&ns.iso.as_str()))
        {
            for &(slot, factor) in &ns.slots {
                c[slot] = factor * e.value;
            }
        }
    }
    c
}

/// A BK4 result: the error range per machine direction and overall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Bk4Range {
    /// max − min of dx, dy, dz over the test, µm.
    pub range_um: [f64; 3],
    /// The largest of the three ("BK4 error range" as in seed 002), µm.
    pub max_range_um: f64,
}

/// Predicts BK4 (noise-free) for a machine with true errors `truth` and a controller with slot
/// values `controller` (empty = nominal), ball at `setup`.
///
/// # Errors
/// As [`simulate`].
pub fn predict_bk4<E: ErrorField + ?Sized>(
    m: &Machine,
    truth: &E,
    controller: &[f64],
    setup: &SetupSpec,
) -> Result<Bk4Range> {
    let plan = [PlanItem {
        setup: setup.clone(),
        programs: vec![Program::bk4(m, None)?],
    }];
    let opts = SimOptions {
        noise_sd_mm: 0.0,
        controller_errors: controller.to_vec(),
        ..Default::default()
    };
    let sim = simulate(m, &plan, truth, &opts)?;
    let mut r = [0.0; 3];
    for (k, rk) in r.iter_mut().enumerate() {
        let v: Vec<f64> = sim.dataset.readings.iter().map(|x| x.d_mm[k]).collect();
        let mx = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mn = v.iter().copied().fold(f64::INFINITY, f64::min);
        *rk = (mx - mn) * 1e3;
    }
    Ok(Bk4Range {
        range_um: r,
        max_range_um: r.iter().copied().fold(0.0, f64::max),
    })
}
