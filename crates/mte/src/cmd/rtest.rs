//! `mte rtest simulate|identify`: ISO 10791-6 R-test (seed 002).

use std::fmt::Write;
use std::path::{Path, PathBuf};

use mte::CliError;
use mte::output::OutDir;
use mte::plot::{Axis, Series, XyChart};
use mte::report::read_text;
use mte_kinematics::Machine;
use mte_linalg::Vec3;
use mte_rtest::io::{dataset_to_strings, read_dataset};
use mte_rtest::{
    Dataset, FitSpec, ParamKind, PlanItem, Program, SetupSpec, SimOptions, identify,
    setup_consistency, simulate, slot_by_name,
};

/// Arguments of `mte rtest`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    cmd: Sub,
}

#[derive(clap::Subcommand)]
enum Sub {
    /// Simulate R-test programs on a machine with given errors; writes manifest.json, readings.csv and SVG traces.
    Simulate {
        /// Machine: library name or machine JSON file.
        #[arg(long, default_value = "seed002-bc-trunnion")]
        machine: String,
        /// Ball centre in table coordinates, mm, "x,y,z" (repeat for several setups).
        #[arg(long, default_values_t = vec!["0,177,60".to_string()])]
        ball: Vec<String>,
        /// Rotary angle at the centring of each setup, e.g. "C=180" (one per --ball, optional).
        #[arg(long)]
        centring: Vec<String>,
        /// Tests: BK1, BK2, BK4 (comma separated).
        #[arg(long, default_value = "BK1,BK2,BK4")]
        tests: String,
        /// Injected errors, e.g. "EX0B=10um,EZ0B=-5um,EA0B=0.003deg" (units um, mm, urad, rad, deg).
        #[arg(long, default_value = "")]
        errors: String,
        /// Sensor noise, µm (standard deviation per component).
        #[arg(long, default_value_t = 0.5)]
        noise_um: f64,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output folder.
        #[arg(long, default_value = "out/rtest-sim")]
        out: PathBuf,
    },
    /// Identify rotary-axis location errors from R-test data (manifest + CSV); writes report.md, fit.json and SVG traces.
    Identify {
        /// The manifest (format mte-rtest/1, docs/formats.md).
        #[arg(long)]
        manifest: PathBuf,
        /// Also fit the linear-axis squareness errors EC0Y, EB0Z, EA0Z.
        #[arg(long)]
        squareness: bool,
        /// Extra parameters by ISO name (comma separated), e.g. "EA0Y".
        #[arg(long, default_value = "")]
        params: String,
        /// Accept setups centred outside an axis's stroke (an error otherwise).
        #[arg(long)]
        allow_outside_stroke: bool,
        /// Output folder.
        #[arg(long, default_value = "out/rtest-identify")]
        out: PathBuf,
    },
}

fn lib(e: impl std::fmt::Display) -> CliError {
    CliError::Library(e.to_string())
}

fn parse_errors(m: &Machine, s: &str) -> Result<Vec<f64>, CliError> {
    let mut e = vec![0.0; m.n_slots()];
    for item in s.split(',').map(str::trim).filter(|x| !x.is_empty()) {
        let (name, val) = item
            .split_once('=')
            .ok_or_else(|| CliError::Usage(format!("--errors: `{item}` is not NAME=VALUEunit")))?;
        let slot = slot_by_name(m, name.trim()).map_err(lib)?;
        let val = val.trim();
        let split = val
            .find(|c: char| c.is_alphabetic() || c == 'µ')
            .unwrap_or(val.len());
        let (num, unit) = val.split_at(split);
        let x: f64 = num.parse().map_err(|_| {
            CliError::Usage(format!("--errors: `{num}` in `{item}` is not a number"))
        })?;
        let v = match (unit, slot.angular) {
            ("um" | "µm", false) => x * 1e-3,
            ("mm" | "", false) => x,
            ("urad" | "µrad", true) => x * 1e-6,
            ("rad" | "", true) => x,
            ("deg", true) => x.to_radians(),
            _ => {
                return Err(CliError::Usage(format!(
                    "--errors: unit `{unit}` does not fit {} ({})",
                    slot.iso,
                    if slot.angular {
                        "angle: urad, rad, deg"
                    } else {
                        "length: um, mm"
                    }
                )));
            }
        };
        slot.add_to(&mut e, v);
    }
    Ok(e)
}

