//! Generators of realistic machines and their measurement datasets, for studying the
//! model-discrepancy diagnosis (`mte-diagnose`) from the outside.
//!
//! A real machine carries all its ordinary errors at once. Each generator draws, from a seed, a
//! machine with every ordinary error at a random realistic size, as a random smooth function of
//! its axis coordinate ([`smooth`]), adds the [`Hidden`] effects asked for, simulates the
//! measurement with its own homogeneous transforms (written out per machine type here, sharing
//! no code with `mte-kinematics`, `mte-rtest` or `mte-diagnose`) and writes the files the
//! diagnosis reads. The truth is returned in memory only ([`Truth`]): nothing about the hidden
//! effects reaches the files (manifest text, file names and directory names are the same for
//! every dataset of a kind).
//!
//! ```no_run
//! use xtask::realistic::{Hidden, Kind, write};
//! let dir = std::env::temp_dir().join("ds0");
//! let truth = write(Kind::Axis, &[Hidden::Pitch { axis: 0, amplitude_um: 1.5, period_mm: 20.0 }], 7, &dir)?;
//! println!("{:?}", truth.effects);
//! # Ok::<(), std::io::Error>(())
//! ```

pub mod axis;
pub mod geom;
pub mod points;
pub mod rotary;
pub mod rtest;
pub mod smooth;
pub mod tracker;

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The kind of dataset (instrument and machine type).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Kind {
    /// Bidirectional ISO 230-2 runs of the X axis with a laser interferometer (`mte-dataset/1`,
    /// `"kind": "axis"`).
    Axis,
    /// Laser-tracker multilateration of a three-axis machine (`mte-dataset/1`,
    /// `"kind": "tracker"`), machine file written beside the manifest.
    Tracker,
    /// [`Kind::Tracker`] with every pose measured with the reflector at 3–4 offsets from the
    /// tool tip, stated in the targets table (a volumetric calibration's tool offsets).
    TrackerTools,
    /// ISO 10791-6 R-test of a B/C trunnion (table–table) five-axis machine (`mte-rtest/1`).
    Rtest,
    /// ISO 10791-6 R-test of a head–table five-axis machine: B swivel head, C table
    /// (`mte-rtest/1`).
    RtestHead,
    /// ISO 10791-6 R-test of an A/C trunnion (table–table) five-axis machine: A tilts the
    /// cradle about X and carries the C table (`mte-rtest/1`).
    RtestAc,
    /// 3-D points of a target on the spindle of a C-table machine with X, Y, Z stages
    /// (`mte-dataset/1`, `"kind": "points"`).
    Points,
    /// [`Kind::Points`] with every position measured at 3–4 targets on a holder (across in X,
    /// across in Y, down the tool), their places stated per row, as a volumetric calibration
    /// with a tracker in 3-D mode measures.
    PointsTargets,
    /// Bidirectional ISO 230-2 runs of a rotary table C with an autocollimator and a polygon,
    /// deviations in arcsec (`mte-dataset/1`, `"kind": "axis"`, `"axis": "C"`).
    Rotary,
}

impl Kind {
    /// All kinds.
    pub const ALL: [Kind; 9] = [
        Kind::Axis,
        Kind::Tracker,
        Kind::TrackerTools,
        Kind::Rtest,
        Kind::RtestHead,
        Kind::RtestAc,
        Kind::Points,
        Kind::PointsTargets,
        Kind::Rotary,
    ];

    /// Lower-case name (`axis`, `tracker`, `tracker-tools`, `rtest`, `rtest-head`, `rtest-ac`, `points`,
    /// `points-targets`, `rotary`).
    pub fn name(self) -> &'static str {
        match self {
            Kind::Axis => "axis",
            Kind::Tracker => "tracker",
            Kind::TrackerTools => "tracker-tools",
            Kind::Rtest => "rtest",
            Kind::RtestHead => "rtest-head",
            Kind::RtestAc => "rtest-ac",
            Kind::Points => "points",
            Kind::PointsTargets => "points-targets",
            Kind::Rotary => "rotary",
        }
    }

    /// The kind named `name` ([`Kind::name`]).
    pub fn parse(name: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Every kind's name, `|`-separated (for usage lines).
    pub fn names() -> String {
        Kind::ALL.map(Kind::name).join("|")
    }
}

