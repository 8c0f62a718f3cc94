//! `cargo xtask bench-diagnose`: the diagnosis on a long interferometer log (default 1 000 000
//! readings of a realistic X axis with a ball-screw pitch error and a reversal on top), timed
//! against reading the same dataset in the same run, with the process' peak memory.

use std::path::Path;
use std::time::Instant;

use crate::realistic::{Hidden, Kind, Spec, write_spec};

/// What one run measured.
#[derive(Debug, Clone)]
pub struct ScaleRun {
    /// Scalar observations.
    pub rows: usize,
    /// Seconds to read the dataset and build its base model and candidates (the baseline).
    pub load_s: f64,
    /// Seconds of the diagnosis itself (search, outer folds, final model).
    pub diagnose_s: f64,
    /// Peak resident memory of the process, GB (`VmHWM`; `None` where /proc is absent).
    pub peak_gb: Option<f64>,
    /// The same once the dataset was read and prepared, before the diagnosis.
    pub load_peak_gb: Option<f64>,
    /// The causes named, with their sizes.
    pub findings: Vec<String>,
}

/// Writes the log into `dir`, reads it and diagnoses it.
///
/// # Errors
/// Generator, reader or diagnosis errors as text.
pub fn run(rows: usize, seed: u64, dir: &Path, max_memory_gb: f64) -> Result<ScaleRun, String> {
    const RUNS: usize = 10;
    let mut spec = Spec::new(
        Kind::Axis,
        &[
            Hidden::Pitch {
                axis: 0,
                amplitude_um: 1.5,
                period_mm: 20.0,
            },
            Hidden::Reversal { um: 2.0 },
        ],
    );
    spec.log = Some((RUNS, rows.div_ceil(2 * RUNS)));
    let truth = write_spec(&spec, seed, dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let start = Instant::now();
    let prepared = mte_diagnose::load(&truth.manifest).map_err(|e| e.to_string())?;
    let load_s = start.elapsed().as_secs_f64();
    let load_peak_gb = peak_memory_gb();
    let params = mte_diagnose::DiagnoseParams {
        max_memory_gb,
        ..Default::default()
    };
    let start = Instant::now();
    let d = prepared.diagnose(&params).map_err(|e| e.to_string())?;
    let diagnose_s = start.elapsed().as_secs_f64();
    Ok(ScaleRun {
        rows: d.observations,
        load_s,
        diagnose_s,
        peak_gb: peak_memory_gb(),
        load_peak_gb,
        findings: d
            .findings
            .iter()
            .map(|f| {
                let size = f
                    .estimates
                    .first()
                    .map_or(String::new(), |e| e.text.clone());
                match &f.hyper_parameter {
                    Some(h) => format!("{} {size} ({} {})", f.name, h.name, h.text),
                    None => format!("{} {size}", f.name),
                }
            })
            .collect(),
    })
}

/// Peak resident set of this process, GB, from `/proc/self/status`.
fn peak_memory_gb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0 / 1e9)
}
