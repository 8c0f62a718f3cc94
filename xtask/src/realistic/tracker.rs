//! `tracker` datasets: laser-tracker multilateration of a three-axis machine.
//!
//! The machine (chain workpiece–Y–X–bed–Z–tool, table axes X and Y with sign −1 as in
//! `fixtures/machines/seed004-3axis.json`) is written as an `mte-machine/1` file beside the
//! manifest with strokes and offsets drawn per dataset. Its tool tip in the workpiece frame is
//! computed here with the full homogeneous-transform chain: every carriage carries the error
//! transform `Trans(δ(q))·Rot(ε(q))` of its six component errors, the Y and Z motions run along
//! directions tilted by the squareness errors, and the angular errors act through the offsets
//! of the axis stack and the tool (Abbe offsets).
//!
//! `tracker-tools` datasets measure every pose with the reflector at 3–4 offsets from the tool
//! tip (the tool tip itself, one across in X, one across in Y, one further down the tool), as
//! a volumetric calibration does to see the tool's angular errors apart from its translations.

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::axis::stated_noise;
use super::geom::{Iso, LinearErrors, REALISTIC, V3, rot_x, rot_y, rot_z, trans};
use super::smooth::signed;
use super::{
    EffectKind, Hidden, Kind, LINEAR, SQUARENESS, Spec, TrueEffect, Truth, sawtooth, unsupported,
    write_manifest,
};

/// An extra positioning error of one linear axis (hidden pitch or sawtooth), mm.
#[derive(Debug, Clone, Copy)]
pub struct Wave {
    /// Amplitude, mm.
    pub amplitude_mm: f64,
    /// Period, mm.
    pub period_mm: f64,
    /// Phase, rad.
    pub phase: f64,
    /// Sawtooth instead of sine.
    pub sawtooth: bool,
}

impl Wave {
    /// The value at coordinate `q` (mm).
    pub fn at(&self, q: f64) -> f64 {
        if self.sawtooth {
            self.amplitude_mm * sawtooth(q / self.period_mm + self.phase / TAU)
        } else {
            self.amplitude_mm * (TAU * q / self.period_mm + self.phase).sin()
        }
    }
}

/// A three-axis machine with its true errors.
#[derive(Debug, Clone)]
pub struct TrackerMachine {
    /// Strokes of X, Y, Z, mm (X `[0, Sx]`, Y `[−Sy, 0]`, Z `[−Sz, 0]`).
    pub strokes: [(f64, f64); 3],
    /// Height of the Y carriage frame above the X carriage frame, mm.
    pub h_y_mm: f64,
    /// Height of the workpiece frame above the Y carriage frame, mm.
    pub h_w_mm: f64,
    /// Tool length (spindle nose to tip), mm.
    pub tool_mm: f64,
    /// Component errors of X, Y, Z.
    pub components: [LinearErrors; 3],
    /// Squareness errors EC0Y (Y to X), EA0Z (Z to Y), EB0Z (Z to X), rad: the Y motion runs along
    /// `Rot_z(EC0Y)·ŷ`, the Z motion along `Rot_x(EA0Z)·Rot_y(EB0Z)·ẑ`.
    pub squareness: [f64; 3],
    /// Extra positioning errors per axis.
    pub waves: [Vec<Wave>; 3],
    /// Open world: a Y positioning error growing from mid-Y at a rate that changes along X.
    pub two_axis: Option<super::TwoAxis>,
}

impl TrackerMachine {
    /// A machine without errors.
    pub fn perfect(strokes: [(f64, f64); 3], h_y_mm: f64, h_w_mm: f64, tool_mm: f64) -> Self {
        Self {
            strokes,
            h_y_mm,
            h_w_mm,
            tool_mm,
            components: [
                LinearErrors::zero(),
                LinearErrors::zero(),
                LinearErrors::zero(),
            ],
            squareness: [0.0; 3],
            waves: [Vec::new(), Vec::new(), Vec::new()],
            two_axis: None,
        }
    }

    fn carriage(&self, k: usize, q: f64) -> Iso {
        let mut e = self.components[k].at(q);
        let extra: f64 = self.waves[k].iter().map(|w| w.at(q)).sum();
        let mut d = V3::zeros();
        d[k] = extra;
        e = trans(d) * e;
        e
    }

