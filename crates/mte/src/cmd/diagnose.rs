//! `mte diagnose <manifest>`: what the model gets wrong, the named cause and the gain.

use std::path::PathBuf;

use mte_diagnose::{DiagnoseParams, Diagnosis, Quantity, load_with_noise, report};
use plotters::prelude::*;

use mte::CliError;

/// Arguments of `mte diagnose`.
#[derive(clap::Args)]
pub struct Args {
    /// The dataset's manifest: JSON, `mte-dataset/1` (axis runs, tracker lengths, 3-D points;
    /// docs/formats-diagnose.md) or `mte-rtest/1` (R-test; docs/formats.md).
    pub manifest: PathBuf,
    /// Folder for the report (report.md, diagnosis.json, one SVG of residuals per finding).
    #[arg(long, default_value = "out/diagnose")]
    pub out: PathBuf,
    /// Standard uncertainty of one observation (µm) where the dataset states none (R-test data).
    #[arg(long)]
    pub noise_um: Option<f64>,
    /// Family-wise significance level of a discovery.
    #[arg(long, default_value_t = 1e-3)]
    pub alpha: f64,
}

/// Runs the diagnosis and writes the report.
pub fn run(args: &Args) -> Result<(), CliError> {
    let mut out = mte::output::OutDir::prepare(&args.out)?;
    mte::report::check_regular_file(&args.manifest)?;
    let prepared = load_with_noise(&args.manifest, args.noise_um)
        .map_err(|e| CliError::Library(e.to_string()))?;
    let params = DiagnoseParams {
        alpha: args.alpha,
        max_memory_gb: mte::limits::max_memory_gb()?,
        ..DiagnoseParams::default()
    };
    let title = prepared.title.clone();
    // Units: the preparation, the search on all data, each outer fold's search, the final model.
    let bar = mte::progress::bar(mte_diagnose::progress_units(&params), "diagnosis");
    let diagnosis = prepared.diagnose_with_progress(&params, &|n: u64| bar.inc(n));
    bar.finish_and_clear();
    let diagnosis = diagnosis.map_err(|e| CliError::Library(e.to_string()))?;
    let markdown = report::markdown(&diagnosis, &title);
    let md_path = args.out.join("report.md");
    out.add("report.md", markdown.clone());
    let json_path = args.out.join("diagnosis.json");
    out.add_json("diagnosis.json", &diagnosis)?;
    let mut plots = Vec::new();
    for (k, series) in diagnosis.residual_series.iter().enumerate() {
        let name = format!("residuals-{}-{}.svg", k + 1, series.variable);
        out.add(name.clone(), residual_svg(&diagnosis, k));
        plots.push(args.out.join(name));
    }
    out.commit()?;
    // The verdict first: what an engineer reads in a minute.
    let verdict: String = markdown
        .split("## Base model")
        .next()
        .unwrap_or(&markdown)
        .to_string();
    println!("{verdict}");
    println!("Report: {}", md_path.display());
    println!("JSON:   {}", json_path.display());
    for p in plots {
        println!("Plot:   {}", p.display());
    }
    Ok(())
}

