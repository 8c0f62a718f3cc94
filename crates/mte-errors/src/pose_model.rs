//! The pose error of a machine as a sensitivity model: inputs are constant values of catalogue
//! parameters (mm or rad), outputs the pose error (px, py, pz in mm, vx, vy, vz in rad) at each of
//! a list of axis positions, point after point — 6 outputs per point.
//!
//! Two ways in: [`PoseErrorModel::new`] (every parameter of a catalogue is an input) and
//! [`PoseErrorModel::from_error_set`] (the random entries of an [`ErrorSet`] are the inputs, with
//! their distributions; its fixed entries — constants or position-dependent models — are held at
//! their values). Test points: an explicit list, [`points_from_csv`] or [`diagonal_points`].
//!
//! This adapter lives here because `mte-sensitivity` knows nothing of machines; error sets and
//! the sensitivity methods share one [`Distribution`](mte_sensitivity::Distribution).

use crate::errorset::ModelSpec;
use crate::evaluator::AxisState;
use crate::{Catalogue, ErrorSet, Evaluator};
use mte_kinematics::{AxisKind, Machine};
use mte_linalg::bridge;
use mte_linalg::csv::{CsvError, CsvTable};
use mte_linalg::faer::linalg::matmul::matmul;
use mte_linalg::faer::{Accum, MatMut, MatRef, Par};
use mte_linalg::nalgebra::DMatrixView;
use mte_linalg::{DMat, DVec};
use mte_sensitivity::{Input, Model, Problem};

/// Names of the six pose-error components, in output order: position x, y, z and orientation
/// (rotation vector) x, y, z — the seed 003 paper's P and V directions.
pub const COMPONENTS: [&str; 6] = ["PX", "PY", "PZ", "VX", "VY", "VZ"];

/// How the pose error is computed from the slot errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Linearisation {
    /// Exact rigid-body pose error ([`Machine::pose_error`]).
    Exact,
    /// First order `J(q)·G(q)·x`: a fixed linear map per point, evaluated in batches as one
    /// matrix product.
    FirstOrder,
}

/// What went wrong when building a [`PoseErrorModel`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PoseModelError {
    /// A test point does not hold one command per machine axis.
    #[error("test point {index}: expected {expected} axis commands, got {got}")]
    PointLength {
        /// Index of the point.
        index: usize,
        /// Number of axes.
        expected: usize,
        /// Length given.
        got: usize,
    },
    /// A test point holds a non-finite command.
    #[error("test point {index}: command {axis} is not finite")]
    NotFinite {
        /// Index of the point.
        index: usize,
        /// Axis index.
        axis: usize,
    },
    /// No test point.
    #[error("at least one test point is needed")]
    NoPoints,
    /// From the catalogue or the error set (names the parameter or field).
    #[error(transparent)]
    Errors(#[from] crate::Error),
    /// The error set has no entry with a distribution, so there is nothing to vary.
    #[error(
        "error set `{set}`: no entry has a `distribution`, so there is no uncertain input (give at least one parameter a distribution)"
    )]
    NoRandomEntry {
        /// Name of the set.
        set: String,
    },
    /// An entry with a distribution is not a constant: only constant parameters can be inputs.
    #[error(
        "error set entry `{entry}` ({field}): has a distribution but is not a constant value; only constant parameters can be sensitivity inputs (drop the model or the distribution)"
    )]
    NotConstant {
        /// The entry's name.
        entry: String,
        /// Where it was defined (`parameters[3]`).
        field: String,
    },
    /// A random entry's distribution is not accepted by `mte-sensitivity`.
    #[error("error set entry `{entry}`: distribution: {source}")]
    Distribution {
        /// The entry's name.
        entry: String,
        /// What `mte-sensitivity` said.
        source: mte_sensitivity::Error,
    },
    /// Diagonal test points need a machine with linear axes and at least two points per diagonal.
    #[error("diagonal test points: {0}")]
    Diagonals(String),
    /// A test-point table is malformed (names file, line and column).
    #[error(transparent)]
    Csv(#[from] CsvError),
}

