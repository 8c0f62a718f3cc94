//! The crate's error type.

/// Everything that can go wrong in `mte-errors`. Every variant names the offending input
/// (file, line, field, parameter) and what was expected.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A JSON document is malformed or a field has the wrong type or value.
    #[error("{source_name}: field `{field}`: {message}")]
    Json {
        /// File name (or `<string>`).
        source_name: String,
        /// Path of the offending field, e.g. `parameters[3].model.coefficients_um`.
        field: String,
        /// What was expected.
        message: String,
    },
    /// A CSV table is malformed.
    #[error("{source_name}: line {line}: {message}")]
    Csv {
        /// File name (or `<string>`).
        source_name: String,
        /// 1-based line number in the file (0 when the table is empty).
        line: usize,
        /// What was expected.
        message: String,
    },
    /// A parameter name is neither an ISO 230-1 name nor an alias of this machine's catalogue.
    #[error("unknown error parameter `{name}` for machine `{machine}`{}", suggest(.suggestions))]
    UnknownParameter {
        /// The name as written.
        name: String,
        /// The machine.
        machine: String,
        /// Close names from the catalogue (edit distance), best first.
        suggestions: Vec<String>,
    },
    /// A value was given in a unit of the wrong kind (length for an angle or vice versa), or in an
    /// unknown unit.
    #[error("{field}: unit `{unit}` does not fit: {message}")]
    Unit {
        /// Field or parameter concerned.
        field: String,
        /// The unit as written.
        unit: String,
        /// What was expected.
        message: String,
    },
    /// A model was evaluated outside the range where it is defined (e.g. a measured table).
    #[error(
        "parameter `{parameter}`: axis position {position} is outside the model's range [{low}, {high}] (internal units: mm or rad)"
    )]
    OutOfRange {
        /// The parameter.
        parameter: String,
        /// The axis position (mm or rad).
        position: f64,
        /// Lower end of the range.
        low: f64,
        /// Upper end of the range.
        high: f64,
    },
    /// A model or distribution has invalid settings (e.g. zero stroke, negative standard deviation).
    #[error("{what}: {message}")]
    Invalid {
        /// Which object.
        what: String,
        /// What is wrong with it.
        message: String,
    },
    /// Input lengths do not match (axis commands vs machine axes, slot vector vs slots).
    #[error("{what}: expected {expected} values, got {got}")]
    Dimension {
        /// Which input.
        what: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// The machine model (mte-kinematics) reported an error.
    #[error("kinematics: {0}")]
    Kinematics(String),
    /// Reading a file failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// What the operating system said.
        message: String,
    },
}

fn suggest(s: &[String]) -> String {
    if s.is_empty() {
        String::new()
    } else {
        format!(
            "; did you mean {}?",
            s.iter()
                .map(|x| format!("`{x}`"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

/// Result type of this crate.
pub type Result<T> = std::result::Result<T, Error>;

pub(crate) fn invalid(what: impl Into<String>, message: impl Into<String>) -> Error {
    Error::Invalid {
        what: what.into(),
        message: message.into(),
    }
}
