//! Sparse polynomial chaos expansion (PCE) by orthogonal matching pursuit (OMP).
//!
//! y ≈ Σ_α c_α Ψ_α(ξ), Ψ_α = Π ψ_{αᵢ}(ξᵢ) with orthonormal Hermite (normal germ) or Legendre
//! (uniform germ on [−1, 1]) polynomials; ξ = T(x) the isoprobabilistic transform
//! ([`Problem::to_germ`]). Candidates: total degree ≤ p with hyperbolic truncation
//! (Σ αᵢ^q)^{1/q} ≤ p (q = 1 is the full total-degree set).
//!
//! OMP adds, one at a time, the candidate most correlated with the residual (normalised by its
//! column norm), re-solving least squares on the active set by an incremental Gram–Schmidt QR
//! (twice orthogonalised). The model size is chosen by K-fold cross-validation along the OMP path
//! (default: each fold runs its own path on its training rows, the error on the held-out rows is
//! averaged over folds at each path length, the size with the smallest error is refitted on all
//! runs) or by the corrected leave-one-out error (Blatman & Sudret 2011:
//! LOO·n/(n − p)·(1 + tr(C⁻¹)/n), C = Ψ_AᵀΨ_A/n). All paths advance in lockstep so that the
//! correlations of every path come from one matrix product Ψᵀ[r₀ … r_K] per step. The degree is
//! chosen the same way when `adaptive_degree` is on (degrees 1 … p, stop when the error grows).
//!
//! Sobol' indices from the coefficients (Sudret 2008): V = Σ_{α≠0} c_α², Sᵢ = Σ_{α: only i} c_α²/V,
//! S_Tᵢ = Σ_{α ∋ i} c_α²/V, S_ij = Σ_{α: exactly {i, j}} c_α²/V.

use crate::design::{Sampling, UnitDesign};
use crate::dist::{Germ, Problem};
use crate::error::{Error, Result};
use crate::model::{Model, eval_checked};
use crate::stats::{interval, stream};
use faer::{Accum, Mat, Par};
use rand::Rng;
use rand::seq::SliceRandom;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One multivariate basis term: (input index, degree) pairs with degree ≥ 1; empty = constant.
pub type MultiIndex = Vec<(u32, u32)>;

/// How OMP's model size is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "rule")]
pub enum Selection {
    /// K-fold cross-validation along the OMP path (robust default).
    KFold {
        /// Number of folds (≥ 2).
        folds: usize,
    },
    /// Corrected leave-one-out error on the full-data path (UQLab-style; can overfit when
    /// candidates far outnumber runs).
    CorrectedLoo,
}

/// Settings of a sparse PCE.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PceParams {
    /// Largest total degree p.
    pub degree: usize,
    /// Hyperbolic truncation q ∈ (0, 1].
    pub q_norm: f64,
    /// Try degrees 1…p and keep the best by the selection error.
    pub adaptive_degree: bool,
    /// Model-size rule.
    pub selection: Selection,
    /// Largest number of terms (default: half the runs).
    pub max_terms: Option<usize>,
    /// Bootstrap replicates for index intervals (refit on the selected basis; 0 = none).
    pub n_bootstrap: usize,
    /// Confidence level of the intervals.
    pub confidence: f64,
    /// Seed (fold assignment, bootstrap, and the design in [`build_pce`]).
    pub seed: u64,
    /// Number of model runs for [`build_pce`].
    pub n_samples: usize,
    /// Design for [`build_pce`].
    pub sampling: Sampling,
}

impl Default for PceParams {
    fn default() -> Self {
        PceParams {
            degree: 3,
            q_norm: 1.0,
            adaptive_degree: true,
            selection: Selection::KFold { folds: 5 },
            max_terms: None,
            n_bootstrap: 0,
            confidence: 0.95,
            seed: 0,
            n_samples: 1000,
            sampling: Sampling::LatinHypercube,
        }
    }
}

