//! Dense least squares on faer: QR, SVD, numerical rank, pseudo-inverse, null space, minimum-norm,
//! weighted, equality-constrained and datum-constrained (minimum norm on a subset) solutions, the
//! fitted-result type [`LstsqFit`] and the [`identifiability`] report.
//!
//! Matrices cross the API as nalgebra [`DMat`]/[`DVec`]; the decompositions run in faer on
//! zero-copy views (see [`crate::bridge`]).
//!
//! # Model and notation
//! Observations `b = A x + e`, `A` is `m × n` (m observations, n unknowns), `Cov(e) = σ0² W⁻¹`.
//! The weighted solution minimises `(b − A x)ᵀ W (b − A x)`. With the Cholesky factor
//! `W⁻¹ = L Lᵀ` the problem is whitened: `Ã = L⁻¹ A`, `b̃ = L⁻¹ b`, and `‖b̃ − Ã x‖²` is minimised.
//!
//! # Numerical rank
//! A singular value σᵢ counts as zero when `σᵢ ≤ τ`. The default ([`RankTolerance::Auto`]) is
//! `τ = max(m, n) · ε · σ_max` (ε = `f64::EPSILON`), the choice of LAPACK/NumPy `matrix_rank`;
//! the caller can give a relative or absolute threshold instead. The rank depends on the scaling
//! of the columns: scale unknowns to comparable units (e.g. mm and mm/m) before asking.
//!
//! # Example
//! ```
//! use mte_linalg::bridge::{DMat, DVec};
//! use mte_linalg::lstsq::{Lstsq, Weights};
//! // straight line y = c0 + c1·t through four points
//! let a = DMat::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
//! let b = DVec::from_vec(vec![1.0, 3.1, 4.9, 7.0]);
//! let fit = Lstsq::new().weights(Weights::Diagonal(DVec::from_element(4, 1.0))).fit(&a, &b)?;
//! assert!((fit.x[1] - 1.98).abs() < 1e-12);
//! assert_eq!(fit.dof, 2);
//! # Ok::<(), mte_linalg::LinalgError>(())
//! ```

use crate::bridge::{
    DMat, DVec, as_faer, as_faer_mut, clean_vector_state, faer_col_to_dvec, faer_to_dmat,
    vec_as_faer,
};
use crate::error::{LinalgError, Result};
use faer::Par;
use faer::linalg::solvers::SolveLstsq;

/// Coefficients of a null-space combination smaller than this (relative to the leading
/// coefficient 1) are dropped from its text and from [`NullCombination::terms`]; a parameter
/// whose component in the orthonormal null-space basis is below it counts as identifiable.
pub const COEFFICIENT_TOLERANCE: f64 = 1e-6;

/// Estimated parameters with |correlation| above this are listed in
/// [`IdentifiabilityReport::correlated_pairs`].
pub const CORRELATION_THRESHOLD: f64 = 0.99;

/// Threshold below which a singular value counts as zero (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum RankTolerance {
    /// `τ = max(m, n) · ε · σ_max`.
    #[default]
    Auto,
    /// `τ = r · σ_max` for the given `r ≥ 0`.
    Relative(f64),
    /// `τ` given directly (`≥ 0`, in the units of the matrix entries).
    Absolute(f64),
}

impl RankTolerance {
    /// The threshold τ for an `nrows × ncols` matrix whose largest singular value is `sigma_max`.
    ///
    /// # Example
    /// ```
    /// use mte_linalg::lstsq::RankTolerance;
    /// assert_eq!(RankTolerance::Auto.threshold(10, 3, 2.0), 10.0 * f64::EPSILON * 2.0);
    /// assert_eq!(RankTolerance::Relative(1e-8).threshold(10, 3, 2.0), 2e-8);
    /// assert_eq!(RankTolerance::Absolute(1e-3).threshold(10, 3, 2.0), 1e-3);
    /// ```
    pub fn threshold(self, nrows: usize, ncols: usize, sigma_max: f64) -> f64 {
        match self {
            RankTolerance::Auto => nrows.max(ncols) as f64 * f64::EPSILON * sigma_max,
            RankTolerance::Relative(r) => r * sigma_max,
            RankTolerance::Absolute(t) => t,
        }
    }

    fn validate(self) -> Result<()> {
        let (name, v) = match self {
            RankTolerance::Auto => return Ok(()),
            RankTolerance::Relative(r) => ("RankTolerance::Relative", r),
            RankTolerance::Absolute(t) => ("RankTolerance::Absolute", t),
        };
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(LinalgError::InvalidParameter {
                name: name.into(),
                value: v.to_string(),
                expected: "a finite value ≥ 0".into(),
            })
        }
    }
}

// ---------------------------------------------------------------------------------------------
// input checks

fn check_nonempty(m: &DMat, what: &str) -> Result<()> {
    if m.nrows() == 0 || m.ncols() == 0 {
        return Err(LinalgError::Empty {
            what: what.into(),
            rows: m.nrows(),
            cols: m.ncols(),
        });
    }
    Ok(())
}

fn check_finite_mat(m: &DMat, what: &str) -> Result<()> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            let v = m[(i, j)];
            if !v.is_finite() {
                return Err(LinalgError::NonFinite {
                    what: what.into(),
                    row: i,
                    col: j,
                    value: v,
                });
            }
        }
    }
    Ok(())
}

fn check_finite_vec(v: &DVec, what: &str) -> Result<()> {
    for (i, &x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(LinalgError::NonFinite {
                what: what.into(),
                row: i,
                col: 0,
                value: x,
            });
        }
    }
    Ok(())
}

fn check_matrix(a: &DMat, what: &str) -> Result<()> {
    check_nonempty(a, what)?;
    check_finite_mat(a, what)
}

fn check_system(a: &DMat, b: &DVec) -> Result<()> {
    check_matrix(a, "design matrix A")?;
    if b.len() != a.nrows() {
        return Err(LinalgError::DimensionMismatch {
            what: "right-hand side b".into(),
            expected: format!("{} rows (the rows of A)", a.nrows()),
            found: format!("{} rows", b.len()),
        });
    }
    check_finite_vec(b, "right-hand side b")
}

fn default_names(n: usize) -> Vec<String> {
    (0..n).map(|j| format!("x[{j}]")).collect()
}

// ---------------------------------------------------------------------------------------------
// SVD

