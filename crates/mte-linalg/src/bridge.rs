//! The one place where nalgebra and faer meet.
//!
//! nalgebra's dynamic matrices ([`DMat`], [`DVec`]) store their entries column-major in one
//! contiguous buffer, which is exactly the layout of a faer view with row stride 1 and column
//! stride `nrows`. So:
//!
//! * **nalgebra → faer, zero copy:** [`as_faer`], [`as_faer_mut`], [`vec_as_faer`],
//!   [`vec_as_faer_mut`] borrow the nalgebra buffer as a faer view. A faer routine writing into
//!   [`as_faer_mut`] writes straight into the nalgebra matrix — this is how faer results land in
//!   nalgebra storage without a copy.
//! * **faer → nalgebra, zero copy:** [`faer_col_as_nalgebra`] and [`faer_col_as_nalgebra_mut`]
//!   borrow a contiguous faer column as a nalgebra vector view; [`faer_mat_col_as_nalgebra`]
//!   does the same for column `j` of a faer matrix view. faer's safe API exposes contiguous memory
//!   one column at a time only (its owned matrices pad the column stride), and this workspace
//!   forbids `unsafe`, so a whole faer matrix becomes a nalgebra matrix by copy:
//! * **owned conversions (copy):** [`faer_to_dmat`], [`dmat_to_faer`], [`faer_col_to_dvec`],
//!   [`dvec_to_faer_col`].

use crate::error::{LinalgError, Result};
use faer::{ColMut, ColRef, MatMut, MatRef};
use nalgebra::{DMatrix, DVector, DVectorView, DVectorViewMut};

/// Dynamic nalgebra matrix of `f64` (same as the crate-wide alias `DMat`).
pub type DMat = DMatrix<f64>;
/// Dynamic nalgebra vector of `f64` (same as the crate-wide alias `DVec`).
pub type DVec = DVector<f64>;

/// Borrows a nalgebra matrix as a faer view, without copying.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{as_faer, DMat};
/// let a = DMat::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
/// let v = as_faer(&a);
/// assert_eq!((v.nrows(), v.ncols()), (2, 3));
/// assert_eq!(*v.get(1, 2), 6.0);
/// // the same memory:
/// assert!(std::ptr::eq(v.get(0, 0), &a[(0, 0)]));
/// ```
pub fn as_faer(m: &DMat) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(m.as_slice(), m.nrows(), m.ncols())
}

/// Borrows a nalgebra matrix mutably as a faer view, without copying; faer writes land in `m`.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{as_faer_mut, DMat};
/// let mut a = DMat::zeros(2, 2);
/// as_faer_mut(&mut a).fill(3.0);
/// assert_eq!(a, DMat::from_element(2, 2, 3.0));
/// ```
pub fn as_faer_mut(m: &mut DMat) -> MatMut<'_, f64> {
    let (r, c) = m.shape();
    MatMut::from_column_major_slice_mut(m.as_mut_slice(), r, c)
}

/// Borrows a nalgebra vector as a faer column view, without copying.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{vec_as_faer, DVec};
/// let b = DVec::from_vec(vec![1.0, 2.0, 3.0]);
/// let c = vec_as_faer(&b);
/// assert_eq!(c.nrows(), 3);
/// assert_eq!(*c.get(2), 3.0);
/// ```
pub fn vec_as_faer(v: &DVec) -> ColRef<'_, f64> {
    ColRef::from_slice(v.as_slice())
}

/// Borrows a nalgebra vector mutably as a faer column view, without copying.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{vec_as_faer_mut, DVec};
/// let mut b = DVec::zeros(3);
/// vec_as_faer_mut(&mut b).fill(2.0);
/// assert_eq!(b.sum(), 6.0);
/// ```
pub fn vec_as_faer_mut(v: &mut DVec) -> ColMut<'_, f64> {
    ColMut::from_slice_mut(v.as_mut_slice())
}

/// Borrows a faer column as a nalgebra vector view, without copying.
///
/// # Errors
/// [`LinalgError::NotContiguous`] if the column's row stride is not 1 (e.g. a row of a
/// column-major matrix viewed as a column).
///
/// # Example
/// ```
/// use mte_linalg::bridge::faer_col_as_nalgebra;
/// let c = faer::col![1.0, 2.0, 3.0];
/// let v = faer_col_as_nalgebra(c.as_ref())?;
/// assert_eq!(v[1], 2.0);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn faer_col_as_nalgebra(c: ColRef<'_, f64>) -> Result<DVectorView<'_, f64>> {
    let stride = c.row_stride();
    match c.try_as_col_major() {
        Some(cc) => Ok(DVectorView::from_slice(cc.as_slice(), c.nrows())),
        None => Err(LinalgError::NotContiguous {
            what: "faer column".into(),
            detail: format!("row stride {stride}, expected 1"),
        }),
    }
}

