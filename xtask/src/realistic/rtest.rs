//! `rtest` datasets: ISO 10791-6 R-test of a B/C trunnion (table–table) five-axis machine;
//! `rtest-head`: a B swivel head over a C table; `rtest-ac`: an A/C trunnion.
//!
//! Machine type of `fixtures/machines/seed002-bc-trunnion.json` (tool side bed–Y–X–Z–tool,
//! table side bed–B–C–workpiece, B about Y through the machine origin, C about Z with the table
//! surface `h_c` below the B line, table rotary axes with sign −1), written beside the manifest
//! with the table height and tool length drawn per dataset. The workpiece frame in the bed is
//!
//! `T_B(b) = Trans(p_B)·R_B·E_B(b)·Rot_y(−b)·R_B⁻¹·Trans(−p_B)` (B line through
//! `p_B = (EX0B, 0, EZ0B)`, direction `R_B·ŷ`, `R_B = Rot_x(EA0B)·Rot_z(EC0B)`, error motion
//! `E_B` in the fixed frame), times
//! `T_C(c) = Trans(c₀ + δ_C)·R_C·E_C(c)·Rot_z(−c)·R_C⁻¹·Trans(−δ_C)` (C line through
//! `c₀ + δ_C`, `c₀ = (0, 0, −h_c)`, `δ_C = (EX0C, EY0C, 0)`, direction `R_C·ẑ`,
//! `R_C = Rot_x(EA0C)·Rot_y(EB0C)`); the tool tip in the bed is the linear-axis chain with the
//! carriages' error transforms. A reading is the ball centre (fixed in the workpiece where the
//! actual tool point was at the setup's centring) minus the nest centre (the tool point), in
//! machine coordinates, µm.
//!
//! The A/C trunnion is the B/C one turned a quarter turn about Z: its table side is
//! `Q·T_B(a)·T_C(c)·Q⁻¹` with `Q = Rot_z(−90°)` (B/C's x̂ is A/C's −ŷ, its ŷ A/C's x̂), so B about Y
//! becomes A about X (sign −1) and the B/C location errors become A/C ones: `EY0A = −EX0B`,
//! `EZ0A = EZ0B`, `EB0A = −EA0B`, `EC0A = EC0B`, `EX0C = EY0C'`, `EY0C = −EX0C'`,
//! `EA0C = EB0C'`, `EB0C = −EA0C'` (primes: the B/C frame's).

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::geom::{ComponentSizes, Iso, LinearErrors, V3, rot_x, rot_y, rot_z, trans};
use super::smooth::{Periodic, Waviness, signed};
use super::{
    EffectKind, Hidden, Kind, Spec, TrueDrift, TrueEffect, Truth, unsupported, write_manifest,
};

/// A function of time for a location error, mm.
#[derive(Debug, Clone, Copy)]
pub enum TimeFn {
    /// `a · (1 − exp(−t/τ))`.
    FirstOrder {
        /// Final value, mm.
        a: f64,
        /// Time constant, s.
        tau_s: f64,
    },
    /// `a · (t/τ) · exp(1 − t/τ)`: rises to `a` at `τ`, then falls.
    RiseFall {
        /// Peak, mm.
        a: f64,
        /// Time of the peak, s.
        tau_s: f64,
    },
}

impl TimeFn {
    /// Value at `t` (s).
    pub fn at(&self, t: f64) -> f64 {
        match *self {
            TimeFn::FirstOrder { a, tau_s } => a * (1.0 - (-t / tau_s).exp()),
            TimeFn::RiseFall { a, tau_s } => a * (t / tau_s) * (1.0 - t / tau_s).exp(),
        }
    }
}

/// Error motions of a rotary axis as periodic functions of its angle: translations (mm) and
/// rotations (rad) along / about the machine X, Y, Z axes, in the fixed frame. Along / about the
/// axis' own direction they are the axial error motion and the angular positioning error.
#[derive(Debug, Clone)]
pub struct RotaryErrors {
    /// Translations, mm.
    pub d: [Periodic; 3],
    /// Rotations, rad.
    pub e: [Periodic; 3],
    /// Extra angular positioning: `(amplitude rad, harmonic, phase)`.
    pub harmonic: Option<(f64, f64, f64)>,
}