/// The evidence of one finding: the residuals of the final model with the finding left out,
/// against the covariate that exposes it (rotary angles of more than a turn folded to one), with the fitted
/// effect drawn over them; one panel per channel. For unexplained structure, the final residuals
/// with the dependence the structure test found drawn over them.
/// In µm (arcsec for angular observations).
fn residual_svg(d: &Diagnosis, index: usize) -> String {
    let s = &d.residual_series[index];
    let rotary = s.variable.len() == 1 && "ABC".contains(s.variable.as_str());
    let (x_scale, x_unit) = match s.variable.as_str() {
        "t" => (1.0 / 60.0, "min"),
        "direction" | "setup" => (1.0, ""),
        _ if rotary => (180.0 / std::f64::consts::PI, "deg"),
        _ => (1.0, "mm"),
    };
    let mut xs: Vec<f64> = s.x.iter().map(|x| x * x_scale).collect();
    // Angles of more than one turn folded to one (a tilting axis' −90° to 90° stays as it is).
    let (lo, hi) = extent(&xs);
    let folded = rotary && hi - lo > 360.0 + 1e-9;
    if folded {
        xs.iter_mut().for_each(|v| *v = v.rem_euclid(360.0));
    }
    let (y_scale, y_desc) = match d.quantity {
        Quantity::Angle => (180.0 / std::f64::consts::PI * 3600.0, "residual (arcsec)"),
        _ => (1e3, "residual (µm)"),
    };
    let residual: Vec<f64> = s.residual.iter().map(|v| v * y_scale).collect();
    let effect: Vec<f64> = s.effect.iter().map(|v| v * y_scale).collect();
    let (x_lo, x_hi) = bounds(&xs);
    let (y_lo, y_hi) = bounds(
        residual
            .iter()
            .chain(effect.iter())
            .copied()
            .collect::<Vec<_>>()
            .as_slice(),
    );
    let channels: Vec<usize> = (0..d.channels.len())
        .filter(|c| s.channel.contains(c))
        .collect();
    // A long record: small dots, or the markers would hide the residuals.
    let dense = xs.len() > 2_000;
    let mut svg = String::new();
    {
        let height = 120 + 300 * channels.len() as u32;
        let root = SVGBackend::with_string(&mut svg, (900, height)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let title = match &s.finding {
            Some(name) => format!(
                "{name}: residuals without it against {} (grey), fitted effect (red {})",
                s.variable,
                if dense { "dots" } else { "crosses" }
            ),
            None => format!(
                "unexplained structure: final residuals against {} (grey), {} beyond the model (red {})",
                s.variable,
                s.structure.as_deref().unwrap_or("the dependence"),
                if dense { "dots" } else { "crosses" }
            ),
        };
        let root = root
            .titled(&title, ("sans-serif", 18))
            .unwrap_or_else(|_| root.clone());
        let panels = root.split_evenly((channels.len().max(1), 1));
        for (panel, &ch) in panels.iter().zip(&channels) {
            let chart = ChartBuilder::on(panel)
                .caption(&d.channels[ch], ("sans-serif", 15))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi);
            let Ok(mut chart) = chart else { continue };
            let x_desc = match (x_unit.is_empty(), folded) {
                (true, _) => s.variable.clone(),
                (false, true) => format!("{} ({x_unit}, one turn)", s.variable),
                (false, false) => format!("{} ({x_unit})", s.variable),
            };
            let _ = chart.configure_mesh().x_desc(x_desc).y_desc(y_desc).draw();
            let points = |values: &[f64]| -> Vec<(f64, f64)> {
                (0..xs.len())
                    .filter(|&i| s.channel[i] == ch)
                    .map(|i| (xs[i], values[i]))
                    .collect()
            };
            let residual_style = RGBColor(90, 110, 150).mix(0.45).filled();
            let effect_style = RGBColor(210, 30, 20).stroke_width(2);
            let _ = chart.draw_series(
                points(&residual)
                    .into_iter()
                    .map(|p| Circle::new(p, 2, residual_style)),
            );
            if dense {
                let _ = chart.draw_series(
                    points(&effect)
                        .into_iter()
                        .map(|p| Circle::new(p, 1, RGBColor(210, 30, 20).filled())),
                );
            } else {
                let _ = chart.draw_series(
                    points(&effect)
                        .into_iter()
                        .map(|p| Cross::new(p, 4, effect_style)),
                );
            }
        }
        let _ = root.present();
    }
    svg
}

/// The smallest and largest of `v` (∞ and −∞ when empty).
fn extent(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        })
}

fn bounds(v: &[f64]) -> (f64, f64) {
    let (lo, hi) = extent(v);
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-6);
    (lo - pad, hi + pad)
}
