//! The tolerance-based error predictor of seed 000 (Fan et al. 2019, eqs 6–11).
//!
//! For a guideway of stroke `L`, with `s` the distance travelled from the start of the stroke:
//!
//! - straightness (eqs 6, 8): `δ(s) = (k/m)·sin(nπs/L)`
//! - positioning (eq 7): `δ(s) = (k/m)·sin(nπs/L) + K·s/L`
//! - angle from two carriages `b` apart (eqs 9, 11): `ε(s) = ±(δ(s − b) − δ(s))/b`
//! - roll from the twist tolerance over rails `w` apart (eq 10): `ε(s) = (k/w)·sin(nπs/L)`
//!
//! `k` is the tolerance, `n ∈ 1..=8` the number of half-waves, `m = 1` for `n = 1` else `2`.
//! All forms are linear in the tolerances (`k`, and `K` for positioning).

use super::{Context, ErrorModel};
use crate::error::{Result, invalid};
use crate::units::Kind;
use std::f64::consts::PI;

/// Which of eqs 6–11 a [`ToleranceModel`] implements.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ToleranceForm {
    /// Eqs 6/8: `(k/m)·sin(nπs/L)` (mm).
    Straightness {
        /// Straightness tolerance k (mm).
        tolerance: f64,
        /// Number of half-waves n (1..=8).
        half_waves: u32,
    },
    /// Eq 7: `(k/m)·sin(nπs/L) + K·s/L` (mm).
    Positioning {
        /// Positioning tolerance k (mm).
        tolerance: f64,
        /// Number of half-waves n (1..=8).
        half_waves: u32,
        /// Scale (linear positioning) term K over the whole stroke (mm).
        scale: f64,
    },
    /// Eqs 9/11: `sign·(δ(s − b) − δ(s))/b` with `δ` the straightness `(k/m)·sin(nπs/L)` (rad).
    /// Eq 9 (εx of the Y guideway from δz) has `sign = +1`, eq 11 (εz from δx) `sign = −1`.
    CarriageDifference {
        /// Straightness tolerance k of the driving straightness (mm).
        tolerance: f64,
        /// Half-waves of the driving straightness.
        half_waves: u32,
        /// Distance b between the front and rear carriages (mm).
        carriage_spacing: f64,
        /// +1 or −1.
        sign: f64,
    },
    /// Eq 10: `(k/w)·sin(nπs/L)` (rad), k = twist tolerance between the two rails (mm).
    Twist {
        /// Twist tolerance k (mm).
        tolerance: f64,
        /// Number of half-waves n.
        half_waves: u32,
        /// Rail spacing w (mm).
        rail_spacing: f64,
    },
}

/// One error component of one guideway predicted from its tolerance (seed 000, eqs 6–11).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToleranceModel {
    form: ToleranceForm,
    stroke: f64,
    origin: f64,
}

fn m_of(n: u32) -> f64 {
    if n == 1 { 1.0 } else { 2.0 }
}

