//! Input distributions, the problem definition (inputs + optional correlation) and the
//! isoprobabilistic transform from the unit hypercube / the standard normal germ.

use crate::error::{Error, Result};
use crate::special::{norm_cdf, norm_ppf, norm_ppf_fast};
use mte_linalg::stats::truncated_normal_moments;
use rand::Rng;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// Largest |parameter| (mean, sd, bound) of a distribution: beyond it the variance overflows.
pub const MAX_PARAMETER: f64 = 1e100;

/// Names accepted for `"dist"` in problem files.
pub const DISTRIBUTION_NAMES: &str = "\"normal\", \"uniform\", \"truncated_normal\", \"tolerance\" (normal with mean 0 from a ± tolerance and its coverage)";

/// A univariate input distribution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "dist", rename_all = "snake_case")]
pub enum Distribution {
    /// Normal N(mean, sd²).
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (> 0).
        sd: f64,
    },
    /// Uniform U(lo, hi).
    Uniform {
        /// Lower bound.
        lo: f64,
        /// Upper bound (> lo).
        hi: f64,
    },
    /// Normal N(mean, sd²) truncated to [lo, hi].
    TruncatedNormal {
        /// Mean of the parent normal.
        mean: f64,
        /// Standard deviation of the parent normal (> 0).
        sd: f64,
        /// Lower bound.
        lo: f64,
        /// Upper bound (> lo).
        hi: f64,
    },
}

/// Which orthonormal polynomial family a PCE uses for an input (Wiener–Askey scheme).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Germ {
    /// Standard normal germ ξ ~ N(0, 1), Hermite polynomials.
    Normal,
    /// Uniform germ ξ ~ U(−1, 1), Legendre polynomials.
    Uniform,
}

impl Distribution {
    /// Normal distribution; errors if `sd` is not finite and positive.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field `sd`.
    pub fn normal(mean: f64, sd: f64) -> Result<Self> {
        let d = Distribution::Normal { mean, sd };
        d.validate("normal")?;
        Ok(d)
    }

    /// Uniform distribution on [lo, hi].
    ///
    /// # Errors
    /// [`Error::InvalidInput`] if lo ≥ hi or a bound is not finite.
    pub fn uniform(lo: f64, hi: f64) -> Result<Self> {
        let d = Distribution::Uniform { lo, hi };
        d.validate("uniform")?;
        Ok(d)
    }

    /// Truncated normal distribution.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] if sd ≤ 0, lo ≥ hi, or the interval carries no probability.
    pub fn truncated_normal(mean: f64, sd: f64, lo: f64, hi: f64) -> Result<Self> {
        let d = Distribution::TruncatedNormal { mean, sd, lo, hi };
        d.validate("truncated_normal")?;
        Ok(d)
    }

    /// A tolerance as engineers state it: "± `half_width`" covering `coverage_sigmas` standard
    /// deviations of a zero-mean normal (e.g. ±15 µm at 3σ → σ = 5 µm).
    ///
    /// ```
    /// use mte_sensitivity::Distribution;
    /// let d = Distribution::tolerance(0.015, 3.0).unwrap();   // ±15 µm at 3σ, in mm
    /// assert!((d.sd() - 0.005).abs() < 1e-15);
    /// ```
    ///
    /// # Errors
    /// [`Error::InvalidInput`] if the half width or the coverage is not positive.
    pub fn tolerance(half_width: f64, coverage_sigmas: f64) -> Result<Self> {
        if !(coverage_sigmas.is_finite() && coverage_sigmas > 0.0) {
            return Err(Error::InvalidInput {
                input: "tolerance".into(),
                field: "coverage".into(),
                message: format!(
                    "must be a positive number of standard deviations, got {coverage_sigmas}"
                ),
            });
        }
        Self::normal(0.0, half_width.abs() / coverage_sigmas).map_err(|_| Error::InvalidInput {
            input: "tolerance".into(),
            field: "half_width".into(),
            message: format!("must be finite and non-zero, got {half_width}"),
        })
    }

