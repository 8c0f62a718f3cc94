//! Variance-based (Sobol') indices by the pick-freeze scheme: Saltelli (2010) first-order and
//! Jansen (1999) total-effect estimators, optional Saltelli (2002) second-order indices, on Monte
//! Carlo, Latin hypercube or scrambled Sobol' designs; bootstrap intervals and convergence curves.
//!
//! With base matrices A, B (N × k) and A_B⁽ⁱ⁾ = A with column i from B:
//! V = Var over [f(A); f(B)], Vᵢ = (1/N) Σ f(B)(f(A_B⁽ⁱ⁾) − f(A)), V_Tᵢ = (1/2N) Σ (f(A) − f(A_B⁽ⁱ⁾))²,
//! Sᵢ = Vᵢ/V, S_Tᵢ = V_Tᵢ/V (Saltelli et al. 2010, Table 2, rows (b) and (f)).
//! Cost: N(k + 2) model runs (N(2k + 2) with second-order indices).
//!
//! Work is split in fixed blocks of rows; each block's design and partial sums depend only on
//! (seed, block), and blocks are summed in order, so results are identical for any thread count.
//! The bootstrap resamples these blocks (rows are i.i.d. under Monte Carlo, so blocks are too).

use crate::design::{ROW_BLOCK, Sampling, UnitDesign};
use crate::dist::Problem;
use crate::error::{Error, Result};
use crate::model::{Model, eval_checked};
use crate::stats::{NoProgress, Progress, interval, stream};
use rand::Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Settings of a Sobol' analysis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SobolParams {
    /// Base sample size N (model runs N(k + 2)). Powers of two suit the Sobol' design best.
    pub n: usize,
    /// Design of the base matrices.
    pub sampling: Sampling,
    /// Seed of every random stream.
    pub seed: u64,
    /// Bootstrap replicates for the intervals (0 = none).
    pub n_bootstrap: usize,
    /// Confidence level of the intervals.
    pub confidence: f64,
    /// Also estimate second-order indices (Saltelli 2002; N(2k + 2) runs).
    pub second_order: bool,
    /// Sample sizes at which to record estimates for a convergence curve (rounded down to the
    /// block size).
    pub checkpoints: Vec<usize>,
}

impl Default for SobolParams {
    fn default() -> Self {
        SobolParams {
            n: 8192,
            sampling: Sampling::Sobol,
            seed: 0,
            n_bootstrap: 100,
            confidence: 0.95,
            second_order: false,
            checkpoints: vec![],
        }
    }
}

/// Indices of one output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SobolIndices {
    /// First-order indices Sᵢ.
    pub first: Vec<f64>,
    /// Total-effect indices S_Tᵢ.
    pub total: Vec<f64>,
    /// Bootstrap intervals of Sᵢ (empty without bootstrap).
    pub first_ci: Vec<[f64; 2]>,
    /// Bootstrap intervals of S_Tᵢ.
    pub total_ci: Vec<[f64; 2]>,
    /// Bootstrap standard errors of Sᵢ.
    pub first_se: Vec<f64>,
    /// Bootstrap standard errors of S_Tᵢ.
    pub total_se: Vec<f64>,
    /// Second-order indices S_ij (k × k, symmetric, zero diagonal) when requested.
    pub second: Option<Vec<Vec<f64>>>,
    /// Output mean.
    pub mean: f64,
    /// Output variance.
    pub variance: f64,
}

/// Estimates at one sample size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvergencePoint {
    /// Base sample size used.
    pub n: usize,
    /// First-order indices per output.
    pub first: Vec<Vec<f64>>,
    /// Total indices per output.
    pub total: Vec<Vec<f64>>,
}

/// Result of [`sobol`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SobolResult {
    /// Input names.
    pub names: Vec<String>,
    /// Base sample size.
    pub n: usize,
    /// Model runs spent.
    pub n_model_runs: usize,
    /// Design used.
    pub sampling: Sampling,
    /// Confidence level of the intervals.
    pub confidence: f64,
    /// One entry per model output.
    pub outputs: Vec<SobolIndices>,
    /// Estimates at the requested checkpoints.
    pub convergence: Vec<ConvergencePoint>,
}

/// Which index of an input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IndexKind {
    /// First order Sᵢ.
    First,
    /// Total effect S_Tᵢ.
    Total,
}

impl IndexKind {
    /// The short name used in reports: `S1`, `ST`.
    pub fn label(self) -> &'static str {
        match self {
            IndexKind::First => "S1",
            IndexKind::Total => "ST",
        }
    }
}