impl ToleranceModel {
    /// A model over a stroke of length `stroke_mm` starting at axis coordinate `origin_mm`
    /// (`s = x − origin_mm`).
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] when the stroke, spacings are not positive, `n ∉ 1..=8`, the sign
    /// is not ±1 or a value is not finite.
    pub fn new(form: ToleranceForm, stroke_mm: f64, origin_mm: f64) -> Result<ToleranceModel> {
        let what = "tolerance model";
        if !(stroke_mm.is_finite() && stroke_mm > 0.0 && origin_mm.is_finite()) {
            return Err(invalid(
                what,
                format!("stroke {stroke_mm} mm must be > 0 and origin finite"),
            ));
        }
        let (k, n) = match form {
            ToleranceForm::Straightness {
                tolerance,
                half_waves,
            } => (tolerance, half_waves),
            ToleranceForm::Positioning {
                tolerance,
                half_waves,
                scale,
            } => {
                if !scale.is_finite() {
                    return Err(invalid(what, "scale K must be finite"));
                }
                (tolerance, half_waves)
            }
            ToleranceForm::CarriageDifference {
                tolerance,
                half_waves,
                carriage_spacing,
                sign,
            } => {
                if !(carriage_spacing.is_finite() && carriage_spacing > 0.0) {
                    return Err(invalid(
                        what,
                        format!("carriage spacing b = {carriage_spacing} mm must be > 0"),
                    ));
                }
                if sign != 1.0 && sign != -1.0 {
                    return Err(invalid(what, format!("sign {sign} must be +1 or -1")));
                }
                (tolerance, half_waves)
            }
            ToleranceForm::Twist {
                tolerance,
                half_waves,
                rail_spacing,
            } => {
                if !(rail_spacing.is_finite() && rail_spacing > 0.0) {
                    return Err(invalid(
                        what,
                        format!("rail spacing w = {rail_spacing} mm must be > 0"),
                    ));
                }
                (tolerance, half_waves)
            }
        };
        if !k.is_finite() {
            return Err(invalid(what, "tolerance must be finite"));
        }
        if !(1..=8).contains(&n) {
            return Err(invalid(
                what,
                format!("number of half-waves n = {n} must be in 1..=8 (seed 000, eq 6)"),
            ));
        }
        Ok(ToleranceModel {
            form,
            stroke: stroke_mm,
            origin: origin_mm,
        })
    }
    /// The form.
    pub fn form(&self) -> ToleranceForm {
        self.form
    }
    /// Length (straightness, positioning) or angle (carriage difference, twist).
    pub fn output_kind(&self) -> Kind {
        match self.form {
            ToleranceForm::Straightness { .. } | ToleranceForm::Positioning { .. } => Kind::Length,
            _ => Kind::Angle,
        }
    }
    /// sin(nπs/L) and its derivative d/ds.
    fn wave(&self, n: u32, s: f64) -> (f64, f64) {
        let a = n as f64 * PI / self.stroke;
        let (sn, cs) = (a * s).sin_cos();
        (sn, a * cs)
    }
    /// (basis, d basis/ds) pairs: up to two basis functions.
    fn basis2(&self, x: f64) -> ([f64; 2], [f64; 2]) {
        let s = x - self.origin;
        match self.form {
            ToleranceForm::Straightness { half_waves: n, .. } => {
                let (w, dw) = self.wave(n, s);
                ([w / m_of(n), 0.0], [dw / m_of(n), 0.0])
            }
            ToleranceForm::Positioning { half_waves: n, .. } => {
                let (w, dw) = self.wave(n, s);
                (
                    [w / m_of(n), s / self.stroke],
                    [dw / m_of(n), 1.0 / self.stroke],
                )
            }
            ToleranceForm::CarriageDifference {
                half_waves: n,
                carriage_spacing: b,
                sign,
                ..
            } => {
                let (w1, dw1) = self.wave(n, s - b);
                let (w0, dw0) = self.wave(n, s);
                let f = sign / (m_of(n) * b);
                ([f * (w1 - w0), 0.0], [f * (dw1 - dw0), 0.0])
            }
            ToleranceForm::Twist {
                half_waves: n,
                rail_spacing: w,
                ..
            } => {
                let (v, dv) = self.wave(n, s);
                ([v / w, 0.0], [dv / w, 0.0])
            }
        }
    }
}

impl ErrorModel for ToleranceModel {
    fn value(&self, ctx: &Context) -> f64 {
        let (b, _) = self.basis2(ctx.position);
        let c = self.coefficients();
        c.iter().zip(b).map(|(c, b)| c * b).sum()
    }
    fn derivative(&self, ctx: &Context) -> f64 {
        let (_, d) = self.basis2(ctx.position);
        let c = self.coefficients();
        c.iter().zip(d).map(|(c, d)| c * d).sum()
    }
    fn n_basis(&self) -> usize {
        match self.form {
            ToleranceForm::Positioning { .. } => 2,
            _ => 1,
        }
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        let (b, _) = self.basis2(ctx.position);
        let n = out.len();
        out.copy_from_slice(&b[..n]);
    }
    fn coefficients(&self) -> Vec<f64> {
        match self.form {
            ToleranceForm::Straightness { tolerance, .. }
            | ToleranceForm::CarriageDifference { tolerance, .. }
            | ToleranceForm::Twist { tolerance, .. } => vec![tolerance],
            ToleranceForm::Positioning {
                tolerance, scale, ..
            } => vec![tolerance, scale],
        }
    }
    fn coefficient_names(&self) -> Vec<String> {
        match self.form {
            ToleranceForm::Positioning { .. } => vec!["tolerance".into(), "scale".into()],
            _ => vec!["tolerance".into()],
        }
    }
}

