//! A long record (a continuous interferometer log) is searched on an evenly thinned copy and
//! what the search finds is fitted to every observation: the sizes and their uncertainties come
//! from all of them, and the report says how the search was run.

mod common;

use mte_diagnose::{DiagnoseParams, load};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::f64::consts::TAU;

/// Writes 8 runs × 2 directions of a continuous log of X (`per_pass` readings per direction,
/// 20 ms apart): a smooth positioning error, a 12.5 mm ball-screw pitch of `pitch_um`, a
/// reversal of `reversal_um` and 0.3 µm of noise. Returns the manifest's path.
fn write_log(
    dir: &std::path::Path,
    per_pass: usize,
    pitch_um: f64,
    reversal_um: f64,
) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let noise = Normal::new(0.0, 0.3).unwrap();
    let stroke = 600.0;
    let mut csv = String::from("run,direction,x_mm,t_s,deviation_um\n");
    let mut t = 0.0;
    for run in 1..=8 {
        for sign in [1.0, -1.0] {
            for k in 0..per_pass {
                let u = k as f64 / (per_pass - 1) as f64;
                let x = if sign > 0.0 {
                    u * stroke
                } else {
                    (1.0 - u) * stroke
                };
                let s = x / stroke;
                let smooth = 6.0 * s * s - 2.5 * s + 1.2 * (TAU * s * 0.7 + 0.3).sin();
                let dev = smooth
                    + pitch_um * (TAU * x / 12.5 + 0.4).sin()
                    + 0.5 * reversal_um * sign
                    + noise.sample(&mut rng);
                csv.push_str(&format!(
                    "{run},{},{x:.4},{t:.2},{dev:.4}\n",
                    if sign > 0.0 { "+" } else { "-" }
                ));
                t += 0.02;
            }
            t += 20.0;
        }
    }
    std::fs::write(dir.join("runs.csv"), csv).unwrap();
    let manifest = dir.join("manifest.json");
    std::fs::write(
        &manifest,
        r#"{"format": "mte-dataset/1", "kind": "axis", "axis": "X", "data": "runs.csv", "noise_um": 0.3}"#,
    )
    .unwrap();
    manifest
}

#[test]
fn a_long_log_is_searched_thinned_and_fitted_whole() {
    let dir = common::scratch("long");
    let rows = 16 * 2_500;
    let manifest = write_log(&dir, 2_500, 0.8, 1.5);
    let p = load(&manifest).unwrap();
    assert_eq!(p.observations.len(), rows);
    let params = DiagnoseParams::default();
    assert!(
        rows > params.search_rows,
        "the test needs a record longer than the search"
    );
    let d = p.diagnose(&params).unwrap();
    assert!(
        d.notes.iter().any(
            |n| n.contains("long record") && n.contains(&format!("of the {rows} observations"))
        ),
        "{:?}",
        d.notes
    );
    let pitch = d.finding("EXX periodic").expect("the pitch is found");
    let amplitude = pitch
        .estimates
        .iter()
        .find(|e| e.name.contains("amplitude"))
        .unwrap();
    let period = pitch.hyper_parameter.as_ref().unwrap();
    // Sizes from all 40 000 readings: u of the amplitude ~ 0.3 µm · √(2/40 000) ≈ 2 nm.
    assert!(
        amplitude.uncertainty < 5e-6,
        "u = {} mm",
        amplitude.uncertainty
    );
    assert!(
        (amplitude.value - 0.8e-3).abs() < 3.0 * amplitude.uncertainty.max(2e-6),
        "{}",
        amplitude.text
    );
    assert!(
        (period.value - 12.5).abs() < 3.0 * period.uncertainty.max(1e-4),
        "{}",
        period.text
    );
    let reversal = d.finding("EXX reversal").expect("the reversal is found");
    assert!(
        (reversal.estimates[0].value - 1.5e-3).abs()
            < 3.0 * reversal.estimates[0].uncertainty.max(2e-6)
    );
    // The plots' evidence is thinned; the held-out gain is honest (near the noise).
    assert!(d.residual_series.iter().all(|s| s.x.len() <= 20_000));
    let held = d.held_out.as_ref().unwrap();
    assert!(
        held.diagnosed_rms < 0.4e-3 && held.base_rms > held.diagnosed_rms,
        "{held:?}"
    );
}