/// A hidden effect put on top of the ordinary errors. Linear axes are numbered 0 = X, 1 = Y,
/// 2 = Z; rotary axes 0 = B, 1 = C (R-test machine). Sizes are signed where a sign makes sense.
#[derive(Debug, Clone, PartialEq)]
pub enum Hidden {
    /// Periodic pitch error of a linear axis' positioning (ball screw): amplitude µm, period mm
    /// (axis, tracker).
    Pitch {
        /// Linear axis 0..3.
        axis: usize,
        /// Amplitude, µm.
        amplitude_um: f64,
        /// Period, mm.
        period_mm: f64,
    },
    /// Squareness between two linear axes beyond the ordinary one, µrad (tracker, rtest, points).
    /// `pair`: 0 = EC0Y (Y to X), 1 = EA0Z (Z to Y), 2 = EB0Z (Z to X).
    Squareness {
        /// Which squareness.
        pair: usize,
        /// Extra angle, µrad.
        urad: f64,
    },
    /// Reversal (backlash): the `-` runs sit `um` below the `+` runs (axis; of a rotary table,
    /// µrad).
    Reversal {
        /// Difference between the directions, µm (µrad for a rotary table).
        um: f64,
    },
    /// A reversal that grows along the axis, from none at its start to `um` at its end (a
    /// screw worn towards one end), on top of the ordinary reversal (axis).
    ReversalGrowing {
        /// Reversal at the end of the travel, µm.
        um: f64,
    },
    /// Scale error of every tracker length, ppm (tracker).
    TrackerScale {
        /// ppm.
        ppm: f64,
    },
    /// First-order thermal drift of a rotary axis line's X position over repeated cycles
    /// (EX0B for `rotary = 0`, EX0C for 1): `um · (1 − exp(−t/τ))` (rtest).
    PivotDrift {
        /// Rotary axis 0 = B, 1 = C.
        rotary: usize,
        /// Final drift, µm.
        um: f64,
        /// Time constant, s.
        tau_s: f64,
    },
    /// First-order thermal growth of the spindle, `um · (1 − exp(−t/τ))`: the tool point moves
    /// along x, y or z of the spindle's frame (`EX0[tool]`, `EY0[tool]`, `EZ0[tool]`) (rtest).
    SpindleDrift {
        /// Direction 0 = x, 1 = y, 2 = z.
        axis: usize,
        /// Final growth, µm.
        um: f64,
        /// Time constant, s.
        tau_s: f64,
    },
    /// First-order thermal expansion of the axis' screw or scale about its fixed bearing at
    /// `x₀`, `ppm · 10⁻⁶ · (x − x₀) · (1 − exp(−t/τ))` (axis).
    ScaleDrift {
        /// Final scale change, ppm.
        ppm: f64,
        /// Time constant, s.
        tau_s: f64,
        /// The fixed bearing's place as a fraction of the stroke from the axis' zero.
        fixed: f64,
    },
    /// Linear drift of the zero in time, µm/min (axis).
    ZeroDrift {
        /// Rate, µm/min.
        um_per_min: f64,
    },
    /// Angular positioning error of a rotary axis as a harmonic of a turn:
    /// `urad · sin(k·θ + φ)` (rtest; points, where `rotary` must be 1 = C).
    AngularPositioning {
        /// Rotary axis 0 = B, 1 = C.
        rotary: usize,
        /// Harmonic (cycles per turn).
        harmonic: u32,
        /// Amplitude, µrad.
        urad: f64,
    },
    /// Orientation of the B axis line about X (EA0B) beyond the ordinary one, µrad (rtest).
    BTilt {
        /// µrad.
        urad: f64,
    },
    /// Open world: sawtooth positioning error of a linear axis (a slipping scale, a stepped
    /// compensation table), amplitude µm (peak), period mm (axis, tracker).
    Sawtooth {
        /// Linear axis 0..3.
        axis: usize,
        /// Peak amplitude, µm.
        amplitude_um: f64,
        /// Period, mm.
        period_mm: f64,
    },
    /// Open world: a drift that rises and falls, `um · (t/τ)·exp(1 − t/τ)` (peak `um` at t = τ):
    /// the zero of the axis (axis) or EX0B (rtest).
    RiseFall {
        /// Peak, µm.
        um: f64,
        /// Time of the peak as a fraction of the measuring time (R-test: of its readings' time
        /// plus the mean pause between cycles, the pauses being drawn as the cycles are).
        peak: f64,
    },
    /// Open world: a Y positioning error growing linearly from mid-Y, at a rate that changes
    /// along X (a table warmed unevenly stretches Y more on one side): a smooth shape of x with
    /// peak `um` at the ends of Y (tracker, points). (An X straightness growing linearly with Z would
    /// not do: that is the roll of X through the Z lever arm, which the standard model has.)
    TwoAxis {
        /// Peak, µm.
        um: f64,
    },
}

