//! Weighted least squares over blocks of terms, blocked cross-validation, and the projection
//! that scores a candidate against the current model.

use std::borrow::Cow;

use mte_linalg::bridge::{as_faer, gram, product};
use mte_linalg::nalgebra::{DMatrixView, Dyn, SymmetricEigen};
use mte_linalg::{DMat, DVec};

use crate::basis::Spread;
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
    let mut data = Vec::with_capacity(n * p);
    for t in terms {
        assert_eq!(
            t.columns.nrows(),
            n,
            "{}: {} rows, not {n}",
            t.name,
            t.columns.nrows()
        );
        data.extend_from_slice(t.columns.as_slice());
    }
    DMat::from_vec(n, p, data)
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
        let rss_w = weighted_rss(y, w);
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
    let rss_w = weighted_rss(&residuals, w);
    Solution {
        coef,
        cofactor,
        rank,
        residuals,
        rss_w,
        observations,
    }
}

/// Weighted residual sum of squares `Σ (wᵢ rᵢ)²`.
fn weighted_rss(residuals: &DVec, w: &DVec) -> f64 {
    residuals
        .iter()
        .zip(w.iter())
        .map(|(r, w)| (r * w).powi(2))
        .sum()
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
pub(crate) fn whitened_r(x: &DMat, y: &DVec, w: &DVec) -> (DMat, DVec, DVec) {
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
    let mut data = Vec::with_capacity(rows.len() * m.ncols());
    gather_rows(m, rows, &mut data);
    DMat::from_vec(rows.len(), m.ncols(), data)
}

/// Appends the rows `rows` of `m`, column by column (column-major), to `data`.
fn gather_rows(m: &DMat, rows: &[usize], data: &mut Vec<f64>) {
    gather_rows_from(m, 0, rows, data);
}

/// [`gather_rows`] of the columns of `m` from `first` on.
fn gather_rows_from(m: &DMat, first: usize, rows: &[usize], data: &mut Vec<f64>) {
    if m.nrows() == 0 {
        return;
    }
    for column in m.as_slice()[first * m.nrows()..].chunks_exact(m.nrows()) {
        data.extend(rows.iter().map(|&i| column[i]));
    }
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
}

impl Folds {
    /// `k` folds of blocks of about `n / (k · blocks_per_fold)` of the observations marked in
    /// `include`; the others take part in no fold. A fold's training rows are every
    /// observation of nonzero weight outside it: the fits give the observations outside
    /// `include` zero weight.
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
        Folds { test }
    }

    /// `k` folds of the distinct `positions` (an axis' coordinate of each observation) of the
    /// observations marked in `include`, interleaved by rank: fold `j` holds every observation
    /// at the `j`-th, `(j + k)`-th … position along the axis, so each held-out position has
    /// training positions on both sides.
    pub fn by_position(positions: &[f64], include: &[bool], k: usize) -> Folds {
        let k = k.max(1);
        let mut test = vec![Vec::new(); k];
        for (i, rank) in position_ranks(positions, include).into_iter().enumerate() {
            if let Some(rank) = rank {
                test[rank % k].push(i);
            }
        }
        Folds { test }
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
}

/// The rank of each observation's position among the distinct `positions` of the observations
/// marked in `include` (`None` for the others).
pub(crate) fn position_ranks(positions: &[f64], include: &[bool]) -> Vec<Option<usize>> {
    let kept: Vec<f64> = positions
        .iter()
        .zip(include)
        .filter_map(|(&p, &keep)| keep.then_some(p))
        .collect();
    let distinct = crate::basis::distinct_sorted(&kept);
    positions
        .iter()
        .zip(include)
        .map(|(&p, &keep)| keep.then(|| distinct.partition_point(|&d| d < p - 1e-9)))
        .collect()
}

/// The least-squares fit of `r` by the columns `c` on the rows `rows` alone (both whitened):
/// the fall of the residual sum of squares over those rows and the coefficients (zero when the
/// rows do not determine them).
pub(crate) fn fit_on_rows(c: &DMat, r: &DVec, rows: &[usize]) -> (f64, DVec) {
    let k = c.ncols();
    let (mut g, mut b) = (DMat::zeros(k, k), DVec::zeros(k));
    for &i in rows {
        let row = c.row(i).transpose();
        g.ger(1.0, &row, &row, 1.0);
        b.axpy(r[i], &row, 1.0);
    }
    match mte_linalg::lstsq::spd_inverse(&g) {
        Some(inv) => {
            let beta = inv * &b;
            (b.dot(&beta), beta)
        }
        None => (0.0, DVec::zeros(k)),
    }
}

/// The folds' fits of one model, kept to score candidates added to it. One orthonormal basis
/// `Q` of the whitened, column-normalised design on all observations serves every fold: a
/// fold's training fit has coordinates `a = M⁺ (Qᵀy − Q_Tᵀ y_T)` in it, `M = I − Q_TᵀQ_T` the
/// training rows' Gram (`T` the fold's test rows, whitened `y`), so a fold costs `|T| · rank²`
/// instead of a factorisation of its training design; directions the training rows do not
/// determine (an eigenvalue of `M` below [`FOLD_TOLERANCE`]) get the minimum-norm solution, as
/// in [`solve`]. A candidate's out-of-fold residuals then cost its projection on the basis and
/// a small block elimination per fold.
pub(crate) struct FoldFits<'a> {
    folds: &'a Folds,
    x: &'a DMat,
    y: &'a DVec,
    w: &'a DVec,
    /// Orthonormal basis of the whitened design (n × rank) and the map with `(W X) map = q`.
    q: Cow<'a, DMat>,
    map: Cow<'a, DMat>,
    fits: Vec<FoldFit>,
}

struct FoldFit {
    /// The basis on the fold's test rows, `Q_T`.
    qt: DMat,
    /// `M⁺`, `M = I − Q_TᵀQ_T`.
    m_pinv: DMat,
    /// `Qᵀ W y − Q_Tᵀ (W y)_T`: the training rows' share of `Qᵀ W y`.
    g: DVec,
}

/// Eigenvalue of a fold's training Gram `M` (in units of the whole data's, which is 1) below
/// which its direction counts as undetermined by the training rows.
const FOLD_TOLERANCE: f64 = 1e-10;

/// `M⁺` of a symmetric positive semi-definite `m`, dropping eigenvalues below
/// [`FOLD_TOLERANCE`] × its largest (and never above 1).
fn pinv_psd(m: DMat) -> DMat {
    let k = m.nrows();
    if k == 0 {
        return m;
    }
    // Well determined: the inverse by Cholesky (a tenth of the eigen route's work), kept when
    // its ∞-norm, which bounds 1/λ_min, shows every eigenvalue above 1e-6 × the largest
    // diagonal — far from the tolerance, where the two routes agree to rounding.
    let top_diag = m.diagonal().max();
    if let Some(inv) = mte_linalg::lstsq::spd_inverse(&m) {
        let norm = inv
            .row_iter()
            .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        if norm.is_finite() && norm * 1e-6 * top_diag < 1.0 {
            return inv;
        }
    }
    let eig = m.symmetric_eigen();
    let top = eig.eigenvalues.max().max(1.0);
    // V diag(1/λ) Vᵀ over the kept eigenvalues, as one product.
    let mut scaled = eig.eigenvectors.clone();
    for (mut column, l) in scaled.column_iter_mut().zip(eig.eigenvalues.iter()) {
        let f = if *l > FOLD_TOLERANCE * top {
            1.0 / l
        } else {
            0.0
        };
        column.scale_mut(f);
    }
    product(as_faer(&scaled), as_faer(&eig.eigenvectors).transpose())
}

/// The first directions of a model's basis on each fold's test rows, `Q₀_T`, and their Gram
/// there: what the fold fits of every model extending it share ([`Projector::fold_fits`]),
/// formed once for a search instead of at each of its steps.
pub(crate) struct FoldBasis {
    rank: usize,
    /// Per fold, `Q₀_T` and `Q₀_TᵀQ₀_T`.
    folds: Vec<(DMat, DMat)>,
}

/// The rows `rows` of a basis `q` and their Gram.
fn rows_and_gram(q: &DMat, rows: &[usize]) -> (DMat, DMat) {
    let qt = select_rows(q, rows);
    let g = gram(as_faer(&qt));
    (qt, g)
}

