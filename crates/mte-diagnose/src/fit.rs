//! Weighted least squares over blocks of terms, blocked cross-validation, and the projection
//! that scores a candidate against the current model.

use std::borrow::Cow;

use mte_linalg::bridge::{as_faer, product};
use mte_linalg::nalgebra::{DMatrixView, Dyn, SymmetricEigen};
use mte_linalg::{DMat, DVec};

use crate::data::Observations;
use crate::term::Term;

/// A borrowed block of columns.
type DMatView<'a> = DMatrixView<'a, f64>;

/// Relative singular-value threshold below which a direction of the (column-normalised,
/// whitened) design counts as undetermined.
pub(crate) const RANK_TOLERANCE: f64 = 1e-9;

/// A candidate whose columns keep less than this fraction of their norm after projecting out the
/// current model is "not separable with this data" (|cos| of the angle above 0.9999).
pub(crate) const SEPARABILITY_TOLERANCE: f64 = 1e-2;

/// Whitening factors 1/σ (all 1 when the data state no σ).
pub(crate) fn whitening(obs: &Observations) -> DVec {
    match &obs.sigma {
        Some(s) => s.map(|s| 1.0 / s),
        None => DVec::from_element(obs.len(), 1.0),
    }
}

/// Columns of several terms side by side.
pub(crate) fn design(terms: &[&Term], n: usize) -> DMat {
    let p: usize = terms.iter().map(|t| t.width()).sum();
    let mut x = DMat::zeros(n, p);
    let mut c = 0;
    for t in terms {
        x.columns_mut(c, t.width()).copy_from(&t.columns);
        c += t.width();
    }
    x
}

/// A weighted least-squares solution.
#[derive(Debug, Clone)]
pub(crate) struct Solution {
    pub coef: DVec,
    /// `(XᵀWX)⁺`, the cofactor matrix of the coefficients.
    pub cofactor: DMat,
    pub rank: usize,
    /// Unweighted residuals `y − X b`, one per row of the fit.
    pub residuals: DVec,
    /// Weighted residual sum of squares.
    pub rss_w: f64,
    /// Observations that took part (weight above zero).
    pub observations: usize,
}

impl Solution {
    /// Degrees of freedom of the residuals.
    pub fn dof(&self) -> usize {
        self.observations.saturating_sub(self.rank)
    }
}

/// Solves `min ‖diag(w)(y − X b)‖` by QR of the column-normalised whitened design and an SVD of
/// its small triangular factor (the SVD gives the rank; undetermined directions get the
/// minimum-norm solution).
pub(crate) fn solve(x: &DMat, y: &DVec, w: &DVec) -> Solution {
    let (n, p) = x.shape();
    let observations = w.iter().filter(|w| **w > 0.0).count();
    if p == 0 {
        let rss_w = y.iter().zip(w.iter()).map(|(r, w)| (r * w).powi(2)).sum();
        return Solution {
            coef: DVec::zeros(0),
            cofactor: DMat::zeros(0, 0),
            rank: 0,
            residuals: y.clone(),
            rss_w,
            observations,
        };
    }
    let (r, qty, scale) = if n > p {
        whitened_r(x, y, w)
    } else {
        whitened(x, y, w)
    };
    let svd = r.svd(true, true);
    let (u, vt) = (svd.u.expect("requested"), svd.v_t.expect("requested"));
    let smax = svd.singular_values.max();
    let mut coef_s = DVec::zeros(p);
    let mut cof_s = DMat::zeros(p, p);
    let mut rank = 0;
    for k in 0..svd.singular_values.len() {
        let s = svd.singular_values[k];
        if s > RANK_TOLERANCE * smax && s > 0.0 {
            rank += 1;
            let v = vt.row(k).transpose();
            coef_s += &v * (u.column(k).dot(&qty) / s);
            cof_s += &v * v.transpose() / (s * s);
        }
    }
    let coef = coef_s.component_mul(&scale);
    let cofactor = DMat::from_fn(p, p, |i, j| cof_s[(i, j)] * scale[i] * scale[j]);
    let residuals = y - x * &coef;
    let rss_w = residuals
        .iter()
        .zip(w.iter())
        .map(|(r, w)| (r * w).powi(2))
        .sum();
    Solution {
        coef,
        cofactor,
        rank,
        residuals,
        rss_w,
        observations,
    }
}