    /// Workpiece frame in the bed frame at commanded `q` (mm).
    pub fn workpiece_in_bed(&self, q: [f64; 3]) -> Iso {
        let u_x = V3::x();
        let u_y = rot_z(self.squareness[0]) * V3::y();
        trans(-q[0] * u_x)
            * self.carriage(0, q[0])
            * trans(V3::new(0.0, 0.0, self.h_y_mm))
            * trans(-q[1] * u_y)
            * self.carriage(1, q[1])
            * trans(V3::new(0.0, 0.0, self.h_w_mm))
    }

    /// Tool tip frame in the bed frame at commanded `q` (mm).
    pub fn tool_in_bed(&self, q: [f64; 3]) -> Iso {
        let u_z = rot_x(self.squareness[1]) * rot_y(self.squareness[2]) * V3::z();
        trans(V3::new(0.0, 0.0, self.h_y_mm + self.h_w_mm + self.tool_mm))
            * trans(q[2] * u_z)
            * self.carriage(2, q[2])
            * trans(V3::new(0.0, 0.0, -self.tool_mm))
    }

    /// The actual tool tip in the workpiece frame (mm); ideally `(X, Y, Z)`.
    pub fn tip(&self, q: [f64; 3]) -> V3 {
        self.reflector(q, V3::zeros())
    }

    /// The actual place of a reflector at `offset` from the tool tip (tool frame, mm) in the
    /// workpiece frame; ideally `(X, Y, Z) + offset`.
    pub fn reflector(&self, q: [f64; 3], offset: V3) -> V3 {
        let mut p = (self.workpiece_in_bed(q).inverse() * self.tool_in_bed(q))
            .transform_point(&offset.into())
            .coords;
        if let Some(e) = &self.two_axis {
            p.y += e.at(q[0], q[1], self.strokes[1]);
        }
        p
    }

    /// The squareness errors EC0Y, EA0Z, EB0Z as ISO 230-1 defines them, the angles between the
    /// axes' least-squares reference lines (rad, signs of `squareness`), through what the
    /// measured positions of each axis (`positions`: X, Y, Z, each once) show: besides the tilted
    /// directions of motion, the slope of each straightness (a straightness's linear part is a
    /// squareness), and the mean roll and yaw of the X carriage, which turn Y (riding on it)
    /// against X and Z. The component errors are zero at the stroke's end, not at their mean, and
    /// their straightness has a linear part; a model of their variation along the axis leaves
    /// both to the squareness. (Over the whole stroke the lines differ by what the errors do
    /// between the positions, which no measurement at them shows.)
    pub fn squareness_at(&self, positions: [&[f64]; 3]) -> [f64; 3] {
        let (x, y, z) = (
            &self.components[0],
            &self.components[1],
            &self.components[2],
        );
        let slope = |f: &super::smooth::Smooth, k: usize| f.slope(positions[k]);
        let mean = |f: &super::smooth::Smooth| f.mean(positions[0]);
        [
            self.squareness[0] + mean(&x.e[2]) + slope(&x.d[1], 0) + slope(&y.d[0], 1),
            self.squareness[1] - mean(&x.e[0]) + slope(&y.d[2], 1) - slope(&z.d[1], 2),
            self.squareness[2] - slope(&x.d[2], 0) + slope(&z.d[0], 2),
        ]
    }

    /// Tip error: actual minus ideal tip, mm.
    pub fn tip_error(&self, q: [f64; 3]) -> V3 {
        self.tip(q) - V3::new(q[0], q[1], q[2])
    }