impl RotaryErrors {
    /// None.
    pub fn zero() -> Self {
        Self {
            d: [Periodic::zero(), Periodic::zero(), Periodic::zero()],
            e: [Periodic::zero(), Periodic::zero(), Periodic::zero()],
            harmonic: None,
        }
    }

    fn draw(rng: &mut impl Rng, scale: f64, waviness: Waviness) -> Self {
        let mut r = Self::zero();
        for k in 0..3 {
            let size = rng.random_range(1.0..=5.0) * 1e-3 * scale;
            r.d[k] = Periodic::draw(rng, size, waviness);
            let size = rng.random_range(2.0..=20.0) * 1e-6 * scale;
            r.e[k] = Periodic::draw(rng, size, waviness);
        }
        r
    }

    /// Error transform at angle `theta` (rad), about axis direction `axis_dir`.
    pub fn at(&self, theta: f64, axis_dir: usize) -> Iso {
        let d = V3::new(
            self.d[0].at(theta),
            self.d[1].at(theta),
            self.d[2].at(theta),
        );
        let mut e = V3::new(
            self.e[0].at(theta),
            self.e[1].at(theta),
            self.e[2].at(theta),
        );
        if let Some((a, k, ph)) = self.harmonic {
            e[axis_dir] += a * (k * theta + ph).sin();
        }
        trans(d) * super::geom::rot(e)
    }
}

/// The eight location errors (mm, rad).
#[derive(Debug, Clone, Copy, Default)]
pub struct Location {
    /// X position of the B line, mm.
    pub ex0b: f64,
    /// Z position of the B line, mm.
    pub ez0b: f64,
    /// Orientation of the B line about X, rad.
    pub ea0b: f64,
    /// Orientation of the B line about Z, rad.
    pub ec0b: f64,
    /// X position of the C line, mm.
    pub ex0c: f64,
    /// Y position of the C line, mm.
    pub ey0c: f64,
    /// Orientation of the C line about X, rad.
    pub ea0c: f64,
    /// Orientation of the C line about Y, rad.
    pub eb0c: f64,
}

/// A B/C five-axis machine with its true errors: a trunnion (B tilts the table), or with
/// `head_pivot_mm` a B swivel head on the tool side and the C table on the bed.
#[derive(Debug, Clone)]
pub struct BcMachine {
    /// Table surface (C reference point) below the B line (on the head machine: below the
    /// machine origin), mm.
    pub h_c_mm: f64,
    /// B swivel head: the B line lies this far above the tool point (pivot length), mm; the
    /// location errors EX0B, EZ0B place the line against the tool, EA0B, EC0B tilt it.
    pub head_pivot_mm: Option<f64>,
    /// An A/C trunnion: the table side turned a quarter turn about Z (module doc).
    pub ac: bool,
    /// Tool length, mm.
    pub tool_mm: f64,
    /// Location errors.
    pub location: Location,
    /// Time-dependent parts of EX0B (rotary 0) and EX0C (rotary 1).
    pub drift: Vec<(usize, TimeFn)>,
    /// Thermal growth of the spindle: the tool point's offset along x, y, z (0, 1, 2) of the
    /// spindle's own frame (turned by the head's B), a function of time.
    pub spindle: Vec<(usize, TimeFn)>,
    /// Error motions of B and C.
    pub rotary: [RotaryErrors; 2],
    /// Component errors of X, Y, Z.
    pub linear: [LinearErrors; 3],
    /// Squareness EC0Y, EA0Z, EB0Z, rad (as in the tracker machine).
    pub squareness: [f64; 3],
    /// Strokes of X, Y, Z, mm.
    pub strokes: [(f64, f64); 3],
}

