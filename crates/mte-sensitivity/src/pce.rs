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
//! LOO·n/(n − p)·(1 + tr(C⁻¹)/n), C = Ψ_AᵀΨ_A/n). A path that is sized by its own error (a fold
//! path, or the single path under corrected LOO) stops max(10, p*/5) steps after the size p* of
//! its smallest error so far, at `max_terms` or when the runs are fitted exactly; under K-fold
//! the full-data path is only taken as far as the folds' choice. One seeded fold partition serves
//! every output. The correlations Ψ_vᵀr of each path (row variant v: all rows, or all but one
//! fold) are updated after each step from the Gram columns Ψ_vᵀψ_a of the chosen candidate,
//! cached and shared by all paths and outputs of one design. Ψ itself is never stored: every
//! product Ψᵀ·B is computed block by block from the univariate values (see `Design`), each value
//! one fixed-order dot product, so results do not depend on timing, batching or thread count.
//! The degree is chosen the same way when `adaptive_degree` is on (degrees 1 … p, stop when the
//! error grows).
//!
//! Every result carries an error on new inputs that sees the search
//! ([`PceOutput::selection_aware_error`]). Under K-fold that is the CV error. The corrected LOO
//! treats the chosen terms as fixed, so after a search over far more candidates than runs it is
//! optimistic, by orders of magnitude on hard problems; under corrected LOO the runs are
//! therefore split into [`LOO_CHECK_FOLDS`] folds as under K-fold, and each fold path runs the
//! corrected-LOO search on its training rows by its own corrected LOO (size, stopping, at most
//! half its training runs), its choice scored on its held-out rows. The full-data path is
//! unaffected by the folds. As under K-fold, the choice among degrees is not repeated.
//! [`PceOutput::warnings`] flags errors that disagree and errors too large for the indices to be
//! read; [`build_pce`] can measure the error on fresh runs ([`PceParams::validation`]).
//!
//! Sobol' indices from the coefficients (Sudret 2008): V = Σ_{α≠0} c_α², Sᵢ = Σ_{α: only i} c_α²/V,
//! S_Tᵢ = Σ_{α ∋ i} c_α²/V, S_ij = Σ_{α: exactly {i, j}} c_α²/V.

use crate::design::{Sampling, UnitDesign};
use crate::dist::{Germ, Problem};
use crate::error::{Error, Result};
use crate::model::{Model, eval_checked};
use crate::stats::{interval, stream};
use faer::{Accum, MatRef, Par};
use rand::Rng;
use rand::seq::SliceRandom;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

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
    /// candidates far outnumber runs, and its score does not see the search: the result
    /// reports a selection-aware estimate beside it, [`PceOutput::selection_aware_error`]).
    CorrectedLoo,
}

/// Settings of a sparse PCE.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
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
    /// Seed (fold assignment, one for all outputs; bootstrap; the design in [`build_pce`]).
    pub seed: u64,
    /// Number of model runs for [`build_pce`].
    pub n_samples: usize,
    /// Design for [`build_pce`].
    pub sampling: Sampling,
    /// Fresh model runs on which [`build_pce`] measures the fitted expansion's error
    /// ([`PceOutput::validation_error`]); none by default.
    pub validation: Option<Validation>,
}

/// Fresh model runs for the validation error: independent Monte Carlo points, so that the
/// relative mean squared error on them is an unbiased estimate of the error on new inputs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Validation {
    /// Number of runs.
    pub n: usize,
    /// Seed of their design (default: the PCE seed on a stream of its own, independent of the
    /// fit's design).
    #[serde(default)]
    pub seed: Option<u64>,
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
            validation: None,
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
    /// K-fold CV mean squared error / Var(y) at the chosen size: each fold runs the search on
    /// its training runs (NaN under corrected LOO selection).
    pub cv_error: f64,
    /// Corrected leave-one-out error / Var(y) of the chosen model. It treats the chosen terms
    /// as fixed in advance: after a search over many more candidates than runs it can be
    /// optimistic by orders of magnitude; read [`PceOutput::selection_aware_error`].
    pub loo_error: f64,
    /// Training mean squared error / Var(y) (optimistic by construction).
    pub train_error: f64,
    /// OMP steps taken on the full-data path (under K-fold CV the chosen size, unless the path
    /// ran out of candidates or fitted the runs exactly before it).
    pub omp_steps: usize,
    /// Estimate of the mean squared error / Var(y) on new inputs that sees the term search:
    /// under K-fold the K-fold CV error (`cv_error`); under corrected LOO the corrected-LOO
    /// term search repeated on the training runs of each of [`LOO_CHECK_FOLDS`] folds (at the
    /// chosen degree), the error of each fold's choice on its held-out runs, averaged. The error
    /// to read. Neither rule repeats the choice among the few degrees of `adaptive_degree`
    /// inside the folds.
    pub selection_aware_error: f64,
    /// Mean squared error / Var(y) on fresh model runs ([`PceParams::validation`]; `None`
    /// without, or from [`fit_pce`]).
    pub validation_error: Option<f64>,
    /// Where the reported errors say the expansion or its error is not to be trusted.
    pub warnings: Vec<PceWarning>,
}

/// A reported error, by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorName {
    /// [`PceOutput::loo_error`], the corrected-LOO rule's own score.
    CorrectedLoo,
    /// [`PceOutput::selection_aware_error`].
    SelectionAware,
    /// [`PceOutput::validation_error`].
    Validation,
}

impl std::fmt::Display for ErrorName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ErrorName::CorrectedLoo => "corrected LOO error",
            ErrorName::SelectionAware => "selection-aware error",
            ErrorName::Validation => "validation error",
        })
    }
}

/// Two reported errors differing by more than this factor disagree ([`PceWarning::Disagree`]).
pub const DISAGREEMENT: f64 = 2.0;

/// Errors below this are not compared: at a relative error ε no index is off by more than
/// 2√ε + ε (see [`READABLE_ERROR`]), 0.02 here, whatever the two say.
pub const NEGLIGIBLE_ERROR: f64 = 1e-4;

/// Largest relative error (MSE / Var on new inputs) at which the indices are still to be read.
/// The part of the output the expansion gets wrong has variance ε·V; it can hide in any one
/// term of the variance decomposition, so (with ‖P_u f‖ the part of input set u) each
/// √V_u is off by at most √(εV): an input shown with index 0 may truly have index ε, and an
/// index S may truly be (√S ± √ε)², off by up to 2√(Sε) + ε. At ε = 0.1 an input shown as
/// negligible may carry a tenth of the variance, above the usual screening levels (0.05–0.1),
/// and a leading index of 0.3 may be off by 0.45: the indices no longer answer which inputs
/// matter.
pub const READABLE_ERROR: f64 = 0.1;

/// What the reported errors of one output say about trusting it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "warning", rename_all = "snake_case")]
pub enum PceWarning {
    /// Two errors disagree by more than [`DISAGREEMENT`] times, the larger above
    /// [`NEGLIGIBLE_ERROR`]: the smaller one is not an error on new inputs (the rule's own score
    /// does not see the term search, or the estimate is off); trust the larger.
    Disagree {
        /// The smaller error.
        low: ErrorName,
        /// Its value.
        low_value: f64,
        /// The larger error.
        high: ErrorName,
        /// Its value.
        high_value: f64,
    },
    /// The largest estimate of the error on new inputs (selection-aware or validation) is above
    /// [`READABLE_ERROR`]: the indices should not be read.
    LargeError {
        /// Which error.
        error: ErrorName,
        /// Its value.
        value: f64,
        /// The limit ([`READABLE_ERROR`]).
        limit: f64,
    },
}

