//! Forward kinematics (MBS characteristic matrices and product of exponentials),
//! pose error and its analytic Jacobian.

use crate::machine::{AxisKind, Branch, Machine};
use mte_linalg::nalgebra::{Quaternion, Translation3, UnitQuaternion};
use mte_linalg::{DMat, Iso3, Vec3, Vec6, quaternion_from_rotation_vector, se3, so3};

/// Poses of the two branch ends in the bed (machine) frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchPoses {
    /// Workpiece frame in the bed frame.
    pub workpiece_in_base: Iso3,
    /// Tool frame (origin = tool tip, +z = tool axis) in the bed frame.
    pub tool_in_base: Iso3,
}

impl BranchPoses {
    /// Tool frame in the workpiece frame: `(base→workpiece)⁻¹ · (base→tool)`.
    pub fn tool_in_workpiece(&self) -> Iso3 {
        self.workpiece_in_base.inv_mul(&self.tool_in_base)
    }
}

/// Pose error of the tool relative to the workpiece, in the workpiece frame.
///
/// `position = p_actual − p_ideal` of the tool tip (mm);
/// `orientation = log(R_actual · R_idealᵀ)` (rad, rotation vector).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PoseError {
    /// Tool-tip position error, mm, workpiece frame.
    pub position: Vec3,
    /// Tool orientation error (rotation vector), rad, workpiece frame.
    pub orientation: Vec3,
}

impl PoseError {
    /// As a 6-vector (px, py, pz, ox, oy, oz).
    pub fn to_vec6(&self) -> Vec6 {
        let (p, o) = (self.position, self.orientation);
        Vec6::new(p.x, p.y, p.z, o.x, o.y, o.z)
    }
    /// From a 6-vector (px, py, pz, ox, oy, oz).
    pub fn from_vec6(v: &Vec6) -> PoseError {
        PoseError {
            position: Vec3::new(v[0], v[1], v[2]),
            orientation: Vec3::new(v[3], v[4], v[5]),
        }
    }
    /// Error of the tool axis direction (mm/mm): `orientation × axis` for the ideal tool
    /// axis `axis` (unit, workpiece frame) — to first order the change of the axis vector.
    pub fn axis_error(&self, axis: &Vec3) -> Vec3 {
        self.orientation.cross(axis)
    }
}

/// Jacobian of the pose error with respect to the error slots at e = 0: a 6 × n_slots
/// matrix (rows px, py, pz, ox, oy, oz; columns in slot order). Dereferences to the
/// matrix; [`Jacobian::apply`] evaluates the first-order model `J · e`.
#[derive(Debug, Clone, PartialEq)]
pub struct Jacobian {
    /// The 6 × n_slots matrix (column-major).
    pub matrix: DMat,
}

impl std::ops::Deref for Jacobian {
    type Target = DMat;
    fn deref(&self) -> &DMat {
        &self.matrix
    }
}

impl Jacobian {
    /// First-order pose error `J · e` (no allocation).
    ///
    /// # Panics
    /// If `e.len()` differs from the number of columns.
    pub fn apply(&self, e: &[f64]) -> PoseError {
        assert_eq!(e.len(), self.matrix.ncols(), "error vector length");
        let s = self.matrix.as_slice();
        let mut acc = [0.0f64; 6];
        for (col, &ek) in s.chunks_exact(6).zip(e) {
            for r in 0..6 {
                acc[r] += col[r] * ek;
            }
        }
        PoseError {
            position: Vec3::new(acc[0], acc[1], acc[2]),
            orientation: Vec3::new(acc[3], acc[4], acc[5]),
        }
    }
}

/// Rotation vector of a unit quaternion (log), exact near 0 and stable up to π.
pub(crate) fn rotation_vector(q: &UnitQuaternion<f64>) -> Vec3 {
    let (mut w, mut v) = (q.w, q.imag());
    if w < 0.0 {
        w = -w;
        v = -v;
    }
    let n = v.norm();
    // 2·atan2(n, w)/n; for n < 1e-8 the series 2/w·(1 − n²/(3w²)) differs by < 1e-16.
    let f = if n < 1e-8 {
        2.0 / w
    } else {
        2.0 * n.atan2(w) / n
    };
    v * f
}

#[inline]
fn axis_rotation(u: &Vec3, angle: f64) -> UnitQuaternion<f64> {
    let (s, c) = (0.5 * angle).sin_cos();
    UnitQuaternion::new_unchecked(Quaternion::new(c, s * u.x, s * u.y, s * u.z))
}

