//! The pose error of a machine as a sensitivity model: inputs are constant values of catalogue
//! parameters (mm or rad), outputs the pose error (px, py, pz in mm, vx, vy, vz in rad) at each of
//! a list of axis positions, point after point — 6 outputs per point.
//!
//! This adapter lives here because `mte-sensitivity` knows nothing of machines and `mte-errors`
//! does not depend on `mte-sensitivity`.

use mte_errors::Catalogue;
use mte_kinematics::Machine;
use mte_linalg::DMat;
use mte_linalg::nalgebra::{DMatrixView, DMatrixViewMut};
use mte_sensitivity::Model;

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
    /// From the catalogue.
    #[error(transparent)]
    Errors(#[from] mte_errors::Error),
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
        let k = catalogue.len();
        let mut slots = Vec::with_capacity(points.len());
        let mut effect = DMat::zeros(6 * points.len(), k);
        for (p, q) in points.iter().enumerate() {
            let mut g = DMat::zeros(machine.n_slots(), k);
            catalogue.slot_matrix_into(machine, q, &mut g);
            slots.push(g);
            let e = catalogue.effect_matrix(machine, q)?;
            effect.rows_mut(6 * p, 6).copy_from(&e);
        }
        Ok(PoseErrorModel {
            machine: machine.clone(),
            points,
            slots,
            effect,
            mode,
        })
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
                // Yᵀ (m × n column-major, i.e. Y row-major) = E · Xᵀ
                let xt = DMatrixView::from_slice(xs, k, n_rows);
                let mut yt = DMatrixViewMut::from_slice(ys, m, n_rows);
                yt.gemm(1.0, &self.effect, &xt, 0.0);
            }
            Linearisation::Exact => {
                let mut e = vec![0.0; self.machine.n_slots()];
                for (x, y) in xs.chunks_exact(k).zip(ys.chunks_exact_mut(m)) {
                    let xv = DMatrixView::from_slice(x, k, 1);
                    for (p, (q, g)) in self.points.iter().zip(&self.slots).enumerate() {
                        let ev = g * xv;
                        e.copy_from_slice(ev.as_slice());
                        let pe = self.machine.pose_error(q, &e);
                        let o = &mut y[6 * p..6 * p + 6];
                        o[..3].copy_from_slice(&[pe.position.x, pe.position.y, pe.position.z]);
                        o[3..].copy_from_slice(&[
                            pe.orientation.x,
                            pe.orientation.y,
                            pe.orientation.z,
                        ]);
                    }
                }
            }
        }
    }
}