    /// Checks the parameters; `input` names the input in the error. Parameters must be finite
    /// and within ±[`MAX_PARAMETER`] (so that variances stay finite).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field.
    pub fn validate(&self, input: &str) -> Result<()> {
        let bad = |field: &str, message: String| {
            Err(Error::InvalidInput {
                input: input.to_string(),
                field: field.to_string(),
                message,
            })
        };
        let params: Vec<(&str, f64)> = match *self {
            Distribution::Normal { mean, sd } => vec![("mean", mean), ("sd", sd)],
            Distribution::Uniform { lo, hi } => vec![("lo", lo), ("hi", hi)],
            // infinite bounds are allowed (a half-truncated normal)
            Distribution::TruncatedNormal { mean, sd, lo, hi } => {
                vec![("mean", mean), ("sd", sd), ("lo", lo), ("hi", hi)]
            }
        };
        for (field, v) in params {
            if v.is_finite() && v.abs() > MAX_PARAMETER {
                return bad(
                    field,
                    format!(
                        "{v:e} is beyond ±{MAX_PARAMETER:e}: its square (the variance) overflows; check the unit"
                    ),
                );
            }
        }
        match *self {
            Distribution::Normal { mean, sd } => {
                if !mean.is_finite() {
                    return bad("mean", format!("must be finite, got {mean}"));
                }
                if !(sd.is_finite() && sd > 0.0) {
                    return bad(
                        "sd",
                        format!(
                            "standard deviation must be finite and > 0 (zero variance carries no sensitivity), got {sd}"
                        ),
                    );
                }
            }
            Distribution::Uniform { lo, hi } => {
                if !(lo.is_finite() && hi.is_finite()) {
                    return bad("lo/hi", format!("bounds must be finite, got [{lo}, {hi}]"));
                }
                if lo >= hi {
                    return bad(
                        "hi",
                        format!(
                            "must be greater than lo (zero variance otherwise), got lo = {lo}, hi = {hi}"
                        ),
                    );
                }
            }
            Distribution::TruncatedNormal { mean, sd, lo, hi } => {
                if !mean.is_finite() {
                    return bad("mean", format!("must be finite, got {mean}"));
                }
                if !(sd.is_finite() && sd > 0.0) {
                    return bad(
                        "sd",
                        format!("standard deviation must be finite and > 0, got {sd}"),
                    );
                }
                if lo.is_nan() || hi.is_nan() || lo >= hi {
                    return bad(
                        "hi",
                        format!("must be greater than lo, got lo = {lo}, hi = {hi}"),
                    );
                }
                let (pa, pb) = self.tail_probs();
                if pb - pa < 1e-12 {
                    return bad(
                        "lo/hi",
                        format!(
                            "interval [{lo}, {hi}] carries no probability under N({mean}, {sd}²) (only {:.1e})",
                            pb - pa
                        ),
                    );
                }
            }
        }
        Ok(())
    }

    /// For the truncated normal: Φ of the standardised bounds, in the lower tail (mirrored when
    /// both bounds are above the mean, for accuracy); (0, 1) otherwise.
    fn tail_probs(&self) -> (f64, f64) {
        if let Distribution::TruncatedNormal { mean, sd, lo, hi } = *self {
            let (a, b) = ((lo - mean) / sd, (hi - mean) / sd);
            if a > 0.0 {
                (norm_cdf(-b), norm_cdf(-a))
            } else {
                (norm_cdf(a), norm_cdf(b))
            }
        } else {
            (0.0, 1.0)
        }
    }

