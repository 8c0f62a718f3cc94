//! `axis` datasets: bidirectional ISO 230-2 style runs of the X axis measured with a laser
//! interferometer. The reading is the deviation (measured − commanded, µm) at each target.

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::smooth::{Smooth, signed};
use super::{
    EffectKind, Hidden, Kind, Spec, TrueDrift, TrueEffect, Truth, sawtooth, unsupported,
    write_manifest,
};

/// The stated noise a user writes: the true σ rounded to 0.1 µm (at least 0.1 µm; for a rotary
/// table the same in arcsec).
pub fn stated_noise(sigma_um: f64) -> f64 {
    ((sigma_um * 10.0).round() / 10.0).max(0.1)
}

/// Irregularly spaced targets over `[0, stroke]`, ends included (ISO 230-2 asks for irregular
/// spacing so that periodic errors are not sampled at one phase).
pub fn irregular_targets(rng: &mut impl Rng, stroke: f64, n: usize) -> Vec<f64> {
    let step = stroke / (n - 1) as f64;
    (0..n)
        .map(|i| {
            if i == 0 || i == n - 1 {
                i as f64 * step
            } else {
                i as f64 * step + rng.random_range(-0.35..0.35) * step
            }
        })
        .map(|x: f64| (x * 1000.0).round() / 1000.0)
        .collect()
}

/// A programme of bidirectional runs (ISO 230-2): `runs` runs over `targets`, each a forward
/// sweep over the targets in order and a backward one in reverse, readings `dt` s apart and a
/// `pause` after each sweep.
pub(crate) struct Programme<'a> {
    pub targets: &'a [f64],
    pub runs: usize,
    pub dt: f64,
    pub pause: f64,
}

impl Programme<'_> {
    /// Writes `dir/runs.csv` (columns `run,direction,<position>,t_s,<deviation>`, the time with
    /// `time_decimals`): at each reading the deviation `f(position, direction ±1, t)` plus noise
    /// of σ `sigma` drawn from `rng` (none at σ = 0). Returns the number of readings.
    pub(crate) fn write(
        &self,
        dir: &Path,
        (position, deviation): (&str, &str),
        time_decimals: usize,
        sigma: f64,
        rng: &mut ChaCha8Rng,
        f: impl Fn(f64, f64, f64) -> f64,
    ) -> std::io::Result<usize> {
        let noise = Normal::new(0.0, sigma.max(1e-300)).expect("finite σ");
        let mut csv = format!("run,direction,{position},t_s,{deviation}\n");
        let (mut t, mut count) = (0.0, 0);
        for run in 1..=self.runs {
            for sign in [1.0, -1.0] {
                let order: Vec<f64> = if sign > 0.0 {
                    self.targets.to_vec()
                } else {
                    self.targets.iter().rev().copied().collect()
                };
                for x in order {
                    let mut dev = f(x, sign, t);
                    if sigma > 0.0 {
                        dev += noise.sample(rng);
                    }
                    let _ = writeln!(
                        csv,
                        "{run},{},{x:.3},{t:.*},{dev:.4}",
                        if sign > 0.0 { "+" } else { "-" },
                        time_decimals,
                    );
                    count += 1;
                    t += self.dt;
                }
                t += self.pause;
            }
        }
        std::fs::write(dir.join("runs.csv"), csv)?;
        Ok(count)
    }
}

/// A hidden effect as a function of (x mm, direction ±1, t s), µm.
type Part = Box<dyn Fn(f64, f64, f64) -> f64>;

/// The time of the last reading of [`Programme::write`]: `runs` × two directions of `targets`
/// readings `dt` apart, a pause between directions.
fn programme_duration(runs: usize, targets: usize, dt: f64, pause: f64) -> f64 {
    let sweeps = 2 * runs;
    (sweeps * targets) as f64 * dt + (sweeps - 1) as f64 * pause - dt
}