impl BcMachine {
    /// A machine without errors.
    pub fn perfect(h_c_mm: f64, tool_mm: f64) -> Self {
        Self {
            h_c_mm,
            head_pivot_mm: None,
            ac: false,
            tool_mm,
            location: Location::default(),
            drift: Vec::new(),
            spindle: Vec::new(),
            rotary: [RotaryErrors::zero(), RotaryErrors::zero()],
            linear: [
                LinearErrors::zero(),
                LinearErrors::zero(),
                LinearErrors::zero(),
            ],
            squareness: [0.0; 3],
            strokes: [(-325.0, 325.0), (-260.0, 260.0), (-300.0, 250.0)],
        }
    }

    fn drift_of(&self, rotary: usize, t: f64) -> f64 {
        self.drift
            .iter()
            .filter(|(r, _)| *r == rotary)
            .map(|(_, f)| f.at(t))
            .sum()
    }

    /// The B motion about its actual line through `p_b` (mm; sign ±1 of the joint): the
    /// error motion in the fixed frame.
    fn b_motion(&self, b: f64, p_b: V3, sign: f64) -> Iso {
        let l = &self.location;
        let r_b = rot_x(l.ea0b) * rot_z(l.ec0b);
        trans(p_b) * r_b * self.rotary[0].at(b, 1) * rot_y(sign * b) * r_b.inverse() * trans(-p_b)
    }

    /// Workpiece frame in the bed at commanded B, C (rad) and time `t` (s).
    pub fn workpiece_in_bed(&self, b: f64, c: f64, t: f64) -> Iso {
        let l = &self.location;
        let t_b = if self.head_pivot_mm.is_some() {
            Iso::identity()
        } else {
            self.b_motion(b, V3::new(l.ex0b + self.drift_of(0, t), 0.0, l.ez0b), -1.0)
        };
        let c0 = V3::new(0.0, 0.0, -self.h_c_mm);
        let d_c = V3::new(l.ex0c + self.drift_of(1, t), l.ey0c, 0.0);
        let r_c = rot_x(l.ea0c) * rot_y(l.eb0c);
        let t_c = trans(c0 + d_c)
            * r_c
            * self.rotary[1].at(c, 2)
            * rot_z(-c)
            * r_c.inverse()
            * trans(-d_c);
        let q = self.quarter_turn();
        q * t_b * t_c * q.inverse()
    }

