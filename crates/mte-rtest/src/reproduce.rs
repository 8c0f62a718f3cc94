//! Reproduction of seed 002 (Spaan-Burke et al.): Table 2 (two ball positions), the BK4
//! compensation story and Tables 3–4 (thermal drift), on the library machine
//! `seed002-bc-trunnion`. `cargo xtask reproduce seed002` writes [`seed002`] to
//! `docs/reproduction/seed002.md`.

use crate::compensate::{Bk4Range, corrected_controller, predict_bk4};
use crate::error::Result;
use crate::identify::{Fit, FitSpec, identify, setup_consistency};
use crate::model::ErrorField;
use crate::names::slot_by_name;
use crate::program::Program;
use crate::simulate::{PlanItem, SetupSpec, SimOptions, simulate};
use crate::thermal::track;
use mte_kinematics::Machine;
use mte_linalg::Vec3;
use std::fmt::Write;

const MACHINE: &str = "seed002-bc-trunnion";

fn set(m: &Machine, e: &mut [f64], name: &str, v: f64) -> Result<()> {
    e[slot_by_name(m, name)?.slot] = v;
    Ok(())
}

/// The Table 2 / BK4 truth: B and C location errors plus a Y straightness δz(y) = α·y (Y sags
/// in Z while moving out, the paper's diagnosis) and δx(y) = γ·y.
struct Truth {
    base: Vec<f64>,
    yi: usize,
    sz: usize,
    sx: usize,
    alpha: f64,
    gamma: f64,
}

impl Truth {
    fn field(&self) -> impl Fn(&[f64], f64) -> Vec<f64> + '_ {
        move |q: &[f64], _t: f64| {
            let mut e = self.base.clone();
            e[self.sz] += self.alpha * q[self.yi];
            e[self.sx] += self.gamma * q[self.yi];
            e
        }
    }
}

/// BK1 at both ball positions (Table 2): C held at 180° (ball at Y = −177 mm) and at 0°.
fn two_positions(m: &Machine) -> Result<Vec<PlanItem>> {
    let ball = Vec3::from(BALL);
    Ok(vec![
        PlanItem {
            setup: SetupSpec::new("Y-177", ball).centred_at("C", 180.0),
            programs: vec![Program::bk1(m, None)?.with_hold("C", 180.0)],
        },
        PlanItem {
            setup: SetupSpec::new("Y+177", ball),
            programs: vec![Program::bk1(m, None)?],
        },
    ])
}

/// Ball position on the table (0, 177, 60) mm: 60 mm above the table, 177 mm off the C axis.
const BALL: [f64; 3] = [0.0, 177.0, 60.0];

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
    ctrl[slot_by_name(m, "EA0B")?.slot] += delta_rad;
    ctrl[slot_by_name(m, "EZ0B")?.slot] -= delta_rad * y_mm;
    Ok(())
}