fn parse_vec3(s: &str) -> Result<Vec3, CliError> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| CliError::Usage(format!("--ball: `{s}` is not x,y,z")))?;
    if v.len() != 3 {
        return Err(CliError::Usage(format!(
            "--ball: `{s}` needs three numbers"
        )));
    }
    Ok(Vec3::new(v[0], v[1], v[2]))
}

fn rotary(m: &Machine) -> impl Fn(&str) -> bool + '_ {
    move |a: &str| {
        m.axis_index(a)
            .map(|i| matches!(m.axes()[i].kind, mte_kinematics::AxisKind::Rotary))
            .unwrap_or(false)
    }
}

/// SVG traces per (setup, test): dx, dy, dz (µm) against the rotary angle with the largest travel.
fn traces(
    m: &Machine,
    ds: &Dataset,
    model: Option<&[Vec3]>,
    out: &mut OutDir,
) -> Result<Vec<String>, CliError> {
    let rot = rotary(m);
    let mut files = Vec::new();
    for (si, s) in ds.setups.iter().enumerate() {
        let mut tests: Vec<String> = ds
            .readings
            .iter()
            .filter(|r| r.setup == si)
            .map(|r| r.test.clone())
            .collect();
        tests.dedup();
        for t in tests {
            let rows = ds.select(Some(&t), Some(si));
            let travel = |i: usize| {
                let v: Vec<f64> = rows.iter().map(|&k| ds.readings[k].q[i]).collect();
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                    - v.iter().copied().fold(f64::INFINITY, f64::min)
            };
            let ax = (0..ds.axis_names.len())
                .filter(|&i| rot(&ds.axis_names[i]))
                .max_by(|&a, &b| travel(a).total_cmp(&travel(b)))
                .unwrap_or(0);
            let mut chart = XyChart::new(format!("R-test {t}, setup {}", s.id))
                .x_axis(Axis::new(format!("{} angle", ds.axis_names[ax]), "deg"))
                .y_axis(Axis::new("ball − nest", "µm"));
            for (c, name) in ["dx", "dy", "dz"].iter().enumerate() {
                let meas: Vec<(f64, f64)> = rows
                    .iter()
                    .map(|&k| {
                        (
                            ds.readings[k].q[ax].to_degrees(),
                            ds.readings[k].d_mm[c] * 1e3,
                        )
                    })
                    .collect();
                chart = chart.series(Series::scatter(format!("{name} measured"), meas));
                if let Some(pred) = model {
                    let p: Vec<(f64, f64)> = rows
                        .iter()
                        .map(|&k| (ds.readings[k].q[ax].to_degrees(), pred[k][c] * 1e3))
                        .collect();
                    chart = chart.series(Series::line(format!("{name} model"), p));
                }
            }
            let svg = chart.render()?;
            let f = format!("trace-{}-{}.svg", s.id.replace(['/', ' '], "_"), t);
            out.add(f.clone(), svg);
            files.push(f);
        }
    }
    Ok(files)
}

