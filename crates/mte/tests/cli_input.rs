//! Issue 20 on the command line: bad, odd and huge input gets a clear error naming the file,
//! line and field or the flag; memory is refused with the figure before allocating; `--out` is
//! checked first and written atomically. Each test runs the binary as a user would.

use common::{root, scratch};
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

/// Runs `mte args…` (no memory limit from the environment); (success, stderr).
fn mte<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> (bool, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_mte"))
        .args(args)
        .env_remove("MTE_MAX_MEMORY_GB")
        .output()
        .unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn fails_with(args: &[&str], needles: &[&str]) {
    let (ok, err) = mte(args);
    assert!(!ok, "{args:?} succeeded");
    for n in needles {
        assert!(err.contains(n), "{args:?}: `{n}` not in: {err}");
    }
}

fn s(p: &Path) -> String {
    p.display().to_string()
}

// ---------------------------------------------------------------- ISO 230-2

fn iso_runs(dir: &Path, deviation: &str) -> PathBuf {
    let mut t = String::from("target_mm,run,direction,deviation_um\n");
    for target in [0, 100] {
        for run in 1..=2 {
            for d in ["up", "down"] {
                t.push_str(&format!("{target},{run},{d},1.5\n"));
            }
        }
    }
    t.push_str(&format!(
        "200,1,up,{deviation}\n200,2,up,1\n200,1,down,1\n200,2,down,1\n"
    ));
    let p = dir.join("runs.csv");
    std::fs::write(&p, t).unwrap();
    p
}

#[test]
fn iso230_2_huge_deviation_is_an_input_error_naming_file_line_column() {
    let d = scratch("iso-huge");
    for dev in ["1e155", "1e6", "-2e150"] {
        let runs = iso_runs(&d, dev);
        fails_with(
            &["iso230-2", &s(&runs), "--out", &s(&d.join("out"))],
            &["runs.csv", ":10:", "deviation_um", dev, "1 m"],
        );
    }
    // just below 1 m is accepted and evaluated (the plot's axis copes with the range)
    let runs = iso_runs(&d, "999999");
    let (ok, err) = mte(&["iso230-2", &s(&runs), "--out", &s(&d.join("out"))]);
    assert!(ok, "{err}");
    assert!(d.join("out/iso230-2.svg").exists());
}

#[test]
fn iso230_2_duplicate_reading_names_both_lines() {
    let d = scratch("iso-dup");
    let runs = iso_runs(&d, "1");
    let mut t = std::fs::read_to_string(&runs).unwrap();
    t.push_str("0,1,up,2\n");
    std::fs::write(&runs, t).unwrap();
    fails_with(
        &["iso230-2", &s(&runs), "--out", &s(&d.join("out"))],
        &["runs.csv", ":14:", "duplicate reading", "line 2"],
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_as_data_file_is_refused_not_read() {
    let d = scratch("fifo");
    let fifo = d.join("runs.csv");
    let made = Command::new("mkfifo").arg(&fifo).status();
    if !made.map(|s| s.success()).unwrap_or(false) {
        eprintln!("mkfifo not available; skipped");
        return;
    }
    fails_with(
        &["iso230-2", &s(&fifo), "--out", &s(&d.join("out"))],
        &["runs.csv", "not a regular file"],
    );
}

#[test]
fn out_pointing_at_a_file_is_refused_before_any_work() {
    let d = scratch("out-file");
    let f = d.join("taken.txt");
    std::fs::write(&f, "mine").unwrap();
    // the input does not even exist: the --out check comes first
    fails_with(
        &["iso230-2", &s(&d.join("missing.csv")), "--out", &s(&f)],
        &["--out", "taken.txt", "not a folder"],
    );
    fails_with(
        &[
            "simulate",
            "--machine",
            "seed003-ac-table",
            "--errors",
            "missing.json",
            "--out",
            &s(&f),
        ],
        &["not a folder"],
    );
    assert_eq!(std::fs::read_to_string(&f).unwrap(), "mine");
}

#[test]
fn a_rerun_into_the_same_out_leaves_no_stale_file() {
    let d = scratch("rerun");
    let out = d.join("sim");
    let (ok, err) = mte(&["rtest", "simulate", "--tests", "BK1,BK2", "--out", &s(&out)]);
    assert!(ok, "{err}");
    assert!(out.join("trace-ball1-BK2.svg").exists());
    let (ok, err) = mte(&["rtest", "simulate", "--tests", "BK1", "--out", &s(&out)]);
    assert!(ok, "{err}");
    assert!(out.join("trace-ball1-BK1.svg").exists());
    assert!(
        !out.join("trace-ball1-BK2.svg").exists(),
        "the first run's BK2 trace is still there"
    );
    let tmp: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".mte-tmp"))
        .collect();
    assert!(tmp.is_empty(), "{tmp:?}");
}

// ---------------------------------------------------------------- memory

#[test]
fn memory_is_refused_with_the_figure_before_allocating() {
    let d = scratch("memory");
    // simulate --n 400: 6.4e7 points
    fails_with(
        &[
            "simulate",
            "--machine",
            "seed003-ac-table",
            "--errors",
            &s(&root().join("fixtures/errors/seed003-demo.json")),
            "--n",
            "400",
            "--out",
            &s(&d.join("sim")),
        ],
        &[
            "64000000 points",
            "GB; this limit is 4 GB, set by --max-memory-gb or MTE_MAX_MEMORY_GB",
        ],
    );
    // the flag lowers the limit
    fails_with(
        &[
            "--max-memory-gb",
            "0.001",
            "simulate",
            "--machine",
            "seed003-ac-table",
            "--errors",
            &s(&root().join("fixtures/errors/seed003-demo.json")),
            "--n",
            "20",
            "--out",
            &s(&d.join("sim")),
        ],
        &["8000 points", "this limit is 0.00100 GB"],
    );
    fails_with(
        &["--max-memory-gb", "NaN", "machine", "list"],
        &["--max-memory-gb"],
    );
    // tracker uncertainty --trials 10^12
    let sim = d.join("net");
    let (ok, err) = mte(&["tracker", "simulate", "--out", &s(&sim)]);
    assert!(ok, "{err}");
    fails_with(
        &[
            "tracker",
            "uncertainty",
            "--stations",
            &s(&sim.join("stations.csv")),
            "--targets",
            &s(&sim.join("targets.csv")),
            "--lengths",
            &s(&sim.join("lengths.csv")),
            "--trials",
            "1000000000000",
            "--out",
            &s(&d.join("unc")),
        ],
        &[
            "--trials 1000000000000 needs 16000 GB",
            "this limit is 4 GB",
        ],
    );
    // sensitivity: Sobol' n = 10^12 and PCE degree 12 on the 41-input study
    let study = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(root().join("fixtures/sensitivity/seed003-study.json"))
                .unwrap(),
        )
        .unwrap();
        v["model"]["errors"] = s(&root().join("fixtures/errors/seed003-tolerances.json")).into();
        edit(&mut v);
        let p = d.join("study.json");
        std::fs::write(&p, v.to_string()).unwrap();
        p
    };
    let p = study(&|v| v["sobol"]["n"] = 1_000_000_000_000u64.into());
    fails_with(
        &[
            "sensitivity",
            "sobol",
            "--problem",
            &s(&p),
            "--out",
            &s(&d.join("s")),
        ],
        &[
            "study.json",
            "n = 1000000000000",
            "over 41 inputs",
            "GB; this limit is 4 GB",
        ],
    );
    let p = study(&|v| v["morris"]["r"] = 1_000_000_000_000u64.into());
    fails_with(
        &[
            "sensitivity",
            "morris",
            "--problem",
            &s(&p),
            "--out",
            &s(&d.join("s")),
        ],
        &[
            "Morris with r = 1000000000000 over 41 inputs",
            "GB; this limit is 4 GB",
        ],
    );
    let p = study(&|v| v["pce"]["degree"] = 12.into());
    fails_with(
        &[
            "sensitivity",
            "pce",
            "--problem",
            &s(&p),
            "--out",
            &s(&d.join("s")),
        ],
        &["PCE of degree 12 over 41 inputs", "GB; this limit is 4 GB"],
    );
}

