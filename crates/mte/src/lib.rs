#![doc = include_str!("../README.md")]

pub mod limits;
pub mod output;
pub mod plot;
pub mod problem;
pub mod progress;
pub mod report;

/// Everything that can go wrong in a command: the message names the file, line or field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CliError {
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// A library reported an error (its message names the offending input).
    #[error("{0}")]
    Library(String),
    /// The command line itself is inconsistent.
    #[error("{0}")]
    Usage(String),
    /// Writing or reading JSON failed (serialisation or syntax); names the file.
    #[error("{path}: JSON: {source}")]
    Json {
        /// The file.
        path: std::path::PathBuf,
        /// What serde_json said (with line and column for syntax errors).
        source: serde_json::Error,
    },
    /// A chart could not be drawn (bad data or a plotting-backend failure).
    #[error("plot {title:?}: {detail}")]
    Plot {
        /// Chart title.
        title: String,
        /// What went wrong (e.g. which series holds a non-finite value).
        detail: String,
    },
}
