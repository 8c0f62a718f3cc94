//! The model interface: any map R^k → R^m, evaluated point by point or in batches.

use crate::error::{Error, Result};

/// A model y = f(x), x ∈ R^k, y ∈ R^m. Implement [`Model::evaluate`]; override
/// [`Model::evaluate_batch`] when a vectorised evaluation is faster, and [`Model::n_outputs`]
/// when m > 1.
///
/// Closures `Fn(&[f64]) -> f64` are models with one output:
/// ```
/// use mte_sensitivity::Model;
/// let f = |x: &[f64]| x[0] + 2.0 * x[1];
/// let mut y = [0.0];
/// f.evaluate(&[1.0, 1.0], &mut y);
/// assert_eq!(y[0], 3.0);
/// ```
pub trait Model: Sync {
    /// Evaluates the model at one point: `x.len() == k`, `y.len() == n_outputs()`.
    fn evaluate(&self, x: &[f64], y: &mut [f64]);

    /// Number of outputs m (default 1).
    fn n_outputs(&self) -> usize {
        1
    }

    /// Evaluates `n_rows` points stored row-major in `xs` (n_rows × k) into `ys` (n_rows × m).
    fn evaluate_batch(&self, n_rows: usize, xs: &[f64], ys: &mut [f64]) {
        if n_rows == 0 {
            return;
        }
        let k = xs.len() / n_rows;
        let m = ys.len() / n_rows;
        for (x, y) in xs.chunks_exact(k).zip(ys.chunks_exact_mut(m)) {
            self.evaluate(x, y);
        }
    }
}

impl<F: Fn(&[f64]) -> f64 + Sync> Model for F {
    fn evaluate(&self, x: &[f64], y: &mut [f64]) {
        y[0] = self(x);
    }
}

/// A closure with several outputs: `f(x, y)` writes m values.
///
/// ```
/// use mte_sensitivity::{Model, MultiOutput};
/// let f = MultiOutput::new(2, |x: &[f64], y: &mut [f64]| { y[0] = x[0]; y[1] = x[0] * x[1]; });
/// assert_eq!(f.n_outputs(), 2);
/// ```
pub struct MultiOutput<F> {
    m: usize,
    f: F,
}

impl<F: Fn(&[f64], &mut [f64]) + Sync> MultiOutput<F> {
    /// Wraps `f` writing `m` outputs.
    pub fn new(m: usize, f: F) -> Self {
        MultiOutput { m, f }
    }
}

impl<F: Fn(&[f64], &mut [f64]) + Sync> Model for MultiOutput<F> {
    fn evaluate(&self, x: &[f64], y: &mut [f64]) {
        (self.f)(x, y)
    }
    fn n_outputs(&self) -> usize {
        self.m
    }
}

/// Evaluates a batch and checks every output is finite.
pub(crate) fn eval_checked<M: Model + ?Sized>(
    model: &M,
    n_rows: usize,
    k: usize,
    xs: &[f64],
    ys: &mut [f64],
) -> Result<()> {
    let m = model.n_outputs();
    ys.iter_mut().for_each(|v| *v = f64::NAN);
    model.evaluate_batch(n_rows, xs, ys);
    if all_finite(ys) {
        return Ok(());
    }
    if let Some(pos) = ys.iter().position(|v| !v.is_finite()) {
        let row = pos / m;
        return Err(Error::ModelOutput {
            output: pos % m,
            value: ys[pos],
            x: xs[row * k..(row + 1) * k].to_vec(),
        });
    }
    Ok(())
}

/// Whether every value is finite. `v · 0` is 0 for a finite `v` and NaN otherwise, so the lanes
/// sum to NaN exactly when a value is not finite; eight independent lanes let the compiler
/// vectorise what a short-circuiting search cannot (the check runs over every model output).
fn all_finite(ys: &[f64]) -> bool {
    let mut lanes = [0.0f64; 8];
    let chunks = ys.chunks_exact(8);
    let tail = chunks.remainder();
    for c in chunks {
        for (l, v) in lanes.iter_mut().zip(c) {
            *l += v * 0.0;
        }
    }
    lanes.iter().chain(tail).all(|v| v.is_finite())
}

/// Standard test functions with known sensitivity indices.
pub mod testfn {
    use super::Model;
    use crate::dist::{Distribution, Problem};
    use std::f64::consts::PI;

    /// Ishigami function y = sin x₁ + a sin² x₂ + b x₃⁴ sin x₁, xᵢ ~ U(−π, π).
    #[derive(Debug, Clone, Copy)]
    pub struct Ishigami {
        /// a (7 in the usual benchmark).
        pub a: f64,
        /// b (0.1 in the usual benchmark).
        pub b: f64,
    }

    impl Default for Ishigami {
        fn default() -> Self {
            Ishigami { a: 7.0, b: 0.1 }
        }
    }