// ---------------------------------------------------------------- tracker

fn tracker_net(d: &Path) -> PathBuf {
    let sim = d.join("net");
    let (ok, err) = mte(&["tracker", "simulate", "--out", &s(&sim)]);
    assert!(ok, "{err}");
    sim
}

/// Replaces the first occurrence of `from` in line `line` (1-based) of `file`.
fn edit_line(file: &Path, line: usize, from: &str, to: &str) {
    let text = std::fs::read_to_string(file).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    assert!(lines[line - 1].contains(from), "{}", lines[line - 1]);
    lines[line - 1] = lines[line - 1].replacen(from, to, 1);
    std::fs::write(file, lines.join("\n") + "\n").unwrap();
}

fn adjust(sim: &Path, out: &Path) -> (bool, String) {
    mte(&[
        "tracker",
        "adjust",
        "--stations",
        &s(&sim.join("stations.csv")),
        "--targets",
        &s(&sim.join("targets.csv")),
        "--lengths",
        &s(&sim.join("lengths.csv")),
        "--out",
        &s(out),
    ])
}

#[test]
fn tracker_simulate_flags_must_be_finite_and_possible() {
    let d = scratch("tracker-flags");
    for v in ["NaN", "1e300", "-1", "inf"] {
        fails_with(
            &[
                "tracker",
                "simulate",
                &format!("--field-um={v}"),
                "--out",
                &s(&d.join("o")),
            ],
            &["--field-um"],
        );
    }
    fails_with(
        &[
            "tracker",
            "simulate",
            "--edge-mm",
            "1e150",
            "--out",
            &s(&d.join("o")),
        ],
        &["--edge-mm"],
    );
}

