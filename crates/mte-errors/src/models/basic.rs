//! Constant, Legendre, Fourier, thermal drift, reversal and sums of models.

use super::{Context, ErrorModel};
use crate::error::{Result, invalid};
use std::f64::consts::PI;

/// A constant error: `e = value` (position-independent errors, squareness, location errors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Constant {
    /// The value (mm or rad).
    pub value: f64,
}

impl ErrorModel for Constant {
    fn value(&self, _: &Context) -> f64 {
        self.value
    }
    fn derivative(&self, _: &Context) -> f64 {
        0.0
    }
    fn n_basis(&self) -> usize {
        1
    }
    fn basis(&self, _: &Context, out: &mut [f64]) {
        out[0] = 1.0;
    }
    fn coefficients(&self) -> Vec<f64> {
        vec![self.value]
    }
    fn coefficient_names(&self) -> Vec<String> {
        vec!["value".into()]
    }
}

/// Legendre series over a range `[low, high]` of the axis (usually its stroke):
/// `e(x) = Σ_k c_k P_k(u)`, `u = (2x − low − high)/(high − low)` ∈ [−1, 1].
///
/// The polynomials are evaluated by Bonnet's recurrence `(k+1)P_{k+1} = (2k+1)uP_k − kP_{k−1}` and
/// their derivatives by `P'_{k+1} = P'_{k−1} + (2k+1)P_k`. Outside the range the polynomial is
/// extrapolated (no domain restriction).
#[derive(Debug, Clone, PartialEq)]
pub struct Legendre {
    coefficients: Vec<f64>,
    low: f64,
    high: f64,
}

impl Legendre {
    /// A Legendre series; `coefficients[k]` multiplies `P_k`.
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] when the range is empty or not finite or a coefficient is not finite.
    pub fn new(coefficients: Vec<f64>, low: f64, high: f64) -> Result<Legendre> {
        if !(low.is_finite() && high.is_finite() && high > low) {
            return Err(invalid(
                "legendre model",
                format!("range [{low}, {high}] must be finite with high > low"),
            ));
        }
        if coefficients.iter().any(|c| !c.is_finite()) {
            return Err(invalid("legendre model", "coefficients must be finite"));
        }
        Ok(Legendre {
            coefficients,
            low,
            high,
        })
    }
    fn u(&self, x: f64) -> f64 {
        (2.0 * x - self.low - self.high) / (self.high - self.low)
    }
    /// P_0(u) … P_{n−1}(u) into `p`, and optionally their derivatives d/du into `dp`.
    fn polys(u: f64, p: &mut [f64], mut dp: Option<&mut [f64]>) {
        let n = p.len();
        for k in 0..n {
            p[k] = match k {
                0 => 1.0,
                1 => u,
                _ => ((2 * k - 1) as f64 * u * p[k - 1] - (k - 1) as f64 * p[k - 2]) / k as f64,
            };
            if let Some(dp) = dp.as_deref_mut() {
                dp[k] = match k {
                    0 => 0.0,
                    1 => 1.0,
                    _ => dp[k - 2] + (2 * k - 1) as f64 * p[k - 1],
                };
            }
        }
    }
}

impl ErrorModel for Legendre {
    fn value(&self, ctx: &Context) -> f64 {
        let u = self.u(ctx.position);
        let (mut p0, mut p1) = (1.0, u);
        let mut s = 0.0;
        for (k, c) in self.coefficients.iter().enumerate() {
            let pk = match k {
                0 => 1.0,
                1 => u,
                _ => {
                    let p2 = ((2 * k - 1) as f64 * u * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                    p2
                }
            };
            s += c * pk;
        }
        s
    }
    fn derivative(&self, ctx: &Context) -> f64 {
        let n = self.coefficients.len();
        let mut p = vec![0.0; n];
        let mut dp = vec![0.0; n];
        Self::polys(self.u(ctx.position), &mut p, Some(&mut dp));
        let dudx = 2.0 / (self.high - self.low);
        self.coefficients
            .iter()
            .zip(&dp)
            .map(|(c, d)| c * d)
            .sum::<f64>()
            * dudx
    }
    fn n_basis(&self) -> usize {
        self.coefficients.len()
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        Self::polys(self.u(ctx.position), out, None);
    }
    fn coefficients(&self) -> Vec<f64> {
        self.coefficients.clone()
    }
    fn coefficient_names(&self) -> Vec<String> {
        (0..self.coefficients.len())
            .map(|k| format!("P{k}"))
            .collect()
    }
}

/// Periodic error (e.g. ball-screw pitch error, or a once-per-revolution rotary error):
/// `e(x) = c0 + Σ_{k=1..K} a_k cos(2πk(x − x0)/P) + b_k sin(2πk(x − x0)/P)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Fourier {
    offset: f64,
    cos: Vec<f64>,
    sin: Vec<f64>,
    period: f64,
    phase_origin: f64,
}

