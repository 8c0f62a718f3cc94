//! The BK4 sections of the seed 002 page: the compensation sequence (Figs. 5–7, 9), its mechanism
//! shown on the Y sag alone, and the hypotheses tried.

use super::{BALL, Truth, deg, set, um};
use mte_kinematics::Machine;
use mte_linalg::Vec3;
use mte_rtest::Result;
use mte_rtest::compensate::{Bk4Range, corrected_controller, predict_bk4};
use mte_rtest::identify::{Fit, FitSpec, identify};
use mte_rtest::model::ErrorField;
use mte_rtest::names::slot_by_name;
use mte_rtest::program::Program;
use mte_rtest::simulate::{PlanItem, SetupSpec, SimOptions, simulate};
use std::fmt::Write;

/// C angle of the single-position session (C = 180° puts the ball at machine Y = −177 mm).
const SINGLE_C_DEG: f64 = 180.0;

/// One single-position session: centring with C at `c_deg`, then BK1 with C held there and BK2;
/// BK4 is run in the same setup.
fn session(m: &Machine, c_deg: f64) -> Result<PlanItem> {
    Ok(PlanItem {
        setup: SetupSpec::new(&format!("C{c_deg:.0}"), Vec3::from(BALL)).centred_at("C", c_deg),
        programs: vec![
            Program::bk1(m, None)?.with_hold("C", c_deg),
            Program::bk2(m)?,
        ],
    })
}

/// Tilts the controller's B line about X by `delta_rad` about its point at machine Y = `y_mm`
/// (where it was measured): EA0B += δ and, since EA0B turns the B body about the machine origin
/// (`T = P·ΔP·S(q)`), EZ0B −= δ·y so that the point at `y_mm` stays where it was.
fn tilt_b_line_about(m: &Machine, ctrl: &mut [f64], delta_rad: f64, y_mm: f64) -> Result<()> {
    ctrl[slot_by_name(m, "EA0B")?.slot()] += delta_rad;
    ctrl[slot_by_name(m, "EZ0B")?.slot()] -= delta_rad * y_mm;
    Ok(())
}

/// The BK4 results of the paper's compensation sequence for a session at `c_deg`.
pub(super) struct Story {
    none: Bk4Range,
    pivots: Bk4Range,
    squareness: Bk4Range,
    /// AOB + δ: only the EA0B slot; and EA0C − δ (AOC kept); and EZ0B − δ·y (line turned about
    /// the measured point).
    corrected: [Bk4Range; 3],
    two_position: Bk4Range,
    /// Only the fitted ZOB, only the fitted AOC.
    split: [Bk4Range; 2],
    fit: Fit,
    delta_rad: f64,
}

