//! Homogeneous transforms written out by hand, as a metrologist would: exact rotations about the
//! machine axes, translations, and the error transform of a carriage (`Trans(δ)·Rot(ε)`).

use mte_linalg::nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::Rng;

use super::smooth::{Smooth, Waviness, signed};

/// A rigid transform.
pub type Iso = Isometry3<f64>;
/// A 3-vector (mm).
pub type V3 = Vector3<f64>;

/// Pure translation by `v`.
pub fn trans(v: V3) -> Iso {
    Iso::from_parts(Translation3::from(v), UnitQuaternion::identity())
}

/// Exact rotation by the rotation vector `r` (axis · angle, rad).
pub fn rot(r: V3) -> Iso {
    Iso::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_scaled_axis(r),
    )
}

/// Rotation about X by `a` rad.
pub fn rot_x(a: f64) -> Iso {
    rot(V3::new(a, 0.0, 0.0))
}

/// Rotation about Y by `a` rad.
pub fn rot_y(a: f64) -> Iso {
    rot(V3::new(0.0, a, 0.0))
}

/// Rotation about Z by `a` rad.
pub fn rot_z(a: f64) -> Iso {
    rot(V3::new(0.0, 0.0, a))
}

/// The six component errors of a linear axis as smooth functions of its coordinate: `d` the
/// translations (mm) along X, Y, Z, `e` the rotations (rad) about X, Y, Z of the carriage.
#[derive(Debug, Clone)]
pub struct LinearErrors {
    /// Translation errors along X, Y, Z, mm.
    pub d: [Smooth; 3],
    /// Rotation errors about X, Y, Z, rad.
    pub e: [Smooth; 3],
}

/// Sizes for drawing [`LinearErrors`]: µm for positioning and straightness, µrad for angles.
#[derive(Debug, Clone, Copy)]
pub struct ComponentSizes {
    /// Positioning error range, µm.
    pub positioning_um: (f64, f64),
    /// Straightness range, µm.
    pub straightness_um: (f64, f64),
    /// Angular error range, µrad.
    pub angular_urad: (f64, f64),
}

/// The realistic sizes of the brief: 3–20 µm, 1–8 µm, 2–25 µrad.
pub const REALISTIC: ComponentSizes = ComponentSizes {
    positioning_um: (3.0, 20.0),
    straightness_um: (1.0, 8.0),
    angular_urad: (2.0, 25.0),
};

impl LinearErrors {
    /// No errors.
    pub fn zero() -> Self {
        Self {
            d: [Smooth::zero(), Smooth::zero(), Smooth::zero()],
            e: [Smooth::zero(), Smooth::zero(), Smooth::zero()],
        }
    }

    /// Random smooth errors of the axis along machine direction `dir` (0..3) over `[lo, hi]`,
    /// every size multiplied by `scale`, of the given waviness.
    pub fn draw(
        rng: &mut impl Rng,
        dir: usize,
        (lo, hi): (f64, f64),
        sizes: ComponentSizes,
        scale: f64,
        waviness: Waviness,
    ) -> Self {
        let mut d = [Smooth::zero(), Smooth::zero(), Smooth::zero()];
        for (k, slot) in d.iter_mut().enumerate() {
            let (a, b) = if k == dir {
                sizes.positioning_um
            } else {
                sizes.straightness_um
            };
            let size = signed(rng, a, b).abs() * 1e-3 * scale;
            *slot = Smooth::draw(rng, lo, hi, size, waviness);
        }
        let mut e = [Smooth::zero(), Smooth::zero(), Smooth::zero()];
        for slot in &mut e {
            let size = signed(rng, sizes.angular_urad.0, sizes.angular_urad.1).abs() * 1e-6 * scale;
            *slot = Smooth::draw(rng, lo, hi, size, waviness);
        }
        Self { d, e }
    }

    /// The carriage's error transform at coordinate `q`: `Trans(δ(q))·Rot(ε(q))`.
    pub fn at(&self, q: f64) -> Iso {
        let d = V3::new(self.d[0].at(q), self.d[1].at(q), self.d[2].at(q));
        let e = V3::new(self.e[0].at(q), self.e[1].at(q), self.e[2].at(q));
        trans(d) * rot(e)
    }
}
