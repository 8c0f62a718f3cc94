//! `rotary` datasets: bidirectional ISO 230-2 style runs of a rotary table (C) measured with an
//! autocollimator and a polygon or a rotary interferometer. The reading is the deviation
//! (measured − commanded angle, arcsec) at each target angle.

use std::path::Path;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::smooth::{Periodic, signed};
use super::{
    EffectKind, Hidden, Kind, Spec, TrueEffect, Truth, angular_positioning, unsupported,
    write_manifest,
};

/// Arcseconds per radian.
const ARCSEC: f64 = 180.0 * 3600.0 / std::f64::consts::PI;

/// `n` target angles over a turn, °, about 360/n apart with irregular steps (each moved by up
/// to ±35 % of the step, 0° kept), as ISO 230-2 asks so that periodic errors are not sampled at
/// one phase.
pub fn irregular_turn(rng: &mut impl Rng, n: usize) -> Vec<f64> {
    let step = 360.0 / n as f64;
    (0..n)
        .map(|i| {
            let c = if i == 0 {
                0.0
            } else {
                i as f64 * step + rng.random_range(-0.35..0.35) * step
            };
            (c * 1000.0).round() / 1000.0
        })
        .collect()
}

/// A rotary table with its ordinary angular positioning error — a zero offset and a random
/// smooth function over a turn (harmonics of a turn, [`Periodic`]) of 2–15″ — measured at 24–48
/// irregular angles in 3–5 bidirectional runs, noise 0.2–1.0″; on top, the hidden effects of
/// `spec`: an angular positioning error at one harmonic of a turn (a worm gear's tooth error), a
/// reversal (the worm's backlash: the `-` runs `um` µrad below the `+` runs).
pub(crate) fn write(spec: &Spec, rng: &mut ChaCha8Rng, dir: &Path) -> std::io::Result<Truth> {
    let n_targets = rng.random_range(24..=48);
    let targets = irregular_turn(rng, n_targets);
    let runs = rng.random_range(3..=5);
    let sigma_arcsec = rng.random_range(0.2..=1.0) * spec.noise_scale;
    let s = spec.ordinary_scale;
    let size = rng.random_range(2.0..=15.0) / ARCSEC * s;
    let positioning = Periodic::draw(rng, size, spec.waviness);
    let zero = signed(rng, 0.0, 5.0) / ARCSEC * s;
    let dt = rng.random_range(5.0..=10.0_f64);
    let pause = rng.random_range(10.0..=60.0_f64);

    let mut effects = Vec::new();
    // The hidden harmonics: (rad, cycles per turn, phase).
    let mut harmonics: Vec<(f64, f64, f64)> = Vec::new();
    // The hidden reversal, rad.
    let mut reversal = 0.0;
    for h in &spec.hidden {
        match *h {
            Hidden::AngularPositioning {
                rotary: 1,
                harmonic,
                urad,
            } => {
                let (drawn, truth) = angular_positioning(rng, &positioning, 1, harmonic, urad);
                harmonics.push(drawn);
                effects.push(truth);
            }
            Hidden::Reversal { um: urad } => {
                reversal += urad * 1e-6;
                effects.push(TrueEffect {
                    iso_name_hint: "reversal".into(),
                    kind: EffectKind::Reversal,
                    size: urad,
                    unit: "urad",
                    value: urad * 1e-6,
                    signed: true,
                    period: None,
                    detail: String::new(),
                    drift: None,
                });
            }
            _ => return Err(unsupported(Kind::Rotary, h)),
        }
    }

    let programme = super::axis::Programme {
        targets: &targets,
        runs,
        dt,
        pause,
    };
    // The noise's stream, from here on ([`Spec::noise_seed`]).
    let mut own = spec.noise_rng();
    let rng = own.as_mut().unwrap_or(rng);
    let n_obs = programme.write(
        dir,
        ("c_deg", "deviation_arcsec"),
        1,
        sigma_arcsec,
        rng,
        |c, sign, _| {
            let theta = c.to_radians();
            let mut dev = zero + positioning.at(theta) + 0.5 * reversal * sign;
            for &(amp, k, phase) in &harmonics {
                dev += amp * (k * theta + phase).sin();
            }
            dev * ARCSEC
        },
    )?;
    let manifest = serde_json::json!({
        "format": "mte-dataset/1",
        "kind": "axis",
        "description": "C rotary table bidirectional positioning runs (autocollimator and polygon)",
        "axis": "C",
        "noise_arcsec": super::axis::stated_noise(sigma_arcsec.max(0.05)),
        "data": "runs.csv",
    });
    let path = write_manifest(dir, manifest, &spec.base_model)?;
    Ok(Truth {
        kind: Kind::Rotary,
        manifest: path,
        effects,
        ordinary: Vec::new(),
        noise_um: sigma_arcsec / ARCSEC * 1e3,
        stations: Vec::new(),
        n_observations: n_obs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn a_turn_of_targets_is_irregular_and_inside_the_turn() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let t = irregular_turn(&mut rng, 36);
        assert_eq!(t[0], 0.0);
        assert!(
            t.windows(2).all(|w| w[1] > w[0] + 3.0) && t[35] < 360.0,
            "{t:?}"
        );
        let steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let spread = steps.iter().fold(0.0_f64, |m, s| m.max((s - 10.0).abs()));
        assert!(spread > 2.0, "irregular steps: {steps:?}");
    }
}