    /// Draws one value from `rng` (Monte Carlo of error sets): a standard normal draw scaled,
    /// a uniform draw, or the truncated normal by inverting its CDF in the accurate tail.
    ///
    /// ```
    /// use mte_sensitivity::Distribution;
    /// use rand::SeedableRng;
    /// let d = Distribution::truncated_normal(0.0, 1.0, 3.0, 4.0).unwrap();
    /// let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    /// let x = d.sample(&mut rng);
    /// assert!((3.0..=4.0).contains(&x));
    /// ```
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            Distribution::Normal { mean, sd } => {
                let z: f64 = rng.sample(rand_distr::StandardNormal);
                mean + sd * z
            }
            Distribution::Uniform { lo, hi } => lo + (hi - lo) * rng.random::<f64>(),
            Distribution::TruncatedNormal { mean, sd, lo, hi } => {
                let a = (lo - mean) / sd;
                let (pa, pb) = self.tail_probs();
                let u: f64 = rng.random();
                let p = (pa + u * (pb - pa)).clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON);
                let z = norm_ppf(p);
                let z = if a > 0.0 { -z } else { z };
                (mean + sd * z).clamp(lo, hi)
            }
        }
    }

    /// Nominal value used when not sampling: the mean (normal), the midpoint (uniform), the
    /// parent mean clamped into the interval (truncated normal; not the truncated law's mean,
    /// see [`Distribution::mean`]).
    pub fn nominal(&self) -> f64 {
        match *self {
            Distribution::Normal { mean, .. } => mean,
            Distribution::Uniform { lo, hi } => 0.5 * (lo + hi),
            Distribution::TruncatedNormal { mean, lo, hi, .. } => mean.clamp(lo, hi),
        }
    }

    /// Mean of the distribution.
    pub fn mean(&self) -> f64 {
        match *self {
            Distribution::Normal { mean, .. } => mean,
            Distribution::Uniform { lo, hi } => 0.5 * (lo + hi),
            Distribution::TruncatedNormal { mean, sd, lo, hi } => {
                truncated_normal_moments(mean, sd, lo, hi).0
            }
        }
    }

    /// Standard deviation of the distribution. For the truncated normal this is the truncated
    /// law's (±1σ truncation: 0.54 of the parent's), not the parent's `sd` field.
    pub fn sd(&self) -> f64 {
        match *self {
            Distribution::Normal { sd, .. } => sd,
            Distribution::Uniform { lo, hi } => (hi - lo) / 12f64.sqrt(),
            Distribution::TruncatedNormal { mean, sd, lo, hi } => {
                truncated_normal_moments(mean, sd, lo, hi).1
            }
        }
    }

    /// Quantile function F⁻¹(u), u ∈ (0, 1). Normal quantiles use the fast approximation
    /// (relative error < 1.2e-9), which is far below sampling noise.
    pub fn ppf(&self, u: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, sd } => mean + sd * norm_ppf_fast(u),
            Distribution::Uniform { lo, hi } => lo + (hi - lo) * u,
            Distribution::TruncatedNormal { mean, sd, lo, hi } => {
                let (a, b) = (norm_cdf((lo - mean) / sd), norm_cdf((hi - mean) / sd));
                (mean + sd * norm_ppf(a + u * (b - a))).clamp(lo, hi)
            }
        }
    }

    /// CDF F(x).
    pub fn cdf(&self, x: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, sd } => norm_cdf((x - mean) / sd),
            Distribution::Uniform { lo, hi } => ((x - lo) / (hi - lo)).clamp(0.0, 1.0),
            Distribution::TruncatedNormal { mean, sd, lo, hi } => {
                let (a, b) = (norm_cdf((lo - mean) / sd), norm_cdf((hi - mean) / sd));
                ((norm_cdf((x - mean) / sd) - a) / (b - a)).clamp(0.0, 1.0)
            }
        }
    }

    /// The natural PCE germ of this distribution: Hermite for normal (and truncated normal, through
    /// the isoprobabilistic transform), Legendre for uniform.
    pub fn germ(&self) -> Germ {
        match self {
            Distribution::Uniform { .. } => Germ::Uniform,
            _ => Germ::Normal,
        }
    }

    /// Maps a germ value ξ (standard normal or U(−1, 1), see [`Distribution::germ`]) to x.
    pub fn from_germ(&self, xi: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, sd } => mean + sd * xi,
            Distribution::Uniform { lo, hi } => lo + (hi - lo) * 0.5 * (xi + 1.0),
            Distribution::TruncatedNormal { .. } => self.ppf(norm_cdf(xi)),
        }
    }

    /// Maps x to its germ value ξ (inverse of [`Distribution::from_germ`]).
    pub fn to_germ(&self, x: f64) -> f64 {
        match *self {
            Distribution::Normal { mean, sd } => (x - mean) / sd,
            Distribution::Uniform { lo, hi } => 2.0 * (x - lo) / (hi - lo) - 1.0,
            Distribution::TruncatedNormal { .. } => {
                norm_ppf(self.cdf(x).clamp(1e-300, 1.0 - 1e-16))
            }
        }
    }
}

