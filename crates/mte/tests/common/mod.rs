//! What the command-line tests share: the workspace root and scratch directories.

use std::path::{Path, PathBuf};

/// The workspace root (the bundled fixtures are under it).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh scratch directory for one test, removed when the test ends.
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

/// The scratch directory `mte-cli-{name}-{process id}` under the system's temporary folder.
pub fn scratch(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("mte-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}