#[test]
fn tracker_files_name_the_real_cause() {
    let d = scratch("tracker-files");
    let sim = tracker_net(&d);
    let out = d.join("adj");
    let (ok, err) = adjust(&sim, &out);
    assert!(ok, "{err}");
    let keep = |f: &str| std::fs::read_to_string(sim.join(f)).unwrap();
    let (st, ln) = (keep("stations.csv"), keep("lengths.csv"));
    let restore = || {
        std::fs::write(sim.join("stations.csv"), &st).unwrap();
        std::fs::write(sim.join("lengths.csv"), &ln).unwrap();
    };
    // a length of 1e150 mm: the length, not "invalid datum"
    let first_len = ln
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .nth(2)
        .unwrap()
        .to_string();
    edit_line(&sim.join("lengths.csv"), 2, &first_len, "1e150");
    let (ok, err) = adjust(&sim, &out);
    assert!(!ok);
    assert!(
        err.contains("lengths.csv:2") && err.contains("length_mm") && !err.contains("datum"),
        "{err}"
    );
    restore();
    // sigma 1e-300 µm
    let sigma = ln
        .lines()
        .nth(1)
        .unwrap()
        .rsplit(',')
        .next()
        .unwrap()
        .to_string();
    edit_line(&sim.join("lengths.csv"), 2, &sigma, "1e-300");
    let (ok, err) = adjust(&sim, &out);
    assert!(!ok);
    assert!(
        err.contains("lengths.csv:2") && err.contains("sigma_um") && err.contains("1 nm"),
        "{err}"
    );
    restore();
    // a station at 1e300: the coordinate, not "coplanar"
    let x = st
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .to_string();
    edit_line(&sim.join("stations.csv"), 2, &format!(",{x},"), ",1e300,");
    let (ok, err) = adjust(&sim, &out);
    assert!(!ok);
    assert!(
        err.contains("stations.csv:2") && err.contains("x_mm") && !err.contains("coplanar"),
        "{err}"
    );
    restore();
    // a duplicate station id names both lines
    let id1 = st
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .to_string();
    let id2 = st
        .lines()
        .nth(2)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .to_string();
    edit_line(&sim.join("stations.csv"), 3, &id2, &id1);
    let (ok, err) = adjust(&sim, &out);
    assert!(!ok);
    assert!(
        err.contains("stations.csv:3")
            && err.contains("duplicate station id")
            && err.contains("line 2"),
        "{err}"
    );
    restore();
}

