//! The committed seed-002 reproduction page is regenerated in memory and compared byte for byte
//! (moved here with the generator from `mte-rtest`'s artefact tests). Run with
//! `MTE_REGENERATE=1` to rewrite.

use std::path::PathBuf;
use xtask::reproduce::{self, seed002};

fn check_or_write(path: &PathBuf, text: &str) {
    if std::env::var("MTE_REGENERATE").is_ok() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    let on_disk = std::fs::read_to_string(path).unwrap_or_default();
    assert!(
        on_disk == text,
        "{} is stale: run `MTE_REGENERATE=1 cargo test -p xtask --test seed002`",
        path.display()
    );
}

#[test]
fn seed002_reproduction_is_fresh() {
    check_or_write(
        &reproduce::output_path(&reproduce::workspace_root(), "seed002"),
        &seed002::generate().unwrap_or_else(|e| format!("# Seed 002\n\ngeneration failed: {e}\n")),
    );
}