/// Singular value decomposition `A = U · diag(σ) · Vᵀ` of an `m × n` matrix.
///
/// `u` is `m × k` and `singular_values` has `k = min(m, n)` entries in non-increasing order; `v`
/// is the full `n × n` orthogonal matrix, so its columns `rank..n` span the null space even when
/// `m < n`.
#[derive(Debug, Clone, PartialEq)]
pub struct Svd {
    /// Left singular vectors, `m × min(m, n)`.
    pub u: DMat,
    /// Singular values σ₁ ≥ σ₂ ≥ … ≥ 0, `min(m, n)` of them.
    pub singular_values: DVec,
    /// Right singular vectors, `n × n`.
    pub v: DMat,
}

impl Svd {
    /// Decomposes `a` (faer's SVD on a zero-copy view).
    ///
    /// # Errors
    /// [`LinalgError::Empty`], [`LinalgError::NonFinite`] for bad input;
    /// [`LinalgError::NoConvergence`] if faer's SVD does not converge.
    ///
    /// # Example
    /// ```
    /// use mte_linalg::bridge::DMat;
    /// use mte_linalg::lstsq::Svd;
    /// let a = DMat::from_row_slice(2, 2, &[3.0, 0.0, 0.0, -4.0]);
    /// let s = Svd::new(&a)?;
    /// assert!((s.singular_values[0] - 4.0).abs() < 1e-14);
    /// assert!((s.singular_values[1] - 3.0).abs() < 1e-14);
    /// # Ok::<(), mte_linalg::LinalgError>(())
    /// ```
    pub fn new(a: &DMat) -> Result<Self> {
        check_matrix(a, "matrix")?;
        Self::new_unchecked(a)
    }

    fn new_unchecked(a: &DMat) -> Result<Self> {
        let (m, n) = a.shape();
        let k = m.min(n);
        let f = as_faer(a);
        let dec = if m >= n { f.thin_svd() } else { f.svd() };
        clean_vector_state();
        let dec = dec.map_err(|e| LinalgError::NoConvergence {
            what: format!("SVD of a {m} × {n} matrix ({e:?})"),
        })?;
        let u = faer_to_dmat(dec.U().subcols(0, k));
        let v = faer_to_dmat(dec.V());
        let s = dec.S().column_vector();
        let singular_values = DVec::from_fn(k, |i, _| *s.get(i));
        Ok(Self {
            u,
            singular_values,
            v,
        })
    }

    /// Number of rows `m` of the decomposed matrix.
    pub fn nrows(&self) -> usize {
        self.u.nrows()
    }

    /// Number of columns `n` of the decomposed matrix.
    pub fn ncols(&self) -> usize {
        self.v.nrows()
    }

    /// Largest singular value (0 for a zero matrix).
    pub fn sigma_max(&self) -> f64 {
        self.singular_values.iter().copied().fold(0.0, f64::max)
    }

    /// The threshold τ the tolerance gives for this matrix.
    pub fn threshold(&self, tol: RankTolerance) -> f64 {
        tol.threshold(self.nrows(), self.ncols(), self.sigma_max())
    }

    /// Numerical rank: the number of singular values `> τ`.
    ///
    /// # Example
    /// ```
    /// use mte_linalg::bridge::DMat;
    /// use mte_linalg::lstsq::{RankTolerance, Svd};
    /// // third column = first + second
    /// let a = DMat::from_row_slice(3, 3, &[1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 2.0]);
    /// assert_eq!(Svd::new(&a)?.rank(RankTolerance::Auto), 2);
    /// # Ok::<(), mte_linalg::LinalgError>(())
    /// ```
    pub fn rank(&self, tol: RankTolerance) -> usize {
        let t = self.threshold(tol);
        self.singular_values.iter().filter(|&&s| s > t).count()
    }

    /// Condition number σ_max / σ_min over all `min(m, n)` singular values; `f64::INFINITY` when
    /// σ_min is 0.
    pub fn condition_number(&self) -> f64 {
        let smax = self.sigma_max();
        let smin = self
            .singular_values
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        if smax == 0.0 || smin == 0.0 {
            f64::INFINITY
        } else {
            smax / smin
        }
    }

    /// Orthonormal basis of the numerical null space, `n × (n − rank)` (columns `rank..n` of V).
    pub fn null_space(&self, tol: RankTolerance) -> DMat {
        let r = self.rank(tol);
        self.v.columns(r, self.ncols() - r).into_owned()
    }

    /// Pseudo-inverse `A⁺ = V_r Σ_r⁻¹ U_rᵀ` keeping the singular values above τ.
    pub fn pinv(&self, tol: RankTolerance) -> DMat {
        let r = self.rank(tol);
        let mut vs = self.v.columns(0, r).into_owned();
        for j in 0..r {
            let s = self.singular_values[j];
            vs.column_mut(j).scale_mut(1.0 / s);
        }
        vs * self.u.columns(0, r).transpose()
    }

    /// `V_r Σ_r⁻¹ U_rᵀ b` for the first `r` singular triplets.
    fn apply_pinv(&self, r: usize, b: &DVec) -> DVec {
        let mut c = self.u.columns(0, r).tr_mul(b);
        for j in 0..r {
            c[j] /= self.singular_values[j];
        }
        self.v.columns(0, r) * c
    }

    /// `V_r Σ_r⁻² V_rᵀ`, the (pseudo-)inverse of `AᵀA`.
    fn inverse_normal(&self, r: usize) -> DMat {
        let mut vs = self.v.columns(0, r).into_owned();
        for j in 0..r {
            vs.column_mut(j).scale_mut(1.0 / self.singular_values[j]);
        }
        &vs * vs.transpose()
    }
}

/// Singular value decomposition of `a`; see [`Svd`].
///
/// # Errors
/// As [`Svd::new`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::DMat;
/// let a = DMat::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
/// let s = mte_linalg::lstsq::svd(&a)?;
/// let back = &s.u * DMat::from_diagonal(&s.singular_values) * s.v.transpose();
/// assert!((back - a).abs().max() < 1e-14);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn svd(a: &DMat) -> Result<Svd> {
    Svd::new(a)
}

/// Numerical rank of `a` with the tolerance `tol` (see the module docs).
///
/// # Errors
/// As [`Svd::new`]; [`LinalgError::InvalidParameter`] for a negative or non-finite tolerance.
///
/// # Example
/// ```
/// use mte_linalg::bridge::DMat;
/// use mte_linalg::lstsq::{numerical_rank, RankTolerance};
/// let a = DMat::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1e-9]);
/// assert_eq!(numerical_rank(&a, RankTolerance::Auto)?, 2);
/// assert_eq!(numerical_rank(&a, RankTolerance::Relative(1e-6))?, 1);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn numerical_rank(a: &DMat, tol: RankTolerance) -> Result<usize> {
    tol.validate()?;
    Ok(Svd::new(a)?.rank(tol))
}