/// The sparse expansion of one output and its indices.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PceOutput {
    /// Total degree of the candidate set finally used.
    pub degree: usize,
    /// Selected terms and coefficients.
    pub terms: Vec<(MultiIndex, f64)>,
    /// Mean (coefficient of the constant term).
    pub mean: f64,
    /// Variance Σ_{α≠0} c_α².
    pub variance: f64,
    /// First-order indices.
    pub first: Vec<f64>,
    /// Total indices.
    pub total: Vec<f64>,
    /// Second-order interaction indices (i, j, S_ij) for pairs with a non-zero share.
    pub interactions: Vec<(usize, usize, f64)>,
    /// Bootstrap intervals of the first-order indices (empty without bootstrap).
    pub first_ci: Vec<[f64; 2]>,
    /// Bootstrap intervals of the total indices.
    pub total_ci: Vec<[f64; 2]>,
    /// Validation error: K-fold CV mean squared error / Var(y) at the chosen size (NaN under
    /// corrected LOO selection).
    pub cv_error: f64,
    /// Corrected leave-one-out error / Var(y) of the chosen model.
    pub loo_error: f64,
    /// Training mean squared error / Var(y).
    pub train_error: f64,
    /// OMP steps taken on the full-data path.
    pub omp_steps: usize,
}

/// A fitted PCE for every output of a model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PceResult {
    /// Input names.
    pub names: Vec<String>,
    /// Number of runs used.
    pub n_samples: usize,
    /// Candidate terms at the largest degree.
    pub n_candidates: usize,
    /// Settings used.
    pub params: PceParams,
    /// One expansion per output.
    pub outputs: Vec<PceOutput>,
    /// Germ family of each input.
    pub germs: Vec<Germ>,
}

/// Candidate multi-indices of total degree ≤ p with (Σ αᵢ^q)^{1/q} ≤ p, ordered by total degree.
pub fn multi_indices(k: usize, p: usize, q: f64) -> Vec<MultiIndex> {
    let mut out = vec![vec![]];
    fn rec(
        k: usize,
        start: usize,
        left: usize,
        cur: &mut MultiIndex,
        total: usize,
        target: usize,
        q: f64,
        p: usize,
        out: &mut Vec<MultiIndex>,
    ) {
        if left == 0 {
            if total == target {
                let qn: f64 = cur
                    .iter()
                    .map(|&(_, d)| (d as f64).powf(q))
                    .sum::<f64>()
                    .powf(1.0 / q);
                if qn <= p as f64 + 1e-9 {
                    out.push(cur.clone());
                }
            }
            return;
        }
        for v in start..k {
            for d in (1..=left).rev() {
                cur.push((v as u32, d as u32));
                rec(k, v + 1, left - d, cur, total + d, target, q, p, out);
                cur.pop();
            }
        }
    }
    for t in 1..=p {
        let mut cur = vec![];
        let before = out.len();
        rec(k, 0, t, &mut cur, 0, t, q, p, &mut out);
        out[before..].sort();
    }
    out
}

/// Orthonormal univariate values ψ₀…ψ_p at ξ into `out`.
pub fn univariate(germ: Germ, xi: f64, p: usize, out: &mut [f64]) {
    out[0] = 1.0;
    if p == 0 {
        return;
    }
    match germ {
        Germ::Normal => {
            out[1] = xi;
            for n in 1..p {
                let nf = n as f64;
                out[n + 1] = (xi * out[n] - nf.sqrt() * out[n - 1]) / (nf + 1.0).sqrt();
            }
        }
        Germ::Uniform => {
            // Legendre P_n, then scaled by √(2n+1) (orthonormal under the U(−1, 1) density)
            let mut p0 = 1.0;
            let mut p1 = xi;
            out[1] = 3f64.sqrt() * xi;
            for n in 1..p {
                let nf = n as f64;
                let p2 = ((2.0 * nf + 1.0) * xi * p1 - nf * p0) / (nf + 1.0);
                out[n + 1] = (2.0 * nf + 3.0).sqrt() * p2;
                p0 = p1;
                p1 = p2;
            }
        }
    }
}

/// Design matrix Ψ (n × P, column-major) of the candidates at germ points `xi` (n × k row-major).
fn design_matrix(
    xi: &[f64],
    n: usize,
    k: usize,
    germs: &[Germ],
    p: usize,
    basis: &[MultiIndex],
) -> Mat<f64> {
    let mut uni = vec![0.0; n * k * (p + 1)];
    for r in 0..n {
        for j in 0..k {
            let o = (r * k + j) * (p + 1);
            univariate(germs[j], xi[r * k + j], p, &mut uni[o..o + p + 1]);
        }
    }
    let mut psi = Mat::<f64>::zeros(n, basis.len());
    let cols: Vec<(usize, &MultiIndex)> = basis.iter().enumerate().collect();
    let ncols = basis.len();
    // Fill columns in parallel (each column is independent).
    let data: Vec<Vec<f64>> = cols
        .par_iter()
        .map(|(_, a)| {
            (0..n)
                .map(|r| {
                    a.iter()
                        .map(|&(v, d)| uni[(r * k + v as usize) * (p + 1) + d as usize])
                        .product::<f64>()
                })
                .collect()
        })
        .collect();
    for c in 0..ncols {
        for r in 0..n {
            psi[(r, c)] = data[c][r];
        }
    }
    psi
}

