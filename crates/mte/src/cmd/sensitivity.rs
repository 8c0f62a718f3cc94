//! `mte sensitivity <morris|sobol|pce|local> --problem problem.json --out DIR`: sensitivity of a
//! built-in test model (ishigami, gfunction, linear) over the inputs of a problem file
//! (format in docs/formats.md, "Sensitivity problem"). Writes result.json, indices.csv and
//! indices.svg (bar chart with intervals).

use clap::{Args as ClapArgs, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget};
use mte::CliError;
use mte::plot::{Axis, Interval, error_bar_chart};
use mte_sensitivity::testfn::{GFunction, Ishigami, Linear};
use mte_sensitivity::{Model, Problem};
use serde_json::Value;
use std::io::IsTerminal;
use std::path::PathBuf;

/// One row of the index table: input name, index values per output, and their intervals.
type IndexRow = (String, Vec<f64>, Vec<[f64; 2]>);

/// Which analysis.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Method {
    /// Morris elementary effects.
    Morris,
    /// Sobol' first/total indices (Saltelli 2010 / Jansen).
    Sobol,
    /// Sparse polynomial chaos (OMP, K-fold CV).
    Pce,
    /// Gradient × spread at the means.
    Local,
}

/// Arguments of `mte sensitivity`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Method.
    method: Method,
    /// Problem JSON (inputs, model, method settings).
    #[arg(long)]
    problem: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "sensitivity-out")]
    out: PathBuf,
}

fn lib(e: mte_sensitivity::Error, path: &std::path::Path) -> CliError {
    CliError::Library(format!("{}: {e}", path.display()))
}

fn build_model(v: &Value, k: usize, path: &std::path::Path) -> Result<Box<dyn Model>, CliError> {
    let bad = |m: String| CliError::Library(format!("{}: field `model`: {m}", path.display()));
    let name = v
        .get("name")
        .and_then(Value::as_str)
        .ok_or_else(|| bad("missing `name` (ishigami, gfunction, linear)".into()))?;
    let floats = |f: &str| -> Result<Vec<f64>, CliError> {
        v.get(f)
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .map(|x| {
                        x.as_f64()
                            .ok_or_else(|| bad(format!("`{f}` must hold numbers")))
                    })
                    .collect()
            })
            .unwrap_or_else(|| {
                Err(bad(format!(
                    "`{f}` (array of {k} numbers) is required for `{name}`"
                )))
            })
    };
    match name {
        "ishigami" if k == 3 => Ok(Box::new(Ishigami::default())),
        "ishigami" => Err(bad(format!("ishigami needs 3 inputs, the problem has {k}"))),
        "gfunction" => {
            let a = if v.get("a").is_some() {
                floats("a")?
            } else {
                (0..k).map(|i| i as f64 / 2.0).collect()
            };
            if a.len() != k {
                return Err(bad(format!("`a` has {} values, expected {k}", a.len())));
            }
            Ok(Box::new(GFunction::new(a)))
        }
        "linear" => {
            let c = floats("coef")?;
            if c.len() != k {
                return Err(bad(format!("`coef` has {} values, expected {k}", c.len())));
            }
            Ok(Box::new(Linear::new(c)))
        }
        o => Err(bad(format!(
            "unknown model `{o}`; expected ishigami, gfunction or linear"
        ))),
    }
}

struct Boxed<'a>(&'a dyn Model);
impl Model for Boxed<'_> {
    fn evaluate(&self, x: &[f64], y: &mut [f64]) {
        self.0.evaluate(x, y)
    }
    fn n_outputs(&self) -> usize {
        self.0.n_outputs()
    }
    fn evaluate_batch(&self, n: usize, x: &[f64], y: &mut [f64]) {
        self.0.evaluate_batch(n, x, y)
    }
}

fn params<T: serde::de::DeserializeOwned + Default>(
    v: &Value,
    key: &str,
    path: &std::path::Path,
) -> Result<T, CliError> {
    match v.get(key) {
        None => Ok(T::default()),
        Some(s) => serde_json::from_value(s.clone())
            .map_err(|e| CliError::Library(format!("{}: field `{key}`: {e}", path.display()))),
    }
}