/// The whitened, column-normalised design and observations as they are (fewer rows than
/// columns: nothing to triangularise), with the column scale factors.
fn whitened(x: &DMat, y: &DVec, w: &DVec) -> (DMat, DVec, DVec) {
    let (xw, scale) = whitened_columns(x.clone(), w);
    (xw, y.component_mul(w), scale)
}

/// `x` whitened (each row times its `w`) and its columns normalised, with the column scale
/// factors.
fn whitened_columns(mut x: DMat, w: &DVec) -> (DMat, DVec) {
    for mut column in x.column_iter_mut() {
        column.component_mul_assign(w);
    }
    let scale = reciprocal_norms(x.column_iter().map(|c| c.norm()));
    for (mut column, s) in x.column_iter_mut().zip(scale.iter()) {
        column.scale_mut(*s);
    }
    (x, scale)
}

/// The column scale factors of a design from its columns' norms (1 for a zero column).
fn reciprocal_norms(norms: impl ExactSizeIterator<Item = f64>) -> DVec {
    DVec::from_iterator(
        norms.len(),
        norms.map(|n| if n > 0.0 { 1.0 / n } else { 1.0 }),
    )
}

/// R and Qᵀy of the whitened, column-normalised design and observations, with the column
/// scale factors: the design is whitened row by row into the blocks of a streamed QR (faer's
/// blocked Householder) with the observations as a last column, so a long record is never
/// copied whole.
fn whitened_r(x: &DMat, y: &DVec, w: &DVec) -> (DMat, DVec, DVec) {
    let (n, p) = x.shape();
    let scale = reciprocal_norms((0..p).map(|j| {
        x.column(j)
            .iter()
            .zip(w.iter())
            .map(|(v, w)| (v * w).powi(2))
            .sum::<f64>()
            .sqrt()
    }));
    let ra = streamed_r(n, p + 1, &|start, len| {
        let mut block = DMat::zeros(len, p + 1);
        for j in 0..p {
            let (xj, s) = (x.column(j), scale[j]);
            for (i, b) in block.column_mut(j).iter_mut().enumerate() {
                *b = xj[start + i] * w[start + i] * s;
            }
        }
        for (i, b) in block.column_mut(p).iter_mut().enumerate() {
            *b = y[start + i] * w[start + i];
        }
        block
    });
    (
        ra.view((0, 0), (p, p)).into_owned(),
        ra.view((0, p), (p, 1)).column(0).into_owned(),
        scale,
    )
}

/// Rows per block of [`streamed_r`].
const QR_BLOCK: usize = 32_768;

/// The triangular factor R (m × m) of the thin QR of the n × m matrix (n ≥ m) whose rows
/// `start..start + len` `rows(start, len)` gives, in blocks of rows: R of the block stacked on
/// the previous blocks' R (the tall-skinny QR), so memory stays at a block whatever the length
/// of the record.
pub(crate) fn streamed_r(n: usize, m: usize, rows: &dyn Fn(usize, usize) -> DMat) -> DMat {
    let mut r: Option<DMat> = None;
    let mut start = 0;
    while start < n {
        let end = (start + QR_BLOCK).min(n);
        let top = r.as_ref().map_or(0, DMat::nrows);
        let mut block = DMat::zeros(top + end - start, m);
        if let Some(r) = &r {
            block.rows_mut(0, top).copy_from(r);
        }
        block
            .rows_mut(top, end - start)
            .copy_from(&rows(start, end - start));
        r = Some(if block.nrows() >= m {
            mte_linalg::lstsq::qr_r(&block)
        } else {
            block
        });
        start = end;
    }
    let r = r.unwrap_or_else(|| DMat::zeros(0, m));
    // Fewer rows than columns only when n < m, which the callers exclude.
    let mut full = DMat::zeros(m, m);
    full.rows_mut(0, r.nrows().min(m))
        .copy_from(&r.rows(0, r.nrows().min(m)));
    full
}

