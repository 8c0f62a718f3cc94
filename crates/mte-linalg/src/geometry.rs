//! Rigid-body geometry: type aliases, `skew`/`unskew`, exact SO(3) and SE(3)
//! exponential and logarithm, the adjoint, and the transform of a 6-vector error.
//!
//! Conventions (shared by every mte crate):
//! - 6-vectors are ordered (translation x, y, z ; rotation x, y, z): a twist is (v, ω),
//!   an error vector is (δx, δy, δz, εx, εy, εz).
//! - `se3::exp((v, ω))` is the matrix exponential of the twist
//!   `[[ω̂, v], [0, 0]]` (Lynch & Park, *Modern Robotics*, §3.3.3).
//! - The adjoint acts on twists ordered (v, ω): `Ad_g = [[R, p̂R], [0, R]]`.
//! - The exact error transform of e = (δ, ε) is `Trans(δ)·Rot(exp ε̂)`; its first-order
//!   (small-angle) form is `[[I + ε̂, δ], [0, 1]]`.

use nalgebra::{Quaternion, Translation3, UnitQuaternion};

/// 3-vector of f64 (mm or rad, as the name of the variable says).
pub type Vec3 = nalgebra::Vector3<f64>;
/// 6-vector of f64, ordered (translation ; rotation).
pub type Vec6 = nalgebra::Vector6<f64>;
/// 3 × 3 matrix of f64.
pub type Mat3 = nalgebra::Matrix3<f64>;
/// 4 × 4 matrix of f64 (homogeneous transforms).
pub type Mat4 = nalgebra::Matrix4<f64>;
/// 6 × 6 matrix of f64 (adjoints, Jacobians of twists).
pub type Mat6 = nalgebra::Matrix6<f64>;
/// Rigid transform (rotation as a unit quaternion, translation in mm).
pub type Iso3 = nalgebra::Isometry3<f64>;
/// Dynamic dense matrix of f64.
pub type DMat = nalgebra::DMatrix<f64>;
/// Dynamic dense vector of f64.
pub type DVec = nalgebra::DVector<f64>;

/// The skew-symmetric (cross-product) matrix `v̂` with `v̂ u = v × u`.
///
/// ```
/// use mte_linalg::{skew, Vec3};
/// let (v, u) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.0, 0.5, 2.0));
/// assert!((skew(&v) * u - v.cross(&u)).norm() < 1e-15);
/// ```
pub fn skew(v: &Vec3) -> Mat3 {
    Mat3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Inverse of [`skew`]: the vector of the skew-symmetric part of `m`,
/// `((m₃₂ − m₂₃)/2, (m₁₃ − m₃₁)/2, (m₂₁ − m₁₂)/2)`.
///
/// ```
/// use mte_linalg::{skew, unskew, Vec3};
/// let v = Vec3::new(0.1, -0.2, 0.3);
/// assert_eq!(unskew(&skew(&v)), v);
/// ```
pub fn unskew(m: &Mat3) -> Vec3 {
    Vec3::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
    )
}

/// Coefficients `(sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³)` from `θ²`, with
/// Taylor series below θ = 1e-2 so that they stay exact to rounding near 0.
fn rodrigues_coefficients(theta2: f64) -> (f64, f64, f64) {
    if theta2 < 1e-4 {
        let t2 = theta2;
        let a = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0));
        let b = 0.5 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0)));
        let c = (1.0 / 6.0) * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0)));
        (a, b, c)
    } else {
        let t = theta2.sqrt();
        let (s, co) = t.sin_cos();
        (s / t, (1.0 - co) / theta2, (t - s) / (theta2 * t))
    }
}