/// A named model input with its distribution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Input {
    /// Name shown in reports.
    pub name: String,
    /// Distribution.
    #[serde(flatten)]
    pub dist: Distribution,
}

impl Input {
    /// A validated input.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming this input.
    pub fn new(name: impl Into<String>, dist: Distribution) -> Result<Self> {
        let name = name.into();
        dist.validate(&name)?;
        Ok(Input { name, dist })
    }
}

/// The inputs of a study: k named inputs and an optional correlation (Gaussian copula).
///
/// With a correlation matrix C = L Lᵀ, a point is built from independent standard normals z by
/// z' = L z, u = Φ(z'), xᵢ = Fᵢ⁻¹(uᵢ) (Nataf / Gaussian copula). Variance-based indices are then
/// indices of the independent germ variables zᵢ in the given order (xᵢ depends on z₁…zᵢ).
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    inputs: Vec<Input>,
    /// Lower Cholesky factor of the correlation matrix, row-major k×k.
    chol: Option<Vec<f64>>,
}

impl Problem {
    /// Independent inputs.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an invalid distribution, [`Error::Dimension`] for no inputs.
    pub fn new(inputs: Vec<Input>) -> Result<Self> {
        if inputs.is_empty() {
            return Err(Error::Dimension {
                what: "number of inputs".into(),
                expected: 1,
                got: 0,
            });
        }
        for (i, inp) in inputs.iter().enumerate() {
            inp.dist.validate(&inp.name)?;
            if let Some(j) = inputs[..i].iter().position(|o| o.name == inp.name) {
                return Err(Error::InvalidInput {
                    input: format!("{} (inputs[{i}])", inp.name),
                    field: "name".into(),
                    message: format!(
                        "the name `{}` is already used by inputs[{j}]; every input needs its own name",
                        inp.name
                    ),
                });
            }
        }
        Ok(Problem { inputs, chol: None })
    }

    /// Independent inputs from distributions, named `x1 … xk`.
    ///
    /// # Errors
    /// As [`Problem::new`].
    pub fn from_dists(dists: &[Distribution]) -> Result<Self> {
        let inputs = dists
            .iter()
            .enumerate()
            .map(|(i, d)| Input {
                name: format!("x{}", i + 1),
                dist: *d,
            })
            .collect();
        Self::new(inputs)
    }

    /// Adds a correlation matrix (row-major k×k, symmetric, unit diagonal, positive definite).
    ///
    /// # Errors
    /// [`Error::Correlation`] naming the offending entry.
    pub fn with_correlation(mut self, corr: &[f64]) -> Result<Self> {
        let k = self.inputs.len();
        if corr.len() != k * k {
            return Err(Error::Dimension {
                what: "correlation matrix entries (k×k)".into(),
                expected: k * k,
                got: corr.len(),
            });
        }
        for i in 0..k {
            if (corr[i * k + i] - 1.0).abs() > 1e-12 {
                return Err(Error::Correlation(format!(
                    "diagonal entry ({0},{0}) for `{1}` is {2}, expected 1",
                    i,
                    self.inputs[i].name,
                    corr[i * k + i]
                )));
            }
            for j in 0..i {
                let (a, b) = (corr[i * k + j], corr[j * k + i]);
                if !a.is_finite() || (a - b).abs() > 1e-12 || a.abs() >= 1.0 {
                    return Err(Error::Correlation(format!(
                        "entry ({i},{j}) = {a} / ({j},{i}) = {b} between `{}` and `{}` must be symmetric and in (−1, 1)",
                        self.inputs[i].name, self.inputs[j].name
                    )));
                }
            }
        }
        let mut l = vec![0.0; k * k];
        for i in 0..k {
            for j in 0..=i {
                let mut s = corr[i * k + j];
                for p in 0..j {
                    s -= l[i * k + p] * l[j * k + p];
                }
                if i == j {
                    if s <= 1e-12 {
                        return Err(Error::Correlation(format!(
                            "not positive definite (Cholesky pivot {s:.3e} at `{}`)",
                            self.inputs[i].name
                        )));
                    }
                    l[i * k + i] = s.sqrt();
                } else {
                    l[i * k + j] = s / l[j * k + j];
                }
            }
        }
        let independent = (0..k).all(|i| (0..i).all(|j| l[i * k + j] == 0.0));
        self.chol = if independent { None } else { Some(l) };
        Ok(self)
    }