/// Rows of `m` selected by `rows`.
pub(crate) fn select_rows(m: &DMat, rows: &[usize]) -> DMat {
    DMat::from_fn(rows.len(), m.ncols(), |i, j| m[(rows[i], j)])
}

pub(crate) fn select(v: &DVec, rows: &[usize]) -> DVec {
    DVec::from_iterator(rows.len(), rows.iter().map(|&i| v[i]))
}

/// Blocked K-fold cross-validation: the acquisition order of the included observations is cut
/// into contiguous blocks and every K-th block (counted from a different start in each set-up)
/// is held out together, so a fold never sees the neighbours of its test points within a block.
#[derive(Debug, Clone)]
pub(crate) struct Folds {
    pub test: Vec<Vec<usize>>,
    pub train: Vec<Vec<usize>>,
}

impl Folds {
    /// `k` folds of blocks of about `n / (k · blocks_per_fold)` of the observations marked in
    /// `include`; the others take part in no fold.
    pub fn blocked(
        obs: &Observations,
        include: &[bool],
        k: usize,
        blocks_per_fold: usize,
    ) -> Folds {
        let order: Vec<usize> = obs
            .acquisition_order()
            .into_iter()
            .filter(|&i| include[i])
            .collect();
        let n = order.len();
        let n_blocks = (k * blocks_per_fold).min(n).max(k);
        let mut test = vec![Vec::new(); k];
        // Each set-up's blocks start at a different fold: when the set-ups repeat one programme
        // (runs over the same targets), the fold would otherwise hold the same stretch of the
        // programme in every set-up, and no other fold would ever see those poses.
        for (pos, &i) in order.iter().enumerate() {
            let block = pos * n_blocks / n;
            test[(block + obs.setup[i]) % k].push(i);
        }
        let train = test
            .iter()
            .map(|t| {
                let mut held = vec![false; include.len()];
                t.iter().for_each(|&i| held[i] = true);
                (0..include.len())
                    .filter(|&i| include[i] && !held[i])
                    .collect()
            })
            .collect();
        Folds { test, train }
    }

    /// RMS of out-of-fold residuals over the observations the folds hold out.
    pub fn rms(&self, cv: &DVec) -> f64 {
        let (sum, count) = self
            .test
            .iter()
            .flatten()
            .fold((0.0, 0usize), |(s, c), &i| (s + cv[i] * cv[i], c + 1));
        if count == 0 {
            0.0
        } else {
            (sum / count as f64).sqrt()
        }
    }

    /// Out-of-fold prediction residuals (mm) of the model with design `x`, one per observation
    /// (zero for observations in no fold).
    pub fn residuals(&self, x: &DMat, y: &DVec, w: &DVec) -> DVec {
        let mut out = DVec::zeros(y.len());
        for (train, test) in self.train.iter().zip(&self.test) {
            let sol = solve(&select_rows(x, train), &select(y, train), &select(w, train));
            for &i in test {
                out[i] = y[i] - x.row(i).dot(&sol.coef.transpose());
            }
        }
        out
    }
}

/// The folds' fits of one model, kept to score candidates added to it: per fold an orthonormal
/// basis of the whitened, column-normalised training design (the directions [`solve`] keeps,
/// same tolerance) and the map from it to the coefficients. A candidate's out-of-fold residuals
/// then cost products with the basis, not a fresh factorisation per fold.
pub(crate) struct FoldFits<'a> {
    folds: &'a Folds,
    x: &'a DMat,
    y: &'a DVec,
    w: &'a DVec,
    fits: Vec<FoldFit>,
}