// ---------------------------------------------------------------- sensitivity

fn test_problem(d: &Path, v: serde_json::Value) -> PathBuf {
    let p = d.join("problem.json");
    std::fs::write(&p, v.to_string()).unwrap();
    p
}

#[test]
fn sensitivity_problems_reject_bad_fields_names_and_magnitudes() {
    let d = scratch("sens");
    let out = s(&d.join("out"));
    let inputs = serde_json::json!([
        {"name": "a", "dist": "normal", "sd": 1},
        {"name": "b", "dist": "normal", "sd": 1}
    ]);
    let ok_problem = serde_json::json!({"format": "mte-sensitivity/1", "inputs": inputs,
        "model": {"name": "linear", "coef": [1, 2]}});
    let p = test_problem(&d, ok_problem.clone());
    let (ok, err) = mte(&["sensitivity", "local", "--problem", &s(&p), "--out", &out]);
    assert!(ok, "{err}");
    let cases: Vec<(serde_json::Value, Vec<&str>)> = vec![
        (
            {
                let mut v = ok_problem.clone();
                v.as_object_mut().unwrap().remove("format");
                v
            },
            vec!["problem.json", "`format`", "missing"],
        ),
        (
            {
                let mut v = ok_problem.clone();
                v["sobl"] = serde_json::json!({"n": 1024});
                v
            },
            vec![
                "problem.json",
                "`sobl`",
                "unknown field",
                "did you mean `sobol`",
            ],
        ),
        (
            {
                let mut v = ok_problem.clone();
                v["inputs"][0]["sdd"] = 1.into();
                v
            },
            vec!["problem.json", "inputs[0]", "sdd", "unknown field"],
        ),
        (
            {
                let mut v = ok_problem.clone();
                v["inputs"][1]["name"] = "a".into();
                v
            },
            vec!["problem.json", "inputs[1]", "already used by inputs[0]"],
        ),
        (
            {
                let mut v = ok_problem.clone();
                v["inputs"][0]["sd"] = 1e300.into();
                v
            },
            vec!["problem.json", "a (inputs[0])", "sd", "1e300", "overflows"],
        ),
        (
            {
                let mut v = ok_problem.clone();
                v["sobol"] = serde_json::json!({"n": 1024, "seeed": 1});
                v
            },
            vec!["problem.json", "`sobol`", "seeed"],
        ),
    ];
    for (v, needles) in cases {
        let p = test_problem(&d, v);
        let (ok, err) = mte(&["sensitivity", "sobol", "--problem", &s(&p), "--out", &out]);
        assert!(!ok, "{needles:?} accepted");
        for n in needles {
            assert!(err.contains(n), "`{n}` not in: {err}");
        }
    }
}

#[test]
fn sensitivity_points_outside_the_stroke_need_the_flag() {
    let d = scratch("sens-stroke");
    let v = serde_json::json!({"format": "mte-sensitivity/1",
        "model": {"name": "machine", "machine": "seed003-ac-table",
                  "errors": s(&root().join("fixtures/errors/seed003-tolerances.json")),
                  "points": [[0, 0, 0, 0, 0], [1e5, 0, 0, 0, 0]]}});
    let p = test_problem(&d, v);
    let out = s(&d.join("out"));
    fails_with(
        &["sensitivity", "local", "--problem", &s(&p), "--out", &out],
        &[
            "problem.json",
            "model.points",
            "point 2",
            "outside the stroke",
            "--allow-outside-stroke",
        ],
    );
    let (ok, err) = mte(&[
        "sensitivity",
        "local",
        "--problem",
        &s(&p),
        "--out",
        &out,
        "--allow-outside-stroke",
    ]);
    assert!(ok, "{err}");
}

// ---------------------------------------------------------------- simulate

