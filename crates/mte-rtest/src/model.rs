//! The R-test observation model: setups, readings, exact prediction and first-order sensitivity.
//!
//! # Measurement model
//! A precision ball is fixed on the table at `ball_mm` (workpiece-body coordinates); the sensor
//! nest sits in the spindle at `nest_mm` (tool-body coordinates). Each setup starts with a
//! *centring* at the commanded axes `centring_q` (time `centring_t_s`): the ball's actual
//! position on the table is taken to be where the actual nest centre is at that moment
//! (that is what centring the ball in the nest means). With slot errors `e` (exact transforms):
//!
//! ```text
//! b_act = G_e(q_ref) · (n + δn) + δb          (table coordinates; G = tool in workpiece)
//! d(q)  = W_e(q) · b_act − T_e(q) · (n + δn) + R_T(q) · s      (machine coordinates)
//! ```
//! `W`, `T` = workpiece / tool body in the machine (base) frame, `s` = sensor zero offset (nest
//! frame), `δn` = nest offset (tool frame), `δb` = residual centring offset of the ball (table
//! frame). `d` is the displacement of the ball relative to the nest, as the R-test reads it.
//! The prediction depends only on the *commanded* axes recorded with each reading, never on the
//! controller's model that produced them.
//!
//! First order at e = 0 (`J_n = J_p − [R_G n]× J_o`, the position Jacobian of the nest point):
//! `∂d/∂e(q) = −R_W(q) J_n(q)` for the slot values at the reading and `+R_W(q) J_n(q_ref)` for
//! the slot values at the centring; `∂d/∂s = R_T(q)`, `∂d/∂δn = R_W(q) R_G(q_ref) − R_T(q)`,
//! `∂d/∂δb = R_W(q)`.

use crate::error::{Result, RtestError};
use crate::kin;
use mte_kinematics::Machine;
use mte_linalg::{DMat, Mat3, Vec3, skew};
use serde::{Deserialize, Serialize};

/// One placement of the ball (and nest) on the machine, with its centring pose.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Setup {
    /// Identifier, unique in the dataset (e.g. "ball_y+177").
    pub id: String,
    /// Nominal ball centre in workpiece (table) coordinates, mm.
    pub ball_mm: Vec3,
    /// Nominal nest centre in tool coordinates, mm (usually 0: the tool point).
    pub nest_mm: Vec3,
    /// Commanded axes (machine axis order; mm, rad) at which the ball was centred in the nest.
    pub centring_q: Vec<f64>,
    /// Time of the centring, s.
    pub centring_t_s: f64,
}

/// One R-test reading.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reading {
    /// Index into [`Dataset::setups`].
    pub setup: usize,
    /// Name of the test this reading belongs to ("BK1", "BK2", "BK4", user names).
    pub test: String,
    /// Time stamp, s.
    pub t_s: f64,
    /// Commanded axes in machine axis order (mm, rad).
    pub q: Vec<f64>,
    /// Measured displacement of the ball relative to the nest, machine coordinates, mm.
    pub d_mm: Vec3,
}

/// A set of R-test readings on one machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dataset {
    /// Machine name (library name or file).
    pub machine: String,
    /// Axis names in the order of every `q`.
    pub axis_names: Vec<String>,
    /// Setups (ball placements).
    pub setups: Vec<Setup>,
    /// Readings.
    pub readings: Vec<Reading>,
    /// Free text: where the data come from (e.g. "simulated, σ = 0.5 µm").
    pub note: String,
}