    /// The name of the axis that tilts the table or the head: `A` or `B`.
    pub fn tilt_axis(&self) -> &'static str {
        if self.ac { "A" } else { "B" }
    }

    /// `Q` of the A/C trunnion (module doc), the identity otherwise.
    fn quarter_turn(&self) -> Iso {
        if self.ac {
            rot_z(-std::f64::consts::FRAC_PI_2)
        } else {
            Iso::identity()
        }
    }

    /// Tool point (nest centre) in the bed at commanded linear axes (mm), B (rad, the head's)
    /// and time `t` (s). The Z carriage's frame sits `tool_mm` (the head: the pivot length)
    /// above the tool point.
    pub fn tool_in_bed(&self, x: f64, y: f64, z: f64, b: f64, t: f64) -> V3 {
        let u_y = rot_z(self.squareness[0]) * V3::y();
        let u_z = rot_x(self.squareness[1]) * rot_y(self.squareness[2]) * V3::z();
        let arm = self.head_pivot_mm.unwrap_or(self.tool_mm);
        let carriage = trans(y * u_y)
            * self.linear[1].at(y)
            * trans(x * V3::x())
            * self.linear[0].at(x)
            * trans(V3::new(0.0, 0.0, arm))
            * trans(z * u_z)
            * self.linear[2].at(z);
        let head = match self.head_pivot_mm {
            Some(_) => {
                let l = &self.location;
                self.b_motion(b, V3::new(l.ex0b + self.drift_of(0, t), 0.0, l.ez0b), 1.0)
            }
            None => Iso::identity(),
        };
        let mut growth = V3::zeros();
        for (k, f) in &self.spindle {
            growth[*k] += f.at(t);
        }
        (carriage * head * trans(V3::new(0.0, 0.0, -arm) + growth))
            .translation
            .vector
    }

    /// Commanded linear axes putting the nominal tool point on the nominal ball (table
    /// coordinates, mm) at B, C (rad).
    pub fn command(&self, ball: V3, b: f64, c: f64) -> [f64; 3] {
        match self.head_pivot_mm {
            Some(arm) => {
                let p = (trans(V3::new(0.0, 0.0, -self.h_c_mm)) * rot_z(-c))
                    .transform_point(&ball.into());
                // The tool point swings about the pivot `arm` above it.
                [p.x + arm * b.sin(), p.y, p.z - arm * (1.0 - b.cos())]
            }
            None => {
                let q = self.quarter_turn();
                let p = (q
                    * rot_y(-b)
                    * trans(V3::new(0.0, 0.0, -self.h_c_mm))
                    * rot_z(-c)
                    * q.inverse())
                .transform_point(&ball.into());
                [p.x, p.y, p.z]
            }
        }
    }

    /// The actual ball centre in table coordinates after centring at B = 0, C = `c_ref` (rad),
    /// time `t` (s).
    pub fn centre_ball(&self, ball: V3, c_ref: f64, t: f64) -> V3 {
        let q = self.command(ball, 0.0, c_ref);
        let tool = self.tool_in_bed(q[0], q[1], q[2], 0.0, t);
        self.workpiece_in_bed(0.0, c_ref, t)
            .inverse_transform_point(&tool.into())
            .coords
    }

    /// The reading (ball minus nest, machine coordinates, µm) with the ball at `ball_actual`
    /// (table coordinates) and the nominal ball `ball` commanded, at B, C (rad), time `t`.
    pub fn reading(&self, ball: V3, ball_actual: V3, b: f64, c: f64, t: f64) -> V3 {
        let q = self.command(ball, b, c);
        let wp = self
            .workpiece_in_bed(b, c, t)
            .transform_point(&ball_actual.into());
        (wp.coords - self.tool_in_bed(q[0], q[1], q[2], b, t)) * 1e3
    }

    /// The `mte-machine/1` description of the nominal machine.
    pub fn machine_json(&self) -> serde_json::Value {
        let [sx, sy, sz] = self.strokes;
        let arm = self.head_pivot_mm.unwrap_or(self.tool_mm);
        let mut bodies = vec![
            serde_json::json!({"name": "bed"}),
            serde_json::json!({"name": "Y", "parent": "bed", "offset_mm": [0, 0, 0],
             "joint": {"type": "linear", "axis": "Y", "direction": [0, 1, 0], "sign": 1, "stroke_mm": [sy.0, sy.1]}}),
            serde_json::json!({"name": "X", "parent": "Y", "offset_mm": [0, 0, 0],
             "joint": {"type": "linear", "axis": "X", "direction": [1, 0, 0], "sign": 1, "stroke_mm": [sx.0, sx.1]}}),
            serde_json::json!({"name": "Z", "parent": "X", "offset_mm": [0.0, 0.0, arm],
             "joint": {"type": "linear", "axis": "Z", "direction": [0, 0, 1], "sign": 1, "stroke_mm": [sz.0, sz.1]}}),
        ];
        let (name, description) = if self.head_pivot_mm.is_some() {
            bodies.extend([
                serde_json::json!({"name": "B", "parent": "Z", "offset_mm": [0, 0, 0],
                 "joint": {"type": "rotary", "axis": "B", "direction": [0, 1, 0], "sign": 1, "stroke_deg": [-120, 120]}}),
                serde_json::json!({"name": "tool", "parent": "B", "offset_mm": [0.0, 0.0, -arm]}),
                serde_json::json!({"name": "C", "parent": "bed", "offset_mm": [0.0, 0.0, -self.h_c_mm],
                 "joint": {"type": "rotary", "axis": "C", "direction": [0, 0, 1], "sign": -1, "stroke_deg": [0, 360]}}),
            ]);
            (
                "b-head-c-table",
                "Five-axis machine with a B swivel head and a C table: X, Y, Z on the tool side (bed-Y-X-Z-B-tool), the B head tilts the tool about Y through the pivot above the tool point; C turns the table on the bed (sign -1).",
            )
        } else {
            let (tilt, direction) = if self.ac {
                ("A", [1, 0, 0])
            } else {
                ("B", [0, 1, 0])
            };
            bodies.extend([
                serde_json::json!({"name": "tool", "parent": "Z", "offset_mm": [0.0, 0.0, -arm]}),
                serde_json::json!({"name": tilt, "parent": "bed", "offset_mm": [0, 0, 0],
                 "joint": {"type": "rotary", "axis": tilt, "direction": direction, "sign": -1, "stroke_deg": [-120, 120]}}),
                serde_json::json!({"name": "C", "parent": tilt, "offset_mm": [0.0, 0.0, -self.h_c_mm],
                 "joint": {"type": "rotary", "axis": "C", "direction": [0, 0, 1], "sign": -1, "stroke_deg": [0, 360]}}),
            ]);
            if self.ac {
                (
                    "ac-trunnion",
                    "A/C trunnion five-axis machine: X, Y, Z on the tool side (bed-Y-X-Z-tool), A tilts the cradle about X through the machine origin and carries the C table; table rotary axes with sign -1.",
                )
            } else {
                (
                    "bc-trunnion",
                    "B/C trunnion five-axis machine: X, Y, Z on the tool side (bed-Y-X-Z-tool), B tilts the cradle about Y through the machine origin and carries the C table; table rotary axes with sign -1.",
                )
            }
        };
        bodies
            .push(serde_json::json!({"name": "workpiece", "parent": "C", "offset_mm": [0, 0, 0]}));
        serde_json::json!({
            "format": "mte-machine/1",
            "name": name,
            "description": description,
            "tool": "tool",
            "workpiece": "workpiece",
            "axis_order": ["X", "Y", "Z", self.tilt_axis(), "C"],
            "bodies": bodies,
        })
    }
}