#[test]
fn simulate_grid_and_at_are_checked() {
    let d = scratch("sim-grid");
    let errors = s(&root().join("fixtures/errors/seed003-demo.json"));
    let out = s(&d.join("out"));
    let run = |extra: &[&str]| {
        let mut a = vec![
            "simulate",
            "--machine",
            "seed003-ac-table",
            "--errors",
            &errors,
            "--out",
            &out,
        ];
        a.extend_from_slice(extra);
        mte(&a)
    };
    let fails = |extra: &[&str], needles: &[&str]| {
        let (ok, err) = run(extra);
        assert!(!ok, "{extra:?} accepted");
        for n in needles {
            assert!(err.contains(n), "{extra:?}: `{n}` not in: {err}");
        }
    };
    fails(
        &["--grid", "X=0:10:3,X=0:20:3"],
        &["--grid", "axis X appears twice", "X=0:10:3", "X=0:20:3"],
    );
    fails(&["--grid", ""], &["--grid", "names no axis"]);
    fails(&["--grid", "X=5:5:3"], &["--grid", "same point"]);
    fails(
        &["--grid", "X=0:1e6:3"],
        &["--grid", "outside the stroke", "--allow-outside-stroke"],
    );
    fails(&["--grid", "X=NaN:1:3"], &["--grid", "not a finite number"]);
    fails(&["--at", "C=1e9"], &["--at", "outside the stroke"]);
    fails(
        &["--grid", "X=0:10:3", "--at", "X=1"],
        &["--at", "on the grid"],
    );
    let (ok, err) = run(&["--grid", "X=0:1e4:3", "--allow-outside-stroke"]);
    assert!(ok, "{err}");
}

#[test]
fn simulate_program_outside_the_stroke_needs_the_flag() {
    let d = scratch("sim-prog");
    let prog = root().join("fixtures/errors/seed004-program.csv");
    let text = std::fs::read_to_string(&prog).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header = lines.iter().position(|l| !l.starts_with('#')).unwrap();
    let cells: Vec<String> = lines[header + 1].split(',').map(String::from).collect();
    let mut bad = cells.clone();
    bad[0] = "1e5".into();
    lines[header + 1] = bad.join(",");
    let p = d.join("program.csv");
    std::fs::write(&p, lines.join("\n") + "\n").unwrap();
    let (ok, err) = mte(&[
        "simulate",
        "--machine",
        "seed004-3axis",
        "--errors",
        &s(&root().join("fixtures/errors/seed004-demo.json")),
        "--program",
        &s(&p),
        "--out",
        &s(&d.join("out")),
    ]);
    assert!(!ok);
    assert!(
        err.contains("program.csv") && err.contains("outside the stroke"),
        "{err}"
    );
}

// ---------------------------------------------------------------- R-test

#[test]
fn rtest_flags_are_checked() {
    let d = scratch("rtest-flags");
    let out = s(&d.join("out"));
    for v in ["-1", "NaN", "1e300"] {
        fails_with(
            &[
                "rtest",
                "simulate",
                &format!("--noise-um={v}"),
                "--out",
                &out,
            ],
            &["--noise-um"],
        );
    }
    fails_with(
        &["rtest", "simulate", "--tests", "", "--out", &out],
        &["--tests", "names no test"],
    );
    fails_with(
        &["rtest", "simulate", "--tests", "BK1,BK1", "--out", &out],
        &["--tests", "twice"],
    );
    fails_with(
        &[
            "rtest",
            "simulate",
            "--centring",
            "C=0",
            "--centring",
            "C=180",
            "--out",
            &out,
        ],
        &["--centring given 2 times for 1 --ball", "C=180"],
    );
    fails_with(
        &["rtest", "simulate", "--centring", "B=1e9", "--out", &out],
        &["--centring", "outside the stroke"],
    );
}

#[test]
fn rtest_identify_on_one_test_of_one_setup_warns_the_design_cannot_separate() {
    let d = scratch("rtest-one");
    let sim = d.join("sim");
    let (ok, err) = mte(&["rtest", "simulate", "--tests", "BK1", "--out", &s(&sim)]);
    assert!(ok, "{err}");
    let (ok, err) = mte(&[
        "rtest",
        "identify",
        "--manifest",
        &s(&sim.join("manifest.json")),
        "--out",
        &s(&d.join("fit")),
    ]);
    assert!(ok, "{err}");
    assert!(
        err.contains("warning: the design cannot separate these parameters"),
        "{err}"
    );
    let report = std::fs::read_to_string(d.join("fit/report.md")).unwrap();
    assert!(report.contains("the design cannot separate these parameters"));
}