/// Moore–Penrose pseudo-inverse of `a` (`n × m`), singular values `≤ τ` treated as zero.
///
/// # Errors
/// As [`numerical_rank`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::DMat;
/// use mte_linalg::lstsq::{pinv, RankTolerance};
/// let a = DMat::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
/// let p = pinv(&a, RankTolerance::Auto)?;
/// assert!((p - DMat::from_element(2, 2, 0.25)).abs().max() < 1e-15);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn pinv(a: &DMat, tol: RankTolerance) -> Result<DMat> {
    tol.validate()?;
    Ok(Svd::new(a)?.pinv(tol))
}

/// Orthonormal basis of the numerical null space of `a`: an `n × (n − rank)` matrix `N` with
/// `A N ≈ 0` and `Nᵀ N = I`.
///
/// # Errors
/// As [`numerical_rank`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::DMat;
/// use mte_linalg::lstsq::{null_space, RankTolerance};
/// let a = DMat::from_row_slice(1, 2, &[1.0, 1.0]);
/// let n = null_space(&a, RankTolerance::Auto)?;
/// assert_eq!(n.ncols(), 1);
/// assert!((n[(0, 0)] + n[(1, 0)]).abs() < 1e-15);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn null_space(a: &DMat, tol: RankTolerance) -> Result<DMat> {
    tol.validate()?;
    Ok(Svd::new(a)?.null_space(tol))
}

/// Least squares by thin Householder QR (faer): `x = R⁻¹ Qᵀ b` for a full-column-rank `A`, `m ≥ n`.
///
/// The fastest route when the design is known to be well posed. Rank deficiency is detected
/// from the diagonal of R (`|rᵢᵢ| ≤ max(m, n)·ε·max|rⱼⱼ|`) and confirmed by an SVD, which then
/// names the null-space combinations (unknowns called `x[j]`).
///
/// # Errors
/// [`LinalgError::Empty`], [`LinalgError::NonFinite`], [`LinalgError::DimensionMismatch`] for bad
/// input; [`LinalgError::TooFewRows`] if `m < n`; [`LinalgError::RankDeficient`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, DVec};
/// // fit y = c·t through (1, 2), (2, 4.2): c = (2 + 8.4) / 5
/// let a = DMat::from_row_slice(2, 1, &[1.0, 2.0]);
/// let b = DVec::from_vec(vec![2.0, 4.2]);
/// let x = mte_linalg::lstsq::lstsq_qr(&a, &b)?;
/// assert!((x[0] - 2.08).abs() < 1e-14);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn lstsq_qr(a: &DMat, b: &DVec) -> Result<DVec> {
    check_system(a, b)?;
    let (m, n) = a.shape();
    if m < n {
        return Err(LinalgError::TooFewRows { rows: m, needed: n });
    }
    let qr = as_faer(a).qr();
    clean_vector_state();
    let r = qr.thin_R();
    let diag_max = (0..n).map(|i| r.get(i, i).abs()).fold(0.0, f64::max);
    let tau = RankTolerance::Auto.threshold(m, n, diag_max);
    if diag_max == 0.0 || (0..n).any(|i| r.get(i, i).abs() <= tau) {
        let s = Svd::new_unchecked(a)?;
        let rank = s.rank(RankTolerance::Auto);
        if rank < n {
            let null = s.null_space(RankTolerance::Auto);
            return Err(rank_deficient(rank, n, &null, &default_names(n)));
        }
    }
    let x = qr.solve_lstsq(vec_as_faer(b));
    clean_vector_state();
    Ok(faer_col_to_dvec(x.as_ref()))
}

/// The triangular factor `R` (n × n) of the thin QR decomposition `A = Q R` of a tall `A`
/// (m ≥ n), by faer's blocked Householder QR, sequential (the same bits whatever the thread
/// count). Appending the right-hand side as a last column
/// gives `Qᵀb` in that column's top rows and the residual norm in its last entry, without
/// forming `Q`.
///
/// # Example
/// ```
/// use mte_linalg::bridge::DMat;
/// let a = DMat::from_row_slice(3, 2, &[3.0, 1.0, 4.0, 2.0, 0.0, 2.0]);
/// let r = mte_linalg::lstsq::qr_r(&a);
/// // RᵀR = AᵀA
/// assert!(((r.transpose() * &r) - a.transpose() * &a).norm() < 1e-12);
/// ```
pub fn qr_r(a: &DMat) -> DMat {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::qr::no_pivoting::factor;
    let (m, n) = a.shape();
    let size = m.min(n);
    if size == 0 {
        return DMat::zeros(0, n);
    }
    // Sequential: the same bits whatever the thread count (callers parallelise above it).
    let mut qr = a.clone();
    let block = factor::recommended_block_size::<f64>(m, n);
    let mut coeff = faer::Mat::<f64>::zeros(block, size);
    let scratch = factor::qr_in_place_scratch::<f64>(m, n, block, Par::Seq, Default::default());
    factor::qr_in_place(
        as_faer_mut(&mut qr),
        coeff.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    );
    clean_vector_state();
    DMat::from_fn(size, n, |i, j| if i <= j { qr[(i, j)] } else { 0.0 })
}

/// The inverse of a symmetric positive definite matrix by its Cholesky factor (faer's blocked
/// factorisation and triangular inverse, sequential: the same bits whatever the thread count);
/// `None` when a pivot is not positive (not positive definite to working precision). Only the
/// lower triangle of `a` is read.
///
/// # Example
/// ```
/// use mte_linalg::bridge::DMat;
/// let a = DMat::from_row_slice(2, 2, &[4.0, 2.0, 2.0, 3.0]);
/// let inv = mte_linalg::lstsq::spd_inverse(&a).unwrap();
/// assert!((&a * &inv - DMat::identity(2, 2)).norm() < 1e-14);
/// assert!(mte_linalg::lstsq::spd_inverse(&DMat::from_row_slice(1, 1, &[-1.0])).is_none());
/// ```
pub fn spd_inverse(a: &DMat) -> Option<DMat> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::{factor, inverse};
    let n = a.nrows();
    assert_eq!(n, a.ncols(), "spd_inverse: a square matrix");
    let mut l = a.clone();
    let factored = factor::cholesky_in_place(
        as_faer_mut(&mut l),
        Default::default(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(
            factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()),
        )),
        Default::default(),
    );
    let mut inv = DMat::zeros(n, n);
    if factored.is_ok() {
        inverse::inverse(
            as_faer_mut(&mut inv),
            as_faer(&l),
            Par::Seq,
            MemStack::new(&mut MemBuffer::new(inverse::inverse_scratch::<f64>(
                n,
                Par::Seq,
            ))),
        );
    }
    clean_vector_state();
    factored.ok()?;
    // The lower triangle holds the inverse: mirror it.
    for j in 0..n {
        for i in 0..j {
            inv[(i, j)] = inv[(j, i)];
        }
    }
    Some(inv)
}

