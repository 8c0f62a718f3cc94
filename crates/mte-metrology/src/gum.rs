//! GUM Supplement 1 (JCGM 101:2008) Monte Carlo propagation of distributions for any scalar
//! measurement function, with the first-order GUM uncertainty framework (GUF) and the §8
//! validation of the GUF against the Monte Carlo result.
//!
//! Reproducibility: trials are split into fixed chunks of [`CHUNK`] trials; chunk `c` draws
//! from `ChaCha20Rng::seed_from_u64(seed)` with stream `c`, so the values — and every result —
//! are identical for any number of threads.

use crate::error::{Result, invalid};
use crate::stats;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha20Rng;
use rand_distr::{Distribution as _, StandardNormal, StudentT};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Trials per chunk (fixed: the chunk index is the random stream).
pub const CHUNK: usize = 1024;

/// A scalar measurement function Y = f(X₁, …, X_N). One required method.
pub trait MeasurementFunction: Sync {
    /// Evaluate f at input values `x`.
    fn evaluate(&self, x: &[f64]) -> f64;
    /// Sensitivity coefficients ∂f/∂xᵢ at `x`, if known analytically (default: none → central
    /// differences with step uᵢ/100 are used by [`gum_framework`]).
    fn sensitivities(&self, _x: &[f64]) -> Option<Vec<f64>> {
        None
    }
}

impl<F: Fn(&[f64]) -> f64 + Sync> MeasurementFunction for F {
    fn evaluate(&self, x: &[f64]) -> f64 {
        self(x)
    }
}

/// Probability distribution of an input quantity (GUM-S1 §6.4).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum InputDistribution {
    /// Gaussian N(mean, sd²).
    Normal {
        /// Expectation.
        mean: f64,
        /// Standard deviation.
        sd: f64,
    },
    /// Rectangular on [a, b].
    Rectangular {
        /// Lower limit.
        a: f64,
        /// Upper limit.
        b: f64,
    },
    /// Symmetric triangular on [a, b].
    Triangular {
        /// Lower limit.
        a: f64,
        /// Upper limit.
        b: f64,
    },
    /// Arc sine (U-shaped) on [a, b].
    ArcSine {
        /// Lower limit.
        a: f64,
        /// Upper limit.
        b: f64,
    },
    /// Scaled and shifted t: mean + scale·t_ν (GUM-S1 6.4.9).
    StudentT {
        /// Location.
        mean: f64,
        /// Scale.
        scale: f64,
        /// Degrees of freedom ν.
        dof: f64,
    },
}

impl InputDistribution {
    /// Expectation.
    pub fn mean(&self) -> f64 {
        match *self {
            Self::Normal { mean, .. } | Self::StudentT { mean, .. } => mean,
            Self::Rectangular { a, b } | Self::Triangular { a, b } | Self::ArcSine { a, b } => {
                0.5 * (a + b)
            }
        }
    }
    /// Standard deviation.
    pub fn sd(&self) -> f64 {
        match *self {
            Self::Normal { sd, .. } => sd,
            Self::Rectangular { a, b } => (b - a) / 12f64.sqrt(),
            Self::Triangular { a, b } => (b - a) / 24f64.sqrt(),
            Self::ArcSine { a, b } => (b - a) / 8f64.sqrt(),
            Self::StudentT { scale, dof, .. } => {
                if dof > 2.0 {
                    scale * (dof / (dof - 2.0)).sqrt()
                } else {
                    f64::INFINITY
                }
            }
        }
    }
    fn check(&self, i: usize) -> Result<()> {
        let ok = match *self {
            Self::Normal { mean, sd } => mean.is_finite() && sd.is_finite() && sd >= 0.0,
            Self::Rectangular { a, b } | Self::Triangular { a, b } | Self::ArcSine { a, b } => {
                a.is_finite() && b.is_finite() && b >= a
            }
            Self::StudentT { mean, scale, dof } => {
                mean.is_finite() && scale.is_finite() && scale >= 0.0 && dof > 0.0
            }
        };
        if ok {
            Ok(())
        } else {
            Err(invalid(format!("input {i}: invalid distribution {self:?}")))
        }
    }
    fn sample<R: Rng>(&self, rng: &mut R) -> f64 {
        match *self {
            Self::Normal { mean, sd } => {
                let z: f64 = StandardNormal.sample(rng);
                mean + sd * z
            }
            Self::Rectangular { a, b } => a + (b - a) * rng.random::<f64>(),
            Self::Triangular { a, b } => {
                a + 0.5 * (b - a) * (rng.random::<f64>() + rng.random::<f64>())
            }
            Self::ArcSine { a, b } => {
                0.5 * (a + b) + 0.5 * (b - a) * (std::f64::consts::PI * rng.random::<f64>()).sin()
            }
            Self::StudentT { mean, scale, dof } => {
                let t: f64 = StudentT::new(dof).map(|d| d.sample(rng)).unwrap_or(0.0);
                mean + scale * t
            }
        }
    }
}