impl<'a> FoldFits<'a> {
    /// The folds' fits of the model with design `x` from the basis `q` of its whitened design
    /// and the map with `(W X) map = q` ([`Projector::fold_fits`]); `shared`: the first
    /// directions of `q` on the folds' test rows, where known.
    fn with_basis(
        folds: &'a Folds,
        x: &'a DMat,
        y: &'a DVec,
        w: &'a DVec,
        q: Cow<'a, DMat>,
        map: Cow<'a, DMat>,
        shared: Option<&FoldBasis>,
    ) -> FoldFits<'a> {
        let yw = y.component_mul(w);
        let qty = q.tr_mul(&yw);
        let r = q.ncols();
        let shared = shared.filter(|s| s.rank <= r && s.folds.len() == folds.test.len());
        let fits = folds
            .test
            .iter()
            .enumerate()
            .map(|(f, test)| {
                let (qt, gram_t) = match shared {
                    // [Q₀_T, Q₁_T] and its Gram from Q₀_T's: only the directions beyond are
                    // gathered and multiplied.
                    Some(shared) => {
                        let (q0t, g0) = &shared.folds[f];
                        let r0 = shared.rank;
                        let mut data = Vec::with_capacity(test.len() * r);
                        data.extend_from_slice(q0t.as_slice());
                        gather_rows_from(&q, r0, test, &mut data);
                        let qt = DMat::from_vec(test.len(), r, data);
                        let q1t = qt.columns(r0, r - r0).into_owned();
                        let cross = tr_mul(q0t, &q1t);
                        let mut g = DMat::zeros(r, r);
                        g.view_mut((0, 0), (r0, r0)).copy_from(g0);
                        g.view_mut((0, r0), (r0, r - r0)).copy_from(&cross);
                        g.view_mut((r0, 0), (r - r0, r0))
                            .copy_from(&cross.transpose());
                        g.view_mut((r0, r0), (r - r0, r - r0))
                            .copy_from(&gram(as_faer(&q1t)));
                        (qt, g)
                    }
                    None => rows_and_gram(&q, test),
                };
                let m = DMat::identity(r, r) - gram_t;
                let g = &qty - qt.tr_mul(&select(&yw, test));
                FoldFit {
                    qt,
                    m_pinv: pinv_psd(m),
                    g,
                }
            })
            .collect();
        FoldFits {
            folds,
            x,
            y,
            w,
            q,
            map,
            fits,
        }
    }

    /// Out-of-fold residuals of the model (mm), one per observation (zero for observations in
    /// no fold).
    pub fn residuals(&self) -> DVec {
        self.residuals_with(&DMat::zeros(self.x.nrows(), 0))
    }

    /// RMS of the out-of-fold residuals of the model.
    pub fn rms(&self) -> f64 {
        self.folds.rms(&self.residuals())
    }

    /// RMS of the out-of-fold residuals of the model with the columns `c` added (the same as
    /// [`Folds::residuals`] of the wider design, up to rounding).
    pub fn rms_with(&self, c: &DMat) -> f64 {
        self.folds.rms(&self.residuals_with(c))
    }

    /// Out-of-fold residuals of the model with the columns `c` added.
    fn residuals_with(&self, c: &DMat) -> DVec {
        let n = self.x.nrows();
        // The candidate's new directions q_c = [X, c] · [−map a_c vc; scale_c ⊙ vc].
        let (cw, scale_c) = whitened_columns(c.clone(), self.w);
        let Beyond {
            a: a_c,
            v: vc,
            q: qc,
        } = beyond(&self.q, cw);
        let k = qc.ncols();
        let yw = self.y.component_mul(self.w);
        let h_all = qc.tr_mul(&yw);
        let avc = &a_c * &vc;
        let mut out = DVec::zeros(n);
        for (fit, test) in self.fits.iter().zip(&self.folds.test) {
            // Training coordinates [u; v] in [Q, q_c]: the block system
            // [M, B; Bᵀ, D] [u; v] = [g; h], B = −Q_Tᵀ q_cT, D = I − q_cTᵀ q_cT, by the Schur
            // complement of M.
            let qct = select_rows(&qc, test);
            let (u, v) = if k == 0 {
                (&fit.m_pinv * &fit.g, DVec::zeros(0))
            } else {
                let b = -fit.qt.tr_mul(&qct);
                let d = DMat::identity(k, k) - qct.tr_mul(&qct);
                let h = &h_all - qct.tr_mul(&select(&yw, test));
                let mb = &fit.m_pinv * &b;
                let schur = d - b.tr_mul(&mb);
                let v = pinv_psd(schur) * (h - mb.tr_mul(&fit.g));
                let u = &fit.m_pinv * (&fit.g - &b * &v);
                (u, v)
            };
            // The training fit's whitened values on the test rows are its coordinates in
            // [Q, q_c] there, `Q_T u + q_cT v`; on a row of weight zero (no fold tests one),
            // its design row times the coefficients.
            let mut fitted = &fit.qt * &u;
            if k > 0 {
                fitted += &qct * &v;
            }
            for (&i, f) in test.iter().zip(fitted.iter()) {
                let prediction = if self.w[i] > 0.0 {
                    f / self.w[i]
                } else {
                    let beta = &*self.map * (&u - &avc * &v);
                    let gamma = (&vc * &v).component_mul(&scale_c);
                    self.x.row(i).dot(&beta.transpose()) + c.row(i).dot(&gamma.transpose())
                };
                out[i] = self.y[i] - prediction;
            }
        }
        out
    }
}

/// The directions whitened, column-normalised columns `cw` (n × k) add to the orthonormal
/// basis `q` (n × r): `cw` with `q` projected out — a second time where the first left less
/// than [`REPROJECT_BELOW`] of a column's norm, for rounding — whose Gram's eigenpairs that are
/// new directions ([`new_directions`]) make them orthonormal.
struct Beyond {
    /// `Qᵀ cw` (both passes), r × k.
    a: DMat,
    /// `V Λ^{-1/2}`, k × m: the new directions are `(cw − Q a) v`.
    v: DMat,
    /// The new directions, n × m, orthonormal and orthogonal to `q`.
    q: DMat,
}

fn beyond(q: &DMat, cw: DMat) -> Beyond {
    let (r, k) = (q.ncols(), cw.ncols());
    let (mut a, mut perp) = (DMat::zeros(r, k), cw);
    if r > 0 && k > 0 {
        let norms: Vec<f64> = perp.column_iter().map(|c| c.norm()).collect();
        for pass in 0..2 {
            let step = tr_mul(q, &perp);
            perp -= mul(q, &step);
            a += step;
            let kept = || {
                perp.column_iter()
                    .zip(&norms)
                    .all(|(c, n)| c.norm() >= REPROJECT_BELOW * n)
            };
            if pass == 0 && kept() {
                break;
            }
        }
    }
    let directions = if k == 0 {
        Vec::new()
    } else {
        new_directions(&perp.tr_mul(&perp).symmetric_eigen())
    };
    let v = DMat::from_fn(k, directions.len(), |i, j| {
        directions[j].1[i] / directions[j].0.sqrt()
    });
    let q = &perp * &v;
    Beyond { a, v, q }
}

/// Orthonormal (whitened) directions, grown block by block ([`separable_columns`]).
pub(crate) struct Directions {
    m: DMat,
    len: usize,
}

impl Directions {
    /// No directions yet, room for `capacity` of length `n`.
    pub fn new(n: usize, capacity: usize) -> Directions {
        Directions {
            m: DMat::zeros(n, capacity),
            len: 0,
        }
    }

    fn push(&mut self, v: &DVec) {
        if self.len == self.m.ncols() {
            let grown = (2 * self.len).max(self.len + 1);
            self.m = std::mem::take(&mut self.m).resize_horizontally(grown, 0.0);
        }
        self.m.column_mut(self.len).copy_from(v);
        self.len += 1;
    }

    /// `b` less its components along the first `len` directions.
    fn project_out(&self, len: usize, b: &mut DMat) {
        if len > 0 {
            let basis = as_faer(&self.m).subcols(0, len);
            let coef = product(basis.transpose(), as_faer(b));
            *b -= product(basis, as_faer(&coef));
        }
    }
}