/// An index whose bootstrap interval is wider than the index itself ([`SobolIndices::wide`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WideInterval {
    /// Which index.
    pub index: IndexKind,
    /// Input number.
    pub input: usize,
    /// The estimate.
    pub value: f64,
    /// Its interval.
    pub interval: [f64; 2],
}

impl SobolIndices {
    /// The first-order and total indices whose interval is wider than the index it brackets
    /// (high − low > |S|): the estimate is not resolved from 0 at this number of model runs —
    /// expected for an input without influence, a reason for more runs where the input matters.
    /// Empty without bootstrap.
    ///
    /// ```
    /// use mte_sensitivity::sobol::{IndexKind, SobolIndices};
    /// let s = SobolIndices {
    ///     first: vec![0.5, 0.01], total: vec![0.6, 0.02],
    ///     first_ci: vec![[0.45, 0.55], [-0.01, 0.03]], total_ci: vec![[0.5, 0.7], [0.0, 0.03]],
    ///     first_se: vec![], total_se: vec![], second: None, mean: 0.0, variance: 1.0,
    /// };
    /// let w = s.wide();
    /// assert_eq!(w.len(), 2);
    /// assert_eq!((w[0].index, w[0].input), (IndexKind::First, 1));
    /// ```
    pub fn wide(&self) -> Vec<WideInterval> {
        let kinds = [
            (IndexKind::First, &self.first, &self.first_ci),
            (IndexKind::Total, &self.total, &self.total_ci),
        ];
        kinds
            .into_iter()
            .flat_map(|(index, values, cis)| {
                values
                    .iter()
                    .zip(cis)
                    .enumerate()
                    .filter(|(_, (v, ci))| ci[1] - ci[0] > v.abs())
                    .map(move |(input, (&value, &interval))| WideInterval {
                        index,
                        input,
                        value,
                        interval,
                    })
            })
            .collect()
    }
}

/// Per-thread work buffers of one block: unit design, model inputs, model outputs.
#[derive(Default)]
struct Buffers {
    u: Vec<f64>,
    xs: Vec<f64>,
    ys: Vec<f64>,
}

/// Rows per block for a base sample of n: at most ~1024 blocks.
fn block_rows(n: usize) -> usize {
    let want = n.div_ceil(1024);
    want.div_ceil(ROW_BLOCK).max(1) * ROW_BLOCK
}

/// Smallest base sample size accepted.
pub const MIN_N: usize = 2 * ROW_BLOCK;

/// Sobol' indices of every output of `model` over the inputs of `problem`.
///
/// ```
/// use mte_sensitivity::{sobol::{sobol, SobolParams}, testfn::Ishigami};
/// let f = Ishigami::default();
/// let r = sobol(&f, &Ishigami::problem(), &SobolParams { n: 4096, n_bootstrap: 0, ..Default::default() }).unwrap();
/// assert!((r.outputs[0].first[1] - f.analytic().0[1]).abs() < 0.02);
/// ```
///
/// # Errors
/// [`Error::SampleSize`] if N < [`MIN_N`] or too few blocks for the bootstrap,
/// [`Error::ModelOutput`] for a non-finite model value, [`Error::Degenerate`] for an output with
/// zero variance.
pub fn sobol<M: Model + ?Sized>(
    model: &M,
    problem: &Problem,
    params: &SobolParams,
) -> Result<SobolResult> {
    sobol_with_progress(model, problem, params, &NoProgress)
}

