//! Probability distributions of error parameters, for Monte Carlo sampling.

use crate::error::{Result, invalid};
use mte_linalg::stats::{normal_cdf, normal_quantile};
use rand::Rng;

/// Distribution of one error parameter (internal units, mm or rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distribution {
    /// Normal N(mean, sd²).
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation (> 0).
        sd: f64,
    },
    /// Uniform on [low, high].
    Uniform {
        /// Lower bound.
        low: f64,
        /// Upper bound (> low).
        high: f64,
    },
    /// Normal N(mean, sd²) restricted to [low, high], sampled exactly by inverting the CDF.
    TruncatedNormal {
        /// Mean of the parent normal.
        mean: f64,
        /// Standard deviation of the parent normal.
        sd: f64,
        /// Lower bound.
        low: f64,
        /// Upper bound.
        high: f64,
    },
}

impl Distribution {
    /// A normal distribution from a tolerance "±t at kσ": `sd = t/k`, mean 0; truncated at ±t
    /// when `truncate` is true.
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] for t ≤ 0 or k ≤ 0.
    pub fn from_tolerance(
        tolerance: f64,
        sigma_level: f64,
        truncate: bool,
    ) -> Result<Distribution> {
        if !(tolerance.is_finite()
            && tolerance > 0.0
            && sigma_level.is_finite()
            && sigma_level > 0.0)
        {
            return Err(invalid(
                "tolerance distribution",
                format!("tolerance {tolerance} and sigma level {sigma_level} must be > 0"),
            ));
        }
        let sd = tolerance / sigma_level;
        let d = if truncate {
            Distribution::TruncatedNormal {
                mean: 0.0,
                sd,
                low: -tolerance,
                high: tolerance,
            }
        } else {
            Distribution::Normal { mean: 0.0, sd }
        };
        d.validate()?;
        Ok(d)
    }

    /// Check the parameters.
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] for a non-positive sd, empty interval, non-finite values, or a
    /// truncation interval holding less than 1e-12 of the parent normal's probability.
    pub fn validate(&self) -> Result<()> {
        let fin = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match *self {
            Distribution::Normal { mean, sd } => {
                if !fin(&[mean, sd]) || sd <= 0.0 {
                    return Err(invalid(
                        "normal distribution",
                        format!("sd = {sd} must be > 0, mean = {mean} finite"),
                    ));
                }
            }
            Distribution::Uniform { low, high } => {
                if !fin(&[low, high]) || high <= low {
                    return Err(invalid(
                        "uniform distribution",
                        format!("need low < high, got [{low}, {high}]"),
                    ));
                }
            }
            Distribution::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => {
                if !fin(&[mean, sd, low, high]) || sd <= 0.0 || high <= low {
                    return Err(invalid(
                        "truncated normal distribution",
                        format!("need sd > 0 and low < high, got sd = {sd}, [{low}, {high}]"),
                    ));
                }
                let (pa, pb) = self.tail_probs();
                if pb - pa < 1e-12 {
                    return Err(invalid(
                        "truncated normal distribution",
                        format!(
                            "the interval [{low}, {high}] holds only {:.1e} of N({mean}, {sd}²)",
                            pb - pa
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// For the truncated normal: Φ of the standardised bounds, in the lower tail (mirrored when
    /// both bounds are above the mean, for accuracy).
    fn tail_probs(&self) -> (f64, f64) {
        if let Distribution::TruncatedNormal {
            mean,
            sd,
            low,
            high,
        } = *self
        {
            let (a, b) = ((low - mean) / sd, (high - mean) / sd);
            if a > 0.0 {
                (normal_cdf(-b), normal_cdf(-a))
            } else {
                (normal_cdf(a), normal_cdf(b))
            }
        } else {
            (0.0, 1.0)
        }
    }

    /// Draw one value.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        match *self {
            Distribution::Normal { mean, sd } => {
                let z: f64 = rng.sample(rand_distr::StandardNormal);
                mean + sd * z
            }
            Distribution::Uniform { low, high } => low + (high - low) * rng.random::<f64>(),
            Distribution::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => {
                let a = (low - mean) / sd;
                let (pa, pb) = self.tail_probs();
                let u: f64 = rng.random();
                let p = (pa + u * (pb - pa)).clamp(f64::MIN_POSITIVE, 1.0 - f64::EPSILON);
                let z = normal_quantile(p);
                let z = if a > 0.0 { -z } else { z };
                (mean + sd * z).clamp(low, high)
            }
        }
    }

    /// Nominal value used when not sampling: the mean (normal), the midpoint (uniform), the
    /// parent mean clamped into the interval (truncated normal).
    pub fn nominal(&self) -> f64 {
        match *self {
            Distribution::Normal { mean, .. } => mean,
            Distribution::Uniform { low, high } => 0.5 * (low + high),
            Distribution::TruncatedNormal {
                mean, low, high, ..
            } => mean.clamp(low, high),
        }
    }

    /// Standard deviation of the distribution. For the truncated normal this is the truncated
    /// law's (±1σ truncation: 0.54 of the parent's), not the parent's `sd` field.
    pub fn sd(&self) -> f64 {
        match *self {
            Distribution::Normal { sd, .. } => sd,
            Distribution::Uniform { low, high } => (high - low) / 12f64.sqrt(),
            Distribution::TruncatedNormal {
                mean,
                sd,
                low,
                high,
            } => mte_linalg::stats::truncated_normal_moments(mean, sd, low, high).1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn moments(d: &Distribution, n: usize) -> (f64, f64, f64, f64) {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let xs: Vec<f64> = (0..n).map(|_| d.sample(&mut rng)).collect();
        let m = xs.iter().sum::<f64>() / n as f64;
        let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
        let lo = xs.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        (m, v.sqrt(), lo, hi)
    }

    #[test]
    fn sample_moments() {
        // n = 40000: standard error of the mean = sd/200, of the sd ≈ sd/283; 5 standard errors.
        let n = 40_000;
        let (m, s, _, _) = moments(&Distribution::Normal { mean: 1.0, sd: 2.0 }, n);
        assert!(
            (m - 1.0).abs() < 5.0 * 2.0 / 200.0 && (s - 2.0).abs() < 5.0 * 2.0 / 283.0,
            "{m} {s}"
        );
        let (m, s, lo, hi) = moments(
            &Distribution::Uniform {
                low: -3.0,
                high: 1.0,
            },
            n,
        );
        assert!(
            (m + 1.0).abs() < 0.03
                && (s - 4.0 / 12f64.sqrt()).abs() < 0.03
                && lo >= -3.0
                && hi <= 1.0
        );
        // Truncated at ±1σ: variance = 1 − 2φ(1)/(2Φ(1) − 1) = 0.29112 (standard formula), sd 0.53956.
        let d = Distribution::from_tolerance(15e-3, 1.0, true).unwrap();
        let (m, s, lo, hi) = moments(&d, n);
        assert!(m.abs() < 5.0 * 15e-3 * 0.54 / 200.0, "{m}");
        assert!((s / 15e-3 - 0.53956).abs() < 0.01, "{}", s / 15e-3);
        assert!((d.sd() / 15e-3 - 0.539_560).abs() < 1e-6, "{}", d.sd());
        assert!(lo >= -15e-3 && hi <= 15e-3);
        // One-sided far tail [3σ, 4σ]: every draw inside; mean of N(0,1) on [3,4] = (φ(3) − φ(4))/(Φ(4) − Φ(3)) = 3.26045;
        // sd of that truncated law ≈ 0.23, n = 40000 → standard error 0.0012.
        let d = Distribution::TruncatedNormal {
            mean: 0.0,
            sd: 1.0,
            low: 3.0,
            high: 4.0,
        };
        let (m, s, lo, hi) = moments(&d, n);
        assert!(lo >= 3.0 && hi <= 4.0 && (m - 3.26045).abs() < 0.006, "{m}");
        assert!((d.sd() - s).abs() < 0.005, "{} vs sampled {s}", d.sd());
    }

    #[test]
    fn invalid_parameters() {
        assert!(
            Distribution::Normal { mean: 0.0, sd: 0.0 }
                .validate()
                .is_err()
        );
        assert!(
            Distribution::Uniform {
                low: 1.0,
                high: 1.0
            }
            .validate()
            .is_err()
        );
        assert!(
            Distribution::TruncatedNormal {
                mean: 0.0,
                sd: 1.0,
                low: 50.0,
                high: 51.0
            }
            .validate()
            .is_err()
        );
        assert!(Distribution::from_tolerance(-1.0, 3.0, false).is_err());
        assert_eq!(
            Distribution::from_tolerance(15.0, 3.0, false).unwrap().sd(),
            5.0
        );
    }
}