impl std::fmt::Display for PceWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            PceWarning::Disagree {
                low,
                low_value,
                high,
                high_value,
            } => write!(
                f,
                "{low} {low_value:.3e} and {high} {high_value:.3e} disagree by more than a factor \
                 {DISAGREEMENT}: the {low} is not an error on new inputs; trust the {high}"
            ),
            PceWarning::LargeError {
                error,
                value,
                limit,
            } => write!(
                f,
                "{error} {value:.3e} > {limit}: the expansion misses so much of the output that \
                 its indices should not be read (more runs, another degree, or Sobol')"
            ),
        }
    }
}

impl PceOutput {
    /// The output with its [`PceOutput::warnings`] derived from its errors under `selection`.
    fn assessed(mut self, selection: Selection) -> Self {
        let named = |name: ErrorName, v: f64| v.is_finite().then_some((name, v));
        let rule = match selection {
            Selection::CorrectedLoo => named(ErrorName::CorrectedLoo, self.loo_error),
            // the K-fold score is the selection-aware estimate
            Selection::KFold { .. } => None,
        };
        let estimate = named(ErrorName::SelectionAware, self.selection_aware_error);
        let validation = self
            .validation_error
            .and_then(|v| named(ErrorName::Validation, v));
        let mut warnings = vec![];
        // the rule's score against the selection-aware estimate, that against the validation
        let pairs = [(rule, estimate), (estimate.or(rule), validation)];
        for (a, b) in pairs {
            let (Some(a), Some(b)) = (a, b) else { continue };
            let (low, high) = if a.1 <= b.1 { (a, b) } else { (b, a) };
            if high.1 > NEGLIGIBLE_ERROR && high.1 > DISAGREEMENT * low.1 {
                warnings.push(PceWarning::Disagree {
                    low: low.0,
                    low_value: low.1,
                    high: high.0,
                    high_value: high.1,
                });
            }
        }
        let largest = [estimate.or(rule), validation]
            .into_iter()
            .flatten()
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((error, value)) = largest.filter(|l| l.1 > READABLE_ERROR) {
            warnings.push(PceWarning::LargeError {
                error,
                value,
                limit: READABLE_ERROR,
            });
        }
        self.warnings = warnings;
        self
    }
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

/// The design matrix Ψ (n × P), never stored: a candidate's column is the product of a few
/// univariate columns, and every product Ψᵀ·B is computed parent by parent. Each candidate α is
/// its parent (α without its last variable's factor, also a candidate: the sets are downward
/// closed) times one univariate column φ_d(ξ_l); for a parent column π and right-hand side b,
/// Σ_r b_r π_r φ_d(ξ_rl) = φ_d(ξ_l)ᵀ(b ⊙ π) — so Ψᵀ·B costs n·P·W multiply-adds on data that
/// stay in cache (the univariate table is n × (1 + p·k)), where a stored Ψ (n·P values, 106 MB
/// for 41 inputs at degree 3 and 1000 runs) would be streamed from memory on every product.
/// Parents with the same list of last factors (under total degree: all parents whose last
/// variable and degree agree) form one block, so each univariate value loaded serves up to four
/// parents or right-hand sides: a register-blocked matrix product instead of dot products.
/// The candidates are stored in block order ([`Design::basis`]). Rows are grouped fold by fold,
/// so every fold's held-out rows are one contiguous segment.
struct Design {
    n: usize,
    p: usize,
    /// Univariate columns (n values each): 0 is the constant 1, 1 + (d − 1)·k + l is φ_d(ξ_l).
    uni: Vec<f64>,
    /// The candidates, in the design's order (block by block, parent-major).
    basis: Vec<MultiIndex>,
    /// Univariate column index of each candidate's factors.
    factors: Vec<Vec<usize>>,
    blocks: Vec<Block>,
    /// Row ranges (start, len) of the folds (one range over all rows without folds).
    segs: Vec<(usize, usize)>,
}

/// Parents (at most [`BLOCK_PARENTS`]) sharing one list of last factors. Their candidates
/// follow those of the blocks before, parent-major (parent i, child t at i·children.len() + t).
struct Block {
    /// Univariate columns of each parent's factors (none: the constant 1, parent of the
    /// constant and the univariate terms).
    parents: Vec<Vec<usize>>,
    /// Univariate column of each child's last factor.
    children: Vec<usize>,
}

impl Block {
    /// Number of candidates (parents × children), also the block's share of a product's work.
    fn len(&self) -> usize {
        self.parents.len() * self.children.len()
    }
}

/// Largest number of parents in one block: two passes of the four-wide register block for one
/// right-hand side, and few enough z vectors (b ⊙ π) to stay in L1 while the children stream
/// past; more blocks also share the work out more evenly over threads.
const BLOCK_PARENTS: usize = 8;

impl Design {
    /// Ψ of the candidates `basis` at germ points `xi` (n × k row-major, already in fold order).
    /// The design holds the same candidates in its own order ([`Design::basis`]).
    fn new(
        xi: &[f64],
        n: usize,
        k: usize,
        germs: &[Germ],
        deg: usize,
        basis: &[MultiIndex],
        segs: Vec<(usize, usize)>,
    ) -> Design {
        let mut uni = vec![0.0; n * (1 + deg * k)];
        uni[..n].fill(1.0);
        let mut vals = vec![0.0; deg + 1];
        for r in 0..n {
            for (l, &germ) in germs.iter().enumerate().take(k) {
                univariate(germ, xi[r * k + l], deg, &mut vals);
                for (d, &v) in vals.iter().enumerate().skip(1) {
                    uni[(1 + (d - 1) * k + l) * n + r] = v;
                }
            }
        }
        let column_of = |&(l, d): &(u32, u32)| 1 + (d as usize - 1) * k + l as usize;
        // children (last factor's column, candidate) of each parent, parents in basis order
        let mut parents: Vec<(Option<&[(u32, u32)]>, Vec<(usize, &MultiIndex)>)> = vec![];
        let mut parent_at: HashMap<Option<&[(u32, u32)]>, usize> = HashMap::new();
        for a in basis {
            let (parent, last) = match a.split_last() {
                None => (None, 0),
                Some((last, rest)) => ((!rest.is_empty()).then_some(rest), column_of(last)),
            };
            let at = *parent_at.entry(parent).or_insert_with(|| {
                parents.push((parent, vec![]));
                parents.len() - 1
            });
            parents[at].1.push((last, a));
        }
        // parents with equal children lists, in order of first appearance, BLOCK_PARENTS at most
        let mut lists: Vec<(Vec<usize>, Vec<usize>)> = vec![];
        let mut list_at: HashMap<Vec<usize>, usize> = HashMap::new();
        for (i, (_, children)) in parents.iter().enumerate() {
            let key: Vec<usize> = children.iter().map(|c| c.0).collect();
            let at = *list_at.entry(key.clone()).or_insert_with(|| {
                lists.push((key, vec![]));
                lists.len() - 1
            });
            lists[at].1.push(i);
        }
        let mut ordered = Vec::with_capacity(basis.len());
        let mut blocks = vec![];
        for (children, members) in lists {
            for chunk in members.chunks(BLOCK_PARENTS) {
                blocks.push(Block {
                    parents: chunk
                        .iter()
                        .map(|&i| parents[i].0.unwrap_or(&[]).iter().map(column_of).collect())
                        .collect(),
                    children: children.clone(),
                });
                for &i in chunk {
                    ordered.extend(parents[i].1.iter().map(|c| c.1.clone()));
                }
            }
        }
        let factors = ordered
            .iter()
            .map(|a| a.iter().map(column_of).collect())
            .collect();
        Design {
            n,
            p: ordered.len(),
            uni,
            basis: ordered,
            factors,
            blocks,
            segs,
        }
    }