/// Minimum-norm least squares `x = A⁺ b` (SVD): of all minimisers of ‖A x − b‖ the one with the
/// smallest ‖x‖. Works for any shape and rank.
///
/// # Errors
/// As [`lstsq_qr`] except that rank deficiency and `m < n` are allowed.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, DVec};
/// use mte_linalg::lstsq::{lstsq_min_norm, RankTolerance};
/// // x0 + x1 = 2 has the minimum-norm solution (1, 1)
/// let a = DMat::from_row_slice(1, 2, &[1.0, 1.0]);
/// let x = lstsq_min_norm(&a, &DVec::from_vec(vec![2.0]), RankTolerance::Auto)?;
/// assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn lstsq_min_norm(a: &DMat, b: &DVec, tol: RankTolerance) -> Result<DVec> {
    check_system(a, b)?;
    tol.validate()?;
    let s = Svd::new_unchecked(a)?;
    Ok(s.apply_pinv(s.rank(tol), b))
}

// ---------------------------------------------------------------------------------------------
// the fit

/// Observation weights.
#[derive(Debug, Clone, PartialEq)]
pub enum Weights {
    /// `W = diag(w)`, one positive weight per observation (typically `1/σᵢ²`).
    Diagonal(DVec),
    /// The observations' covariance matrix `Σ` (`m × m`, symmetric positive definite);
    /// `W = Σ⁻¹`, applied by Cholesky whitening `Σ = L Lᵀ`.
    Covariance(DMat),
}

/// What to do when the (weighted, constraint-reduced) design is rank deficient.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum RankDeficiency {
    /// Return [`LinalgError::RankDeficient`] naming the undetermined combinations.
    #[default]
    Error,
    /// Choose the solution of minimum ‖x‖ (or ‖x − x_p‖ under constraints, see [`Lstsq::constraints`]).
    MinimumNorm,
    /// Free-network datum: choose the solution minimising ‖x_S‖ over the chosen subset S of
    /// unknowns (indices). Null-space directions that do not touch S are resolved by minimum
    /// norm.
    MinimumNormSubset(Vec<usize>),
}

/// Least-squares problem parameters (builder); [`Lstsq::fit`] solves.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, DVec};
/// use mte_linalg::lstsq::{Lstsq, RankTolerance};
/// let a = DMat::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
/// let b = DVec::from_vec(vec![1.0, 2.0, 3.3]);
/// let fit = Lstsq::new().rank_tolerance(RankTolerance::Relative(1e-10)).fit(&a, &b)?;
/// assert_eq!(fit.rank, 2);
/// assert!(fit.sigma0.is_some());
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct Lstsq {
    weights: Option<Weights>,
    rank_tol: RankTolerance,
    policy: RankDeficiency,
    constraints: Option<(DMat, DVec)>,
    names: Option<Vec<String>>,
}

/// Result of [`Lstsq::fit`]: estimate, residuals and their statistics, covariance, diagnostics.
#[derive(Debug, Clone, PartialEq)]
pub struct LstsqFit {
    /// Estimated unknowns, `n`.
    pub x: DVec,
    /// Residuals `b − A x`, in the units of `b`, `m`.
    pub residuals: DVec,
    /// Whitened residuals `L⁻¹ (b − A x)` (equal to `residuals` without weights); each has
    /// variance ≈ σ0² for a correct model.
    pub weighted_residuals: DVec,
    /// Weighted residual sum of squares `(b − A x)ᵀ W (b − A x)`.
    pub rss: f64,
    /// Degrees of freedom `m − rank` (rank of the constraint-reduced design).
    pub dof: usize,
    /// A-posteriori standard deviation of unit weight `√(rss / dof)`; `None` when `dof = 0`.
    pub sigma0: Option<f64>,
    /// Cofactor matrix `Q` with `Cov(x) = σ0² Q`: `(AᵀWA)⁻¹` for a full-rank design, the
    /// matching generalised inverse (pseudo-inverse, constrained or datum version) otherwise.
    pub cofactor: DMat,
    /// `σ0² Q`; `None` when `dof = 0`.
    pub covariance: Option<DMat>,
    /// Numerical rank of the (whitened, constraint-reduced) design.
    pub rank: usize,
    /// Number of free unknowns: `n − rank(C)` with constraints, `n` without.
    pub n_free: usize,
    /// Singular values of the (whitened, constraint-reduced) design, non-increasing.
    pub singular_values: DVec,
    /// Orthonormal basis (`n × (n_free − rank)`) of the directions the data do not determine,
    /// in the space of the unknowns; empty for a full-rank problem.
    pub null_space: DMat,
}

/// The result type named in the workspace contract; the same as [`LstsqFit`].
pub type LstsqSolution = LstsqFit;

impl LstsqFit {
    /// Standard uncertainties `√diag(Cov(x))`; `None` when `dof = 0`.
    pub fn std_errors(&self) -> Option<DVec> {
        self.covariance
            .as_ref()
            .map(|c| DVec::from_fn(c.nrows(), |i, _| c[(i, i)].max(0.0).sqrt()))
    }

    /// Correlation matrix of the estimates from the cofactor matrix (`Qᵢⱼ / √(Qᵢᵢ Qⱼⱼ)`);
    /// entries of unknowns with zero variance are 0 (1 on the diagonal).
    pub fn correlation(&self) -> DMat {
        correlation_from(&self.cofactor)
    }
}

fn correlation_from(q: &DMat) -> DMat {
    let n = q.nrows();
    DMat::from_fn(n, n, |i, j| {
        if i == j {
            1.0
        } else {
            let d = q[(i, i)] * q[(j, j)];
            if d > 0.0 { q[(i, j)] / d.sqrt() } else { 0.0 }
        }
    })
}

impl Lstsq {
    /// Unweighted, unconstrained, rank deficiency is an error, default rank tolerance.
    pub fn new() -> Self {
        Self::default()
    }

    /// Observation weights (diagonal or full covariance).
    pub fn weights(mut self, w: Weights) -> Self {
        self.weights = Some(w);
        self
    }

    /// Rank tolerance (default [`RankTolerance::Auto`]).
    pub fn rank_tolerance(mut self, tol: RankTolerance) -> Self {
        self.rank_tol = tol;
        self
    }

    /// What to do with a rank-deficient design (default: error).
    pub fn rank_deficiency(mut self, policy: RankDeficiency) -> Self {
        self.policy = policy;
        self
    }

