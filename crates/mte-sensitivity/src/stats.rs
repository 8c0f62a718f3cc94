//! Small statistics helpers shared by the estimators.

pub use mte_linalg::progress::{NoProgress, Progress};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// A ChaCha8 stream derived from (seed, stream id): the same numbers whatever thread runs it.
pub(crate) fn stream(seed: u64, id: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(id);
    r
}

/// Linear-interpolation percentile (q ∈ [0, 1]) of an ascending slice.
pub(crate) fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = q * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// Percentile interval and standard deviation of bootstrap replicates.
pub(crate) fn interval(mut reps: Vec<f64>, confidence: f64) -> ([f64; 2], f64) {
    let n = reps.len() as f64;
    let mean = reps.iter().sum::<f64>() / n;
    let sd = (reps.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
    reps.sort_by(f64::total_cmp);
    let a = 0.5 * (1.0 - confidence);
    ([percentile(&reps, a), percentile(&reps, 1.0 - a)], sd)
}

/// Spearman rank correlation of two equally long slices (average ranks for ties).
pub fn spearman(a: &[f64], b: &[f64]) -> f64 {
    fn ranks(v: &[f64]) -> Vec<f64> {
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by(|&i, &j| v[i].total_cmp(&v[j]));
        let mut r = vec![0.0; v.len()];
        let mut i = 0;
        while i < idx.len() {
            let mut j = i;
            while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
                j += 1;
            }
            let avg = (i + j) as f64 / 2.0;
            for &t in &idx[i..=j] {
                r[t] = avg;
            }
            i = j + 1;
        }
        r
    }
    let (ra, rb) = (ranks(a), ranks(b));
    let n = ra.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let cov: f64 = ra.iter().zip(&rb).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = ra.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = rb.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}