/// Pose error at fixed axis positions as a function of the values of a catalogue's parameters
/// (inputs in catalogue order). Outputs `6·p + c` for point `p`, component `c` in
/// (px, py, pz, vx, vy, vz).
#[derive(Debug, Clone)]
pub struct PoseErrorModel {
    machine: Machine,
    points: Vec<Vec<f64>>,
    /// Slot matrix G(q) of each point (n_slots × k).
    slots: Vec<DMat>,
    /// Stacked first-order effects E (6·points × k).
    effect: DMat,
    /// Slot errors of the fixed entries at each point, and their first-order pose error
    /// J(q)·e₀(q) stacked like the outputs; `None` when nothing is held fixed.
    offset: Option<(Vec<DVec>, DVec)>,
    mode: Linearisation,
}

impl PoseErrorModel {
    /// Model of `catalogue`'s parameters on `machine` at the axis positions `points` (one command
    /// per axis, mm and rad).
    ///
    /// # Errors
    /// [`PoseModelError`] for no points, a wrong length or a non-finite command.
    pub fn new(
        machine: &Machine,
        catalogue: &Catalogue,
        points: Vec<Vec<f64>>,
        mode: Linearisation,
    ) -> Result<PoseErrorModel, PoseModelError> {
        let columns: Vec<usize> = (0..catalogue.len()).collect();
        PoseErrorModel::build(machine, catalogue, &columns, None, points, mode)
    }

    /// Model of the random entries of `set` (those with a `distribution`, in
    /// [`ErrorSet::random_entries`] order) on `machine` at `points`, with the matching
    /// sensitivity [`Problem`] (input names as written in the set, distributions in mm or rad).
    /// Names are resolved in `catalogue` (e.g. [`Catalogue::for_machine`]). The fixed entries
    /// (constants and position-dependent models) are held at their values: their slot errors
    /// e₀(q) are evaluated once per point by an [`Evaluator`] (time 0, direction of motion
    /// unknown) and added, `e = G(q)·x + e₀(q)`; to first order they shift the outputs by
    /// J(q)·e₀(q) and leave every index unchanged.
    ///
    /// ```
    /// use mte_errors::pose_model::{Linearisation, PoseErrorModel, diagonal_points};
    /// use mte_errors::{Catalogue, ErrorSet, distribution::Distribution, units::Kind};
    /// use mte_kinematics::Machine;
    /// use mte_sensitivity::Model;
    /// let m = Machine::library("seed004-3axis").unwrap();
    /// let set = ErrorSet::new("demo")
    ///     .with_constant("EZZ", 0.002, Kind::Length)
    ///     .with_distribution("EXX", Distribution::Normal { mean: 0.0, sd: 0.005 }, Kind::Length);
    /// let points = diagonal_points(&m, 3).unwrap();
    /// let (problem, model) = PoseErrorModel::from_error_set(
    ///     &m, &Catalogue::for_machine(&m), &set, points, Linearisation::FirstOrder,
    /// ).unwrap();
    /// assert_eq!(problem.names(), ["EXX"]);
    /// assert_eq!(model.n_outputs(), 4 * 3 * 6);
    /// ```
    ///
    /// # Errors
    /// [`PoseModelError::Errors`] for an entry not in the catalogue (with suggestions), a unit
    /// of the wrong kind, or a fixed model that cannot be evaluated at a point;
    /// [`PoseModelError::NoRandomEntry`], [`PoseModelError::NotConstant`] (an entry with a
    /// distribution and a position-dependent model, possible only for sets built in code: the
    /// JSON form rejects it), [`PoseModelError::Distribution`], and the point errors of
    /// [`PoseErrorModel::new`].
    pub fn from_error_set(
        machine: &Machine,
        catalogue: &Catalogue,
        set: &ErrorSet,
        points: Vec<Vec<f64>>,
        mode: Linearisation,
    ) -> Result<(Problem, PoseErrorModel), PoseModelError> {
        let bound = Evaluator::with_catalogue(machine, catalogue.clone(), set)?;
        let random = set.random_entries();
        if random.is_empty() {
            return Err(PoseModelError::NoRandomEntry {
                set: set.name.clone(),
            });
        }
        let mut inputs = Vec::with_capacity(random.len());
        for &i in &random {
            let e = &set.entries[i];
            if !matches!(e.spec, ModelSpec::Constant(_)) {
                return Err(PoseModelError::NotConstant {
                    entry: e.name.clone(),
                    field: e.field.clone(),
                });
            }
            let d = e.distribution.expect("random entries have a distribution");
            inputs.push(Input::new(e.name.clone(), d).map_err(|source| {
                PoseModelError::Distribution {
                    entry: e.name.clone(),
                    source,
                }
            })?);
        }
        let problem = Problem::new(inputs).map_err(|source| PoseModelError::Distribution {
            entry: set.entries[random[0]].name.clone(),
            source,
        })?;
        let columns: Vec<usize> = random
            .iter()
            .map(|&i| bound.parameter_indices()[i])
            .collect();
        let mut fixed = set.clone();
        fixed.entries.retain(|e| e.distribution.is_none());
        let fixed = Evaluator::with_catalogue(machine, catalogue.clone(), &fixed)?;
        let model =
            PoseErrorModel::build(machine, catalogue, &columns, Some(&fixed), points, mode)?;
        Ok((problem, model))
    }

