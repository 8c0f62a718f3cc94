//! Local sensitivity: gradient × input spread (the classic unit-increment method) and seed 000's
//! motion-increment method (Fan et al. 2019, eqs 12–13 and index 16).

use crate::dist::Problem;
use crate::error::{Error, Result};
use crate::model::{Model, eval_checked};
use serde::{Deserialize, Serialize};

/// Result of a local analysis for one output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LocalIndices {
    /// Raw effect per input (|∂f/∂xᵢ|·σᵢ, or the range Eₙ).
    pub effect: Vec<f64>,
    /// Normalised shares Sᵢ = effectᵢ / Σ effect.
    pub share: Vec<f64>,
}

fn shares(effect: Vec<f64>) -> Result<LocalIndices> {
    let s: f64 = effect.iter().sum();
    if !(s > 0.0) {
        return Err(Error::Degenerate {
            output: 0,
            message: "all local effects are zero".into(),
        });
    }
    Ok(LocalIndices {
        share: effect.iter().map(|e| e / s).collect(),
        effect,
    })
}

/// Gradient × spread at the input means: effectᵢ = |∂f/∂xᵢ|·σᵢ by central differences with step
/// `rel_step`·σᵢ. Exact for linear models. Returns one result per output.
///
/// ```
/// use mte_sensitivity::{local::gradient_spread, Problem, Distribution};
/// let p = Problem::from_dists(&[Distribution::normal(0.0, 1.0).unwrap(), Distribution::normal(0.0, 2.0).unwrap()]).unwrap();
/// let r = gradient_spread(&|x: &[f64]| 3.0 * x[0] + x[1], &p, 1e-3).unwrap();
/// assert!((r[0].share[0] - 0.6).abs() < 1e-12);
/// ```
///
/// # Errors
/// [`Error::ModelOutput`] for non-finite values, [`Error::Degenerate`] when every effect is zero.
pub fn gradient_spread<M: Model + ?Sized>(
    model: &M,
    problem: &Problem,
    rel_step: f64,
) -> Result<Vec<LocalIndices>> {
    let k = problem.dim();
    let m = model.n_outputs();
    let x0: Vec<f64> = problem.inputs().iter().map(|i| i.dist.mean()).collect();
    let mut xs = Vec::with_capacity(2 * k * k);
    for i in 0..k {
        let h = rel_step * problem.inputs()[i].dist.sd();
        for s in [1.0, -1.0] {
            let mut x = x0.clone();
            x[i] += s * h;
            xs.extend_from_slice(&x);
        }
    }
    let mut ys = vec![0.0; 2 * k * m];
    eval_checked(model, 2 * k, k, &xs, &mut ys)?;
    (0..m)
        .map(|o| {
            let eff = (0..k)
                .map(|i| {
                    let sd = problem.inputs()[i].dist.sd();
                    let h = rel_step * sd;
                    ((ys[(2 * i) * m + o] - ys[(2 * i + 1) * m + o]) / (2.0 * h)).abs() * sd
                })
                .collect();
            shares(eff).map_err(|_| Error::Degenerate {
                output: o,
                message: "all local effects are zero".into(),
            })
        })
        .collect()
}

/// Motion-increment index (seed 000, eqs 12–13, 16): for each input n and trajectory point t,
/// ΔEₙ(t) = ∂E/∂δₙ(t) · dδₙ/dsₙ(t) · Δsₙ(t); Eₙ = max_t ΔEₙ − min_t ΔEₙ; Sₙ = Eₙ / Σ E.
/// `sens[n][t]` = ∂E/∂δₙ, `rate[n][t]` = dδₙ/dsₙ (1 for position-independent errors), `ds[n][t]`
/// = Δsₙ (the increment of the axis the error depends on; 1 for position-independent errors).
///
/// # Errors
/// [`Error::Dimension`] when the series lengths differ, [`Error::Degenerate`] when all ranges are 0.
pub fn motion_increment(
    sens: &[Vec<f64>],
    rate: &[Vec<f64>],
    ds: &[Vec<f64>],
) -> Result<LocalIndices> {
    let n_in = sens.len();
    if rate.len() != n_in || ds.len() != n_in {
        return Err(Error::Dimension {
            what: "motion increment: number of inputs in rate/ds".into(),
            expected: n_in,
            got: rate.len().min(ds.len()),
        });
    }
    let mut eff = Vec::with_capacity(n_in);
    for n in 0..n_in {
        let t = sens[n].len();
        if rate[n].len() != t || ds[n].len() != t || t == 0 {
            return Err(Error::Dimension {
                what: format!("motion increment: series length of input {n}"),
                expected: t,
                got: rate[n].len().min(ds[n].len()),
            });
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for i in 0..t {
            let d = sens[n][i] * rate[n][i] * ds[n][i];
            if !d.is_finite() {
                return Err(Error::ModelOutput {
                    output: 0,
                    value: d,
                    x: vec![n as f64, i as f64],
                });
            }
            lo = lo.min(d);
            hi = hi.max(d);
        }
        eff.push(hi - lo);
    }
    shares(eff)
}

/// Classic unit-increment index over the same points: Eₙ = range over t of ∂E/∂δₙ(t) · uₙ with a
/// unit (or tolerance) increment uₙ, Sₙ = Eₙ / Σ E.
///
/// # Errors
/// As [`motion_increment`].
pub fn unit_increment(sens: &[Vec<f64>], unit: &[f64]) -> Result<LocalIndices> {
    let rate: Vec<Vec<f64>> = sens.iter().map(|s| vec![1.0; s.len()]).collect();
    let ds: Vec<Vec<f64>> = sens
        .iter()
        .zip(unit)
        .map(|(s, u)| vec![*u; s.len()])
        .collect();
    if unit.len() != sens.len() {
        return Err(Error::Dimension {
            what: "unit increments".into(),
            expected: sens.len(),
            got: unit.len(),
        });
    }
    motion_increment(sens, &rate, &ds)
}