    /// Shorthand for `rank_deficiency(RankDeficiency::MinimumNorm)`.
    pub fn minimum_norm(self) -> Self {
        self.rank_deficiency(RankDeficiency::MinimumNorm)
    }

    /// Shorthand for `rank_deficiency(RankDeficiency::MinimumNormSubset(subset))`: the
    /// free-network datum on the unknowns `subset`.
    pub fn minimum_norm_on(self, subset: &[usize]) -> Self {
        self.rank_deficiency(RankDeficiency::MinimumNormSubset(subset.to_vec()))
    }

    /// Linear equality constraints `C x = d` (`C` is `p × n`), solved by the null-space
    /// method: `x = x_p + Z y` with `x_p = C⁺ d` and `Z` an orthonormal basis of null(C).
    /// Redundant (linearly dependent but consistent) constraint rows are allowed.
    pub fn constraints(mut self, c: DMat, d: DVec) -> Self {
        self.constraints = Some((c, d));
        self
    }

    /// Names of the unknowns, used in [`LinalgError::RankDeficient`] (default `x[j]`).
    pub fn column_names<S: Into<String>>(mut self, names: impl IntoIterator<Item = S>) -> Self {
        self.names = Some(names.into_iter().map(Into::into).collect());
        self
    }

    /// Solves `min (b − A x)ᵀ W (b − A x)` subject to the options.
    ///
    /// Steps: whiten with the weights; reduce to the free unknowns of the constraints; SVD of the
    /// reduced design; rank with the tolerance; solution by the pseudo-inverse of the retained
    /// singular triplets (identical to the normal-equation solution for a full-rank design) and,
    /// when rank deficient, the chosen datum. Every estimate is linear in `b`, `x = M b + c`, so
    /// its cofactor is `M W⁻¹ Mᵀ` exactly.
    ///
    /// # Errors
    /// * [`LinalgError::Empty`], [`LinalgError::NonFinite`], [`LinalgError::DimensionMismatch`]
    ///   for bad `a`, `b`, weights, constraints, names or subset indices (the message names which);
    /// * [`LinalgError::InvalidValue`] for a weight that is not positive;
    /// * [`LinalgError::NotPositiveDefinite`] for a covariance that is not SPD;
    /// * [`LinalgError::InconsistentConstraints`] when `C x = d` has no solution;
    /// * with [`RankDeficiency::Error`]: [`LinalgError::TooFewRows`] when there are fewer
    ///   observations than free unknowns, else [`LinalgError::RankDeficient`] naming the
    ///   combinations that cannot be told apart;
    /// * [`LinalgError::NoConvergence`] if an SVD fails.
    ///
    /// # Example
    /// ```
    /// use mte_linalg::bridge::{DMat, DVec};
    /// use mte_linalg::LinalgError;
    /// use mte_linalg::lstsq::Lstsq;
    /// // two unknowns that only ever appear as their sum
    /// let a = DMat::from_row_slice(3, 2, &[1.0, 1.0, 2.0, 2.0, 3.0, 3.0]);
    /// let b = DVec::from_vec(vec![1.0, 2.0, 3.0]);
    /// let err = Lstsq::new().column_names(["EX0B", "EX0C"]).fit(&a, &b).unwrap_err();
    /// match err {
    ///     LinalgError::RankDeficient { rank, expected, combinations } => {
    ///         assert_eq!((rank, expected), (1, 2));
    ///         assert_eq!(combinations, vec!["EX0B − 1.00·EX0C".to_string()]);
    ///     }
    ///     other => panic!("{other}"),
    /// }
    /// // with a datum: EX0C = 0 fixed by minimising |EX0C|
    /// let fit = Lstsq::new().minimum_norm_on(&[1]).fit(&a, &b)?;
    /// assert!((fit.x[0] - 1.0).abs() < 1e-12 && fit.x[1].abs() < 1e-12);
    /// # Ok::<(), LinalgError>(())
    /// ```
    pub fn fit(&self, a: &DMat, b: &DVec) -> Result<LstsqFit> {
        check_system(a, b)?;
        self.rank_tol.validate()?;
        let (m, n) = a.shape();
        let names = match &self.names {
            Some(names) if names.len() != n => {
                return Err(LinalgError::DimensionMismatch {
                    what: "column names".into(),
                    expected: format!("{n} names (the columns of A)"),
                    found: format!("{} names", names.len()),
                });
            }
            Some(names) => names.clone(),
            None => default_names(n),
        };

        // 1. whitening
        let whitener = Whitener::new(self.weights.as_ref(), m)?;
        let aw = whitener.apply_mat(a);
        let bw = whitener.apply_vec(b);

        // 2. constraints: x = x_p + Z y
        let (xp, z) = match &self.constraints {
            Some((c, d)) => {
                let (xp, z) = constraint_basis(c, d, n)?;
                (Some(xp), Some(z))
            }
            None => (None, None),
        };
        let n_free = z.as_ref().map_or(n, DMat::ncols);
        let ar = match &z {
            Some(z) => &aw * z,
            None => aw.clone(),
        };
        let br = match &xp {
            Some(xp) => &bw - &aw * xp,
            None => bw.clone(),
        };

        // 3. SVD of the reduced design and rank
        let (s, rank) = if n_free == 0 {
            (None, 0)
        } else {
            let s = Svd::new_unchecked(&ar)?;
            let r = s.rank(self.rank_tol);
            (Some(s), r)
        };
        let to_full = |v: DMat| -> DMat {
            match &z {
                Some(z) => z * v,
                None => v,
            }
        };
        let null_red = match &s {
            Some(s) => s.v.columns(rank, n_free - rank).into_owned(),
            None => DMat::zeros(0, 0),
        };
        let null_full = if n_free > rank {
            to_full(null_red.clone())
        } else {
            DMat::zeros(n, 0)
        };

        if rank < n_free && self.policy == RankDeficiency::Error {
            if m < n_free && self.constraints.is_none() {
                return Err(LinalgError::TooFewRows {
                    rows: m,
                    needed: n_free,
                });
            }
            return Err(rank_deficient(rank, n_free, &null_full, &names));
        }

        // 4. solution y (reduced unknowns) and its cofactor
        let (y, q_red) = match &s {
            None => (DVec::zeros(0), DMat::zeros(0, 0)),
            Some(s) => {
                let y0 = s.apply_pinv(rank, &br);
                let q0 = s.inverse_normal(rank);
                match (&self.policy, rank < n_free) {
                    (RankDeficiency::MinimumNormSubset(subset), true) => {
                        for &j in subset {
                            if j >= n {
                                return Err(LinalgError::DimensionMismatch {
                                    what: "datum subset index".into(),
                                    expected: format!("< {n} (the number of unknowns)"),
                                    found: j.to_string(),
                                });
                            }
                        }
                        // x_S(t) = S (x_p + Z (y0 + N t)); minimise over t
                        let sz = select_rows(&to_full(DMat::identity(n_free, n_free)), subset);
                        let szn = &sz * &null_red;
                        let g = if szn.nrows() == 0 {
                            DMat::zeros(null_red.ncols(), 0)
                        } else {
                            Svd::new_unchecked(&szn)?.pinv(RankTolerance::Auto)
                        };
                        let mut offset = &sz * &y0;
                        if let Some(xp) = &xp {
                            offset += select_rows_vec(xp, subset);
                        }
                        let t = -(&g * offset);
                        let y = &y0 + &null_red * t;
                        // y = P y0 + const with P = I − N G S Z
                        let p = DMat::identity(n_free, n_free) - &null_red * &g * &sz;
                        let q = &p * q0 * p.transpose();
                        (y, q)
                    }
                    _ => (y0, q0),
                }
            }
        };

        // 5. back to the full unknowns, residuals and statistics
        let mut x = to_full(DMat::from_column_slice(y.len(), 1, y.as_slice()))
            .column(0)
            .into_owned();
        if n_free == 0 {
            x = DVec::zeros(n);
        }
        if let Some(xp) = &xp {
            x += xp;
        }
        let cofactor = match &z {
            Some(z) => z * q_red * z.transpose(),
            None => q_red,
        };
        let cofactor = if cofactor.nrows() == n {
            cofactor
        } else {
            DMat::zeros(n, n)
        };
        let residuals = b - a * &x;
        let weighted_residuals = whitener.apply_vec(&residuals);
        let rss = weighted_residuals.norm_squared();
        let dof = m.saturating_sub(rank);
        let sigma0 = (dof > 0).then(|| (rss / dof as f64).sqrt());
        let covariance = sigma0.map(|s0| &cofactor * (s0 * s0));
        let singular_values = s
            .as_ref()
            .map_or_else(|| DVec::zeros(0), |s| s.singular_values.clone());
        Ok(LstsqFit {
            x,
            residuals,
            weighted_residuals,
            rss,
            dof,
            sigma0,
            cofactor,
            covariance,
            rank,
            n_free,
            singular_values,
            null_space: null_full,
        })
    }
}

