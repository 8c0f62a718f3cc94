//! Probability distributions of error parameters, for Monte Carlo sampling: the workspace's one
//! [`Distribution`] (defined in `mte-sensitivity`, re-exported here), and the error-set file's
//! tolerance form "±t at kσ".

use crate::error::{Result, invalid};
pub use mte_sensitivity::Distribution;

/// A normal distribution from a tolerance "±t at kσ": `sd = t/k`, mean 0; truncated at ±t
/// when `truncate` is true.
///
/// ```
/// let d = mte_errors::distribution::from_tolerance(0.015, 3.0, false).unwrap();
/// assert!((d.sd() - 0.005).abs() < 1e-15);
/// ```
///
/// # Errors
/// [`crate::Error::Invalid`] for t ≤ 0 or k ≤ 0.
pub fn from_tolerance(tolerance: f64, sigma_level: f64, truncate: bool) -> Result<Distribution> {
    if !(tolerance.is_finite() && tolerance > 0.0 && sigma_level.is_finite() && sigma_level > 0.0) {
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
            lo: -tolerance,
            hi: tolerance,
        }
    } else {
        Distribution::Normal { mean: 0.0, sd }
    };
    validate(&d, "tolerance")?;
    Ok(d)
}

/// Checks a distribution's parameters ([`Distribution::validate`]), as this crate's error;
/// `what` names the distribution's type.
///
/// # Errors
/// [`crate::Error::Invalid`] for a non-positive sd, an empty interval, non-finite values, or a
/// truncation interval holding (almost) none of the parent normal's probability.
pub fn validate(d: &Distribution, what: &str) -> Result<()> {
    d.validate(what).map_err(|e| match e {
        mte_sensitivity::Error::InvalidInput { field, message, .. } => invalid(
            format!("{what} distribution"),
            format!("field `{field}`: {message}"),
        ),
        e => invalid(format!("{what} distribution"), e.to_string()),
    })
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
        let (m, s, lo, hi) = moments(&Distribution::Uniform { lo: -3.0, hi: 1.0 }, n);
        assert!(
            (m + 1.0).abs() < 0.03
                && (s - 4.0 / 12f64.sqrt()).abs() < 0.03
                && lo >= -3.0
                && hi <= 1.0
        );
        // Truncated at ±1σ: variance = 1 − 2φ(1)/(2Φ(1) − 1) = 0.29112 (standard formula), sd 0.53956.
        let d = from_tolerance(15e-3, 1.0, true).unwrap();
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
            lo: 3.0,
            hi: 4.0,
        };
        let (m, s, lo, hi) = moments(&d, n);
        assert!(lo >= 3.0 && hi <= 4.0 && (m - 3.26045).abs() < 0.006, "{m}");
        assert!((d.sd() - s).abs() < 0.005, "{} vs sampled {s}", d.sd());
    }

    #[test]
    fn invalid_parameters() {
        assert!(validate(&Distribution::Normal { mean: 0.0, sd: 0.0 }, "normal").is_err());
        assert!(validate(&Distribution::Uniform { lo: 1.0, hi: 1.0 }, "uniform").is_err());
        assert!(
            validate(
                &Distribution::TruncatedNormal {
                    mean: 0.0,
                    sd: 1.0,
                    lo: 50.0,
                    hi: 51.0
                },
                "truncated_normal"
            )
            .is_err()
        );
        assert!(from_tolerance(-1.0, 3.0, false).is_err());
        assert_eq!(from_tolerance(15.0, 3.0, false).unwrap().sd(), 5.0);
    }
}