/// Fixed chunk of candidate columns per matrix product (keeps results thread-count independent).
const COL_CHUNK: usize = 512;

/// C = Ψᵀ R, computed in fixed column chunks.
fn correlations(psi: &Mat<f64>, r: &Mat<f64>, parallel: bool) -> Mat<f64> {
    let (n, p) = (psi.nrows(), psi.ncols());
    let f = r.ncols();
    let chunks: Vec<usize> = (0..p).step_by(COL_CHUNK).collect();
    let work = |&c0: &usize| {
        let c1 = (c0 + COL_CHUNK).min(p);
        let mut out = Mat::<f64>::zeros(c1 - c0, f);
        faer::linalg::matmul::matmul(
            out.as_mut(),
            Accum::Replace,
            psi.as_ref().subcols(c0, c1 - c0).transpose(),
            r.as_ref(),
            1.0,
            Par::Seq,
        );
        out
    };
    let parts: Vec<Mat<f64>> = if parallel {
        chunks.par_iter().map(work).collect()
    } else {
        chunks.iter().map(work).collect()
    };
    let _ = n;
    let mut c = Mat::<f64>::zeros(p, f);
    for (ci, part) in chunks.iter().zip(parts) {
        for j in 0..f {
            for i in 0..part.nrows() {
                c[(ci + i, j)] = part[(i, j)];
            }
        }
    }
    c
}

#[derive(Clone, Copy, PartialEq)]
enum Stop {
    Running,
    Done,
}

/// One OMP path on a subset of rows (mask) of Ψ.
struct Path {
    mask: Vec<f64>,
    hold: Vec<usize>,
    norm2: Vec<f64>,
    excluded: Vec<bool>,
    active: Vec<usize>,
    q: Vec<Vec<f64>>,
    rcols: Vec<Vec<f64>>,
    rinv: Vec<Vec<f64>>,
    rinv_f2: f64,
    qty: Vec<f64>,
    resid: Vec<f64>,
    h: Vec<f64>,
    n_train: usize,
    var_y: f64,
    y_norm2: f64,
    hold_err: Vec<f64>,
    cloo: Vec<f64>,
    best: f64,
    best_p: usize,
    state: Stop,
    kmax: usize,
}

impl Path {
    fn new(psi: &Mat<f64>, y: &[f64], mask: Vec<f64>, kmax: usize, col_norm2: &[f64]) -> Self {
        let n = y.len();
        let hold: Vec<usize> = (0..n).filter(|&i| mask[i] == 0.0).collect();
        let mut norm2 = col_norm2.to_vec();
        for &i in &hold {
            for (j, v) in norm2.iter_mut().enumerate() {
                *v -= psi[(i, j)] * psi[(i, j)];
            }
        }
        let n_train = n - hold.len();
        let resid: Vec<f64> = y.iter().zip(&mask).map(|(a, b)| a * b).collect();
        let mean = resid.iter().sum::<f64>() / n_train as f64;
        let var_y = resid
            .iter()
            .zip(&mask)
            .map(|(v, m)| m * (v - mean).powi(2))
            .sum::<f64>()
            / n_train as f64;
        let y_norm2 = resid.iter().map(|v| v * v).sum();
        let excluded = norm2.iter().map(|&v| v <= 1e-300).collect();
        Path {
            mask,
            hold,
            norm2,
            excluded,
            active: vec![],
            q: vec![],
            rcols: vec![],
            rinv: vec![],
            rinv_f2: 0.0,
            qty: vec![],
            resid,
            h: vec![0.0; n],
            n_train,
            var_y,
            y_norm2,
            hold_err: vec![],
            cloo: vec![],
            best: f64::INFINITY,
            best_p: 0,
            state: Stop::Running,
            kmax,
        }
    }