/// A running rigid transform as (rotation, translation); cheaper than repeated `Iso3 * Iso3`
/// because most factors are pure translations or pure rotations.
#[derive(Clone, Copy)]
struct Frame {
    r: UnitQuaternion<f64>,
    t: Vec3,
}

impl Frame {
    const IDENTITY: Frame = Frame {
        r: UnitQuaternion::new_unchecked(Quaternion::new(1.0, 0.0, 0.0, 0.0)),
        t: Vec3::new(0.0, 0.0, 0.0),
    };
    #[inline]
    fn translate(&mut self, d: &Vec3) {
        self.t += self.r * d;
    }
    #[inline]
    fn rotate(&mut self, q: &UnitQuaternion<f64>) {
        self.r *= q;
    }
    /// Right-multiply by the exact error transform Trans(δ)·Rot(ε) of `e[0..6]`.
    #[inline]
    fn error(&mut self, e: &[f64]) {
        if e.iter().all(|&x| x == 0.0) {
            return;
        }
        self.translate(&Vec3::new(e[0], e[1], e[2]));
        let eps = Vec3::new(e[3], e[4], e[5]);
        if eps != Vec3::zeros() {
            self.rotate(&quaternion_from_rotation_vector(&eps));
        }
    }
    fn iso(&self) -> Iso3 {
        Iso3::from_parts(Translation3::from(self.t), self.r)
    }
}

impl Machine {
    fn check_inputs(&self, q: &[f64], e: &[f64]) {
        assert_eq!(
            q.len(),
            self.axes.len(),
            "q has {} entries, machine {} has {} axes",
            q.len(),
            self.name,
            self.axes.len()
        );
        assert!(
            e.is_empty() || e.len() == self.slots.len(),
            "e has {} entries, machine {} has {} error slots (or pass an empty slice)",
            e.len(),
            self.name,
            self.slots.len()
        );
    }

    /// MBS product along a chain: Π_j P_j · ΔP_j · S_j(q) · ΔS_j.
    /// Returns (ideal, actual) when `e` is non-empty, else (ideal, ideal).
    #[inline]
    fn chain_pair(&self, chain: &[usize], q: &[f64], e: &[f64]) -> (Frame, Frame) {
        let mut ideal = Frame::IDENTITY;
        let mut act = Frame::IDENTITY;
        let with_e = !e.is_empty();
        for &j in chain {
            let c = &self.consts[j];
            let off = &self.bodies[j].offset_mm;
            ideal.translate(off);
            if with_e {
                act.translate(off);
                if let Some(s) = c.pos_slot {
                    act.error(&e[s..s + 6]);
                }
            }
            if let Some((kind, u, k)) = &c.joint {
                match kind {
                    AxisKind::Linear => {
                        let d = u * q[*k];
                        ideal.translate(&d);
                        if with_e {
                            act.translate(&d);
                        }
                    }
                    AxisKind::Rotary => {
                        let r = axis_rotation(u, q[*k]);
                        ideal.rotate(&r);
                        if with_e {
                            act.rotate(&r);
                        }
                    }
                }
            }
            if with_e && let Some(s) = c.mot_slot {
                act.error(&e[s..s + 6]);
            }
        }
        if with_e { (ideal, act) } else { (ideal, ideal) }
    }

    /// Poses of workpiece and tool in the bed frame (MBS form), with errors `e`
    /// (empty = ideal machine).
    ///
    /// # Panics
    /// If `q.len() != axes().len()` or `e` is neither empty nor `n_slots()` long.
    pub fn branch_poses(&self, q: &[f64], e: &[f64]) -> BranchPoses {
        self.check_inputs(q, e);
        let (_, w) = self.chain_pair(&self.wp_chain, q, e);
        let (_, t) = self.chain_pair(&self.tool_chain, q, e);
        BranchPoses {
            workpiece_in_base: w.iso(),
            tool_in_base: t.iso(),
        }
    }

    /// Tool frame in the workpiece frame from the MBS characteristic matrices
    /// `T_ij = P_ij · ΔP_ij · S_ij(q) · ΔS_ij` (seeds 000/001), exact error transforms.
    ///
    /// # Panics
    /// As [`Machine::branch_poses`].
    ///
    /// ```
    /// let m = mte_kinematics::Machine::library("seed004-3axis").unwrap();
    /// let g = m.tool_in_workpiece(&[100.0, -200.0, -300.0], &[]);
    /// // ISO 841 signs: the ideal tool tip in the workpiece frame is (X, Y, Z)
    /// assert!((g.translation.vector - mte_linalg::Vec3::new(100.0, -200.0, -300.0)).norm() < 1e-12);
    /// ```
    pub fn tool_in_workpiece(&self, q: &[f64], e: &[f64]) -> Iso3 {
        self.branch_poses(q, e).tool_in_workpiece()
    }