/// Runs `mte rtest`.
///
/// # Errors
/// Usage, I/O and library errors, each naming the offending input.
pub fn run(args: &Args) -> Result<(), CliError> {
    match &args.cmd {
        Sub::Simulate {
            machine,
            ball,
            centring,
            tests,
            errors,
            noise_um,
            seed,
            out,
        } => {
            let mut dir = OutDir::prepare(out)?;
            if !(noise_um.is_finite() && *noise_um >= 0.0 && *noise_um < 1e4) {
                return Err(CliError::Usage(format!(
                    "--noise-um: expected a sensor noise in [0, 10 000) µm, got {noise_um}"
                )));
            }
            if centring.len() > ball.len() {
                return Err(CliError::Usage(format!(
                    "--centring given {} times for {} --ball setup(s): one --centring per --ball, in order (`{}` has no setup)",
                    centring.len(),
                    ball.len(),
                    centring[ball.len()]
                )));
            }
            let test_names: Vec<&str> = tests
                .split(',')
                .map(str::trim)
                .filter(|x| !x.is_empty())
                .collect();
            if test_names.is_empty() {
                return Err(CliError::Usage(format!(
                    "--tests: `{tests}` names no test; expected BK1, BK2 and/or BK4"
                )));
            }
            for (i, t) in test_names.iter().enumerate() {
                if test_names[..i].contains(t) {
                    return Err(CliError::Usage(format!("--tests: `{t}` appears twice")));
                }
            }
            let m = super::machine::load(machine)?;
            let e = parse_errors(&m, errors)?;
            let mut plan = Vec::new();
            for (k, b) in ball.iter().enumerate() {
                let mut spec = SetupSpec::new(&format!("ball{}", k + 1), parse_vec3(b)?);
                let mut hold = None;
                if let Some(c) = centring.get(k) {
                    let (a, v) = c.split_once('=').ok_or_else(|| {
                        CliError::Usage(format!("--centring: `{c}` is not AXIS=deg"))
                    })?;
                    let v: f64 = v
                        .trim()
                        .parse()
                        .ok()
                        .filter(|v: &f64| v.is_finite())
                        .ok_or_else(|| {
                            CliError::Usage(format!("--centring: `{v}` is not a finite number"))
                        })?;
                    let k = m.axis_index(a.trim()).ok_or_else(|| {
                        CliError::Usage(format!("--centring: unknown axis `{}` in `{c}`", a.trim()))
                    })?;
                    let ax = &m.axes()[k];
                    if !matches!(ax.kind, mte_kinematics::AxisKind::Rotary) {
                        return Err(CliError::Usage(format!(
                            "--centring: `{c}`: axis {} is not rotary",
                            ax.name
                        )));
                    }
                    let (lo, hi) = (ax.stroke.0.to_degrees(), ax.stroke.1.to_degrees());
                    let tol = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
                    if v < lo - tol || v > hi + tol {
                        return Err(CliError::Usage(format!(
                            "--centring: `{c}`: {v} deg is outside the stroke [{lo}, {hi}] deg of axis {}",
                            ax.name
                        )));
                    }
                    spec = spec.centred_at(a.trim(), v);
                    hold = Some((a.trim().to_string(), v));
                }
                let mut programs = Vec::new();
                for &t in &test_names {
                    let mut p = match t {
                        "BK1" => Program::bk1(&m, None),
                        "BK2" => Program::bk2(&m),
                        "BK4" => Program::bk4(&m, None),
                        other => {
                            return Err(CliError::Usage(format!(
                                "--tests: unknown test `{other}` (BK1, BK2, BK4)"
                            )));
                        }
                    }
                    .map_err(lib)?;
                    if let Some((a, v)) = &hold
                        && !p.axes.contains(a)
                    {
                        p = p.with_hold(a, *v);
                    }
                    programs.push(p);
                }
                plan.push(PlanItem {
                    setup: spec,
                    programs,
                });
            }
            let opts = SimOptions {
                noise_sd_mm: noise_um * 1e-3,
                seed: *seed,
                ..Default::default()
            };
            let sim = simulate(&m, &plan, &e[..], &opts).map_err(lib)?;
            let (man, csv) = dataset_to_strings(
                &sim.dataset,
                "readings.csv",
                "R-test (simulated)",
                &rotary(&m),
            );
            dir.add("manifest.json", man);
            dir.add("readings.csv", csv);
            let files = traces(&m, &sim.dataset, None, &mut dir)?;
            dir.commit()?;
            println!(
                "wrote {} readings to {} (manifest.json, readings.csv, {} SVG traces)",
                sim.dataset.readings.len(),
                out.display(),
                files.len()
            );
            Ok(())
        }
        Sub::Identify {
            manifest,
            squareness,
            params,
            allow_outside_stroke,
            out,
        } => {
            let mut outdir = OutDir::prepare(out)?;
            let text = read_text(manifest)?;
            let v: serde_json::Value = serde_json::from_str(&text)
                .map_err(|e| CliError::Library(format!("{}: {e}", manifest.display())))?;
            let mname = v.get("machine").and_then(|x| x.as_str()).ok_or_else(|| {
                CliError::Library(format!("{}: missing field `machine`", manifest.display()))
            })?;
            let dir = manifest.parent().unwrap_or(Path::new("."));
            if !Machine::library_names().contains(&mname) {
                mte::report::check_regular_file(&dir.join(mname))?;
            }
            let m = Machine::library_or_file(mname, dir).map_err(lib)?;
            let ds = read_dataset(manifest, &rotary(&m)).map_err(lib)?;
            if !allow_outside_stroke {
                for (i, s) in ds.setups.iter().enumerate() {
                    for (name, v) in ds.axis_names.iter().zip(&s.centring_q) {
                        let Some(k) = m.axis_index(name) else {
                            continue;
                        };
                        let ax = &m.axes()[k];
                        let (lo, hi) = ax.stroke;
                        let tol = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
                        if *v < lo - tol || *v > hi + tol {
                            let (f, unit) = if rotary(&m)(name) {
                                (180.0 / std::f64::consts::PI, "deg")
                            } else {
                                (1.0, "mm")
                            };
                            return Err(CliError::Library(format!(
                                "{}: setups[{i}].centring.{name}: {} {unit} is outside the stroke [{}, {}] {unit}; pass --allow-outside-stroke to identify anyway",
                                manifest.display(),
                                v * f,
                                lo * f,
                                hi * f
                            )));
                        }
                    }
                }
            }
            let mut spec = FitSpec::pivots(&m).map_err(lib)?;
            if *squareness {
                spec = spec.with_squareness(&m).map_err(lib)?;
            }
            let extra: Vec<&str> = params
                .split(',')
                .map(str::trim)
                .filter(|x| !x.is_empty())
                .collect();
            spec = spec.with_names(&m, &extra).map_err(lib)?;
            let fit = identify(&m, &ds, &spec).map_err(lib)?;
            let pred: Vec<Vec3> = ds
                .readings
                .iter()
                .zip(&fit.residuals)
                .map(|(r, e)| r.d_mm - e)
                .collect();
            let files = traces(&m, &ds, Some(&pred), &mut outdir)?;
            let mut md = String::new();
            let _ = writeln!(
                md,
                "# R-test identification\n\nData: `{}` ({} readings, {} setups; {}). Machine `{}`.\n",
                manifest.display(),
                ds.readings.len(),
                ds.setups.len(),
                ds.note,
                m.name()
            );
            let _ = writeln!(
                md,
                "| ISO | IBS | value | std. uncertainty |\n|---|---|---|---|"
            );
            for e in fit.kinematic() {
                if let ParamKind::Slot(s) = &e.kind {
                    let (val, u) = if s.angular {
                        (
                            format!("{:.5} °", e.value.to_degrees()),
                            e.std_uncertainty
                                .map(|u| format!("{:.5} °", u.to_degrees())),
                        )
                    } else {
                        (
                            format!("{:.2} µm", e.value * 1e3),
                            e.std_uncertainty.map(|u| format!("{:.2} µm", u * 1e3)),
                        )
                    };
                    let _ = writeln!(
                        md,
                        "| {} | {} | {val} | {} |",
                        s.iso,
                        s.ibs.clone().unwrap_or_default(),
                        u.unwrap_or_else(|| "unobservable".into())
                    );
                }
            }
            let _ = writeln!(
                md,
                "\nσ0 = {:.3} µm per component, {} degrees of freedom, largest residual {:.2} µm.\n",
                fit.sigma0_mm * 1e3,
                fit.dof,
                fit.max_abs_residual_mm() * 1e3
            );
            let _ = writeln!(
                md,
                "## Identifiability\n\nRank {} of {} parameters; relative singular values: {}.\n",
                fit.identifiability.rank,
                fit.identifiability.n_params,
                fit.identifiability
                    .relative_singular_values
                    .iter()
                    .map(|v| format!("{v:.1e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            if fit.warnings.is_empty() {
                let _ = writeln!(md, "All parameters are identifiable from these data.\n");
            }
            for w in &fit.warnings {
                let _ = writeln!(md, "- {w}");
            }
            if ds.setups.len() > 1 {
                match setup_consistency(&m, &ds, &spec) {
                    Ok(c) => {
                        let _ = writeln!(
                            md,
                            "\n## Setup consistency (each setup fitted alone)\n\n| parameter | max − min | z |\n|---|---|---|"
                        );
                        for (l, sp, z) in &c.spread {
                            let _ = writeln!(md, "| {l} | {sp:.3e} | {z:.1} |");
                        }
                        let bad = c.inconsistent(5.0);
                        if !bad.is_empty() {
                            let _ = writeln!(
                                md,
                                "\nSetups disagree beyond 5σ on {bad:?}: the model misses an effect that depends on the ball position (e.g. a linear-axis squareness to a rotary axis, seed 002 Table 2)."
                            );
                        }
                    }
                    Err(e) => {
                        let _ = writeln!(md, "\nSetup consistency not available: {e}");
                    }
                }
            }
            let _ = writeln!(md, "\n## Traces\n");
            for f in &files {
                let _ = writeln!(md, "![{f}]({f})");
            }
            outdir.add("report.md", md.clone());
            outdir.add_json("fit.json", &fit)?;
            outdir.commit()?;
            for w in &fit.warnings {
                eprintln!("warning: {w}");
            }
            println!("{md}");
            Ok(())
        }
    }
}