/// Monte Carlo result in GUM-S1 form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct McResult {
    /// Number of trials M.
    pub trials: usize,
    /// Estimate y = mean of the model values (GUM-S1 eq. 12).
    pub estimate: f64,
    /// Standard uncertainty u(y) (GUM-S1 eq. 13, 1/(M−1)).
    pub standard_uncertainty: f64,
    /// Coverage probability p.
    pub coverage: f64,
    /// Probabilistically symmetric coverage interval (GUM-S1 7.7.2).
    pub symmetric_interval: (f64, f64),
    /// Shortest coverage interval (GUM-S1 7.7.3).
    pub shortest_interval: (f64, f64),
    /// Adaptive runs used (h), 1 for a fixed M.
    pub batches: usize,
    /// Numerical tolerance δ reached (adaptive only; 0 for fixed M).
    pub tolerance: f64,
}

/// Parameters of a Monte Carlo run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct McParams {
    /// Trials M (fixed), or trials per batch (adaptive; at least max(10⁴, 100/(1 − p))).
    pub trials: usize,
    /// Coverage probability p (0.95).
    pub coverage: f64,
    /// Seed.
    pub seed: u64,
}

impl Default for McParams {
    fn default() -> Self {
        Self {
            trials: 100_000,
            coverage: 0.95,
            seed: 1,
        }
    }
}

/// Draw model values for trials [first_chunk·CHUNK, …) of `n` trials (deterministic).
fn draws<F: MeasurementFunction + ?Sized>(
    f: &F,
    inputs: &[InputDistribution],
    seed: u64,
    first_chunk: usize,
    n: usize,
) -> Vec<f64> {
    let nchunks = n.div_ceil(CHUNK);
    let parts: Vec<Vec<f64>> = (0..nchunks)
        .into_par_iter()
        .map(|c| {
            let mut rng = ChaCha20Rng::seed_from_u64(seed);
            rng.set_stream((first_chunk + c) as u64);
            let m = CHUNK.min(n - c * CHUNK);
            let mut x = vec![0.0; inputs.len()];
            let mut out = Vec::with_capacity(m);
            for _ in 0..m {
                for (xi, d) in x.iter_mut().zip(inputs) {
                    *xi = d.sample(&mut rng);
                }
                out.push(f.evaluate(&x));
            }
            out
        })
        .collect();
    parts.concat()
}

/// Summarise sorted model values (GUM-S1 §7.5–7.7).
///
/// # Errors
/// Too few values for the coverage probability, or non-finite model values.
pub fn summarise(values: &mut [f64], coverage: f64) -> Result<McResult> {
    let m = values.len();
    if !(coverage > 0.0 && coverage < 1.0) {
        return Err(invalid(format!(
            "coverage probability must be in (0, 1), got {coverage}"
        )));
    }
    if m < 2 || (m as f64) < 1.0 / (1.0 - coverage) {
        return Err(invalid(format!(
            "{m} trials are too few for p = {coverage}"
        )));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(invalid(format!(
            "model value #{i} is {} (the measurement function failed)",
            values[i]
        )));
    }
    let mean = values.iter().sum::<f64>() / m as f64;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (m as f64 - 1.0);
    values.sort_by(|a, b| a.total_cmp(b));
    // q = pM if integer, else ⌊pM + 1/2⌋ (GUM-S1 7.7.1)
    let pm = coverage * m as f64;
    let q = if (pm - pm.round()).abs() < 1e-9 {
        pm.round() as usize
    } else {
        (pm + 0.5).floor() as usize
    };
    let q = q.clamp(1, m - 1);
    // symmetric: r = (M − q)/2 if integer, else (M − q + 1)/2 (1-based)
    let r = if (m - q) % 2 == 0 {
        (m - q) / 2
    } else {
        (m - q).div_ceil(2)
    };
    let r = r.max(1);
    let symmetric = (values[r - 1], values[(r + q - 1).min(m - 1)]);
    let mut best = (f64::INFINITY, 0usize);
    for r in 0..(m - q) {
        let w = values[r + q] - values[r];
        if w < best.0 {
            best = (w, r);
        }
    }
    let shortest = (values[best.1], values[best.1 + q]);
    Ok(McResult {
        trials: m,
        estimate: mean,
        standard_uncertainty: var.sqrt(),
        coverage,
        symmetric_interval: symmetric,
        shortest_interval: shortest,
        batches: 1,
        tolerance: 0.0,
    })
}