/// Runs the subcommand.
///
/// # Errors
/// Unreadable or invalid problem files (the message names the field), analysis errors, I/O errors.
pub fn run(args: &Args) -> Result<(), CliError> {
    let path = &args.problem;
    let text = std::fs::read_to_string(path).map_err(|source| CliError::Io {
        path: path.clone(),
        source,
    })?;
    let v: Value = serde_json::from_str(&text)
        .map_err(|e| CliError::Library(format!("{}: line {}: {e}", path.display(), e.line())))?;
    let problem = Problem::from_json(&v).map_err(|e| lib(e, path))?;
    let model_box = build_model(v.get("model").unwrap_or(&Value::Null), problem.dim(), path)?;
    let model = Boxed(model_box.as_ref());
    let names = problem.names();
    // (label, [(index name, values, intervals)])
    let (json, rows): (Value, Vec<IndexRow>) = match args.method {
        Method::Sobol => {
            let p: mte_sensitivity::sobol::SobolParams = params(&v, "sobol", path)?;
            let total = (p.n * (problem.dim() + 2)) as u64;
            let bar = ProgressBar::new(total);
            if !std::io::stderr().is_terminal() {
                bar.set_draw_target(ProgressDrawTarget::hidden());
            }
            let r = mte_sensitivity::sobol::sobol_with_progress(&model, &problem, &p, &|n: u64| {
                bar.inc(n)
            })
            .map_err(|e| lib(e, path))?;
            bar.finish_and_clear();
            let o = &r.outputs[0];
            let rows = vec![
                ("S1".to_string(), o.first.clone(), o.first_ci.clone()),
                ("ST".to_string(), o.total.clone(), o.total_ci.clone()),
            ];
            (serde_json::to_value(&r).expect("serialisable"), rows)
        }
        Method::Pce => {
            let p: mte_sensitivity::pce::PceParams = params(&v, "pce", path)?;
            let r =
                mte_sensitivity::pce::build_pce(&model, &problem, &p).map_err(|e| lib(e, path))?;
            let o = &r.outputs[0];
            eprintln!(
                "PCE: degree {}, {} terms, K-fold CV error {:.3e}, corrected LOO {:.3e}",
                o.degree,
                o.terms.len(),
                o.cv_error,
                o.loo_error
            );
            let rows = vec![
                ("S1".to_string(), o.first.clone(), o.first_ci.clone()),
                ("ST".to_string(), o.total.clone(), o.total_ci.clone()),
            ];
            (serde_json::to_value(&r).expect("serialisable"), rows)
        }
        Method::Morris => {
            let p: mte_sensitivity::morris::MorrisParams = params(&v, "morris", path)?;
            let r =
                mte_sensitivity::morris::morris(&model, &problem, &p).map_err(|e| lib(e, path))?;
            let o = &r.outputs[0];
            let rows = vec![
                (
                    "mu_star".to_string(),
                    o.mu_star.clone(),
                    o.mu_star_ci.clone(),
                ),
                ("sigma".to_string(), o.sigma.clone(), vec![]),
            ];
            (serde_json::to_value(&r).expect("serialisable"), rows)
        }
        Method::Local => {
            let r = mte_sensitivity::local::gradient_spread(&model, &problem, 1e-4)
                .map_err(|e| lib(e, path))?;
            let rows = vec![("share".to_string(), r[0].share.clone(), vec![])];
            (serde_json::to_value(&r).expect("serialisable"), rows)
        }
    };
    std::fs::create_dir_all(&args.out).map_err(|source| CliError::Io {
        path: args.out.clone(),
        source,
    })?;
    let write = |name: &str, s: String| {
        let p = args.out.join(name);
        std::fs::write(&p, s).map_err(|source| CliError::Io { path: p, source })
    };
    write(
        "result.json",
        serde_json::to_string_pretty(&json).expect("json"),
    )?;
    let mut csv = String::from("input");
    for (label, _, ci) in &rows {
        csv.push_str(&format!(",{label}"));
        if !ci.is_empty() {
            csv.push_str(&format!(",{label}_low,{label}_high"));
        }
    }
    csv.push('\n');
    for (i, n) in names.iter().enumerate() {
        csv.push_str(n);
        for (_, vals, ci) in &rows {
            csv.push_str(&format!(",{}", vals[i]));
            if !ci.is_empty() {
                csv.push_str(&format!(",{},{}", ci[i][0], ci[i][1]));
            }
        }
        csv.push('\n');
    }
    write("indices.csv", csv)?;
    let (label, vals, ci) = &rows[rows.len().min(2) - 1];
    let bars: Vec<Interval> = names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let (lo, hi) = ci
                .get(i)
                .map(|c| (c[0].min(vals[i]), c[1].max(vals[i])))
                .unwrap_or((vals[i], vals[i]));
            Interval {
                label: n.clone(),
                value: vals[i],
                low: lo,
                high: hi,
            }
        })
        .collect();
    write(
        "indices.svg",
        error_bar_chart(
            &format!("{:?}: {label}", args.method),
            &Axis::new(label.as_str(), ""),
            &bars,
        )?,
    )?;
    println!(
        "wrote {}/result.json, indices.csv, indices.svg",
        args.out.display()
    );
    Ok(())
}
