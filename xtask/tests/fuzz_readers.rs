//! Fuzzing every file reader with random mutations of the bundled fixtures (issue 20): bytes
//! flipped, lines dropped or duplicated, numbers replaced by NaN / inf / ±1e300 / 1e-300 /
//! nothing, field names altered, ids (quoted strings, first CSV fields) copied from elsewhere in
//! the file. Each reader must not panic, and must return either a value or an error whose
//! message names the file it read (one of the files of a multi-file input).
//!
//! Cases per reader: `MTE_FUZZ_CASES` (default [`DEFAULT_CASES`]); a longer local run is
//! described in `docs/fuzzing.md`. Failing inputs are printed with the mutations applied.

use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use std::path::{Path, PathBuf};

/// Cases per reader when `MTE_FUZZ_CASES` is not set.
const DEFAULT_CASES: u32 = 10_000;

fn cases() -> u32 {
    std::env::var("MTE_FUZZ_CASES")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(DEFAULT_CASES)
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A scratch folder in memory where there is one (`/dev/shm`: a file write on a disk-backed
/// temporary folder costs milliseconds, as much as the reader).
fn scratch(name: &str) -> PathBuf {
    let base = Path::new("/dev/shm");
    let base = if base.is_dir() {
        base.to_path_buf()
    } else {
        std::env::temp_dir()
    };
    let d = base.join(format!("mte-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// One mutation: a kind and two random numbers that pick where and what.
type Mutation = (u8, u64, u64);

const REPLACEMENTS: [&str; 11] = [
    "NaN", "inf", "-inf", "1e300", "-1e300", "", "1e-300", "0", "-1", "1e155", "nan",
];

/// Byte ranges of the numbers in `t` (a digit, optionally after `-`/`+`/`.`, then number chars).
fn numbers(t: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < t.len() {
        let starts = t[i].is_ascii_digit()
            || ((t[i] == b'-' || t[i] == b'.') && t.get(i + 1).is_some_and(u8::is_ascii_digit));
        let after_word = i > 0 && (t[i - 1].is_ascii_alphanumeric() || t[i - 1] == b'_');
        if starts && !after_word {
            let mut j = i + 1;
            while j < t.len()
                && (t[j].is_ascii_digit() || matches!(t[j], b'.' | b'e' | b'E' | b'-' | b'+'))
            {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of the quoted strings in `t` (without the quotes).
fn quoted(t: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < t.len() {
        if t[i] == b'"' {
            let j = t[i + 1..]
                .iter()
                .position(|&c| c == b'"')
                .map(|p| i + 1 + p);
            match j {
                Some(j) => {
                    out.push((i + 1, j));
                    i = j + 1;
                }
                None => break,
            }
        } else {
            i += 1;
        }
    }
    out
}

/// Byte ranges of the lines of `t` (with their newline).
fn lines(t: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for (i, &c) in t.iter().enumerate() {
        if c == b'\n' {
            out.push((s, i + 1));
            s = i + 1;
        }
    }
    if s < t.len() {
        out.push((s, t.len()));
    }
    out
}

fn splice(t: &mut Vec<u8>, (a, b): (usize, usize), with: &[u8]) {
    t.splice(a..b, with.iter().copied());
}

fn pick<T: Copy>(v: &[T], r: u64) -> Option<T> {
    (!v.is_empty()).then(|| v[(r % v.len() as u64) as usize])
}

/// Applies one mutation to `t`.
fn mutate(t: &mut Vec<u8>, (kind, a, b): Mutation) {
    match kind % 7 {
        // flip one bit of one byte
        0 => {
            if !t.is_empty() {
                let i = (a % t.len() as u64) as usize;
                t[i] ^= 1 << (b % 8);
            }
        }
        // drop a line
        1 => {
            if let Some(r) = pick(&lines(t), a) {
                splice(t, r, b"");
            }
        }
        // duplicate a line
        2 => {
            if let Some((s, e)) = pick(&lines(t), a) {
                let copy = t[s..e].to_vec();
                splice(t, (s, s), &copy);
            }
        }
        // a number replaced
        3 | 4 => {
            if let Some(r) = pick(&numbers(t), a) {
                let with = REPLACEMENTS[(b % REPLACEMENTS.len() as u64) as usize];
                splice(t, r, with.as_bytes());
            }
        }
        // a field name (quoted string, or a word of the first CSV line) altered
        5 => {
            let mut fields = quoted(t);
            if fields.is_empty()
                && let Some((s, e)) = lines(t).into_iter().find(|&(s, _)| t.get(s) != Some(&b'#'))
            {
                let mut p = s;
                for (k, &c) in t[s..e].iter().enumerate() {
                    if c == b',' || c == b'\n' {
                        fields.push((p, s + k));
                        p = s + k + 1;
                    }
                }
            }
            if let Some((s, e)) = pick(&fields, a) {
                match b % 3 {
                    0 => splice(t, (e, e), b"x"),
                    1 if e > s => splice(t, (e - 1, e), b""),
                    _ => {
                        let upper: Vec<u8> = t[s..e].to_ascii_uppercase();
                        splice(t, (s, e), &upper);
                    }
                }
            }
        }
        // an id duplicated: a quoted string, or a line's first CSV field, copied over another
        _ => {
            let q = quoted(t);
            if q.len() >= 2 {
                let from = pick(&q, a).unwrap();
                let to = pick(&q, b).unwrap();
                let copy = t[from.0..from.1].to_vec();
                splice(t, to, &copy);
            } else {
                let first = |(s, e): (usize, usize), t: &[u8]| {
                    let end = t[s..e].iter().position(|&c| c == b',').map(|p| s + p);
                    end.map(|end| (s, end))
                };
                let ls = lines(t);
                if let (Some(x), Some(y)) = (pick(&ls, a), pick(&ls, b))
                    && let (Some(f), Some(g)) = (first(x, t), first(y, t))
                {
                    let copy = t[f.0..f.1].to_vec();
                    splice(t, g, &copy);
                }
            }
        }
    }
}

fn mutations() -> impl Strategy<Value = (u64, Vec<Mutation>)> {
    (
        any::<u64>(),
        proptest::collection::vec((any::<u8>(), any::<u64>(), any::<u64>()), 1..4),
    )
}

/// Reads an input from a folder, given the index of the mutated file.
type ReadFn = Box<dyn Fn(&Path, usize) -> Result<(), String>>;

/// One reader under test: its input files (the fixtures to copy into a scratch folder) and the
/// call that reads them from that folder.
struct Reader {
    name: &'static str,
    /// (file name in the scratch folder, fixture bytes).
    files: Vec<(String, Vec<u8>)>,
    /// Which files may be mutated (indices into `files`).
    mutable: Vec<usize>,
    /// Reads the input from the folder; the argument is the index of the mutated file.
    read: ReadFn,
}

fn fixture(rel: &str) -> Vec<u8> {
    std::fs::read(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Runs `reader` on `cases()` random mutations of its fixtures.
fn fuzz(reader: Reader) {
    let dir = scratch(reader.name);
    let names: Vec<String> = reader.files.iter().map(|f| f.0.clone()).collect();
    // the fixtures themselves read
    for (n, bytes) in &reader.files {
        std::fs::write(dir.join(n), bytes).unwrap();
    }
    for &i in &reader.mutable {
        (reader.read)(&dir, i)
            .unwrap_or_else(|e| panic!("{}: the fixture fails: {e}", reader.name));
    }
    let last = std::cell::Cell::new(None::<usize>);
    let config = Config {
        cases: cases(),
        failure_persistence: None,
        max_shrink_iters: 200,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(
        config,
        proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        ),
    );
    let dir_text = dir.display().to_string();
    let result = runner.run(&mutations(), |(which, muts)| {
        let target = reader.mutable[(which % reader.mutable.len() as u64) as usize];
        // only the mutated file is rewritten; the one of the previous case is restored
        if let Some(i) = last.replace(Some(target)) {
            std::fs::write(dir.join(&reader.files[i].0), &reader.files[i].1).unwrap();
        }
        let mut b = reader.files[target].1.clone();
        for m in &muts {
            mutate(&mut b, *m);
        }
        std::fs::write(dir.join(&names[target]), &b).unwrap();
        let outcome =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (reader.read)(&dir, target)));
        match outcome {
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                Err(TestCaseError::fail(format!(
                    "{}: panic `{msg}` on {} mutated by {muts:?}",
                    reader.name, names[target]
                )))
            }
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => {
                // a mutated manifest may name another file in the folder: that file is named
                if names.iter().any(|n| e.contains(n.as_str())) || e.contains(&dir_text) {
                    Ok(())
                } else {
                    Err(TestCaseError::fail(format!(
                        "{}: the error does not name the file ({}): `{e}`; {} mutated by {muts:?}",
                        reader.name,
                        names.join(", "),
                        names[target]
                    )))
                }
            }
        }
    });
    let _ = std::fs::remove_dir_all(&dir);
    if let Err(e) = result {
        panic!("{e}");
    }
}

fn text(e: impl std::fmt::Display) -> String {
    e.to_string()
}

#[test]
fn iso230_2_runs() {
    fuzz(Reader {
        name: "iso230-2",
        files: vec![(
            "runs.csv".into(),
            fixture("fixtures/iso230-2/worked-example.csv"),
        )],
        mutable: vec![0],
        read: Box::new(|d, _| {
            let p = d.join("runs.csv");
            let t = mte_linalg::text::read_text(&p).map_err(|e| format!("{}: {e}", p.display()))?;
            let r = mte_metrology::iso230_2::readings_from_csv(&p.display().to_string(), &t)
                .map_err(text)?;
            // the evaluation of what the reader accepted must not fail without naming it either
            let _ = mte_metrology::iso230_2::evaluate(&r);
            Ok(())
        }),
    });
}

/// The tracker network of `mte tracker simulate` (seed 004 layout), as its three CSV files.
fn tracker_files() -> Vec<(String, Vec<u8>)> {
    use mte_metrology::network::{LengthUncertainty, Vec3};
    use mte_metrology::simulate::{SmoothErrorField, StationLayout, cube_edge_targets, simulate};
    let targets = cube_edge_targets(500.0, 2);
    let field = SmoothErrorField::new(500.0, &targets, 20.0);
    let sim = simulate(
        &StationLayout::FourLow.stations(500.0, true),
        &targets,
        &|p: &Vec3| field.eval(p),
        LengthUncertainty::SEED004,
        1,
    )
    .unwrap();
    // 40 lengths keep each case fast.
    let mut n = sim.network;
    n.observations.truncate(40);
    let (s, t, l) = mte_metrology::io::network_to_csv(&n);
    vec![
        ("stations.csv".into(), s.into_bytes()),
        ("targets.csv".into(), t.into_bytes()),
        ("lengths.csv".into(), l.into_bytes()),
    ]
}

#[test]
fn tracker_network() {
    fuzz(Reader {
        name: "tracker",
        files: tracker_files(),
        mutable: vec![0, 1, 2],
        read: Box::new(|d, _| {
            let f = |n: &str| {
                let p = d.join(n);
                mte_linalg::text::read_text(&p)
                    .map(|t| (p.display().to_string(), t))
                    .map_err(|e| format!("{}: {e}", p.display()))
            };
            let (s, t, l) = (f("stations.csv")?, f("targets.csv")?, f("lengths.csv")?);
            mte_metrology::io::network_from_csv(
                (&s.0, &s.1),
                (&t.0, &t.1),
                (&l.0, &l.1),
                mte_metrology::network::LengthUncertainty::SEED004,
            )
            .map(|_| ())
            .map_err(text)
        }),
    });
}

#[test]
fn rtest_dataset() {
    fuzz(Reader {
        name: "rtest",
        files: vec![
            (
                "seed002-two-positions.json".into(),
                fixture("fixtures/rtest/seed002-two-positions.json"),
            ),
            (
                "seed002-two-positions.csv".into(),
                fixture("fixtures/rtest/seed002-two-positions.csv"),
            ),
        ],
        mutable: vec![0, 1],
        read: Box::new(|d, _| {
            let rotary = |a: &str| a == "B" || a == "C";
            mte_rtest::io::read_dataset(&d.join("seed002-two-positions.json"), &rotary)
                .map(|_| ())
                .map_err(text)
        }),
    });
}

#[test]
fn sensitivity_problems() {
    let test_model = br#"{"format": "mte-sensitivity/1",
 "inputs": [{"name": "dx", "dist": "tolerance", "half_width": 0.015, "coverage": 3},
            {"name": "a",  "dist": "normal", "mean": 0, "sd": 1},
            {"name": "b",  "dist": "uniform", "lo": 0, "hi": 1},
            {"name": "c",  "dist": "truncated_normal", "mean": 0, "sd": 1, "lo": -2, "hi": 2}],
 "correlation": [[1,0,0,0],[0,1,0.3,0],[0,0.3,1,0],[0,0,0,1]],
 "model": {"name": "linear", "coef": [1, 2, 3, 4]},
 "sobol":  {"n": 8192, "sampling": "sobol", "seed": 0, "n_bootstrap": 100, "confidence": 0.95, "second_order": false, "checkpoints": [1024, 4096]},
 "pce":    {"degree": 3, "q_norm": 1.0, "adaptive_degree": true, "selection": {"rule": "k_fold", "folds": 5}, "n_samples": 1000, "sampling": "latin_hypercube", "n_bootstrap": 0, "validation": {"n": 20000}},
 "morris": {"r": 50, "levels": 4, "design": "trajectory", "n_bootstrap": 100}}
"#;
    fuzz(Reader {
        name: "sensitivity",
        files: vec![
            ("test-model.json".into(), test_model.to_vec()),
            (
                "seed003-study.json".into(),
                fixture("fixtures/sensitivity/seed003-study.json"),
            ),
            (
                "seed003-machine.json".into(),
                fixture("fixtures/sensitivity/seed003-machine.json"),
            ),
        ],
        mutable: vec![0, 1, 2],
        read: Box::new(|d, i| {
            let n = [
                "test-model.json",
                "seed003-study.json",
                "seed003-machine.json",
            ][i];
            mte::problem::read_problem(&d.join(n))
                .map(|_| ())
                .map_err(text)
        }),
    });
}

#[test]
fn machine_json() {
    let dir = root().join("crates/mte-kinematics/machines");
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    files.sort();
    let names: Vec<String> = files.iter().map(|f| f.0.clone()).collect();
    fuzz(Reader {
        name: "machine",
        mutable: (0..files.len()).collect(),
        files,
        read: Box::new(move |d, i| {
            mte_kinematics::Machine::from_file(&d.join(&names[i]))
                .map(|_| ())
                .map_err(text)
        }),
    });
}

fn error_set_reader() -> Reader {
    let names = [
        "seed003-demo.json",
        "seed003-tolerances.json",
        "seed004-demo.json",
        "seed004-eyy.csv",
    ];
    Reader {
        name: "errorset",
        files: names
            .iter()
            .map(|n| (n.to_string(), fixture(&format!("fixtures/errors/{n}"))))
            .collect(),
        mutable: vec![0, 1, 2, 3],
        read: Box::new(move |d, i| {
            // the table is read through the set that names it
            let n = if i == 3 { names[2] } else { names[i] };
            mte_errors::ErrorSet::from_file(&d.join(n))
                .map(|_| ())
                .map_err(text)
        }),
    }
}

/// No panic, and every error names the file.
#[test]
fn error_sets() {
    fuzz(error_set_reader());
}

/// Every bundled dataset of `fixtures/datasets/*/` (manifest and data files).
#[test]
fn diagnosis_datasets() {
    let base = root().join("fixtures/datasets");
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(&base)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("manifest.json").is_file())
        .collect();
    dirs.sort();
    assert!(!dirs.is_empty());
    for ds in dirs {
        let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(&ds)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.is_file())
            .map(|p| {
                (
                    p.file_name().unwrap().to_string_lossy().into_owned(),
                    std::fs::read(&p).unwrap(),
                )
            })
            .collect();
        files.sort();
        fuzz(Reader {
            name: "diagnose",
            mutable: (0..files.len()).collect(),
            files,
            read: Box::new(|d, _| {
                mte_diagnose::load(&d.join("manifest.json"))
                    .map(|_| ())
                    .map_err(text)
            }),
        });
    }
}

#[test]
fn the_mutations_do_what_they_say() {
    let t = b"id,x_mm\nS1,1.5\nS2,-2e3\n".to_vec();
    assert_eq!(numbers(&t).len(), 2);
    let mut m = t.clone();
    mutate(&mut m, (3, 1, 3));
    assert_eq!(m, b"id,x_mm\nS1,1.5\nS2,1e300\n");
    let mut m = t.clone();
    mutate(&mut m, (1, 0, 0));
    assert_eq!(m, b"S1,1.5\nS2,-2e3\n");
    let mut m = t.clone();
    mutate(&mut m, (2, 1, 0));
    assert_eq!(m, b"id,x_mm\nS1,1.5\nS1,1.5\nS2,-2e3\n");
    let mut m = t.clone();
    mutate(&mut m, (6, 1, 2));
    assert_eq!(m, b"id,x_mm\nS1,1.5\nS1,-2e3\n");
    let j = br#"{"id": "a", "x": "b"}"#.to_vec();
    let mut m = j.clone();
    mutate(&mut m, (6, 1, 3));
    assert_eq!(m, br#"{"id": "a", "x": "a"}"#);
}