impl Hidden {
    /// Whether no candidate of the diagnosis's library has this shape exactly.
    pub fn is_open_world(&self) -> bool {
        matches!(
            self,
            Hidden::Sawtooth { .. } | Hidden::RiseFall { .. } | Hidden::TwoAxis { .. }
        )
    }
}

/// What a true effect is, for matching a finding to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EffectKind {
    /// Periodic error along an axis.
    Periodic,
    /// Squareness between linear axes.
    Squareness,
    /// Reversal.
    Reversal,
    /// Instrument scale.
    InstrumentScale,
    /// Drift in time (linear or first order).
    Drift,
    /// Angular positioning error of a rotary axis.
    AngularPositioning,
    /// Location (position or orientation) error of a rotary axis line.
    Location,
    /// An effect no candidate has exactly.
    OpenWorld,
}

/// One true effect.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueEffect {
    /// The ISO-like name the diagnosis would give it (`EXX`, `EC0Y`, `EA0B`, `EX0B`, `ECC`,
    /// `reversal`, `tracker scale`, `X zero`, …).
    pub iso_name_hint: String,
    /// What it is.
    pub kind: EffectKind,
    /// Its size in `unit`.
    pub size: f64,
    /// `um`, `urad`, `ppm`, `um/min`.
    pub unit: &'static str,
    /// The value the diagnosis should estimate, in its internal units (mm, rad, ratio, mm/s):
    /// the total of the machine's parameter (ordinary + hidden) where the two add.
    pub value: f64,
    /// Whether the sign of `value` is defined the diagnosis's way; `false` (periodic amplitudes,
    /// squareness sign conventions) means compare magnitudes.
    pub signed: bool,
    /// Free text (period, time constant …).
    pub detail: String,
    /// For an effect that repeats along an axis: the axis and the period (mm, or rad for a
    /// rotary axis).
    pub period: Option<(String, f64)>,
    /// For a first-order drift: its course over the record.
    pub drift: Option<TrueDrift>,
}

/// The course of a first-order drift over the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueDrift {
    /// The change of its parameter from the first reading to the last, in the units of
    /// [`TrueEffect::value`] (what the data show of a first-order drift whatever form it is
    /// found in).
    pub record_change: f64,
    /// Its time constant, s.
    pub tau_s: f64,
}

/// What the generator put into a dataset (kept in memory, never written).
#[derive(Debug, Clone)]
pub struct Truth {
    /// The kind of dataset.
    pub kind: Kind,
    /// The manifest to load.
    pub manifest: PathBuf,
    /// The hidden effects.
    pub effects: Vec<TrueEffect>,
    /// The ordinary constant parameters (location and squareness errors), for reference.
    pub ordinary: Vec<TrueEffect>,
    /// Standard deviation of the noise, µm (of a rotary axis' angles, mrad: the readings' unit,
    /// mm or rad, × 1000).
    pub noise_um: f64,
    /// Tracker: true station positions (workpiece frame, mm) and dead paths (mm).
    pub stations: Vec<([f64; 3], f64)>,
    /// Number of observations written.
    pub n_observations: usize,
}

/// The base model written in the manifest.
#[derive(Debug, Clone, PartialEq)]
pub enum BaseModel {
    /// The user's model of a real machine, [`BaseModel::standard`], for every kind: every
    /// ordinary error (component errors, squareness, location errors) is in it.
    Default,
    /// Leave the field out.
    Omit,
    /// Write this JSON value as `"base_model"`.
    Given(serde_json::Value),
}

impl BaseModel {
    /// `{"components": {"degree": 3}, "squareness": true, "location": true}`.
    pub fn standard() -> serde_json::Value {
        serde_json::json!({"components": {"degree": 3}, "squareness": true, "location": true})
    }

    /// The value to write, if any.
    pub fn resolve(&self) -> Option<serde_json::Value> {
        match self {
            BaseModel::Default => Some(Self::standard()),
            BaseModel::Omit => None,
            BaseModel::Given(v) => Some(v.clone()),
        }
    }
}