/// Borrows a faer column mutably as a nalgebra vector view, without copying.
///
/// # Errors
/// [`LinalgError::NotContiguous`] if the column's row stride is not 1.
///
/// # Example
/// ```
/// use mte_linalg::bridge::faer_col_as_nalgebra_mut;
/// let mut c = faer::Col::<f64>::zeros(3);
/// faer_col_as_nalgebra_mut(c.as_mut())?.fill(1.5);
/// assert_eq!(c[2], 1.5);
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn faer_col_as_nalgebra_mut(c: ColMut<'_, f64>) -> Result<DVectorViewMut<'_, f64>> {
    let stride = c.row_stride();
    let n = c.nrows();
    match c.try_as_col_major_mut() {
        Some(cc) => Ok(DVectorViewMut::from_slice(cc.as_slice_mut(), n)),
        None => Err(LinalgError::NotContiguous {
            what: "faer column".into(),
            detail: format!("row stride {stride}, expected 1"),
        }),
    }
}

/// Borrows column `j` of a faer matrix view as a nalgebra vector view, without copying.
///
/// # Errors
/// [`LinalgError::DimensionMismatch`] if `j` is out of range; [`LinalgError::NotContiguous`] if
/// the matrix is not column-major (row stride ≠ 1).
///
/// # Example
/// ```
/// use mte_linalg::bridge::faer_mat_col_as_nalgebra;
/// let m = faer::mat![[1.0, 2.0], [3.0, 4.0]];
/// let c1 = faer_mat_col_as_nalgebra(m.as_ref(), 1)?;
/// assert_eq!((c1[0], c1[1]), (2.0, 4.0));
/// # Ok::<(), mte_linalg::LinalgError>(())
/// ```
pub fn faer_mat_col_as_nalgebra(m: MatRef<'_, f64>, j: usize) -> Result<DVectorView<'_, f64>> {
    if j >= m.ncols() {
        return Err(LinalgError::DimensionMismatch {
            what: "column index".into(),
            expected: format!("< {}", m.ncols()),
            found: j.to_string(),
        });
    }
    faer_col_as_nalgebra(m.col(j))
}

/// Copies a faer matrix view (any strides) into a new nalgebra matrix.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{faer_to_dmat, DMat};
/// let m = faer::mat![[1.0, 2.0], [3.0, 4.0]];
/// assert_eq!(faer_to_dmat(m.as_ref()), DMat::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]));
/// ```
pub fn faer_to_dmat(m: MatRef<'_, f64>) -> DMat {
    DMat::from_fn(m.nrows(), m.ncols(), |i, j| *m.get(i, j))
}

/// Copies a nalgebra matrix into a new faer matrix.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{dmat_to_faer, DMat};
/// let a = DMat::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]);
/// assert_eq!(dmat_to_faer(&a), faer::mat![[1.0, 2.0], [3.0, 4.0]]);
/// ```
pub fn dmat_to_faer(m: &DMat) -> faer::Mat<f64> {
    as_faer(m).to_owned()
}

/// Copies a faer column view (any stride) into a new nalgebra vector.
///
/// # Example
/// ```
/// use mte_linalg::bridge::faer_col_to_dvec;
/// let c = faer::col![1.0, 2.0];
/// assert_eq!(faer_col_to_dvec(c.as_ref()).as_slice(), &[1.0, 2.0]);
/// ```
pub fn faer_col_to_dvec(c: ColRef<'_, f64>) -> DVec {
    DVec::from_fn(c.nrows(), |i, _| *c.get(i))
}

/// Copies a nalgebra vector into a new faer column.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{dvec_to_faer_col, DVec};
/// let v = DVec::from_vec(vec![1.0, 2.0]);
/// assert_eq!(dvec_to_faer_col(&v), faer::col![1.0, 2.0]);
/// ```
pub fn dvec_to_faer_col(v: &DVec) -> faer::Col<f64> {
    vec_as_faer(v).to_owned()
}

/// The product `a b` by faer, sequential (the same bits whatever the thread count; callers
/// parallelise above it), into a new nalgebra matrix.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, as_faer, product};
/// let a = DMat::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
/// let p = product(as_faer(&a).transpose(), as_faer(&a));
/// assert_eq!(p, a.transpose() * &a);
/// ```
pub fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> DMat {
    let mut out = DMat::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(
        as_faer_mut(&mut out),
        faer::Accum::Replace,
        a,
        b,
        1.0,
        faer::Par::Seq,
    );
    clean_vector_state();
    out
}

/// The Gram matrix `aᵀ a` by faer, sequential like [`product`]: only its lower triangle is
/// computed (half the work of the full product) and mirrored, so it is exactly symmetric.
///
/// # Example
/// ```
/// use mte_linalg::bridge::{DMat, as_faer, gram};
/// let a = DMat::from_row_slice(3, 2, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
/// assert_eq!(gram(as_faer(&a)), a.transpose() * &a);
/// ```
pub fn gram(a: MatRef<'_, f64>) -> DMat {
    use faer::linalg::matmul::triangular::{BlockStructure, matmul};
    let k = a.ncols();
    let mut out = DMat::zeros(k, k);
    matmul(
        as_faer_mut(&mut out),
        BlockStructure::TriangularLower,
        faer::Accum::Replace,
        a.transpose(),
        BlockStructure::Rectangular,
        a,
        BlockStructure::Rectangular,
        1.0,
        faer::Par::Seq,
    );
    clean_vector_state();
    for j in 0..k {
        for i in 0..j {
            out[(i, j)] = out[(j, i)];
        }
    }
    out
}

/// Leaves the vector registers as compiled code expects them after a faer kernel.
///
/// faer's matrix kernels (the `gemm` crate's AVX-512 micro-kernels) return with the upper halves
/// of the vector registers dirty (no `vzeroupper`). Until something clears them, every
/// SSE-encoded instruction that follows — the scalar floating-point code of this workspace,
/// built for baseline x86-64 — pays a transition penalty: sin/cos loops ran 12× slower after
/// one product on this project's machine (Xeon, AVX-512). Every faer call of the workspace
/// ([`product`], the QR, SVD and Cholesky routines of `lstsq`, the pose model, PCE) is followed
/// by this; it issues `vzeroupper` through pulp's safe wrapper where the CPU has AVX, and does
/// nothing elsewhere.
pub fn clean_vector_state() {
    #[cfg(target_arch = "x86_64")]
    if let Some(avx) = pulp::core_arch::x86::Avx::try_new() {
        avx._mm256_zeroupper();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(m: usize, n: usize) -> DMat {
        DMat::from_fn(m, n, |i, j| (i * 10 + j) as f64 + 0.25)
    }

    #[test]
    fn nalgebra_to_faer_view_shares_memory_and_entries() {
        let a = sample(4, 3);
        let v = as_faer(&a);
        for i in 0..4 {
            for j in 0..3 {
                assert_eq!(*v.get(i, j), a[(i, j)]);
                assert!(std::ptr::eq(v.get(i, j), &a[(i, j)]));
            }
        }
    }

    #[test]
    fn faer_writes_land_in_nalgebra_storage() {
        // product computed by faer directly into nalgebra memory, compared with nalgebra's product
        let a = sample(3, 4);
        let b = sample(4, 2);
        let mut c = DMat::zeros(3, 2);
        faer::linalg::matmul::matmul(
            as_faer_mut(&mut c),
            faer::Accum::Replace,
            as_faer(&a),
            as_faer(&b),
            1.0,
            faer::Par::Seq,
        );
        let expected = &a * &b;
        assert_eq!(c, expected);
    }

    #[test]
    fn round_trips_are_exact() {
        let a = sample(5, 2);
        assert_eq!(faer_to_dmat(dmat_to_faer(&a).as_ref()), a);
        assert_eq!(faer_to_dmat(as_faer(&a)), a);
        let v = DVec::from_fn(6, |i, _| i as f64 * 1.5 - 2.0);
        assert_eq!(faer_col_to_dvec(dvec_to_faer_col(&v).as_ref()), v);
        let fc = dvec_to_faer_col(&v);
        let back = faer_col_as_nalgebra(fc.as_ref()).unwrap();
        assert_eq!(back.into_owned(), v);
        assert!(std::ptr::eq(&back[0], fc.get(0)));
        // strided faer views copy correctly: the transpose of a column-major matrix
        let t = faer_to_dmat(as_faer(&a).transpose());
        assert_eq!(t, a.transpose());
    }

    #[test]
    fn faer_matrix_columns_view_without_copy() {
        let f = dmat_to_faer(&sample(3, 3));
        for j in 0..3 {
            let c = faer_mat_col_as_nalgebra(f.as_ref(), j).unwrap();
            for i in 0..3 {
                assert!(std::ptr::eq(&c[i], f.get(i, j)));
            }
        }
        assert!(matches!(
            faer_mat_col_as_nalgebra(f.as_ref(), 3),
            Err(LinalgError::DimensionMismatch { .. })
        ));
        // a row of a column-major matrix is strided: no zero-copy view
        let row_as_col = f.as_ref().row(0).transpose();
        assert!(matches!(
            faer_col_as_nalgebra(row_as_col),
            Err(LinalgError::NotContiguous { .. })
        ));
    }

    #[test]
    fn mutable_views_both_ways() {
        let mut v = DVec::zeros(3);
        vec_as_faer_mut(&mut v).copy_from(faer::col![1.0, 2.0, 3.0]);
        assert_eq!(v.as_slice(), &[1.0, 2.0, 3.0]);
        let mut c = faer::Col::<f64>::zeros(2);
        faer_col_as_nalgebra_mut(c.as_mut()).unwrap()[1] = 7.0;
        assert_eq!(*c.get(1), 7.0);
    }
}