#[test]
fn rtest_manifest_duplicate_setup_and_huge_reading_are_named() {
    let d = scratch("rtest-files");
    let (man, text) = two_positions_copy(&d);
    std::fs::write(&man, text.replace("\"Y-177\"", "\"Y+177\"")).unwrap();
    fails_with(
        &[
            "rtest",
            "identify",
            "--manifest",
            &s(&man),
            "--out",
            &s(&d.join("o")),
        ],
        &[
            "seed002-two-positions.json",
            "setups[1].id",
            "appears twice",
            "setups[0]",
        ],
    );
    std::fs::write(&man, text).unwrap();
    edit_line(&d.join("seed002-two-positions.csv"), 2, "-3.2691", "1e300");
    fails_with(
        &[
            "rtest",
            "identify",
            "--manifest",
            &s(&man),
            "--out",
            &s(&d.join("o")),
        ],
        &[
            "seed002-two-positions.csv",
            "line 2",
            "dx_um",
            "out of range",
        ],
    );
}

#[test]
fn a_byte_order_mark_is_accepted_in_json_and_csv() {
    let d = scratch("bom");
    let mut problem = b"\xEF\xBB\xBF".to_vec();
    problem.extend_from_slice(
        br#"{"format": "mte-sensitivity/1", "inputs": [{"name": "a", "dist": "normal", "sd": 1}],
            "model": {"name": "linear", "coef": [2]}}"#,
    );
    let p = d.join("problem.json");
    std::fs::write(&p, problem).unwrap();
    let (ok, err) = mte(&[
        "sensitivity",
        "local",
        "--problem",
        &s(&p),
        "--out",
        &s(&d.join("o")),
    ]);
    assert!(ok, "{err}");
    let mut runs = b"\xEF\xBB\xBF".to_vec();
    runs.extend(std::fs::read(root().join("fixtures/iso230-2/worked-example.csv")).unwrap());
    let r = d.join("runs.csv");
    std::fs::write(&r, runs).unwrap();
    let (ok, err) = mte(&["iso230-2", &s(&r), "--out", &s(&d.join("i"))]);
    assert!(ok, "{err}");
}

#[cfg(unix)]
#[test]
fn a_fifo_as_error_set_or_machine_is_refused_not_read() {
    let d = scratch("fifo2");
    let fifo = d.join("errors.json");
    if !Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
    {
        eprintln!("mkfifo not available; skipped");
        return;
    }
    fails_with(
        &[
            "simulate",
            "--machine",
            "seed003-ac-table",
            "--errors",
            &s(&fifo),
            "--out",
            &s(&d.join("o")),
        ],
        &["errors.json", "not a regular file"],
    );
    fails_with(
        &[
            "simulate",
            "--machine",
            &s(&fifo),
            "--errors",
            &s(&fifo),
            "--out",
            &s(&d.join("o")),
        ],
        &["errors.json", "not a regular file"],
    );
}

#[test]
fn rtest_identify_refuses_a_centring_outside_the_stroke() {
    let d = scratch("rtest-centring");
    let (man, text) = two_positions_copy(&d);
    std::fs::write(&man, text.replace("\"Z\": -40.0", "\"Z\": -40000.0")).unwrap();
    fails_with(
        &[
            "rtest",
            "identify",
            "--manifest",
            &s(&man),
            "--out",
            &s(&d.join("o")),
        ],
        &[
            "seed002-two-positions.json",
            "centring.Z",
            "outside the stroke",
            "--allow-outside-stroke",
        ],
    );
}

/// Copies the bundled two-position R-test dataset into `d`: its manifest's path and text.
fn two_positions_copy(d: &Path) -> (PathBuf, String) {
    let fx = root().join("fixtures/rtest");
    for f in ["seed002-two-positions.json", "seed002-two-positions.csv"] {
        std::fs::copy(fx.join(f), d.join(f)).unwrap();
    }
    let man = d.join("seed002-two-positions.json");
    let text = std::fs::read_to_string(&man).unwrap();
    (man, text)
}