    fn coef(&self, p: usize) -> Vec<f64> {
        (0..p)
            .map(|i| (i..p).map(|j| self.rinv[j][i] * self.qty[j]).sum())
            .collect()
    }

    /// Adds the best candidate given correlations `c` (length P). Returns false when stopped.
    fn step(&mut self, psi: &Mat<f64>, y: &[f64], c: &[f64], use_hold: bool) {
        let n = y.len();
        loop {
            let mut best = None;
            let mut bv = -1.0;
            for (j, &cj) in c.iter().enumerate() {
                if self.excluded[j] {
                    continue;
                }
                let v = cj * cj / self.norm2[j];
                if v > bv {
                    bv = v;
                    best = Some(j);
                }
            }
            let Some(j) = best else {
                self.state = Stop::Done;
                return;
            };
            self.excluded[j] = true;
            let col = psi.col(j);
            let mut v: Vec<f64> = (0..n).map(|i| col[i] * self.mask[i]).collect();
            let p = self.q.len();
            let mut rc = vec![0.0; p + 1];
            for _ in 0..2 {
                for (t, qt) in self.q.iter().enumerate() {
                    let d: f64 = qt.iter().zip(&v).map(|(a, b)| a * b).sum();
                    rc[t] += d;
                    for (vi, qi) in v.iter_mut().zip(qt) {
                        *vi -= d * qi;
                    }
                }
            }
            let rkk = v.iter().map(|a| a * a).sum::<f64>().sqrt();
            if rkk <= 1e-9 * self.norm2[j].sqrt() {
                continue; // numerically dependent on the active set: skip this candidate
            }
            v.iter_mut().for_each(|a| *a /= rkk);
            rc[p] = rkk;
            // R⁻¹ new column: −R⁻¹[:p,:p] r[:p] / rkk, diagonal 1/rkk
            let mut ic = vec![0.0; p + 1];
            for i in 0..p {
                let mut s = 0.0;
                for t in i..p {
                    s += self.rinv[t][i] * rc[t];
                }
                ic[i] = -s / rkk;
            }
            ic[p] = 1.0 / rkk;
            self.rinv_f2 += ic.iter().map(|a| a * a).sum::<f64>();
            let d: f64 = v.iter().zip(&self.resid).map(|(a, b)| a * b).sum();
            self.qty.push(
                v.iter()
                    .zip(y)
                    .zip(&self.mask)
                    .map(|((a, b), m)| a * b * m)
                    .sum(),
            );
            for ((r, h), qi) in self.resid.iter_mut().zip(self.h.iter_mut()).zip(&v) {
                *r -= d * qi;
                *h += qi * qi;
            }
            self.q.push(v);
            self.rcols.push(rc);
            // store R⁻¹ by columns: rinv[col][row]
            self.rinv.push(ic);
            self.active.push(j);
            break;
        }
        let p = self.active.len();
        // corrected LOO
        let nt = self.n_train as f64;
        let mut loo = 0.0;
        for i in 0..n {
            if self.mask[i] != 0.0 {
                let e = self.resid[i] / (1.0 - self.h[i]).max(1e-12);
                loo += e * e;
            }
        }
        loo /= nt * self.var_y.max(f64::MIN_POSITIVE);
        let corr = if (p as f64) < nt {
            nt / (nt - p as f64) * (1.0 + self.rinv_f2)
        } else {
            f64::INFINITY
        };
        self.cloo.push(loo * corr);
        let crit = if use_hold {
            let b = self.coef(p);
            let mut e = 0.0;
            for &i in &self.hold {
                let pred: f64 = self
                    .active
                    .iter()
                    .zip(&b)
                    .map(|(&a, bb)| psi[(i, a)] * bb)
                    .sum();
                e += (y[i] - pred).powi(2);
            }
            let e = e / self.hold.len() as f64;
            self.hold_err.push(e);
            e
        } else {
            *self.cloo.last().expect("pushed")
        };
        if crit < self.best {
            self.best = crit;
            self.best_p = p;
        }
        let rr: f64 = self.resid.iter().map(|a| a * a).sum();
        let patience = 10.max(self.best_p / 5);
        if p >= self.kmax || rr <= 1e-26 * self.y_norm2 || p - self.best_p >= patience {
            self.state = Stop::Done;
        }
    }
}

struct Fit {
    terms: Vec<(usize, f64)>,
    cv_error: f64,
    loo_error: f64,
    train_error: f64,
    steps: usize,
    crit: f64,
}