/// Unit quaternion of the rotation vector `w` (exact; a Taylor series without
/// trigonometry below |w| = 0.1, accurate to rounding).
///
/// ```
/// use mte_linalg::{quaternion_from_rotation_vector, Vec3};
/// let w = Vec3::new(1e-5, -2e-5, 3e-6);
/// let q = quaternion_from_rotation_vector(&w);
/// let r = mte_linalg::nalgebra::UnitQuaternion::from_scaled_axis(w);
/// assert!(q.angle_to(&r) < 1e-15);
/// ```
pub fn quaternion_from_rotation_vector(w: &Vec3) -> UnitQuaternion<f64> {
    let t2 = w.norm_squared();
    let (c, s) = if t2 < 1e-2 {
        // cos(θ/2) and sin(θ/2)/θ as series in θ²; the first omitted terms are
        // θ¹⁰/3.7e9 and θ⁸/1.9e8: below 6e-17 for θ < 0.1.
        let c = 1.0 - t2 / 8.0 * (1.0 - t2 / 48.0 * (1.0 - t2 / 120.0 * (1.0 - t2 / 224.0)));
        let s = 0.5 * (1.0 - t2 / 24.0 * (1.0 - t2 / 80.0 * (1.0 - t2 / 168.0)));
        (c, s)
    } else {
        let t = t2.sqrt();
        let (sh, ch) = (0.5 * t).sin_cos();
        (ch, sh / t)
    };
    UnitQuaternion::new_unchecked(Quaternion::new(c, s * w.x, s * w.y, s * w.z))
}

/// SO(3): exponential and logarithm of rotation vectors.
pub mod so3 {
    use super::{Mat3, Vec3, rodrigues_coefficients, skew, unskew};

    /// Rotation matrix `exp(ŵ) = I + (sin θ/θ) ŵ + ((1 − cos θ)/θ²) ŵ²`, θ = |w|
    /// (Rodrigues), exact to rounding for every θ including 0.
    ///
    /// ```
    /// use mte_linalg::{so3, Vec3};
    /// let r = so3::exp(&Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
    /// assert!((r * Vec3::x() - Vec3::y()).norm() < 1e-15);
    /// ```
    pub fn exp(w: &Vec3) -> Mat3 {
        let (a, b, _) = rodrigues_coefficients(w.norm_squared());
        let k = skew(w);
        Mat3::identity() + k * a + k * k * b
    }

    /// Rotation vector `w` with `exp(ŵ) = r`, |w| ∈ [0, π]. Stable near 0 (series)
    /// and near π (axis from the symmetric part). At exactly π the sign of the axis
    /// is not defined by `r`; the component of largest magnitude is made positive.
    ///
    /// `r` must be a rotation matrix (orthonormal, det +1); the result for other
    /// matrices is the log of a nearby rotation at best.
    ///
    /// ```
    /// use mte_linalg::{so3, Vec3};
    /// let w = Vec3::new(0.3, -3.0, 0.2).normalize() * (std::f64::consts::PI - 1e-9);
    /// assert!((so3::log(&so3::exp(&w)) - w).norm() < 1e-8);
    /// ```
    pub fn log(r: &Mat3) -> Vec3 {
        let s = unskew(r); // sin θ · n
        let c = ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0); // cos θ
        let sn = s.norm();
        let theta = sn.atan2(c);
        if theta < 1e-4 {
            // θ / sin θ = 1 + θ²/6 + 7θ⁴/360
            let t2 = theta * theta;
            return s * (1.0 + t2 / 6.0 + 7.0 * t2 * t2 / 360.0);
        }
        if c > -0.7 {
            return s * (theta / sn);
        }
        // Near π: (R + Rᵀ)/2 − cos θ I = (1 − cos θ) n nᵀ.
        let m = (r + r.transpose()) * 0.5 - Mat3::identity() * c;
        let one_c = 1.0 - c;
        let mut k = 0;
        for i in 1..3 {
            if m[(i, i)] > m[(k, k)] {
                k = i;
            }
        }
        let mut n: Vec3 = m.column(k).into_owned() / (m[(k, k)].max(0.0) * one_c).sqrt();
        n /= n.norm();
        let dot = n.dot(&s);
        if dot < 0.0 || (dot == 0.0 && n[k] < 0.0) {
            n = -n;
        }
        n * theta
    }

    /// Left Jacobian of SO(3):
    /// `J(w) = I + ((1 − cos θ)/θ²) ŵ + ((θ − sin θ)/θ³) ŵ²`.
    /// It maps a twist's v to the translation of its exponential: `p = J(ω) v`.
    ///
    /// ```
    /// use mte_linalg::{so3, Mat3, Vec3};
    /// assert_eq!(so3::left_jacobian(&Vec3::zeros()), Mat3::identity());
    /// ```
    pub fn left_jacobian(w: &Vec3) -> Mat3 {
        let (_, b, c) = rodrigues_coefficients(w.norm_squared());
        let k = skew(w);
        Mat3::identity() + k * b + k * k * c
    }

    /// Inverse of [`left_jacobian`]:
    /// `J⁻¹(w) = I − ŵ/2 + (1/θ² − (1 + cos θ)/(2θ sin θ)) ŵ²`, valid for θ < 2π
    /// (series below θ = 1e-2).
    ///
    /// ```
    /// use mte_linalg::{so3, Mat3, Vec3};
    /// let w = Vec3::new(0.4, 1.0, -2.0);
    /// let p = so3::left_jacobian(&w) * so3::left_jacobian_inv(&w);
    /// assert!((p - Mat3::identity()).norm() < 1e-14);
    /// ```
    pub fn left_jacobian_inv(w: &Vec3) -> Mat3 {
        let t2 = w.norm_squared();
        let d = if t2 < 1e-4 {
            // 1/12 + θ²/720 + θ⁴/30240
            1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
        } else {
            // (1 + cos θ)/sin θ = cot(θ/2): accurate near π, where 1 + cos θ cancels.
            let t = t2.sqrt();
            1.0 / t2 - 1.0 / (2.0 * t * (0.5 * t).tan())
        };
        let k = skew(w);
        Mat3::identity() - k * 0.5 + k * k * d
    }
}