    /// Tool frame in the workpiece frame from the product of exponentials with space-frame
    /// twists (seed 003), computed independently of the MBS matrices: with C_j the home
    /// pose of body j, `Π_j (P_j X_j) = Π_j exp(Ad_{C_j} ξ_j) · C_n`, where each error
    /// factor is `exp(Ad_{C_j} (J⁻¹(ε)δ, ε))` and each joint factor `exp(Ad_{C_j} ξ q)`
    /// with ξ = (u, 0) (linear) or (0, u) (rotary).
    ///
    /// # Panics
    /// As [`Machine::branch_poses`].
    pub fn tool_in_workpiece_poe(&self, q: &[f64], e: &[f64]) -> Iso3 {
        self.check_inputs(q, e);
        let w = self.chain_poe(&self.wp_chain, q, e);
        let t = self.chain_poe(&self.tool_chain, q, e);
        w.inv_mul(&t)
    }

    /// Error twist of a 6-vector error: `(J⁻¹(ε) δ, ε)`, so that
    /// `exp(twist) = Trans(δ)·Rot(ε)`.
    fn error_twist(e: &[f64]) -> Vec6 {
        let d = Vec3::new(e[0], e[1], e[2]);
        let eps = Vec3::new(e[3], e[4], e[5]);
        let v = so3::left_jacobian_inv(&eps) * d;
        Vec6::new(v.x, v.y, v.z, eps.x, eps.y, eps.z)
    }

    fn chain_poe(&self, chain: &[usize], q: &[f64], e: &[f64]) -> Iso3 {
        let mut g = Iso3::identity();
        for &j in chain {
            let c = &self.consts[j];
            let cj = Iso3::translation(c.home.x, c.home.y, c.home.z);
            let ad = se3::adjoint(&cj);
            if !e.is_empty()
                && let Some(s) = c.pos_slot
            {
                g *= se3::exp(&(ad * Self::error_twist(&e[s..s + 6])));
            }
            if let Some((kind, u, k)) = &c.joint {
                let local = match kind {
                    AxisKind::Linear => Vec6::new(u.x, u.y, u.z, 0.0, 0.0, 0.0),
                    AxisKind::Rotary => Vec6::new(0.0, 0.0, 0.0, u.x, u.y, u.z),
                };
                g *= se3::exp(&(ad * local * q[*k]));
            }
            if !e.is_empty()
                && let Some(s) = c.mot_slot
            {
                g *= se3::exp(&(ad * Self::error_twist(&e[s..s + 6])));
            }
        }
        let end = chain.last().map_or(Vec3::zeros(), |&j| self.consts[j].home);
        g * Iso3::translation(end.x, end.y, end.z)
    }

    /// Exact pose error of the tool relative to the workpiece (workpiece frame) for
    /// errors `e` at axis position `q` (MBS form). No allocation (see the crate benches).
    ///
    /// # Panics
    /// As [`Machine::branch_poses`].
    ///
    /// ```
    /// use mte_kinematics::Machine;
    /// let m = Machine::library("seed004-3axis").unwrap();
    /// let mut e = vec![0.0; m.n_slots()];
    /// e[m.slot_index_by_name("Z.motion.dz").unwrap()] = 0.010; // +10 µm Z positioning error
    /// let pe = m.pose_error(&[0.0, 0.0, -100.0], &e);
    /// assert!((pe.position.z - 0.010).abs() < 1e-12);
    /// ```
    pub fn pose_error(&self, q: &[f64], e: &[f64]) -> PoseError {
        self.check_inputs(q, e);
        if e.is_empty() {
            return PoseError::default();
        }
        let (wi, wa) = self.chain_pair(&self.wp_chain, q, e);
        let (ti, ta) = self.chain_pair(&self.tool_chain, q, e);
        // tool in workpiece: R = Rwᵀ Rt, p = Rwᵀ (pt − pw)
        let ri = wi.r.inverse() * ti.r;
        let ra = wa.r.inverse() * ta.r;
        let pi = wi.r.inverse_transform_vector(&(ti.t - wi.t));
        let pa = wa.r.inverse_transform_vector(&(ta.t - wa.t));
        PoseError {
            position: pa - pi,
            orientation: rotation_vector(&(ra * ri.inverse())),
        }
    }