/// Everything a generator is asked for.
#[derive(Debug, Clone)]
pub struct Spec {
    /// The kind of dataset.
    pub kind: Kind,
    /// Hidden effects on top of the ordinary errors.
    pub hidden: Vec<Hidden>,
    /// Axis kind: put an ordinary reversal (0.5–3 µm) into the data (not in the axis kind's base
    /// model, so clean-data studies leave it out).
    pub ordinary_reversal: bool,
    /// Base model written in the manifest.
    pub base_model: BaseModel,
    /// Multiplies every ordinary error (1 = realistic, 0 = a perfect machine).
    pub ordinary_scale: f64,
    /// How wavy the ordinary errors are ([`smooth::Waviness`]).
    pub waviness: smooth::Waviness,
    /// Multiplies the noise σ (1 = realistic, 0 = noise-free readings).
    pub noise_scale: f64,
    /// The readings' noise from its own stream of this seed instead of the dataset's: the same
    /// machine with another draw of the noise, which tells an estimate's bias (the same in
    /// every draw) from its scatter. What a generator draws after the noise starts comes from
    /// the noise's stream too: an R-test's pauses between cycles, a points dataset's set-up
    /// poses and angles of C, a tracker dataset's stated station guesses — parts of the
    /// programme, never of the machine.
    pub noise_seed: Option<u64>,
    /// R-test: number of measurement cycles (re-centred each cycle); `None` draws 1–3.
    pub cycles: Option<usize>,
    /// Axis: a continuous interferometer log instead of stop-and-go targets — `(runs, readings
    /// per direction)`, one reading every 20 ms while the axis creeps through its stroke.
    pub log: Option<(usize, usize)>,
    /// Tracker: this many uniformly random targets instead of a drawn grid or 60–150 random
    /// ones (each measured from every station: 4–6 lengths per target).
    pub targets: Option<usize>,
}

impl Spec {
    /// The noise's own stream where [`Spec::noise_seed`] asks for one.
    pub(crate) fn noise_rng(&self) -> Option<ChaCha8Rng> {
        self.noise_seed.map(ChaCha8Rng::seed_from_u64)
    }

    /// A realistic dataset of `kind` with `hidden` effects and the default base model.
    pub fn new(kind: Kind, hidden: &[Hidden]) -> Self {
        Self {
            kind,
            hidden: hidden.to_vec(),
            ordinary_reversal: false,
            base_model: BaseModel::Default,
            ordinary_scale: 1.0,
            waviness: smooth::Waviness::Gentle,
            noise_scale: 1.0,
            noise_seed: None,
            cycles: None,
            log: None,
            targets: None,
        }
    }
}

/// Writes a realistic dataset of `kind` with `hidden` effects into `dir` (created), drawn from
/// `seed`; returns the truth. Deterministic for a seed.
///
/// # Errors
/// File-system errors, and `InvalidInput` for a hidden effect the kind cannot carry.
pub fn write(kind: Kind, hidden: &[Hidden], seed: u64, dir: &Path) -> std::io::Result<Truth> {
    write_spec(&Spec::new(kind, hidden), seed, dir)
}

/// Writes `manifest.json` in `dir`, with the base model's `base_model` field if it has one.
fn write_manifest(
    dir: &Path,
    mut manifest: serde_json::Value,
    base_model: &BaseModel,
) -> std::io::Result<std::path::PathBuf> {
    if let Some(b) = base_model.resolve() {
        manifest["base_model"] = b;
    }
    let path = dir.join("manifest.json");
    std::fs::write(&path, serde_json::to_string_pretty(&manifest)?)?;
    Ok(path)
}

/// [`write()`] with every option.
///
/// # Errors
/// As [`write()`].
pub fn write_spec(spec: &Spec, seed: u64, dir: &Path) -> std::io::Result<Truth> {
    std::fs::create_dir_all(dir)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    match spec.kind {
        Kind::Axis => axis::write(spec, &mut rng, dir),
        Kind::Tracker | Kind::TrackerTools => tracker::write(spec, &mut rng, dir),
        Kind::Rtest | Kind::RtestHead | Kind::RtestAc => rtest::write(spec, &mut rng, dir),
        Kind::Points | Kind::PointsTargets => points::write(spec, &mut rng, dir),
        Kind::Rotary => rotary::write(spec, &mut rng, dir),
    }
}