/// SE(3): exponential and logarithm of twists ordered (v, ω), and the adjoint.
pub mod se3 {
    use super::{Iso3, Mat3, Mat6, Vec3, Vec6, quaternion_from_rotation_vector, skew, so3};
    use nalgebra::{Rotation3, Translation3, UnitQuaternion};

    /// `exp` of the twist ξ = (v, ω): rotation `exp(ω̂)`, translation `J(ω) v`
    /// ([`so3::left_jacobian`]). For a revolute joint through q with unit axis ω,
    /// `v = −ω × q` and `exp(ξθ)` rotates by θ about that line; for a prismatic joint
    /// ω = 0 and `exp` is a translation by `vθ`.
    ///
    /// ```
    /// use mte_linalg::{se3, Vec3, Vec6};
    /// // rotation by π/2 about the z line through (1, 0, 0) takes the origin to (1, -1, 0)
    /// let (w, q) = (Vec3::z() * std::f64::consts::FRAC_PI_2, Vec3::new(1.0, 0.0, 0.0));
    /// let v = -w.cross(&q);
    /// let g = se3::exp(&Vec6::new(v.x, v.y, v.z, w.x, w.y, w.z));
    /// assert!((g.translation.vector - Vec3::new(1.0, -1.0, 0.0)).norm() < 1e-15);
    /// ```
    pub fn exp(twist: &Vec6) -> Iso3 {
        let v = Vec3::new(twist[0], twist[1], twist[2]);
        let w = Vec3::new(twist[3], twist[4], twist[5]);
        let p = so3::left_jacobian(&w) * v;
        Iso3::from_parts(Translation3::from(p), quaternion_from_rotation_vector(&w))
    }

    /// `log` of a rigid transform: the twist (v, ω) with `exp(v, ω) = g`, |ω| ≤ π.
    /// Stable near 0 and π (see [`so3::log`]).
    ///
    /// ```
    /// use mte_linalg::{se3, Vec6};
    /// let xi = Vec6::new(10.0, -3.0, 2.0, 0.1, 0.2, -3.0);
    /// assert!((se3::log(&se3::exp(&xi)) - xi).norm() < 1e-12);
    /// ```
    pub fn log(g: &Iso3) -> Vec6 {
        let r: Mat3 = g.rotation.to_rotation_matrix().into_inner();
        let w = so3::log(&r);
        let v = so3::left_jacobian_inv(&w) * g.translation.vector;
        Vec6::new(v.x, v.y, v.z, w.x, w.y, w.z)
    }

    /// Adjoint `Ad_g = [[R, p̂R], [0, R]]` for twists ordered (v, ω):
    /// `Ad_g ξ` is the twist ξ expressed in the frame in which `g` is given, i.e.
    /// `g·exp(ξ)·g⁻¹ = exp(Ad_g ξ)`.
    ///
    /// ```
    /// use mte_linalg::{se3, Iso3, Vec3, Vec6};
    /// let g = Iso3::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.3, -0.1, 0.7));
    /// let xi = Vec6::new(0.5, 0.1, -0.2, 0.05, 0.3, -0.4);
    /// let lhs = g * se3::exp(&xi) * g.inverse();
    /// let rhs = se3::exp(&(se3::adjoint(&g) * xi));
    /// assert!((lhs.to_homogeneous() - rhs.to_homogeneous()).norm() < 1e-13);
    /// ```
    pub fn adjoint(g: &Iso3) -> Mat6 {
        let r: Mat3 = g.rotation.to_rotation_matrix().into_inner();
        let pr = skew(&g.translation.vector) * r;
        let mut a = Mat6::zeros();
        a.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        a.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
        a.fixed_view_mut::<3, 3>(0, 3).copy_from(&pr);
        a
    }