/// A true effect of the B/C trunnion's frame named and signed in the A/C trunnion's (module
/// doc): its table side turned a quarter turn about Z. Names of the tool side stay.
fn turned_a_quarter(mut e: TrueEffect) -> TrueEffect {
    let (name, sign) = match e.iso_name_hint.as_str() {
        "EX0B" => ("EY0A", -1.0),
        "EZ0B" => ("EZ0A", 1.0),
        "EA0B" => ("EB0A", -1.0),
        "EC0B" => ("EC0A", 1.0),
        "EBB" => ("EAA", 1.0),
        "EX0C" => ("EY0C", -1.0),
        "EY0C" => ("EX0C", 1.0),
        "EA0C" => ("EB0C", -1.0),
        "EB0C" => ("EA0C", 1.0),
        _ => return e,
    };
    e.iso_name_hint = name.into();
    e.size *= sign;
    e.value *= sign;
    e
}

/// Small component errors of the linear axes of the five-axis machine (R-test sees them only
/// through the short moves that follow the ball).
const SMALL: ComponentSizes = ComponentSizes {
    positioning_um: (1.0, 5.0),
    straightness_um: (0.5, 3.0),
    angular_urad: (1.0, 8.0),
};

/// A first-order drift `um · (1 − exp(−t/τ))` (µm, s) of entry `k` of `drifts`, and its truth
/// (`hint`: the parameter's ISO name).
fn first_order(
    drifts: &mut Vec<(usize, TimeFn)>,
    k: usize,
    hint: String,
    (um, tau_s): (f64, f64),
    what: &str,
) -> TrueEffect {
    drifts.push((
        k,
        TimeFn::FirstOrder {
            a: um * 1e-3,
            tau_s,
        },
    ));
    TrueEffect {
        iso_name_hint: hint,
        kind: EffectKind::Drift,
        size: um,
        unit: "um",
        value: um * 1e-3,
        signed: true,
        period: None,
        detail: format!("{what}, τ = {tau_s:.0} s"),
        drift: None,
    }
}

