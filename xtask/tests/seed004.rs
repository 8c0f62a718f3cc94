//! The committed `docs/reproduction/seed004.md` must equal the generator's output
//! (regenerate with `cargo xtask reproduce seed004`, or write `seed004()` to the file).
//! Moved here with the generator from `mte-metrology`.

#[test]
fn seed004_reproduction_is_current() {
    let text = xtask::reproduce::seed004::seed004();
    let path = xtask::reproduce::output_path(&xtask::reproduce::workspace_root(), "seed004");
    if std::env::var("MTE_BLESS").is_ok() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &text).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == text,
        "{} is stale: run with MTE_BLESS=1 or `cargo xtask reproduce seed004`",
        path.display()
    );
    assert!(text.contains("shortest 95 %"));
}
