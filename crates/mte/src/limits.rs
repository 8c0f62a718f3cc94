//! Limits of the command line: the memory a command may allocate in proportion to a user's
//! number (`--n`, `--trials`, a Sobol' sample size, a PCE degree), checked before allocating.
//!
//! The limit is 4 GB unless `--max-memory-gb` or the environment variable `MTE_MAX_MEMORY_GB`
//! says otherwise (the flag wins). A command computes the bytes it needs and calls
//! [`check_memory`], which refuses with the figure:
//!
//! ```
//! let err = mte::limits::check_memory_with("Sobol' samples (N = 10^12)", 62.5e9, 4.0).unwrap_err();
//! assert_eq!(
//!     err.to_string(),
//!     "Sobol' samples (N = 10^12) needs 62.5 GB; this limit is 4 GB, set by --max-memory-gb or MTE_MAX_MEMORY_GB"
//! );
//! ```

use crate::CliError;
use std::sync::OnceLock;

/// The default limit, GB (10⁹ bytes).
pub const DEFAULT_MAX_MEMORY_GB: f64 = 4.0;

static FLAG: OnceLock<f64> = OnceLock::new();

/// Sets the limit from `--max-memory-gb` (called once by `main`).
///
/// # Errors
/// [`CliError::Usage`] naming the flag when the value is not a positive finite number.
pub fn set_max_memory_gb(gb: f64) -> Result<(), CliError> {
    if !(gb.is_finite() && gb > 0.0) {
        return Err(CliError::Usage(format!(
            "--max-memory-gb: expected a positive number of GB, got {gb}"
        )));
    }
    let _ = FLAG.set(gb);
    Ok(())
}

/// The limit in GB: `--max-memory-gb`, else `MTE_MAX_MEMORY_GB`, else 4.
///
/// # Errors
/// [`CliError::Usage`] when `MTE_MAX_MEMORY_GB` is set but not a positive number.
pub fn max_memory_gb() -> Result<f64, CliError> {
    if let Some(gb) = FLAG.get() {
        return Ok(*gb);
    }
    match std::env::var("MTE_MAX_MEMORY_GB") {
        Ok(s) => match s.trim().parse::<f64>() {
            Ok(gb) if gb.is_finite() && gb > 0.0 => Ok(gb),
            _ => Err(CliError::Usage(format!(
                "MTE_MAX_MEMORY_GB: expected a positive number of GB, got `{s}`"
            ))),
        },
        Err(_) => Ok(DEFAULT_MAX_MEMORY_GB),
    }
}

/// Refuses `what` when it needs more than the limit; `bytes` may be computed in `f64` so that
/// huge counts do not overflow.
///
/// # Errors
/// [`CliError::Usage`] with the figure and how to raise the limit.
pub fn check_memory(what: &str, bytes: f64) -> Result<(), CliError> {
    check_memory_with(what, bytes, max_memory_gb()?)
}

/// [`check_memory`] against an explicit limit (GB).
///
/// # Errors
/// As [`check_memory`].
pub fn check_memory_with(what: &str, bytes: f64, limit_gb: f64) -> Result<(), CliError> {
    let gb = bytes / 1e9;
    if gb.is_nan() || gb > limit_gb {
        return Err(CliError::Usage(format!(
            "{what} needs {}; this limit is {} GB, set by --max-memory-gb or MTE_MAX_MEMORY_GB",
            fmt_gb(gb),
            if limit_gb.fract() == 0.0 {
                format!("{limit_gb:.0}")
            } else {
                crate::report::fmt_sig(limit_gb, 3)
            }
        )));
    }
    Ok(())
}

fn fmt_gb(gb: f64) -> String {
    if !gb.is_finite() {
        "more memory than exists".into()
    } else if gb >= 1e6 {
        format!("{gb:.2e} GB")
    } else {
        format!("{} GB", crate::report::fmt_sig(gb, 3))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_message_gives_the_figure_and_the_limit() {
        assert!(check_memory_with("x", 3.9e9, 4.0).is_ok());
        let e = check_memory_with("x", 6.4e9, 4.0).unwrap_err().to_string();
        assert!(e.contains("needs 6.40 GB; this limit is 4 GB"), "{e}");
        let e = check_memory_with("x", f64::INFINITY, 4.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("more memory than exists"), "{e}");
        let e = check_memory_with("x", 1e9, 0.5).unwrap_err().to_string();
        assert!(e.contains("this limit is 0.500 GB"), "{e}");
    }
}