/// OMP with the selection rule on one output.
fn omp_select(
    psi: &Mat<f64>,
    col_norm2: &[f64],
    y: &[f64],
    params: &PceParams,
    kmax_user: usize,
    parallel: bool,
    seed: u64,
) -> Fit {
    let n = y.len();
    let mut paths = vec![];
    let folds = match params.selection {
        Selection::KFold { folds } => folds,
        Selection::CorrectedLoo => 0,
    };
    let kmax = |nt: usize| kmax_user.min(psi.ncols()).min(nt.saturating_sub(2)).max(1);
    paths.push(Path::new(psi, y, vec![1.0; n], kmax(n), col_norm2));
    if folds > 0 {
        let mut idx: Vec<usize> = (0..n).collect();
        idx.shuffle(&mut stream(seed, 0xF01D));
        for f in 0..folds {
            let mut mask = vec![1.0; n];
            for (t, &i) in idx.iter().enumerate() {
                if t % folds == f {
                    mask[i] = 0.0;
                }
            }
            let nt = mask.iter().filter(|&&m| m != 0.0).count();
            paths.push(Path::new(psi, y, mask, kmax(nt), col_norm2));
        }
    }
    loop {
        // The full path (0) keeps going while any fold runs (its size is decided by the folds).
        let folds_running = paths[1..].iter().any(|p| p.state == Stop::Running);
        let live: Vec<usize> = (0..paths.len())
            .filter(|&i| paths[i].state == Stop::Running && (i > 0 || folds == 0 || folds_running))
            .collect();
        if live.is_empty() {
            break;
        }
        let mut r = Mat::<f64>::zeros(n, live.len());
        for (c, &pi) in live.iter().enumerate() {
            for i in 0..n {
                r[(i, c)] = paths[pi].resid[i];
            }
        }
        let c = correlations(psi, &r, parallel);
        for (ci, &pi) in live.iter().enumerate() {
            let cc: Vec<f64> = (0..psi.ncols()).map(|j| c[(j, ci)]).collect();
            paths[pi].step(psi, y, &cc, pi > 0);
        }
    }
    let full = &paths[0];
    let var_y = full.var_y.max(f64::MIN_POSITIVE);
    let (p_star, cv_error) = if folds > 0 {
        let len = paths[1..]
            .iter()
            .map(|p| p.hold_err.len())
            .max()
            .unwrap_or(0)
            .min(full.active.len());
        let mut best = (1, f64::INFINITY);
        for p in 1..=len {
            let mut s = 0.0;
            let mut w = 0.0;
            for fp in &paths[1..] {
                if fp.hold_err.is_empty() {
                    continue;
                }
                let e = fp.hold_err[(p - 1).min(fp.hold_err.len() - 1)];
                s += e * fp.hold.len() as f64;
                w += fp.hold.len() as f64;
            }
            let e = s / w;
            if e < best.1 {
                best = (p, e);
            }
        }
        (best.0, best.1 / var_y)
    } else {
        let mut best = (1, f64::INFINITY);
        for (i, &e) in full.cloo.iter().enumerate() {
            if e < best.1 {
                best = (i + 1, e);
            }
        }
        (best.0, f64::NAN)
    };
    let p_star = p_star.min(full.active.len()).max(1.min(full.active.len()));
    let coef = full.coef(p_star);
    let terms: Vec<(usize, f64)> = full.active[..p_star]
        .iter()
        .copied()
        .zip(coef.iter().copied())
        .collect();
    // training error of the chosen model
    let mut tr = 0.0;
    for i in 0..n {
        let pred: f64 = terms.iter().map(|&(a, b)| psi[(i, a)] * b).sum();
        tr += (y[i] - pred).powi(2);
    }
    let loo = full
        .cloo
        .get(p_star.saturating_sub(1))
        .copied()
        .unwrap_or(f64::NAN);
    Fit {
        terms,
        cv_error,
        loo_error: loo,
        train_error: tr / n as f64 / var_y,
        steps: full.active.len(),
        crit: if folds > 0 { cv_error } else { loo },
    }
}