fn select_rows(m: &DMat, rows: &[usize]) -> DMat {
    DMat::from_fn(rows.len(), m.ncols(), |i, j| m[(rows[i], j)])
}

fn select_rows_vec(v: &DVec, rows: &[usize]) -> DVec {
    DVec::from_fn(rows.len(), |i, _| v[rows[i]])
}

/// `x_p = C⁺ d` and `Z` = orthonormal basis of null(C), after checking consistency.
fn constraint_basis(c: &DMat, d: &DVec, n: usize) -> Result<(DVec, DMat)> {
    check_matrix(c, "constraint matrix C")?;
    if c.ncols() != n {
        return Err(LinalgError::DimensionMismatch {
            what: "constraint matrix C".into(),
            expected: format!("{n} columns (the columns of A)"),
            found: format!("{} columns", c.ncols()),
        });
    }
    if d.len() != c.nrows() {
        return Err(LinalgError::DimensionMismatch {
            what: "constraint right-hand side d".into(),
            expected: format!("{} rows (the rows of C)", c.nrows()),
            found: format!("{} rows", d.len()),
        });
    }
    check_finite_vec(d, "constraint right-hand side d")?;
    let s = Svd::new_unchecked(c)?;
    let rc = s.rank(RankTolerance::Auto);
    let xp = s.apply_pinv(rc, d);
    let residual = (c * &xp - d).norm();
    // consistent constraints leave only rounding: allow a few hundred ulps of the data scale
    let tolerance = 1e3 * f64::EPSILON * (c.norm() * xp.norm() + d.norm()).max(f64::MIN_POSITIVE);
    if residual > tolerance {
        return Err(LinalgError::InconsistentConstraints {
            residual,
            tolerance,
        });
    }
    Ok((xp, s.v.columns(rc, n - rc).into_owned()))
}

/// `L⁻¹` applied to rows, from the weights.
enum Whitener {
    None,
    Diagonal(DVec),
    Cholesky(faer::Mat<f64>),
}

impl Whitener {
    fn new(w: Option<&Weights>, m: usize) -> Result<Self> {
        match w {
            None => Ok(Whitener::None),
            Some(Weights::Diagonal(w)) => {
                if w.len() != m {
                    return Err(LinalgError::DimensionMismatch {
                        what: "diagonal weights".into(),
                        expected: format!("{m} weights (the rows of A)"),
                        found: format!("{} weights", w.len()),
                    });
                }
                check_finite_vec(w, "diagonal weights")?;
                if let Some((i, &v)) = w.iter().enumerate().find(|(_, v)| **v <= 0.0) {
                    return Err(LinalgError::InvalidValue {
                        what: "diagonal weights".into(),
                        index: i,
                        value: v,
                        expected: "a positive weight".into(),
                    });
                }
                Ok(Whitener::Diagonal(w.map(f64::sqrt)))
            }
            Some(Weights::Covariance(cov)) => {
                if cov.shape() != (m, m) {
                    return Err(LinalgError::DimensionMismatch {
                        what: "observation covariance".into(),
                        expected: format!("{m} × {m}"),
                        found: format!("{} × {}", cov.nrows(), cov.ncols()),
                    });
                }
                check_finite_mat(cov, "observation covariance")?;
                let scale = cov.abs().max();
                for j in 0..m {
                    for i in (j + 1)..m {
                        if (cov[(i, j)] - cov[(j, i)]).abs() > 1e-10 * scale {
                            return Err(LinalgError::NotPositiveDefinite {
                                what: "observation covariance".into(),
                                detail: format!(
                                    "not symmetric: entry ({i}, {j}) = {} but ({j}, {i}) = {}",
                                    cov[(i, j)],
                                    cov[(j, i)]
                                ),
                            });
                        }
                    }
                }
                let llt = as_faer(cov).llt(faer::Side::Lower);
                clean_vector_state();
                let llt = llt.map_err(|e| LinalgError::NotPositiveDefinite {
                    what: "observation covariance".into(),
                    detail: format!("Cholesky factorisation failed ({e:?})"),
                })?;
                Ok(Whitener::Cholesky(llt.L().to_owned()))
            }
        }
    }