    /// Row variants: all rows, and with folds all rows but each fold.
    fn n_variants(&self) -> usize {
        match self.segs.len() {
            1 => 1,
            folds => folds + 1,
        }
    }

    /// Column ψ_j over all rows.
    fn col(&self, j: usize) -> Vec<f64> {
        let mut out = vec![1.0; self.n];
        for &c in &self.factors[j] {
            for (o, u) in out.iter_mut().zip(&self.uni[c * self.n..(c + 1) * self.n]) {
                *o *= u;
            }
        }
        out
    }

    /// Squared column norms over every row variant: v = 0 all rows, v = f + 1 all rows but fold f
    /// (Σ_r π_r²·φ_r² from the squared univariate columns).
    fn norms2(&self) -> Vec<Vec<f64>> {
        let squares: Vec<f64> = self.uni.iter().map(|u| u * u).collect();
        let ones = vec![1.0; self.n];
        self.products(&squares, &[&ones], true)
            .into_iter()
            .map(|mut v| v.pop().expect("one right-hand side"))
            .collect()
    }

    /// Ψ_vᵀ·B for every variant v of the row set (v = 0 all rows, v = f + 1 all rows but fold f).
    /// `b` holds W columns of n values in the design's row order; returns [variant][rhs][P].
    /// Every value is one fixed-order dot product per fold segment, whatever else is in `b` and
    /// however the work is split over threads.
    fn variant_products(&self, b: &[&[f64]], parallel: bool) -> Vec<Vec<Vec<f64>>> {
        self.products(&self.uni, b, parallel)
    }

    /// [variant][rhs][P]: for candidate π × φ (π = Π of the parent's factors), Σ_r b_r·π_r·φ_r
    /// over each variant's rows, with π and φ taken from `table` (the univariate columns, or
    /// their squares). Each task takes a run of blocks through the fold segments one after the
    /// other, so that one segment of the table stays in L2 while the run's blocks pass over it;
    /// all rows is the sum over the segments in order, fold f's training rows that sum minus
    /// segment f.
    fn products(&self, table: &[f64], b: &[&[f64]], parallel: bool) -> Vec<Vec<Vec<f64>>> {
        let (w, n_var) = (b.len(), self.n_variants());
        let mut out: Vec<Vec<Vec<f64>>> = (0..n_var)
            .map(|_| (0..w).map(|_| vec![0.0; self.p]).collect())
            .collect();
        // each block's stretch of every out[v][c], in the order v·w + c
        let mut per_block: Vec<Vec<&mut [f64]>> = self
            .blocks
            .iter()
            .map(|_| Vec::with_capacity(n_var * w))
            .collect();
        for values in out.iter_mut().flatten() {
            let mut rest = values.as_mut_slice();
            for (block, mine) in self.blocks.iter().zip(per_block.iter_mut()) {
                let (head, tail) = std::mem::take(&mut rest).split_at_mut(block.len());
                mine.push(head);
                rest = tail;
            }
        }
        // runs of consecutive blocks of about equal work, one task each (one parallel region per
        // product; a value does not depend on the run its block falls in)
        let tasks = if parallel {
            4 * rayon::current_num_threads()
        } else {
            1
        };
        let share = self
            .blocks
            .iter()
            .map(Block::len)
            .sum::<usize>()
            .div_ceil(tasks);
        let mut runs: Vec<(&[Block], &mut [Vec<&mut [f64]>])> = vec![];
        let (mut blocks, mut outs) = (&self.blocks[..], &mut per_block[..]);
        while !blocks.is_empty() {
            let (mut len, mut work) = (1, blocks[0].len());
            while len < blocks.len() && work + blocks[len].len() <= share {
                work += blocks[len].len();
                len += 1;
            }
            let (run_outs, rest) = std::mem::take(&mut outs).split_at_mut(len);
            runs.push((&blocks[..len], run_outs));
            (blocks, outs) = (&blocks[len..], rest);
        }
        let arch = pulp::Arch::new();
        let run = |(blocks, outs): (&[Block], &mut [Vec<&mut [f64]>])| {
            let mut z = Vec::new();
            for (s, &rows) in self.segs.iter().enumerate() {
                for (block, out) in blocks.iter().zip(outs.iter_mut()) {
                    arch.dispatch(BlockProducts {
                        n: self.n,
                        table,
                        b,
                        block,
                        rows,
                        s,
                        folds: n_var > 1,
                        z: &mut z,
                        out,
                    })
                }
            }
        };
        if parallel {
            runs.into_par_iter().for_each(run);
        } else {
            runs.into_iter().for_each(run);
        }
        drop(per_block);
        // out[f + 1] holds segment f: fold f's training rows are all rows minus it
        if let Some((full, folds)) = out.split_first_mut() {
            for fold in folds {
                for (seg, all) in fold.iter_mut().zip(full.iter()) {
                    seg.iter_mut().zip(all).for_each(|(v, a)| *v = a - *v);
                }
            }
        }
        out
    }
}

/// One block's dot products over one row segment for its vectors z = b_c ⊙ π (parent-major, then
/// right-hand side c), vectorised for the CPU found at run time. Segment by segment, they are
/// summed in order into out[c] (all rows) and, with folds, segment s is kept in out[(s + 1)·w + c].
struct BlockProducts<'a, 'b> {
    n: usize,
    table: &'a [f64],
    b: &'a [&'a [f64]],
    block: &'a Block,
    /// The segment's rows (start, len) and its index.
    rows: (usize, usize),
    s: usize,
    /// Whether the rows are in folds (the segments are kept).
    folds: bool,
    /// Scratch for the z vectors.
    z: &'a mut Vec<f64>,
    /// The block's stretch of out[v][c], at v·w + c.
    out: &'a mut [&'b mut [f64]],
}