impl Dataset {
    /// Checks the dataset against a machine: axis names and order, vector lengths, setup indices,
    /// finite values.
    ///
    /// # Errors
    /// [`RtestError::UnknownAxis`] or [`RtestError::Invalid`] naming the field.
    pub fn validate(&self, machine: &Machine) -> Result<()> {
        let names = kin::axis_names(machine);
        for n in &self.axis_names {
            if !names.contains(n) {
                return Err(kin::unknown_axis(machine, n, "not an axis of the machine"));
            }
        }
        if self.axis_names != names {
            return Err(RtestError::Invalid {
                field: "axis_names".into(),
                message: format!(
                    "found [{}], the machine's axis order is [{}]",
                    self.axis_names.join(", "),
                    names.join(", ")
                ),
            });
        }
        if self.setups.is_empty() {
            return Err(RtestError::TooShort {
                what: "setups".into(),
                found: 0,
                needed: 1,
                unit: "setups".into(),
            });
        }
        for (i, s) in self.setups.iter().enumerate() {
            if s.centring_q.len() != names.len() {
                return Err(RtestError::Invalid {
                    field: format!("setups[{i}].centring_q"),
                    message: format!("{} values, expected {}", s.centring_q.len(), names.len()),
                });
            }
            let finite = s
                .ball_mm
                .iter()
                .chain(s.nest_mm.iter())
                .chain(s.centring_q.iter())
                .all(|v| v.is_finite())
                && s.centring_t_s.is_finite();
            if !finite {
                return Err(RtestError::Invalid {
                    field: format!("setups[{i}]"),
                    message: "non-finite value".into(),
                });
            }
            if self.setups[..i].iter().any(|o| o.id == s.id) {
                return Err(RtestError::Invalid {
                    field: format!("setups[{i}].id"),
                    message: format!("duplicate setup id `{}`", s.id),
                });
            }
        }
        for (i, r) in self.readings.iter().enumerate() {
            if r.setup >= self.setups.len() {
                return Err(RtestError::Invalid {
                    field: format!("readings[{i}].setup"),
                    message: format!(
                        "setup index {} but only {} setups",
                        r.setup,
                        self.setups.len()
                    ),
                });
            }
            if r.q.len() != names.len() {
                return Err(RtestError::Invalid {
                    field: format!("readings[{i}].q"),
                    message: format!("{} values, expected {}", r.q.len(), names.len()),
                });
            }
            if !(r.q.iter().all(|v| v.is_finite())
                && r.d_mm.iter().all(|v| v.is_finite())
                && r.t_s.is_finite())
            {
                return Err(RtestError::Invalid {
                    field: format!("readings[{i}]"),
                    message: "non-finite value".into(),
                });
            }
        }
        Ok(())
    }

    /// Indices of the readings of one test name (and optionally one setup).
    pub fn select(&self, test: Option<&str>, setup: Option<usize>) -> Vec<usize> {
        (0..self.readings.len())
            .filter(|&i| {
                let r = &self.readings[i];
                test.is_none_or(|t| r.test == t) && setup.is_none_or(|s| r.setup == s)
            })
            .collect()
    }

    /// A dataset with only the given readings (setups kept, indices unchanged).
    pub fn subset(&self, rows: &[usize]) -> Dataset {
        Dataset {
            machine: self.machine.clone(),
            axis_names: self.axis_names.clone(),
            setups: self.setups.clone(),
            readings: rows.iter().map(|&i| self.readings[i].clone()).collect(),
            note: self.note.clone(),
        }
    }
}

/// A slot error vector as a function of the commanded axes and time: the error model the
/// observation model evaluates. Implemented for slices (constant errors) and for closures
/// `Fn(&[f64], f64) -> Vec<f64>`.
pub trait ErrorField {
    /// Slot error values (mm, rad; `Machine::error_slots` order) at commanded axes `q`, time `t_s`.
    fn slot_errors(&self, q: &[f64], t_s: f64) -> Vec<f64>;
}

impl ErrorField for [f64] {
    fn slot_errors(&self, _q: &[f64], _t_s: f64) -> Vec<f64> {
        self.to_vec()
    }
}

impl<F: Fn(&[f64], f64) -> Vec<f64>> ErrorField for F {
    fn slot_errors(&self, q: &[f64], t_s: f64) -> Vec<f64> {
        self(q, t_s)
    }
}

/// The three kinds of setup nuisance parameter (3 components each).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum NuisanceKind {
    /// Sensor zero offset `s`, nest (tool) frame.
    SensorZero,
    /// Nest centre offset `δn` from its nominal position, tool frame.
    NestOffset,
    /// Residual centring offset of the ball `δb`, table frame.
    BallOffset,
}