/// The six component errors of one linear guideway from its tolerances (seed 000, eqs 6–11,
/// written for the Y guideway and generalised by cyclic permutation (u, v, w) of (x, y, z), which
/// keeps the handedness: for an axis along u, `δv`, `δw` are straightness (eqs 6, 8), `δu` the
/// positioning (eq 7), `εw = +(δv(s−b) − δv(s))/b` (eq 9), `εv = −(δw(s−b) − δw(s))/b` (eq 11),
/// `εu` the twist (eq 10)). For the Y axis (u, v, w) = (y, z, x), which gives eqs 6–11 verbatim.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToleranceAxis {
    /// Direction of motion: 0 = x, 1 = y, 2 = z.
    pub direction: usize,
    /// Stroke L (mm).
    pub stroke_mm: f64,
    /// Axis coordinate where the stroke starts (s = 0) (mm).
    pub origin_mm: f64,
    /// Front–rear carriage distance b (mm).
    pub carriage_spacing_mm: f64,
    /// Rail spacing w (mm).
    pub rail_spacing_mm: f64,
    /// Straightness tolerance k per direction (mm); the entry of the axis' own direction is unused.
    /// For Y: `[k_y1 (δx), –, k_y3 (δz)]`.
    pub straightness_mm: [f64; 3],
    /// Half-waves n per straightness direction.
    pub straightness_half_waves: [u32; 3],
    /// Positioning tolerance k_y2 (mm).
    pub positioning_mm: f64,
    /// Half-waves n2 of the positioning error.
    pub positioning_half_waves: u32,
    /// Scale term K_y (mm).
    pub scale_mm: f64,
    /// Twist tolerance k_y4 (mm).
    pub twist_mm: f64,
    /// Half-waves n4 of the twist.
    pub twist_half_waves: u32,
}

