//! Basis functions of covariates: Legendre polynomials over the observed range, sine/cosine
//! pairs of a period, exponential approach in time, and the grids of periods and time
//! constants the diagnosis scans.

use mte_linalg::DMat;

/// Range of the values (min, max).
pub(crate) fn range(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// Legendre polynomials P_d of the values mapped onto [−1, 1] over their observed range, one
/// column per degree in `degrees` (an empty column set when the values do not vary).
pub(crate) fn legendre_columns(values: &[f64], degrees: std::ops::RangeInclusive<usize>) -> DMat {
    let (lo, hi) = range(values);
    let n = values.len();
    let degrees: Vec<usize> = degrees.collect();
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return DMat::zeros(n, 0);
    }
    let max_degree = degrees.iter().copied().max().unwrap_or(0);
    DMat::from_fn(n, degrees.len(), |i, j| {
        let u = 2.0 * (values[i] - lo) / (hi - lo) - 1.0;
        legendre(max_degree, u)[degrees[j]]
    })
}

/// P_0 … P_n at u by Bonnet's recursion.
pub(crate) fn legendre(n: usize, u: f64) -> Vec<f64> {
    let mut p = vec![1.0, u];
    for k in 1..n {
        let k = k as f64;
        let next = ((2.0 * k + 1.0) * u * p[k as usize] - k * p[k as usize - 1]) / (k + 1.0);
        p.push(next);
    }
    p.truncate(n + 1);
    p
}

/// `sin(2π v / period)` and `cos(2π v / period)`.
pub(crate) fn sin_cos_columns(values: &[f64], period: f64) -> DMat {
    let n = values.len();
    DMat::from_fn(n, 2, |i, j| {
        let phase = std::f64::consts::TAU * values[i] / period;
        if j == 0 { phase.sin() } else { phase.cos() }
    })
}

/// Periods to scan along an axis: for a linear axis, log-spaced from 2.5 × the smallest step
/// between distinct positions (above the Nyquist limit of the sampling) to the travel ÷ 1.5
/// (below that a period is a polynomial trend); for a rotary axis, the harmonics 2 … 8 of a
/// turn (the first harmonic is what location errors produce).
pub(crate) fn periods_to_scan(values: &[f64], rotary: bool) -> Vec<f64> {
    if rotary {
        return (2..=8).map(|k| std::f64::consts::TAU / k as f64).collect();
    }
    let mut sorted: Vec<f64> = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    if sorted.len() < 6 {
        return Vec::new();
    }
    let step = sorted
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let travel = sorted[sorted.len() - 1] - sorted[0];
    let (lo, hi) = (2.5 * step, travel / 1.5);
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    // Uniform in frequency, oversampled twice the Fourier resolution 1/travel; the best
    // period is then refined continuously.
    let df = 0.5 / travel;
    let (f_lo, f_hi) = (1.0 / hi, 1.0 / lo);
    let count = ((f_hi - f_lo) / df).ceil() as usize + 1;
    let mut periods: Vec<f64> = (0..count)
        .map(|k| 1.0 / (f_hi - k as f64 * (f_hi - f_lo) / (count - 1).max(1) as f64))
        .collect();
    periods.sort_by(f64::total_cmp);
    periods
}

/// Time constants to scan for a first-order thermal drift: log-spaced from 1/20 to 2 times the
/// time span of the data.
pub(crate) fn time_constants_to_scan(times: &[f64]) -> Vec<f64> {
    let (lo, hi) = range(times);
    let span = hi - lo;
    if span.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Vec::new();
    }
    let count = 12;
    (0..count)
        .map(|k| span / 20.0 * 40f64.powf(k as f64 / (count - 1) as f64))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legendre_matches_closed_forms() {
        for &u in &[-1.0, -0.3, 0.0, 0.7, 1.0] {
            let p = legendre(3, u);
            assert!((p[2] - 0.5 * (3.0 * u * u - 1.0)).abs() < 1e-15);
            assert!((p[3] - 0.5 * (5.0 * u * u * u - 3.0 * u)).abs() < 1e-15);
        }
    }

    #[test]
    fn period_grid_respects_sampling() {
        let x: Vec<f64> = (0..=70).map(|i| i as f64 * 10.0).collect();
        let p = periods_to_scan(&x, false);
        assert!((p[0] - 25.0).abs() < 1e-9 && (p[p.len() - 1] - 700.0 / 1.5).abs() < 1e-9);
        assert!(p.windows(2).all(|w| w[1] > w[0]));
    }
}
