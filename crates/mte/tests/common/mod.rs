//! What the command-line tests share: the workspace root and scratch directories (the
//! diagnosis tests', which remove themselves when a test is done with them).

use std::path::{Path, PathBuf};

#[path = "../../../mte-diagnose/tests/common/mod.rs"]
mod scratch_dirs;

/// The workspace root (the bundled fixtures are under it).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The scratch directory `mte-test-cli-{name}-{process id}` under the system's temporary folder.
pub fn scratch(name: &str) -> scratch_dirs::Scratch {
    scratch_dirs::scratch(&format!("cli-{name}"))
}