pub(crate) fn write(spec: &Spec, rng: &mut ChaCha8Rng, dir: &Path) -> std::io::Result<Truth> {
    let stroke = rng.random_range(500.0..=1000.0_f64).round();
    let n_targets = rng.random_range(15..=25);
    let mut targets = irregular_targets(rng, stroke, n_targets);
    let mut runs = rng.random_range(3..=5);
    let sigma = rng.random_range(0.1..=0.6) * spec.noise_scale;
    let s = spec.ordinary_scale;
    let pos_size = rng.random_range(3.0..=20.0) * s;
    let positioning = Smooth::draw(rng, 0.0, stroke, pos_size, spec.waviness);
    let zero_um = signed(rng, 0.0, 5.0) * s;
    let ordinary_reversal_um = if spec.ordinary_reversal {
        signed(rng, 0.5, 3.0) * s
    } else {
        0.0
    };
    let mut dt = rng.random_range(3.0..=6.0_f64);
    let pause = rng.random_range(10.0..=60.0_f64);
    let phase = rng.random_range(0.0..TAU);
    if let Some((log_runs, readings)) = spec.log {
        // Drawn after the ordinary dataset's draws: the machine is the same for a seed.
        runs = log_runs;
        targets = irregular_targets(rng, stroke, readings.max(2));
        dt = 0.02;
    }

    let mut effects = Vec::new();
    let mut ordinary = Vec::new();
    if spec.ordinary_reversal {
        ordinary.push(TrueEffect {
            iso_name_hint: "reversal".into(),
            kind: EffectKind::Reversal,
            size: ordinary_reversal_um,
            unit: "um",
            value: ordinary_reversal_um * 1e-3,
            signed: true,
            period: None,
            detail: "ordinary reversal".into(),
            drift: None,
        });
    }
    let mut reversal_um = ordinary_reversal_um;
    // Each hidden effect as a function of (x, direction, t) in µm.
    let mut parts: Vec<Part> = Vec::new();
    for h in &spec.hidden {
        match *h {
            Hidden::Pitch {
                axis: 0,
                amplitude_um,
                period_mm,
            } => {
                parts.push(Box::new(move |x, _, _| {
                    amplitude_um * (TAU * x / period_mm + phase).sin()
                }));
                effects.push(TrueEffect {
                    iso_name_hint: "EXX".into(),
                    kind: EffectKind::Periodic,
                    size: amplitude_um,
                    unit: "um",
                    value: amplitude_um.abs() * 1e-3,
                    signed: false,
                    period: Some(("X".into(), period_mm)),
                    detail: format!("period {period_mm:.2} mm"),
                    drift: None,
                });
            }
            Hidden::Reversal { um } => {
                reversal_um += um;
                effects.push(TrueEffect {
                    iso_name_hint: "reversal".into(),
                    kind: EffectKind::Reversal,
                    size: um,
                    unit: "um",
                    value: 0.0, // set below: the total
                    signed: true,
                    period: None,
                    detail: String::new(),
                    drift: None,
                });
            }
            Hidden::ReversalGrowing { um } => {
                parts.push(Box::new(move |x, sign, _| 0.5 * sign * um * x / stroke));
                // What the targets show: the reversal's mean over them.
                let mean =
                    targets.iter().map(|x| um * x / stroke).sum::<f64>() / targets.len() as f64;
                effects.push(TrueEffect {
                    iso_name_hint: "reversal".into(),
                    kind: EffectKind::Reversal,
                    size: um,
                    unit: "um",
                    value: mean * 1e-3, // plus the ordinary reversal, below
                    signed: true,
                    period: None,
                    detail: format!("growing along X to {um:.2} µm at its end"),
                    drift: None,
                });
            }
            Hidden::ZeroDrift { um_per_min } => {
                parts.push(Box::new(move |_, _, t| um_per_min * t / 60.0));
                effects.push(TrueEffect {
                    iso_name_hint: "drift".into(),
                    kind: EffectKind::Drift,
                    size: um_per_min,
                    unit: "um/min",
                    value: um_per_min * 1e-3 / 60.0,
                    signed: true,
                    period: None,
                    detail: "linear drift of the zero".into(),
                    drift: None,
                });
            }
            Hidden::ScaleDrift { ppm, tau_s, fixed } => {
                let x0 = fixed * stroke;
                parts.push(Box::new(move |x, _, t| {
                    ppm * 1e-3 * (x - x0) * (1.0 - (-t / tau_s).exp())
                }));
                let t_last = programme_duration(runs, targets.len(), dt, pause);
                effects.push(TrueEffect {
                    iso_name_hint: "EXX scale".into(),
                    kind: EffectKind::Drift,
                    size: ppm,
                    unit: "ppm",
                    value: ppm * 1e-6,
                    signed: true,
                    period: None,
                    detail: format!("thermal expansion about X = {x0:.0} mm, τ = {tau_s:.0} s"),
                    drift: Some(TrueDrift {
                        record_change: ppm * 1e-6 * (1.0 - (-t_last / tau_s).exp()),
                        tau_s,
                    }),
                });
            }
            Hidden::Sawtooth {
                axis: 0,
                amplitude_um,
                period_mm,
            } => {
                let off = phase / TAU;
                parts.push(Box::new(move |x, _, _| {
                    amplitude_um * sawtooth(x / period_mm + off)
                }));
                effects.push(TrueEffect {
                    iso_name_hint: "EXX".into(),
                    kind: EffectKind::OpenWorld,
                    size: amplitude_um,
                    unit: "um",
                    value: amplitude_um.abs() * 1e-3,
                    signed: false,
                    period: Some(("X".into(), period_mm)),
                    detail: format!("sawtooth, period {period_mm:.2} mm"),
                    drift: None,
                });
            }
            Hidden::RiseFall { um, peak } => {
                let tau_s = peak * programme_duration(runs, targets.len(), dt, pause);
                parts.push(Box::new(move |_, _, t| {
                    um * (t / tau_s) * (1.0 - t / tau_s).exp()
                }));
                effects.push(TrueEffect {
                    iso_name_hint: "drift".into(),
                    kind: EffectKind::OpenWorld,
                    size: um,
                    unit: "um",
                    value: um * 1e-3,
                    signed: true,
                    period: None,
                    detail: format!("rise and fall of the zero, peak at {tau_s:.0} s"),
                    drift: None,
                });
            }
            _ => return Err(unsupported(Kind::Axis, h)),
        }
    }
    for (e, h) in effects.iter_mut().zip(&spec.hidden) {
        match h {
            Hidden::Reversal { .. } => e.value = reversal_um * 1e-3,
            Hidden::ReversalGrowing { .. } => e.value += reversal_um * 1e-3,
            _ => {}
        }
    }

    let programme = Programme {
        targets: &targets,
        runs,
        dt,
        pause,
    };
    let time_decimals = if spec.log.is_some() { 2 } else { 1 };
    // The noise's stream, from here on ([`Spec::noise_seed`]).
    let mut own = spec.noise_rng();
    let rng = own.as_mut().unwrap_or(rng);
    let n_obs = programme.write(
        dir,
        ("x_mm", "deviation_um"),
        time_decimals,
        sigma,
        rng,
        |x, sign, t| {
            let mut dev = zero_um + positioning.at(x) + 0.5 * reversal_um * sign;
            for p in &parts {
                dev += p(x, sign, t);
            }
            dev
        },
    )?;
    let manifest = serde_json::json!({
        "format": "mte-dataset/1",
        "kind": "axis",
        "description": "X-axis bidirectional positioning runs (laser interferometer)",
        "axis": "X",
        "noise_um": stated_noise(sigma.max(0.05)),
        "data": "runs.csv",
    });
    let path = write_manifest(dir, manifest, &spec.base_model)?;
    Ok(Truth {
        kind: Kind::Axis,
        manifest: path,
        effects,
        ordinary,
        noise_um: sigma,
        stations: Vec::new(),
        n_observations: n_obs,
    })
}