    impl Ishigami {
        /// The three U(−π, π) inputs.
        pub fn problem() -> Problem {
            Problem::from_dists(&[Distribution::Uniform { lo: -PI, hi: PI }; 3]).expect("valid")
        }
        /// Analytic (S1, ST) (Ishigami & Homma 1990; Saltelli et al. 2008, §4.4).
        pub fn analytic(&self) -> ([f64; 3], [f64; 3]) {
            let (a, b) = (self.a, self.b);
            let v1 = 0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2);
            let v2 = a * a / 8.0;
            let v13 = b * b * PI.powi(8) * (1.0 / 18.0 - 1.0 / 50.0);
            let v = v1 + v2 + v13;
            ([v1 / v, v2 / v, 0.0], [(v1 + v13) / v, v2 / v, v13 / v])
        }
    }

    impl Model for Ishigami {
        fn evaluate(&self, x: &[f64], y: &mut [f64]) {
            let s1 = x[0].sin();
            let s2 = x[1].sin();
            y[0] = s1 + self.a * s2 * s2 + self.b * x[2].powi(4) * s1;
        }
    }

    /// Sobol' G-function g = Π (|4xᵢ − 2| + aᵢ)/(1 + aᵢ), xᵢ ~ U(0, 1).
    #[derive(Debug, Clone)]
    pub struct GFunction {
        a: Vec<f64>,
        inv: Vec<f64>,
    }

    impl GFunction {
        /// With coefficients aᵢ.
        pub fn new(a: Vec<f64>) -> Self {
            let inv = a.iter().map(|v| 1.0 / (1.0 + v)).collect();
            GFunction { a, inv }
        }
        /// The benchmark with aᵢ = (i − 1)/2, i = 1…k (the peers' k = 41 case).
        pub fn benchmark(k: usize) -> Self {
            Self::new((0..k).map(|i| i as f64 / 2.0).collect())
        }
        /// k U(0, 1) inputs.
        pub fn problem(&self) -> Problem {
            Problem::from_dists(&vec![
                Distribution::Uniform { lo: 0.0, hi: 1.0 };
                self.a.len()
            ])
            .expect("valid")
        }
        /// Analytic (S1, ST): Vᵢ = 1/(3(1 + aᵢ)²), V = Π(1 + Vᵢ) − 1, ST_i = Vᵢ Π_{j≠i}(1 + Vⱼ)/V.
        pub fn analytic(&self) -> (Vec<f64>, Vec<f64>) {
            let vi: Vec<f64> = self
                .a
                .iter()
                .map(|a| 1.0 / (3.0 * (1.0 + a) * (1.0 + a)))
                .collect();
            let prod: f64 = vi.iter().map(|v| 1.0 + v).product();
            let v = prod - 1.0;
            (
                vi.iter().map(|x| x / v).collect(),
                vi.iter().map(|x| x * prod / (1.0 + x) / v).collect(),
            )
        }
        /// The coefficients aᵢ.
        pub fn a(&self) -> &[f64] {
            &self.a
        }
    }

    impl Model for GFunction {
        fn evaluate(&self, x: &[f64], y: &mut [f64]) {
            let mut p = 1.0;
            for ((xi, ai), inv) in x.iter().zip(&self.a).zip(&self.inv) {
                p *= ((4.0 * xi - 2.0).abs() + ai) * inv;
            }
            y[0] = p;
        }
    }

    /// Linear model y = Σ aᵢ xᵢ (one output per coefficient row).
    #[derive(Debug, Clone)]
    pub struct Linear {
        /// Coefficients, one row of k per output.
        pub coef: Vec<Vec<f64>>,
    }

    impl Linear {
        /// One output with coefficients `a`.
        pub fn new(a: Vec<f64>) -> Self {
            Linear { coef: vec![a] }
        }
        /// Analytic indices for independent inputs: Sᵢ = STᵢ = aᵢ²σᵢ² / Σ aⱼ²σⱼ² (first output).
        pub fn analytic(&self, problem: &Problem) -> Vec<f64> {
            let w: Vec<f64> = self.coef[0]
                .iter()
                .zip(problem.inputs())
                .map(|(a, i)| (a * i.dist.sd()).powi(2))
                .collect();
            let s: f64 = w.iter().sum();
            w.iter().map(|x| x / s).collect()
        }
    }

    impl Model for Linear {
        fn evaluate(&self, x: &[f64], y: &mut [f64]) {
            for (yo, c) in y.iter_mut().zip(&self.coef) {
                *yo = c.iter().zip(x).map(|(a, b)| a * b).sum();
            }
        }
        fn n_outputs(&self) -> usize {
            self.coef.len()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::all_finite;

    #[test]
    fn all_finite_finds_every_bad_value() {
        let mut ys = vec![1e308; 21];
        assert!(all_finite(&ys));
        for pos in 0..ys.len() {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let keep = ys[pos];
                ys[pos] = bad;
                assert!(!all_finite(&ys), "{bad} at {pos}");
                ys[pos] = keep;
            }
        }
    }
}