struct FoldFit {
    /// Orthonormal basis of the whitened training design (training rows × rank).
    q: DMat,
    /// Coefficients from basis coordinates: `x_train · diag(w) · map = q`.
    map: DMat,
    /// `qᵀ · (whitened training observations)`.
    qty: DVec,
    /// Whitened training residuals of the model.
    residuals: DVec,
}

impl<'a> FoldFits<'a> {
    /// Fits the model with design `x` on every fold's training rows.
    pub fn new(folds: &'a Folds, x: &'a DMat, y: &'a DVec, w: &'a DVec) -> FoldFits<'a> {
        let fits = folds
            .train
            .iter()
            .map(|train| {
                let wt = select(w, train);
                let (xw, scale) = whitened_columns(select_rows(x, train), &wt);
                let (q, map) = orthonormal_basis_and_map(&xw);
                let map = DMat::from_fn(map.nrows(), map.ncols(), |i, j| map[(i, j)] * scale[i]);
                let yw = select(y, train).component_mul(&wt);
                let qty = q.tr_mul(&yw);
                let residuals = &yw - &q * &qty;
                FoldFit {
                    q,
                    map,
                    qty,
                    residuals,
                }
            })
            .collect();
        FoldFits {
            folds,
            x,
            y,
            w,
            fits,
        }
    }

    /// RMS of the out-of-fold residuals of the model.
    pub fn rms(&self) -> f64 {
        self.rms_with(&DMat::zeros(self.x.nrows(), 0))
    }

    /// RMS of the out-of-fold residuals of the model with the columns `c` added (the same as
    /// [`Folds::residuals`] of the wider design, up to rounding).
    pub fn rms_with(&self, c: &DMat) -> f64 {
        let mut out = DVec::zeros(self.y.len());
        for (fit, (train, test)) in self
            .fits
            .iter()
            .zip(self.folds.train.iter().zip(&self.folds.test))
        {
            let k = c.ncols();
            let mut gamma = DVec::zeros(k);
            let mut coef_q = fit.qty.clone();
            if k > 0 {
                let (cw, norms) = whitened_columns(select_rows(c, train), &select(self.w, train));
                let a = tr_mul(&fit.q, &cw);
                let perp = &cw - &fit.q * &a;
                let b = perp.tr_mul(&fit.residuals);
                for (l, v) in new_directions(&perp.tr_mul(&perp).symmetric_eigen()) {
                    gamma += &v * (v.dot(&b) / l);
                }
                coef_q -= &a * &gamma;
                gamma.component_mul_assign(&norms);
            }
            let beta = &fit.map * &coef_q;
            for &i in test {
                let mut pred = self.x.row(i).dot(&beta.transpose());
                if k > 0 {
                    pred += c.row(i).dot(&gamma.transpose());
                }
                out[i] = self.y[i] - pred;
            }
        }
        self.folds.rms(&out)
    }
}

/// Splits the nonzero columns of `c` into those that keep at least [`SEPARABILITY_TOLERANCE`]
/// of their whitened (by `w`) norm once the span of the orthonormal `q` and the directions in
/// `kept` are projected out (twice, for rounding) — their directions are appended to `kept` —
/// and those that do not: `(separable, not separable)` column indices.
pub(crate) fn separable_columns(
    c: &DMat,
    w: &DVec,
    q: Option<&DMat>,
    kept: &mut Vec<DVec>,
) -> (Vec<usize>, Vec<usize>) {
    let (mut separable, mut not) = (Vec::new(), Vec::new());
    for (j, column) in c.column_iter().enumerate() {
        let cw = column.component_mul(w);
        let norm = cw.norm();
        if norm == 0.0 {
            continue;
        }
        let mut r = cw / norm;
        for _ in 0..2 {
            if let Some(q) = q {
                r -= q * q.tr_mul(&r);
            }
            for e in kept.iter() {
                r.axpy(-e.dot(&r), e, 1.0);
            }
        }
        let left = r.norm();
        if left >= SEPARABILITY_TOLERANCE {
            kept.push(r / left);
            separable.push(j);
        } else {
            not.push(j);
        }
    }
    (separable, not)
}