pub(crate) fn write(spec: &Spec, rng: &mut ChaCha8Rng, dir: &Path) -> std::io::Result<Truth> {
    let s = spec.ordinary_scale;
    let mut m = BcMachine::perfect(
        rng.random_range(80.0..=120.0_f64).round(),
        rng.random_range(100.0..=200.0_f64).round(),
    );
    m.ac = spec.kind == Kind::RtestAc;
    if spec.kind == Kind::RtestHead {
        m.head_pivot_mm = Some(rng.random_range(150.0..=350.0_f64).round());
        // The table surface below the machine origin, which lies at the tool point with Z at 0.
        m.h_c_mm = rng.random_range(150.0..=300.0_f64).round();
        m.strokes = [(-600.0, 600.0), (-300.0, 300.0), (-800.0, 300.0)];
    }
    let pos = |rng: &mut ChaCha8Rng| signed(rng, 5.0, 40.0) * 1e-3 * s;
    let ori = |rng: &mut ChaCha8Rng| signed(rng, 10.0, 100.0) * 1e-6 * s;
    m.location = Location {
        ex0b: pos(rng),
        ez0b: pos(rng),
        ea0b: ori(rng),
        ec0b: ori(rng),
        ex0c: pos(rng),
        ey0c: pos(rng),
        ea0c: ori(rng),
        eb0c: ori(rng),
    };
    m.rotary = [
        RotaryErrors::draw(rng, s, spec.waviness),
        RotaryErrors::draw(rng, s, spec.waviness),
    ];
    for k in 0..3 {
        let (lo, hi) = m.strokes[k];
        m.linear[k] = LinearErrors::draw(rng, k, (lo, hi), SMALL, s, spec.waviness);
    }
    for k in 0..3 {
        m.squareness[k] = signed(rng, 5.0, 60.0) * 1e-6 * s;
    }
    let sigma = rng.random_range(0.2..=0.8) * spec.noise_scale;
    let mut effects = Vec::new();
    let mut min_cycles = 1;
    let mut rise_fall: Option<(f64, f64)> = None; // (peak mm, fraction of the measuring time)
    for h in &spec.hidden {
        match *h {
            Hidden::PivotDrift { rotary, um, tau_s } if rotary < 2 => {
                min_cycles = min_cycles.max(4);
                effects.push(first_order(
                    &mut m.drift,
                    rotary,
                    ["EX0B", "EX0C"][rotary].into(),
                    (um, tau_s),
                    "first order",
                ));
            }
            Hidden::SpindleDrift { axis, um, tau_s } if axis < 3 => {
                min_cycles = min_cycles.max(4);
                effects.push(first_order(
                    &mut m.spindle,
                    axis,
                    format!("E{}0[tool]", ["X", "Y", "Z"][axis]),
                    (um, tau_s),
                    "spindle growth, first order",
                ));
            }
            Hidden::RiseFall { um, peak } => {
                // Its time constant once the programme's length is known (below).
                rise_fall = Some((um * 1e-3, peak));
                min_cycles = min_cycles.max(4);
                effects.push(TrueEffect {
                    iso_name_hint: "EX0B".into(),
                    kind: EffectKind::OpenWorld,
                    size: um,
                    unit: "um",
                    value: um * 1e-3,
                    signed: true,
                    period: None,
                    detail: format!(
                        "rise and fall, peak at {:.0} % of the measuring time",
                        100.0 * peak
                    ),
                    drift: None,
                });
            }
            Hidden::AngularPositioning {
                rotary,
                harmonic,
                urad,
            } if rotary < 2 => {
                // On top of the ordinary error motion about the axis' own line (B: about Y, C:
                // about Z).
                let (drawn, truth) = super::angular_positioning(
                    rng,
                    &m.rotary[rotary].e[rotary + 1],
                    rotary,
                    harmonic,
                    urad,
                );
                m.rotary[rotary].harmonic = Some(drawn);
                effects.push(truth);
            }
            Hidden::BTilt { urad } => {
                m.location.ea0b += urad * 1e-6;
                effects.push(TrueEffect {
                    iso_name_hint: "EA0B".into(),
                    kind: EffectKind::Location,
                    size: urad,
                    unit: "urad",
                    value: 0.0, // the total, set below
                    signed: true,
                    period: None,
                    detail: String::new(),
                    drift: None,
                });
            }
            Hidden::Squareness { pair, urad } if pair < 3 => {
                m.squareness[pair] += urad * 1e-6;
                effects.push(super::squareness_truth(pair, urad, m.squareness[pair]));
            }
            _ => return Err(unsupported(spec.kind, h)),
        }
    }
    for e in &mut effects {
        if e.iso_name_hint == "EA0B" && e.kind == EffectKind::Location {
            e.value = m.location.ea0b;
        }
    }
    let l = m.location;
    let ordinary = [
        ("EX0B", l.ex0b, "um", 1e3),
        ("EZ0B", l.ez0b, "um", 1e3),
        ("EA0B", l.ea0b, "urad", 1e6),
        ("EC0B", l.ec0b, "urad", 1e6),
        ("EX0C", l.ex0c, "um", 1e3),
        ("EY0C", l.ey0c, "um", 1e3),
        ("EA0C", l.ea0c, "urad", 1e6),
        ("EB0C", l.eb0c, "urad", 1e6),
    ]
    .into_iter()
    .map(|(n, v, unit, f)| TrueEffect {
        iso_name_hint: n.into(),
        kind: EffectKind::Location,
        size: v * f,
        unit,
        value: v,
        signed: true,
        period: None,
        detail: "ordinary (+ hidden)".into(),
        drift: None,
    })
    .collect::<Vec<_>>();
    // The A/C trunnion's names and signs (module doc).
    let (ordinary, mut effects) = if m.ac {
        (
            ordinary.into_iter().map(turned_a_quarter).collect(),
            effects.into_iter().map(turned_a_quarter).collect(),
        )
    } else {
        (ordinary, effects)
    };

    // Programme: setups (ball positions), BK1 and BK2 per setup, repeated cycles.
    let n_setups = rng.random_range(1..=3);
    let balls: Vec<(V3, f64)> = (0..n_setups)
        .map(|_| {
            let r = rng.random_range(100.0..=200.0_f64);
            let phi = rng.random_range(0.0..TAU);
            let h = rng.random_range(30.0..=150.0_f64);
            let round = |v: f64| (v * 1000.0).round() / 1000.0;
            let ball = V3::new(round(r * phi.cos()), round(r * phi.sin()), round(h));
            (ball, [0.0, 90.0, 180.0, 270.0][rng.random_range(0..4)])
        })
        .collect();
    let cycles = match spec.cycles {
        Some(n) => n.max(1),
        None if min_cycles > 1 => rng.random_range(min_cycles..=min_cycles + 2),
        None => rng.random_range(1..=3),
    };
    let b_max = rng.random_range(60.0..=110.0_f64).round();
    let b_step: f64 = [5.0, 7.5, 10.0][rng.random_range(0..3)];
    let c_step: f64 = [10.0, 15.0, 20.0][rng.random_range(0..3)];
    let dt = rng.random_range(3.0..=5.0_f64);
    if let Some((a, peak)) = rise_fall {
        // The readings' time (the programme below, per ball and cycle) and the mean pause
        // between cycles.
        let per_ball = (2.0 * b_max / b_step).round() + 1.0 + 2.0 * (360.0 / c_step).round() + 1.0;
        let duration = (cycles * balls.len()) as f64 * per_ball * dt + 300.0 * (cycles - 1) as f64;
        m.drift.push((
            0,
            TimeFn::RiseFall {
                a,
                tau_s: peak * duration,
            },
        ));
    }
    // The noise's stream, from here on ([`Spec::noise_seed`]).
    let mut own = spec.noise_rng();
    let rng = own.as_mut().unwrap_or(rng);
    let noise = Normal::new(0.0, sigma.max(1e-300)).expect("finite σ");
    let tilt = m.tilt_axis();
    let mut csv = format!(
        "setup,test,t_s,x_mm,y_mm,z_mm,{}_deg,c_deg,dx_um,dy_um,dz_um\n",
        tilt.to_lowercase()
    );
    let mut setups = Vec::new();
    let mut t = 0.0;
    let mut t_last = 0.0;
    let mut n_obs = 0;
    for cycle in 0..cycles {
        for (i, (ball, c_deg)) in balls.iter().enumerate() {
            let id = format!("S{}-{}", i + 1, cycle + 1);
            let c_ref = c_deg.to_radians();
            let ball_actual = m.centre_ball(*ball, c_ref, t);
            let q_ref = m.command(*ball, 0.0, c_ref);
            setups.push(serde_json::json!({
                "id": id,
                "ball_mm": [ball.x, ball.y, ball.z],
                "centring": {"X": q_ref[0], "Y": q_ref[1], "Z": q_ref[2], tilt: 0.0, "C": c_deg},
                "centring_t_s": t,
            }));
            let mut program: Vec<(&str, f64, f64)> = Vec::new();
            let nb = (2.0 * b_max / b_step).round() as usize;
            for k in 0..=nb {
                program.push(("BK1", -b_max + b_step * k as f64, *c_deg));
            }
            let nc = (360.0 / c_step).round() as usize;
            for k in 0..=nc {
                program.push(("BK2", 0.0, c_step * k as f64));
            }
            for k in (0..nc).rev() {
                program.push(("BK2", 0.0, c_step * k as f64));
            }
            for (test, b_deg, c_deg) in program {
                let (b, c) = (b_deg.to_radians(), c_deg.to_radians());
                let q = m.command(*ball, b, c);
                let mut r = m.reading(*ball, ball_actual, b, c, t);
                if sigma > 0.0 {
                    for k in 0..3 {
                        r[k] += noise.sample(rng);
                    }
                }
                let _ = writeln!(
                    csv,
                    "{id},{test},{t:.1},{:.4},{:.4},{:.4},{b_deg:.3},{c_deg:.3},{:.4},{:.4},{:.4}",
                    q[0], q[1], q[2], r.x, r.y, r.z
                );
                n_obs += 3;
                t_last = t;
                t += dt;
            }
        }
        t += rng.random_range(0.0..=600.0);
    }
    // The drifts' change from the first reading (t = 0) to the last.
    // (One true effect per hidden one, in order: any other is refused above.)
    for (e, h) in effects.iter_mut().zip(&spec.hidden) {
        if let Hidden::PivotDrift { tau_s, .. } | Hidden::SpindleDrift { tau_s, .. } = *h {
            // The truth's value carries the A/C trunnion's sign (the final drift, signed).
            e.drift = Some(TrueDrift {
                record_change: e.value * (1.0 - (-t_last / tau_s).exp()),
                tau_s,
            });
        }
    }
    std::fs::write(dir.join("rtest.csv"), csv)?;
    std::fs::write(
        dir.join("machine.json"),
        serde_json::to_string_pretty(&m.machine_json())?,
    )?;
    let manifest = serde_json::json!({
        "format": "mte-rtest/1",
        "machine": "machine.json",
        "instrument": "R-test (three displacement sensors)",
        "note": "simulated",
        "csv": "rtest.csv",
        "axes": ["X", "Y", "Z", tilt, "C"],
        "setups": setups,
    });
    let path = write_manifest(dir, manifest, &spec.base_model)?;
    Ok(Truth {
        kind: spec.kind,
        manifest: path,
        effects,
        ordinary,
        noise_um: sigma,
        stations: Vec::new(),
        n_observations: n_obs,
    })
}
