//! A progress sink for long computations (a Sobol' study, a diagnosis): the computation calls
//! [`Progress::inc`] with the work units it just finished, a command line draws them as a bar.
//!
//! ```
//! use mte_linalg::progress::Progress;
//! use std::sync::atomic::{AtomicU64, Ordering};
//! let done = AtomicU64::new(0);
//! let sink = |n: u64| {
//!     done.fetch_add(n, Ordering::Relaxed);
//! };
//! sink.inc(3);
//! assert_eq!(done.load(Ordering::Relaxed), 3);
//! ```

/// A progress sink: called with the number of work units just finished.
pub trait Progress: Sync {
    /// `n` more units done.
    fn inc(&self, n: u64);
}

impl<F: Fn(u64) + Sync> Progress for F {
    fn inc(&self, n: u64) {
        self(n)
    }
}

/// No progress reporting.
pub struct NoProgress;

impl Progress for NoProgress {
    fn inc(&self, _n: u64) {}
}