/// Root mean square of a vector.
pub(crate) fn rms(v: &DVec) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        (v.norm_squared() / v.len() as f64).sqrt()
    }
}

/// Largest absolute entry.
pub(crate) fn max_abs(v: &DVec) -> f64 {
    v.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
}

/// An orthonormal basis of the whitened current model and its residuals, to project candidates
/// against.
#[derive(Clone)]
pub(crate) struct Projector {
    q: DMat,
    w: DVec,
    /// Whitened residuals and their components along the basis.
    rw: DVec,
    qtr: DVec,
}

/// What a candidate adds beyond the current model.
#[derive(Debug, Clone)]
pub(crate) struct Increment {
    /// Reduction of the weighted RSS if the candidate were added.
    pub delta_rss: f64,
    /// Number of new independent directions the candidate brings.
    pub new_rank: usize,
    /// Smallest fraction of a (normalised) candidate direction left after projecting out the
    /// current model: near 0 means the candidate is a combination of existing terms.
    pub separability: f64,
}

/// `aᵀ b`, the inner loop of every scan, by faer's blocked, vectorised product.
fn tr_mul(a: &DMat, b: &DMat) -> DMat {
    product(as_faer(a).transpose(), as_faer(b))
}

impl Projector {
    /// The model with design `x`, weights `w` and residuals `r`.
    pub fn new(x: &DMat, w: &DVec, r: &DVec) -> Projector {
        let mut xw = x.clone();
        for (i, wi) in w.iter().enumerate() {
            xw.row_mut(i).scale_mut(*wi);
        }
        let q = orthonormal_basis(&xw);
        let rw = r.component_mul(w);
        let qtr = if q.ncols() > 0 {
            q.tr_mul(&rw)
        } else {
            DVec::zeros(0)
        };
        Projector {
            q,
            w: w.clone(),
            rw,
            qtr,
        }
    }

