//! A precompiled evaluator: error set + machine → slot error vector and pose error.

use crate::catalogue::{Catalogue, Gain};
use crate::error::{Error, Result};
use crate::errorset::{AxisInfo, ErrorSet};
use crate::models::{Context, Direction, ErrorModel};
use crate::units::Kind;
use mte_kinematics::{AxisKind, Machine, PoseError};
use mte_linalg::DMat;
use std::sync::Arc;

/// The state of the machine at one point: axis commands (mm, rad, in [`Machine::axes`] order),
/// time (s) and each axis' direction of motion (empty slice = all unknown).
#[derive(Debug, Clone, Copy)]
pub struct AxisState<'a> {
    /// Axis commands.
    pub q: &'a [f64],
    /// Time since the start (s).
    pub time_s: f64,
    /// Direction of motion per axis, or empty.
    pub directions: &'a [Direction],
}

impl<'a> AxisState<'a> {
    /// At `q`, time 0, directions unknown.
    pub fn at(q: &'a [f64]) -> AxisState<'a> {
        AxisState {
            q,
            time_s: 0.0,
            directions: &[],
        }
    }
}

#[derive(Debug, Clone)]
struct Term {
    model: Arc<dyn ErrorModel>,
    entry: usize,
    slot: usize,
    weight: f64,
    coord: bool,
    axis: Option<usize>,
    lo: f64,
    hi: f64,
}

/// Error set bound to a machine and its catalogue. Cheap to share across threads; evaluation
/// does not allocate.
///
/// ```
/// use mte_kinematics::Machine;
/// use mte_errors::{ErrorSet, Evaluator, evaluator::AxisState, units::Kind};
/// let m = Machine::library("seed004-3axis").unwrap();
/// // 10 µm Z positioning error.
/// let set = ErrorSet::new("demo").with_constant("EZZ", 0.010, Kind::Length);
/// let ev = Evaluator::new(&m, &set).unwrap();
/// let mut e = vec![0.0; ev.n_slots()];
/// let pe = ev.pose_error(&AxisState::at(&[0.0, 0.0, -100.0]), &mut e).unwrap();
/// assert!((pe.position.z - 0.010).abs() < 1e-12);
/// ```
#[derive(Debug, Clone)]
pub struct Evaluator {
    machine: Machine,
    catalogue: Catalogue,
    names: Vec<String>,
    params: Vec<usize>,
    terms: Vec<Term>,
}

impl Evaluator {
    /// Bind `set` to `machine` with the machine's full catalogue.
    ///
    /// # Errors
    /// As [`Evaluator::with_catalogue`].
    pub fn new(machine: &Machine, set: &ErrorSet) -> Result<Evaluator> {
        Evaluator::with_catalogue(machine, Catalogue::for_machine(machine), set)
    }

    /// Bind `set` to `machine`, resolving names in `catalogue` (e.g. a paper view, whose
    /// aliases and derived parameters such as seed 000's `q6e` are then accepted).
    ///
    /// # Errors
    /// [`Error::UnknownParameter`] with suggestions; [`Error::Unit`] when a parameter's unit
    /// kind differs from the catalogue's (e.g. µrad for a straightness) or model positions do
    /// not fit the axis; [`Error::Invalid`] for two entries naming the same parameter or bad
    /// model settings.
    pub fn with_catalogue(
        machine: &Machine,
        catalogue: Catalogue,
        set: &ErrorSet,
    ) -> Result<Evaluator> {
        let mut terms = Vec::new();
        let mut names = Vec::new();
        let mut params: Vec<usize> = Vec::new();
        for (ei, entry) in set.entries.iter().enumerate() {
            let found = catalogue.find(&entry.name)?;
            let pi = catalogue.index_of(&found.name).unwrap_or(0);
            let p = &catalogue.parameters()[pi];
            if let Some(k) = params.iter().position(|&x| x == pi) {
                return Err(crate::error::invalid(
                    &entry.field,
                    format!(
                        "`{}` is the same parameter as `{}` ({}; also {})",
                        entry.name, set.entries[k].name, p.name, set.entries[k].field
                    ),
                ));
            }
            if entry.kind != p.quantity {
                return Err(Error::Unit {
                    field: entry.unit_field.clone(),
                    unit: entry.kind.internal_unit().to_string(),
                    message: format!(
                        "unit mismatch: `{}` ({}) is {} but the value is given as {}",
                        entry.name,
                        p.name,
                        if p.quantity == Kind::Length {
                            "a length (use _mm, _um, _nm)"
                        } else {
                            "an angle (use _rad, _urad, _arcsec, _deg)"
                        },
                        if entry.kind == Kind::Length {
                            "a length"
                        } else {
                            "an angle"
                        }
                    ),
                });
            }
            let axis_info = p.axis.map(|a| {
                let ax = &machine.axes()[a];
                AxisInfo {
                    kind: if ax.kind == AxisKind::Linear {
                        Kind::Length
                    } else {
                        Kind::Angle
                    },
                    stroke: ax.stroke,
                }
            });
            let model = entry.spec.build(axis_info, &entry.field)?;
            let (lo, hi) = model.domain().unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
            for c in &p.contributions {
                terms.push(Term {
                    model: model.clone(),
                    entry: ei,
                    slot: c.slot,
                    weight: c.weight,
                    coord: c.gain == Gain::Coordinate,
                    axis: p.axis,
                    lo,
                    hi,
                });
            }
            names.push(entry.name.clone());
            params.push(pi);
        }
        Ok(Evaluator {
            machine: machine.clone(),
            catalogue,
            names,
            params,
            terms,
        })
    }

