//! The crate's error type.

/// Everything that can go wrong in a sensitivity analysis. Each variant names the
/// offending input, field or estimator and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A distribution parameter or input definition is invalid (zero variance, lo ≥ hi, …).
    #[error("input `{input}`: field `{field}`: {message}")]
    InvalidInput {
        /// Name of the input (or `#index` if unnamed).
        input: String,
        /// The offending field.
        field: String,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A distribution name in a problem file is not known.
    #[error("input `{input}`: unknown distribution `{name}`; expected one of {expected}")]
    UnknownDistribution {
        /// Name of the input.
        input: String,
        /// The name found in the file.
        name: String,
        /// The accepted names.
        expected: &'static str,
    },
    /// A JSON document could not be read.
    #[error("{context}: {message}")]
    Json {
        /// Where in the document (field path).
        context: String,
        /// The parser's message or what was expected.
        message: String,
    },
    /// The sample size is too small for the estimator.
    #[error("{estimator}: sample size {n} is too small; need at least {min}")]
    SampleSize {
        /// Which estimator or method.
        estimator: &'static str,
        /// The size given.
        n: usize,
        /// The smallest acceptable size.
        min: usize,
    },
    /// The model returned a non-finite value.
    #[error("model output {output} is {value} at input point {x:?}")]
    ModelOutput {
        /// Index of the output.
        output: usize,
        /// The value returned (NaN or ±inf).
        value: f64,
        /// The input point that produced it.
        x: Vec<f64>,
    },
    /// Array sizes do not agree.
    #[error("{what}: expected {expected}, got {got}")]
    Dimension {
        /// What was being checked.
        what: String,
        /// The expected size.
        expected: usize,
        /// The size found.
        got: usize,
    },
    /// A correlation matrix is not a valid correlation matrix.
    #[error("correlation matrix: {0}")]
    Correlation(String),
    /// A method parameter is out of range.
    #[error("parameter `{name}`: {message}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// What was wrong and what was expected.
        message: String,
    },
    /// The analysis cannot produce indices (e.g. the output has zero variance).
    #[error("output {output}: {message}")]
    Degenerate {
        /// Index of the output.
        output: usize,
        /// Explanation.
        message: String,
    },
}

/// Result alias of this crate.
pub type Result<T> = std::result::Result<T, Error>;