    /// Number of inputs k.
    pub fn dim(&self) -> usize {
        self.inputs.len()
    }

    /// The inputs.
    pub fn inputs(&self) -> &[Input] {
        &self.inputs
    }

    /// Input names.
    pub fn names(&self) -> Vec<String> {
        self.inputs.iter().map(|i| i.name.clone()).collect()
    }

    /// Whether the inputs are correlated.
    pub fn is_correlated(&self) -> bool {
        self.chol.is_some()
    }

    /// Maps a point of the unit hypercube (independent uniforms) to the input space in place
    /// (through the Gaussian copula when correlated).
    pub fn transform_unit(&self, u: &mut [f64]) {
        match &self.chol {
            None => {
                for (x, inp) in u.iter_mut().zip(&self.inputs) {
                    *x = inp.dist.ppf(*x);
                }
            }
            Some(l) => {
                let k = self.inputs.len();
                let z: Vec<f64> = u.iter().map(|&v| norm_ppf_fast(v)).collect();
                for i in 0..k {
                    let zi: f64 = (0..=i).map(|j| l[i * k + j] * z[j]).sum();
                    u[i] = match self.inputs[i].dist {
                        Distribution::Normal { mean, sd } => mean + sd * zi,
                        d => d.ppf(norm_cdf(zi)),
                    };
                }
            }
        }
    }

    /// Maps a point of independent germ values (see [`Distribution::germ`]; standard normals for
    /// every input when correlated) to the input space in place.
    pub fn transform_germ(&self, xi: &mut [f64]) {
        match &self.chol {
            None => {
                for (x, inp) in xi.iter_mut().zip(&self.inputs) {
                    *x = inp.dist.from_germ(*x);
                }
            }
            Some(l) => {
                let k = self.inputs.len();
                let z = xi.to_vec();
                for i in 0..k {
                    let zi: f64 = (0..=i).map(|j| l[i * k + j] * z[j]).sum();
                    xi[i] = match self.inputs[i].dist {
                        Distribution::Normal { mean, sd } => mean + sd * zi,
                        d => d.ppf(norm_cdf(zi)),
                    };
                }
            }
        }
    }

    /// Inverse of [`Problem::transform_germ`]: input values to independent germ values, in place.
    pub fn to_germ(&self, x: &mut [f64]) {
        match &self.chol {
            None => {
                for (v, inp) in x.iter_mut().zip(&self.inputs) {
                    *v = inp.dist.to_germ(*v);
                }
            }
            Some(l) => {
                let k = self.inputs.len();
                let zc: Vec<f64> = x
                    .iter()
                    .zip(&self.inputs)
                    .map(|(&v, inp)| match inp.dist {
                        Distribution::Normal { mean, sd } => (v - mean) / sd,
                        d => norm_ppf(d.cdf(v).clamp(1e-300, 1.0 - 1e-16)),
                    })
                    .collect();
                for i in 0..k {
                    let mut s = zc[i];
                    for j in 0..i {
                        s -= l[i * k + j] * x[j];
                    }
                    x[i] = s / l[i * k + i];
                }
            }
        }
    }

    /// The germ family used for each input by PCE.
    pub fn germs(&self) -> Vec<Germ> {
        if self.chol.is_some() {
            vec![Germ::Normal; self.inputs.len()]
        } else {
            self.inputs.iter().map(|i| i.dist.germ()).collect()
        }
    }