    /// The model of catalogue parameters `columns`, plus the slot errors of `fixed` when given.
    fn build(
        machine: &Machine,
        catalogue: &Catalogue,
        columns: &[usize],
        fixed: Option<&Evaluator>,
        points: Vec<Vec<f64>>,
        mode: Linearisation,
    ) -> Result<PoseErrorModel, PoseModelError> {
        if points.is_empty() {
            return Err(PoseModelError::NoPoints);
        }
        let n_axes = machine.axes().len();
        for (index, q) in points.iter().enumerate() {
            if q.len() != n_axes {
                return Err(PoseModelError::PointLength {
                    index,
                    expected: n_axes,
                    got: q.len(),
                });
            }
            if let Some(axis) = q.iter().position(|v| !v.is_finite()) {
                return Err(PoseModelError::NotFinite { index, axis });
            }
        }
        let n_slots = machine.n_slots();
        let k = columns.len();
        let mut slots = Vec::with_capacity(points.len());
        let mut effect = DMat::zeros(6 * points.len(), k);
        let mut g = DMat::zeros(n_slots, catalogue.len());
        for (p, q) in points.iter().enumerate() {
            catalogue.slot_matrix_into(machine, q, &mut g);
            slots.push(g.select_columns(columns));
            let e = catalogue.effect_matrix(machine, q)?;
            effect
                .rows_mut(6 * p, 6)
                .copy_from(&e.select_columns(columns));
        }
        let offset = match fixed {
            None => None,
            Some(ev) => {
                let mut e0s = Vec::with_capacity(points.len());
                let mut stacked = DVec::zeros(6 * points.len());
                let mut jac = DMat::zeros(6, n_slots);
                for (p, q) in points.iter().enumerate() {
                    let mut e0 = vec![0.0; n_slots];
                    let pe = ev.pose_error_first_order(&AxisState::at(q), &mut e0, &mut jac)?;
                    stacked.rows_mut(6 * p, 6).copy_from(&pe.to_vec6());
                    e0s.push(DVec::from_vec(e0));
                }
                Some((e0s, stacked))
            }
        };
        Ok(PoseErrorModel {
            machine: machine.clone(),
            points,
            slots,
            effect,
            offset,
            mode,
        })
    }

    /// First-order effect of each input on each output: the 6·points × inputs matrix E stacked
    /// from `J(q)·G(q)` of each point (mm or rad per mm or rad). The first-order model is
    /// `y = E·x` plus the fixed entries' shift.
    pub fn effect(&self) -> &DMat {
        &self.effect
    }

    /// Output names `p01.PX` … (1-based point number, zero-padded to at least two digits, then
    /// one of [`COMPONENTS`]), in output order.
    pub fn output_names(&self) -> Vec<String> {
        let w = self.points.len().to_string().len().max(2);
        (1..=self.points.len())
            .flat_map(|p| COMPONENTS.iter().map(move |c| format!("p{p:0w$}.{c}")))
            .collect()
    }

    /// Number of inputs (catalogue parameters).
    pub fn n_inputs(&self) -> usize {
        self.effect.ncols()
    }

    /// The test points.
    pub fn points(&self) -> &[Vec<f64>] {
        &self.points
    }
}

impl Model for PoseErrorModel {
    fn evaluate(&self, x: &[f64], y: &mut [f64]) {
        self.evaluate_batch(1, x, y);
    }

    fn n_outputs(&self) -> usize {
        6 * self.points.len()
    }

