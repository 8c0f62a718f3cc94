//! The error type of `mte-rtest`.

/// Everything that can go wrong in `mte-rtest`. Messages name the file, line, field or
/// parameter and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RtestError {
    /// An axis name is not an axis of the machine (or not of the required kind).
    #[error("axis `{name}`: {message} (machine `{machine}` has axes {known})")]
    UnknownAxis {
        /// The name that was asked for.
        name: String,
        /// Why it does not fit.
        message: String,
        /// The machine.
        machine: String,
        /// The machine's axes, comma separated.
        known: String,
    },
    /// A parameter name is not a known error name for this machine.
    #[error("parameter `{name}`: {message}")]
    UnknownParameter {
        /// The name.
        name: String,
        /// What was expected.
        message: String,
    },
    /// A program, trajectory or dataset is too short to carry the information asked for.
    #[error("{what}: {found} {unit}, at least {needed} needed")]
    TooShort {
        /// What is too short.
        what: String,
        /// What was found.
        found: usize,
        /// The minimum.
        needed: usize,
        /// Unit of the counts ("readings", "waypoints", …).
        unit: String,
    },
    /// An input value is invalid (non-finite, out of range, inconsistent).
    #[error("{field}: {message}")]
    Invalid {
        /// The field, e.g. `setups[1].ball_mm` or `rtest.csv line 17, column dz_um`.
        field: String,
        /// What was found and what was expected.
        message: String,
    },
    /// The commanded axes needed by a program leave an axis stroke.
    #[error(
        "program `{program}`: axis {axis} would go to {value:.4} outside its stroke [{lo:.4}, {hi:.4}] ({unit}) at sample {sample}"
    )]
    OutOfStroke {
        /// The program.
        program: String,
        /// The axis.
        axis: String,
        /// Commanded value.
        value: f64,
        /// Stroke lower end.
        lo: f64,
        /// Stroke upper end.
        hi: f64,
        /// Unit of the values ("mm" or "deg").
        unit: String,
        /// Sample index in the program.
        sample: usize,
    },
    /// The linear axes cannot place the nest on the ball (singular axis directions).
    #[error("inverse kinematics: {0}")]
    Inverse(String),
    /// The kinematics crate reported an error.
    #[error("kinematics: {0}")]
    Kinematics(String),
    /// Too few readings for the number of parameters, or a fit that cannot be carried out.
    #[error("fit: {0}")]
    Fit(String),
    /// Reading or writing a file failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// What the operating system said.
        message: String,
    },
}

/// Result alias of `mte-rtest`.
pub type Result<T> = std::result::Result<T, RtestError>;

impl From<mte_linalg::csv::CsvError> for RtestError {
    fn from(e: mte_linalg::csv::CsvError) -> Self {
        RtestError::Invalid {
            field: format!("{} line {}", e.source_name, e.line),
            message: e.message,
        }
    }
}