fn bk4_story<E: ErrorField + ?Sized>(
    m: &Machine,
    truth: &E,
    c_deg: f64,
    opts: &SimOptions,
) -> Result<Story> {
    let n = m.n_slots();
    let item = session(m, c_deg)?;
    let single = simulate(
        m,
        std::slice::from_ref(&item),
        truth,
        &SimOptions {
            seed: 2003,
            ..opts.clone()
        },
    )?;
    let spec8 = FitSpec::pivots(m)?;
    let fit = identify(m, &single.dataset, &spec8)?;
    let pivots = corrected_controller(&[], n, &fit, Some(&["EX0B", "EZ0B", "EX0C", "EY0C"]));
    let with_sq = corrected_controller(&[], n, &fit, None);
    // the same session plus BK1 at the other ball position (C turned by 180°)
    let other_c = (c_deg + 180.0) % 360.0;
    let plan = [
        item.clone(),
        PlanItem {
            setup: SetupSpec::new("other", Vec3::from(BALL)).centred_at("C", other_c),
            programs: vec![Program::bk1(m, None)?.with_hold("C", other_c)],
        },
    ];
    let two = simulate(
        m,
        &plan,
        truth,
        &SimOptions {
            seed: 2004,
            ..opts.clone()
        },
    )?;
    let fit2 = identify(m, &two.dataset, &spec8)?;
    let slot = |nm: &str| slot_by_name(m, nm).map(|s| s.slot());
    let (ea_b, ea_c, ez_b) = (slot("EA0B")?, slot("EA0C")?, slot("EZ0B")?);
    let delta_rad = fit2.get("EA0B").map(|e| e.value).unwrap_or(0.0) - with_sq[ea_b];
    // machine Y of the ball in the session: the point where the B line was measured
    let y_mm = BALL[1] * c_deg.to_radians().cos();
    let mut fix = [with_sq.clone(), with_sq.clone(), with_sq.clone()];
    fix[0][ea_b] += delta_rad;
    fix[1][ea_b] += delta_rad;
    fix[1][ea_c] -= delta_rad;
    tilt_b_line_about(m, &mut fix[2], delta_rad, y_mm)?;
    fix[2][ea_c] -= delta_rad;
    let bk4 = |c: &[f64]| predict_bk4(m, truth, c, &item.setup);
    let alone = |k: usize| {
        let mut c = vec![0.0; n];
        c[k] = with_sq[k];
        bk4(&c)
    };
    Ok(Story {
        none: bk4(&[])?,
        pivots: bk4(&pivots)?,
        squareness: bk4(&with_sq)?,
        corrected: [bk4(&fix[0])?, bk4(&fix[1])?, bk4(&fix[2])?],
        two_position: bk4(&corrected_controller(&[], n, &fit2, None))?,
        split: [alone(ez_b)?, alone(ea_c)?],
        fit,
        delta_rad,
    })
}

