//! `cargo xtask reproduce [seed000|seed002|seed003|seed004|all] [--check]`,
//! `cargo xtask reproduce seed003 --timing` (writes `docs/reproduction/seed003-timing.md`) and
//! `cargo xtask bench [-- criterion args]`.
//!
//! The generators are in the library target (`xtask::reproduce`), so the staleness test in
//! `tests/reproduction_up_to_date.rs` runs the very same code.

use std::process::{Command, ExitCode};
use xtask::reproduce::{self, Freshness, PAPERS};

const USAGE: &str = "usage: cargo xtask <reproduce [seed000|seed002|seed003|seed004|all] [--check] | reproduce seed003 --timing | bench [-- criterion args]>";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("reproduce") => run_reproduce(&args[1..]),
        Some("bench") => run_bench(&args[1..]),
        _ => Err(USAGE.to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run_reproduce(args: &[String]) -> Result<(), String> {
    let check = args.iter().any(|a| a == "--check");
    if args.iter().any(|a| a == "--timing") {
        // Wall-clock times are not deterministic: a separate page the staleness test ignores.
        let text = reproduce::seed003::timing().map_err(|e| e.to_string())?;
        let path = reproduce::workspace_root().join("docs/reproduction/seed003-timing.md");
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        println!("wrote {}", path.display());
        return Ok(());
    }
    let names: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| *a != "--check")
        .collect();
    let papers: Vec<&str> = match names.as_slice() {
        [] | ["all"] => PAPERS.iter().map(|p| p.0).collect(),
        list => list.to_vec(),
    };
    let root = reproduce::workspace_root();
    let mut failures = Vec::new();
    for paper in papers {
        let outcome = if check {
            reproduce::generate(paper)
                .and_then(|text| {
                    let path = reproduce::output_path(&root, paper);
                    reproduce::compare(&path, &text).map(|f| (f, path))
                })
                .map(|(f, path)| match f {
                    Freshness::UpToDate => Ok(format!("{}: up to date", path.display())),
                    Freshness::Missing => Err(format!("{}: missing", path.display())),
                    Freshness::Stale { first_diff_line } => Err(format!(
                        "{}: stale (first difference at line {first_diff_line})",
                        path.display()
                    )),
                })
        } else {
            reproduce::write(&root, paper).map(|p| Ok(format!("wrote {}", p.display())))
        };
        match outcome {
            Ok(Ok(msg)) => println!("{msg}"),
            Ok(Err(msg)) => {
                eprintln!("{msg}");
                failures.push(msg);
            }
            Err(e) => {
                eprintln!("{paper}: {e}");
                failures.push(e.to_string());
            }
        }
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(format!("{} reproduction(s) failed", failures.len()))
    }
}

/// Runs every criterion bench of the workspace with short warm-up and measurement times and
/// prints a Markdown summary (bench name, median time). Extra arguments go to criterion.
fn run_bench(args: &[String]) -> Result<(), String> {
    let extra: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| *a != "--")
        .collect();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(reproduce::workspace_root())
        .args([
            "bench",
            "--workspace",
            "--",
            "--warm-up-time",
            "0.5",
            "--measurement-time",
            "2",
        ])
        .args(&extra);
    let out = cmd
        .output()
        .map_err(|e| format!("cannot run cargo bench: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    print!("{stdout}");
    eprint!("{}", String::from_utf8_lossy(&out.stderr));
    if !out.status.success() {
        return Err(format!("cargo bench failed ({})", out.status));
    }
    let rows = parse_criterion(&stdout);
    println!("\n| bench | median time |\n|---|---:|");
    for (name, time) in &rows {
        println!("| {name} | {time} |");
    }
    println!("\n{} benches", rows.len());
    Ok(())
}

/// `(name, median)` from criterion's text output: the name is on the line before `time:` or at
/// its start; the median is the middle value of `[low median high]`.
fn parse_criterion(text: &str) -> Vec<(String, String)> {
    let mut rows = Vec::new();
    let mut last_name = String::new();
    for line in text.lines() {
        if let Some(pos) = line.find("time:") {
            let head = line[..pos].trim();
            let name = if head.is_empty() {
                last_name.clone()
            } else {
                head.to_string()
            };
            if let (Some(a), Some(b)) = (line.find('['), line.find(']')) {
                let parts: Vec<&str> = line[a + 1..b].split_whitespace().collect();
                if parts.len() == 6 {
                    rows.push((name, format!("{} {}", parts[2], parts[3])));
                }
            }
        } else if !line.starts_with(char::is_whitespace) && !line.trim().is_empty() {
            last_name = line.trim().to_string();
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    #[test]
    fn parses_criterion_output_in_both_layouts() {
        let text = "Benchmarking pose_error: Analyzing\npose_error              time:   [812.31 ns 815.02 ns 818.40 ns]\n\
                    a/very/long/bench/name/that/wraps\n                        time:   [1.2000 µs 1.2500 µs 1.3000 µs]\n";
        let rows = super::parse_criterion(text);
        assert_eq!(
            rows,
            vec![
                ("pose_error".to_string(), "815.02 ns".to_string()),
                (
                    "a/very/long/bench/name/that/wraps".to_string(),
                    "1.2500 µs".to_string()
                )
            ]
        );
    }
}
