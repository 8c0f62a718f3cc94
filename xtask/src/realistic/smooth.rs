//! Random smooth error functions: what a real machine's component errors look like.
//!
//! A component error of a linear axis is drawn as a random cubic polynomial plus two or three
//! low-frequency waves of random phase with wavelengths between half and twice the stroke, then
//! scaled so that its largest deviation from its mean line over the stroke equals a drawn size.
//! It is deliberately neither a Legendre polynomial nor a single sine: a base model of degree 3
//! fits it closely but not exactly, as on a real machine. An error motion of a rotary axis is a
//! random sum of the first three harmonics of a turn (periodic over one turn by construction).
//! [`Waviness::Wavy`] draws them with more and shorter waves and harmonics (robustness rows).

use rand::Rng;
use std::f64::consts::TAU;

/// How wavy the ordinary errors are drawn ([`Smooth::draw`], [`Periodic::draw`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Waviness {
    /// Two or three waves of ½–2 strokes on the cubic; rotary error motions up to the 3rd
    /// harmonic of a turn.
    #[default]
    Gentle,
    /// Two to five waves of ⅕–2 strokes; rotary error motions up to the 5th harmonic: smooth
    /// errors with more shape than a cubic and a few waves hold, for the studies' robustness
    /// rows (the base model's completions must absorb them).
    Wavy,
}

/// A smooth function of a linear axis coordinate over `[lo, hi]` (mm), value in the unit of its
/// size (the caller decides: mm or rad).
#[derive(Debug, Clone)]
pub struct Smooth {
    lo: f64,
    hi: f64,
    poly: [f64; 4],
    waves: Vec<(f64, f64, f64)>,
    scale: f64,
    offset: f64,
}

impl Smooth {
    /// The zero function.
    pub fn zero() -> Self {
        Self {
            lo: 0.0,
            hi: 1.0,
            poly: [0.0; 4],
            waves: Vec::new(),
            scale: 0.0,
            offset: 0.0,
        }
    }

    /// A random smooth function over `[lo, hi]` whose peak-to-valley over the stroke is `size`
    /// (sign and shape random). Zero at the stroke's lower end, as an interferometer run that is
    /// zeroed at its first target.
    pub fn draw(rng: &mut impl Rng, lo: f64, hi: f64, size: f64, waviness: Waviness) -> Self {
        let stroke = hi - lo;
        let poly = [
            0.0,
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ];
        let (most_waves, shortest) = match waviness {
            Waviness::Gentle => (3, 0.5),
            Waviness::Wavy => (5, 0.2),
        };
        let n_waves = rng.random_range(2..=most_waves);
        let waves = (0..n_waves)
            .map(|_| {
                (
                    rng.random_range(0.2..0.8),
                    rng.random_range(shortest..2.0) * stroke,
                    rng.random_range(0.0..TAU),
                )
            })
            .collect();
        let mut f = Self {
            lo,
            hi,
            poly,
            waves,
            scale: 1.0,
            offset: 0.0,
        };
        let samples: Vec<f64> = (0..=200)
            .map(|i| f.raw(lo + stroke * i as f64 / 200.0))
            .collect();
        let max = samples.iter().copied().fold(f64::MIN, f64::max);
        let min = samples.iter().copied().fold(f64::MAX, f64::min);
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        f.scale = sign * size / (max - min).max(1e-12);
        f.offset = f.raw(lo);
        f
    }

    fn raw(&self, x: f64) -> f64 {
        let u = 2.0 * (x - self.lo) / (self.hi - self.lo) - 1.0;
        let p = self.poly[0] + u * (self.poly[1] + u * (self.poly[2] + u * self.poly[3]));
        p + self
            .waves
            .iter()
            .map(|(a, l, ph)| a * (TAU * (x - self.lo) / l + ph).sin())
            .sum::<f64>()
    }

    /// The value at `x`.
    pub fn at(&self, x: f64) -> f64 {
        if self.scale == 0.0 {
            return 0.0;
        }
        self.scale * (self.raw(x) - self.offset)
    }

    /// The mean of its values at the positions `at` (each once).
    pub fn mean(&self, at: &[f64]) -> f64 {
        at.iter().map(|&x| self.at(x)).sum::<f64>() / at.len().max(1) as f64
    }

    /// The slope of the least-squares line through its values at the positions `at` (each
    /// once): ISO 230-1's reference line of what those positions show.
    pub fn slope(&self, at: &[f64]) -> f64 {
        let c = at.iter().sum::<f64>() / at.len().max(1) as f64;
        let spread: f64 = at.iter().map(|&x| (x - c).powi(2)).sum();
        if spread == 0.0 {
            return 0.0;
        }
        at.iter().map(|&x| (x - c) * self.at(x)).sum::<f64>() / spread
    }
}

/// A smooth periodic function of a rotary axis angle (rad): random first to third harmonics of a
/// turn, largest absolute value `size`.
#[derive(Debug, Clone)]
pub struct Periodic {
    harmonics: Vec<(f64, f64, f64)>,
}

impl Periodic {
    /// The zero function.
    pub fn zero() -> Self {
        Self {
            harmonics: Vec::new(),
        }
    }

    /// A random periodic function with largest absolute value `size`.
    pub fn draw(rng: &mut impl Rng, size: f64, waviness: Waviness) -> Self {
        let highest = match waviness {
            Waviness::Gentle => 3,
            Waviness::Wavy => 5,
        };
        let mut harmonics: Vec<(f64, f64, f64)> = (1..=highest)
            .map(|k| {
                (
                    rng.random_range(0.2..1.0) / k as f64,
                    k as f64,
                    rng.random_range(0.0..TAU),
                )
            })
            .collect();
        let f = Self {
            harmonics: harmonics.clone(),
        };
        let max = (0..360)
            .map(|i| f.at((i as f64).to_radians()).abs())
            .fold(0.0, f64::max);
        for h in &mut harmonics {
            h.0 *= size / max.max(1e-12);
        }
        Self { harmonics }
    }

    /// Its component of `k` cycles per turn as `(a, b)` of `a·sin(kθ) + b·cos(kθ)`.
    pub fn component(&self, k: f64) -> (f64, f64) {
        self.harmonics
            .iter()
            .filter(|h| h.1 == k)
            .fold((0.0, 0.0), |(a, b), (amp, _, ph)| {
                (a + amp * ph.cos(), b + amp * ph.sin())
            })
    }

    /// The value at angle `theta` (rad).
    pub fn at(&self, theta: f64) -> f64 {
        self.harmonics
            .iter()
            .map(|(a, k, ph)| a * (k * theta + ph).sin())
            .sum()
    }
}

/// A size drawn uniformly in `[lo, hi]` with a random sign.
pub fn signed(rng: &mut impl Rng, lo: f64, hi: f64) -> f64 {
    let v = rng.random_range(lo..=hi);
    if rng.random_bool(0.5) { v } else { -v }
}
