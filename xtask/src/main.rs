//! `cargo xtask reproduce [seed000|seed002|seed003|seed004|all] [--check]`,
//! `cargo xtask reproduce seed003 --timing` (writes `docs/reproduction/seed003-timing.md`) and
//! `cargo xtask bench [-- criterion args]` and
//! `cargo xtask study [fdr|power|coverage|combined|openworld|all] [--n N] [--n-power M] [--seed S] [--kind axis|tracker|tracker-tools|rtest|rtest-head|rtest-ac|points|points-targets|rotary] [--base-model omit] [--out FILE]`.
//!
//! The generators are in the library target (`xtask::reproduce`), so the staleness test in
//! `tests/reproduction_up_to_date.rs` runs the very same code.

use std::process::{Command, ExitCode};

/// `println!` that ends the program quietly (exit status 141, as a shell's for SIGPIPE) when
/// stdout is closed, as by `| head`, instead of panicking.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($arg)*).is_err() {
            std::process::exit(141);
        }
    }};
}

/// `print!` that ends the program quietly when stdout is closed ([`outln!`]).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if write!(std::io::stdout(), $($arg)*).is_err() {
            std::process::exit(141);
        }
    }};
}
use xtask::reproduce::{self, Freshness, PAPERS};

const USAGE: &str = "usage: cargo xtask <reproduce [seed000|seed002|seed003|seed004|all] [--check] | reproduce seed003 --timing | bench [-- criterion args] | bench-diagnose [--rows N] [--seed S] | study [fdr|power|coverage|combined|openworld|all] [--n N] [--n-power M] [--seed S] [--kind axis|tracker|tracker-tools|rtest|rtest-head|rtest-ac|points|points-targets|rotary] [--base-model omit] [--out FILE]>";