/// Least squares on a fixed support through the normal equations (Cholesky), for the bootstrap.
fn lstsq_support(psi: &Mat<f64>, rows: &[usize], support: &[usize], y: &[f64]) -> Option<Vec<f64>> {
    let p = support.len();
    let mut g = vec![0.0; p * p];
    let mut b = vec![0.0; p];
    let mut row = vec![0.0; p];
    for &i in rows {
        for (t, &a) in support.iter().enumerate() {
            row[t] = psi[(i, a)];
        }
        for s in 0..p {
            b[s] += row[s] * y[i];
            for t in 0..=s {
                g[s * p + t] += row[s] * row[t];
            }
        }
    }
    for s in 0..p {
        for t in 0..=s {
            let mut v = g[s * p + t];
            for u in 0..t {
                v -= g[s * p + u] * g[t * p + u];
            }
            if s == t {
                if v <= 1e-12 * g[s * p + s].abs().max(1e-300) {
                    return None;
                }
                g[s * p + s] = v.sqrt();
            } else {
                g[s * p + t] = v / g[t * p + t];
            }
        }
    }
    for s in 0..p {
        let mut v = b[s];
        for u in 0..s {
            v -= g[s * p + u] * b[u];
        }
        b[s] = v / g[s * p + s];
    }
    for s in (0..p).rev() {
        let mut v = b[s];
        for u in (s + 1)..p {
            v -= g[u * p + s] * b[u];
        }
        b[s] = v / g[s * p + s];
    }
    Some(b)
}

fn indices_from(
    k: usize,
    basis: &[MultiIndex],
    terms: &[(usize, f64)],
) -> (f64, f64, Vec<f64>, Vec<f64>, Vec<(usize, usize, f64)>) {
    let mut mean = 0.0;
    let mut var = 0.0;
    let mut first = vec![0.0; k];
    let mut total = vec![0.0; k];
    let mut pairs = std::collections::BTreeMap::new();
    for &(a, c) in terms {
        let mi = &basis[a];
        if mi.is_empty() {
            mean += c;
            continue;
        }
        let c2 = c * c;
        var += c2;
        if mi.len() == 1 {
            first[mi[0].0 as usize] += c2;
        }
        if mi.len() == 2 {
            *pairs
                .entry((mi[0].0 as usize, mi[1].0 as usize))
                .or_insert(0.0) += c2;
        }
        for &(v, _) in mi {
            total[v as usize] += c2;
        }
    }
    if var > 0.0 {
        first
            .iter_mut()
            .chain(total.iter_mut())
            .for_each(|v| *v /= var);
    }
    let inter = pairs
        .into_iter()
        .map(|((i, j), v)| (i, j, if var > 0.0 { v / var } else { 0.0 }))
        .collect();
    (mean, var, first, total, inter)
}

