//! What the diagnosis' integration tests share: scratch directories for the datasets they write,
//! removed when a test is done with them (the command-line and xtask tests use them too).
// (Each test file uses what it needs of this.)
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// A fresh scratch directory for one test, removed with what the test wrote in it when the value
/// is dropped (a failing test's too).
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The scratch directory `mte-test-{name}-{process id}` under the system's temporary folder.
pub fn scratch(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("mte-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

/// A dataset written to a scratch directory, read as the path of its `manifest.json`; the
/// directory goes when the dataset does.
pub struct Dataset {
    manifest: PathBuf,
    _dir: Scratch,
}

impl Dataset {
    /// The dataset whose manifest is `manifest.json` in `dir`.
    pub fn new(dir: Scratch) -> Dataset {
        Dataset {
            manifest: dir.join("manifest.json"),
            _dir: dir,
        }
    }
}

impl std::ops::Deref for Dataset {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.manifest
    }
}

impl AsRef<Path> for Dataset {
    fn as_ref(&self) -> &Path {
        &self.manifest
    }
}