    /// The `mte-machine/1` description of the nominal machine.
    pub fn machine_json(&self) -> serde_json::Value {
        let [sx, sy, sz] = self.strokes;
        serde_json::json!({
            "format": "mte-machine/1",
            "name": "three-axis",
            "description": "Three-axis machine, chain W-Y-X-Z-T: the workpiece sits on Y, Y on X, X on the bed; Z on the bed carries the tool. Table axes X and Y with sign -1; the tool tip is at the workpiece origin at X = Y = Z = 0.",
            "tool": "tool",
            "workpiece": "workpiece",
            "axis_order": ["X", "Y", "Z"],
            "bodies": [
                {"name": "bed"},
                {"name": "X", "parent": "bed", "offset_mm": [0, 0, 0],
                 "joint": {"type": "linear", "axis": "X", "direction": [1, 0, 0], "sign": -1, "stroke_mm": [sx.0, sx.1]}},
                {"name": "Y", "parent": "X", "offset_mm": [0.0, 0.0, self.h_y_mm],
                 "joint": {"type": "linear", "axis": "Y", "direction": [0, 1, 0], "sign": -1, "stroke_mm": [sy.0, sy.1]}},
                {"name": "workpiece", "parent": "Y", "offset_mm": [0.0, 0.0, self.h_w_mm]},
                {"name": "Z", "parent": "bed", "offset_mm": [0.0, 0.0, self.h_y_mm + self.h_w_mm + self.tool_mm],
                 "joint": {"type": "linear", "axis": "Z", "direction": [0, 0, 1], "sign": 1, "stroke_mm": [sz.0, sz.1]}},
                {"name": "tool", "parent": "Z", "offset_mm": [0.0, 0.0, -self.tool_mm]}
            ]
        })
    }
}

/// Station positions around the working volume (workpiece frame, mm).
fn draw_stations(rng: &mut impl Rng, strokes: [(f64, f64); 3]) -> Vec<V3> {
    let n = rng.random_range(4..=6);
    let c = V3::new(
        0.5 * (strokes[0].0 + strokes[0].1),
        0.5 * (strokes[1].0 + strokes[1].1),
        0.5 * (strokes[2].0 + strokes[2].1),
    );
    let half_diag = 0.5
        * ((strokes[0].1 - strokes[0].0).powi(2) + (strokes[1].1 - strokes[1].0).powi(2)).sqrt();
    let sz = strokes[2].1 - strokes[2].0;
    let phi0 = rng.random_range(0.0..TAU);
    (0..n)
        .map(|i| {
            let phi = phi0 + TAU * i as f64 / n as f64 + rng.random_range(-0.3..0.3);
            // 250–700 mm outside the volume's circumscribed circle: every line of sight is
            // longer than the largest dead path (150 mm) plus a margin, as a tracker needs.
            let r = half_diag + rng.random_range(250.0..700.0);
            let z = c.z + rng.random_range(-0.8..0.8) * sz;
            V3::new(c.x + r * phi.cos(), c.y + r * phi.sin(), z)
        })
        .collect()
}

/// The reflector's offsets from the tool tip (tool frame, mm): the tip itself only, or for
/// `tracker-tools` 3–4 offsets — across in X, across in Y and (with four) further down the
/// tool, each 80–200 mm with a few mm to the sides, to 0.1 mm as a calibrated holder states them.
fn draw_tool_offsets(rng: &mut impl Rng, kind: Kind) -> Vec<V3> {
    let mut offsets = vec![V3::zeros()];
    if kind != Kind::TrackerTools {
        return offsets;
    }
    let round = |v: f64| (v * 10.0).round() / 10.0;
    let n = rng.random_range(3..=4);
    for k in [0, 1, 2].into_iter().take(n - 1) {
        let mut o = V3::from_fn(|_, _| round(rng.random_range(-10.0..=10.0)));
        let reach = round(rng.random_range(80.0..=200.0));
        o[k] = match k {
            2 => -reach,
            _ if rng.random_bool(0.5) => reach,
            _ => -reach,
        };
        offsets.push(o);
    }
    offsets
}

/// Targets: a random grid or uniform random points in the box of the strokes (`count` of them
/// when given).
fn draw_targets(
    rng: &mut impl Rng,
    strokes: [(f64, f64); 3],
    count: Option<usize>,
) -> Vec<[f64; 3]> {
    let lerp = |(lo, hi): (f64, f64), u: f64| lo + (hi - lo) * u;
    let round = |v: f64| (v * 1000.0).round() / 1000.0;
    if count.is_none() && rng.random_bool(0.5) {
        let (nx, ny, nz) = (
            rng.random_range(5..=7),
            rng.random_range(4..=5),
            rng.random_range(3..=4),
        );
        let mut v = Vec::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    v.push([
                        round(lerp(strokes[0], i as f64 / (nx - 1) as f64)),
                        round(lerp(strokes[1], j as f64 / (ny - 1) as f64)),
                        round(lerp(strokes[2], k as f64 / (nz - 1) as f64)),
                    ]);
                }
            }
        }
        v
    } else {
        let n = count.unwrap_or_else(|| rng.random_range(60..=150));
        (0..n)
            .map(|_| {
                [
                    round(lerp(strokes[0], rng.random_range(0.0..=1.0))),
                    round(lerp(strokes[1], rng.random_range(0.0..=1.0))),
                    round(lerp(strokes[2], rng.random_range(0.0..=1.0))),
                ]
            })
            .collect()
    }
}

