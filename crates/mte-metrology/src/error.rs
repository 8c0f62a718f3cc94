//! The crate's single error type.

/// Everything that can go wrong in this crate. Each variant names the offending item and value.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MetrologyError {
    /// An input value is not usable (NaN, infinite, negative length or sigma, …).
    #[error("invalid input: {what}")]
    InvalidInput {
        /// What is wrong, naming the item (station/target/observation id, field, value).
        what: String,
    },
    /// Two stations or two targets share an id.
    #[error("duplicate {kind} id `{id}`")]
    DuplicateId {
        /// "station" or "target".
        kind: &'static str,
        /// The repeated id.
        id: String,
    },
    /// Not enough observations / stations / targets for the unknowns.
    #[error("too few data: {what}")]
    TooFewData {
        /// The failed count check with the numbers.
        what: String,
    },
    /// The network has a rank defect beyond the 6 datum parameters.
    #[error("rank defect beyond the datum: {what}")]
    RankDefect {
        /// Which parameters (or parameter combination) cannot be determined.
        what: String,
    },
    /// Gauss–Newton did not converge.
    #[error(
        "no convergence after {iterations} iterations (last max |correction| = {last_step_mm:e} mm)"
    )]
    NoConvergence {
        /// Iterations done.
        iterations: usize,
        /// Last step size (mm).
        last_step_mm: f64,
    },
    /// A datum definition cannot fix the 6 rigid-motion degrees of freedom.
    #[error("invalid datum: {what}")]
    InvalidDatum {
        /// Why.
        what: String,
    },
    /// A parse error in a text input, naming the source, line and field.
    #[error("{source_name}:{line}: {what}")]
    Parse {
        /// File name (or "<input>").
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What was expected.
        what: String,
    },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, MetrologyError>;

pub(crate) fn invalid(what: impl Into<String>) -> MetrologyError {
    MetrologyError::InvalidInput { what: what.into() }
}

impl From<mte_linalg::csv::CsvError> for MetrologyError {
    fn from(e: mte_linalg::csv::CsvError) -> Self {
        MetrologyError::Parse {
            source_name: e.source_name,
            line: e.line,
            what: e.message,
        }
    }
}
