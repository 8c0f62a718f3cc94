//! The error type of `mte-kinematics`.

/// Everything that can go wrong in `mte-kinematics`. Messages name the file or JSON
/// field (as a path such as `bodies[3].joint.direction`) and what was expected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum KinError {
    /// The machine file is not valid JSON.
    #[error("{source_name}: invalid JSON at line {line}, column {column}: {message}")]
    Json {
        /// File name or `<string>`.
        source_name: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the JSON parser said.
        message: String,
    },
    /// A field of the machine description is missing, of the wrong type or has an invalid value.
    #[error("{source_name}: field `{field}`: {message}")]
    Field {
        /// File name or `<string>`.
        source_name: String,
        /// JSON path of the offending field, e.g. `bodies[2].joint.direction`.
        field: String,
        /// What was found and what was expected.
        message: String,
    },
    /// Reading a machine file failed.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// What the operating system said.
        message: String,
    },
    /// No bundled machine has this name.
    #[error("unknown library machine `{name}` (known: {known})")]
    UnknownMachine {
        /// The requested name.
        name: String,
        /// The bundled names, comma separated.
        known: String,
    },
    /// A name is neither a bundled machine nor an existing machine file.
    #[error("`{name}` is neither a library machine ({known}) nor an existing file ({path})")]
    NoSuchMachine {
        /// The requested name.
        name: String,
        /// The file it was looked for at.
        path: String,
        /// The bundled names, comma separated.
        known: String,
    },
    /// The requested tool pose is not reachable by the machine's kinematics (not a stroke issue).
    #[error("unreachable pose: {reason}")]
    Unreachable {
        /// Why (e.g. the tool axis cannot be produced by the rotary axes).
        reason: String,
    },
    /// The requested pose is a singular configuration: an axis value is not determined.
    #[error("singular configuration: axis {axis} is not determined ({reason})")]
    Singular {
        /// The axis whose value is free.
        axis: String,
        /// Why (e.g. tool axis parallel to the first rotary axis).
        reason: String,
    },
    /// Solutions exist but none lies within the axis strokes.
    #[error("no solution within strokes: {reason}")]
    OutOfStroke {
        /// Which axis left its stroke, with value and limits, for each candidate.
        reason: String,
    },
    /// Inverse kinematics is not implemented for this machine structure.
    #[error("inverse kinematics not supported for machine `{machine}`: {reason}")]
    UnsupportedStructure {
        /// The machine name.
        machine: String,
        /// What structure it has and what is supported.
        reason: String,
    },
}

/// Result type of `mte-kinematics`.
pub type Result<T> = std::result::Result<T, KinError>;
