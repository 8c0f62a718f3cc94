//! Tables 3–4 of the seed 002 page: thermal drift of the location errors from repeated BK1 + BK2
//! cycles, fitted cycle by cycle and tracked in time.

use super::{BALL, deg, um};
use mte_kinematics::Machine;
use mte_linalg::Vec3;
use mte_rtest::Result;
use mte_rtest::identify::FitSpec;
use mte_rtest::names::slot_by_name;
use mte_rtest::program::Program;
use mte_rtest::simulate::{PlanItem, SetupSpec, SimOptions, simulate};
use mte_rtest::thermal::track;
use std::fmt::Write;

/// The generator (the paper's values at t = 0, 5 and 30 min, joined linearly), the 19 cycles, and
/// the table of fitted values, drifts and time constants.
pub(super) fn tables_3_4(w: &mut String, m: &Machine, opts: &SimOptions) -> Result<()> {
    let n = m.n_slots();
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
        .map(|t| slot_by_name(m, t.0).map(|s| s.slot()))
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
                    Program::bk1(m, None)?.with_step(6.0),
                    Program::bk2(m)?.with_step(6.0),
                ],
            })
        })
        .collect::<Result<_>>()?;
    // cycles start every 100 s: the gap after each cycle pads it to 100 s
    let mut all = mte_rtest::Dataset {
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
        let s = simulate(m, std::slice::from_ref(item), &thermal, &o)?;
        let off = all.setups.len();
        all.machine = s.dataset.machine.clone();
        all.axis_names = s.dataset.axis_names.clone();
        all.setups.extend(s.dataset.setups);
        all.readings
            .extend(s.dataset.readings.into_iter().map(|mut r| {
                r.setup += off;
                r
            }));
    }
    let (_fits, series) = track(m, &all, &FitSpec::pivots(m)?)?;
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
            slot_by_name(m, name)?.ibs.unwrap_or_default(),
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
    Ok(())
}
