//! Reproduction of seed004 (see `shared/papers/DIGEST.md`): returns the Markdown of
//! `docs/reproduction/seed004.md` (the paper's values beside ours).

use super::ReproduceError;

// generator provided by the mte-metrology helper

/// Generates the Markdown text of `docs/reproduction/seed004.md`.
///
/// # Errors
/// None today: the generator (`mte_metrology::reproduce::seed004`) is infallible.
pub fn generate() -> Result<String, ReproduceError> {
    Ok(mte_metrology::reproduce::seed004())
}