impl ToleranceAxis {
    /// The six models in component order (δx, δy, δz, εx, εy, εz).
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] as [`ToleranceModel::new`], or `direction > 2`.
    pub fn models(&self) -> Result<[ToleranceModel; 6]> {
        if self.direction > 2 {
            return Err(invalid(
                "tolerance axis",
                format!("direction {} must be 0, 1 or 2", self.direction),
            ));
        }
        let (u, v, w) = (
            self.direction,
            (self.direction + 1) % 3,
            (self.direction + 2) % 3,
        );
        let mk = |f| ToleranceModel::new(f, self.stroke_mm, self.origin_mm);
        let straight = |d: usize| ToleranceForm::Straightness {
            tolerance: self.straightness_mm[d],
            half_waves: self.straightness_half_waves[d],
        };
        let diff = |d: usize, sign: f64| ToleranceForm::CarriageDifference {
            tolerance: self.straightness_mm[d],
            half_waves: self.straightness_half_waves[d],
            carriage_spacing: self.carriage_spacing_mm,
            sign,
        };
        let mut out = [mk(straight(v))?; 6];
        out[u] = mk(ToleranceForm::Positioning {
            tolerance: self.positioning_mm,
            half_waves: self.positioning_half_waves,
            scale: self.scale_mm,
        })?;
        out[v] = mk(straight(v))?;
        out[w] = mk(straight(w))?;
        out[3 + u] = mk(ToleranceForm::Twist {
            tolerance: self.twist_mm,
            half_waves: self.twist_half_waves,
            rail_spacing: self.rail_spacing_mm,
        })?;
        out[3 + w] = mk(diff(v, 1.0))?;
        out[3 + v] = mk(diff(w, -1.0))?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::*;
    use approx::assert_relative_eq;

    /// Seed 000 Table 3 geometry for the Y guideway: L_y = 4500, b_y = 4000, w_y = 1800 mm.
    /// The paper gives no tolerance values; we take k_y1 = 0.020 mm (n1 = 2), k_y2 = 0.010 mm
    /// (n2 = 1), K_y = 0.008 mm, k_y3 = 0.015 mm (n3 = 1), k_y4 = 0.012 mm (n4 = 2).
    fn y_axis() -> ToleranceAxis {
        ToleranceAxis {
            direction: 1,
            stroke_mm: 4500.0,
            origin_mm: 0.0,
            carriage_spacing_mm: 4000.0,
            rail_spacing_mm: 1800.0,
            straightness_mm: [0.020, 0.0, 0.015],
            straightness_half_waves: [2, 1, 1],
            positioning_mm: 0.010,
            positioning_half_waves: 1,
            scale_mm: 0.008,
            twist_mm: 0.012,
            twist_half_waves: 2,
        }
    }

    #[test]
    fn y_guideway_matches_eqs_6_to_11_by_hand() {
        let m = y_axis().models().unwrap();
        let c = Context::at(1500.0);
        // Worked by hand at y = 1500 mm (π·1500/4500 = π/3):
        // eq 6:  δx = (0.020/2)·sin(2π/3)            = 0.010·0.8660254038   = 0.008660254038 mm
        // eq 7:  δy = (0.010/1)·sin(π/3) + 0.008·1500/4500
        //           = 0.010·0.8660254038 + 0.0026666667                  = 0.011326920705 mm
        // eq 8:  δz = 0.015·sin(π/3)                                       = 0.012990381057 mm
        // eq 9:  εx = (δz(1500 − 4000) − δz(1500))/4000
        //           δz(−2500) = 0.015·sin(−2500π/4500) = 0.015·sin(−100°) = −0.014772116295
        //           εx = (−0.014772116295 − 0.012990381057)/4000            = −6.940624338e-6 rad
        // eq 10: εy = (0.012/1800)·sin(2π/3) = 6.6667e-6·0.8660254038     = 5.773502692e-6 rad
        // eq 11: εz = −(δx(−2500) − δx(1500))/4000
        //           δx(−2500) = 0.010·sin(−5000π/4500) = 0.010·sin(−200°) = 0.010·0.3420201433
        //                     = 0.003420201433
        //           εz = −(0.003420201433 − 0.008660254038)/4000             = 1.310013151e-6 rad
        let want: [f64; 6] = [
            0.008660254038,
            0.011326920705,
            0.012990381057,
            -6.940624338e-6,
            5.773502692e-6,
            1.310013151e-6,
        ];
        for (i, w) in want.iter().enumerate() {
            // 1e-11 mm / 1e-14 rad: the hand values are rounded to 10–12 significant digits.
            assert_relative_eq!(m[i].value(&c), *w, epsilon = 1e-9 * w.abs());
        }
        // Kinds: first three lengths, last three angles.
        assert!(m[..3].iter().all(|m| m.output_kind() == Kind::Length));
        assert!(m[3..].iter().all(|m| m.output_kind() == Kind::Angle));
    }

    #[test]
    fn derivatives_and_bases() {
        let m = y_axis().models().unwrap();
        for i in 0..=30 {
            let c = Context::at(4500.0 * i as f64 / 30.0);
            for mm in &m {
                let d = mm.derivative(&c);
                // h = 0.01 mm over wavelengths ≥ 4500 mm: truncation ≈ (2π/4500)²h²/6 ≈ 3e-11 relative.
                assert_relative_eq!(d, fd(mm, &c, 1e-2), epsilon = 1e-7 * d.abs().max(1e-12));
                check_basis(mm, &c);
            }
        }
    }

    #[test]
    fn x_axis_by_cyclic_permutation() {
        // For X (u, v, w) = (x, y, z): εz = +(δy(s−b) − δy(s))/b, εy = −(δz(s−b) − δz(s))/b.
        let ax = ToleranceAxis {
            direction: 0,
            ..y_axis()
        };
        let m = ax.models().unwrap();
        let s = 1000.0;
        let d = |k: f64, n: u32, x: f64| k / m_of(n) * (n as f64 * PI * x / 4500.0).sin();
        let c = Context::at(s);
        assert_relative_eq!(
            m[5].value(&c),
            (d(0.0, 1, s - 4000.0) - d(0.0, 1, s)) / 4000.0,
            epsilon = 1e-18
        );
        assert_relative_eq!(
            m[4].value(&c),
            -(d(0.015, 1, s - 4000.0) - d(0.015, 1, s)) / 4000.0,
            epsilon = 1e-18
        );
        assert_relative_eq!(m[2].value(&c), d(0.015, 1, s), epsilon = 1e-18);
    }

    #[test]
    fn rejects_bad_settings() {
        let f = ToleranceForm::Straightness {
            tolerance: 0.01,
            half_waves: 9,
        };
        assert!(ToleranceModel::new(f, 100.0, 0.0).is_err());
        let f = ToleranceForm::Straightness {
            tolerance: 0.01,
            half_waves: 1,
        };
        assert!(ToleranceModel::new(f, 0.0, 0.0).is_err());
        let f = ToleranceForm::Twist {
            tolerance: 0.01,
            half_waves: 1,
            rail_spacing: 0.0,
        };
        assert!(ToleranceModel::new(f, 100.0, 0.0).is_err());
    }
}
