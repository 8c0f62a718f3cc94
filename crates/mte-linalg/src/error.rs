//! The error type of `mte-linalg`.
//!
//! Every variant carries the offending numbers (which input, which index, which value,
//! which limit) so the message can be shown to a user as it is.

/// Everything that can go wrong in `mte-linalg`.
///
/// Numerical trouble (rank deficiency, a covariance that is not positive definite, an SVD that
/// does not converge) is reported here, never by a panic.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LinalgError {
    /// An input holds NaN or ±∞.
    #[error("{what}: non-finite value {value} at row {row}, column {col}")]
    NonFinite {
        /// Which input (e.g. "design matrix A").
        what: String,
        /// Row of the first offending entry (0-based).
        row: usize,
        /// Column of the first offending entry (0-based; 0 for vectors).
        col: usize,
        /// The offending value.
        value: f64,
    },
    /// Shapes of the inputs do not fit together.
    #[error("{what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// Which input or relation (e.g. "right-hand side b").
        what: String,
        /// What the shape should have been (e.g. "12 rows").
        expected: String,
        /// What it was.
        found: String,
    },
    /// An input has no rows or no columns.
    #[error("{what} is empty ({rows} × {cols})")]
    Empty {
        /// Which input.
        what: String,
        /// Its number of rows.
        rows: usize,
        /// Its number of columns.
        cols: usize,
    },
    /// Fewer observations than unknowns where a unique solution is required.
    #[error("too few rows: {rows} observations for {needed} unknowns")]
    TooFewRows {
        /// Number of observations (rows).
        rows: usize,
        /// Number of rows needed (the number of unknowns to determine).
        needed: usize,
    },
    /// The design does not determine every unknown; `combinations` names the parameter
    /// combinations the data cannot tell apart (null-space directions).
    #[error(
        "rank deficient: rank {rank} of {expected} expected; not determined by the data: {}",
        if combinations.is_empty() { "(no column names given)".to_string() } else { combinations.join("; ") }
    )]
    RankDeficient {
        /// Numerical rank found.
        rank: usize,
        /// Rank needed for a unique solution (number of free unknowns).
        expected: usize,
        /// Null-space directions written as named combinations, e.g. `"EX0B − 1.00·EX0C"`.
        combinations: Vec<String>,
    },
    /// A matrix that must be symmetric positive definite (a covariance, a weight matrix) is not.
    #[error("{what} is not symmetric positive definite: {detail}")]
    NotPositiveDefinite {
        /// Which input.
        what: String,
        /// What was found (e.g. the failing pivot, the asymmetric entry).
        detail: String,
    },
    /// A weight is zero, negative or otherwise unusable.
    #[error("{what}: invalid value {value} at index {index}; expected {expected}")]
    InvalidValue {
        /// Which input.
        what: String,
        /// Index of the offending entry.
        index: usize,
        /// The offending value.
        value: f64,
        /// What was expected (e.g. "a positive weight").
        expected: String,
    },
    /// The equality constraints `C x = d` have no solution.
    #[error(
        "equality constraints C x = d are inconsistent: ‖C x − d‖ = {residual:.3e} > {tolerance:.3e}"
    )]
    InconsistentConstraints {
        /// Norm of the constraint residual of the best (least-squares) x.
        residual: f64,
        /// Tolerance that was exceeded.
        tolerance: f64,
    },
    /// An iterative decomposition (SVD, eigen-decomposition) did not converge.
    #[error("{what} did not converge")]
    NoConvergence {
        /// Which decomposition.
        what: String,
    },
    /// A parameter of a routine is out of its range.
    #[error("invalid parameter {name} = {value}: expected {expected}")]
    InvalidParameter {
        /// Parameter name.
        name: String,
        /// The given value, formatted.
        value: String,
        /// What was expected.
        expected: String,
    },
    /// A zero-copy view was requested for data that is not laid out contiguously.
    #[error("{what}: cannot view without copying ({detail})")]
    NotContiguous {
        /// Which input.
        what: String,
        /// Why (e.g. the stride found).
        detail: String,
    },
}

/// `Result` with [`LinalgError`].
pub type Result<T> = std::result::Result<T, LinalgError>;