pub(crate) fn write(spec: &Spec, rng: &mut ChaCha8Rng, dir: &Path) -> std::io::Result<Truth> {
    let strokes = [
        (0.0, rng.random_range(400.0..=1000.0_f64).round()),
        (-rng.random_range(300.0..=600.0_f64).round(), 0.0),
        (-rng.random_range(300.0..=700.0_f64).round(), 0.0),
    ];
    let mut m = TrackerMachine::perfect(
        strokes,
        rng.random_range(50.0..=150.0_f64).round(),
        rng.random_range(20.0..=80.0_f64).round(),
        rng.random_range(100.0..=250.0_f64).round(),
    );
    let s = spec.ordinary_scale;
    for (k, (lo, hi)) in strokes.iter().enumerate() {
        m.components[k] = LinearErrors::draw(rng, k, (*lo, *hi), REALISTIC, s, spec.waviness);
    }
    for k in 0..3 {
        m.squareness[k] = signed(rng, 5.0, 60.0) * 1e-6 * s;
    }
    let sigma = rng.random_range(0.2..=1.0) * spec.noise_scale;
    let mut effects = Vec::new();
    let mut length_scale = 0.0;
    for h in &spec.hidden {
        match *h {
            Hidden::Pitch {
                axis,
                amplitude_um,
                period_mm,
            }
            | Hidden::Sawtooth {
                axis,
                amplitude_um,
                period_mm,
            } if axis < 3 => {
                let saw = matches!(h, Hidden::Sawtooth { .. });
                m.waves[axis].push(Wave {
                    amplitude_mm: amplitude_um * 1e-3,
                    period_mm,
                    phase: rng.random_range(0.0..TAU),
                    sawtooth: saw,
                });
                let n = LINEAR[axis];
                effects.push(TrueEffect {
                    iso_name_hint: format!("E{n}{n}"),
                    kind: if saw {
                        EffectKind::OpenWorld
                    } else {
                        EffectKind::Periodic
                    },
                    size: amplitude_um,
                    unit: "um",
                    value: amplitude_um.abs() * 1e-3,
                    signed: false,
                    period: Some((LINEAR[axis].to_string(), period_mm)),
                    detail: format!(
                        "{} period {period_mm:.2} mm",
                        if saw { "sawtooth" } else { "sine" }
                    ),
                    drift: None,
                });
            }
            Hidden::Squareness { pair, urad } if pair < 3 => {
                m.squareness[pair] += urad * 1e-6;
                // (The total, set below.)
                effects.push(super::squareness_truth(pair, urad, 0.0));
            }
            Hidden::TrackerScale { ppm } => {
                length_scale += ppm * 1e-6;
                effects.push(TrueEffect {
                    iso_name_hint: "tracker scale".into(),
                    kind: EffectKind::InstrumentScale,
                    size: ppm,
                    unit: "ppm",
                    value: ppm * 1e-6,
                    signed: true,
                    period: None,
                    detail: String::new(),
                    drift: None,
                });
            }
            Hidden::TwoAxis { um } => {
                let (e, truth) = super::two_axis(rng, um, strokes[0]);
                m.two_axis = Some(e);
                effects.push(truth);
            }
            _ => return Err(unsupported(spec.kind, h)),
        }
    }
    let stations = draw_stations(rng, strokes);
    let dead: Vec<f64> = stations
        .iter()
        .map(|_| rng.random_range(80.0..=150.0))
        .collect();
    let targets = draw_targets(rng, strokes, spec.targets);
    let offsets = draw_tool_offsets(rng, spec.kind);
    // The squareness between the reference lines through the measured positions.
    let positions: Vec<Vec<f64>> = (0..3)
        .map(|k| {
            let mut v: Vec<f64> = targets.iter().map(|q| q[k]).collect();
            v.sort_by(f64::total_cmp);
            v.dedup();
            v
        })
        .collect();
    let squareness = m.squareness_at([&positions[0], &positions[1], &positions[2]]);
    for e in &mut effects {
        if e.kind == EffectKind::Squareness {
            let k = SQUARENESS
                .iter()
                .position(|n| *n == e.iso_name_hint)
                .unwrap_or(0);
            e.value = squareness[k].abs();
        }
    }
    let ordinary = (0..3)
        .map(|k| TrueEffect {
            iso_name_hint: SQUARENESS[k].into(),
            kind: EffectKind::Squareness,
            size: squareness[k] * 1e6,
            unit: "urad",
            value: squareness[k],
            signed: false,
            period: None,
            detail: "ordinary + hidden, between the axes' reference lines".into(),
            drift: None,
        })
        .collect();

    // The noise's stream, from here on ([`Spec::noise_seed`]).
    let mut own = spec.noise_rng();
    let rng = own.as_mut().unwrap_or(rng);
    let noise = Normal::new(0.0, (sigma * 1e-3).max(1e-300)).expect("finite σ");
    let mut targets_csv = String::from(if offsets.len() > 1 {
        "id,x_mm,y_mm,z_mm,tool_x_mm,tool_y_mm,tool_z_mm\n"
    } else {
        "id,x_mm,y_mm,z_mm\n"
    });
    let mut lengths = String::from("station,target,length_mm\n");
    let mut n_obs = 0;
    for (i, q) in targets.iter().enumerate() {
        for (k, o) in offsets.iter().enumerate() {
            let id = if offsets.len() > 1 {
                format!("P{}T{}", i + 1, k + 1)
            } else {
                format!("P{}", i + 1)
            };
            let _ = write!(targets_csv, "{id},{},{},{}", q[0], q[1], q[2]);
            if offsets.len() > 1 {
                let _ = write!(targets_csv, ",{},{},{}", o.x, o.y, o.z);
            }
            targets_csv.push('\n');
            let p = m.reflector(*q, *o);
            for (j, st) in stations.iter().enumerate() {
                let mut l = (1.0 + length_scale) * (st - p).norm() - dead[j];
                if sigma > 0.0 {
                    l += noise.sample(rng);
                }
                let _ = writeln!(lengths, "S{},{id},{l:.7}", j + 1);
                n_obs += 1;
            }
        }
    }
    std::fs::write(dir.join("targets.csv"), targets_csv)?;
    std::fs::write(dir.join("lengths.csv"), lengths)?;
    std::fs::write(
        dir.join("machine.json"),
        serde_json::to_string_pretty(&m.machine_json())?,
    )?;
    // Approximate station positions, as a user reads them off a sketch (within ±5 mm).
    let setups: Vec<serde_json::Value> = stations
        .iter()
        .enumerate()
        .map(|(j, st)| {
            let mut a = [0.0; 3];
            for (k, v) in a.iter_mut().enumerate() {
                *v = ((st[k] + rng.random_range(-5.0..5.0)) * 10.0).round() / 10.0;
            }
            serde_json::json!({"id": format!("S{}", j + 1), "station_mm": a})
        })
        .collect();
    let manifest = serde_json::json!({
        "format": "mte-dataset/1",
        "kind": "tracker",
        "description": "Laser-tracker multilateration of a three-axis machine",
        "machine": "machine.json",
        "noise_um": stated_noise(sigma.max(0.05)),
        "data": "lengths.csv",
        "targets": "targets.csv",
        "setups": setups,
    });
    let path = write_manifest(dir, manifest, &spec.base_model)?;
    Ok(Truth {
        kind: spec.kind,
        manifest: path,
        effects,
        ordinary,
        noise_um: sigma,
        stations: stations
            .iter()
            .zip(&dead)
            .map(|(s, d)| ([s.x, s.y, s.z], *d))
            .collect(),
        n_observations: n_obs,
    })
}