    fn evaluate_batch(&self, n_rows: usize, xs: &[f64], ys: &mut [f64]) {
        let k = self.n_inputs();
        let m = self.n_outputs();
        match self.mode {
            Linearisation::FirstOrder => {
                // Yᵀ (m × n column-major, i.e. Y row-major) = E · Xᵀ, by faer's product
                // (sequential: batches are evaluated in parallel by the caller)
                let xt = MatRef::from_column_major_slice(xs, k, n_rows);
                let mut yt = MatMut::from_column_major_slice_mut(ys, m, n_rows);
                let accum = match &self.offset {
                    None => Accum::Replace,
                    Some((_, shift)) => {
                        for mut col in yt.as_mut().col_iter_mut() {
                            col.copy_from(bridge::vec_as_faer(shift));
                        }
                        Accum::Add
                    }
                };
                matmul(yt, accum, bridge::as_faer(&self.effect), xt, 1.0, Par::Seq);
                bridge::clean_vector_state();
            }
            Linearisation::Exact => {
                let mut e = vec![0.0; self.machine.n_slots()];
                for (x, y) in xs.chunks_exact(k).zip(ys.chunks_exact_mut(m)) {
                    let xv = DMatrixView::from_slice(x, k, 1);
                    for (p, (q, g)) in self.points.iter().zip(&self.slots).enumerate() {
                        let ev = g * xv;
                        e.copy_from_slice(ev.as_slice());
                        if let Some((e0s, _)) = &self.offset {
                            e.iter_mut().zip(e0s[p].iter()).for_each(|(a, b)| *a += b);
                        }
                        let pe = self.machine.pose_error(q, &e);
                        y[6 * p..6 * p + 6].copy_from_slice(pe.to_vec6().as_slice());
                    }
                }
            }
        }
    }
}

/// `per_diagonal` equally spaced points (ends included) on each body diagonal of the box spanned
/// by the strokes of the machine's linear axes, rotary axes at 0 — the test points of the seed 003
/// study (5 per diagonal on its X–Y–Z box: 20 points). With L linear axes there are 2^(L−1)
/// diagonals, from the low corner of the first axis to its high corner; diagonal d runs the
/// linear axis j + 1 downwards when bit j of d is set (for X, Y, Z: (+,+), (−,+), (+,−), (−,−)
/// for the Y and Z directions relative to X). Points in axis order, mm and rad.
///
/// ```
/// use mte_errors::pose_model::diagonal_points;
/// use mte_kinematics::Machine;
/// let m = Machine::library("seed003-ac-table").unwrap(); // X ±400, Y ±425, Z ±275
/// let p = diagonal_points(&m, 5).unwrap();
/// assert_eq!(p.len(), 20);
/// assert_eq!(p[0], [-400.0, -425.0, -275.0, 0.0, 0.0]);
/// assert_eq!(p[9], [400.0, -425.0, 275.0, 0.0, 0.0]);
/// ```
///
/// # Errors
/// [`PoseModelError::Diagonals`] for `per_diagonal < 2` or a machine without linear axes.
pub fn diagonal_points(
    machine: &Machine,
    per_diagonal: usize,
) -> Result<Vec<Vec<f64>>, PoseModelError> {
    if per_diagonal < 2 {
        return Err(PoseModelError::Diagonals(format!(
            "need at least 2 points per diagonal (its two corners), got {per_diagonal}"
        )));
    }
    let linear: Vec<usize> = (0..machine.axes().len())
        .filter(|&a| machine.axes()[a].kind == AxisKind::Linear)
        .collect();
    if linear.is_empty() {
        return Err(PoseModelError::Diagonals(format!(
            "machine `{}` has no linear axis",
            machine.name()
        )));
    }
    let mut points = Vec::new();
    for d in 0..1usize << (linear.len() - 1) {
        for t in 0..per_diagonal {
            let s = -1.0 + 2.0 * t as f64 / (per_diagonal - 1) as f64;
            let mut q = vec![0.0; machine.axes().len()];
            for (j, &a) in linear.iter().enumerate() {
                let sign = if j > 0 && d >> (j - 1) & 1 == 1 {
                    -1.0
                } else {
                    1.0
                };
                let (lo, hi) = machine.axes()[a].stroke;
                q[a] = 0.5 * (lo + hi) + s * sign * (0.5 * (hi - lo));
            }
            points.push(q);
        }
    }
    Ok(points)
}