    /// A rigid transform from a rotation matrix (re-orthonormalised) and a translation.
    pub fn from_rotation_translation(r: &Mat3, p: &Vec3) -> Iso3 {
        let rot = Rotation3::from_matrix(r);
        Iso3::from_parts(
            Translation3::from(*p),
            UnitQuaternion::from_rotation_matrix(&rot),
        )
    }
}

/// Exact transform of the error 6-vector e = (δ, ε): `Trans(δ) · Rot(exp ε̂)`
/// (rotation vector ε, rotation applied first, then the translation δ).
///
/// ```
/// use mte_linalg::{error_transform, Vec3, Vec6};
/// let t = error_transform(&Vec6::new(0.01, 0.0, 0.0, 0.0, 0.0, 1e-4));
/// // a point at (100, 0, 0) moves by δ plus ε × p = (0.01, 0.01, 0) to first order
/// let p = t.transform_point(&Vec3::new(100.0, 0.0, 0.0).into());
/// assert!((p.coords - Vec3::new(100.01, 0.01, 0.0)).norm() < 1e-6);
/// ```
pub fn error_transform(e: &Vec6) -> Iso3 {
    let eps = Vec3::new(e[3], e[4], e[5]);
    Iso3::from_parts(
        Translation3::new(e[0], e[1], e[2]),
        quaternion_from_rotation_vector(&eps),
    )
}