impl Fourier {
    /// Harmonics `cos[k−1]`, `sin[k−1]` of order k = 1..K (the shorter list is padded with zeros),
    /// period `period` (mm or rad) and phase origin `phase_origin` (mm or rad).
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] for a non-positive or non-finite period or non-finite coefficients.
    pub fn new(
        offset: f64,
        mut cos: Vec<f64>,
        mut sin: Vec<f64>,
        period: f64,
        phase_origin: f64,
    ) -> Result<Fourier> {
        if !(period.is_finite() && period > 0.0) {
            return Err(invalid(
                "fourier model",
                format!("period {period} must be finite and > 0"),
            ));
        }
        if !offset.is_finite()
            || !phase_origin.is_finite()
            || cos.iter().chain(&sin).any(|c| !c.is_finite())
        {
            return Err(invalid(
                "fourier model",
                "coefficients and phase origin must be finite",
            ));
        }
        let k = cos.len().max(sin.len());
        cos.resize(k, 0.0);
        sin.resize(k, 0.0);
        Ok(Fourier {
            offset,
            cos,
            sin,
            period,
            phase_origin,
        })
    }
    fn w(&self) -> f64 {
        2.0 * PI / self.period
    }
}

impl ErrorModel for Fourier {
    fn value(&self, ctx: &Context) -> f64 {
        let t = self.w() * (ctx.position - self.phase_origin);
        let mut s = self.offset;
        for k in 0..self.cos.len() {
            let (sn, cs) = ((k + 1) as f64 * t).sin_cos();
            s += self.cos[k] * cs + self.sin[k] * sn;
        }
        s
    }
    fn derivative(&self, ctx: &Context) -> f64 {
        let w = self.w();
        let t = w * (ctx.position - self.phase_origin);
        let mut s = 0.0;
        for k in 0..self.cos.len() {
            let kk = (k + 1) as f64;
            let (sn, cs) = (kk * t).sin_cos();
            s += kk * w * (-self.cos[k] * sn + self.sin[k] * cs);
        }
        s
    }
    fn n_basis(&self) -> usize {
        1 + 2 * self.cos.len()
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        let t = self.w() * (ctx.position - self.phase_origin);
        out[0] = 1.0;
        for k in 0..self.cos.len() {
            let (sn, cs) = ((k + 1) as f64 * t).sin_cos();
            out[1 + 2 * k] = cs;
            out[2 + 2 * k] = sn;
        }
    }
    fn coefficients(&self) -> Vec<f64> {
        let mut c = vec![self.offset];
        for k in 0..self.cos.len() {
            c.push(self.cos[k]);
            c.push(self.sin[k]);
        }
        c
    }
    fn coefficient_names(&self) -> Vec<String> {
        let mut c = vec!["offset".to_string()];
        for k in 1..=self.cos.len() {
            c.push(format!("cos{k}"));
            c.push(format!("sin{k}"));
        }
        c
    }
}

/// Thermal drift growing linearly in time: `e(t) = rate · (t − t0)` for `t ≥ t0`, 0 before.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalLinear {
    /// Drift rate (mm/s or rad/s).
    pub rate_per_s: f64,
    /// Start of the drift (s).
    pub t0_s: f64,
}

impl ThermalLinear {
    fn phi(&self, t: f64) -> f64 {
        (t - self.t0_s).max(0.0)
    }
}

impl ErrorModel for ThermalLinear {
    fn value(&self, ctx: &Context) -> f64 {
        self.rate_per_s * self.phi(ctx.time_s)
    }
    fn derivative(&self, _: &Context) -> f64 {
        0.0
    }
    fn n_basis(&self) -> usize {
        1
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        out[0] = self.phi(ctx.time_s);
    }
    fn coefficients(&self) -> Vec<f64> {
        vec![self.rate_per_s]
    }
    fn coefficient_names(&self) -> Vec<String> {
        vec!["rate_per_s".into()]
    }
}

/// First-order thermal drift towards a steady state: `e(t) = A · (1 − exp(−(t − t0)/τ))` for
/// `t ≥ t0`, 0 before. Linear in the amplitude `A` for a fixed time constant `τ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalExponential {
    amplitude: f64,
    tau_s: f64,
    t0_s: f64,
}