/// Splits the nonzero columns of `c` into those that keep at least [`SEPARABILITY_TOLERANCE`]
/// of their whitened (by `w`) norm once the span of the orthonormal `q` and the directions in
/// `kept` are projected out (twice, for rounding: the block at once, then column by column
/// against the block's own new directions) — their directions are appended to `kept` — and
/// those that do not: `(separable, not separable)` column indices.
pub(crate) fn separable_columns(
    c: &DMat,
    w: &DVec,
    q: Option<&DMat>,
    kept: &mut Directions,
) -> (Vec<usize>, Vec<usize>) {
    let (mut separable, mut not) = (Vec::new(), Vec::new());
    let nonzero: Vec<(usize, f64)> = c
        .column_iter()
        .enumerate()
        .map(|(j, column)| (j, column.component_mul(w).norm()))
        .filter(|&(_, norm)| norm > 0.0)
        .collect();
    let mut block = DMat::from_fn(c.nrows(), nonzero.len(), |i, k| {
        let (j, norm) = nonzero[k];
        c[(i, j)] * w[i] / norm
    });
    let before = kept.len;
    for _ in 0..2 {
        if let Some(q) = q.filter(|q| q.ncols() > 0) {
            let coef = tr_mul(q, &block);
            block -= mul(q, &coef);
        }
        kept.project_out(before, &mut block);
    }
    for (k, &(j, _)) in nonzero.iter().enumerate() {
        let mut r = block.column(k).into_owned();
        for _ in 0..2 {
            for e in before..kept.len {
                let e = kept.m.column(e);
                r.axpy(-e.dot(&r), &e, 1.0);
            }
        }
        let left = r.norm();
        if left >= SEPARABILITY_TOLERANCE {
            kept.push(&(r / left));
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
    /// `map` with `(W X) · map = q`: a candidate's `Qᵀ W c` is `mapᵀ (Xᵀ W² c)`.
    map: DMat,
    w: DVec,
    /// Whitened residuals and their components along the basis.
    rw: DVec,
    qtr: DVec,
}

/// A projector's products with the functions of one variable spread over its rows
/// ([`Projector::spread_products`]).
pub(crate) struct SpreadProducts {
    /// `Sᵀ W Q` (values × directions).
    qs: DMat,
    /// `Sᵀ W r_w`.
    sr: DVec,
    /// `Sᵀ W² S` ([`Spread::gram`]).
    gram: Vec<(usize, usize, f64)>,
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
    /// `C⊥ᵀ W² C⊥` (k × k), and the whitened norms of the columns before projection: what
    /// [`Increment::beyond`] needs.
    gram: DMat,
    norms: Vec<f64>,
}

impl Increment {
    /// The whitened sum of squares a unit coefficient vector adds beyond the model and beyond
    /// more directions, at its least and its most over the directions of the coefficients
    /// (the extreme eigenvalues of `C⊥ᵀ W² C⊥ − bᵀb`): what a cause of a given size would show
    /// in these data, depending on its phase when it has two coefficients (a sine and a
    /// cosine). `b = Nᵀ W C` (m × k) are the candidate's products with the further directions
    /// (`N` orthonormal and orthogonal to the model, [`Projector::directions_beyond`]; m = 0:
    /// none). `None` when they hold it (less than [`SEPARABILITY_TOLERANCE`] of a column's norm
    /// left in some direction).
    pub fn beyond(&self, b: &DMat) -> Option<(f64, f64)> {
        if self.new_rank == 0 {
            return None;
        }
        let g = &self.gram - b.tr_mul(b);
        let normalised = DMat::from_fn(g.nrows(), g.ncols(), |i, j| {
            g[(i, j)] / (self.norms[i] * self.norms[j])
        });
        (extreme_eigenvalues(&normalised).0.sqrt() >= SEPARABILITY_TOLERANCE)
            .then(|| extreme_eigenvalues(&g))
    }
}

/// `aᵀ b`, the inner loop of every scan, by faer's blocked, vectorised product — or, for a
/// `b` of a few columns against a wide `a` (a refinement's trial columns against the model's
/// basis), by dot products that read `a` once instead of packing it first.
pub(crate) fn tr_mul(a: &DMat, b: &DMat) -> DMat {
    if read_in_place(a, b) {
        let mut out = DMat::zeros(a.ncols(), b.ncols());
        let b_columns: Vec<&[f64]> = b.as_slice().chunks_exact(b.nrows()).collect();
        for (i, ai) in a.as_slice().chunks_exact(a.nrows()).enumerate() {
            // Two columns of `b` per pass over a column of `a`: a quarter fewer loads.
            let mut j = 0;
            for pair in b_columns.chunks(2) {
                match pair {
                    [b0, b1] => (out[(i, j)], out[(i, j + 1)]) = dot2(ai, b0, b1),
                    _ => out[(i, j)] = dot(ai, pair[0]),
                }
                j += pair.len();
            }
        }
        return out;
    }
    product(as_faer(a).transpose(), as_faer(b))
}

/// Whether [`tr_mul`] and [`mul`] read `a` in place: `b` has a few columns against a wide `a`.
fn read_in_place(a: &DMat, b: &DMat) -> bool {
    b.ncols() <= NARROW_PRODUCT && a.ncols() > 4 * b.ncols() && a.nrows() > 0
}

/// `xᵀ y` with eight partial sums (independent chains the processor can overlap).
fn dot(x: &[f64], y: &[f64]) -> f64 {
    let mut acc = [0.0; 8];
    for (a, b) in x.chunks_exact(8).zip(y.chunks_exact(8)) {
        for k in 0..8 {
            acc[k] += a[k] * b[k];
        }
    }
    added_up(&acc, x, y)
}

/// [`dot`] of `x` with `y0` and with `y1`, `x` read once for both (the same sums).
fn dot2(x: &[f64], y0: &[f64], y1: &[f64]) -> (f64, f64) {
    let (mut acc0, mut acc1) = ([0.0; 8], [0.0; 8]);
    for ((a, b0), b1) in x
        .chunks_exact(8)
        .zip(y0.chunks_exact(8))
        .zip(y1.chunks_exact(8))
    {
        for k in 0..8 {
            acc0[k] += a[k] * b0[k];
            acc1[k] += a[k] * b1[k];
        }
    }
    (added_up(&acc0, x, y0), added_up(&acc1, x, y1))
}

/// The partial sums `acc` of [`dot`] added up, with the products of the entries beyond the
/// last whole eight.
fn added_up(acc: &[f64; 8], x: &[f64], y: &[f64]) -> f64 {
    let body = x.len() - x.len() % 8;
    let tail: f64 = x[body..].iter().zip(&y[body..]).map(|(a, b)| a * b).sum();
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}

/// `a b`, by faer's product — or, for a `b` of a few columns against a wide `a` (the model's
/// basis times a candidate's coordinates in it), column by column of `a`, read once instead of
/// packed first.
pub(crate) fn mul(a: &DMat, b: &DMat) -> DMat {
    if read_in_place(a, b) {
        // Four columns of `a` per pass over a column of the result: half the loads and stores.
        // (Each entry sums its terms in the order of the columns of `a`, as one at a time.)
        let n = a.nrows();
        let mut out = DMat::zeros(n, b.ncols());
        let a_columns: Vec<&[f64]> = a.as_slice().chunks_exact(n).collect();
        let mut i = 0;
        for block in a_columns.chunks(4) {
            for (j, o) in out.as_mut_slice().chunks_exact_mut(n).enumerate() {
                match block {
                    [a0, a1, a2, a3] => {
                        let c = [b[(i, j)], b[(i + 1, j)], b[(i + 2, j)], b[(i + 3, j)]];
                        let columns = a0.iter().zip(*a1).zip(*a2).zip(*a3);
                        for (o, (((x0, x1), x2), x3)) in o.iter_mut().zip(columns) {
                            *o = (((*o + c[0] * x0) + c[1] * x1) + c[2] * x2) + c[3] * x3;
                        }
                    }
                    _ => {
                        for (l, al) in block.iter().enumerate() {
                            let c = b[(i + l, j)];
                            for (o, a) in o.iter_mut().zip(*al) {
                                *o += c * a;
                            }
                        }
                    }
                }
            }
            i += block.len();
        }
        return out;
    }
    product(as_faer(a), as_faer(b))
}

impl Projector {
    /// The model with design `x`, weights `w` and residuals `r`.
    pub fn new(x: &DMat, w: &DVec, r: &DVec) -> Projector {
        // The column-normalised whitened design: the directions [`solve`] keeps.
        let (xw, scale) = whitened_columns(x.clone(), w);
        let (q, map) = orthonormal_basis_and_map(&xw);
        let map = DMat::from_fn(map.nrows(), map.ncols(), |i, j| map[(i, j)] * scale[i]);
        let rw = r.component_mul(w);
        let qtr = if q.ncols() > 0 {
            q.tr_mul(&rw)
        } else {
            DVec::zeros(0)
        };
        Projector {
            q,
            map,
            w: w.clone(),
            rw,
            qtr,
        }
    }

    /// The least-squares fit of `y` by the model with design `x` and weights `w`, as a
    /// projector: one factorisation gives the basis and the residuals ([`solve`] is for the
    /// coefficients and their cofactor).
    pub fn fit(x: &DMat, y: &DVec, w: &DVec) -> Projector {
        let mut p = Projector::new(x, w, &DVec::zeros(y.len()));
        p.fit_residuals(y);
        p
    }

    /// Sets the residuals to those of the least-squares fit of `y`.
    fn fit_residuals(&mut self, y: &DVec) {
        let yw = y.component_mul(&self.w);
        self.rw = if self.q.ncols() > 0 {
            &yw - &self.q * self.q.tr_mul(&yw)
        } else {
            yw
        };
        self.qtr = if self.q.ncols() > 0 {
            self.q.tr_mul(&self.rw)
        } else {
            DVec::zeros(0)
        };
    }

    /// The fit ([`Projector::fit`]) of the model with the columns `c` appended to its design:
    /// the basis grows by the directions `c` adds (projected out twice, for rounding; as in
    /// [`FoldFits`], directions with less than 1e-6 of their norm left are not new), and the
    /// residuals lose their component along them — `n × rank × k` work instead of a new
    /// factorisation. The design the result belongs to is the old one with `c` to its right.
    pub fn extended(&self, c: &DMat) -> Projector {
        let (n, r, p) = (self.w.len(), self.q.ncols(), self.map.nrows());
        let k = c.ncols();
        if k == 0 {
            return self.clone();
        }
        let (cw, scale) = whitened_columns(c.clone(), &self.w);
        let Beyond { a, v, q: qc } = beyond(&self.q, cw);
        let m = qc.ncols();
        // [W X, W c] · [map, −map a v; 0, diag(scale) v] = [Q, qc].
        // Column-major: the old basis, then the new directions (no zeroed n × (r + m) first).
        let mut data = Vec::with_capacity(n * (r + m));
        data.extend_from_slice(self.q.as_slice());
        data.extend_from_slice(qc.as_slice());
        let q = DMat::from_vec(n, r + m, data);
        let mut map = DMat::zeros(p + k, r + m);
        map.view_mut((0, 0), (p, r)).copy_from(&self.map);
        if r > 0 {
            map.view_mut((0, r), (p, m))
                .copy_from(&(-(&self.map * (&a * &v))));
        }
        map.view_mut((p, r), (k, m))
            .copy_from(&DMat::from_fn(k, m, |i, j| v[(i, j)] * scale[i]));
        let rw = &self.rw - &qc * qc.tr_mul(&self.rw);
        let qtr = if r + m > 0 {
            q.tr_mul(&rw)
        } else {
            DVec::zeros(0)
        };
        Projector {
            q,
            map,
            w: self.w.clone(),
            rw,
            qtr,
        }
    }

    /// The part of the residuals that the columns `c` would fit beyond the model, in the
    /// observations' units (zero where the weight is zero).
    pub fn fitted_along(&self, c: &DMat) -> DVec {
        let extended = self.extended(c);
        DVec::from_fn(self.w.len(), |i, _| {
            if self.w[i] > 0.0 {
                (self.rw[i] - extended.rw[i]) / self.w[i]
            } else {
                0.0
            }
        })
    }

    /// The fit ([`Projector::fit`] of `y`) of the same model with the observations `rows`
    /// given zero weight (an outer fold's held-out rows), by downdating the basis: with `M =
    /// I − Q_RᵀQ_R = V Λ Vᵀ` the remaining rows' Gram, `Q V Λ^{-1/2}` on the other rows is
    /// orthonormal — `n × rank²` work instead of a factorisation. Directions the remaining rows
    /// do not determine (λ below [`FOLD_TOLERANCE`]) are dropped; the rare poorly determined
    /// ones (λ below 1e-6) get a second orthonormalisation.
    pub fn without_rows(&self, rows: &[usize], y: &DVec) -> Projector {
        let mut w = self.w.clone();
        for &i in rows {
            w[i] = 0.0;
        }
        let r = self.q.ncols();
        if r == 0 {
            return Projector::fit(&DMat::zeros(w.len(), self.map.nrows()), y, &w);
        }
        let mut q = self.q.clone();
        for &i in rows {
            q.row_mut(i).fill(0.0);
        }
        let (q, map) = orthonormalised(q, self.map.clone());
        let mut p = Projector {
            q,
            map,
            w,
            rw: DVec::zeros(0),
            qtr: DVec::zeros(0),
        };
        p.fit_residuals(y);
        p
    }

    /// [`Projector::extended`] to the design `x`, whose first columns are this model's.
    pub fn extended_to(&self, x: &DMat) -> Projector {
        let p0 = self.design_columns();
        self.extended(&x.columns(p0, x.ncols() - p0).into_owned())
    }

    /// Each observation's leverage, the diagonal of the whitened hat matrix `Q Qᵀ`.
    pub fn leverages(&self) -> DVec {
        DVec::from_fn(self.q.nrows(), |i, _| self.q.row(i).norm_squared())
    }

    /// The model's whitened residuals.
    pub fn weighted_residuals(&self) -> &DVec {
        &self.rw
    }

    /// Weighted residual sum of squares of the model's fit.
    pub fn rss_w(&self) -> f64 {
        self.rw.norm_squared()
    }

    /// [`solve`]'s solution for the observations `y` and this fit's design `x`, without a
    /// factorisation, where the basis spans every column of `x`: the coefficients are then
    /// unique, `map Qᵀ W y`, and their cofactor `(XᵀW²X)⁻¹ = map mapᵀ` (`W X map = Q`). `None`
    /// for a design of lower rank, whose minimum-norm solution [`solve`] gives.
    pub fn solution(&self, x: &DMat, y: &DVec) -> Option<Solution> {
        let p = self.map.nrows();
        if self.q.ncols() != p || x.ncols() != p || p == 0 {
            return None;
        }
        let coef = self.coefficients(y);
        let residuals = y - x * &coef;
        let rss_w = weighted_rss(&residuals, &self.w);
        Some(Solution {
            cofactor: &self.map * self.map.transpose(),
            coef,
            rank: p,
            residuals,
            rss_w,
            observations: self.w.iter().filter(|w| **w > 0.0).count(),
        })
    }

    /// The least-squares coefficients of `c` on the model's design (minimum norm in the
    /// column-normalised design, as [`solve`]'s).
    pub fn coefficients(&self, c: &DVec) -> DVec {
        if self.q.ncols() == 0 {
            return DVec::zeros(self.map.nrows());
        }
        &self.map * self.basis_of(c)
    }

    /// [`Projector::coefficients`] of each column of `c`, by one product.
    pub fn coefficients_of(&self, c: &DMat) -> DMat {
        if self.q.ncols() == 0 {
            return DMat::zeros(self.map.nrows(), c.ncols());
        }
        let mut cw = c.clone();
        for mut column in cw.column_iter_mut() {
            column.component_mul_assign(&self.w);
        }
        &self.map * tr_mul(&self.q, &cw)
    }

    /// Columns of the model's design.
    pub fn design_columns(&self) -> usize {
        self.map.nrows()
    }

    /// The number of observations.
    pub fn rows(&self) -> usize {
        self.w.len()
    }

    /// Rank of the model.
    pub fn rank(&self) -> usize {
        self.q.ncols()
    }

    /// Degrees of freedom of the residuals: observations of nonzero weight less the rank.
    pub fn dof(&self) -> usize {
        let observations = self.w.iter().filter(|w| **w > 0.0).count();
        observations.saturating_sub(self.rank())
    }

    /// The residual variance (weighted RSS over its degrees of freedom, at least one): the unit
    /// of the χ² differences the search compares causes by.
    pub fn residual_variance(&self) -> f64 {
        self.rss_w() / self.dof().max(1) as f64
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
            map: self.map.clone(),
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
        separable_columns(c, &self.w, q, &mut Directions::new(c.nrows(), c.ncols())).0
    }

    /// An orthonormal basis (whitened, n × m) of the directions this fit's model adds to the
    /// model of `narrower`, which it extends ([`Projector::extended`]): for
    /// [`Increment::beyond`].
    pub fn directions_beyond(&self, narrower: &Projector) -> DMat {
        let r = narrower.q.ncols();
        self.q.columns(r, self.q.ncols() - r).into_owned()
    }

    /// What `c` explains of the differences between visits of the same pose alone: the
    /// whitened residuals and `c` (whitened, the model projected out) less their means over
    /// each pose of `poses` (a pose index per observation; a pose measured once drops out).
    /// Whatever the model lacks as a function of the pose is constant over a pose's visits and
    /// drops out too: only an effect of time shows there. Returns the residual sum of squares
    /// within the poses, the part of it `c` explains, and its degrees of freedom (the repeat
    /// visits); `None` where fewer than two would remain beside `c`.
    pub fn within_poses(&self, c: &DMat, poses: &[usize]) -> Option<(f64, f64, usize)> {
        let cw = self.residual_part(c);
        let x = DMat::from_columns(
            &cw.column_iter()
                .map(|col| less_pose_means(col.into_owned(), poses))
                .collect::<Vec<_>>(),
        );
        let repeats = repeat_visits(poses);
        if repeats < c.ncols() + 2 {
            return None;
        }
        let r = less_pose_means(self.rw.clone(), poses);
        let b = x.tr_mul(&r);
        let explained = x
            .tr_mul(&x)
            .pseudo_inverse(1e-12)
            .ok()
            .map_or(0.0, |g| b.dot(&(g * &b)));
        Some((r.norm_squared(), explained, repeats))
    }

    /// The weighted residual sum of squares within the poses of `poses` (the whitened residuals
    /// less their means over each pose), and the number of repeat visits it rests on.
    pub fn rss_within_poses(&self, poses: &[usize]) -> (f64, usize) {
        (
            less_pose_means(self.rw.clone(), poses).norm_squared(),
            repeat_visits(poses),
        )
    }

    /// Whitened `c` with the current model projected out.
    pub fn residual_part(&self, c: &DMat) -> DMat {
        let mut cw = c.clone();
        for mut column in cw.column_iter_mut() {
            column.component_mul_assign(&self.w);
        }
        if self.q.ncols() > 0 {
            let coef = tr_mul(&self.q, &cw);
            cw -= mul(&self.q, &coef);
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
        let mut out = Vec::with_capacity(count);
        in_batches(count, self.w.len(), candidate, |batch, mut cw| {
            for mut column in cw.column_iter_mut() {
                column.component_mul_assign(&self.w);
            }
            let a = (self.q.ncols() > 0).then(|| tr_mul(&self.q, &cw));
            let mut at = 0;
            for c in batch {
                let k = c.ncols();
                let ak = a.as_ref().map(|a| a.columns(at, k));
                out.push(self.increment_of(cw.columns(at, k), ak));
                at += k;
            }
        });
        out
    }

    /// [`Projector::increment_from_products`] of the candidates `c` whose products with the first
    /// directions of this projector's basis are known: `known[i]` holds `Qᵀ W cᵢ` on the first
    /// `known[i].nrows()` of them (from a projector this one extends: [`Projector::extended`]
    /// keeps the old basis as its first directions). Only the products with the directions
    /// beyond are formed — a model completed one term at a time reads the directions each
    /// term adds, not its whole basis again — and `known` becomes the products with all.
    /// `own[i]`: `(cᵢᵀ W² cᵢ, cᵢᵀ W² y)`, and `qty = Qᵀ W y` ([`Projector::basis_of`]) of the
    /// observations `y` the residuals are of: a candidate that knows every direction costs
    /// no pass over the observations.
    pub fn increments_knowing(
        &self,
        c: &[&DMat],
        known: &mut [DMat],
        own: Vec<(DMat, DVec)>,
        qty: &DVec,
    ) -> Vec<Increment> {
        let r = self.q.ncols();
        // Candidates that know as many directions: one product with the directions beyond.
        let from: Vec<usize> = known.iter().map(|k| k.nrows().min(r)).collect();
        let mut order: Vec<usize> = (0..c.len()).filter(|&i| from[i] < r).collect();
        order.sort_by_key(|&i| from[i]);
        for group in order.chunk_by(|&a, &b| from[a] == from[b]) {
            let r0 = from[group[0]];
            // The directions beyond, weighted (`(W Q)ᵀ c = Qᵀ W c`): each candidate's columns
            // are read in place, not copied and whitened first.
            let qw = DMat::from_fn(self.w.len(), r - r0, |i, j| self.q[(i, r0 + j)] * self.w[i]);
            for &i in group {
                let k = c[i].ncols();
                let mut a = DMat::zeros(r, k);
                if r0 > 0 {
                    a.rows_mut(0, r0).copy_from(&known[i].rows(0, r0));
                }
                a.rows_mut(r0, r - r0).copy_from(&tr_mul(&qw, c[i]));
                known[i] = a;
            }
        }
        own.into_iter()
            .zip(known.iter())
            .map(|((g, cy), a)| self.increment_from_products(&g, cy, a.rows(0, r), qty))
            .collect()
    }

    /// [`Projector::increments`] of `count` candidates that are functions of one variable:
    /// candidate `k` has the columns `spread.expand(basis(k, v))`, `v` the variable's distinct
    /// values ([`Spread::values`]). Its products with the model and the residuals come from
    /// sums over the rows of each value, formed once ([`Projector::spread_products`]): a scan
    /// over repeated positions (runs over the same targets, program cycles) costs the distinct
    /// positions, not the observations.
    pub fn increments_on(
        &self,
        spread: &Spread,
        count: usize,
        basis: impl Fn(usize, &[f64]) -> DMat,
    ) -> Vec<Increment> {
        let products = self.spread_products(spread);
        let mut out = Vec::with_capacity(count);
        let values = |k: usize| Cow::Owned(basis(k, spread.values()));
        in_batches(count, spread.values().len(), values, |batch, cs| {
            let a = (self.q.ncols() > 0).then(|| tr_mul(&products.qs, &cs));
            let mut at = 0;
            for c in batch {
                let k = c.ncols();
                let ak = a.as_ref().map(|a| a.columns(at, k));
                out.push(self.increment_from_spread(&products, c, ak));
                at += k;
            }
        });
        out
    }

    /// The products of this projector's basis, weights and residuals with the functions of
    /// one variable `spread` (on the projector's rows): `Sᵀ W Q`, `Sᵀ W r_w`, `Sᵀ W² S`.
    pub fn spread_products(&self, spread: &Spread) -> SpreadProducts {
        assert_eq!(
            spread.rows(),
            self.w.len(),
            "a spread on the projector's rows"
        );
        let rw = DMat::from_column_slice(self.rw.len(), 1, self.rw.as_slice());
        SpreadProducts {
            qs: spread.weighted_sums(&self.q, &self.w, None),
            sr: spread
                .weighted_sums(&rw, &self.w, None)
                .column(0)
                .into_owned(),
            gram: spread.gram(&self.w.component_mul(&self.w)),
        }
    }

    /// [`Projector::increment`] of the functions `b` of a spread's values (columns
    /// `spread.expand(b)`), from the spread's products with this projector: no pass over the
    /// observations.
    pub fn increment_spread(&self, products: &SpreadProducts, b: &DMat) -> Increment {
        let a = (self.q.ncols() > 0).then(|| tr_mul(&products.qs, b));
        self.increment_from_spread(products, b, a.as_ref().map(|a| a.columns(0, b.ncols())))
    }

    fn increment_from_spread(
        &self,
        products: &SpreadProducts,
        b: &DMat,
        a: Option<DMatView<'_>>,
    ) -> Increment {
        let gram = Spread::quadratic(&products.gram, b);
        self.increment_from(gram, b.tr_mul(&products.sr), a)
    }

    /// The folds' fits of the projector's model (design `x`, observations `y`), on its basis.
    /// `shared`: the [`Projector::fold_basis`] on `folds` of a fit this one extends, or of this
    /// one itself (its first directions are then not gathered again).
    pub fn fold_fits<'a>(
        &'a self,
        folds: &'a Folds,
        x: &'a DMat,
        y: &'a DVec,
        shared: Option<&FoldBasis>,
    ) -> FoldFits<'a> {
        FoldFits::with_basis(
            folds,
            x,
            y,
            &self.w,
            Cow::Borrowed(&self.q),
            Cow::Borrowed(&self.map),
            shared,
        )
    }

    /// This fit's basis on the test rows of `folds`, for the fold fits of the models that
    /// extend it ([`Projector::extended`] keeps it as their first directions): passed to their
    /// [`Projector::fold_fits`], only the directions they add are gathered and multiplied.
    pub fn fold_basis(&self, folds: &Folds) -> FoldBasis {
        FoldBasis {
            rank: self.q.ncols(),
            folds: folds
                .test
                .iter()
                .map(|test| rows_and_gram(&self.q, test))
                .collect(),
        }
    }

    /// `Qᵀ W C` of candidates' columns `C` on the basis' `directions`, from their products
    /// `xtc = Xᵀ W² C` with the model's design `X` (p × columns, weights `W`): those rows of
    /// `mapᵀ xtc`, directions × p × columns work instead of a pass over the observations
    /// (n × directions × columns). A search keeps the products of every candidate with its
    /// model and adds rows as the model grows ([`weighted_products`]); a fit extended from
    /// another differs from it only on the directions it adds ([`Projector::extended`] keeps
    /// the old basis as its first directions).
    pub fn basis_products_of(&self, directions: std::ops::Range<usize>, xtc: &DMat) -> DMat {
        let map = self
            .map
            .columns(directions.start, directions.len())
            .into_owned();
        tr_mul(&map, xtc)
    }

    /// `Qᵀ W y` of the observations `y` the projector's residuals are of: with it, a candidate's
    /// increment needs no pass over the observations ([`Projector::increment_from_products`]).
    pub fn basis_of(&self, y: &DVec) -> DVec {
        if self.q.ncols() == 0 {
            return DVec::zeros(0);
        }
        self.q.tr_mul(&y.component_mul(&self.w))
    }

    /// [`Projector::increment`] of a candidate `C` from its products alone: `g = CᵀW²C`,
    /// `cy = CᵀW²y`, `a = QᵀWC` ([`Projector::basis_products_of`]) and `qty = QᵀWy`
    /// ([`Projector::basis_of`]) — its product with the residuals is `cy − aᵀ qty`.
    pub fn increment_from_products(
        &self,
        g: &DMat,
        cy: DVec,
        a: DMatView<'_>,
        qty: &DVec,
    ) -> Increment {
        let b = if self.q.ncols() > 0 {
            cy - a.tr_mul(qty)
        } else {
            cy
        };
        self.increment_from(g.clone(), b, (self.q.ncols() > 0).then_some(a))
    }

    /// The increment of whitened candidate columns `cw` with `a = Qᵀ cw` (`None`: no model).
    fn increment_of(&self, cw: DMatView<'_>, a: Option<DMatView<'_>>) -> Increment {
        self.increment_from(cw.tr_mul(&cw), cw.tr_mul(&self.rw), a)
    }

    /// The increment of a candidate `C` given its whitened products: `g = CᵀW²C`,
    /// `b = CᵀW r_w` and `a = Qᵀ W C` (`None`: no model).
    fn increment_from(&self, mut g: DMat, mut b: DVec, a: Option<DMatView<'_>>) -> Increment {
        let k = g.ncols();
        let none = Increment {
            delta_rss: 0.0,
            new_rank: 0,
            separability: 0.0,
            gram: DMat::zeros(0, 0),
            norms: Vec::new(),
        };
        if k == 0 {
            return none;
        }
        let norms: Vec<f64> = (0..k).map(|i| g[(i, i)].sqrt()).collect();
        if norms.iter().any(|n| n.is_nan() || *n <= 0.0) {
            return none;
        }
        if let Some(a) = a {
            g -= a.tr_mul(&a);
            b -= a.tr_mul(&self.qtr);
        }
        let gram = g.clone();
        for i in 0..k {
            b[i] /= norms[i];
            for j in 0..k {
                g[(i, j)] /= norms[i] * norms[j];
            }
        }
        // One or two columns (most candidates: a drift, a sine and cosine) in closed form; the
        // same eigenpairs as the general route, without its allocations.
        let (lambda_min, directions) = match k {
            1 => (g[(0, 0)], vec![(g[(0, 0)], DVec::from_element(1, 1.0))]),
            2 => {
                let (a, c, d) = (g[(0, 0)], g[(0, 1)], g[(1, 1)]);
                let (mean, half) = (0.5 * (a + d), (0.5 * (a - d)).hypot(c));
                let (hi, lo) = (mean + half, mean - half);
                // The eigenvector of `hi`; the other is perpendicular.
                let v = if half > 0.0 {
                    let (x, y) = if a >= d { (hi - d, c) } else { (c, hi - a) };
                    let n = x.hypot(y);
                    (x / n, y / n)
                } else {
                    (1.0, 0.0)
                };
                (
                    lo,
                    vec![
                        (hi, DVec::from_vec(vec![v.0, v.1])),
                        (lo, DVec::from_vec(vec![-v.1, v.0])),
                    ],
                )
            }
            _ => {
                let eig = g.symmetric_eigen();
                let pairs = eig
                    .eigenvalues
                    .iter()
                    .zip(eig.eigenvectors.column_iter())
                    .map(|(l, v)| (*l, v.into_owned()))
                    .collect();
                (eig.eigenvalues.min(), pairs)
            }
        };
        let directions = kept_directions(directions);
        Increment {
            delta_rss: directions
                .iter()
                .fold(0.0, |d, (l, v)| d + v.dot(&b).powi(2) / l),
            new_rank: directions.len(),
            separability: lambda_min.max(0.0).sqrt(),
            gram,
            norms,
        }
    }
}

/// The least and the largest eigenvalue of a symmetric matrix (closed form up to 2 × 2), both
/// at least 0.
fn extreme_eigenvalues(g: &DMat) -> (f64, f64) {
    let (lo, hi) = match g.ncols() {
        1 => (g[(0, 0)], g[(0, 0)]),
        2 => {
            let (a, c, d) = (g[(0, 0)], g[(0, 1)], g[(1, 1)]);
            let (mean, half) = (0.5 * (a + d), (0.5 * (a - d)).hypot(c));
            (mean - half, mean + half)
        }
        _ => {
            let e = g.clone().symmetric_eigenvalues();
            (e.min(), e.max())
        }
    };
    (lo.max(0.0), hi.max(0.0))
}

/// The eigenpairs `(λ, v)` of the normalised Gram matrix of a candidate's columns with the
/// model projected out that are new directions: those with less than 1e-6 of their norm left
/// are rounding (the Gram difference cancels to about 1e-16).
fn new_directions(eig: &SymmetricEigen<f64, Dyn>) -> Vec<(f64, DVec)> {
    kept_directions(
        eig.eigenvalues
            .iter()
            .zip(eig.eigenvectors.column_iter())
            .map(|(l, v)| (*l, v.into_owned()))
            .collect(),
    )
}

/// The eigenpairs of [`new_directions`] that are new directions.
fn kept_directions(pairs: Vec<(f64, DVec)>) -> Vec<(f64, DVec)> {
    let lambda_max = pairs.iter().map(|p| p.0).fold(0.0, f64::max);
    pairs
        .into_iter()
        .filter(|&(l, _)| l > 1e-12 && l > 1e-12 * lambda_max)
        .collect()
}

/// Candidates `make(0..count)` (of `rows` rows) in batches of about [`BATCH_COLUMNS`] columns
/// (fewer for long columns), built one batch at a time: `each(blocks, their columns side by
/// side)`.
fn in_batches<'a>(
    count: usize,
    rows: usize,
    make: impl Fn(usize) -> Cow<'a, DMat>,
    mut each: impl FnMut(&[Cow<'a, DMat>], DMat),
) {
    let batch_columns = (BATCH_VALUES / rows.max(1)).clamp(1, BATCH_COLUMNS);
    let mut next = 0;
    while next < count {
        let mut batch = Vec::new();
        let mut width = 0;
        while next < count && (batch.is_empty() || width < batch_columns) {
            let c = make(next);
            width += c.ncols();
            batch.push(c);
            next += 1;
        }
        let mut data = Vec::with_capacity(rows * width);
        for c in &batch {
            data.extend_from_slice(c.as_slice());
        }
        each(&batch, DMat::from_vec(rows, width, data));
    }
}

/// Each block's Gram `cᵀ diag(w2) c` over the rows of each group (`group[i]` < `groups`: the
/// group of row `i`), in one pass over the columns: `[group][block]`. Blocks in parallel.
pub(crate) fn block_grams(
    column_blocks: &[&DMat],
    w2: &DVec,
    group: &[usize],
    groups: usize,
) -> Vec<Vec<DMat>> {
    use rayon::prelude::*;
    let per_block: Vec<Vec<DMat>> = column_blocks
        .par_iter()
        .map(|c| {
            let (n, k) = c.shape();
            let mut acc = vec![0.0; groups * k * k];
            // Column pair by column pair, each sum over the rows in order (as row by row).
            let columns: Vec<&[f64]> = (0..k).map(|j| &c.as_slice()[j * n..(j + 1) * n]).collect();
            let mut sums = vec![0.0; groups];
            for a in 0..k {
                for b in a..k {
                    sums.fill(0.0);
                    for (((&g, &ca), &cb), &w2) in
                        group.iter().zip(columns[a]).zip(columns[b]).zip(w2.iter())
                    {
                        sums[g] += ca * w2 * cb;
                    }
                    for (g, s) in sums.iter().enumerate() {
                        acc[g * k * k + a * k + b] = *s;
                    }
                }
            }
            (0..groups)
                .map(|g| DMat::from_fn(k, k, |a, b| acc[g * k * k + a.min(b) * k + a.max(b)]))
                .collect()
        })
        .collect();
    (0..groups)
        .map(|g| per_block.iter().map(|b| b[g].clone()).collect())
        .collect()
}

/// `xᵀ diag(w2) c` over all observations for the candidates' columns `c` (given by
/// `column_blocks`, each block's columns side by side in order): p × (total columns), one
/// blocked product per batch of about [`BATCH_COLUMNS`] columns, batches in parallel (the
/// result does not depend on the number of threads).
pub(crate) fn weighted_products(x: &DMat, w2: &DVec, column_blocks: &[&DMat]) -> DMat {
    let mut xs = x.clone();
    for (i, v) in w2.iter().enumerate() {
        xs.row_mut(i).scale_mut(*v);
    }
    if x.ncols() <= NARROW_PRODUCT {
        // A few columns (the terms a search step adds): each block's product read in place —
        // the cost is reading the candidates once, which a copy into batches would double.
        let total: usize = column_blocks.iter().map(|c| c.ncols()).sum();
        let mut out = DMat::zeros(x.ncols(), total);
        let mut at = 0;
        for block in column_blocks {
            for (j, c) in block.column_iter().enumerate() {
                for (i, xc) in xs.column_iter().enumerate() {
                    out[(i, at + j)] = xc.dot(&c);
                }
            }
            at += block.ncols();
        }
        return out;
    }
    batched_products(&[xs], column_blocks, |block, data| {
        data.extend_from_slice(block.as_slice())
    })
    .pop()
    .expect("one group")
}

/// [`weighted_products`] over each group of observations `groups` (disjoint rows, e.g. the
/// outer folds' test rows): one product per group, in one pass over the candidates — each
/// batch's rows are gathered group after group, and each group's product reads its own rows.
pub(crate) fn weighted_products_by_rows(
    x: &DMat,
    w2: &DVec,
    groups: &[Vec<usize>],
    column_blocks: &[&DMat],
) -> Vec<DMat> {
    let xs: Vec<DMat> = groups
        .iter()
        .map(|rows| {
            let mut xs = select_rows(x, rows);
            for (k, &i) in rows.iter().enumerate() {
                xs.row_mut(k).scale_mut(w2[i]);
            }
            xs
        })
        .collect();
    let order = groups.concat();
    batched_products(&xs, column_blocks, |block, data| {
        gather_rows(block, &order, data)
    })
}

/// `xs[g]ᵀ` times the rows of group `g` of the candidates' columns (the groups' rows one group
/// after the other, as many as `xs[g]` has), for every group, batch by batch: `fill(block,
/// data)` appends a block's rows in that order, column-major, to the batch's buffer.
fn batched_products(
    xs: &[DMat],
    column_blocks: &[&DMat],
    fill: impl Fn(&DMat, &mut Vec<f64>) + Sync,
) -> Vec<DMat> {
    let rows: usize = xs.iter().map(DMat::nrows).sum();
    // Batches of whole blocks.
    let mut batches: Vec<(usize, usize)> = Vec::new(); // (first block, end block)
    let mut start = 0;
    while start < column_blocks.len() {
        let mut end = start;
        let mut width = 0;
        while end < column_blocks.len() && (end == start || width < BATCH_COLUMNS) {
            width += column_blocks[end].ncols();
            end += 1;
        }
        batches.push((start, end));
        start = end;
    }
    use rayon::prelude::*;
    let parts: Vec<Vec<DMat>> = batches
        .par_iter()
        .map(|&(a, b)| {
            // The batch's columns side by side (column-major), copied once.
            let width: usize = column_blocks[a..b].iter().map(|c| c.ncols()).sum();
            let mut data = Vec::with_capacity(rows * width);
            for block in &column_blocks[a..b] {
                fill(block, &mut data);
            }
            let c = DMat::from_vec(rows, width, data);
            let mut at = 0;
            xs.iter()
                .map(|xs| {
                    let part =
                        product(as_faer(xs).transpose(), as_faer(&c).subrows(at, xs.nrows()));
                    at += xs.nrows();
                    part
                })
                .collect()
        })
        .collect();
    let total: usize = parts.iter().map(|p| p[0].ncols()).sum();
    (0..xs.len())
        .map(|g| {
            let mut out = DMat::zeros(xs[g].ncols(), total);
            let mut at = 0;
            for part in &parts {
                out.columns_mut(at, part[g].ncols()).copy_from(&part[g]);
                at += part[g].ncols();
            }
            out
        })
        .collect()
}

/// `q` (n × r, columns spanning what remains of an orthonormal basis after some rows were
/// zeroed) made orthonormal again, with `map` (p × r) carried along: `q V Λ^{-1/2}` from the
/// eigen-decomposition `qᵀq = V Λ Vᵀ`, directions with λ below [`FOLD_TOLERANCE`] × the largest
/// dropped; repeated once when a kept λ is below 1e-6 (its rounding, ε/λ, would show).
fn orthonormalised(q: DMat, map: DMat) -> (DMat, DMat) {
    let (mut q, mut map) = (q, map);
    for _ in 0..2 {
        let eig = gram(as_faer(&q)).symmetric_eigen();
        let top = eig.eigenvalues.max().max(0.0);
        let keep: Vec<usize> = (0..eig.eigenvalues.len())
            .filter(|&k| eig.eigenvalues[k] > FOLD_TOLERANCE * top && top > 0.0)
            .collect();
        let s = DMat::from_fn(q.ncols(), keep.len(), |i, j| {
            eig.eigenvectors[(i, keep[j])] / eig.eigenvalues[keep[j]].sqrt()
        });
        let smallest = keep
            .iter()
            .map(|&k| eig.eigenvalues[k] / top)
            .fold(1.0, f64::min);
        q = product(as_faer(&q), as_faer(&s));
        map = &map * &s;
        if smallest >= 1e-6 {
            break;
        }
    }
    (q, map)
}

/// Columns of `x` up to which [`weighted_products`] reads each candidate block in place.
const NARROW_PRODUCT: usize = 8;

/// [`beyond`] projects the basis out of a block of columns a second time when the first pass
/// left any column less than this share of its norm. One pass of classical Gram–Schmidt leaves
/// a component along the basis of about ε √r / ρ of what remains, ρ the share left: 5e-13 at
/// ρ = 1e-3 and r = 1 000. (Twice always cost 7 % of an 8-cycle R-test diagnosis: candidate
/// columns keep 10–50 % of their norm beyond the model, the next orders of its errors 1 %.
/// The search's choices do not hang on such rounding: candidates that differ by it rank by
/// their place in the library, and a shortlist's cut takes them all. With one pass and with
/// two, the R-test false-discovery study, default base included, came out the same.)
const REPROJECT_BELOW: f64 = 1e-3;

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

/// Visits of a pose after its first, over all poses of `poses` (a pose index per entry).
fn repeat_visits(poses: &[usize]) -> usize {
    let mut count = vec![0usize; poses.iter().max().map_or(0, |&m| m + 1)];
    for &p in poses {
        count[p] += 1;
    }
    count.iter().map(|&k| k.saturating_sub(1)).sum()
}

/// `v` less its mean over each pose of `poses` (a pose index per entry).
fn less_pose_means(mut v: DVec, poses: &[usize]) -> DVec {
    let groups = poses.iter().max().map_or(0, |&m| m + 1);
    let (mut sum, mut count) = (vec![0.0; groups], vec![0usize; groups]);
    for (&p, x) in poses.iter().zip(v.iter()) {
        sum[p] += x;
        count[p] += 1;
    }
    for (x, &p) in v.iter_mut().zip(poses) {
        *x -= sum[p] / count[p] as f64;
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

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
    fn a_fit_of_full_rank_gives_the_solution_of_a_factorisation() {
        let n = 300;
        let (x, y, w) = problem(n);
        // Columns 0–3 (full rank), fitted at once and as a fit extended by its last column.
        let full = x.columns(0, 4).into_owned();
        let reference = solve(&full, &y, &w);
        let base = Projector::fit(&x.columns(0, 3).into_owned(), &y, &w);
        for fit in [
            Projector::fit(&full, &y, &w),
            base.extended(&x.columns(3, 1).into_owned()),
        ] {
            let sol = fit.solution(&full, &y).expect("full rank");
            assert_eq!(sol.rank, reference.rank);
            assert_eq!(sol.dof(), reference.dof());
            assert!((sol.rss_w - reference.rss_w).abs() < 1e-10 * reference.rss_w);
            assert!((&sol.coef - &reference.coef).amax() < 1e-9 * reference.coef.amax());
            let scale = reference.cofactor.amax();
            assert!((&sol.cofactor - &reference.cofactor).amax() < 1e-9 * scale);
        }
        // Column 4 is a combination of columns 1 and 2: the minimum-norm solution is solve's.
        let deficient = x.columns(0, 5).into_owned();
        assert!(
            Projector::fit(&deficient, &y, &w)
                .solution(&deficient, &y)
                .is_none()
        );
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
    fn position_folds_hold_out_every_reading_at_a_position_and_interleave_the_positions() {
        // Positions 0, 10, 20, 30 (twice each, 20 also just below by rounding), one excluded.
        let x = [20.0, 0.0, 10.0, 30.0, 20.0 - 1e-12, 0.0, 10.0, 30.0, 5.0];
        let include = [true, true, true, true, true, true, true, true, false];
        let f = Folds::by_position(&x, &include, 2);
        assert_eq!(f.test, vec![vec![0, 1, 4, 5], vec![2, 3, 6, 7]]);
    }

    #[test]
    fn a_fit_on_some_rows_is_the_least_squares_fit_of_those_rows() {
        // r = 2 + 3 t on rows 0..3 and anything on row 3: the fit on rows 0..3 recovers it.
        let c = DMat::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
        let r = DVec::from_column_slice(&[2.0, 5.0, 8.0, -40.0]);
        let (gain, beta) = fit_on_rows(&c, &r, &[0, 1, 2]);
        assert_relative_eq!(beta, DVec::from_column_slice(&[2.0, 3.0]), epsilon = 1e-12);
        assert_relative_eq!(gain, 4.0 + 25.0 + 64.0, epsilon = 1e-10);
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
        };
        // The reference: a fresh weighted least-squares fit on each fold's training rows.
        let fresh = |x: &DMat| {
            let mut out = DVec::zeros(n);
            for test in &folds.test {
                let train: Vec<usize> = (0..n).filter(|i| !test.contains(i)).collect();
                let sol = solve(
                    &select_rows(x, &train),
                    &select(&y, &train),
                    &select(&w, &train),
                );
                for &i in test {
                    out[i] = y[i] - x.row(i).dot(&sol.coef.transpose());
                }
            }
            folds.rms(&out)
        };
        let base = x.columns(0, 3).into_owned();
        let fit = Projector::fit(&base, &y, &w);
        let fits = fit.fold_fits(&folds, &base, &y, None);
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
            // The fit extended by it, its fold fits from the base's directions on the test rows
            // ([`Projector::fold_basis`]), and the extended model's fold fits scoring a further
            // column (the periodic one).
            let extended = fit.extended(&added);
            let shared = fit.fold_basis(&folds);
            let fits = extended.fold_fits(&folds, &wide, &y, Some(&shared));
            assert!((fits.rms() - b).abs() < 1e-9 * b, "{} vs {b}", fits.rms());
            let further = x.columns(5, 1).into_owned();
            let widest = DMat::from_fn(
                n,
                5,
                |i, j| {
                    if j < 4 { wide[(i, j)] } else { further[(i, 0)] }
                },
            );
            let (a, b) = (fits.rms_with(&further), fresh(&widest));
            assert!((a - b).abs() < 1e-9 * b, "{a} vs {b}");
        }
    }

    /// The fits a search derives from its base's fit — extended by columns, downdated for
    /// held-out rows — against fresh fits of the same model.
    #[test]
    fn extended_and_downdated_fits_equal_fresh_fits() {
        let n = 300;
        let (x, y, w) = problem(n);
        let fresh_of = |x: &DMat, w: &DVec| Projector::fit(x, &y, w);
        let agree = |a: &Projector, b: &Projector| {
            assert_eq!(a.rank(), b.rank());
            assert_eq!(a.dof(), b.dof());
            assert!(
                (a.rss_w() - b.rss_w()).abs() < 1e-10 * b.rss_w(),
                "{} vs {}",
                a.rss_w(),
                b.rss_w()
            );
            // The same span: a candidate's increment, and its coefficients on the design.
            let c = DMat::from_fn(n, 1, |i, _| ((i * 37) % 11) as f64);
            let (ia, ib) = (a.increment(&c), b.increment(&c));
            assert!((ia.delta_rss - ib.delta_rss).abs() < 1e-9 * ib.delta_rss.max(1e-300));
            let col = c.column(0).into_owned();
            let (fa, fb) = (
                x.columns(0, a.design_columns()) * a.coefficients(&col),
                x.columns(0, b.design_columns()) * b.coefficients(&col),
            );
            let wt = |v: DVec| v.component_mul(&a.w);
            assert!((wt(fa) - wt(fb)).norm() < 1e-9 * col.norm());
        };
        // Columns 3..6 appended to the fit of 0..3; column 4 is a combination of 1 and 2.
        let base = x.columns(0, 3).into_owned();
        let extended = Projector::fit(&base, &y, &w).extended_to(&x);
        agree(&extended, &fresh_of(&x, &w));
        // Every third row held out.
        let rows: Vec<usize> = (0..n).step_by(3).collect();
        let mut w0 = w.clone();
        for &i in &rows {
            w0[i] = 0.0;
        }
        let downdated = Projector::fit(&x, &y, &w).without_rows(&rows, &y);
        agree(&downdated, &fresh_of(&x, &w0));
    }

    #[test]
    fn increments_knowing_an_earlier_basis_equal_direct_ones() {
        let n = 300;
        let (x, y, w) = problem(n);
        let narrow = Projector::fit(&x.columns(0, 3).into_owned(), &y, &w);
        let wide = narrow.extended(&x.columns(3, 2).into_owned());
        let v: Vec<f64> = (0..n).map(|i| ((i * 7) % 23) as f64 * 3.7).collect();
        let c: Vec<DMat> = [11.0, 19.5, 40.0]
            .iter()
            .map(|&p| crate::basis::sin_cos_columns(&v, p))
            .collect();
        let refs: Vec<&DMat> = c.iter().collect();
        // Their own products, `CᵀW²C` and `CᵀW²y`.
        let own = || -> Vec<(DMat, DVec)> {
            c.iter()
                .map(|c| {
                    let cw2 = DMat::from_fn(n, c.ncols(), |i, j| c[(i, j)] * w[i] * w[i]);
                    (c.tr_mul(&cw2), cw2.tr_mul(&y))
                })
                .collect()
        };
        // Nothing known, then the narrow basis' products known (one candidate's not).
        let mut known = vec![DMat::zeros(0, 0); c.len()];
        let first = narrow.increments_knowing(&refs, &mut known, own(), &narrow.basis_of(&y));
        known[1] = DMat::zeros(0, 0);
        let second = wide.increments_knowing(&refs, &mut known, own(), &wide.basis_of(&y));
        for (knowing, fit) in [(&first, &narrow), (&second, &wide)] {
            let direct = fit.increments(c.len(), |k| Cow::Borrowed(&c[k]));
            for (d, k) in direct.iter().zip(knowing) {
                assert_eq!(d.new_rank, k.new_rank);
                assert!((d.delta_rss - k.delta_rss).abs() < 1e-9 * d.delta_rss);
                assert!((d.separability - k.separability).abs() < 1e-9);
            }
        }
        assert!(known.iter().all(|k| k.nrows() == wide.rank()));
    }

    #[test]
    fn increments_from_spreads_and_from_products_equal_direct_ones() {
        let n = 300;
        let (x, y, w) = problem(n);
        let fit = Projector::fit(&x.columns(0, 4).into_owned(), &y, &w);
        // A variable with repeated values (targets visited by several runs).
        let v: Vec<f64> = (0..n).map(|i| ((i * 7) % 23) as f64 * 3.7).collect();
        let periods = [11.0, 19.5, 40.0];
        let direct = fit.increments(periods.len(), |k| {
            Cow::Owned(crate::basis::sin_cos_columns(&v, periods[k]))
        });
        let ones = vec![1.0; n];
        let spread = Spread::new(&[(&v, &ones)]);
        assert_eq!(spread.values().len(), 23);
        let grouped = fit.increments_on(&spread, periods.len(), |k, values| {
            crate::basis::sin_cos_columns(values, periods[k])
        });
        // Seen at two poses with weights (an R-test's reading and its centring).
        let at_ref: Vec<f64> = (0..n).map(|i| ((i / 50) * 5) as f64 * 3.7).collect();
        let (a, r): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|i| ((i as f64 * 0.37).sin(), -(i as f64 * 0.11).cos()))
            .unzip();
        let two = Spread::new(&[(&v, &a), (&at_ref, &r)]);
        let products = fit.spread_products(&two);
        let at_two = |k: usize| crate::basis::sin_cos_columns(two.values(), periods[k]);
        for (k, (d, g)) in direct.iter().zip(&grouped).enumerate() {
            let d2 = fit.increment(&two.expand(&at_two(k)));
            let g2 = fit.increment_spread(&products, &at_two(k));
            for (d, g) in [(d, g), (&d2, &g2)] {
                assert_eq!(d.new_rank, g.new_rank);
                assert!((d.delta_rss - g.delta_rss).abs() < 1e-9 * d.delta_rss);
                assert!((d.separability - g.separability).abs() < 1e-9);
            }
        }
        // From the products alone: CᵀW²C, CᵀW²y, QᵀWC and QᵀWy.
        let c = crate::basis::sin_cos_columns(&v, periods[1]);
        let w2 = w.component_mul(&w);
        let gram = &block_grams(&[&c], &w2, &vec![0; n], 1)[0][0];
        let cy = weighted_products(&DMat::from_column_slice(n, 1, y.as_slice()), &w2, &[&c])
            .row(0)
            .transpose();
        let a = fit.basis_products_of(
            0..fit.rank(),
            &weighted_products(&x.columns(0, 4).into_owned(), &w2, &[&c]),
        );
        let from_products = fit.increment_from_products(gram, cy, a.as_view(), &fit.basis_of(&y));
        let direct = fit.increment(&c);
        assert_eq!(from_products.new_rank, direct.new_rank);
        assert!((from_products.delta_rss - direct.delta_rss).abs() < 1e-9 * direct.delta_rss);
    }

    #[test]
    fn narrow_and_grouped_products_equal_faer_blocked_ones() {
        let n = 301;
        let (x, y, w) = problem(n);
        // (42 columns: whole blocks of four and a remainder; 3: a pair and a single.)
        let wide = DMat::from_fn(n, 42, |i, j| {
            ((i * (j + 3)) % 17) as f64 - 8.0 + x[(i, j % 6)]
        });
        let narrow = DMat::from_fn(n, 3, |i, j| y[i] * (j as f64 + 1.0) - x[(i, 3)]);
        let faer_tr = product(as_faer(&wide).transpose(), as_faer(&narrow));
        assert_relative_eq!(tr_mul(&wide, &narrow), faer_tr, max_relative = 1e-12);
        let coef = DMat::from_fn(42, 3, |i, j| (i as f64 - 2.0 * j as f64) / 7.0);
        let faer_mul = product(as_faer(&wide), as_faer(&coef));
        assert_relative_eq!(
            mul(&wide, &coef),
            faer_mul,
            max_relative = 1e-12,
            epsilon = 1e-12
        );
        // Per group of rows in one pass, as over each group's rows alone.
        let w2 = w.component_mul(&w);
        let blocks = [&narrow, &x];
        let groups: Vec<Vec<usize>> = vec![
            (0..n).filter(|i| i % 3 == 0).collect(),
            (0..n).filter(|i| i % 3 != 0).collect(),
        ];
        let by_rows = weighted_products_by_rows(&wide, &w2, &groups, &blocks);
        for (rows, got) in groups.iter().zip(&by_rows) {
            let mut w2_rows = DVec::zeros(n);
            for &i in rows {
                w2_rows[i] = w2[i];
            }
            let expected = weighted_products(&wide, &w2_rows, &blocks);
            assert_relative_eq!(*got, expected, max_relative = 1e-12, epsilon = 1e-9);
        }
    }

    #[test]
    fn columns_separated_in_the_space_of_r_as_in_the_observations() {
        let n = 300;
        let (x, y, w) = problem(n);
        let mut direct = Directions::new(n, 0);
        let (r, _, _) = whitened_r(&x, &y, &w);
        let mut in_r = Directions::new(6, 6);
        let ones = DVec::from_element(6, 1.0);
        // Blocks [0, 1], [2, 3], [4, 5]: column 4 is a combination of 1 and 2.
        for at in [0, 2, 4] {
            let a = separable_columns(&x.columns(at, 2).into_owned(), &w, None, &mut direct);
            let b = separable_columns(&r.columns(at, 2).into_owned(), &ones, None, &mut in_r);
            assert_eq!(a, b);
        }
        assert_eq!(in_r.len, 5);
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