/// Small-angle (first-order) error transform `[[I + ε̂, δ], [0, 1]]`
/// (the position/motion error matrix of seed 001).
///
/// ```
/// use mte_linalg::{error_transform_small, Vec6};
/// let m = error_transform_small(&Vec6::new(1.0, 2.0, 3.0, 0.1, 0.2, 0.3));
/// assert_eq!(m[(0, 1)], -0.3);
/// assert_eq!(m[(2, 3)], 3.0);
/// ```
pub fn error_transform_small(e: &Vec6) -> Mat4 {
    let eps = Vec3::new(e[3], e[4], e[5]);
    let mut m = Mat4::identity();
    m.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Mat3::identity() + skew(&eps)));
    m[(0, 3)] = e[0];
    m[(1, 3)] = e[1];
    m[(2, 3)] = e[2];
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use proptest::prelude::*;
    use std::f64::consts::PI;

    fn rotvec() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, 0.0..PI).prop_filter_map(
            "non-zero axis",
            |(x, y, z, t)| {
                let v = Vec3::new(x, y, z);
                (v.norm() > 1e-3).then(|| v.normalize() * t)
            },
        )
    }

    /// Reference: nalgebra's own Rodrigues implementation.
    #[test]
    fn so3_exp_matches_nalgebra() {
        for w in [
            Vec3::new(0.3, -0.2, 0.9),
            Vec3::new(1e-9, 2e-9, 0.0),
            Vec3::new(0.0, 0.0, PI),
            Vec3::new(2.0, 1.0, -0.5),
        ] {
            let r = nalgebra::Rotation3::from_scaled_axis(w).into_inner();
            assert_relative_eq!(so3::exp(&w), r, epsilon = 1e-15);
            let q = quaternion_from_rotation_vector(&w)
                .to_rotation_matrix()
                .into_inner();
            assert_relative_eq!(q, r, epsilon = 1e-15);
        }
    }

    #[test]
    fn so3_log_near_zero_is_exact() {
        // For tiny angles log must return w itself to relative rounding.
        for s in [1e-14, 1e-10, 1e-7, 1e-5, 3e-4] {
            let w = Vec3::new(0.3, -0.5, 0.8) * s;
            let back = so3::log(&so3::exp(&w));
            assert_relative_eq!(back, w, max_relative = 1e-12);
        }
        assert_eq!(so3::log(&Mat3::identity()), Vec3::zeros());
    }

    #[test]
    fn so3_log_near_pi() {
        // angle π − d for d from 1e-3 down to 0: the axis is recovered from the
        // symmetric part, the angle from atan2; error scales with rounding / sin θ.
        for d in [1e-3, 1e-6, 1e-9, 1e-12, 0.0] {
            let n = Vec3::new(0.2, -0.9, 0.4).normalize();
            let w = n * (PI - d);
            let back = so3::log(&so3::exp(&w));
            assert!(
                (back - w).norm() < 1e-7 || (d == 0.0 && (back + w).norm() < 1e-7),
                "d = {d}: {back:?} vs {w:?}"
            );
            // the rotation is reproduced in any case
            assert_relative_eq!(so3::exp(&back), so3::exp(&w), epsilon = 1e-14);
        }
        // exactly π about a coordinate axis
        let r = Mat3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
        assert_relative_eq!(so3::log(&r), Vec3::new(PI, 0.0, 0.0), epsilon = 1e-15);
    }

    #[test]
    fn se3_log_exp_near_zero_and_pi() {
        for (t, v) in [
            (1e-12, Vec3::new(1.0, 2.0, 3.0)),
            (1e-6, Vec3::new(-5.0, 0.0, 300.0)),
            (PI - 1e-9, Vec3::new(10.0, -20.0, 5.0)),
        ] {
            let w = Vec3::new(0.6, 0.0, -0.8) * t;
            let xi = Vec6::new(v.x, v.y, v.z, w.x, w.y, w.z);
            let g = se3::exp(&xi);
            let back = se3::exp(&se3::log(&g));
            assert_relative_eq!(back.to_homogeneous(), g.to_homogeneous(), epsilon = 1e-9);
        }
        // pure translation
        let xi = Vec6::new(1.0, 2.0, 3.0, 0.0, 0.0, 0.0);
        assert_eq!(se3::log(&se3::exp(&xi)), xi);
    }

    #[test]
    fn error_transform_first_order_gap_is_second_order() {
        let e = Vec6::new(0.05, -0.03, 0.02, 1e-4, -5e-5, 8e-5);
        let gap = |s: f64| {
            (error_transform(&(e * s)).to_homogeneous() - error_transform_small(&(e * s))).norm()
        };
        let ratio = gap(1.0) / gap(0.5);
        assert!((ratio - 4.0).abs() < 1e-3, "ratio {ratio}");
    }

    proptest! {
        #[test]
        fn so3_round_trip(w in rotvec()) {
            let back = so3::log(&so3::exp(&w));
            prop_assert!((so3::exp(&back) - so3::exp(&w)).norm() < 1e-13);
            if w.norm() < PI - 1e-6 {
                prop_assert!((back - w).norm() < 1e-9);
            }
        }

        #[test]
        fn se3_round_trip(w in rotvec(), v in (-500.0..500.0f64, -500.0..500.0f64, -500.0..500.0f64)) {
            let xi = Vec6::new(v.0, v.1, v.2, w.x, w.y, w.z);
            let g = se3::exp(&xi);
            let back = se3::log(&g);
            let g2 = se3::exp(&back);
            prop_assert!((g2.to_homogeneous() - g.to_homogeneous()).norm() < 1e-9);
            if w.norm() < PI - 1e-6 {
                prop_assert!((back - xi).norm() < 1e-6 * (1.0 + xi.norm()));
            }
        }

        #[test]
        fn adjoint_conjugation(w in rotvec(), p in (-100.0..100.0f64, -100.0..100.0f64, -100.0..100.0f64),
                               xi in proptest::array::uniform6(-1.0..1.0f64)) {
            let g = Iso3::from_parts(Translation3::new(p.0, p.1, p.2), UnitQuaternion::from_scaled_axis(w));
            let xi = Vec6::from_row_slice(&xi);
            let lhs = g * se3::exp(&xi) * g.inverse();
            let rhs = se3::exp(&(se3::adjoint(&g) * xi));
            prop_assert!((lhs.to_homogeneous() - rhs.to_homogeneous()).norm() < 1e-10);
        }

        #[test]
        fn left_jacobian_inverse(w in rotvec()) {
            prop_assume!(w.norm() < PI - 1e-3);
            let p = so3::left_jacobian(&w) * so3::left_jacobian_inv(&w);
            prop_assert!((p - Mat3::identity()).norm() < 1e-12);
        }
    }
}