/// `cargo xtask realistic <axis|tracker|tracker-tools|rtest|rtest-head|rtest-ac|points|points-targets|rotary|c-stage> <seed> <dir> [--hidden EFFECT SIZE]
/// [--cycles N] [--targets N] [--wavy]`: writes one realistic dataset (every ordinary error) for trying
/// `mte diagnose` or timing it; clean unless `--hidden` names a study effect (`pitch`,
/// `sawtooth`, `risefall`, … in the unit of the studies' tables; its other parameters drawn
/// from the seed), whose truth is then printed — and written nowhere in the dataset; the
/// manifest's base model is then the studies' user model lacking the effect
/// ([`xtask::studies::user_model_lacking`]). `--hidden` repeated hides several effects at
/// once, as the studies' combined cells do (the k-th of one family on the k-th axis), against
/// the user's model of a real machine.
/// `--cycles`: R-test measurement cycles; `--targets`: tracker targets (the benches' sizes:
/// 8 cycles, 400 targets); `--wavy`: the false-discovery study's wavier ordinary errors;
/// `--noise-scale`: the noise σ times this (0.01: nearly noise-free readings, to tell an
/// estimate's bias from its scatter); `--noise-seed S`: the same machine with another draw of
/// the noise, from its own stream of seed `S` (a bias from the machine's errors repeats in
/// every draw, the scatter does not; what a generator draws with the noise, an R-test's
/// pauses or a points dataset's set-ups, and with it the truth, may differ).
/// `c-stage` writes the 3-D points of a C table with a calibrated
/// target, the C line's location errors and a scale error of X (the bundled
/// `fixtures/datasets/c-stage-points/` is seed 1); `points` the studies' realistic ones, every
/// ordinary error of that machine at once.
fn run_realistic(args: &[String]) -> Result<(), String> {
    const USAGE: &str = "usage: cargo xtask realistic <axis|tracker|tracker-tools|rtest|rtest-head|rtest-ac|points|points-targets|rotary|c-stage> <seed> <dir> [--hidden EFFECT SIZE] [--cycles N] [--targets N] [--wavy] [--noise-scale F] [--noise-seed S]";
    let (positional, options) = args.split_at(args.len().min(3));
    let [kind, seed, dir] = positional else {
        return Err(USAGE.into());
    };
    let count = |flag: &str, v: Option<&String>| -> Result<usize, String> {
        let v = v.ok_or_else(|| format!("{flag}: expected a number\n{USAGE}"))?;
        v.parse().map_err(|e| format!("{flag} `{v}`: {e}"))
    };
    let (mut hidden, mut cycles, mut targets, mut wavy) = (Vec::new(), None, None, false);
    let (mut noise_scale, mut noise_seed): (Option<f64>, Option<u64>) = (None, None);
    let mut rest = options.iter();
    while let Some(flag) = rest.next() {
        match flag.as_str() {
            "--hidden" => {
                let (Some(effect), Some(size)) = (rest.next(), rest.next()) else {
                    return Err(format!("--hidden: expected EFFECT SIZE\n{USAGE}"));
                };
                let e = xtask::studies::Effect::parse(effect).ok_or_else(|| {
                    format!(
                        "--hidden `{effect}`: expected one of {:?}",
                        xtask::studies::Effect::ALL
                    )
                })?;
                let size: f64 = size.parse().map_err(|e| format!("size `{size}`: {e}"))?;
                hidden.push((e, size));
            }
            "--cycles" => cycles = Some(count(flag, rest.next())?),
            "--targets" => targets = Some(count(flag, rest.next())?),
            "--wavy" => wavy = true,
            "--noise-scale" => {
                let v = rest
                    .next()
                    .ok_or_else(|| format!("--noise-scale: expected a number\n{USAGE}"))?;
                noise_scale = match v.parse::<f64>() {
                    Ok(s) if s.is_finite() && s >= 0.0 => Some(s),
                    _ => return Err(format!("--noise-scale `{v}`: expected a number ≥ 0")),
                };
            }
            "--noise-seed" => {
                let v = rest
                    .next()
                    .ok_or_else(|| format!("--noise-seed: expected a number\n{USAGE}"))?;
                noise_seed = Some(v.parse().map_err(|e| {
                    format!("--noise-seed `{v}`: {e} (expected a whole number ≥ 0)")
                })?);
            }
            other => return Err(format!("option `{other}`: unknown\n{USAGE}")),
        }
    }
    if kind == "c-stage" {
        let seed: u64 = seed.parse().map_err(|e| format!("seed `{seed}`: {e}"))?;
        let truth =
            xtask::realistic::points::write_points(seed, std::path::Path::new(dir), true, None)
                .map_err(|e| format!("{dir}: {e}"))?;
        outln!(
            "wrote {} ({} rows, noise {:.2} µm)",
            truth.manifest.display(),
            truth.rows,
            truth.noise_um
        );
        return Ok(());
    }
    let kind = xtask::realistic::Kind::parse(kind).ok_or_else(|| {
        format!(
            "kind `{kind}`: expected {}",
            xtask::realistic::Kind::names()
        )
    })?;
    let seed: u64 = seed.parse().map_err(|e| format!("seed `{seed}`: {e}"))?;
    let dir = std::path::Path::new(dir);
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let effects = hidden;
    let hidden = xtask::studies::hidden_of_seed(&effects, seed);
    let mut spec = xtask::realistic::Spec::new(kind, &hidden);
    if let [(effect, _)] = effects[..] {
        spec.base_model = xtask::studies::user_model_lacking(kind, effect);
    }
    if let Some(s) = noise_scale {
        spec.noise_scale = s;
    }
    spec.noise_seed = noise_seed;
    spec.cycles = cycles;
    spec.targets = targets;
    if wavy {
        spec.waviness = xtask::realistic::smooth::Waviness::Wavy;
    }
    let truth = xtask::realistic::write_spec(&spec, seed, dir).map_err(|e| e.to_string())?;
    for h in &hidden {
        outln!("hidden: {h:?}");
    }
    // What the studies compare the diagnosis with (the machine's total where ordinary and hidden
    // add), in the diagnosis' internal units.
    for e in &truth.effects {
        outln!(
            "truth: {} = {:e}{} ({})",
            e.iso_name_hint,
            e.value,
            if e.signed { "" } else { " (magnitude)" },
            e.detail
        );
    }
    // (A rotary table's noise is an angle: `noise_um` holds mrad.)
    let noise = if kind == xtask::realistic::Kind::Rotary {
        format!("{:.2}″", (truth.noise_um * 1e-3).to_degrees() * 3600.0)
    } else {
        format!("{:.2} µm", truth.noise_um)
    };
    outln!(
        "wrote {} ({} observations, noise {noise})",
        truth.manifest.display(),
        truth.n_observations,
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("reproduce") => run_reproduce(&args[1..]),
        Some("bench") => run_bench(&args[1..]),
        Some("bench-diagnose") => run_bench_diagnose(&args[1..]),
        Some("study") => run_study(&args[1..]),
        Some("realistic") => run_realistic(&args[1..]),
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
        outln!("wrote {}", path.display());
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
            Ok(Ok(msg)) => outln!("{msg}"),
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

/// Runs the diagnosis studies on realistic datasets and prints (or writes, with `--out`) the
/// Markdown page. `--n` datasets per kind for the false-discovery study (default 200),
/// `--n-power` per cell for the power and open-world studies (default 30).
fn run_study(args: &[String]) -> Result<(), String> {
    use xtask::realistic::{BaseModel, Kind};
    use xtask::studies;
    let mut which = "all".to_string();
    let (mut n, mut n_power, mut seed) = (200usize, 30usize, 1u64);
    let mut out: Option<String> = None;
    let mut base_model = BaseModel::Default;
    let mut kinds: Vec<Kind> = Kind::ALL.to_vec();
    let mut recorded: Vec<String> = Vec::new();
    let mut i = 0;
    while i < args.len() {
        let a = args[i].as_str();
        if a.starts_with("--") {
            let v = args
                .get(i + 1)
                .ok_or_else(|| format!("{a} needs a value"))?
                .clone();
            i += 2;
            let bad = |e: std::num::ParseIntError| format!("{a}: {e}");
            match a {
                "--n" => n = v.parse().map_err(bad)?,
                "--n-power" => n_power = v.parse().map_err(bad)?,
                "--seed" => seed = v.parse().map_err(bad)?,
                "--out" => {
                    // not part of the recorded command: the page says where it goes
                    out = Some(v);
                    continue;
                }
                "--kind" => {
                    kinds = vec![
                        Kind::parse(&v)
                            .ok_or_else(|| format!("--kind: `{v}` ({})", Kind::names()))?,
                    ]
                }
                "--base-model" => {
                    base_model = match v.as_str() {
                        "omit" => BaseModel::Omit,
                        "default" => BaseModel::Default,
                        other => return Err(format!("--base-model: `{other}` (omit|default)")),
                    }
                }
                other => return Err(format!("unknown option `{other}`\n{USAGE}")),
            }
            recorded.extend([a.to_string(), v]);
        } else {
            match a {
                "fdr" | "power" | "coverage" | "combined" | "openworld" | "all" => {
                    which = a.to_string()
                }
                other => return Err(format!("unknown argument `{other}`\n{USAGE}")),
            }
            recorded.push(a.to_string());
            i += 1;
        }
    }
    let mut report = studies::StudyReport {
        command: format!(
            "cargo run --release -p xtask -- study {}",
            recorded.join(" ")
        ),
        base_seed: seed,
        ..Default::default()
    };
    if which == "fdr" || which == "all" {
        use xtask::realistic::smooth::Waviness;
        // Then, for robustness, wavier ordinary errors on half as many datasets.
        for (waviness, count) in [(Waviness::Gentle, n), (Waviness::Wavy, n.div_ceil(2))] {
            for &kind in &kinds {
                report
                    .fdr
                    .push(studies::fdr_with(kind, count, seed, &base_model, waviness));
            }
        }
    }
    if base_model == BaseModel::Default {
        // The same kinds against the instrument's default base, on a sixteenth as many
        // datasets and half as many per power cell (each takes 10–60 s on an R-test: the search
        // names the ordinary errors that base leaves out, twenty and more).
        let (clean, cells) = studies::default_base_plan();
        if which == "fdr" || which == "all" {
            for kind in clean.into_iter().filter(|k| kinds.contains(k)) {
                report.default_base.push(studies::fdr_with(
                    kind,
                    n.div_ceil(16),
                    seed,
                    &BaseModel::Omit,
                    xtask::realistic::smooth::Waviness::Gentle,
                ));
            }
        }
        if which == "power" || which == "all" {
            for (kind, effect, size) in cells.into_iter().filter(|c| kinds.contains(&c.0)) {
                report.default_base_power.extend(studies::power_with(
                    kind,
                    effect,
                    &[size],
                    n_power.div_ceil(2),
                    seed,
                    &BaseModel::Omit,
                ));
            }
        }
    }
    if which == "power" || which == "all" {
        for (kind, effect, sizes) in studies::power_plan()
            .into_iter()
            .filter(|c| kinds.contains(&c.0))
        {
            let base = match base_model {
                BaseModel::Default => studies::user_model_lacking(kind, effect),
                ref other => other.clone(),
            };
            report.power.extend(studies::power_with(
                kind, effect, &sizes, n_power, seed, &base,
            ));
        }
    }
    if which == "coverage" || which == "all" {
        // Coverage of the stated uncertainties: one size per effect, `--n` datasets each.
        for (kind, effect, size) in studies::coverage_plan()
            .into_iter()
            .filter(|c| kinds.contains(&c.0))
        {
            report.coverage.push(studies::coverage_with(
                kind,
                effect,
                size,
                n,
                seed,
                &studies::user_model_lacking(kind, effect),
            ));
        }
    }
    if which == "combined" || which == "all" {
        for (kind, effects) in studies::combined_plan()
            .into_iter()
            .filter(|c| kinds.contains(&c.0))
        {
            report.combined.push(studies::combined(
                kind,
                &effects,
                n_power,
                seed,
                &base_model,
            ));
        }
    }
    if which == "openworld" || which == "all" {
        for (kind, effect, size) in studies::openworld_plan()
            .into_iter()
            .filter(|c| kinds.contains(&c.0))
        {
            report.openworld.push(studies::openworld_with(
                kind,
                effect,
                size,
                n_power,
                seed,
                &base_model,
            ));
        }
    }
    let text = studies::render_markdown(&report);
    match out {
        Some(path) => {
            std::fs::write(&path, &text).map_err(|e| format!("{path}: {e}"))?;
            outln!("wrote {path}");
        }
        None => out!("{text}"),
    }
    Ok(())
}

/// Runs every criterion bench of the workspace with short warm-up and measurement times and
/// prints a Markdown summary (bench name, median time). Extra arguments go to criterion.
/// `cargo xtask bench-diagnose [--rows N] [--seed S]`: the diagnosis of an N-row axis log
/// (default 1 000 000), its time as a ratio to reading the same data in the same run, and the
/// peak memory.
fn run_bench_diagnose(args: &[String]) -> Result<(), String> {
    let mut rows = 1_000_000usize;
    let mut seed = 1u64;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let value = it.next().ok_or_else(|| format!("{a}: expected a value"))?;
        match a.as_str() {
            "--rows" => {
                rows = value
                    .parse()
                    .map_err(|e| format!("--rows `{value}`: {e}"))?
            }
            "--seed" => {
                seed = value
                    .parse()
                    .map_err(|e| format!("--seed `{value}`: {e}"))?
            }
            _ => return Err(format!("unknown option `{a}`; {USAGE}")),
        }
    }
    let dir = reproduce::workspace_root().join("target/bench-diagnose");
    let _ = std::fs::remove_dir_all(&dir);
    let r = xtask::scale::run(rows, seed, &dir, 64.0)?;
    let gb = |g: Option<f64>| g.map_or("n/a".into(), |g| format!("{g:.2} GB"));
    outln!(
        "| rows | read + prepare | diagnosis | ratio | peak memory after reading | peak memory | causes |"
    );
    outln!("|---:|---:|---:|---:|---:|---:|---|");
    outln!(
        "| {} | {:.2} s | {:.2} s | {:.1}× | {} | {} | {} |",
        r.rows,
        r.load_s,
        r.diagnose_s,
        r.diagnose_s / r.load_s,
        gb(r.load_peak_gb),
        gb(r.peak_gb),
        r.findings.join(", ")
    );
    Ok(())
}

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
    out!("{stdout}");
    eprint!("{}", String::from_utf8_lossy(&out.stderr));
    if !out.status.success() {
        return Err(format!("cargo bench failed ({})", out.status));
    }
    let rows = parse_criterion(&stdout);
    outln!("\n| bench | median time |\n|---|---:|");
    for (name, time) in &rows {
        outln!("| {name} | {time} |");
    }
    outln!("\n{} benches", rows.len());
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
