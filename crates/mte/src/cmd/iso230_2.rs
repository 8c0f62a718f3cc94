//! `mte iso230-2 <runs.csv>`: ISO 230-2 evaluation of a linear axis from bidirectional runs.

use std::fmt::Write;
use std::path::PathBuf;

use mte::CliError;
use mte::output::OutDir;
use mte::report::read_text;
use mte_metrology::iso230_2::{AxisResult, evaluate, readings_from_csv};
use plotters::prelude::*;

/// Arguments of `mte iso230-2`.
#[derive(clap::Args)]
pub struct Args {
    /// Runs CSV: target_mm,run,direction,deviation_um (docs/formats.md, section "ISO 230-2").
    pub runs: PathBuf,
    /// Output folder (report.md, iso230-2.json, iso230-2.svg).
    #[arg(long, default_value = "out/iso230-2")]
    pub out: PathBuf,
}

fn markdown(a: &AxisResult) -> String {
    let mut s = String::from("# ISO 230-2 positioning evaluation\n\n");
    let _ = writeln!(s, "| quantity | value (µm) |\n|---|---|");
    for (k, v) in [
        ("reversal B", a.reversal_b_um),
        ("mean reversal B̄", a.mean_reversal_um),
        ("repeatability R↑", a.repeatability_up_um),
        ("repeatability R↓", a.repeatability_down_um),
        ("repeatability R", a.repeatability_um),
        ("systematic deviation E↑", a.systematic_up_um),
        ("systematic deviation E↓", a.systematic_down_um),
        ("systematic deviation E", a.systematic_um),
        ("mean deviation range M", a.mean_range_um),
        ("accuracy A↑", a.accuracy_up_um),
        ("accuracy A↓", a.accuracy_down_um),
        ("accuracy A", a.accuracy_um),
    ] {
        let _ = writeln!(s, "| {k} | {v:.3} |");
    }
    let _ = writeln!(
        s,
        "\n{} runs per direction.\n\n| target (mm) | x̄↑ | x̄↓ | x̄ | B | s↑ | s↓ | R |\n|---|---|---|---|---|---|---|---|",
        a.runs
    );
    for t in &a.targets {
        let _ = writeln!(
            s,
            "| {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
            t.target_mm,
            t.mean_up_um,
            t.mean_down_um,
            t.mean_um,
            t.reversal_um,
            t.s_up_um,
            t.s_down_um,
            t.r_um
        );
    }
    s
}

fn svg(a: &AxisResult) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 480)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let x0 = a.targets.first().map(|t| t.target_mm).unwrap_or(0.0);
        let x1 = a.targets.last().map(|t| t.target_mm).unwrap_or(1.0);
        let lo = a
            .targets
            .iter()
            .map(|t| (t.mean_up_um - 2.0 * t.s_up_um).min(t.mean_down_um - 2.0 * t.s_down_um))
            .fold(f64::MAX, f64::min);
        let hi = a
            .targets
            .iter()
            .map(|t| (t.mean_up_um + 2.0 * t.s_up_um).max(t.mean_down_um + 2.0 * t.s_down_um))
            .fold(f64::MIN, f64::max);
        let (lo, hi) = mte::plot::finite_range(lo, hi);
        let pad = 0.1 * (hi - lo).max(1e-3);
        if let Ok(mut c) = ChartBuilder::on(&root)
            .caption(
                "ISO 230-2: mean deviations ± 2s (↑ red, ↓ blue)",
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(55)
            .build_cartesian_2d(
                {
                    let (x0, x1) = mte::plot::finite_range(x0, x1);
                    x0..x1.max(x0 + 1e-9)
                },
                (lo - pad)..(hi + pad),
            )
        {
            let _ = c
                .configure_mesh()
                .x_desc("target (mm)")
                .y_desc("deviation (µm)")
                .draw();
            for (col, f) in [(RED, true), (BLUE, false)] {
                let pts = |k: f64| -> Vec<(f64, f64)> {
                    a.targets
                        .iter()
                        .map(|t| {
                            if f {
                                (t.target_mm, t.mean_up_um + k * t.s_up_um)
                            } else {
                                (t.target_mm, t.mean_down_um + k * t.s_down_um)
                            }
                        })
                        .collect()
                };
                let _ = c.draw_series(LineSeries::new(pts(0.0), col.stroke_width(2)));
                let _ = c.draw_series(LineSeries::new(pts(2.0), col.mix(0.4)));
                let _ = c.draw_series(LineSeries::new(pts(-2.0), col.mix(0.4)));
            }
        }
        let _ = root.present();
    }
    svg
}

/// Runs `mte iso230-2`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let mut out = OutDir::prepare(&args.out)?;
    let text = read_text(&args.runs)?;
    let r = readings_from_csv(&args.runs.display().to_string(), &text)
        .map_err(|e| CliError::Library(e.to_string()))?;
    let a = evaluate(&r).map_err(|e| CliError::Library(e.to_string()))?;
    let md = markdown(&a);
    out.add("report.md", md.clone());
    out.add_json("iso230-2.json", &a)?;
    out.add("iso230-2.svg", svg(&a));
    out.commit()?;
    println!("{}", md.lines().take(16).collect::<Vec<_>>().join("\n"));
    Ok(())
}
