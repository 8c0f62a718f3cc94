//! `cargo xtask reproduce`: one generator per paper, each in its own module `seedNNN.rs`,
//! returning the Markdown written to `docs/reproduction/seedNNN.md`.
//!
//! To add a generator: implement `seedNNN::generate() -> Result<String, ReproduceError>`
//! (deterministic: fixed seeds, no timestamps), run `cargo xtask reproduce seedNNN`, commit the
//! generated file. For a new paper also add its module below and a row to [`PAPERS`].

use std::fmt;
use std::path::{Path, PathBuf};

pub mod seed000;
pub mod seed002;
pub mod seed003;
pub mod seed004;

/// A reproduction generator: the Markdown of one paper's reproduction page.
pub type Generator = fn() -> Result<String, ReproduceError>;

/// Every paper with a reproduction page, in output order.
pub const PAPERS: &[(&str, Generator)] = &[
    ("seed000", seed000::generate),
    ("seed002", seed002::generate),
    ("seed003", seed003::generate),
    ("seed004", seed004::generate),
];

/// What can go wrong while reproducing.
#[derive(Debug)]
#[non_exhaustive]
pub enum ReproduceError {
    /// The paper's generator has not been written yet.
    NotImplemented(&'static str),
    /// No paper of that name.
    UnknownPaper(String),
    /// A computation failed (the message names the step and input).
    Failed {
        /// Paper.
        paper: &'static str,
        /// What failed.
        detail: String,
    },
    /// Reading or writing a file failed.
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
}

impl fmt::Display for ReproduceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReproduceError::NotImplemented(p) => {
                write!(f, "reproduction of {p} is not implemented yet")
            }
            ReproduceError::UnknownPaper(p) => write!(
                f,
                "unknown paper {p:?}; known: {}",
                PAPERS.iter().map(|p| p.0).collect::<Vec<_>>().join(", ")
            ),
            ReproduceError::Failed { paper, detail } => write!(f, "{paper}: {detail}"),
            ReproduceError::Io { path, source } => write!(f, "{}: {source}", path.display()),
        }
    }
}

impl std::error::Error for ReproduceError {}

/// The workspace root (the parent of the `xtask` directory).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// `docs/reproduction/<paper>.md` under `root`.
pub fn output_path(root: &Path, paper: &str) -> PathBuf {
    root.join("docs")
        .join("reproduction")
        .join(format!("{paper}.md"))
}

/// The generator of `paper`.
///
/// # Errors
/// [`ReproduceError::UnknownPaper`].
pub fn generator(paper: &str) -> Result<(&'static str, Generator), ReproduceError> {
    PAPERS
        .iter()
        .find(|(name, _)| *name == paper)
        .copied()
        .ok_or_else(|| ReproduceError::UnknownPaper(paper.to_string()))
}

/// Generates the Markdown of `paper` in memory.
///
/// # Errors
/// As the paper's generator, or [`ReproduceError::UnknownPaper`].
pub fn generate(paper: &str) -> Result<String, ReproduceError> {
    let (_, g) = generator(paper)?;
    g()
}

/// Result of comparing a generated page with the committed one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Freshness {
    /// Identical.
    UpToDate,
    /// The committed file differs; the first differing line (1-based).
    Stale {
        /// First line that differs.
        first_diff_line: usize,
    },
    /// No committed file.
    Missing,
}

/// Compares the generated Markdown with the committed file at `path`.
///
/// # Errors
/// [`ReproduceError::Io`] if the file exists but cannot be read.
pub fn compare(path: &Path, generated: &str) -> Result<Freshness, ReproduceError> {
    let committed = match std::fs::read_to_string(path) {
        Ok(s) => s,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Freshness::Missing),
        Err(source) => {
            return Err(ReproduceError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    if committed == generated {
        return Ok(Freshness::UpToDate);
    }
    let mut a = committed.lines();
    let mut b = generated.lines();
    let mut line = 1;
    loop {
        match (a.next(), b.next()) {
            (Some(x), Some(y)) if x == y => line += 1,
            _ => {
                return Ok(Freshness::Stale {
                    first_diff_line: line,
                });
            }
        }
    }
}

/// Writes the page of `paper` under `root`.
///
/// # Errors
/// As [`generate`], or [`ReproduceError::Io`].
pub fn write(root: &Path, paper: &str) -> Result<PathBuf, ReproduceError> {
    let text = generate(paper)?;
    let path = output_path(root, paper);
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| ReproduceError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    std::fs::write(&path, text).map_err(|source| ReproduceError::Io {
        path: path.clone(),
        source,
    })?;
    Ok(path)
}