    /// The projector for candidates that are zero outside `rows` (distinct, e.g. one channel's
    /// observations), given on those rows only: the same increments as the full candidate's,
    /// without the zeros. Every row: the projector itself (no copy of a long record's basis).
    pub fn on_rows(&self, rows: &[usize]) -> Cow<'_, Projector> {
        if rows.len() == self.w.len() {
            return Cow::Borrowed(self);
        }
        Cow::Owned(Projector {
            q: select_rows(&self.q, rows),
            w: select(&self.w, rows),
            rw: select(&self.rw, rows),
            // Qᵀr stays the whole residual's: it meets Qᵀc, which only the rows make.
            qtr: self.qtr.clone(),
        })
    }

    /// The columns of `c` that keep at least [`SEPARABILITY_TOLERANCE`] of their whitened norm
    /// once the model and the columns kept before them are projected out: what a block of
    /// columns adds to the model, by the rule the diagnosis applies to its base.
    pub fn separable_columns(&self, c: &DMat) -> Vec<usize> {
        let q = (self.q.ncols() > 0).then_some(&self.q);
        separable_columns(c, &self.w, q, &mut Vec::new()).0
    }

    /// Whitened `c` with the current model projected out.
    pub fn residual_part(&self, c: &DMat) -> DMat {
        let mut cw = c.clone();
        for mut column in cw.column_iter_mut() {
            column.component_mul_assign(&self.w);
        }
        if self.q.ncols() > 0 {
            let coef = tr_mul(&self.q, &cw);
            cw -= &self.q * coef;
        }
        cw
    }

    /// How much the candidate `c` would reduce the weighted RSS of the residuals.
    ///
    /// Works on the k × k Gram matrix of the candidate's whitened columns with the model
    /// projected out, `G = CᵀC − (QᵀC)ᵀ(QᵀC)`, normalised by the columns' norms: its smallest
    /// eigenvalue is the squared separability, and the RSS falls by `bᵀ G⁺ b` with
    /// `b = Cᵀr − (QᵀC)ᵀ(Qᵀr)`. No n × k matrix beyond the whitened columns is formed.
    pub fn increment(&self, c: &DMat) -> Increment {
        self.increments(1, |_| Cow::Borrowed(c))
            .pop()
            .expect("one candidate")
    }

    /// [`Projector::increment`] of `count` candidates whose columns `candidate(i)` gives: their
    /// whitened columns go through one product with the model's basis per batch of about
    /// [`BATCH_COLUMNS`], not one each — a scan over a grid of periods reads the basis once per
    /// batch instead of once per period. The columns are built one batch at a time.
    pub fn increments<'a>(
        &self,
        count: usize,
        candidate: impl Fn(usize) -> Cow<'a, DMat>,
    ) -> Vec<Increment> {
        let n = self.w.len();
        let batch_columns = (BATCH_VALUES / n.max(1)).clamp(1, BATCH_COLUMNS);
        let mut out = Vec::with_capacity(count);
        let mut next = 0;
        while next < count {
            let mut batch = Vec::new();
            let mut width = 0;
            while next < count && (batch.is_empty() || width < batch_columns) {
                let c = candidate(next);
                width += c.ncols();
                batch.push(c);
                next += 1;
            }
            let mut cw = DMat::zeros(n, width);
            let mut at = 0;
            for c in &batch {
                cw.columns_mut(at, c.ncols()).copy_from(c.as_ref());
                at += c.ncols();
            }
            for mut column in cw.column_iter_mut() {
                column.component_mul_assign(&self.w);
            }
            let a = (self.q.ncols() > 0).then(|| tr_mul(&self.q, &cw));
            let mut at = 0;
            for c in &batch {
                let k = c.ncols();
                let ak = a.as_ref().map(|a| a.columns(at, k));
                out.push(self.increment_of(cw.columns(at, k), ak));
                at += k;
            }
        }
        out
    }

    /// The increment of whitened candidate columns `cw` with `a = Qᵀ cw` (`None`: no model).
    fn increment_of(&self, cw: DMatView<'_>, a: Option<DMatView<'_>>) -> Increment {
        let k = cw.ncols();
        let none = Increment {
            delta_rss: 0.0,
            new_rank: 0,
            separability: 0.0,
        };
        if k == 0 {
            return none;
        }
        let norms: Vec<f64> = cw.column_iter().map(|c| c.norm()).collect();
        if norms.iter().any(|n| n.is_nan() || *n <= 0.0) {
            return none;
        }
        let mut g = cw.tr_mul(&cw);
        let mut b = cw.tr_mul(&self.rw);
        if let Some(a) = a {
            g -= a.tr_mul(&a);
            b -= a.tr_mul(&self.qtr);
        }
        for i in 0..k {
            b[i] /= norms[i];
            for j in 0..k {
                g[(i, j)] /= norms[i] * norms[j];
            }
        }
        let eig = g.symmetric_eigen();
        let lambda_min = eig.eigenvalues.min().max(0.0);
        let directions = new_directions(&eig);
        Increment {
            delta_rss: directions
                .iter()
                .fold(0.0, |d, (l, v)| d + v.dot(&b).powi(2) / l),
            new_rank: directions.len(),
            separability: lambda_min.sqrt(),
        }
    }
}

