//! `mte tracker adjust|simulate|uncertainty`: laser-tracker multilateration (seed 004).

use std::fmt::Write;
use std::path::{Path, PathBuf};

use mte::CliError;
use mte_metrology::adjust::{AdjustParams, Adjustment, adjust};
use mte_metrology::gum::{McParams, monte_carlo};
use mte_metrology::io::network_from_csv;
use mte_metrology::network::{LengthUncertainty, Network, Vec3};
use mte_metrology::simulate::{SmoothErrorField, StationLayout, cube_edge_targets, simulate};
use mte_metrology::uncertainty::{LinearisedTracker, TrackerQuantity};
use plotters::prelude::*;

/// Arguments of `mte tracker`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    cmd: Sub,
}

/// The network's CSV inputs (format in docs/formats.md, section "Laser tracker").
#[derive(clap::Args)]
struct Inputs {
    /// Stations CSV: id,x_mm,y_mm,z_mm[,dead_path_mm][,dead_path].
    #[arg(long)]
    stations: PathBuf,
    /// Targets CSV (nominal, commanded positions): id,x_mm,y_mm,z_mm.
    #[arg(long)]
    targets: PathBuf,
    /// Lengths CSV: station,target,length_mm[,sigma_um].
    #[arg(long)]
    lengths: PathBuf,
    /// Output folder (report.md, adjustment.json, deviations-xy.svg).
    #[arg(long, default_value = "out/tracker")]
    out: PathBuf,
}