impl NuisanceKind {
    /// Short name used in parameter labels ("s", "dn", "db").
    pub fn label(self) -> &'static str {
        match self {
            NuisanceKind::SensorZero => "s",
            NuisanceKind::NestOffset => "dn",
            NuisanceKind::BallOffset => "db",
        }
    }
}

/// Nuisance values of one setup (mm).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct SetupNuisance {
    /// Sensor zero offset, nest frame.
    pub sensor_zero_mm: Vec3,
    /// Nest offset, tool frame.
    pub nest_offset_mm: Vec3,
    /// Residual ball centring offset, table frame.
    pub ball_offset_mm: Vec3,
}

impl SetupNuisance {
    /// The value of one kind.
    pub fn get(&self, kind: NuisanceKind) -> Vec3 {
        match kind {
            NuisanceKind::SensorZero => self.sensor_zero_mm,
            NuisanceKind::NestOffset => self.nest_offset_mm,
            NuisanceKind::BallOffset => self.ball_offset_mm,
        }
    }
    /// Mutable access to one kind.
    pub fn get_mut(&mut self, kind: NuisanceKind) -> &mut Vec3 {
        match kind {
            NuisanceKind::SensorZero => &mut self.sensor_zero_mm,
            NuisanceKind::NestOffset => &mut self.nest_offset_mm,
            NuisanceKind::BallOffset => &mut self.ball_offset_mm,
        }
    }
}

/// First-order sensitivity of one reading at e = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct RowSensitivity {
    /// ∂d/∂e for the slot values at the reading's own (q, t): 3 × n_slots.
    pub at_row: DMat,
    /// ∂d/∂e for the slot values at the setup's centring (q_ref, t_ref): 3 × n_slots.
    pub at_centring: DMat,
    /// ∂d/∂s (sensor zero), 3 × 3.
    pub sensor_zero: Mat3,
    /// ∂d/∂δn (nest offset), 3 × 3.
    pub nest_offset: Mat3,
    /// ∂d/∂δb (ball offset), 3 × 3.
    pub ball_offset: Mat3,
}

impl RowSensitivity {
    /// ∂d/∂e for slot errors that do not change with q or t (`at_row + at_centring`), 3 × n_slots.
    pub fn constant(&self) -> DMat {
        &self.at_row + &self.at_centring
    }
    /// The 3 × 3 block of one nuisance kind.
    pub fn nuisance(&self, kind: NuisanceKind) -> Mat3 {
        match kind {
            NuisanceKind::SensorZero => self.sensor_zero,
            NuisanceKind::NestOffset => self.nest_offset,
            NuisanceKind::BallOffset => self.ball_offset,
        }
    }
}

/// The observation model of one dataset on one machine (see the module docs for the equations).
#[derive(Debug, Clone, Copy)]
pub struct ObservationModel<'a> {
    machine: &'a Machine,
    data: &'a Dataset,
}

impl<'a> ObservationModel<'a> {
    /// Binds a dataset to a machine after [`Dataset::validate`].
    ///
    /// # Errors
    /// As [`Dataset::validate`].
    pub fn new(machine: &'a Machine, data: &'a Dataset) -> Result<Self> {
        data.validate(machine)?;
        Ok(ObservationModel { machine, data })
    }

