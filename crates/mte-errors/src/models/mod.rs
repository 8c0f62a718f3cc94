//! Position-, time- and direction-dependent error models behind one small trait.
//!
//! Every model maps a [`Context`] (axis position, time, direction of motion) to one error value in
//! internal units (mm for linear errors, rad for angular errors). Models that are linear in their
//! coefficients also expose their basis functions, so an identification can regress on them:
//! `value(ctx) = Σ coefficients()[i] · basis(ctx)[i]`.

mod basic;
mod tabulated;
mod tolerance;

pub use basic::{Constant, Fourier, Legendre, Reversal, Sum, ThermalExponential, ThermalLinear};
pub use tabulated::Tabulated;
pub use tolerance::{ToleranceAxis, ToleranceForm, ToleranceModel};

/// Direction of motion of an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Moving towards smaller coordinates.
    Negative,
    /// Not known or standing still: direction-dependent models give their mean value.
    #[default]
    Unknown,
    /// Moving towards larger coordinates.
    Positive,
}

impl Direction {
    /// −1, 0 or +1.
    pub fn sign(self) -> f64 {
        match self {
            Direction::Negative => -1.0,
            Direction::Unknown => 0.0,
            Direction::Positive => 1.0,
        }
    }
    /// From the sign of a number (0 → `Unknown`).
    pub fn from_sign(s: f64) -> Direction {
        if s > 0.0 {
            Direction::Positive
        } else if s < 0.0 {
            Direction::Negative
        } else {
            Direction::Unknown
        }
    }
}

/// Where a model is evaluated: the coordinate of the axis the error belongs to (mm or rad), the
/// time since the start of the run (s) and the direction of motion of that axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Context {
    /// Axis coordinate (mm for linear axes, rad for rotary axes).
    pub position: f64,
    /// Time (s).
    pub time_s: f64,
    /// Direction of motion of the axis.
    pub direction: Direction,
}

impl Context {
    /// A context at `position`, time 0, direction unknown.
    pub fn at(position: f64) -> Context {
        Context {
            position,
            ..Context::default()
        }
    }
}

/// One error source as a function of axis position, time and direction of motion.
///
/// Only [`ErrorModel::value`] is required. Implement [`ErrorModel::derivative`] analytically when
/// you can (the default is a central finite difference), and the basis functions when the model is
/// linear in its coefficients.
///
/// ```
/// use mte_errors::models::{Context, ErrorModel};
/// /// A straightness that grows with the square of the position: e(x) = c·x².
/// #[derive(Debug)]
/// struct Quadratic(f64);
/// impl ErrorModel for Quadratic {
///     fn value(&self, ctx: &Context) -> f64 { self.0 * ctx.position * ctx.position }
/// }
/// let m = Quadratic(1e-6);
/// assert!((m.value(&Context::at(100.0)) - 1e-2).abs() < 1e-15);
/// assert!((m.derivative(&Context::at(100.0)) - 2e-4).abs() < 1e-9);
/// ```
pub trait ErrorModel: Send + Sync + std::fmt::Debug {
    /// The error value (mm or rad) at `ctx`.
    fn value(&self, ctx: &Context) -> f64;

    /// d value / d position at `ctx` (mm/mm, rad/mm, mm/rad or rad/rad).
    fn derivative(&self, ctx: &Context) -> f64 {
        let h = 1e-6 * (1.0 + ctx.position.abs());
        let p = Context {
            position: ctx.position + h,
            ..*ctx
        };
        let m = Context {
            position: ctx.position - h,
            ..*ctx
        };
        (self.value(&p) - self.value(&m)) / (2.0 * h)
    }

    /// Number of basis functions (0 when the model is not linear in coefficients).
    fn n_basis(&self) -> usize {
        0
    }

    /// Values of the basis functions at `ctx` written to `out` (`out.len() == n_basis()`), such
    /// that `value(ctx) == Σ coefficients()[i] · out[i]`.
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        let _ = (ctx, out);
    }

    /// The coefficients multiplying the basis functions (empty when `n_basis() == 0`).
    fn coefficients(&self) -> Vec<f64> {
        Vec::new()
    }

    /// Names of the coefficients, in the order of [`ErrorModel::coefficients`].
    fn coefficient_names(&self) -> Vec<String> {
        (0..self.n_basis()).map(|i| format!("c{i}")).collect()
    }

    /// Range of positions where the model is defined (`None`: everywhere). Evaluators report an
    /// [`crate::Error::OutOfRange`] outside it.
    fn domain(&self) -> Option<(f64, f64)> {
        None
    }
}

/// Evaluate `model` at `ctx`, checking its domain.
///
/// # Errors
/// [`crate::Error::OutOfRange`] naming `parameter` when `ctx.position` is outside [`ErrorModel::domain`].
pub fn checked_value(model: &dyn ErrorModel, ctx: &Context, parameter: &str) -> crate::Result<f64> {
    if let Some((low, high)) = model.domain()
        && !(ctx.position >= low && ctx.position <= high)
    {
        return Err(crate::Error::OutOfRange {
            parameter: parameter.to_string(),
            position: ctx.position,
            low,
            high,
        });
    }
    Ok(model.value(ctx))
}

#[cfg(test)]
pub(crate) mod testutil {
    use super::*;

    /// Central finite difference with step h (relative error O(h²)).
    pub fn fd(m: &dyn ErrorModel, ctx: &Context, h: f64) -> f64 {
        let p = Context {
            position: ctx.position + h,
            ..*ctx
        };
        let q = Context {
            position: ctx.position - h,
            ..*ctx
        };
        (m.value(&p) - m.value(&q)) / (2.0 * h)
    }

    /// Check value == Σ c_i φ_i at ctx.
    pub fn check_basis(m: &dyn ErrorModel, ctx: &Context) {
        let n = m.n_basis();
        let mut b = vec![0.0; n];
        m.basis(ctx, &mut b);
        let c = m.coefficients();
        assert_eq!(c.len(), n);
        assert_eq!(m.coefficient_names().len(), n);
        let v: f64 = c.iter().zip(&b).map(|(c, b)| c * b).sum();
        let scale = m.value(ctx).abs().max(1e-12);
        assert!(
            (v - m.value(ctx)).abs() <= 1e-12 * scale.max(1.0),
            "basis sum {v} vs value {}",
            m.value(ctx)
        );
    }
}
