//! Reproduction of seed002 (see `shared/papers/DIGEST.md`): returns the Markdown of
//! `docs/reproduction/seed002.md` (the paper's values beside ours).

use super::ReproduceError;

// generator provided by the mte-rtest helper (`mte_rtest::reproduce::seed002_report`)

/// Generates the Markdown text of `docs/reproduction/seed002.md`.
///
/// # Errors
/// [`ReproduceError::Failed`] when a simulation or fit of the generator fails.
pub fn generate() -> Result<String, ReproduceError> {
    mte_rtest::reproduce::seed002_report().map_err(|e| ReproduceError::Failed {
        paper: "seed002",
        detail: e.to_string(),
    })
}
