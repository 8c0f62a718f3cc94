//! Staleness test: every committed `docs/reproduction/seedNNN.md` must equal what its generator
//! produces now, and no page may be committed for a paper whose generator is not written.

use xtask::reproduce::{self, Freshness, PAPERS, ReproduceError};

#[test]
fn committed_reproduction_pages_are_fresh() {
    let root = reproduce::workspace_root();
    let mut problems = Vec::new();
    for (paper, generator) in PAPERS {
        let path = reproduce::output_path(&root, paper);
        match generator() {
            Err(ReproduceError::NotImplemented(_)) => {
                if path.exists() {
                    problems.push(format!(
                        "{}: committed but its generator is not implemented",
                        path.display()
                    ));
                }
            }
            Err(e) => problems.push(format!("{paper}: {e}")),
            Ok(text) => match reproduce::compare(&path, &text).unwrap() {
                Freshness::UpToDate => {}
                Freshness::Missing => problems.push(format!(
                    "{}: missing; run `cargo xtask reproduce {paper}`",
                    path.display()
                )),
                Freshness::Stale { first_diff_line } => problems.push(format!(
                    "{}: stale from line {first_diff_line}; run `cargo xtask reproduce {paper}`",
                    path.display()
                )),
            },
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn compare_detects_differences() {
    let dir = std::env::temp_dir().join(format!("xtask-compare-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("x.md");
    assert_eq!(reproduce::compare(&p, "a\n").unwrap(), Freshness::Missing);
    std::fs::write(&p, "a\nb\nc\n").unwrap();
    assert_eq!(
        reproduce::compare(&p, "a\nb\nc\n").unwrap(),
        Freshness::UpToDate
    );
    assert_eq!(
        reproduce::compare(&p, "a\nB\nc\n").unwrap(),
        Freshness::Stale { first_diff_line: 2 }
    );
    assert_eq!(
        reproduce::compare(&p, "a\nb\n").unwrap(),
        Freshness::Stale { first_diff_line: 3 }
    );
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(matches!(
        reproduce::generate("seed999"),
        Err(ReproduceError::UnknownPaper(_))
    ));
}
