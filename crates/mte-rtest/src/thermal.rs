//! Thermal tracking: repeated BK cycles (one setup with its own centring per cycle) fitted one by
//! one, each parameter's drift against time, and drift models fitted to it.

use crate::error::{Result, RtestError};
use crate::identify::{Fit, FitSpec, identify};
use crate::model::Dataset;
use mte_kinematics::Machine;
use mte_linalg::{DMat, DVec};
use serde::{Deserialize, Serialize};

/// One parameter's values over the cycles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DriftSeries {
    /// Parameter label (ISO name).
    pub label: String,
    /// Cycle times (centring time of each setup), s.
    pub t_s: Vec<f64>,
    /// Estimates, mm or rad.
    pub values: Vec<f64>,
    /// Standard uncertainties (0 when unobservable).
    pub std_uncertainty: Vec<f64>,
    /// Linear drift model.
    pub linear: DriftModel,
    /// First-order (exponential) drift model `p0 + A·(1 − exp(−t/τ))`, if ≥ 4 cycles.
    pub exponential: Option<DriftModel>,
}

/// A fitted drift model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DriftModel {
    /// "linear" or "exponential".
    pub kind: String,
    /// Value at t = 0 of the first cycle (mm or rad).
    pub p0: f64,
    /// Linear: slope per s. Exponential: amplitude A.
    pub a: f64,
    /// Exponential: time constant τ, s (0 for linear).
    pub tau_s: f64,
    /// rms of the residuals, mm or rad.
    pub rms: f64,
}

impl DriftModel {
    /// Model value at time `t_s` (relative to the first cycle).
    pub fn eval(&self, t_s: f64) -> f64 {
        if self.tau_s > 0.0 {
            self.p0 + self.a * (1.0 - (-t_s / self.tau_s).exp())
        } else {
            self.p0 + self.a * t_s
        }
    }
}

fn ls2(basis: &[(f64, f64)], y: &[f64]) -> Option<(f64, f64, f64)> {
    let n = y.len();
    let a = DMat::from_fn(n, 2, |i, j| if j == 0 { basis[i].0 } else { basis[i].1 });
    let b = DVec::from_column_slice(y);
    let svd = a.clone().svd(true, true);
    let x = svd.solve(&b, 1e-12).ok()?;
    let r = &b - &a * &x;
    Some((x[0], x[1], (r.norm_squared() / n as f64).sqrt()))
}

/// Fits the linear and exponential drift models to a series (times relative to the first).
///
/// # Errors
/// [`RtestError::TooShort`] with fewer than 2 points.
pub fn fit_drift(t_s: &[f64], values: &[f64]) -> Result<(DriftModel, Option<DriftModel>)> {
    if t_s.len() < 2 || t_s.len() != values.len() {
        return Err(RtestError::TooShort {
            what: "drift series".into(),
            found: t_s.len().min(values.len()),
            needed: 2,
            unit: "cycles".into(),
        });
    }
    let t0 = t_s[0];
    let rel: Vec<f64> = t_s.iter().map(|t| t - t0).collect();
    let (p0, a, rms) = ls2(&rel.iter().map(|&t| (1.0, t)).collect::<Vec<_>>(), values)
        .ok_or_else(|| RtestError::Fit("linear drift fit failed".into()))?;
    let linear = DriftModel {
        kind: "linear".into(),
        p0,
        a,
        tau_s: 0.0,
        rms,
    };
    let span = rel.last().copied().unwrap_or(0.0).max(1e-9);
    let exponential = if t_s.len() >= 4 {
        // τ on a log grid from span/50 to 20·span; (p0, A) by linear least squares for each τ
        let mut best: Option<DriftModel> = None;
        for k in 0..=200 {
            let tau = span / 50.0 * (1000.0f64).powf(k as f64 / 200.0);
            if let Some((p0, a, rms)) = ls2(
                &rel.iter()
                    .map(|&t| (1.0, 1.0 - (-t / tau).exp()))
                    .collect::<Vec<_>>(),
                values,
            ) && best.as_ref().is_none_or(|b| rms < b.rms)
            {
                best = Some(DriftModel {
                    kind: "exponential".into(),
                    p0,
                    a,
                    tau_s: tau,
                    rms,
                });
            }
        }
        best
    } else {
        None
    };
    Ok((linear, exponential))
}

/// Fits every setup (= cycle) of `data` on its own and builds the drift series of every
/// kinematic parameter of `spec`.
///
/// # Errors
/// As [`identify`] and [`fit_drift`].
pub fn track(m: &Machine, data: &Dataset, spec: &FitSpec) -> Result<(Vec<Fit>, Vec<DriftSeries>)> {
    let mut fits = Vec::new();
    for si in 0..data.setups.len() {
        let rows = data.select(None, Some(si));
        let mut sub = data.subset(&rows);
        sub.setups = vec![data.setups[si].clone()];
        for r in &mut sub.readings {
            r.setup = 0;
        }
        fits.push(identify(m, &sub, spec)?);
    }
    let t: Vec<f64> = data.setups.iter().map(|s| s.centring_t_s).collect();
    let mut series = Vec::new();
    for p in &spec.params {
        let vals: Vec<f64> = fits
            .iter()
            .map(|f| f.get(&p.iso).map(|e| e.value).unwrap_or(0.0))
            .collect();
        let us: Vec<f64> = fits
            .iter()
            .map(|f| f.get(&p.iso).and_then(|e| e.std_uncertainty).unwrap_or(0.0))
            .collect();
        let (linear, exponential) = fit_drift(&t, &vals)?;
        series.push(DriftSeries {
            label: p.iso.clone(),
            t_s: t.clone(),
            values: vals,
            std_uncertainty: us,
            linear,
            exponential,
        });
    }
    Ok((fits, series))
}