    /// The machine.
    pub fn machine(&self) -> &Machine {
        &self.machine
    }
    /// The catalogue names were resolved in.
    pub fn catalogue(&self) -> &Catalogue {
        &self.catalogue
    }
    /// Catalogue index of each entry of the error set.
    pub fn parameter_indices(&self) -> &[usize] {
        &self.params
    }
    /// Number of error slots (length of the slot vector).
    pub fn n_slots(&self) -> usize {
        self.machine.n_slots()
    }

    fn check(&self, state: &AxisState, e: &[f64]) -> Result<()> {
        let n = self.machine.axes().len();
        if state.q.len() != n {
            return Err(Error::Dimension {
                what: "axis commands q".into(),
                expected: n,
                got: state.q.len(),
            });
        }
        if !state.directions.is_empty() && state.directions.len() != n {
            return Err(Error::Dimension {
                what: "directions".into(),
                expected: n,
                got: state.directions.len(),
            });
        }
        if e.len() != self.machine.n_slots() {
            return Err(Error::Dimension {
                what: "slot vector e".into(),
                expected: self.machine.n_slots(),
                got: e.len(),
            });
        }
        if let Some(i) = state.q.iter().position(|x| !x.is_finite()) {
            return Err(crate::error::invalid(
                "axis commands",
                format!("q[{i}] = {} is not finite", state.q[i]),
            ));
        }
        Ok(())
    }

    /// Fill the slot error vector `e` (length [`Evaluator::n_slots`]) at `state`: the sum over
    /// parameters of `weight · g(q) · model(ctx)`. No allocation.
    ///
    /// # Errors
    /// [`Error::Dimension`] for wrong lengths, [`Error::OutOfRange`] when a model (e.g. a
    /// measured table) is evaluated outside its range, [`Error::Invalid`] for non-finite q.
    pub fn slot_errors(&self, state: &AxisState, e: &mut [f64]) -> Result<()> {
        self.check(state, e)?;
        e.fill(0.0);
        for t in &self.terms {
            let (x, dir) = match t.axis {
                Some(a) => (
                    state.q[a],
                    state.directions.get(a).copied().unwrap_or_default(),
                ),
                None => (0.0, Direction::Unknown),
            };
            if !(x >= t.lo && x <= t.hi) {
                return Err(Error::OutOfRange {
                    parameter: self.names[t.entry].clone(),
                    position: x,
                    low: t.lo,
                    high: t.hi,
                });
            }
            let ctx = Context {
                position: x,
                time_s: state.time_s,
                direction: dir,
            };
            let g = if t.coord { x } else { 1.0 };
            e[t.slot] += t.weight * g * t.model.value(&ctx);
        }
        Ok(())
    }

    /// Exact pose error (tool relative to workpiece, workpiece frame) at `state`; `e` is scratch
    /// space of length [`Evaluator::n_slots`] and holds the slot errors afterwards.
    ///
    /// # Errors
    /// As [`Evaluator::slot_errors`].
    pub fn pose_error(&self, state: &AxisState, e: &mut [f64]) -> Result<PoseError> {
        self.slot_errors(state, e)?;
        Ok(self.machine.pose_error(state.q, e))
    }

    /// First-order pose error `J(q)·e` at `state`; `jac` is scratch space (6 × n_slots).
    ///
    /// # Errors
    /// As [`Evaluator::slot_errors`], and [`Error::Dimension`] for a wrongly sized `jac`.
    pub fn pose_error_first_order(
        &self,
        state: &AxisState,
        e: &mut [f64],
        jac: &mut DMat,
    ) -> Result<PoseError> {
        self.slot_errors(state, e)?;
        if jac.shape() != (6, self.n_slots()) {
            return Err(Error::Dimension {
                what: "jacobian scratch (6 × n_slots)".into(),
                expected: 6 * self.n_slots(),
                got: jac.len(),
            });
        }
        self.machine.jacobian_into(state.q, jac);
        let s = jac.as_slice();
        let mut acc = [0.0f64; 6];
        for (col, &ek) in s.chunks_exact(6).zip(e.iter()) {
            if ek != 0.0 {
                for r in 0..6 {
                    acc[r] += col[r] * ek;
                }
            }
        }
        Ok(PoseError {
            position: mte_linalg::Vec3::new(acc[0], acc[1], acc[2]),
            orientation: mte_linalg::Vec3::new(acc[3], acc[4], acc[5]),
        })
    }
}