/// The eigenpairs `(λ, v)` of the normalised Gram matrix of a candidate's columns with the
/// model projected out that are new directions: those with less than 1e-6 of their norm left
/// are rounding (the Gram difference cancels to about 1e-16).
fn new_directions(eig: &SymmetricEigen<f64, Dyn>) -> Vec<(f64, DVec)> {
    let lambda_max = eig.eigenvalues.max().max(0.0);
    eig.eigenvalues
        .iter()
        .enumerate()
        .filter(|&(_, &l)| l > 1e-12 && l > 1e-12 * lambda_max)
        .map(|(i, &l)| (l, eig.eigenvectors.column(i).into_owned()))
        .collect()
}

/// Candidate columns per product with the model's basis in [`Projector::increments`]: wide
/// enough that reading the basis is paid once for many candidates.
const BATCH_COLUMNS: usize = 128;

/// Values (rows × columns) of a batch at most, so a long record's batch stays at 32 MB.
const BATCH_VALUES: usize = 4_000_000;

/// Orthonormal basis of the column space of `a` (relative tolerance). For a tall `a`: the
/// streamed QR's `R = U S Vᵀ` gives the left singular vectors as `a V S⁻¹` (restricted to the
/// kept directions), orthogonalised once more by a second streamed QR — memory stays at two
/// copies of `a` on a long record, and the work is faer's blocked QR and products, not an SVD
/// of `a` (which costs many times more); a wide `a` from its SVD.
pub(crate) fn orthonormal_basis(a: &DMat) -> DMat {
    orthonormal_basis_and_map(a).0
}