    /// Reads a problem from a JSON value:
    /// `{"inputs": [{"name": "x1", "dist": "uniform", "lo": 0, "hi": 1}, …], "correlation": [[…]]}`.
    /// A `"tolerance"` input takes `"half_width"` and `"coverage"` (σ multiples, default 3).
    ///
    /// # Errors
    /// [`Error::Json`] / [`Error::UnknownDistribution`] / [`Error::InvalidInput`] naming the
    /// input (by name and index) and field.
    pub fn from_json(v: &Value) -> Result<Self> {
        let arr = v
            .get("inputs")
            .and_then(Value::as_array)
            .ok_or_else(|| Error::Json {
                context: "problem".into(),
                message: "field `inputs` must be an array of inputs".into(),
            })?;
        let mut inputs = Vec::with_capacity(arr.len());
        for (i, iv) in arr.iter().enumerate() {
            inputs.push(input_from_json(iv, i)?);
        }
        let p = Problem::new(inputs)?;
        match v.get("correlation") {
            None | Some(Value::Null) => Ok(p),
            Some(c) => {
                let k = p.dim();
                let rows = c.as_array().ok_or_else(|| Error::Json {
                    context: "correlation".into(),
                    message: format!("must be a {k}×{k} array of arrays"),
                })?;
                if rows.len() != k {
                    return Err(Error::Dimension {
                        what: "correlation: number of rows".into(),
                        expected: k,
                        got: rows.len(),
                    });
                }
                let mut m = Vec::with_capacity(k * k);
                for (r, row) in rows.iter().enumerate() {
                    let row =
                        row.as_array()
                            .filter(|a| a.len() == k)
                            .ok_or_else(|| Error::Json {
                                context: format!("correlation[{r}]"),
                                message: format!("must be an array of {k} numbers"),
                            })?;
                    for (c, x) in row.iter().enumerate() {
                        m.push(x.as_f64().ok_or_else(|| Error::Json {
                            context: format!("correlation[{r}][{c}]"),
                            message: "must be a number".into(),
                        })?);
                    }
                }
                p.with_correlation(&m)
            }
        }
    }
}