/// Fits a sparse PCE to given runs: `x` (n × k row-major input values), `y` (n × m outputs).
///
/// ```
/// use mte_sensitivity::{Problem, Distribution, pce::{fit_pce, PceParams}};
/// let prob = Problem::from_dists(&[Distribution::normal(0.0, 1.0).unwrap(); 2]).unwrap();
/// let x: Vec<f64> = (0..200).flat_map(|i| [((i * 37) % 101) as f64 / 30.0 - 1.6, ((i * 53) % 97) as f64 / 30.0 - 1.6]).collect();
/// let y: Vec<f64> = x.chunks(2).map(|v| 1.0 + 2.0 * v[0] + v[0] * v[1]).collect();
/// let r = fit_pce(&prob, &x, &y, 1, &PceParams { degree: 2, ..Default::default() }).unwrap();
/// assert!((r.outputs[0].mean - 1.0).abs() < 1e-9);
/// assert!((r.outputs[0].total[1] - 0.2).abs() < 1e-9);   // Var = 4 + 1
/// ```
///
/// # Errors
/// [`Error::Dimension`] for inconsistent sizes, [`Error::SampleSize`] for fewer than 10 runs or
/// fewer runs than folds, [`Error::InvalidParameter`] for bad settings, [`Error::ModelOutput`] for a
/// non-finite y, [`Error::Degenerate`] for a constant output.
pub fn fit_pce(
    problem: &Problem,
    x: &[f64],
    y: &[f64],
    m: usize,
    params: &PceParams,
) -> Result<PceResult> {
    let k = problem.dim();
    if m == 0 || x.len() % k != 0 {
        return Err(Error::Dimension {
            what: "PCE inputs: values per row".into(),
            expected: k,
            got: x.len(),
        });
    }
    let n = x.len() / k;
    if y.len() != n * m {
        return Err(Error::Dimension {
            what: format!("PCE outputs (n = {n} runs × m = {m})"),
            expected: n * m,
            got: y.len(),
        });
    }
    if !(1..=12).contains(&params.degree) {
        return Err(Error::InvalidParameter {
            name: "degree",
            message: format!("must be 1…12, got {}", params.degree),
        });
    }
    if !(params.q_norm > 0.0 && params.q_norm <= 1.0) {
        return Err(Error::InvalidParameter {
            name: "q_norm",
            message: format!("must be in (0, 1], got {}", params.q_norm),
        });
    }
    let folds = match params.selection {
        Selection::KFold { folds } => {
            if folds < 2 {
                return Err(Error::InvalidParameter {
                    name: "folds",
                    message: format!("K-fold needs at least 2 folds, got {folds}"),
                });
            }
            folds
        }
        Selection::CorrectedLoo => 1,
    };
    let min_n = 10.max(3 * folds);
    if n < min_n {
        return Err(Error::SampleSize {
            estimator: "sparse PCE",
            n,
            min: min_n,
        });
    }
    if let Some(pos) = y.iter().position(|v| !v.is_finite()) {
        let r = pos / m;
        return Err(Error::ModelOutput {
            output: pos % m,
            value: y[pos],
            x: x[r * k..(r + 1) * k].to_vec(),
        });
    }
    let germs = problem.germs();
    let mut xi = x.to_vec();
    for row in xi.chunks_exact_mut(k) {
        problem.to_germ(row);
    }
    let kmax_user = params.max_terms.unwrap_or(n / 2).max(1);
    let degrees: Vec<usize> = if params.adaptive_degree {
        (1..=params.degree).collect()
    } else {
        vec![params.degree]
    };
    let parallel_inner = m == 1;
    let mut best: Vec<Option<(usize, Fit)>> = (0..m).map(|_| None).collect();
    let mut still: Vec<bool> = vec![true; m];
    let mut bases = vec![];
    let mut psis = vec![];
    let mut n_candidates = 0;
    let ys: Vec<Vec<f64>> = (0..m)
        .map(|o| (0..n).map(|r| y[r * m + o]).collect())
        .collect();
    for (o, yo) in ys.iter().enumerate() {
        let mean = yo.iter().sum::<f64>() / n as f64;
        let var = yo.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
        if !(var > 1e-28 * mean * mean) || var == 0.0 {
            return Err(Error::Degenerate {
                output: o,
                message: "output is constant over the runs".into(),
            });
        }
    }
    for (di, &deg) in degrees.iter().enumerate() {
        let basis = multi_indices(k, deg, params.q_norm);
        n_candidates = basis.len();
        let psi = design_matrix(&xi, n, k, &germs, deg, &basis);
        let col_norm2: Vec<f64> = (0..psi.ncols())
            .map(|j| psi.col(j).iter().map(|v| v * v).sum())
            .collect();
        let fits: Vec<Option<Fit>> = (0..m)
            .into_par_iter()
            .map(|o| {
                still[o].then(|| {
                    omp_select(
                        &psi,
                        &col_norm2,
                        &ys[o],
                        params,
                        kmax_user,
                        parallel_inner,
                        params.seed ^ (o as u64) << 20,
                    )
                })
            })
            .collect();
        for (o, f) in fits.into_iter().enumerate() {
            if let Some(f) = f {
                let better = best[o].as_ref().is_none_or(|(_, b)| f.crit < b.crit);
                if better {
                    best[o] = Some((di, f));
                } else {
                    still[o] = false; // error grew with the degree: stop increasing it
                }
            }
        }
        bases.push(basis);
        psis.push(psi);
        if still.iter().all(|s| !s) {
            break;
        }
    }
    let outputs: Vec<PceOutput> = best
        .into_par_iter()
        .enumerate()
        .map(|(o, b)| {
            let (di, fit) = b.expect("at least one degree fitted");
            let basis = &bases[di];
            let (mean, variance, first, total, interactions) = indices_from(k, basis, &fit.terms);
            let (mut first_ci, mut total_ci) = (vec![], vec![]);
            if params.n_bootstrap > 0 {
                let support: Vec<usize> = fit.terms.iter().map(|t| t.0).collect();
                let reps: Vec<(Vec<f64>, Vec<f64>)> = (0..params.n_bootstrap)
                    .filter_map(|rep| {
                        let mut rng =
                            stream(params.seed ^ 0xB0_0757 ^ (o as u64) << 24, rep as u64);
                        let rows: Vec<usize> = (0..n).map(|_| rng.random_range(0..n)).collect();
                        let c = lstsq_support(&psis[di], &rows, &support, &ys[o])?;
                        let terms: Vec<(usize, f64)> = support.iter().copied().zip(c).collect();
                        let (_, _, f, t, _) = indices_from(k, basis, &terms);
                        Some((f, t))
                    })
                    .collect();
                if reps.len() >= 2 {
                    for i in 0..k {
                        first_ci.push(
                            interval(reps.iter().map(|r| r.0[i]).collect(), params.confidence).0,
                        );
                        total_ci.push(
                            interval(reps.iter().map(|r| r.1[i]).collect(), params.confidence).0,
                        );
                    }
                }
            }
            PceOutput {
                degree: degrees[di],
                terms: fit
                    .terms
                    .iter()
                    .map(|&(a, c)| (basis[a].clone(), c))
                    .collect(),
                mean,
                variance,
                first,
                total,
                interactions,
                first_ci,
                total_ci,
                cv_error: fit.cv_error,
                loo_error: fit.loo_error,
                train_error: fit.train_error,
                omp_steps: fit.steps,
            }
        })
        .collect();
    Ok(PceResult {
        names: problem.names(),
        n_samples: n,
        n_candidates,
        params: params.clone(),
        outputs,
        germs,
    })
}