    /// The machine.
    pub fn machine(&self) -> &'a Machine {
        self.machine
    }

    /// The dataset.
    pub fn dataset(&self) -> &'a Dataset {
        self.data
    }

    /// Exact predicted readings (mm, machine frame), one per reading, for slot errors `errors`
    /// and per-setup nuisance values (`nuisance` empty = all zero, else one per setup).
    ///
    /// # Errors
    /// [`RtestError::Invalid`] when `nuisance` has the wrong length or the error field returns a
    /// vector of the wrong length.
    pub fn predict<E: ErrorField + ?Sized>(
        &self,
        errors: &E,
        nuisance: &[SetupNuisance],
    ) -> Result<Vec<Vec3>> {
        let n_set = self.data.setups.len();
        if !nuisance.is_empty() && nuisance.len() != n_set {
            return Err(RtestError::Invalid {
                field: "nuisance".into(),
                message: format!(
                    "{} values, expected one per setup ({n_set}) or none",
                    nuisance.len()
                ),
            });
        }
        let ns = self.machine.n_slots();
        let check = |e: &Vec<f64>, what: &str| -> Result<()> {
            if !e.is_empty() && e.len() != ns {
                return Err(RtestError::Invalid {
                    field: what.into(),
                    message: format!(
                        "error field returned {} slot values, the machine has {ns}",
                        e.len()
                    ),
                });
            }
            if e.iter().any(|v| !v.is_finite()) {
                return Err(RtestError::Invalid {
                    field: what.into(),
                    message: "non-finite slot error".into(),
                });
            }
            Ok(())
        };
        let zero = SetupNuisance::default();
        let mut balls = Vec::with_capacity(n_set);
        for (i, s) in self.data.setups.iter().enumerate() {
            let nu = nuisance.get(i).unwrap_or(&zero);
            let e = errors.slot_errors(&s.centring_q, s.centring_t_s);
            check(
                &e,
                &format!("error field at the centring of setup `{}`", s.id),
            )?;
            let (w, t) = kin::poses(self.machine, &s.centring_q, &e);
            let n_act = s.nest_mm + nu.nest_offset_mm;
            // ball = actual nest at the centring, expressed in the actual table frame
            let b = kin::apply(&w.inverse(), &kin::apply(&t, &n_act)) + nu.ball_offset_mm;
            balls.push(b);
        }
        let mut out = Vec::with_capacity(self.data.readings.len());
        for (k, r) in self.data.readings.iter().enumerate() {
            let nu = nuisance.get(r.setup).unwrap_or(&zero);
            let s = &self.data.setups[r.setup];
            let e = errors.slot_errors(&r.q, r.t_s);
            check(&e, &format!("error field at reading {k}"))?;
            let (w, t) = kin::poses(self.machine, &r.q, &e);
            let n_act = s.nest_mm + nu.nest_offset_mm;
            let d = kin::apply(&w, &balls[r.setup]) - kin::apply(&t, &n_act)
                + kin::rot(&t) * nu.sensor_zero_mm;
            out.push(d);
        }
        Ok(out)
    }

    /// Exact predicted readings for constant slot errors `e` (empty = ideal machine).
    ///
    /// # Errors
    /// As [`ObservationModel::predict`].
    pub fn predict_constant(&self, e: &[f64], nuisance: &[SetupNuisance]) -> Result<Vec<Vec3>> {
        self.predict(e, nuisance)
    }

    /// First-order sensitivity of every reading at e = 0 (one [`RowSensitivity`] per reading).
    pub fn sensitivity(&self) -> Vec<RowSensitivity> {
        let m = self.machine;
        let nest_jac = |q: &[f64], n: &Vec3| -> (DMat, Mat3, Mat3, Mat3) {
            let (w, t) = kin::poses(m, q, &[]);
            let rw = kin::rot(&w);
            let rt = kin::rot(&t);
            let rg = rw.transpose() * rt;
            let j = kin::jacobian(m, q);
            let jp = j.rows(0, 3).into_owned();
            let jo = j.rows(3, 3).into_owned();
            let r = rg * n;
            let sk = skew(&r);
            let skd = DMat::from_fn(3, 3, |a, b| sk[(a, b)]);
            (jp - skd * jo, rw, rt, rg)
        };
        let refs: Vec<(DMat, Mat3)> = self
            .data
            .setups
            .iter()
            .map(|s| {
                let (jn, _, _, rg) = nest_jac(&s.centring_q, &s.nest_mm);
                (jn, rg)
            })
            .collect();
        self.data
            .readings
            .iter()
            .map(|r| {
                let s = &self.data.setups[r.setup];
                let (jn, rw, rt, _) = nest_jac(&r.q, &s.nest_mm);
                let rwd = DMat::from_fn(3, 3, |a, b| rw[(a, b)]);
                let (jn_ref, rg_ref) = &refs[r.setup];
                RowSensitivity {
                    at_row: -(&rwd * jn),
                    at_centring: &rwd * jn_ref,
                    sensor_zero: rt,
                    nest_offset: rw * rg_ref - rt,
                    ball_offset: rw,
                }
            })
            .collect()
    }
}