    fn apply_mat(&self, a: &DMat) -> DMat {
        match self {
            Whitener::None => a.clone(),
            Whitener::Diagonal(s) => {
                let mut out = a.clone();
                for (i, mut row) in out.row_iter_mut().enumerate() {
                    row *= s[i];
                }
                out
            }
            Whitener::Cholesky(l) => {
                let mut out = a.clone();
                l.as_ref()
                    .solve_lower_triangular_in_place(crate::bridge::as_faer_mut(&mut out));
                clean_vector_state();
                out
            }
        }
    }

    fn apply_vec(&self, b: &DVec) -> DVec {
        let m = DMat::from_column_slice(b.len(), 1, b.as_slice());
        self.apply_mat(&m).column(0).into_owned()
    }
}

/// Least squares `min ‖A x − b‖` with full diagnostics; rank deficiency is an error naming the
/// undetermined combinations of `x[j]`. Same as `Lstsq::new().fit(a, b)`.
///
/// # Errors
/// As [`Lstsq::fit`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, DVec};
/// let a = DMat::from_row_slice(3, 1, &[1.0, 1.0, 1.0]);
/// let fit = mte_linalg::lstsq::lstsq(&a, &DVec::from_vec(vec![1.0, 2.0, 6.0]))?;
/// assert!((fit.x[0] - 3.0).abs() < 1e-14);      // the mean
/// assert!((fit.rss - 14.0).abs() < 1e-12);      // 4 + 1 + 9
/// assert!((fit.sigma0.unwrap() - 7f64.sqrt()).abs() < 1e-12);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn lstsq(a: &DMat, b: &DVec) -> Result<LstsqFit> {
    Lstsq::new().fit(a, b)
}

/// Weighted least squares `min (b − A x)ᵀ W (b − A x)`. Same as
/// `Lstsq::new().weights(weights.clone()).fit(a, b)`.
///
/// # Errors
/// As [`Lstsq::fit`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, DVec};
/// use mte_linalg::lstsq::{weighted_lstsq, Weights};
/// // weighted mean of 1 (weight 3) and 5 (weight 1) = 2
/// let a = DMat::from_element(2, 1, 1.0);
/// let w = Weights::Diagonal(DVec::from_vec(vec![3.0, 1.0]));
/// let fit = weighted_lstsq(&a, &DVec::from_vec(vec![1.0, 5.0]), &w)?;
/// assert!((fit.x[0] - 2.0).abs() < 1e-14);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn weighted_lstsq(a: &DMat, b: &DVec, weights: &Weights) -> Result<LstsqFit> {
    Lstsq::new().weights(weights.clone()).fit(a, b)
}

/// Least squares subject to `C x = d`. Same as `Lstsq::new().constraints(c, d).fit(a, b)`.
///
/// # Errors
/// As [`Lstsq::fit`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, DVec};
/// // observe x0 = 1, x1 = 3 with x0 + x1 = 2 imposed: x = (0, 2)
/// let a = DMat::identity(2, 2);
/// let c = DMat::from_row_slice(1, 2, &[1.0, 1.0]);
/// let fit = mte_linalg::lstsq::lstsq_constrained(
///     &a, &DVec::from_vec(vec![1.0, 3.0]), &c, &DVec::from_vec(vec![2.0]))?;
/// assert!((fit.x[0] - 0.0).abs() < 1e-14 && (fit.x[1] - 2.0).abs() < 1e-14);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn lstsq_constrained(a: &DMat, b: &DVec, c: &DMat, d: &DVec) -> Result<LstsqFit> {
    Lstsq::new().constraints(c.clone(), d.clone()).fit(a, b)
}

/// Rank-deficient least squares with a free-network datum: of all minimisers of ‖A x − b‖, the
/// one with the smallest ‖x_S‖ for the unknowns `subset`. Same as
/// `Lstsq::new().rank_tolerance(tol).minimum_norm_on(subset).fit(a, b)`.
///
/// # Errors
/// As [`Lstsq::fit`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, DVec};
/// use mte_linalg::lstsq::{lstsq_min_norm_subset, RankTolerance};
/// // levelling: only height differences observed; datum = mean of points 0 and 1 is zero
/// let a = DMat::from_row_slice(2, 3, &[-1.0, 1.0, 0.0, 0.0, -1.0, 1.0]);
/// let b = DVec::from_vec(vec![2.0, 1.0]);
/// let fit = lstsq_min_norm_subset(&a, &b, &[0, 1], RankTolerance::Auto)?;
/// assert!((fit.x[0] + 1.0).abs() < 1e-12 && (fit.x[1] - 1.0).abs() < 1e-12);
/// assert!((fit.x[2] - 2.0).abs() < 1e-12);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn lstsq_min_norm_subset(
    a: &DMat,
    b: &DVec,
    subset: &[usize],
    tol: RankTolerance,
) -> Result<LstsqFit> {
    Lstsq::new()
        .rank_tolerance(tol)
        .minimum_norm_on(subset)
        .fit(a, b)
}

// ---------------------------------------------------------------------------------------------
// identifiability

/// One direction in parameter space the data cannot see, written with the parameter names.
///
/// Moving the unknowns by `t · Σ cⱼ eⱼ` for any `t` leaves every prediction `A x` unchanged, so
/// e.g. `"EX0B − 1.00·EX0C"` means EX0B and EX0C can only be estimated as their sum.
#[derive(Debug, Clone, PartialEq)]
pub struct NullCombination {
    /// `(name, coefficient)`, the leading parameter first with coefficient 1; coefficients below
    /// [`COEFFICIENT_TOLERANCE`] are omitted.
    pub terms: Vec<(String, f64)>,
    /// The same as text, e.g. `"EX0B − 1.00·EX0C"`.
    pub text: String,
}

/// Two estimated parameters whose estimates are nearly collinear.
#[derive(Debug, Clone, PartialEq)]
pub struct CorrelatedPair {
    /// First parameter name.
    pub first: String,
    /// Second parameter name.
    pub second: String,
    /// Correlation of the two estimates (`Qᵢⱼ / √(Qᵢᵢ Qⱼⱼ)`, `Q = (AᵀA)⁺`).
    pub correlation: f64,
}