/// Monte Carlo with a fixed number of trials M (GUM-S1 §7).
///
/// # Errors
/// Invalid distributions, too few trials for p, or non-finite model values.
///
/// ```
/// use mte_metrology::gum::{monte_carlo, InputDistribution, McParams};
/// // Y = X1 + X2, X1 ~ N(1, 0.3²), X2 ~ N(2, 0.4²): u(y) = 0.5
/// let f = |x: &[f64]| x[0] + x[1];
/// let inputs = [InputDistribution::Normal { mean: 1.0, sd: 0.3 },
///               InputDistribution::Normal { mean: 2.0, sd: 0.4 }];
/// let r = monte_carlo(&f, &inputs, &McParams { trials: 200_000, coverage: 0.95, seed: 3 }).unwrap();
/// assert!((r.estimate - 3.0).abs() < 0.01 && (r.standard_uncertainty - 0.5).abs() < 0.01);
/// ```
pub fn monte_carlo<F: MeasurementFunction + ?Sized>(
    f: &F,
    inputs: &[InputDistribution],
    params: &McParams,
) -> Result<McResult> {
    for (i, d) in inputs.iter().enumerate() {
        d.check(i)?;
    }
    let mut v = draws(f, inputs, params.seed, 0, params.trials);
    summarise(&mut v, params.coverage)
}

/// Numerical tolerance δ of a value `u` stated with `n_dig` significant digits:
/// u = c·10^l with c an n_dig-digit integer → δ = ½·10^l (GUM-S1 7.9.2).
pub fn numerical_tolerance(u: f64, n_dig: u32) -> f64 {
    if u <= 0.0 || !u.is_finite() {
        return 0.0;
    }
    let l = u.log10().floor() as i32 - (n_dig as i32 - 1);
    0.5 * 10f64.powi(l)
}

/// Adaptive Monte Carlo (GUM-S1 7.9.4): batches of M = max(`params.trials`, 10⁴, 100/(1 − p))
/// trials until twice the standard deviations of the batch means of y, u(y) and both interval
/// ends are all ≤ δ for `n_dig` significant digits of u(y). Results use all trials.
///
/// # Errors
/// As [`monte_carlo`]; also when `max_trials` is reached before the tolerance.
pub fn monte_carlo_adaptive<F: MeasurementFunction + ?Sized>(
    f: &F,
    inputs: &[InputDistribution],
    params: &McParams,
    n_dig: u32,
    max_trials: usize,
) -> Result<McResult> {
    for (i, d) in inputs.iter().enumerate() {
        d.check(i)?;
    }
    let j = (100.0 / (1.0 - params.coverage)).ceil() as usize;
    let m = params.trials.max(10_000).max(j).div_ceil(CHUNK) * CHUNK;
    let mut all = Vec::new();
    let mut stats_h: Vec<[f64; 5]> = Vec::new();
    let mut h = 0;
    loop {
        let mut v = draws(f, inputs, params.seed, h * (m / CHUNK), m);
        all.extend_from_slice(&v);
        let r = summarise(&mut v, params.coverage)?;
        stats_h.push([
            r.estimate,
            r.standard_uncertainty,
            r.symmetric_interval.0,
            r.symmetric_interval.1,
            0.0,
        ]);
        h += 1;
        if h >= 2 {
            let hf = h as f64;
            let sd_of_mean = |k: usize| {
                let mean = stats_h.iter().map(|s| s[k]).sum::<f64>() / hf;
                (stats_h.iter().map(|s| (s[k] - mean).powi(2)).sum::<f64>() / (hf * (hf - 1.0)))
                    .sqrt()
            };
            let u_all = stats_h.iter().map(|s| s[1]).sum::<f64>() / hf;
            let delta = numerical_tolerance(u_all, n_dig);
            if (0..4).all(|k| 2.0 * sd_of_mean(k) <= delta) {
                let mut res = summarise(&mut all, params.coverage)?;
                res.batches = h;
                res.tolerance = numerical_tolerance(res.standard_uncertainty, n_dig);
                return Ok(res);
            }
        }
        if all.len() + m > max_trials {
            return Err(invalid(format!(
                "adaptive Monte Carlo did not reach {n_dig} significant digits within {max_trials} trials"
            )));
        }
    }
}