/// [`orthonormal_basis`] `q` of `a` and the map `m` with `a · m = q` (p × rank): the
/// coordinates in `q` of a least-squares fit give its minimum-norm coefficients through `m`.
fn orthonormal_basis_and_map(a: &DMat) -> (DMat, DMat) {
    let (n, p) = a.shape();
    if p == 0 {
        return (DMat::zeros(n, 0), DMat::zeros(0, 0));
    }
    if n < p {
        let svd = a.clone().svd(true, true);
        let smax = svd.singular_values.max();
        let (u, vt) = (svd.u.expect("requested"), svd.v_t.expect("requested"));
        let keep: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&k| svd.singular_values[k] > RANK_TOLERANCE * smax && smax > 0.0)
            .collect();
        let q = DMat::from_fn(n, keep.len(), |i, j| u[(i, keep[j])]);
        let map = DMat::from_fn(p, keep.len(), |i, j| {
            vt[(keep[j], i)] / svd.singular_values[keep[j]]
        });
        return (q, map);
    }
    let r = streamed_r(n, p, &|start, len| a.rows(start, len).into_owned());
    let svd = r.svd(false, true);
    let vt = svd.v_t.expect("requested");
    let smax = svd.singular_values.max();
    let keep: Vec<usize> = (0..svd.singular_values.len())
        .filter(|&k| svd.singular_values[k] > RANK_TOLERANCE * smax && smax > 0.0)
        .collect();
    let k = keep.len();
    let map = DMat::from_fn(p, k, |i, j| vt[(keep[j], i)] / svd.singular_values[keep[j]]);
    let q1 = product(as_faer(a), as_faer(&map));
    // A second pass removes the loss of orthogonality of the first (ε · condition number).
    let r2 = streamed_r(n, k, &|start, len| q1.rows(start, len).into_owned());
    let Some(inv) = r2.try_inverse().filter(|m| m.iter().all(|v| v.is_finite())) else {
        return (q1, map);
    };
    // Q = Q₁ R₂⁻¹, a block of rows at a time in place (memory stays at Q₁).
    let mut q = q1;
    let mut start = 0;
    while start < n {
        let len = (n - start).min(4096);
        let block = q.rows(start, len).into_owned();
        q.rows_mut(start, len)
            .copy_from(&product(as_faer(&block), as_faer(&inv)));
        start += len;
    }
    (q, &map * &inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth, deterministic design of `n` rows: a constant, Legendre-like powers and a sine,
    /// with one column a combination of two others (rank deficient).
    fn problem(n: usize) -> (DMat, DVec, DVec) {
        let u = |i: usize| 2.0 * i as f64 / (n - 1) as f64 - 1.0;
        let x = DMat::from_fn(n, 6, |i, j| match j {
            0 => 1.0,
            1 => u(i),
            2 => u(i).powi(2),
            3 => (7.3 * u(i)).sin(),
            4 => 2.0 * u(i) - 3.0 * u(i).powi(2),
            _ => (i % 7) as f64,
        });
        let y = DVec::from_fn(n, |i, _| {
            0.3 + u(i) - 0.2 * (7.3 * u(i)).sin() + 1e-3 * ((i * 7919) % 13) as f64
        });
        let w = DVec::from_fn(n, |i, _| 1.0 + (i % 3) as f64);
        (x, y, w)
    }

    #[test]
    fn streamed_qr_matches_the_householder_qr() {
        let n = 3 * QR_BLOCK + 17;
        let (x, y, w) = problem(n);
        // The reference: nalgebra's Householder QR of the whole whitened design.
        let (xw, yw, _) = whitened(&x, &y, &w);
        let qr = xw.qr();
        let r1 = qr.r();
        let mut qty1 = yw;
        qr.q_tr_mul(&mut qty1);
        qty1.resize_vertically_mut(x.ncols(), 0.0);
        let (r2, qty2, _) = whitened_r(&x, &y, &w);
        // RᵀR = AᵀA and Rᵀ(Qᵀy) = Aᵀy whatever the signs (and, with a dependent column, the
        // undetermined trailing rows) of R.
        let (g1, g2) = (r1.tr_mul(&r1), r2.tr_mul(&r2));
        assert!((&g1 - &g2).norm() < 1e-12 * g1.norm());
        let (b1, b2) = (r1.tr_mul(&qty1), r2.tr_mul(&qty2));
        assert!((&b1 - &b2).norm() < 1e-12 * b1.norm());
    }

    #[test]
    fn fold_fits_score_an_added_candidate_as_a_fresh_fit_does() {
        let n = 400;
        let (x, y, w) = problem(n);
        // Observations whose acquisition order is their row order, one set-up.
        let folds = Folds {
            test: (0..5)
                .map(|f| (0..n).filter(|i| (i / 20) % 5 == f).collect())
                .collect(),
            train: (0..5)
                .map(|f| (0..n).filter(|i| (i / 20) % 5 != f).collect())
                .collect(),
        };
        let base = x.columns(0, 3).into_owned();
        let fits = FoldFits::new(&folds, &base, &y, &w);
        let fresh = |x: &DMat| folds.rms(&folds.residuals(x, &y, &w));
        assert!((fits.rms() - fresh(&base)).abs() < 1e-10 * fresh(&base));
        // A new direction (the sine), and one already in the model (a combination of columns
        // 1 and 2), which must change nothing.
        for added in [x.columns(3, 1).into_owned(), x.columns(4, 1).into_owned()] {
            let wide = DMat::from_fn(
                n,
                4,
                |i, j| if j < 3 { base[(i, j)] } else { added[(i, 0)] },
            );
            let (a, b) = (fits.rms_with(&added), fresh(&wide));
            assert!((a - b).abs() < 1e-9 * b, "{a} vs {b}");
        }
    }

    #[test]
    fn long_record_basis_is_orthonormal_and_spans_the_design() {
        let n = 2 * QR_BLOCK + 5;
        let (x, _, _) = problem(n);
        let q = orthonormal_basis(&x);
        assert_eq!(q.ncols(), 5, "one column is a combination of two others");
        let gram = q.tr_mul(&q);
        assert!((gram - DMat::identity(5, 5)).norm() < 1e-12);
        // Every column of the design lies in the span.
        let rest = &x - &q * q.tr_mul(&x);
        assert!(rest.norm() / x.norm() < 1e-10);
    }
}
