//! Reproduction of seed003 (see `shared/papers/DIGEST.md`): returns the Markdown of
//! `docs/reproduction/seed003.md` (the paper's values beside ours).

use super::ReproduceError;

/// Generates the Markdown text of `docs/reproduction/seed003.md`.
///
/// # Errors
/// [`ReproduceError::NotImplemented`] until the generator is written;
/// [`ReproduceError::Failed`] when a computation fails.
pub fn generate() -> Result<String, ReproduceError> {
    Err(ReproduceError::NotImplemented("seed003"))
}