/// What a design matrix can and cannot determine; see [`identifiability`].
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiabilityReport {
    /// Parameter (column) names.
    pub names: Vec<String>,
    /// Numerical rank.
    pub rank: usize,
    /// The threshold τ used for the rank.
    pub tolerance: f64,
    /// Singular values, non-increasing.
    pub singular_values: DVec,
    /// σ_max / σ_min (`f64::INFINITY` when σ_min = 0).
    pub condition_number: f64,
    /// Null-space directions as named combinations, in reduced echelon form (each has a leading
    /// parameter that appears in no other combination).
    pub combinations: Vec<NullCombination>,
    /// Per parameter: determined by the data (its unit vector is orthogonal to the null space).
    pub identifiable: Vec<bool>,
    /// Uncentred variance inflation factors `VIFⱼ = ‖aⱼ‖² · [(AᵀA)⁺]ⱼⱼ = 1 / (1 − Rⱼ²)` with
    /// `Rⱼ²` of regressing column j on the others through the origin; `f64::INFINITY` for
    /// non-identifiable parameters. Values above ~10 flag collinearity.
    pub vif: Vec<f64>,
    /// Identifiable parameter pairs with |correlation of the estimates| > [`CORRELATION_THRESHOLD`],
    /// largest first.
    pub correlated_pairs: Vec<CorrelatedPair>,
}

impl IdentifiabilityReport {
    /// `true` when every parameter is determined (full column rank).
    pub fn is_identifiable(&self) -> bool {
        self.combinations.is_empty()
    }

    /// The combinations as text.
    pub fn combination_strings(&self) -> Vec<String> {
        self.combinations.iter().map(|c| c.text.clone()).collect()
    }
}

/// Identifiability of the parameters of a linear(ised) design `A` with named columns: rank,
/// null-space combinations, condition number, variance inflation factors and strongly
/// correlated pairs.
///
/// # Errors
/// [`LinalgError::Empty`], [`LinalgError::NonFinite`] for a bad `a`;
/// [`LinalgError::DimensionMismatch`] when `names.len() != a.ncols()`;
/// [`LinalgError::InvalidParameter`] for a bad tolerance; [`LinalgError::NoConvergence`].
///
/// # Example
/// ```
/// use mte_linalg::bridge::DMat;
/// use mte_linalg::lstsq::{identifiability, RankTolerance};
/// // columns: EX0B, EX0C identical, EY0C independent
/// let a = DMat::from_row_slice(3, 3, &[1.0, 1.0, 0.0, 2.0, 2.0, 1.0, 0.0, 0.0, 1.0]);
/// let rep = identifiability(&a, &["EX0B", "EX0C", "EY0C"], RankTolerance::Auto)?;
/// assert_eq!(rep.rank, 2);
/// assert_eq!(rep.combination_strings(), vec!["EX0B − 1.00·EX0C"]);
/// assert_eq!(rep.identifiable, vec![false, false, true]);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn identifiability<S: AsRef<str>>(
    a: &DMat,
    names: &[S],
    tol: RankTolerance,
) -> Result<IdentifiabilityReport> {
    check_matrix(a, "design matrix A")?;
    tol.validate()?;
    let n = a.ncols();
    if names.len() != n {
        return Err(LinalgError::DimensionMismatch {
            what: "parameter names".into(),
            expected: format!("{n} names (the columns of A)"),
            found: format!("{} names", names.len()),
        });
    }
    let names: Vec<String> = names.iter().map(|s| s.as_ref().to_string()).collect();
    let s = Svd::new_unchecked(a)?;
    let rank = s.rank(tol);
    let null = s.null_space(tol);
    let combinations = null_combinations(&null, &names);
    let identifiable: Vec<bool> = (0..n)
        .map(|j| null.row(j).norm() < COEFFICIENT_TOLERANCE)
        .collect();
    let q = s.inverse_normal(rank);
    let vif: Vec<f64> = (0..n)
        .map(|j| {
            if identifiable[j] {
                a.column(j).norm_squared() * q[(j, j)]
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let corr = correlation_from(&q);
    let mut correlated_pairs = Vec::new();
    for i in 0..n {
        for j in (i + 1)..n {
            if identifiable[i] && identifiable[j] && corr[(i, j)].abs() > CORRELATION_THRESHOLD {
                correlated_pairs.push(CorrelatedPair {
                    first: names[i].clone(),
                    second: names[j].clone(),
                    correlation: corr[(i, j)],
                });
            }
        }
    }
    correlated_pairs.sort_by(|x, y| y.correlation.abs().total_cmp(&x.correlation.abs()));
    Ok(IdentifiabilityReport {
        names,
        rank,
        tolerance: s.threshold(tol),
        singular_values: s.singular_values.clone(),
        condition_number: s.condition_number(),
        combinations,
        identifiable,
        vif,
        correlated_pairs,
    })
}

fn rank_deficient(rank: usize, expected: usize, null: &DMat, names: &[String]) -> LinalgError {
    LinalgError::RankDeficient {
        rank,
        expected,
        combinations: null_combinations(null, names)
            .into_iter()
            .map(|c| c.text)
            .collect(),
    }
}

/// Reduced row-echelon form of `Nᵀ` with full pivoting: each null direction gets a leading
/// parameter (coefficient 1) absent from the other directions.
fn null_combinations(null: &DMat, names: &[String]) -> Vec<NullCombination> {
    let k = null.ncols();
    let n = null.nrows();
    if k == 0 {
        return Vec::new();
    }
    let mut r = null.transpose(); // k × n
    let mut pivots: Vec<usize> = Vec::with_capacity(k);
    for i in 0..k {
        let mut best = (i, 0usize, 0.0f64);
        for row in i..k {
            for col in 0..n {
                if pivots.contains(&col) {
                    continue;
                }
                let v = r[(row, col)].abs();
                if v > best.2 {
                    best = (row, col, v);
                }
            }
        }
        if best.2 <= f64::EPSILON {
            break;
        }
        let (p, q, _) = best;
        r.swap_rows(i, p);
        let piv = r[(i, q)];
        r.row_mut(i).scale_mut(1.0 / piv);
        for row in 0..k {
            if row != i {
                let f = r[(row, q)];
                if f != 0.0 {
                    let ri = r.row(i).into_owned();
                    let mut target = r.row_mut(row);
                    target -= ri * f;
                }
            }
        }
        pivots.push(q);
    }
    pivots
        .iter()
        .enumerate()
        .map(|(i, &q)| {
            let mut terms = vec![(names[q].clone(), 1.0)];
            for col in 0..n {
                let c = r[(i, col)];
                if col != q && c.abs() >= COEFFICIENT_TOLERANCE {
                    terms.push((names[col].clone(), c));
                }
            }
            let mut text = names[q].clone();
            for (name, c) in &terms[1..] {
                let sign = if *c < 0.0 { " − " } else { " + " };
                text.push_str(&format!("{sign}{}·{name}", format_coefficient(c.abs())));
            }
            NullCombination { terms, text }
        })
        .collect()
}

fn format_coefficient(a: f64) -> String {
    if (0.01..1000.0).contains(&a) {
        format!("{a:.2}")
    } else {
        format!("{a:.2e}")
    }
}

#[cfg(test)]
mod tests;