    /// Exact pose error from the POE form (reference implementation, slower).
    ///
    /// # Panics
    /// As [`Machine::branch_poses`].
    pub fn pose_error_poe(&self, q: &[f64], e: &[f64]) -> PoseError {
        let gi = self.tool_in_workpiece_poe(q, &[]);
        let ga = self.tool_in_workpiece_poe(q, e);
        PoseError {
            position: ga.translation.vector - gi.translation.vector,
            orientation: rotation_vector(&(ga.rotation * gi.rotation.inverse())),
        }
    }

    /// First-order pose error `J(q) · e` (computes J; for many error sets at one pose
    /// keep the [`Jacobian`] and call [`Jacobian::apply`]).
    ///
    /// # Panics
    /// As [`Machine::branch_poses`]; `e` must have `n_slots()` entries.
    pub fn pose_error_first_order(&self, q: &[f64], e: &[f64]) -> PoseError {
        self.jacobian(q).apply(e)
    }

    /// Analytic Jacobian of the pose error with respect to every slot at e = 0.
    ///
    /// Each slot's unit twist (a translation along, or rotation about, an axis of the frame
    /// where the error sits) is carried into the workpiece frame by the adjoint of that
    /// frame's pose F in the workpiece frame: a translation δ_k gives position `R_F e_k`; a
    /// rotation ε_k gives orientation `R_F e_k` and position `(R_F e_k) × (p_tip − p_F)`.
    /// Slots on the workpiece branch enter with a negative sign (their frame moves the
    /// workpiece, not the tool); slots on bodies shared by both branches cancel (zero).
    ///
    /// # Panics
    /// If `q.len() != axes().len()`.
    pub fn jacobian(&self, q: &[f64]) -> Jacobian {
        let mut m = DMat::zeros(6, self.slots.len());
        self.jacobian_into(q, &mut m);
        Jacobian { matrix: m }
    }

    /// [`Machine::jacobian`] into a preallocated 6 × n_slots matrix (no allocation).
    ///
    /// # Panics
    /// If `q.len() != axes().len()` or `out` is not 6 × n_slots.
    pub fn jacobian_into(&self, q: &[f64], out: &mut DMat) {
        self.check_inputs(q, &[]);
        assert_eq!(out.shape(), (6, self.slots.len()), "jacobian output shape");
        out.fill(0.0);
        let (w, _) = self.chain_pair(&self.wp_chain, q, &[]);
        let (t, _) = self.chain_pair(&self.tool_chain, q, &[]);
        let winv_r = w.r.inverse();
        let tip = winv_r * (t.t - w.t);
        for (chain, sign) in [(&self.tool_chain, 1.0), (&self.wp_chain, -1.0)] {
            let mut f = Frame::IDENTITY;
            for &j in chain.iter() {
                let c = &self.consts[j];
                let shared = self.bodies[j].branch == Branch::Shared;
                f.translate(&self.bodies[j].offset_mm);
                if let (Some(s), false) = (c.pos_slot, shared) {
                    self.fill_columns(out, s, &f, &w, winv_r, &tip, sign);
                }
                if let Some((kind, u, k)) = &c.joint {
                    match kind {
                        AxisKind::Linear => f.translate(&(u * q[*k])),
                        AxisKind::Rotary => f.rotate(&axis_rotation(u, q[*k])),
                    }
                }
                if let (Some(s), false) = (c.mot_slot, shared) {
                    self.fill_columns(out, s, &f, &w, winv_r, &tip, sign);
                }
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn fill_columns(
        &self,
        out: &mut DMat,
        start: usize,
        f: &Frame,
        w: &Frame,
        winv_r: UnitQuaternion<f64>,
        tip: &Vec3,
        sign: f64,
    ) {
        // pose of the error frame in the workpiece frame
        let rf = (winv_r * f.r).to_rotation_matrix();
        let pf = winv_r * (f.t - w.t);
        let arm = tip - pf;
        for k in 0..3 {
            let axis = rf.matrix().column(k).into_owned() * sign;
            let mut col = out.column_mut(start + k);
            col[0] = axis.x;
            col[1] = axis.y;
            col[2] = axis.z;
            let pos = axis.cross(&arm);
            let mut col = out.column_mut(start + 3 + k);
            col[0] = pos.x;
            col[1] = pos.y;
            col[2] = pos.z;
            col[3] = axis.x;
            col[4] = axis.y;
            col[5] = axis.z;
        }
    }
}