pub(crate) fn unsupported(kind: Kind, h: &Hidden) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!(
            "hidden effect {h:?} is not available for the {} kind",
            kind.name()
        ),
    )
}

/// ISO names of the squareness errors [`Hidden::Squareness`] numbers 0, 1, 2.
pub(crate) const SQUARENESS: [&str; 3] = ["EC0Y", "EA0Z", "EB0Z"];

/// The truth of a hidden squareness `pair` of `urad` µrad whose machine's total (ordinary +
/// hidden) is `total_rad`.
pub(crate) fn squareness_truth(pair: usize, urad: f64, total_rad: f64) -> TrueEffect {
    TrueEffect {
        iso_name_hint: SQUARENESS[pair].into(),
        kind: EffectKind::Squareness,
        size: urad,
        unit: "urad",
        value: total_rad.abs(),
        signed: false,
        period: None,
        detail: String::new(),
        drift: None,
    }
}

/// A hidden angular positioning error of rotary axis `rotary` (0 = B, 1 = C) at `harmonic`
/// cycles per turn, `urad` µrad, on top of the axis' ordinary error motion about its own line
/// `ordinary`: the drawn `(amplitude rad, harmonic, phase)` of `amplitude · sin(k·θ + φ)` and
/// its truth, the amplitude of the machine's total at that harmonic.
pub(crate) fn angular_positioning(
    rng: &mut impl rand::Rng,
    ordinary: &smooth::Periodic,
    rotary: usize,
    harmonic: u32,
    urad: f64,
) -> ((f64, f64, f64), TrueEffect) {
    use std::f64::consts::TAU;
    let (k, phase) = (harmonic as f64, rng.random_range(0.0..TAU));
    let (a, b) = ordinary.component(k);
    let total = (a + urad * 1e-6 * phase.cos()).hypot(b + urad * 1e-6 * phase.sin());
    let truth = TrueEffect {
        iso_name_hint: ["EBB", "ECC"][rotary].into(),
        kind: EffectKind::AngularPositioning,
        size: urad,
        unit: "urad",
        value: total,
        signed: false,
        period: Some((["B", "C"][rotary].into(), TAU / k)),
        detail: format!("harmonic {harmonic} of a turn"),
        drift: None,
    };
    ((urad * 1e-6, k, phase), truth)
}

/// The open-world [`Hidden::TwoAxis`] effect drawn for X's stroke `x_stroke`: a Y positioning
/// error of `um` µm at the ends of Y whose size is a smooth shape of x ([`TwoAxis::at`]), and
/// its truth.
pub(crate) fn two_axis(
    rng: &mut impl rand::Rng,
    um: f64,
    x_stroke: (f64, f64),
) -> (TwoAxis, TrueEffect) {
    let effect = TwoAxis {
        peak_mm: um * 1e-3,
        shape: smooth::Smooth::draw(rng, x_stroke.0, x_stroke.1, 1.0, smooth::Waviness::Gentle),
    };
    let truth = TrueEffect {
        iso_name_hint: "EYY".into(),
        kind: EffectKind::OpenWorld,
        size: um,
        unit: "um",
        value: um.abs() * 1e-3,
        signed: false,
        period: None,
        detail: "Y positioning error changing along X".into(),
        drift: None,
    };
    (effect, truth)
}

/// A Y positioning error proportional to the distance from mid-Y whose size changes along X
/// (peak at the ends of Y, shape of x): no rigid-body error of the axes has it (a yaw of Y gives
/// x·f(y), a yaw of X moves the tip along X in proportion to Y).
#[derive(Debug, Clone)]
pub struct TwoAxis {
    peak_mm: f64,
    shape: smooth::Smooth,
}

impl TwoAxis {
    /// The Y error at (x, y), mm, for Y's stroke `y_stroke`.
    pub fn at(&self, x: f64, y: f64, y_stroke: (f64, f64)) -> f64 {
        let (lo, hi) = y_stroke;
        self.peak_mm * self.shape.at(x) * (2.0 * (y - lo) / (hi - lo) - 1.0)
    }
}

/// Sawtooth of period 1 in `u`, between −1 and 1.
pub(crate) fn sawtooth(u: f64) -> f64 {
    2.0 * (u - u.floor()) - 1.0
}

/// Linear axis names.
pub(crate) const LINEAR: [&str; 3] = ["X", "Y", "Z"];