impl pulp::WithSimd for BlockProducts<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        let BlockProducts {
            n,
            table,
            b,
            block,
            rows: (r0, len),
            s,
            folds,
            z,
            out,
        } = self;
        let col = |c: usize| &table[c * n + r0..c * n + r0 + len];
        let nc = block.children.len();
        let nz = block.parents.len() * b.len();
        // z = b ⊙ π, π the product of the parent's factors in order (as in [`Design::col`])
        z.clear();
        for factors in &block.parents {
            for bc in b {
                let bc = &bc[r0..r0 + len];
                match factors[..] {
                    [] => z.extend_from_slice(bc),
                    [f] => z.extend(bc.iter().zip(col(f)).map(|(x, u)| x * u)),
                    // two factors (every degree-2 parent) in one pass; the same values as the
                    // general arm below, x·(u·v) = (u·v)·x
                    [f, g] => z.extend(
                        bc.iter()
                            .zip(col(f).iter().zip(col(g)))
                            .map(|(x, (u, v))| x * (u * v)),
                    ),
                    [f, ..] => {
                        let at = z.len();
                        z.extend_from_slice(col(f));
                        for &g in &factors[1..] {
                            z[at..].iter_mut().zip(col(g)).for_each(|(v, u)| *v *= u);
                        }
                        z[at..].iter_mut().zip(bc).for_each(|(v, x)| *v *= x);
                    }
                }
            }
        }
        let z: &[f64] = z;
        let w = b.len();
        let mut put = |zi: usize, t: usize, v: f64| {
            let (c, j) = (zi % w, zi / w * nc + t);
            if s == 0 {
                out[c][j] = v;
            } else {
                out[c][j] += v;
            }
            if folds {
                out[(s + 1) * w + c][j] = v;
            }
        };
        let a = |t: usize| col(block.children[t]);
        let zc = |i: usize| &z[i * len..(i + 1) * len];
        let (z2, z4, c4) = (nz - nz % 2, nz - nz % 4, nc - nc % 4);
        // z vectors four at a time against children in pairs (eight accumulators), the odd child
        // against the four
        for i in (0..z4).step_by(4) {
            let zs = [zc(i), zc(i + 1), zc(i + 2), zc(i + 3)];
            let mut t = 0;
            while t + 2 <= nc {
                let d = dots_2x4(simd, [a(t), a(t + 1)], zs);
                for (dt, row) in d.iter().enumerate() {
                    for (di, v) in row.iter().enumerate() {
                        put(i + di, t + dt, *v);
                    }
                }
                t += 2;
            }
            if t < nc {
                // aᵀz = zᵀa: the same fused operations with the roles swapped
                for (di, v) in dots_cx1(simd, zs, a(t)).iter().enumerate() {
                    put(i + di, t, *v);
                }
            }
        }
        // the rest in pairs against children four at a time, then one by one
        for i in (z4..z2).step_by(2) {
            for t in (0..c4).step_by(4) {
                let d = dots_2x4(
                    simd,
                    [zc(i), zc(i + 1)],
                    [a(t), a(t + 1), a(t + 2), a(t + 3)],
                );
                for (di, row) in d.iter().enumerate() {
                    for (dt, v) in row.iter().enumerate() {
                        put(i + di, t + dt, *v);
                    }
                }
            }
            for t in c4..nc {
                for (di, v) in dots_cx1(simd, [zc(i), zc(i + 1)], a(t)).iter().enumerate() {
                    put(i + di, t, *v);
                }
            }
        }
        if z2 < nz {
            let i = z2;
            for t in (0..c4).step_by(4) {
                let d = dots_cx1(simd, [a(t), a(t + 1), a(t + 2), a(t + 3)], zc(i));
                for (dt, v) in d.iter().enumerate() {
                    put(i, t + dt, *v);
                }
            }
            for t in c4..nc {
                put(i, t, dots_cx1(simd, [a(t)], zc(i))[0]);
            }
        }
    }
}

/// The dot products a_iᵀb_w of equal-length slices, two rows of `a` against four of `b` with
/// the eight accumulators in registers. Every value is lane-wise fused multiply-adds in row
/// order, lanes summed, then the left-over rows ([`finish`]) — the same operations as in
/// [`dots_cx1`], so a value does not depend on which block computes it.
#[inline(always)]
fn dots_2x4<S: pulp::Simd>(simd: S, a: [&[f64]; 2], b: [&[f64]; 4]) -> [[f64; 4]; 2] {
    let (a0, a0t) = S::as_simd_f64s(a[0]);
    let (a1, a1t) = S::as_simd_f64s(a[1]);
    let (b0, b0t) = S::as_simd_f64s(b[0]);
    let (b1, b1t) = S::as_simd_f64s(b[1]);
    let (b2, b2t) = S::as_simd_f64s(b[2]);
    let (b3, b3t) = S::as_simd_f64s(b[3]);
    let zero = simd.splat_f64s(0.0);
    let (mut s00, mut s01, mut s02, mut s03) = (zero, zero, zero, zero);
    let (mut s10, mut s11, mut s12, mut s13) = (zero, zero, zero, zero);
    for r in 0..a0.len() {
        let (x0, x1) = (a0[r], a1[r]);
        let y = b0[r];
        s00 = simd.mul_add_f64s(x0, y, s00);
        s10 = simd.mul_add_f64s(x1, y, s10);
        let y = b1[r];
        s01 = simd.mul_add_f64s(x0, y, s01);
        s11 = simd.mul_add_f64s(x1, y, s11);
        let y = b2[r];
        s02 = simd.mul_add_f64s(x0, y, s02);
        s12 = simd.mul_add_f64s(x1, y, s12);
        let y = b3[r];
        s03 = simd.mul_add_f64s(x0, y, s03);
        s13 = simd.mul_add_f64s(x1, y, s13);
    }
    [
        [
            finish(simd, s00, a0t, b0t),
            finish(simd, s01, a0t, b1t),
            finish(simd, s02, a0t, b2t),
            finish(simd, s03, a0t, b3t),
        ],
        [
            finish(simd, s10, a1t, b0t),
            finish(simd, s11, a1t, b1t),
            finish(simd, s12, a1t, b2t),
            finish(simd, s13, a1t, b3t),
        ],
    ]
}

/// The C dot products a_iᵀb, each computed exactly as a value of [`dots_2x4`].
#[inline(always)]
fn dots_cx1<S: pulp::Simd, const C: usize>(simd: S, a: [&[f64]; C], b: &[f64]) -> [f64; C] {
    let (bh, bt) = S::as_simd_f64s(b);
    let a = a.map(|ai| {
        let (h, t) = S::as_simd_f64s(ai);
        (&h[..bh.len()], t)
    });
    let mut acc = [simd.splat_f64s(0.0); C];
    for (r, y) in bh.iter().enumerate() {
        for (acc_i, ai) in acc.iter_mut().zip(&a) {
            *acc_i = simd.mul_add_f64s(ai.0[r], *y, *acc_i);
        }
    }
    std::array::from_fn(|i| finish(simd, acc[i], a[i].1, bt))
}

/// Lanes of `acc` summed, then the rows that did not fill a vector.
#[inline(always)]
fn finish<S: pulp::Simd>(simd: S, acc: S::f64s, a: &[f64], b: &[f64]) -> f64 {
    let mut s = simd.reduce_sum_f64s(acc);
    for (x, y) in a.iter().zip(b) {
        s = x.mul_add(*y, s);
    }
    s
}

/// Outputs fitted together: their Ψ_vᵀy are one product, and their correlation vectors
/// (folds + 1 per output, P values each) are held at the same time.
const OUTPUTS_PER_PRODUCT: usize = 32;

/// Active-set size from which a path takes Ψ_vᵀq from a direct product ([`Path::direct`]).
const DIRECT_AFTER: usize = 160;

/// Columns per block of a path's U = Ψ_vᵀQ ([`Path`]).
const U_BLOCK: usize = 16;

/// Largest number of cached Gram columns (each holds folds + 1 vectors of P values).
const CACHE_BYTES: usize = 256 << 20;

/// Gram columns Ψ_vᵀψ_a of every row variant v, shared by all paths and outputs of one design.
struct GramCache {
    cols: Mutex<HashMap<usize, Arc<Vec<Vec<f64>>>>>,
    capacity: usize,
}

impl GramCache {
    fn new(d: &Design) -> GramCache {
        let per = d.p * d.n_variants() * 8 + 1;
        GramCache {
            cols: Mutex::new(HashMap::new()),
            capacity: (CACHE_BYTES / per).max(64),
        }
    }

    fn get(&self, j: usize) -> Option<Arc<Vec<Vec<f64>>>> {
        self.cols.lock().expect("cache lock").get(&j).cloned()
    }

    fn has(&self, j: usize) -> bool {
        self.cols.lock().expect("cache lock").contains_key(&j)
    }