/// The compensation sequence: C pivot errors are added to the Table-2 `truth`, scaled so that the
/// uncompensated BK4 range is the measured 69 µm; every step after is predicted. Returns that
/// truth and the story of the session at C = 180°.
pub(super) fn compensation(
    w: &mut String,
    m: &Machine,
    truth: &Truth,
    opts: &SimOptions,
) -> Result<(Truth, Story)> {
    let _ = writeln!(w, "## BK4 before and after compensation (Figs. 5–7, 9)\n");
    // C pivot errors added to the Table-2 truth; their size is set so that the uncompensated BK4
    // range (single-position session at C = 180°) is the measured 69 µm (bisection on one scale
    // factor) — everything after is predicted
    let c_dir = [("EX0C", 1.0), ("EY0C", -1.3)];
    let bk4_for = |k: f64| -> Result<(Truth, f64)> {
        let mut b = truth.base.clone();
        for (nm, f) in c_dir {
            set(m, &mut b, nm, k * f * 1e-3)?;
        }
        set(m, &mut b, "EA0C", 0.0004f64.to_radians())?;
        set(m, &mut b, "EB0C", (-0.0003f64).to_radians())?;
        let t = truth.with_base(b);
        let r = predict_bk4(m, &t.field(), &[], &session(m, SINGLE_C_DEG)?.setup)?.max_range_um;
        Ok((t, r))
    };
    let (mut lo, mut hi) = (0.0, 60.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if bk4_for(mid)?.1 < 69.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    let (t4, r0) = bk4_for(0.5 * (lo + hi))?;
    let _ = writeln!(
        w,
        "Generator adds EX0C = {:.1} µm, EY0C = {:.1} µm, EA0C = 0.0004°, EB0C = −0.0003° to the Table-2 truth (C pivot size scaled so the uncompensated BK4 range is 69 µm).\n",
        0.5 * (lo + hi),
        -1.3 * 0.5 * (lo + hi)
    );
    let main = bk4_story(m, &t4.field(), SINGLE_C_DEG, opts)?;
    let _ = writeln!(
        w,
        "Session: one setup, ball at table (0, 177, 60) mm centred with C = 180° (machine Y = −177 mm), then BK1 (C held at 180°), BK2 and BK4 in sequence. \"Pivots\" = XOB, ZOB, XOC, YOC; \"squareness\" adds AOB, COB, AOC, BOC; all from one joint fit of that session's BK1 + BK2. The last step adds to AOB the B/Y squareness of the two-position BK1 (δ = {:+.4}°, joint EA0B of both positions minus the single-position EA0B) and applies it as a controller would (see *Controller convention* below).\n",
        deg(main.delta_rad)
    );
    let _ = writeln!(
        w,
        "| compensation | paper µm | ours µm (max of X/Y/Z range) | X / Y / Z range µm |\n|---|---|---|---|"
    );
    for ((name, p), r) in [
        ("none", "69"),
        ("pivots only (single position)", "19"),
        ("pivots + squareness (single position)", "38.2"),
        ("as above, AOB corrected by δ", "15"),
        ("all 8 from the two-position joint fit", "—"),
    ]
    .iter()
    .zip([
        &main.none,
        &main.pivots,
        &main.squareness,
        &main.corrected[2],
        &main.two_position,
    ]) {
        let _ = writeln!(
            w,
            "| {name} | {p} | {:.1} | {:.1} / {:.1} / {:.1} |",
            r.max_range_um, r.range_um[0], r.range_um[1], r.range_um[2]
        );
    }
    let _ = writeln!(
        w,
        "\n(uncompensated range from the bisection: {r0:.1} µm.) Single-position fit: {}.\n",
        main.fit
            .kinematic()
            .map(|e| {
                let ang = matches!(&e.kind, mte_rtest::ParamKind::Slot(s) if s.angular);
                if ang {
                    format!("{} {:.4}°", e.label, deg(e.value))
                } else {
                    format!("{} {:.1} µm", e.label, um(e.value))
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        w,
        "Shape versus the paper: 69 → {:.1} → {:.1} (worse) → {:.1} µm against the paper's 69 → 19 → 38.2 → 15 µm (differences {:+.1}, {:+.1}, {:+.1} µm). Compensating all eight location errors from a joint fit of both positions gives {:.1} µm.\n",
        main.pivots.max_range_um,
        main.squareness.max_range_um,
        main.corrected[2].max_range_um,
        main.pivots.max_range_um - 19.0,
        main.squareness.max_range_um - 38.2,
        main.corrected[2].max_range_um - 15.0,
        main.two_position.max_range_um
    );
    Ok((t4, main))
}

/// The same sequence on the Y-axis errors of `truth` alone (no pivot or tilt errors): how the sag
/// becomes a false ZOB and a false AOC.
pub(super) fn mechanism(
    w: &mut String,
    m: &Machine,
    truth: &Truth,
    opts: &SimOptions,
) -> Result<()> {
    let n = m.n_slots();
    let alpha = truth.alpha;
    // the same sequence on the Y-axis errors alone (no pivot or tilt errors) shows the mechanism
    let sag = truth.with_base(vec![0.0; n]);
    let sag_main = bk4_story(m, &sag.field(), SINGLE_C_DEG, opts)?;
    let sag_other = bk4_story(m, &sag.field(), 0.0, opts)?;
    let xyz = |r: &Bk4Range| {
        format!(
            "{:.1} / {:.1} / {:.1}",
            r.range_um[0], r.range_um[1], r.range_um[2]
        )
    };
    let _ = writeln!(
        w,
        "Mechanism, shown on the Y-axis errors alone (δz = α·y, α = {:+.4}°, and δx = γ·y; no pivot or tilt errors), BK4 X / Y / Z ranges in µm:\n\n| session at | none | only the fitted ZOB | only the fitted AOC | pivots only | + squareness | AOB corrected by δ |\n|---|---|---|---|---|---|---|",
        deg(alpha)
    );
    for (name, st) in [
        ("Y = −177 mm (C = 180°)", &sag_main),
        ("Y = +177 mm (C = 0°)", &sag_other),
    ] {
        let _ = writeln!(
            w,
            "| {name} | {} | {} | {} | {} | {} | {} |",
            xyz(&st.none),
            xyz(&st.split[0]),
            xyz(&st.split[1]),
            xyz(&st.pivots),
            xyz(&st.squareness),
            xyz(&st.corrected[2])
        );
    }
    let _ = writeln!(
        w,
        "\n(1) BK1 at one ball position books the sag there, α·y, as a ZOB offset (fitted {:+.1} µm at Y = −177 mm, {:+.1} µm at Y = +177 mm, true 0). (2) In BK2 the ball circles through Y = ±177 mm, so the sag tilts the measured circle and the fit books it as a C-axis tilt (fitted AOC {:+.4}°, true 0). (3) BK4 (C = 2·(B + 90°)) passes B = 0 at C = 180°, the session's centring pose (ball at Y = −177 mm), and B = ±90° with the ball at Y = +177 mm. Pivots only: the sag there appears as a Z error of the same sign at B = −90° and B = +90°, range ≈ 2·177 mm·|α| = 18.6 µm — the paper's 19 µm (the fitted ZOB alone moves the uncompensated error from X into Z). (4) The false AOC is compensated as a tilt of C: in the C frame its correction is zero at the centring pose and ±2·177 mm·AOC on the opposite side of the C circle, and B turns that frame. With the session centred at C = 180°, the opposite side is BK4's B = ±90° (C = 0°, 360°), where the correction lands in X with opposite signs at the two ends, for an X error that does not exist: X range 4·177 mm·|AOC|, about twice the sag's Z range, while the sag stays in Z (the paper's 38.2 µm is twice its 19 µm). With the session centred at C = 0°, the correction is zero at B = ±90° and acts at B = 0 in Z, where the sag is, so the squareness step improves BK4. (5) The two-position BK1 exposes the sag as a B/Y squareness; correcting AOB by δ tilts the B line in the controller so that it follows the Y motion, which removes most of it in X and Z; the largest remaining range is in Y, because a B-line tilt also moves points lying off the B–Y plane in Y, which the Y sag does not.\n",
        um(sag_main.fit.get("EZ0B").map(|e| e.value).unwrap_or(0.0)),
        um(sag_other.fit.get("EZ0B").map(|e| e.value).unwrap_or(0.0)),
        deg(sag_main.fit.get("EA0C").map(|e| e.value).unwrap_or(0.0))
    );
    let _ = writeln!(
        w,
        "Controller convention (the paper is silent; our choice): compensation values are ISO 230-7 location errors, each orientation relative to the machine axes at B = C = 0, and a line is corrected about the point where it was measured. So correcting AOB by δ (i) keeps AOC as measured by BK2 (our EA0C slot is relative to the B body, so it is lowered by δ), and (ii) turns the B line about its point at the ball's Y = −177 mm, keeping the ZOB measured there (our EZ0B slot, at Y = 0, moves by −δ·y). Without these, the same δ gives the numbers of the next table.\n"
    );
    Ok(())
}

/// The sessions at C = 180° (`main`) and C = 0° side by side, with the partial AOB corrections.
pub(super) fn hypotheses(
    w: &mut String,
    m: &Machine,
    t4: &Truth,
    main: &Story,
    opts: &SimOptions,
) -> Result<()> {
    let other = bk4_story(m, &t4.field(), 0.0, opts)?;
    let _ = writeln!(
        w,
        "Hypotheses tried (same generator; BK4 in the same setup as the session):\n\n| single-position session | none | pivots only | + squareness | AOB + δ only | and AOC kept | and line turned about the measured point |\n|---|---|---|---|---|---|---|"
    );
    for (name, st) in [
        ("C = 180° (ball at Y = −177 mm), used above", main),
        ("C = 0° (ball at Y = +177 mm)", &other),
    ] {
        let _ = writeln!(
            w,
            "| {name} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} |",
            st.none.max_range_um,
            st.pivots.max_range_um,
            st.squareness.max_range_um,
            st.corrected[0].max_range_um,
            st.corrected[1].max_range_um,
            st.corrected[2].max_range_um
        );
    }
    let _ = writeln!(
        w,
        "\nWith the session at Y = +177 mm the squareness step *improves* BK4 (mechanism (4)), so the paper's \"worse\" is not obtained there; the paper's order (worse, then 15 µm after the AOB correction) needs the session at Y = −177 mm and the controller convention above. In a scan made while choosing this hypothesis (not regenerated here), real C tilts EA0C, EB0C anywhere within ±0.002° moved the pivots-only value between about 20 and 28 µm and left the other steps unchanged (the session fit absorbs them).\n"
    );

    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::MACHINE;
    use super::*;

    /// The B-line point at the measuring Y stays put (to second order in δ) at any B, while a
    /// point 100 mm further along the line moves by δ·100 mm — i.e. the line turned about it.
    #[test]
    fn b_line_tilt_keeps_the_measured_point() {
        let m = Machine::library(MACHINE).unwrap();
        let n = m.n_slots();
        let (delta, y) = (1e-4, -177.0);
        let mut c = vec![0.0; n];
        tilt_b_line_about(&m, &mut c, delta, y).unwrap();
        let bi = m.axis_index("B").unwrap();
        for b_deg in [0.0, 37.0, 90.0] {
            let mut q = vec![0.0; m.axes().len()];
            q[bi] = f64::to_radians(b_deg);
            // the B-line points at machine Y = y and y + 100 (nominal pose), carried by the table
            let on_line = |yy: f64, e: &[f64]| {
                let w0 = m.branch_poses(&q, &vec![0.0; n]).workpiece_in_base;
                let p = w0
                    .inverse()
                    .transform_point(&Vec3::new(0.0, yy, 0.0).into());
                m.branch_poses(&q, e)
                    .workpiece_in_base
                    .transform_point(&p)
                    .coords
            };
            let moved = (on_line(y, &c) - on_line(y, &vec![0.0; n])).norm();
            // second-order residue: δ²·|y| ≈ 2e-6 mm
            assert!(
                moved < 1e-5,
                "B = {b_deg}°: measured point moved {moved} mm"
            );
            let far = (on_line(y + 100.0, &c) - on_line(y + 100.0, &vec![0.0; n])).norm();
            approx::assert_relative_eq!(far, delta * 100.0, max_relative = 1e-3);
        }
    }

    /// The mechanism on a pure Y sag δz = α·y (noise-free): pivots only leaves the sag's Z range
    /// 2·177 mm·|α|; with the session at Y = −177 mm the false AOC adds an X range of twice that;
    /// at Y = +177 mm the squareness step improves BK4 instead.
    #[test]
    fn y_sag_alone_doubles_bk4_with_the_false_c_tilt() {
        let m = Machine::library(MACHINE).unwrap();
        let alpha = -0.0186 / 354.0;
        let sag = Truth {
            base: vec![0.0; m.n_slots()],
            yi: m.axis_index("Y").unwrap(),
            sz: m.slot_index_by_name("Y.motion.dz").unwrap(),
            sx: m.slot_index_by_name("Y.motion.dx").unwrap(),
            alpha,
            gamma: 0.0,
        };
        let opts = SimOptions {
            noise_sd_mm: 0.0,
            ..Default::default()
        };
        let sag_range_um = 2.0 * 177.0 * alpha.abs() * 1e3;
        let minus = bk4_story(&m, &sag.field(), 180.0, &opts).unwrap();
        // 1 µm: second-order terms and the small YOC the fit books from the sag
        assert!((minus.pivots.range_um[2] - sag_range_um).abs() < 1.0);
        assert!((minus.squareness.range_um[0] - 2.0 * sag_range_um).abs() < 1.0);
        let plus = bk4_story(&m, &sag.field(), 0.0, &opts).unwrap();
        assert!(plus.squareness.max_range_um < plus.pivots.max_range_um);
    }
}