/// A test point given in mm (linear axes) and degrees (rotary axes), in axis order, converted to
/// the internal mm and rad. Values beyond the machine's axes are kept, so that
/// [`PoseErrorModel::new`] reports the wrong length.
pub fn point_from_mm_deg(machine: &Machine, values: &[f64]) -> Vec<f64> {
    values
        .iter()
        .enumerate()
        .map(|(a, &v)| match machine.axes().get(a) {
            Some(ax) if ax.kind == AxisKind::Rotary => v.to_radians(),
            _ => v,
        })
        .collect()
}

/// Test points from a CSV table with one column per axis, named exactly as the axis (`X`, `Y`,
/// `Z`, `A`, `C` …; other columns are ignored), linear axes in mm, rotary axes in degrees; one
/// point per row. Returns mm and rad.
///
/// ```
/// use mte_errors::pose_model::points_from_csv;
/// use mte_kinematics::Machine;
/// let m = Machine::library("seed003-ac-table").unwrap();
/// let p = points_from_csv(&m, "X,Y,Z,A,C\n100,0,-50,90,0\n", "pts.csv").unwrap();
/// assert_eq!(p[0][0], 100.0);
/// assert!((p[0][3] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
/// let e = points_from_csv(&m, "X,Y,Z,A\n0,0,0,0\n", "pts.csv").unwrap_err();
/// assert!(e.to_string().contains("pts.csv: line 1") && e.to_string().contains("`C`"));
/// ```
///
/// # Errors
/// [`PoseModelError::Csv`] naming the file, line and column for a missing axis column or a
/// field that is not a finite number; [`PoseModelError::NoPoints`] for a table without rows.
pub fn points_from_csv(
    machine: &Machine,
    text: &str,
    source_name: &str,
) -> Result<Vec<Vec<f64>>, PoseModelError> {
    let t = CsvTable::parse(text, source_name)?;
    let cols = machine
        .axes()
        .iter()
        .map(|a| t.require(&a.name))
        .collect::<Result<Vec<_>, _>>()?;
    if t.is_empty() {
        return Err(PoseModelError::NoPoints);
    }
    (0..t.len())
        .map(|r| {
            let row = cols
                .iter()
                .map(|&c| t.number(r, c))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(point_from_mm_deg(machine, &row))
        })
        .collect()
}

/// The variance-weighted ("generalised", Gamboa et al. 2014) index over the outputs `members`:
/// Σ_p V_p·S_p / Σ_p V_p per input, and the same weighting of the per-output interval ends (a
/// conservative interval: it treats the outputs' estimation errors as fully correlated and the
/// weights as exact). `values[o][i]` is the index of input i for output o, `intervals[o]` its
/// intervals (empty: none), `weights[o]` the variance of output o; `members` the outputs to
/// aggregate (e.g. the PX outputs of every point). `None` when the members carry no weight.
/// Intervals are returned only when every member has them.
///
/// ```
/// use mte_errors::pose_model::generalised_index;
/// // Two outputs: variance 1 with S = (1, 0), variance 3 with S = (0.5, 0.5).
/// let (s, _) = generalised_index(&[vec![1.0, 0.0], vec![0.5, 0.5]], &[], &[1.0, 3.0], &[0, 1]).unwrap();
/// assert_eq!(s, [0.625, 0.375]);
/// ```
pub fn generalised_index(
    values: &[Vec<f64>],
    intervals: &[Vec<[f64; 2]>],
    weights: &[f64],
    members: &[usize],
) -> Option<(Vec<f64>, Vec<[f64; 2]>)> {
    let w: f64 = members.iter().map(|&o| weights[o]).sum();
    if w.is_nan() || w <= 0.0 {
        return None;
    }
    let k = values[members[0]].len();
    let val = (0..k)
        .map(|i| {
            members
                .iter()
                .map(|&o| weights[o] * values[o][i])
                .sum::<f64>()
                / w
        })
        .collect();
    let has_ci = members
        .iter()
        .all(|&o| intervals.get(o).is_some_and(|c| c.len() == k));
    let ci = if has_ci {
        (0..k)
            .map(|i| {
                let end = |e: usize| {
                    members
                        .iter()
                        .map(|&o| weights[o] * intervals[o][i][e])
                        .sum::<f64>()
                        / w
                };
                [end(0), end(1)]
            })
            .collect()
    } else {
        vec![]
    };
    Some((val, ci))
}
