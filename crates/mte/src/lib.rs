#![doc = include_str!("../README.md")]

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
}