/// How sensitivity coefficients are obtained in [`gum_framework`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sensitivities {
    /// Use [`MeasurementFunction::sensitivities`], falling back to numerical ones.
    SuppliedOrNumerical,
    /// Central differences with step uᵢ/100.
    Numerical,
}

/// First-order GUM uncertainty framework result (law of propagation of uncertainty,
/// uncorrelated inputs, Gaussian output: y ± z_p·u).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GufResult {
    /// y = f(x̄).
    pub estimate: f64,
    /// u(y) = √Σ(cᵢuᵢ)².
    pub standard_uncertainty: f64,
    /// Sensitivity coefficients cᵢ.
    pub sensitivities: Vec<f64>,
    /// y ± z_p·u(y).
    pub interval: (f64, f64),
}

/// The GUM uncertainty framework for uncorrelated inputs (GUM 5.1.2).
///
/// # Errors
/// Invalid distributions or a non-finite model value.
pub fn gum_framework<F: MeasurementFunction + ?Sized>(
    f: &F,
    inputs: &[InputDistribution],
    coverage: f64,
    mode: Sensitivities,
) -> Result<GufResult> {
    for (i, d) in inputs.iter().enumerate() {
        d.check(i)?;
    }
    let x: Vec<f64> = inputs.iter().map(|d| d.mean()).collect();
    let y = f.evaluate(&x);
    if !y.is_finite() {
        return Err(invalid(format!(
            "model value at the input estimates is {y}"
        )));
    }
    let c = match (mode, f.sensitivities(&x)) {
        (Sensitivities::SuppliedOrNumerical, Some(c)) if c.len() == x.len() => c,
        _ => {
            let mut c = Vec::with_capacity(x.len());
            let mut xp = x.clone();
            for (i, d) in inputs.iter().enumerate() {
                let h = if d.sd() > 0.0 && d.sd().is_finite() {
                    d.sd() / 100.0
                } else {
                    1e-6 * x[i].abs().max(1.0)
                };
                xp[i] = x[i] + h;
                let a = f.evaluate(&xp);
                xp[i] = x[i] - h;
                let b = f.evaluate(&xp);
                xp[i] = x[i];
                c.push((a - b) / (2.0 * h));
            }
            c
        }
    };
    let u = c
        .iter()
        .zip(inputs)
        .map(|(ci, d)| (ci * d.sd()).powi(2))
        .sum::<f64>()
        .sqrt();
    let k = stats::normal_quantile(0.5 + coverage / 2.0);
    Ok(GufResult {
        estimate: y,
        standard_uncertainty: u,
        sensitivities: c,
        interval: (y - k * u, y + k * u),
    })
}

/// Validation of the GUF by Monte Carlo (GUM-S1 §8).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    /// Numerical tolerance δ from `n_dig` significant digits of u(y) (GUF).
    pub tolerance: f64,
    /// |y_GUF − U_p − y_low,MC|.
    pub d_low: f64,
    /// |y_GUF + U_p − y_high,MC|.
    pub d_high: f64,
    /// Both ≤ δ: the GUF is validated.
    pub validated: bool,
}

/// Compare the GUF interval with the Monte Carlo probabilistically symmetric interval (§8.2).
pub fn validate(guf: &GufResult, mc: &McResult, n_dig: u32) -> Validation {
    let tol = numerical_tolerance(guf.standard_uncertainty, n_dig);
    let d_low = (guf.interval.0 - mc.symmetric_interval.0).abs();
    let d_high = (guf.interval.1 - mc.symmetric_interval.1).abs();
    Validation {
        tolerance: tol,
        d_low,
        d_high,
        validated: d_low <= tol && d_high <= tol,
    }
}