impl ThermalExponential {
    /// Amplitude (mm or rad), time constant τ (s, > 0), start time (s).
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] for τ ≤ 0 or non-finite inputs.
    pub fn new(amplitude: f64, tau_s: f64, t0_s: f64) -> Result<ThermalExponential> {
        if !(tau_s.is_finite() && tau_s > 0.0 && amplitude.is_finite() && t0_s.is_finite()) {
            return Err(invalid(
                "thermal_exponential model",
                format!("tau_s = {tau_s} must be > 0, inputs finite"),
            ));
        }
        Ok(ThermalExponential {
            amplitude,
            tau_s,
            t0_s,
        })
    }
    fn phi(&self, t: f64) -> f64 {
        let dt = t - self.t0_s;
        if dt <= 0.0 {
            0.0
        } else {
            -(-dt / self.tau_s).exp_m1()
        }
    }
}

impl ErrorModel for ThermalExponential {
    fn value(&self, ctx: &Context) -> f64 {
        self.amplitude * self.phi(ctx.time_s)
    }
    fn derivative(&self, _: &Context) -> f64 {
        0.0
    }
    fn n_basis(&self) -> usize {
        1
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        out[0] = self.phi(ctx.time_s);
    }
    fn coefficients(&self) -> Vec<f64> {
        vec![self.amplitude]
    }
    fn coefficient_names(&self) -> Vec<String> {
        vec!["amplitude".into()]
    }
}

/// Reversal error (backlash, lost motion): `e = +span/2` moving in the positive direction,
/// `−span/2` moving in the negative direction, 0 when the direction is unknown (the mean of both).
/// The ISO 230-2 reversal value of the axis is `span`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reversal {
    /// Full reversal span B (mm or rad).
    pub span: f64,
}

impl ErrorModel for Reversal {
    fn value(&self, ctx: &Context) -> f64 {
        0.5 * self.span * ctx.direction.sign()
    }
    fn derivative(&self, _: &Context) -> f64 {
        0.0
    }
    fn n_basis(&self) -> usize {
        1
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        out[0] = 0.5 * ctx.direction.sign();
    }
    fn coefficients(&self) -> Vec<f64> {
        vec![self.span]
    }
    fn coefficient_names(&self) -> Vec<String> {
        vec!["span".into()]
    }
}

/// The sum of several models (e.g. a Legendre geometric part + reversal + thermal drift).
/// Its basis is the concatenation of the parts' bases; it is linear in coefficients only when
/// every part is (otherwise `n_basis() == 0`).
#[derive(Debug)]
pub struct Sum {
    parts: Vec<Box<dyn ErrorModel>>,
}

impl Sum {
    /// Sum of `parts`.
    pub fn new(parts: Vec<Box<dyn ErrorModel>>) -> Sum {
        Sum { parts }
    }
    /// The parts.
    pub fn parts(&self) -> &[Box<dyn ErrorModel>] {
        &self.parts
    }
    fn linear(&self) -> bool {
        self.parts.iter().all(|p| p.n_basis() > 0)
    }
}

impl ErrorModel for Sum {
    fn value(&self, ctx: &Context) -> f64 {
        self.parts.iter().map(|p| p.value(ctx)).sum()
    }
    fn derivative(&self, ctx: &Context) -> f64 {
        self.parts.iter().map(|p| p.derivative(ctx)).sum()
    }
    fn n_basis(&self) -> usize {
        if self.linear() {
            self.parts.iter().map(|p| p.n_basis()).sum()
        } else {
            0
        }
    }
    fn basis(&self, ctx: &Context, out: &mut [f64]) {
        if !self.linear() {
            return;
        }
        let mut i = 0;
        for p in &self.parts {
            let n = p.n_basis();
            p.basis(ctx, &mut out[i..i + n]);
            i += n;
        }
    }
    fn coefficients(&self) -> Vec<f64> {
        if !self.linear() {
            return Vec::new();
        }
        self.parts.iter().flat_map(|p| p.coefficients()).collect()
    }
    fn coefficient_names(&self) -> Vec<String> {
        if !self.linear() {
            return Vec::new();
        }
        self.parts
            .iter()
            .enumerate()
            .flat_map(|(i, p)| {
                p.coefficient_names()
                    .into_iter()
                    .map(move |n| format!("part{i}.{n}"))
            })
            .collect()
    }
    fn domain(&self) -> Option<(f64, f64)> {
        self.parts
            .iter()
            .filter_map(|p| p.domain())
            .reduce(|a, b| (a.0.max(b.0), a.1.min(b.1)))
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Direction, testutil::*};
    use super::*;
    use approx::assert_relative_eq;

    // Finite-difference tolerance: central differences with h = 1e-3 mm have truncation error
    // h²/6·|f'''|; for the smooth models below that is < 1e-9 relative to |f'|, round-off ≈ 1e-13/h.
    const FD_REL: f64 = 1e-6;

    fn ctxs(lo: f64, hi: f64) -> Vec<Context> {
        (0..=20)
            .map(|i| Context {
                position: lo + (hi - lo) * (i as f64 + 0.37) / 21.0,
                time_s: 120.0,
                direction: Direction::Positive,
            })
            .collect()
    }

