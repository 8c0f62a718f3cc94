//! GUM-S1 uncertainty of tracker results: the measurement function maps the measured lengths
//! to a spatial-accuracy quantity (seed 004: ΔD = maxⱼ |Pⱼ − Pⱼ,nominal|).
//!
//! [`LinearisedTracker`] evaluates each trial with the linearised adjustment
//! δP = T·δℓ (T cached once from the converged adjustment, [`Adjustment::target_sensitivity`]).
//! This is valid because the length perturbations (µm) are tiny against the geometry (the
//! neglected second-order term is ~δℓ²/L < 1e-9 mm for L > 100 mm); a test compares it with
//! full re-adjustment per trial ([`FullReadjustment`]).

use crate::adjust::{AdjustParams, Adjustment, adjust};
use crate::error::Result;
use crate::gum::{InputDistribution, MeasurementFunction};
use crate::network::{Network, Vec3};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

/// Which output quantity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum TrackerQuantity {
    /// ΔD = maxⱼ |Pⱼ − Pⱼ,nominal| (mm), seed 004's spatial accuracy.
    MaxDeviation,
    /// |Pⱼ − Pⱼ,nominal| of one target (mm).
    TargetDeviation(usize),
    /// One coordinate (0, 1, 2) of Pⱼ − Pⱼ,nominal (mm).
    TargetComponent(usize, usize),
}

fn quantity(q: TrackerQuantity, dev: &dyn Fn(usize) -> Vec3, n: usize) -> f64 {
    match q {
        TrackerQuantity::MaxDeviation => (0..n).map(|j| dev(j).norm()).fold(0.0, f64::max),
        TrackerQuantity::TargetDeviation(j) => dev(j).norm(),
        TrackerQuantity::TargetComponent(j, c) => dev(j)[c],
    }
}

/// Linearised measurement function of an adjusted network (cached sensitivity matrix).
#[derive(Clone, Debug)]
pub struct LinearisedTracker {
    deviation0: Vec<Vec3>,
    l0: Vec<f64>,
    t: DMatrix<f64>,
    /// The output quantity.
    pub quantity: TrackerQuantity,
}

impl LinearisedTracker {
    /// From a converged adjustment (dense T: 3n × n_obs; small and medium networks).
    ///
    /// # Errors
    /// As [`Adjustment::target_sensitivity`].
    pub fn new(adj: &Adjustment, quantity: TrackerQuantity) -> Result<Self> {
        Ok(Self {
            deviation0: adj.targets.iter().map(|t| t.deviation_mm).collect(),
            l0: adj.observations.iter().map(|o| o.observed_mm).collect(),
            t: adj.target_sensitivity()?,
            quantity,
        })
    }

    /// Input distributions: each length ~ N(observed, σ²) (GUM-S1 6.4.7).
    pub fn inputs(adj: &Adjustment) -> Vec<InputDistribution> {
        adj.observations
            .iter()
            .map(|o| InputDistribution::Normal {
                mean: o.observed_mm,
                sd: o.sigma_mm,
            })
            .collect()
    }
}

impl MeasurementFunction for LinearisedTracker {
    fn evaluate(&self, x: &[f64]) -> f64 {
        let n = self.deviation0.len();
        let dl: Vec<f64> = x.iter().zip(&self.l0).map(|(a, b)| a - b).collect();
        let dev = |j: usize| {
            let mut v = self.deviation0[j];
            for c in 0..3 {
                let row = self.t.row(3 * j + c);
                v[c] += row.iter().zip(&dl).map(|(a, b)| a * b).sum::<f64>();
            }
            v
        };
        quantity(self.quantity, &dev, n)
    }
}

/// Exact measurement function: a full Gauss–Newton adjustment per trial (slow; for checks).
#[derive(Clone, Debug)]
pub struct FullReadjustment {
    /// The network (lengths replaced per trial).
    pub network: Network,
    /// Adjustment parameters.
    pub params: AdjustParams,
    /// Output quantity.
    pub quantity: TrackerQuantity,
}

impl MeasurementFunction for FullReadjustment {
    fn evaluate(&self, x: &[f64]) -> f64 {
        let mut net = self.network.clone();
        for (o, v) in net.observations.iter_mut().zip(x) {
            o.length_mm = *v;
        }
        match adjust(&net, &self.params) {
            Ok(a) => quantity(
                self.quantity,
                &|j| a.targets[j].deviation_mm,
                a.targets.len(),
            ),
            Err(_) => f64::NAN,
        }
    }
}