/// [`sobol`] reporting progress in model runs.
///
/// # Errors
/// As [`sobol`].
pub fn sobol_with_progress<M: Model + ?Sized>(
    model: &M,
    problem: &Problem,
    params: &SobolParams,
    progress: &dyn Progress,
) -> Result<SobolResult> {
    let k = problem.dim();
    let m = model.n_outputs();
    let n = params.n;
    if n < MIN_N {
        return Err(Error::SampleSize {
            estimator: "Sobol' (Saltelli/Jansen)",
            n,
            min: MIN_N,
        });
    }
    if !(params.confidence > 0.0 && params.confidence < 1.0) {
        return Err(Error::InvalidParameter {
            name: "confidence",
            message: format!("must be in (0, 1), got {}", params.confidence),
        });
    }
    let br = block_rows(n);
    let nb = n.div_ceil(br);
    if params.n_bootstrap > 0 && nb < 16 {
        return Err(Error::SampleSize {
            estimator: "Sobol' bootstrap (needs 16 blocks of rows)",
            n,
            min: 16 * br,
        });
    }
    let so = params.second_order;
    let npair = if so { k * (k - 1) / 2 } else { 0 };
    let s_len = 4 + 2 * k + npair;
    let runs_per_row = if so { 2 * k + 2 } else { k + 2 };
    let design = UnitDesign::new(params.sampling, 2 * k, n, params.seed)?;

    // Shift c per output (mean of f(A) on the first block) to keep sums well conditioned.
    let shift = {
        let rows = br.min(n);
        let mut u = vec![0.0; rows * 2 * k];
        design.fill(0, rows, &mut u);
        let mut xa = vec![0.0; rows * k];
        for r in 0..rows {
            xa[r * k..(r + 1) * k].copy_from_slice(&u[r * 2 * k..r * 2 * k + k]);
            problem.transform_unit(&mut xa[r * k..(r + 1) * k]);
        }
        let mut ya = vec![0.0; rows * m];
        eval_checked(model, rows, k, &xa, &mut ya)?;
        (0..m)
            .map(|o| (0..rows).map(|r| ya[r * m + o]).sum::<f64>() / rows as f64)
            .collect::<Vec<_>>()
    };

    let mut partials = vec![0.0; nb * m * s_len];
    partials
        .par_chunks_mut(m * s_len)
        .enumerate()
        // Buffers reused block after block by each thread (every value is overwritten).
        .try_for_each_init(Buffers::default, |buf, (b, out)| -> Result<()> {
            let first = b * br;
            let rows = br.min(n - first);
            let Buffers { u, xs, ys } = buf;
            u.resize(rows * 2 * k, 0.0);
            design.fill(first, rows, &mut u[..rows * 2 * k]);
            let u = &mut u[..rows * 2 * k];
            for row in u.chunks_exact_mut(2 * k) {
                let (a, bb) = row.split_at_mut(k);
                problem.transform_unit(a);
                problem.transform_unit(bb);
            }
            xs.resize(rows * runs_per_row * k, 0.0);
            for r in 0..rows {
                let a = &u[r * 2 * k..r * 2 * k + k];
                let bb = &u[r * 2 * k + k..(r + 1) * 2 * k];
                let base = r * runs_per_row * k;
                xs[base..base + k].copy_from_slice(a);
                xs[base + k..base + 2 * k].copy_from_slice(bb);
                for i in 0..k {
                    let p = base + (2 + i) * k;
                    xs[p..p + k].copy_from_slice(a);
                    xs[p + i] = bb[i];
                }
                if so {
                    for j in 0..k {
                        let p = base + (2 + k + j) * k;
                        xs[p..p + k].copy_from_slice(bb);
                        xs[p + j] = a[j];
                    }
                }
            }
            ys.resize(rows * runs_per_row * m, 0.0);
            let (xs, ys) = (
                &xs[..rows * runs_per_row * k],
                &mut ys[..rows * runs_per_row * m],
            );
            eval_checked(model, rows * runs_per_row, k, xs, ys)?;
            // Partial sums laid out [statistic][output]: the inner loops run over the outputs,
            // contiguous in both the model values and the sums.
            let (mut fa, mut fb) = (vec![0.0; m], vec![0.0; m]);
            let (head, tail) = out.split_at_mut((4 + k) * m);
            let (moments, first_sums) = head.split_at_mut(4 * m);
            let (total_sums, second_sums) = tail.split_at_mut(k * m);
            for r in 0..rows {
                let run =
                    |i: usize| &ys[(r * runs_per_row + i) * m..(r * runs_per_row + i + 1) * m];
                for o in 0..m {
                    fa[o] = run(0)[o] - shift[o];
                    fb[o] = run(1)[o] - shift[o];
                    moments[o] += fa[o];
                    moments[m + o] += fa[o] * fa[o];
                    moments[2 * m + o] += fb[o];
                    moments[3 * m + o] += fb[o] * fb[o];
                }
                for ((t1, t2), i) in first_sums
                    .chunks_exact_mut(m)
                    .zip(total_sums.chunks_exact_mut(m))
                    .zip(0..k)
                {
                    let values = run(2 + i).iter().zip(&shift).zip(fa.iter().zip(&fb));
                    for ((t1, t2), ((y, c), (a, b))) in t1.iter_mut().zip(t2.iter_mut()).zip(values)
                    {
                        let fab = y - c;
                        *t1 += b * (fab - a);
                        let d = a - fab;
                        *t2 += d * d;
                    }
                }
                if so {
                    let mut p = 0;
                    for j in 0..k {
                        let fba_run = run(2 + k + j);
                        for l in (j + 1)..k {
                            let fab_run = run(2 + l);
                            let t = &mut second_sums[p * m..(p + 1) * m];
                            for o in 0..m {
                                let fba = fba_run[o] - shift[o];
                                t[o] += fba * (fab_run[o] - shift[o]) - fa[o] * fb[o];
                            }
                            p += 1;
                        }
                    }
                }
            }
            progress.inc((rows * runs_per_row) as u64);
            Ok(())
        })?;

    let finalize = |sums: &[f64],
                    count: usize,
                    o: usize|
     -> Result<(Vec<f64>, Vec<f64>, f64, f64, Option<Vec<Vec<f64>>>)> {
        let t = |s: usize| sums[s * m + o];
        let nn = count as f64;
        let s1 = t(0) + t(2);
        let var = (t(1) + t(3) - s1 * s1 / (2.0 * nn)) / (2.0 * nn - 1.0);
        let mean = s1 / (2.0 * nn) + shift[o];
        let scale = (t(1) + t(3)) / (2.0 * nn);
        if !(var > 1e-13 * scale.max(f64::MIN_POSITIVE)) {
            return Err(Error::Degenerate {
                output: o,
                message: format!("output variance {var:.3e} is zero: no input has any effect"),
            });
        }
        let first: Vec<f64> = (0..k).map(|i| t(4 + i) / nn / var).collect();
        let total: Vec<f64> = (0..k).map(|i| t(4 + k + i) / (2.0 * nn) / var).collect();
        let second = so.then(|| {
            let mut s2 = vec![vec![0.0; k]; k];
            let mut p = 4 + 2 * k;
            for j in 0..k {
                for l in (j + 1)..k {
                    let v = t(p) / nn / var - first[j] - first[l];
                    s2[j][l] = v;
                    s2[l][j] = v;
                    p += 1;
                }
            }
            s2
        });
        Ok((first, total, mean, var, second))
    };

    // Totals and convergence checkpoints (prefix sums in block order).
    let mut totals = vec![0.0; m * s_len];
    let mut checkpoints: Vec<usize> = params
        .checkpoints
        .iter()
        .map(|&c| (c.min(n) / br).max(1))
        .collect();
    checkpoints.sort_unstable();
    checkpoints.dedup();
    let mut convergence = vec![];
    let mut ci = 0;
    for b in 0..nb {
        for (t, p) in totals
            .iter_mut()
            .zip(&partials[b * m * s_len..(b + 1) * m * s_len])
        {
            *t += p;
        }
        while ci < checkpoints.len() && checkpoints[ci] == b + 1 {
            let count = ((b + 1) * br).min(n);
            let mut first = vec![];
            let mut total = vec![];
            for o in 0..m {
                let (f, t, ..) = finalize(&totals, count, o)?;
                first.push(f);
                total.push(t);
            }
            convergence.push(ConvergencePoint {
                n: count,
                first,
                total,
            });
            ci += 1;
        }
    }

    let mut outputs = Vec::with_capacity(m);
    for o in 0..m {
        let (first, total, mean, variance, second) = finalize(&totals, n, o)?;
        outputs.push(SobolIndices {
            first,
            total,
            first_ci: vec![],
            total_ci: vec![],
            first_se: vec![],
            total_se: vec![],
            second,
            mean,
            variance,
        });
    }

    if params.n_bootstrap > 0 {
        let reps: Vec<Vec<(Vec<f64>, Vec<f64>)>> = (0..params.n_bootstrap)
            .into_par_iter()
            .map(|rep| {
                let mut rng = stream(params.seed ^ 0xB007_5742_u64, rep as u64);
                let mut sums = vec![0.0; m * s_len];
                let mut count = 0;
                for _ in 0..nb {
                    let b = rng.random_range(0..nb);
                    count += br.min(n - b * br);
                    for (s, p) in sums
                        .iter_mut()
                        .zip(&partials[b * m * s_len..(b + 1) * m * s_len])
                    {
                        *s += p;
                    }
                }
                (0..m)
                    .map(|o| match finalize(&sums, count, o) {
                        Ok((f, t, ..)) => (f, t),
                        Err(_) => (vec![f64::NAN; k], vec![f64::NAN; k]),
                    })
                    .collect()
            })
            .collect();
        for (o, out) in outputs.iter_mut().enumerate() {
            for i in 0..k {
                let f: Vec<f64> = reps
                    .iter()
                    .map(|r| r[o].0[i])
                    .filter(|v| v.is_finite())
                    .collect();
                let t: Vec<f64> = reps
                    .iter()
                    .map(|r| r[o].1[i])
                    .filter(|v| v.is_finite())
                    .collect();
                let (fc, fs) = interval(f, params.confidence);
                let (tc, ts) = interval(t, params.confidence);
                out.first_ci.push(fc);
                out.first_se.push(fs);
                out.total_ci.push(tc);
                out.total_se.push(ts);
            }
        }
    }

    Ok(SobolResult {
        names: problem.names(),
        n,
        n_model_runs: n * runs_per_row + br.min(n),
        sampling: params.sampling,
        confidence: params.confidence,
        outputs,
        convergence,
    })
}