    #[test]
    fn legendre_matches_closed_forms_and_fd() {
        // P2(u) = (3u² − 1)/2, P3(u) = (5u³ − 3u)/2 (closed forms).
        let m = Legendre::new(vec![0.001, 0.002, -0.003, 0.004], -400.0, 400.0).unwrap();
        for c in ctxs(-400.0, 400.0) {
            let u = c.position / 400.0;
            let want = 0.001 + 0.002 * u - 0.003 * (3.0 * u * u - 1.0) / 2.0
                + 0.004 * (5.0 * u.powi(3) - 3.0 * u) / 2.0;
            assert_relative_eq!(m.value(&c), want, epsilon = 1e-15);
            let d = m.derivative(&c);
            assert_relative_eq!(d, fd(&m, &c, 1e-3), epsilon = FD_REL * d.abs().max(1e-9));
            check_basis(&m, &c);
        }
        assert!(Legendre::new(vec![1.0], 1.0, 1.0).is_err());
    }

    #[test]
    fn legendre_high_order_derivative() {
        let m = Legendre::new(
            (0..9).map(|k| 1e-3 / (k as f64 + 1.0)).collect(),
            0.0,
            700.0,
        )
        .unwrap();
        for c in ctxs(0.0, 700.0) {
            let d = m.derivative(&c);
            assert_relative_eq!(d, fd(&m, &c, 1e-3), epsilon = FD_REL * d.abs().max(1e-9));
        }
    }

    #[test]
    fn fourier_fd_and_basis() {
        // Ball-screw pitch error: period 10 mm, two harmonics.
        let m = Fourier::new(0.0005, vec![0.002, 0.0003], vec![-0.001], 10.0, 1.5).unwrap();
        for c in ctxs(0.0, 100.0) {
            let d = m.derivative(&c);
            // h = 1e-4 mm: truncation (2π·2/10)²·h²/6 ≈ 2.6e-9 relative.
            assert_relative_eq!(d, fd(&m, &c, 1e-4), epsilon = FD_REL * d.abs().max(1e-6));
            check_basis(&m, &c);
        }
        // Periodicity.
        assert_relative_eq!(
            m.value(&Context::at(3.0)),
            m.value(&Context::at(13.0)),
            epsilon = 1e-15
        );
        assert!(Fourier::new(0.0, vec![], vec![], 0.0, 0.0).is_err());
    }

    #[test]
    fn thermal_and_reversal() {
        let lin = ThermalLinear {
            rate_per_s: 1e-6,
            t0_s: 60.0,
        };
        assert_eq!(
            lin.value(&Context {
                time_s: 30.0,
                ..Context::default()
            }),
            0.0
        );
        assert_relative_eq!(
            lin.value(&Context {
                time_s: 660.0,
                ..Context::default()
            }),
            6e-4,
            epsilon = 1e-15
        );
        // A(1 − e^{−1}) at t − t0 = τ.
        let ex = ThermalExponential::new(0.01, 600.0, 0.0).unwrap();
        let c = Context {
            time_s: 600.0,
            ..Context::default()
        };
        assert_relative_eq!(
            ex.value(&c),
            0.01 * (1.0 - (-1.0f64).exp()),
            epsilon = 1e-15
        );
        check_basis(&ex, &c);
        check_basis(&lin, &c);
        assert!(ThermalExponential::new(1.0, 0.0, 0.0).is_err());
        let r = Reversal { span: 0.004 };
        let at = |d| Context {
            position: 10.0,
            time_s: 0.0,
            direction: d,
        };
        assert_eq!(r.value(&at(Direction::Positive)), 0.002);
        assert_eq!(r.value(&at(Direction::Negative)), -0.002);
        assert_eq!(r.value(&at(Direction::Unknown)), 0.0);
        for m in [&lin as &dyn ErrorModel, &ex, &r] {
            for c in ctxs(-5.0, 5.0) {
                assert_eq!(m.derivative(&c), fd(m, &c, 1e-3));
            }
        }
    }

    #[test]
    fn sum_adds_and_concatenates() {
        let s = Sum::new(vec![
            Box::new(Legendre::new(vec![0.0, 0.001, 0.002], 0.0, 500.0).unwrap()),
            Box::new(Reversal { span: 0.003 }),
            Box::new(ThermalLinear {
                rate_per_s: 2e-7,
                t0_s: 0.0,
            }),
        ]);
        assert_eq!(s.n_basis(), 5);
        for c in ctxs(0.0, 500.0) {
            check_basis(&s, &c);
            let d = s.derivative(&c);
            assert_relative_eq!(d, fd(&s, &c, 1e-3), epsilon = FD_REL * d.abs().max(1e-9));
        }
    }
}