/// Samples `params.n_samples` runs of `model` on `params.sampling` and fits a sparse PCE.
///
/// # Errors
/// As [`fit_pce`], plus [`Error::ModelOutput`] for non-finite model values.
pub fn build_pce<M: Model + ?Sized>(
    model: &M,
    problem: &Problem,
    params: &PceParams,
) -> Result<PceResult> {
    let (x, y) = sample_runs(
        model,
        problem,
        params.sampling,
        params.n_samples,
        params.seed,
    )?;
    fit_pce(problem, &x, &y, model.n_outputs(), params)
}

/// Evaluates `model` on an n-point design: returns (x: n × k, y: n × m), row-major.
///
/// # Errors
/// [`Error::ModelOutput`] for non-finite model values.
pub fn sample_runs<M: Model + ?Sized>(
    model: &M,
    problem: &Problem,
    sampling: Sampling,
    n: usize,
    seed: u64,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let k = problem.dim();
    let m = model.n_outputs();
    let mut x = UnitDesign::new(sampling, k, n, seed)?.to_vec();
    for row in x.chunks_exact_mut(k) {
        problem.transform_unit(row);
    }
    let mut y = vec![0.0; n * m];
    let chunk = 64;
    y.par_chunks_mut(chunk * m)
        .zip(x.par_chunks(chunk * k))
        .try_for_each(|(yc, xc)| eval_checked(model, xc.len() / k, k, xc, yc))?;
    Ok((x, y))
}

impl PceResult {
    /// Evaluates the expansion of output `o` at input values `x` (length k).
    pub fn predict(&self, problem: &Problem, o: usize, x: &[f64]) -> f64 {
        let mut xi = x.to_vec();
        problem.to_germ(&mut xi);
        let out = &self.outputs[o];
        let p = out.degree;
        let mut u = vec![0.0; p + 1];
        out.terms
            .iter()
            .map(|(mi, c)| {
                c * mi
                    .iter()
                    .map(|&(v, d)| {
                        univariate(self.germs[v as usize], xi[v as usize], p, &mut u);
                        u[d as usize]
                    })
                    .product::<f64>()
            })
            .sum()
    }

    /// Relative mean squared error (MSE / Var) of output `o` on independent validation runs.
    pub fn validation_error(&self, problem: &Problem, o: usize, x: &[f64], y: &[f64]) -> f64 {
        let k = problem.dim();
        let n = x.len() / k;
        let m = y.len() / n;
        let yo: Vec<f64> = (0..n).map(|r| y[r * m + o]).collect();
        let mean = yo.iter().sum::<f64>() / n as f64;
        let var = yo.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
        let mse = (0..n)
            .map(|r| (self.predict(problem, o, &x[r * k..(r + 1) * k]) - yo[r]).powi(2))
            .sum::<f64>()
            / n as f64;
        mse / var
    }
}
