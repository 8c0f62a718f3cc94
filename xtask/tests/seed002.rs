//! The committed seed-002 reproduction page is regenerated in memory and compared byte for byte
//! (moved here with the generator from `mte-rtest`'s artefact tests). Run with
//! `MTE_REGENERATE=1` to rewrite.

use xtask::reproduce::{self, seed002};

#[test]
fn seed002_reproduction_is_fresh() {
    let root = reproduce::workspace_root();
    if std::env::var("MTE_REGENERATE").is_ok() {
        reproduce::write(&root, "seed002").unwrap();
    }
    let path = reproduce::output_path(&root, "seed002");
    let text =
        seed002::generate().unwrap_or_else(|e| format!("# Seed 002\n\ngeneration failed: {e}\n"));
    let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        on_disk == text,
        "{} is stale: run `MTE_REGENERATE=1 cargo test -p xtask --test seed002`",
        path.display()
    );
}