fn input_from_json(v: &Value, index: usize) -> Result<Input> {
    let name = v
        .get("name")
        .and_then(Value::as_str)
        .map(str::to_string)
        .unwrap_or_else(|| format!("x{}", index + 1));
    let label = format!("{name} (inputs[{index}])");
    let num = |field: &str| -> Result<f64> {
        v.get(field)
            .and_then(Value::as_f64)
            .ok_or_else(|| Error::InvalidInput {
                input: label.clone(),
                field: field.to_string(),
                message: "missing or not a number".into(),
            })
    };
    let dname = v
        .get("dist")
        .and_then(Value::as_str)
        .ok_or_else(|| Error::InvalidInput {
            input: label.clone(),
            field: "dist".into(),
            message: format!("missing; expected one of {DISTRIBUTION_NAMES}"),
        })?;
    let dist = match dname {
        "normal" | "gaussian" => Distribution::Normal {
            mean: v.get("mean").and_then(Value::as_f64).unwrap_or(0.0),
            sd: num("sd")?,
        },
        "uniform" => Distribution::Uniform {
            lo: num("lo")?,
            hi: num("hi")?,
        },
        "truncated_normal" => Distribution::TruncatedNormal {
            mean: v.get("mean").and_then(Value::as_f64).unwrap_or(0.0),
            sd: num("sd")?,
            lo: num("lo")?,
            hi: num("hi")?,
        },
        "tolerance" => {
            let hw = num("half_width")?;
            let cov = v.get("coverage").and_then(Value::as_f64).unwrap_or(3.0);
            if !(cov.is_finite() && cov > 0.0) {
                return Err(Error::InvalidInput {
                    input: label,
                    field: "coverage".into(),
                    message: format!("must be > 0 standard deviations, got {cov}"),
                });
            }
            Distribution::Normal {
                mean: v.get("mean").and_then(Value::as_f64).unwrap_or(0.0),
                sd: hw.abs() / cov,
            }
        }
        other => {
            return Err(Error::UnknownDistribution {
                input: label,
                name: other.to_string(),
                expected: DISTRIBUTION_NAMES,
            });
        }
    };
    if let Some(o) = v.as_object() {
        const KNOWN: [&str; 8] = [
            "name",
            "dist",
            "mean",
            "sd",
            "lo",
            "hi",
            "half_width",
            "coverage",
        ];
        if let Some(k) = o.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(Error::InvalidInput {
                input: label,
                field: k.clone(),
                message: format!("unknown field; expected {}", KNOWN.join(", ")),
            });
        }
    } else {
        return Err(Error::Json {
            context: format!("inputs[{index}]"),
            message: "must be an object {\"name\": …, \"dist\": …}".into(),
        });
    }
    dist.validate(&label)?;
    Ok(Input { name, dist })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_match_formulas() {
        // Uniform(0, 1): sd = 1/√12. Truncated N(0,1) on [−1, 1]: var = 1 − 2φ(1)/(Φ(1) − Φ(−1))
        // = 0.291_125_094_772_793 (Johnson, Kotz & Balakrishnan, truncated-normal moments).
        let u = Distribution::uniform(0.0, 1.0).unwrap();
        assert!((u.sd() - 0.288_675_134_594_812_9).abs() < 1e-15);
        let t = Distribution::truncated_normal(0.0, 1.0, -1.0, 1.0).unwrap();
        assert!((t.sd() * t.sd() - 0.291_125_094_772_793).abs() < 1e-13);
        assert!(t.mean().abs() < 1e-15);
        for i in 1..20 {
            let p = i as f64 / 20.0;
            assert!((t.cdf(t.ppf(p)) - p).abs() < 1e-12);
            assert!((u.to_germ(u.from_germ(2.0 * p - 1.0)) - (2.0 * p - 1.0)).abs() < 1e-15);
            assert!((t.to_germ(t.from_germ(p - 0.5)) - (p - 0.5)).abs() < 1e-9);
        }
    }

    #[test]
    fn bad_inputs_name_the_field() {
        let e = Distribution::normal(0.0, 0.0).unwrap_err();
        assert!(e.to_string().contains("sd"), "{e}");
        let v: Value = serde_json::json!({"inputs": [{"name": "a", "dist": "uniform", "lo": 0, "hi": 1},
            {"name": "b", "dist": "weibull", "k": 2}]});
        let e = Problem::from_json(&v).unwrap_err();
        assert!(matches!(e, Error::UnknownDistribution { .. }));
        assert!(
            e.to_string().contains("b (inputs[1])") && e.to_string().contains("weibull"),
            "{e}"
        );
        let v: Value =
            serde_json::json!({"inputs": [{"name": "a", "dist": "uniform", "lo": 1, "hi": 1}]});
        let e = Problem::from_json(&v).unwrap_err();
        assert!(
            e.to_string().contains("a (inputs[0])") && e.to_string().contains("hi"),
            "{e}"
        );
        let v: Value = serde_json::json!({"inputs": [{"name": "a", "dist": "normal", "sd": 1},
            {"name": "b", "dist": "normal", "sd": 1}], "correlation": [[1, 1.5], [1.5, 1]]});
        assert!(matches!(
            Problem::from_json(&v).unwrap_err(),
            Error::Correlation(_)
        ));
    }

    #[test]
    fn tolerance_reads_three_sigma() {
        let v: Value = serde_json::json!({"inputs": [{"name": "dx", "dist": "tolerance", "half_width": 0.015}]});
        let p = Problem::from_json(&v).unwrap();
        assert!((p.inputs()[0].dist.sd() - 0.005).abs() < 1e-15);
    }

    #[test]
    fn copula_roundtrip() {
        let p = Problem::from_dists(&[
            Distribution::normal(1.0, 2.0).unwrap(),
            Distribution::uniform(0.0, 1.0).unwrap(),
        ])
        .unwrap()
        .with_correlation(&[1.0, 0.5, 0.5, 1.0])
        .unwrap();
        let mut x = [0.3, -0.7];
        let z = x;
        p.transform_germ(&mut x);
        p.to_germ(&mut x);
        assert!(
            (x[0] - z[0]).abs() < 1e-9 && (x[1] - z[1]).abs() < 1e-9,
            "{x:?}"
        );
    }
}