#[derive(clap::Subcommand)]
enum Sub {
    /// Free-network adjustment: spatial errors at the targets, σ₀ test, residuals, ellipsoids.
    Adjust(Inputs),
    /// Write a simulated seed-004 measurement (cube-edge targets) as CSV files.
    Simulate {
        /// Station layout: 4low, 2high2low or 6.
        #[arg(long, default_value = "4low")]
        layout: String,
        /// Cube edge (mm).
        #[arg(long, default_value_t = 500.0)]
        edge_mm: f64,
        /// Maximum injected error (µm).
        #[arg(long, default_value_t = 20.0)]
        field_um: f64,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output folder for stations.csv, targets.csv, lengths.csv, truth.csv.
        #[arg(long, default_value = "out/tracker-sim")]
        out: PathBuf,
    },
    /// GUM-S1 Monte Carlo uncertainty of ΔD = max |error| (linearised adjustment per trial).
    Uncertainty {
        #[command(flatten)]
        inputs: Inputs,
        /// Monte Carlo trials.
        #[arg(long, default_value_t = 10_000)]
        trials: usize,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

fn lib<E: std::fmt::Display>(e: E) -> CliError {
    CliError::Library(e.to_string())
}

use mte::output::OutDir;
use mte::report::read_text as read;

/// Bytes the Monte Carlo holds per trial: the output value and its sorted copy.
const BYTES_PER_TRIAL: f64 = 16.0;

fn load(i: &Inputs) -> Result<Network, CliError> {
    let (s, t, l) = (read(&i.stations)?, read(&i.targets)?, read(&i.lengths)?);
    network_from_csv(
        (&i.stations.display().to_string(), &s),
        (&i.targets.display().to_string(), &t),
        (&i.lengths.display().to_string(), &l),
        LengthUncertainty::SEED004,
    )
    .map_err(lib)
}

/// Markdown report of an adjustment (µm).
fn markdown(a: &Adjustment) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Laser-tracker multilateration\n\n**Datum:** {}\n",
        a.datum_description
    );
    let (j, d) = a.max_deviation();
    let _ = writeln!(
        s,
        "**Spatial accuracy ΔD = max |error| = {:.2} µm** at {} ({} targets, {} stations, {} iterations).\n",
        d * 1e3,
        a.targets[j].id,
        a.targets.len(),
        a.stations.len(),
        a.iterations
    );
    let g = &a.global;
    let _ = writeln!(
        s,
        "σ₀'/σ₀ = {:.3}, 95 % interval ({:.3}, {:.3}) → {}; [pvv] = {:.4}; {} degrees of freedom.\n",
        g.sigma0_ratio,
        g.interval.0,
        g.interval.1,
        if g.passed { "passed" } else { "FAILED" },
        g.pvv,
        g.degrees_of_freedom
    );
    for w in &a.warnings {
        let _ = writeln!(s, "> warning: {w}\n");
    }
    let sus: Vec<_> = a.observations.iter().filter(|o| o.suspect).collect();
    if !sus.is_empty() {
        let _ = writeln!(
            s,
            "Data snooping (|w| > {:.2}): suspects {}\n",
            g.snooping_critical,
            sus.iter()
                .map(|o| format!(
                    "{}→{} (w = {:.1})",
                    o.station, o.target, o.standardised_residual
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    let _ = writeln!(
        s,
        "| target | nominal x, y, z (mm) | error dx, dy, dz (µm) | \\|error\\| (µm) | 3-D σ (µm) | 95 % ellipsoid semi-axes (µm) |\n|---|---|---|---|---|---|"
    );
    for t in &a.targets {
        let e = t.deviation_mm * 1e3;
        let k = t.ellipsoid.scale_95 * 1e3;
        let _ = writeln!(
            s,
            "| {} | {:.3}, {:.3}, {:.3} | {:.2}, {:.2}, {:.2} | {:.2} | {:.2} | {:.2}, {:.2}, {:.2} |",
            t.id,
            t.nominal_mm.x,
            t.nominal_mm.y,
            t.nominal_mm.z,
            e.x,
            e.y,
            e.z,
            e.norm(),
            t.sigma_3d_mm() * 1e3,
            t.ellipsoid.semi_axes_mm[0] * k,
            t.ellipsoid.semi_axes_mm[1] * k,
            t.ellipsoid.semi_axes_mm[2] * k
        );
    }
    let _ = writeln!(
        s,
        "\n| station | x, y, z (mm) | dead path (mm) |\n|---|---|---|"
    );
    for st in &a.stations {
        let _ = writeln!(
            s,
            "| {} | {:.4}, {:.4}, {:.4} | {:.4} |",
            st.id, st.position_mm.x, st.position_mm.y, st.position_mm.z, st.dead_path_mm
        );
    }
    s
}

/// Volumetric map: error arrows projected on the xy plane (arrows magnified).
fn svg_xy(a: &Adjustment) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (700, 700)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for t in &a.targets {
            x0 = x0.min(t.nominal_mm.x);
            x1 = x1.max(t.nominal_mm.x);
            y0 = y0.min(t.nominal_mm.y);
            y1 = y1.max(t.nominal_mm.y);
        }
        let pad = 0.1 * (x1 - x0).max(y1 - y0).max(1.0);
        let maxe = a.max_deviation().1.max(1e-9);
        let mag = pad / maxe;
        if let Ok(mut chart) = ChartBuilder::on(&root)
            .caption(
                format!(
                    "errors in xy (arrow = error × {mag:.0}); max {:.1} µm",
                    maxe * 1e3
                ),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(50)
            .build_cartesian_2d((x0 - pad)..(x1 + pad), (y0 - pad)..(y1 + pad))
        {
            let _ = chart
                .configure_mesh()
                .x_desc("x (mm)")
                .y_desc("y (mm)")
                .draw();
            for t in &a.targets {
                let (p, e) = (t.nominal_mm, t.deviation_mm * mag);
                let _ = chart.draw_series(std::iter::once(PathElement::new(
                    vec![(p.x, p.y), (p.x + e.x, p.y + e.y)],
                    BLUE.stroke_width(2),
                )));
                let _ =
                    chart.draw_series(std::iter::once(Circle::new((p.x, p.y), 3, BLACK.filled())));
            }
        }
        let _ = root.present();
    }
    svg
}

fn add_adjustment(out: &mut OutDir, a: &Adjustment, extra: &str) -> Result<String, CliError> {
    let md = markdown(a) + extra;
    out.add("report.md", md.clone());
    out.add_json("adjustment.json", a)?;
    out.add("deviations-xy.svg", svg_xy(a));
    Ok(md)
}

fn print_adjustment(out: &Path, md: &str) {
    println!("{}", md.lines().take(6).collect::<Vec<_>>().join("\n"));
    println!("report: {}", out.join("report.md").display());
}

/// Runs `mte tracker …`.
pub fn run(args: &Args) -> Result<(), CliError> {
    match &args.cmd {
        Sub::Adjust(i) => {
            let mut out = OutDir::prepare(&i.out)?;
            let net = load(i)?;
            let a = adjust(&net, &AdjustParams::default()).map_err(lib)?;
            let md = add_adjustment(&mut out, &a, "")?;
            out.commit()?;
            print_adjustment(&i.out, &md);
            Ok(())
        }
        Sub::Uncertainty {
            inputs,
            trials,
            seed,
        } => {
            let mut out = OutDir::prepare(&inputs.out)?;
            if *trials == 0 {
                return Err(CliError::Usage("--trials: at least 1 trial".into()));
            }
            mte::limits::check_memory(
                &format!("--trials {trials}"),
                *trials as f64 * BYTES_PER_TRIAL,
            )?;
            let net = load(inputs)?;
            let a = adjust(&net, &AdjustParams::default()).map_err(lib)?;
            let f = LinearisedTracker::new(&a, TrackerQuantity::MaxDeviation).map_err(lib)?;
            let r = monte_carlo(
                &f,
                &LinearisedTracker::inputs(&a),
                &McParams {
                    trials: *trials,
                    coverage: 0.95,
                    seed: *seed,
                },
            )
            .map_err(lib)?;
            let extra = format!(
                "\n## GUM-S1 Monte Carlo of ΔD\n\nM = {}, seed {}: estimate {:.2} µm, u = {:.2} µm, shortest 95 % interval [{:.2}, {:.2}] µm, symmetric [{:.2}, {:.2}] µm.\n",
                r.trials,
                seed,
                r.estimate * 1e3,
                r.standard_uncertainty * 1e3,
                r.shortest_interval.0 * 1e3,
                r.shortest_interval.1 * 1e3,
                r.symmetric_interval.0 * 1e3,
                r.symmetric_interval.1 * 1e3
            );
            let md = add_adjustment(&mut out, &a, &extra)?;
            out.add_json("uncertainty.json", &r)?;
            out.commit()?;
            print_adjustment(&inputs.out, &md);
            println!("{}", extra.trim());
            Ok(())
        }
        Sub::Simulate {
            layout,
            edge_mm,
            field_um,
            seed,
            out,
        } => {
            let lay = match layout.as_str() {
                "4low" => StationLayout::FourLow,
                "2high2low" => StationLayout::TwoHighTwoLow,
                "6" => StationLayout::Six,
                other => {
                    return Err(CliError::Usage(format!(
                        "--layout: expected 4low, 2high2low or 6, got `{other}`"
                    )));
                }
            };
            let mut dir = OutDir::prepare(out)?;
            if !(edge_mm.is_finite() && *edge_mm > 0.0 && *edge_mm < 1e5) {
                return Err(CliError::Usage(format!(
                    "--edge-mm: expected a cube edge in (0, 100 000) mm, got {edge_mm}"
                )));
            }
            if !(field_um.is_finite() && *field_um >= 0.0 && *field_um < 1e4) {
                return Err(CliError::Usage(format!(
                    "--field-um: expected a maximum error in [0, 10 000) µm, got {field_um}"
                )));
            }
            let targets = cube_edge_targets(*edge_mm, 2);
            let field = SmoothErrorField::new(*edge_mm, &targets, *field_um);
            let sim = simulate(
                &lay.stations(*edge_mm, true),
                &targets,
                &|p: &Vec3| field.eval(p),
                LengthUncertainty::SEED004,
                *seed,
            )
            .map_err(lib)?;
            let n = &sim.network;
            let (s, t, l) = mte_metrology::io::network_to_csv(n);
            let mut tr = String::from("id,x_true_mm,y_true_mm,z_true_mm\n");
            for (tg, p) in n.targets.iter().zip(&sim.true_targets) {
                let _ = writeln!(tr, "{},{:.9},{:.9},{:.9}", tg.id, p.x, p.y, p.z);
            }
            dir.add("stations.csv", s);
            dir.add("targets.csv", t);
            dir.add("truth.csv", tr);
            dir.add("lengths.csv", l);
            dir.commit()?;
            println!(
                "wrote {}/{{stations,targets,lengths,truth}}.csv ({}, {} µm field, seed {seed})",
                out.display(),
                lay.name(),
                field_um
            );
            Ok(())
        }
    }
}