    /// Computes and stores the Gram columns of `want` (their values do not depend on which
    /// other columns share the product, nor on timing or thread count).
    fn fill(&self, d: &Design, want: &[usize], parallel: bool) {
        let cols: Vec<Vec<f64>> = want.iter().map(|&j| d.col(j)).collect();
        let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
        let mut by_column: Vec<Vec<Vec<f64>>> = want.iter().map(|_| vec![]).collect();
        for variant in d.variant_products(&refs, parallel) {
            for (c, values) in variant.into_iter().enumerate() {
                by_column[c].push(values);
            }
        }
        let mut map = self.cols.lock().expect("cache lock");
        if map.len() + want.len() > self.capacity {
            map.clear();
        }
        for (&j, g) in want.iter().zip(by_column) {
            map.insert(j, Arc::new(g));
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Stop {
    Running,
    Done,
}

/// A candidate chosen by a path, orthogonalised against its active set, awaiting its Gram column.
struct Pending {
    j: usize,
    /// The candidate's values on the held-out rows (for the hold-out error).
    held: Vec<f64>,
    v: Vec<f64>,
    rc: Vec<f64>,
    rkk: f64,
}

/// One OMP path on a subset of rows (all rows, or all but one fold) of Ψ.
///
/// The correlations c = Ψ_vᵀ r of every candidate with the residual are kept up to date from
/// Gram columns: with q_k = (ψ_a − Q r_c)/r_kk, Ψ_vᵀq_k = (Ψ_vᵀψ_a − U r_c)/r_kk where
/// U = Ψ_vᵀQ, and c ← c − (q_kᵀr) Ψ_vᵀq_k — P·k work per step instead of P·n.
struct Path {
    variant: usize,
    mask: Vec<f64>,
    hold: Vec<usize>,
    norm2: Vec<f64>,
    excluded: Vec<bool>,
    active: Vec<usize>,
    /// Held-out rows of each active column.
    held: Vec<Vec<f64>>,
    /// Orthonormal basis Q of the active columns (n × p, column-major).
    q: Vec<f64>,
    rinv: Vec<Vec<f64>>,
    rinv_f2: f64,
    qty: Vec<f64>,
    resid: Vec<f64>,
    h: Vec<f64>,
    c: Vec<f64>,
    /// U = Ψ_vᵀQ in blocks of [`U_BLOCK`] columns (P × cols, column-major), so that growing it
    /// never copies what is there.
    u: Vec<Vec<f64>>,
    /// Ψ_vᵀq of the newest column (scratch of P values).
    un: Vec<f64>,
    n_train: usize,
    var_y: f64,
    y_norm2: f64,
    hold_err: Vec<f64>,
    cloo: Vec<f64>,
    best: f64,
    best_p: usize,
    state: Stop,
    kmax: usize,
    /// Active-set size from which steps are [`Path::direct`].
    direct_after: usize,
    /// Whether the path is sized by its own corrected LOO (every path under corrected LOO)
    /// rather than by hold-out errors (the fold paths under K-fold).
    by_loo: bool,
}

impl Path {
    /// Path of row variant `variant` (0: all rows; f + 1: all but fold f); `c0` = Ψ_vᵀy,
    /// `norm2` the squared column norms over the variant's rows; steps are [`Path::direct`] from
    /// `direct_after` active terms; `by_loo`: sized by its own corrected LOO.
    fn new(
        d: &Design,
        y: &[f64],
        variant: usize,
        kmax: usize,
        direct_after: usize,
        by_loo: bool,
        norm2: Vec<f64>,
        c0: Vec<f64>,
    ) -> Self {
        let n = y.len();
        let mut mask = vec![1.0; n];
        let mut hold = vec![];
        if variant > 0 {
            let (r0, len) = d.segs[variant - 1];
            hold.extend(r0..r0 + len);
            mask[r0..r0 + len].fill(0.0);
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
            variant,
            mask,
            hold,
            norm2,
            excluded,
            active: vec![],
            held: vec![],
            q: vec![],
            rinv: vec![],
            rinv_f2: 0.0,
            qty: vec![],
            resid,
            h: vec![0.0; n],
            c: c0,
            u: vec![],
            un: vec![],
            n_train,
            var_y,
            y_norm2,
            hold_err: vec![],
            cloo: vec![],
            best: f64::INFINITY,
            best_p: 0,
            state: Stop::Running,
            kmax,
            direct_after,
            by_loo,
        }
    }

    fn coef(&self, p: usize) -> Vec<f64> {
        (0..p)
            .map(|i| (i..p).map(|j| self.rinv[j][i] * self.qty[j]).sum())
            .collect()
    }

    fn score(&self, j: usize) -> f64 {
        self.c[j] * self.c[j] / self.norm2[j]
    }

    /// Picks the candidate most correlated with the residual (first of equals) and
    /// orthogonalises it against the active set; None (and stopped) when none is left.
    fn select(&mut self, d: &Design) -> Option<Pending> {
        let n = d.n;
        loop {
            let mut best = None;
            let mut bv = -1.0;
            for j in 0..self.c.len() {
                if self.excluded[j] {
                    continue;
                }
                let v = self.score(j);
                if v > bv {
                    bv = v;
                    best = Some(j);
                }
            }
            let Some(j) = best else {
                self.state = Stop::Done;
                return None;
            };
            self.excluded[j] = true;
            let col = d.col(j);
            let mut v: Vec<f64> = (0..n).map(|i| col[i] * self.mask[i]).collect();
            let p = self.active.len();
            let mut rc = vec![0.0; p + 1];
            if p > 0 {
                // classical Gram–Schmidt twice (as accurate as modified G–S twice, in products)
                let q = MatRef::from_column_major_slice(&self.q, n, p);
                let mut dt = faer::Col::<f64>::zeros(p);
                for _ in 0..2 {
                    let vc = faer::ColRef::from_slice(&v);
                    faer::linalg::matmul::matmul(
                        dt.as_mat_mut(),
                        Accum::Replace,
                        q.transpose(),
                        vc.as_mat(),
                        1.0,
                        Par::Seq,
                    );
                    faer::linalg::matmul::matmul(
                        faer::ColMut::from_slice_mut(&mut v).as_mat_mut(),
                        Accum::Add,
                        q,
                        dt.as_mat(),
                        -1.0,
                        Par::Seq,
                    );
                    mte_linalg::bridge::clean_vector_state();
                    for (r, d) in rc.iter_mut().zip(dt.iter()) {
                        *r += d;
                    }
                }
            }
            let rkk = v.iter().map(|a| a * a).sum::<f64>().sqrt();
            if rkk <= 1e-9 * self.norm2[j].sqrt() {
                continue; // numerically dependent on the active set: skip this candidate
            }
            v.iter_mut().for_each(|a| *a /= rkk);
            rc[p] = rkk;
            let held = self.hold.iter().map(|&i| col[i]).collect();
            return Some(Pending {
                j,
                held,
                v,
                rc,
                rkk,
            });
        }
    }

    /// Whether the next step takes Ψ_vᵀq from a direct product rather than from a Gram column
    /// and U = Ψ_vᵀQ: once the active set is long, streaming U (P × p) costs more than the
    /// product (n·P multiply-adds on data in cache), and U is no longer kept.
    fn direct(&self) -> bool {
        self.active.len() >= self.direct_after
    }

    /// Adds the pending candidate, given its Gram columns `g` (one per row variant; `None` for a
    /// [`Path::direct`] step).
    fn commit(
        &mut self,
        d: &Design,
        y: &[f64],
        pend: Pending,
        g: Option<&[Vec<f64>]>,
        parallel: bool,
    ) {
        let n = y.len();
        let Pending {
            j,
            held,
            v,
            rc,
            rkk,
        } = pend;
        let p = self.active.len();
        let np = self.c.len();
        match g {
            // Ψ_vᵀq_new = (Ψ_vᵀψ_j − U·r_c)/r_kk
            Some(g) => {
                self.un.clear();
                self.un.extend_from_slice(&g[self.variant]);
                for (block, rc) in self.u.iter().zip(rc[..p].chunks(U_BLOCK)) {
                    faer::linalg::matmul::matmul(
                        faer::ColMut::from_slice_mut(&mut self.un).as_mat_mut(),
                        Accum::Add,
                        MatRef::from_column_major_slice(block, np, rc.len()),
                        faer::ColRef::from_slice(rc).as_mat(),
                        -1.0,
                        Par::Seq,
                    );
                }
                mte_linalg::bridge::clean_vector_state();
                self.un.iter_mut().for_each(|a| *a /= rkk);
            }
            // q_new is zero on the held-out rows, so Ψᵀq_new over all rows is Ψ_vᵀq_new
            None => {
                self.un = d
                    .variant_products(&[&v], parallel)
                    .swap_remove(0)
                    .swap_remove(0)
            }
        }
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
        let dd: f64 = v.iter().zip(&self.resid).map(|(a, b)| a * b).sum();
        self.qty.push(
            v.iter()
                .zip(y)
                .zip(&self.mask)
                .map(|((a, b), m)| a * b * m)
                .sum(),
        );
        for ((r, h), qi) in self.resid.iter_mut().zip(self.h.iter_mut()).zip(&v) {
            *r -= dd * qi;
            *h += qi * qi;
        }
        for (c, ui) in self.c.iter_mut().zip(&self.un) {
            *c -= dd * ui;
        }
        if !self.direct() {
            if self.u.last().is_none_or(|b| b.len() == U_BLOCK * np) {
                self.u.push(Vec::with_capacity(U_BLOCK * np));
            }
            self.u
                .last_mut()
                .expect("pushed")
                .extend_from_slice(&self.un);
        }
        self.q.extend_from_slice(&v);
        // store R⁻¹ by columns: rinv[col][row]
        self.rinv.push(ic);
        self.active.push(j);
        self.held.push(held);
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
        if self.variant > 0 {
            let b = self.coef(p);
            let mut e = 0.0;
            for (t, &i) in self.hold.iter().enumerate() {
                let pred: f64 = self.held.iter().zip(&b).map(|(h, bb)| h[t] * bb).sum();
                e += (y[i] - pred).powi(2);
            }
            self.hold_err.push(e / self.hold.len() as f64);
        }
        // a fold path under K-fold is sized by its hold-out error, every other by corrected LOO
        let crit = if self.variant > 0 && !self.by_loo {
            *self.hold_err.last().expect("pushed")
        } else {
            *self.cloo.last().expect("pushed")
        };
        if crit < self.best {
            self.best = crit;
            self.best_p = p;
        }
        let rr: f64 = self.resid.iter().map(|a| a * a).sum();
        let patience = 10.max(self.best_p / 5);
        // a path ends by its own criterion (hold-out error of a fold under K-fold, corrected LOO
        // under corrected LOO); the full path under K-fold is sized by the folds ([`omp_select`])
        let own_criterion = self.variant > 0 || self.by_loo;
        let own_end = own_criterion && p - self.best_p >= patience;
        if p >= self.kmax || rr <= 1e-26 * self.y_norm2 || own_end {
            self.state = Stop::Done;
        }
    }
}

/// Folds of the selection-aware estimate under corrected LOO (the rule's search repeated on each
/// fold's training runs, [`PceOutput::selection_aware_error`]).
pub const LOO_CHECK_FOLDS: usize = 5;

/// Number of folds the runs are split into: K under K-fold; under corrected LOO
/// [`LOO_CHECK_FOLDS`] for the selection-aware estimate (fewer with fewer than 15 runs, so that
/// each fold holds at least 3).
fn folds_of(params: &PceParams, n: usize) -> usize {
    match params.selection {
        Selection::KFold { folds } => folds,
        Selection::CorrectedLoo => LOO_CHECK_FOLDS.min(n / 3),
    }
}

/// Row order grouping the folds (run t of a seeded shuffle goes to fold t mod K) and the fold
/// segments in that order; the identity and one segment without folds.
fn fold_order(n: usize, folds: usize, seed: u64) -> (Vec<usize>, Vec<(usize, usize)>) {
    if folds == 0 {
        return ((0..n).collect(), vec![(0, n)]);
    }
    let mut idx: Vec<usize> = (0..n).collect();
    idx.shuffle(&mut stream(seed, 0xF01D));
    let mut perm = Vec::with_capacity(n);
    let mut segs = vec![];
    for f in 0..folds {
        let r0 = perm.len();
        perm.extend(idx.iter().skip(f).step_by(folds));
        segs.push((r0, perm.len() - r0));
    }
    (perm, segs)
}

struct Fit {
    terms: Vec<(usize, f64)>,
    cv_error: f64,
    loo_error: f64,
    train_error: f64,
    steps: usize,
    crit: f64,
    /// [`PceOutput::selection_aware_error`].
    selection_aware: f64,
}

/// OMP with the selection rule on one output; `c0[v]` = Ψ_vᵀy and `col_norm2[v]` the squared
/// column norms for each row variant v. `by_loo`: every path is sized by its own corrected LOO
/// (the fold paths then give the selection-aware estimate); otherwise K-fold. `max_terms`: the
/// user's limit; without it, half the runs (under corrected LOO, half of each path's own
/// training runs: the search on a fold is the search on all runs, repeated).
fn omp_select(
    d: &Design,
    cache: &GramCache,
    col_norm2: &[Vec<f64>],
    y: &[f64],
    c0: Vec<Vec<f64>>,
    max_terms: Option<usize>,
    by_loo: bool,
    direct_after: usize,
    parallel: bool,
) -> Fit {
    let n = y.len();
    let kmax = |nt: usize| {
        let user = max_terms.unwrap_or(if by_loo { nt } else { n } / 2).max(1);
        user.min(d.p).min(nt.saturating_sub(2)).max(1)
    };
    let mut paths: Vec<Path> = c0
        .into_iter()
        .enumerate()
        .map(|(v, c)| {
            let nt = if v == 0 { n } else { n - d.segs[v - 1].1 };
            Path::new(
                d,
                y,
                v,
                kmax(nt),
                direct_after,
                by_loo,
                col_norm2[v].clone(),
                c,
            )
        })
        .collect();
    loop {
        // Under K-fold the full path (0) only needs to reach the size the folds choose: it
        // follows their current choice, one step behind, and finishes the remaining steps (if
        // any) alone. Under corrected LOO every path runs by its own criterion.
        let full_target = if by_loo {
            usize::MAX
        } else {
            cv_choice(&paths[1..], usize::MAX).map_or(1, |c| c.0)
        };
        let live = |i: usize, p: &Path| {
            p.state == Stop::Running && (i > 0 || p.active.len() < full_target)
        };
        if !paths.iter().enumerate().any(|(i, p)| live(i, p)) {
            break;
        }
        let select = |(i, p): (usize, &mut Path)| live(i, p).then(|| p.select(d)).flatten();
        let pending: Vec<Option<Pending>> = if parallel {
            paths.par_iter_mut().enumerate().map(select).collect()
        } else {
            paths.iter_mut().enumerate().map(select).collect()
        };
        let gram = |p: &Path, pe: &Option<Pending>| pe.is_some() && !p.direct();
        // the Gram columns no path has asked for before, in one product
        let mut need: Vec<usize> = paths
            .iter()
            .zip(&pending)
            .filter(|(p, pe)| gram(p, pe))
            .filter_map(|(_, pe)| pe.as_ref().map(|pe| pe.j))
            .filter(|&j| !cache.has(j))
            .collect();
        need.sort_unstable();
        need.dedup();
        if !need.is_empty() {
            cache.fill(d, &need, parallel);
        }
        let work: Vec<(&mut Path, Pending, Option<Arc<Vec<Vec<f64>>>>)> = paths
            .iter_mut()
            .zip(pending)
            .filter_map(|(p, pe)| {
                let pe = pe?;
                let g = (!p.direct()).then(|| match cache.get(pe.j) {
                    Some(g) => g,
                    None => {
                        cache.fill(d, &[pe.j], parallel);
                        cache.get(pe.j).expect("just filled")
                    }
                });
                Some((p, pe, g))
            })
            .collect();
        let commit = |(p, pe, g): (&mut Path, Pending, Option<Arc<Vec<Vec<f64>>>>)| {
            p.commit(d, y, pe, g.as_deref().map(Vec::as_slice), parallel)
        };
        if parallel {
            work.into_par_iter().for_each(commit);
        } else {
            work.into_iter().for_each(commit);
        }
    }
    let full = &paths[0];
    let var_y = full.var_y.max(f64::MIN_POSITIVE);
    let (p_star, cv_error) = if !by_loo {
        let (p, e) = cv_choice(&paths[1..], full.active.len()).unwrap_or((1, f64::INFINITY));
        (p, e / var_y)
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
    let mut pred = vec![0.0; n];
    for &(a, b) in &terms {
        for (p, v) in pred.iter_mut().zip(d.col(a)) {
            *p += v * b;
        }
    }
    let tr: f64 = y.iter().zip(&pred).map(|(a, b)| (a - b).powi(2)).sum();
    let loo = full
        .cloo
        .get(p_star.saturating_sub(1))
        .copied()
        .unwrap_or(f64::NAN);
    // under corrected LOO: each fold path's own choice (its smallest corrected LOO) scored on
    // its held-out rows, weighted by their number
    let selection_aware = if by_loo {
        let (mut sum, mut rows) = (0.0, 0);
        for fp in paths[1..].iter().filter(|fp| fp.best_p > 0) {
            sum += fp.hold_err[fp.best_p - 1] * fp.hold.len() as f64;
            rows += fp.hold.len();
        }
        if rows > 0 {
            sum / rows as f64 / var_y
        } else {
            f64::NAN
        }
    } else {
        cv_error
    };
    Fit {
        terms,
        cv_error,
        loo_error: loo,
        train_error: tr / n as f64 / var_y,
        steps: full.active.len(),
        crit: if by_loo { loo } else { cv_error },
        selection_aware,
    }
}

/// The K-fold choice from the fold paths so far: the size (at most `limit`) with the least
/// hold-out mean squared error over all folds (a fold that ended keeps its last error), and that
/// error; None before any fold has taken a step.
fn cv_choice(folds: &[Path], limit: usize) -> Option<(usize, f64)> {
    let len = folds.iter().map(|p| p.hold_err.len()).max()?.min(limit);
    let mut best = None;
    for p in 1..=len {
        let mut s = 0.0;
        let mut w = 0.0;
        for fp in folds.iter().filter(|fp| !fp.hold_err.is_empty()) {
            let e = fp.hold_err[(p - 1).min(fp.hold_err.len() - 1)];
            s += e * fp.hold.len() as f64;
            w += fp.hold.len() as f64;
        }
        let e = s / w;
        if best.is_none_or(|(_, b)| e < b) {
            best = Some((p, e));
        }
    }
    best
}

/// Least squares on a fixed support through the normal equations (Cholesky), for the bootstrap.
fn lstsq_support(support: &[Vec<f64>], rows: &[usize], y: &[f64]) -> Option<Vec<f64>> {
    let p = support.len();
    let mut g = vec![0.0; p * p];
    let mut b = vec![0.0; p];
    let mut row = vec![0.0; p];
    for &i in rows {
        for (t, col) in support.iter().enumerate() {
            row[t] = col[i];
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
    let degrees: Vec<usize> = if params.adaptive_degree {
        (1..=params.degree).collect()
    } else {
        vec![params.degree]
    };
    let mut best: Vec<Option<(usize, Fit)>> = (0..m).map(|_| None).collect();
    let mut still: Vec<bool> = vec![true; m];
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
    // One fold partition for all outputs (drawn from the seed); rows are stored fold by fold.
    let (perm, segs) = fold_order(n, folds_of(params, n), params.seed);
    let by_loo = params.selection == Selection::CorrectedLoo;
    let mut inv = vec![0; n];
    for (pos, &r) in perm.iter().enumerate() {
        inv[r] = pos;
    }
    let xi: Vec<f64> = perm
        .iter()
        .flat_map(|&r| xi[r * k..(r + 1) * k].iter().copied())
        .collect();
    let ys: Vec<Vec<f64>> = ys
        .iter()
        .map(|yo| perm.iter().map(|&r| yo[r]).collect())
        .collect();
    for (di, &deg) in degrees.iter().enumerate() {
        let basis = multi_indices(k, deg, params.q_norm);
        n_candidates = basis.len();
        let design = Design::new(&xi, n, k, &germs, deg, &basis, segs.clone());
        // Squared column norms of every row variant (all rows; all but fold f), for all outputs.
        let col_norm2 = design.norms2();
        let cache = GramCache::new(&design);
        // Outputs OUTPUTS_PER_PRODUCT at a time: Ψ_vᵀy of every row variant in one product, then
        // their paths in parallel (memory stays bounded however many outputs there are; no value
        // depends on the grouping).
        let mut fits: Vec<Option<Fit>> = Vec::with_capacity(m);
        for chunk in ys.chunks(OUTPUTS_PER_PRODUCT) {
            let o0 = fits.len();
            // one output alone: its paths and products use the threads instead
            let parallel_inner = chunk.len() == 1;
            let y_refs: Vec<&[f64]> = chunk.iter().map(Vec::as_slice).collect();
            let mut c0: Vec<Vec<Vec<f64>>> = chunk.iter().map(|_| vec![]).collect();
            for variant in design.variant_products(&y_refs, true) {
                for (out, c) in c0.iter_mut().zip(variant) {
                    out.push(c);
                }
            }
            fits.par_extend(c0.into_par_iter().enumerate().map(|(i, c0)| {
                let o = o0 + i;
                still[o].then(|| {
                    omp_select(
                        &design,
                        &cache,
                        &col_norm2,
                        &ys[o],
                        c0,
                        params.max_terms,
                        by_loo,
                        DIRECT_AFTER,
                        parallel_inner,
                    )
                })
            }));
        }
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
        psis.push(design);
        if still.iter().all(|s| !s) {
            break;
        }
    }
    let outputs: Vec<PceOutput> = best
        .into_par_iter()
        .enumerate()
        .map(|(o, b)| {
            let (di, fit) = b.expect("at least one degree fitted");
            let basis = &psis[di].basis;
            let (mean, variance, first, total, interactions) = indices_from(k, basis, &fit.terms);
            let (mut first_ci, mut total_ci) = (vec![], vec![]);
            if params.n_bootstrap > 0 {
                let support: Vec<usize> = fit.terms.iter().map(|t| t.0).collect();
                let support_cols: Vec<Vec<f64>> =
                    support.iter().map(|&a| psis[di].col(a)).collect();
                let reps: Vec<(Vec<f64>, Vec<f64>)> = (0..params.n_bootstrap)
                    .filter_map(|rep| {
                        let mut rng =
                            stream(params.seed ^ 0xB0_0757 ^ (o as u64) << 24, rep as u64);
                        let rows: Vec<usize> =
                            (0..n).map(|_| inv[rng.random_range(0..n)]).collect();
                        let c = lstsq_support(&support_cols, &rows, &ys[o])?;
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
                selection_aware_error: fit.selection_aware,
                validation_error: None,
                warnings: vec![],
            }
            .assessed(params.selection)
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

/// Samples `params.n_samples` runs of `model` on `params.sampling` and fits a sparse PCE; with
/// [`PceParams::validation`], measures each output's error on that many fresh runs
/// ([`PceOutput::validation_error`]) and adds the warnings it calls for.
///
/// # Errors
/// As [`fit_pce`], plus [`Error::ModelOutput`] for non-finite model values and
/// [`Error::SampleSize`] for fewer than 2 validation runs.
pub fn build_pce<M: Model + ?Sized>(
    model: &M,
    problem: &Problem,
    params: &PceParams,
) -> Result<PceResult> {
    if let Some(v) = params.validation.filter(|v| v.n < 2) {
        return Err(Error::SampleSize {
            estimator: "PCE validation",
            n: v.n,
            min: 2,
        });
    }
    let (x, y) = sample_runs(
        model,
        problem,
        params.sampling,
        params.n_samples,
        params.seed,
    )?;
    let mut r = fit_pce(problem, &x, &y, model.n_outputs(), params)?;
    if let Some(v) = params.validation {
        let seed = v.seed.unwrap_or(params.seed ^ VALIDATION_SEED);
        let (xv, yv) = sample_runs(model, problem, Sampling::MonteCarlo, v.n, seed)?;
        let errors: Vec<f64> = (0..r.outputs.len())
            .into_par_iter()
            .map(|o| r.validation_error(problem, o, &xv, &yv))
            .collect();
        r.outputs = std::mem::take(&mut r.outputs)
            .into_iter()
            .zip(errors)
            .map(|(mut out, e)| {
                out.validation_error = Some(e);
                out.assessed(params.selection)
            })
            .collect();
    }
    Ok(r)
}

/// Mixed into the PCE seed for the validation runs' design by default.
const VALIDATION_SEED: u64 = 0x7A11_DA7E;

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
        let w = out.degree + 1;
        // ψ₀…ψ_p of every input, once
        let mut u = vec![0.0; xi.len() * w];
        for ((v, &g), ui) in xi.iter().zip(&self.germs).zip(u.chunks_exact_mut(w)) {
            univariate(g, *v, out.degree, ui);
        }
        out.terms
            .iter()
            .map(|(mi, c)| {
                c * mi
                    .iter()
                    .map(|&(v, d)| u[v as usize * w + d as usize])
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Ψ_vᵀb from the parent-by-parent products against the sums written out from the
    /// multi-indices, for mixed germs, a hyperbolic set and folds of unequal length; a value must
    /// not depend on the other right-hand sides of the product.
    #[test]
    fn implicit_products_match_the_written_out_design() {
        let (n, k, deg) = (53, 4, 4);
        let germs = [Germ::Normal, Germ::Uniform, Germ::Normal, Germ::Uniform];
        let xi: Vec<f64> = (0..n * k)
            .map(|i| ((i * 7919 % 211) as f64 / 105.0 - 1.0) * if i % 2 == 0 { 2.0 } else { 1.0 })
            .collect();
        let basis = multi_indices(k, deg, 0.75);
        let segs = vec![(0, 18), (18, 18), (36, 17)];
        let d = Design::new(&xi, n, k, &germs, deg, &basis, segs.clone());
        let basis = &d.basis;
        let b: Vec<Vec<f64>> = (0..5)
            .map(|c| {
                (0..n)
                    .map(|r| ((r * 31 + c * 17) % 13) as f64 - 6.0)
                    .collect()
            })
            .collect();
        let written = |j: usize, r: usize| {
            let mut uni = vec![0.0; deg + 1];
            basis[j].iter().fold(1.0, |acc, &(v, dg)| {
                univariate(germs[v as usize], xi[r * k + v as usize], deg, &mut uni);
                acc * uni[dg as usize]
            })
        };
        let refs: Vec<&[f64]> = b.iter().map(Vec::as_slice).collect();
        let all = d.variant_products(&refs, true);
        assert_eq!(all.len(), segs.len() + 1);
        for (v, variant) in all.iter().enumerate() {
            for (c, bc) in b.iter().enumerate() {
                for j in 0..basis.len() {
                    let rows = (0..n).filter(|&r| {
                        v == 0 || !(segs[v - 1].0..segs[v - 1].0 + segs[v - 1].1).contains(&r)
                    });
                    let want: f64 = rows.map(|r| written(j, r) * bc[r]).sum();
                    let got = variant[c][j];
                    assert!(
                        (got - want).abs() <= 1e-11 * (1.0 + want.abs()),
                        "v {v} c {c} {:?}: {got} vs {want}",
                        basis[j]
                    );
                }
            }
        }
        for j in 0..basis.len() {
            let col = d.col(j);
            for r in 0..n {
                assert!((col[r] - written(j, r)).abs() <= 1e-12 * (1.0 + col[r].abs()));
            }
        }
        // the same column alone, and among others in another position: bit-identical
        let alone = d.variant_products(&refs[3..4], false);
        let shuffled = d.variant_products(&[refs[1], refs[3], refs[0]], false);
        for v in 0..all.len() {
            assert_eq!(alone[v][0], all[v][3]);
            assert_eq!(shuffled[v][1], all[v][3]);
        }
    }

    /// The two ways a path updates its correlations — Gram column and U = Ψ_vᵀQ, or the direct
    /// product Ψ_vᵀq — choose the same terms and coefficients: corrected LOO without folds and
    /// with them (the selection-aware estimate), K-fold.
    #[test]
    fn direct_and_gram_updates_agree() {
        let (n, k, deg) = (120, 3, 3);
        let germs = [Germ::Normal; 3];
        let xi: Vec<f64> = (0..n * k)
            .map(|i| ((i * 7919 % 1009) as f64 / 1009.0 - 0.5) * 3.4)
            .collect();
        let y: Vec<f64> = xi
            .chunks(k)
            .map(|x| (1.3 * x[0]).sin() + 0.4 * x[1] * x[2] + 0.1 * (2.0 * x[2]).cos())
            .collect();
        let basis = multi_indices(k, deg, 1.0);
        let folds = vec![(0, 40), (40, 40), (80, 40)];
        for (segs, by_loo) in [(vec![(0, n)], true), (folds.clone(), true), (folds, false)] {
            let d = Design::new(&xi, n, k, &germs, deg, &basis, segs);
            let fit = |direct_after: usize| {
                let c0 = d
                    .variant_products(&[&y], false)
                    .into_iter()
                    .map(|mut v| v.swap_remove(0))
                    .collect();
                omp_select(
                    &d,
                    &GramCache::new(&d),
                    &d.norms2(),
                    &y,
                    c0,
                    Some(60),
                    by_loo,
                    direct_after,
                    false,
                )
            };
            let (gram, direct) = (fit(usize::MAX), fit(0));
            assert_eq!(gram.steps, direct.steps);
            assert_eq!(gram.terms.len(), direct.terms.len());
            // without folds there is no estimate beside corrected LOO
            let (a, b) = (gram.selection_aware, direct.selection_aware);
            if d.segs.len() > 1 {
                assert!(a.is_finite() && (a - b).abs() <= 1e-9 * a, "{a} vs {b}");
            } else {
                assert!(a.is_nan() && b.is_nan());
            }
            assert!(gram.terms.len() > 3);
            for (a, b) in gram.terms.iter().zip(&direct.terms) {
                assert_eq!(a.0, b.0);
                assert!(
                    (a.1 - b.1).abs() <= 1e-9 * (1.0 + a.1.abs()),
                    "{a:?} vs {b:?}"
                );
            }
        }
    }
}