/// The BK4 results of the paper's compensation sequence for a session at `c_deg`.
struct Story {
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
    let slot = |nm: &str| slot_by_name(m, nm).map(|s| s.slot);
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

fn um(v: f64) -> f64 {
    v * 1e3
}
fn deg(v: f64) -> f64 {
    v.to_degrees()
}

/// The seed-002 reproduction report (Markdown). Deterministic (fixed seeds).
///
/// # Errors
/// Any simulation or fit error (none expected on the library machine).
pub fn seed002_report() -> Result<String> {
    let m = Machine::library(MACHINE).map_err(|e| crate::RtestError::Kinematics(e.to_string()))?;
    let n = m.n_slots();
    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(
        w,
        "# Seed 002 — R-test: two ball positions, BK4 compensation, thermal drift\n"
    );
    let _ = writeln!(
        w,
        "Generated by `cargo xtask reproduce seed002` (`mte_rtest::reproduce::seed002`). Machine: `{MACHINE}` (B tilt about Y carrying a C table; chain bed–Y–X–Z–tool). All data are simulated with the exact kinematics and Gaussian sensor noise; the fits never see the generator's error list.\n"
    );
    let _ = writeln!(w, "## Assumptions (the paper is silent on these)\n");
    let _ = writeln!(
        w,
        "- Ball at table coordinates (0, 177, 60) mm (60 mm above the table, 177 mm off the C axis along table +Y); nest at the tool point; each setup starts with a centring (ball position = actual nest position at the centring pose)."
    );
    let _ = writeln!(
        w,
        "- BK1: B 0 → +90° → −90° → 0 at 12°/s, 2° steps. BK2: C 0 → 360° → 0. BK4: B −90° → +90° → −90° with C = 2·(B + 90°). Sensor noise σ = 0.5 µm per component; a random sensor zero (σ 5 µm) per setup, fitted as nuisance."
    );
    let _ = writeln!(
        w,
        "- The cause found in the paper (\"the Y axis sags in Z while moving out in Y\") is modelled as a Y straightness δz(y) = α·y; the 3.5 µm XOB difference as δx(y) = γ·y. The single-position results are BK1 fits of (EX0B, EZ0B, EA0B, EC0B) + sensor zero.\n"
    );

    // ---------------- Table 2 ----------------
    let alpha0 = 0.0186 / 354.0;
    let gamma0 = 0.0035 / 354.0;
    let mut base = vec![0.0; n];
    set(&m, &mut base, "EX0B", 0.00235)?;
    set(&m, &mut base, "EZ0B", -0.0096)?;
    set(&m, &mut base, "EA0B", 0.00035f64.to_radians())?;
    set(&m, &mut base, "EC0B", (-0.00005f64).to_radians())?;
    let yi = m.axis_index("Y").unwrap_or(1);
    let sz = m
        .slot_index_by_name("Y.motion.dz")
        .ok_or_else(|| crate::RtestError::Kinematics("no Y.motion.dz slot".into()))?;
    let sx = m
        .slot_index_by_name("Y.motion.dx")
        .ok_or_else(|| crate::RtestError::Kinematics("no Y.motion.dx slot".into()))?;
    let spec_b = FitSpec::pivots(&m)?.only(&m, &["EX0B", "EZ0B", "EA0B", "EC0B"])?;
    let opts = SimOptions {
        noise_sd_mm: 0.0005,
        sensor_zero_sd_mm: 0.005,
        seed: 2002,
        ..Default::default()
    };
    // orientation of the sag: Table 2 has the lower ZOB at Y = −177 and the higher XOB there;
    // the signs of α and γ are set from a noise-free probe so the generator matches that
    let probe = |alpha: f64, gamma: f64| -> Result<(f64, f64)> {
        let t = Truth {
            base: base.clone(),
            yi,
            sz,
            sx,
            alpha,
            gamma,
        };
        let sim = simulate(
            &m,
            &two_positions(&m)?,
            &t.field(),
            &SimOptions {
                noise_sd_mm: 0.0,
                ..Default::default()
            },
        )?;
        let c = setup_consistency(&m, &sim.dataset, &spec_b)?;
        let get = |l: &str| {
            c.values
                .iter()
                .find(|v| v.0 == l)
                .map(|v| v.1[0].0 - v.1[1].0)
                .unwrap_or(0.0)
        };
        Ok((get("EX0B"), get("EZ0B")))
    };
    let (dx, dz) = probe(alpha0, gamma0)?;
    let alpha = if dz < 0.0 { alpha0 } else { -alpha0 };
    let gamma = if dx > 0.0 { gamma0 } else { -gamma0 };
    let truth = Truth {
        base: base.clone(),
        yi,
        sz,
        sx,
        alpha,
        gamma,
    };
    let sim = simulate(&m, &two_positions(&m)?, &truth.field(), &opts)?;
    let cons = setup_consistency(&m, &sim.dataset, &spec_b)?;
    let _ = writeln!(w, "## Table 2 — BK1 at Y = −177 and Y = +177 mm\n");
    let _ = writeln!(
        w,
        "Generator: EX0B = 2.35 µm, EZ0B = −9.6 µm, EA0B = 0.00035°, EC0B = −0.00005° (the means of the paper's two rows), α = {:+.1} µrad ({:+.4}°), γ = {:+.1} µrad.\n",
        alpha * 1e6,
        deg(alpha),
        gamma * 1e6
    );
    let _ = writeln!(
        w,
        "| ball at | XOB µm (paper / ours) | ZOB µm | AOB ° | COB ° |\n|---|---|---|---|---|"
    );
    let paper = [
        ["4.1", "-18.9", "0.0005", "-0.0002"],
        ["0.6", "-0.3", "0.0002", "0.0001"],
    ];
    for (k, sid) in cons.setups.iter().enumerate() {
        let v = |l: &str| {
            cons.values
                .iter()
                .find(|x| x.0 == l)
                .map(|x| x.1[k])
                .unwrap_or((0.0, None))
        };
        let f = |l: &str, ang: bool| {
            let (x, u) = v(l);
            let (x, u) = if ang {
                (deg(x), u.map(deg).unwrap_or(0.0))
            } else {
                (um(x), u.map(um).unwrap_or(0.0))
            };
            if ang {
                format!("{x:.4} ± {u:.4}")
            } else {
                format!("{x:.1} ± {u:.1}")
            }
        };
        let _ = writeln!(
            w,
            "| {sid} | {} / {} | {} / {} | {} / {} | {} / {} |",
            paper[k][0],
            f("EX0B", false),
            paper[k][1],
            f("EZ0B", false),
            paper[k][2],
            f("EA0B", true),
            paper[k][3],
            f("EC0B", true)
        );
    }
    let spread = |l: &str| {
        cons.spread
            .iter()
            .find(|s| s.0 == l)
            .map(|s| (s.1, s.2))
            .unwrap_or((0.0, 0.0))
    };
    let _ = writeln!(
        w,
        "| max − min | 3.5 / {:.1} | 18.6 / {:.1} | 0.0003 / {:.4} | 0.0003 / {:.4} |\n",
        um(spread("EX0B").0),
        um(spread("EZ0B").0),
        deg(spread("EA0B").0),
        deg(spread("EC0B").0)
    );
    let _ = writeln!(
        w,
        "Consistency z-scores (difference / combined uncertainty): {}. Parameters disagreeing beyond 5σ: {:?} — a single B pivot line cannot explain both positions.\n",
        cons.spread
            .iter()
            .map(|s| format!("{} {:.0}", s.0, s.2))
            .collect::<Vec<_>>()
            .join(", "),
        cons.inconsistent(5.0)
    );
    let joint = identify(&m, &sim.dataset, &spec_b)?;
    let ea = joint
        .get("EA0B")
        .map(|e| (e.value, e.std_uncertainty.unwrap_or(0.0)))
        .unwrap_or((0.0, 0.0));
    let _ = writeln!(
        w,
        "Joint two-position fit (same four parameters): EA0B = {:.4}° ± {:.4}° (paper: 0.019/354 rad = 0.0031°, corrected by 0.003°); EZ0B = {:.1} µm (generator −9.6 µm). The relative B/Y squareness is found without being in the parameter list.\n",
        deg(ea.0),
        deg(ea.1),
        um(joint.get("EZ0B").map(|e| e.value).unwrap_or(0.0))
    );

    // ---------------- BK4 story ----------------
    let _ = writeln!(w, "## BK4 before and after compensation (Figs. 5–7, 9)\n");
    // C pivot errors added to the Table-2 truth; their size is set so that the uncompensated BK4
    // range (single-position session at C = 180°) is the measured 69 µm (bisection on one scale
    // factor) — everything after is predicted
    let c_dir = [("EX0C", 1.0), ("EY0C", -1.3)];
    let bk4_for = |k: f64| -> Result<(Truth, f64)> {
        let mut b = base.clone();
        for (nm, f) in c_dir {
            set(&m, &mut b, nm, k * f * 1e-3)?;
        }
        set(&m, &mut b, "EA0C", 0.0004f64.to_radians())?;
        set(&m, &mut b, "EB0C", (-0.0003f64).to_radians())?;
        let t = Truth {
            base: b,
            yi,
            sz,
            sx,
            alpha,
            gamma,
        };
        let r = predict_bk4(&m, &t.field(), &[], &session(&m, SINGLE_C_DEG)?.setup)?.max_range_um;
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
    let f4 = t4.field();
    let _ = writeln!(
        w,
        "Generator adds EX0C = {:.1} µm, EY0C = {:.1} µm, EA0C = 0.0004°, EB0C = −0.0003° to the Table-2 truth (C pivot size scaled so the uncompensated BK4 range is 69 µm).\n",
        0.5 * (lo + hi),
        -1.3 * 0.5 * (lo + hi)
    );
    let main = bk4_story(&m, &f4, SINGLE_C_DEG, &opts)?;
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
                let ang = matches!(&e.kind, crate::ParamKind::Slot(s) if s.angular);
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
    // the same sequence on the Y-axis errors alone (no pivot or tilt errors) shows the mechanism
    let sag = Truth {
        base: vec![0.0; n],
        yi,
        sz,
        sx,
        alpha,
        gamma,
    };
    let sag_main = bk4_story(&m, &sag.field(), SINGLE_C_DEG, &opts)?;
    let sag_other = bk4_story(&m, &sag.field(), 0.0, &opts)?;
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
    let other = bk4_story(&m, &f4, 0.0, &opts)?;
    let _ = writeln!(
        w,
        "Hypotheses tried (same generator; BK4 in the same setup as the session):\n\n| single-position session | none | pivots only | + squareness | AOB + δ only | and AOC kept | and line turned about the measured point |\n|---|---|---|---|---|---|---|"
    );
    for (name, st) in [
        ("C = 180° (ball at Y = −177 mm), used above", &main),
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

    // ---------------- Tables 3–4 ----------------
    let _ = writeln!(
        w,
        "## Tables 3–4 — thermal drift from repeated BK1 + BK2 cycles\n"
    );
    let _ = writeln!(
        w,
        "Generator: every location error follows the paper's values at t = 0, 5 and 30 min, joined linearly in time (held after 30 min); a cycle (centring, BK1, BK2, 6° steps) starts every 100 s for 30 min, each fitted on its own (8 location errors + sensor zero).\n"
    );
    let tab: [(&str, [f64; 3], bool); 8] = [
        ("EX0B", [-17.7, -18.6, -22.7], false),
        ("EZ0B", [-29.8, -30.9, -41.0], false),
        ("EA0B", [-0.0073, -0.0071, -0.0071], true),
        ("EC0B", [-0.0091, -0.0091, -0.0100], true),
        ("EX0C", [-17.9, -21.1, -27.4], false),
        ("EY0C", [-31.9, -32.6, -39.0], false),
        ("EA0C", [-0.0005, -0.0006, -0.0008], true),
        ("EB0C", [0.0002, 0.0003, 0.0002], true),
    ];
    let slots: Vec<usize> = tab
        .iter()
        .map(|t| slot_by_name(&m, t.0).map(|s| s.slot))
        .collect::<Result<_>>()?;
    let interp = |v: &[f64; 3], t: f64| -> f64 {
        let tm = t / 60.0;
        if tm <= 5.0 {
            v[0] + (v[1] - v[0]) * tm / 5.0
        } else {
            v[1] + (v[2] - v[1]) * ((tm - 5.0) / 25.0).min(1.0)
        }
    };
    let thermal = |_q: &[f64], t: f64| -> Vec<f64> {
        let mut e = vec![0.0; n];
        for (k, (_, v, ang)) in tab.iter().enumerate() {
            let x = interp(v, t);
            e[slots[k]] = if *ang { x.to_radians() } else { x * 1e-3 };
        }
        e
    };
    let ball = Vec3::from(BALL);
    let plan: Vec<PlanItem> = (0..19)
        .map(|c| -> Result<PlanItem> {
            Ok(PlanItem {
                setup: SetupSpec::new(&format!("cycle{c:02}"), ball),
                programs: vec![
                    Program::bk1(&m, None)?.with_step(6.0),
                    Program::bk2(&m)?.with_step(6.0),
                ],
            })
        })
        .collect::<Result<_>>()?;
    // cycles start every 100 s: the gap after each cycle pads it to 100 s
    let mut ds = None;
    let mut all = crate::model::Dataset {
        machine: String::new(),
        axis_names: vec![],
        setups: vec![],
        readings: vec![],
        note: String::new(),
    };
    for (c, item) in plan.iter().enumerate() {
        let o = SimOptions {
            start_t_s: 100.0 * c as f64,
            seed: 3000 + c as u64,
            ..opts.clone()
        };
        let s = simulate(&m, std::slice::from_ref(item), &thermal, &o)?;
        let off = all.setups.len();
        all.machine = s.dataset.machine.clone();
        all.axis_names = s.dataset.axis_names.clone();
        all.setups.extend(s.dataset.setups);
        all.readings
            .extend(s.dataset.readings.into_iter().map(|mut r| {
                r.setup += off;
                r
            }));
        ds = Some(());
    }
    let _ = ds;
    let (_fits, series) = track(&m, &all, &FitSpec::pivots(&m)?)?;
    let _ = writeln!(
        w,
        "| parameter | t = 0 paper / ours | t = 5 min | t = 30 min | max − min paper / ours | linear drift per 30 min | exponential τ (min) |\n|---|---|---|---|---|---|---|"
    );
    for (k, (name, v, ang)) in tab.iter().enumerate() {
        let s = &series[k];
        let conv = |x: f64| if *ang { deg(x) } else { um(x) };
        let at = |t: f64| {
            s.t_s
                .iter()
                .position(|&x| (x - t).abs() < 1.0)
                .map(|i| conv(s.values[i]))
                .unwrap_or(f64::NAN)
        };
        let prec = if *ang { 4 } else { 1 };
        let unit = if *ang { "°" } else { " µm" };
        let tau = s
            .exponential
            .as_ref()
            .map(|e| format!("{:.0}", e.tau_s / 60.0))
            .unwrap_or_else(|| "—".into());
        let _ = writeln!(
            w,
            "| {name} ({}) | {:.p$} / {:.p$} | {:.p$} / {:.p$} | {:.p$} / {:.p$} | {:.p$} / {:.p$} | {:+.p$}{unit} | {tau} |",
            slot_by_name(&m, name)?.ibs.unwrap_or_default(),
            v[0],
            at(0.0),
            v[1],
            at(300.0),
            v[2],
            at(1800.0),
            v[2] - v[0],
            at(1800.0) - at(0.0),
            conv(s.linear.a * 1800.0),
            p = prec
        );
    }
    let _ = writeln!(
        w,
        "\nPivot positions drift by tens of µm while the orientations change by less than 0.001°, as in the paper, and the cycle fits recover the pivot drifts to about 1–2 µm. The larger deviations (ZOB and AOC at 30 min) come from fitting each cycle at one ball position, where EZ0B/EA0B and EY0C/EA0C are only weakly separable (see the identifiability report of `mte rtest identify`), and from the drift during each 65 s cycle. The generator is piecewise linear in time, so neither drift model is exact; the linear model is the better description here."
    );
    Ok(out)
}

/// [`seed002_report`] as a string; a failure is reported inside the text.
pub fn seed002() -> String {
    seed002_report().unwrap_or_else(|e| format!("# Seed 002\n\ngeneration failed: {e}\n"))
}

#[cfg(test)]
mod tests {
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
                let p = crate::kin::apply(&w0.inverse(), &Vec3::new(0.0, yy, 0.0));
                crate::kin::apply(&m.branch_poses(&q, e).workpiece_in_base, &p)
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
