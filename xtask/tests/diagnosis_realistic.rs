//! The diagnosis on realistic machines: every ordinary error present (random smooth functions
//! of random realistic size, random noise), the user's model stating them, hidden effects on
//! top. The generators (`xtask::realistic`) share no code with the engine; the diagnosis reads
//! only the files they write, and nothing in those files tells what is hidden.
//!
//! A few datasets per case, so CI stays short; the studies with hundreds of datasets are
//! `cargo xtask study all` and their figures are in `docs/diagnosis-studies.md`.

use xtask::realistic::Kind;
use xtask::studies::{self, Effect};

/// Seed of these tests' datasets (the studies use others).
const SEED: u64 = 2026;

/// The diagnosis, with the default settings, of the dataset `spec` writes from `seed`.
fn diagnosed(spec: &xtask::realistic::Spec, seed: u64) -> mte_diagnose::Diagnosis {
    truth_and_diagnosis(spec, seed, false).1
}

/// The truth of the dataset `spec` writes from `seed` and its diagnosis with the default
/// settings; with `state_noise`, the noise stated as the studies state it to an R-test, whose
/// manifest states none.
fn truth_and_diagnosis(
    spec: &xtask::realistic::Spec,
    seed: u64,
    state_noise: bool,
) -> (xtask::realistic::Truth, mte_diagnose::Diagnosis) {
    let dir = std::env::temp_dir().join(format!(
        "mte-test-{}-{}-{seed}",
        spec.kind.name(),
        std::process::id()
    ));
    let truth = xtask::realistic::write_spec(spec, seed, &dir).unwrap();
    let noise = state_noise.then(|| xtask::realistic::axis::stated_noise(truth.noise_um));
    let d = mte_diagnose::load_with_noise(&truth.manifest, noise)
        .unwrap()
        .diagnose(&mte_diagnose::DiagnoseParams::default())
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (truth, d)
}

/// The diagnosis, with the default settings, of the dataset of `manifest`.
fn diagnosed_manifest(manifest: &std::path::Path) -> mte_diagnose::Diagnosis {
    let p = mte_diagnose::load(manifest).unwrap();
    p.diagnose(&mte_diagnose::DiagnoseParams::default())
        .unwrap()
}

#[test]
fn clean_realistic_machines_rarely_yield_a_discovery() {
    // At a 5 % false-discovery rate, 2 or more discoveries among 12 clean datasets happen with
    // probability 0.12; 3 or more with 0.02.
    for (kind, n) in [
        (Kind::Axis, 12),
        (Kind::Tracker, 6),
        (Kind::TrackerTools, 4),
        (Kind::PointsTargets, 2),
        (Kind::Rtest, 4),
        (Kind::RtestHead, 4),
        (Kind::RtestAc, 4),
    ] {
        let f = studies::fdr(kind, n, SEED);
        assert_eq!(f.errors, 0, "{:?}: {:?}", kind, f.first_error);
        let allowed = if n >= 12 { 2 } else { 1 };
        assert!(
            f.with_finding <= allowed,
            "{kind:?}: {} of {n} clean datasets with a finding: {:?}",
            f.with_finding,
            f.names
        );
    }
}

#[test]
fn against_the_rtest_default_base_a_clean_machine_is_given_its_ordinary_errors_and_no_drift() {
    // The location-only base of R-test practice leaves out the component errors, squareness and
    // error motions every real machine has: the search finds those and names them as ordinary
    // errors. A clean machine gets no drift, and any other cause comes with what the data cannot
    // tell it from (a pitch at a free period with its other periods, a set-up offset with the
    // one it is confounded with) or qualified. (Before the ordinary errors went first and a drift
    // had to show between visits of a pose, such machines were given a pitch of Y at 1.17 mm
    // alone, a drift of EA0C or of EB0Z over one cycle.)
    let omit = xtask::realistic::BaseModel::Omit;
    let gentle = xtask::realistic::smooth::Waviness::Gentle;
    let f = studies::fdr_with(Kind::Rtest, 4, SEED, &omit, gentle);
    assert_eq!(f.errors, 0, "{:?}", f.first_error);
    assert_eq!(f.with_finding, f.n, "{:?}", f.names);
    assert!(
        f.other_names.iter().all(|(n, _)| !n.contains("drift")),
        "{:?}",
        f.other_names
    );
    for o in f.records.iter().filter_map(|r| r.outcome.as_ref().ok()) {
        for e in o.findings.iter().filter(|e| !e.ordinary) {
            assert!(
                !e.alternatives.is_empty() || o.qualified.contains(&e.name),
                "{} stated without a caveat",
                e.name
            );
        }
    }
    // A pivot drift on such machines is named and sized beside their ordinary errors.
    let c = &studies::power_with(Kind::Rtest, Effect::PivotDrift, &[10.0], 2, SEED, &omit)[0];
    assert_eq!(c.errors, 0);
    assert_eq!(c.named_right, c.n, "{:?}", c.names);
    assert_eq!(c.change_in_interval, Some(c.named_right), "{c:?}");
}

#[test]
fn a_pitch_fitting_what_missing_ordinary_errors_leave_is_passed_over() {
    // Against the R-test's location-only default base, two clean machines of the study (its
    // seed 1) were given a pitch of Y at 1.57 and 1.37 mm on positions some 6 mm apart, as a
    // caveated finding: a few dozen positions and hundreds of periods hold the structure the
    // ordinary errors the search had not yet found leave in the residuals. Fitted on the
    // residuals at some Y positions, its period chosen again there, it does not predict those
    // at the others: passed over, the structure left to the verdict.
    for index in [2, 6] {
        let seed = studies::dataset_seed(1, "fdr-rtest", index);
        let mut spec = xtask::realistic::Spec::new(Kind::Rtest, &[]);
        spec.base_model = xtask::realistic::BaseModel::Omit;
        let (_, d) = truth_and_diagnosis(&spec, seed, true);
        let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
        assert!(
            !names.iter().any(|n| n.starts_with("EYY periodic")),
            "{names:?}"
        );
        let passed = d.passed_over.iter().find(|p| p.name == "EYY periodic");
        assert!(
            passed.is_some_and(|p| p.axis == "Y" && p.ratio > 0.98),
            "{:?}",
            d.passed_over
        );
    }
}

#[test]
fn hidden_axis_effects_are_named_and_sized() {
    for (effect, size) in [(Effect::Pitch, 2.0), (Effect::Reversal, 1.5)] {
        let cells = studies::power(Kind::Axis, effect, &[size], 6, SEED);
        let c = &cells[0];
        assert_eq!(c.errors, 0);
        assert_eq!(
            c.named_right, c.n,
            "{effect:?} {size}: named right in {} of {}: {:?}",
            c.named_right, c.n, c.names
        );
        assert!(
            c.estimate_within_2u + 1 >= c.named_right,
            "{effect:?} {size}: within 2 u in {} of {}",
            c.estimate_within_2u,
            c.named_right
        );
    }
    // The screw expanding as the machine warms: the scale drifting and nothing else, its change
    // over the measured time within 2 u whatever form (linear, first-order) it is found in.
    let c = &studies::power(Kind::Axis, Effect::ScaleDrift, &[15.0], 6, SEED)[0];
    assert_eq!(c.errors, 0);
    assert_eq!(c.alone_explained, c.n, "{:?}", c.names);
    assert!(
        c.change_in_interval.is_some_and(|k| k + 1 >= c.named_right),
        "change within 2 u in {:?} of {}",
        c.change_in_interval,
        c.named_right
    );
}

#[test]
fn hidden_tracker_pitch_names_no_other_cause() {
    // Half the generator's target layouts are grids of 5–7 X positions, which cannot resolve a
    // 5–40 mm pitch at all: there the report must say so (its note on what the sampling along
    // X cannot show); whatever is found must be the pitch, and on the resolvable layouts it is
    // found.
    let cells = studies::power(Kind::Tracker, Effect::Pitch, &[3.0], 4, SEED);
    let c = &cells[0];
    assert_eq!(c.errors, 0);
    assert!(c.named_right >= 1, "{:?}", c.names);
    assert_eq!(
        c.named_right + c.out_of_reach,
        c.n,
        "missed without the report saying the sampling hides it: {} named, {} out of reach",
        c.named_right,
        c.out_of_reach
    );
    assert!(
        c.names
            .iter()
            .all(|(name, _)| name.starts_with("EXX periodic")),
        "another cause named: {:?}",
        c.names
    );
}

/// The power cell of `effect` at `size` on each R-test machine type (B/C and A/C trunnions,
/// B head over a C table; 2 datasets each): every
/// effect named, alone, the data explained; `sized` checks the sizes of those named.
fn named_alone_on_every_machine_type(
    effect: Effect,
    size: f64,
    sized: impl Fn(&studies::PowerCell) -> bool,
) {
    for kind in [Kind::Rtest, Kind::RtestHead, Kind::RtestAc] {
        let cells = studies::power(kind, effect, &[size], 2, SEED);
        let c = &cells[0];
        assert_eq!(c.errors, 0);
        assert_eq!(c.named_right, c.n, "{kind:?}: {:?}", c.names);
        assert_eq!(c.alone_explained, c.n, "{kind:?}: {:?}", c.names);
        assert!(sized(c), "{kind:?}: {c:?}");
    }
}

#[test]
fn a_pivot_drift_is_named_alone_and_sized_on_every_machine_type() {
    // The tilting axis' line drifts over repeated cycles: on the trunnions against the C line
    // (B's in X, A's in Y), on the head–table machine against the tool the head carries (its
    // pivot). The default model
    // has that location error, so the drift of it is the cause to name, and nothing else: the
    // drift's size must not hide the rotary axes' ordinary higher harmonics until a periodic
    // cause stands in for them, nor leave them as unexplained structure.
    named_alone_on_every_machine_type(Effect::PivotDrift, 20.0, |c| {
        c.estimate_within_2u + 1 >= c.named_right
    });
}

#[test]
fn a_spindle_growing_in_z_is_named_alone_and_beside_a_pivot_drift() {
    // The commonest thermal effect: the spindle grows as it warms, the tool point moves along
    // the spindle (on the head, turned with B). The R-test re-centres the ball at each set-up,
    // so the growth shows through the ball placed where the tool stood at the centring and
    // through its change during the set-up. Alone it is the tool's place drifting (EZ0[tool]),
    // on every machine type; with the B line drifting too, each is named (or, on the trunnion,
    // said not to be separable from what it is confounded with) and nothing else.
    named_alone_on_every_machine_type(Effect::SpindleDrift, 10.0, |c| {
        c.change_in_interval == Some(c.named_right)
    });
    named_or_inseparable_and_nothing_else(&combined_cell(Kind::Rtest, Effect::SpindleDrift, 4));
}

#[test]
fn a_first_order_drift_that_entered_in_linear_form_is_given_its_first_order_course() {
    // The spindle growing and the B line drifting at once, both with time constants of about
    // 3 000 s (the studies' combined cell, dataset 3). Alone, the Z drift's linear form explains
    // as much as its first-order one and enters first; a first-order drift of the same
    // displacement enters later and the final model lets it go again, undetermined beside the
    // linear one. The linear drift was then left carrying a course it does not have, with a
    // caveat that its course is neither linear nor first-order. The final model offers it its
    // first-order form: every drift found is first-order, with no such caveat.
    use xtask::realistic::Spec;
    let effects = [(Effect::PivotDrift, 10.0), (Effect::SpindleDrift, 10.0)];
    let seed = studies::dataset_seed(1, "combined-rtest-PivotDrift-10-SpindleDrift-10", 3);
    let spec = Spec::new(Kind::Rtest, &studies::hidden_of_seed(&effects, seed));
    let (truth, d) = truth_and_diagnosis(&spec, seed, true);
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(d.findings.len(), 2, "{names:?}");
    for f in &d.findings {
        assert!(
            matches!(
                f.family,
                mte_diagnose::Family::Drift {
                    time_constant_s: Some(_)
                }
            ),
            "{names:?}"
        );
    }
    // Nor is a linear drift one the Z drift cannot be told from.
    let z = d.findings.iter().find(|f| f.name.starts_with("EZ0"));
    assert!(
        z.is_some_and(|f| f.alternatives.iter().all(|a| !a.ends_with(" drift"))),
        "{:?}",
        z.map(|f| &f.alternatives)
    );
    assert!(
        d.compound
            .iter()
            .all(|c| !c.note.contains("neither linear")),
        "{:?}",
        d.compound
    );
    // The B line's drift in X, the spindle's in Z (named as the B line's, which the report says
    // it cannot tell from the tool's): each final value's 95 % interval holds the truth (the
    // sign is each parameter's own).
    for (effect, axis) in truth.effects.iter().zip(["EX0", "EZ0"]) {
        let f = d
            .findings
            .iter()
            .find(|f| f.name.starts_with(axis))
            .unwrap_or_else(|| panic!("no {axis} drift: {names:?}"));
        let e = &f.estimates[0];
        let i = e.interval.as_ref().expect("a first-order drift's interval");
        let holds = |v: f64| i.lower.is_none_or(|l| l <= v) && i.upper.is_none_or(|u| v <= u);
        assert!(
            holds(effect.value) || holds(-effect.value),
            "{}: {} ({:?}), truth {}",
            f.name,
            e.text,
            i,
            effect.value
        );
    }
}

#[test]
fn a_first_order_form_that_did_not_earn_its_time_constant_gives_way_to_the_linear_one() {
    // An axis' zero drifting linearly (the studies' coverage cell of 0.1 µm/min, dataset 13).
    // The first-order drift entered the search on a cross-validated RMS a little better than
    // the linear one's, though its time constant lowers χ² by about 2 only, far less than the
    // 6.63 a parameter more must earn; its final value was then stated for a drift that has
    // none. The final model takes the linear form and reports the rate, within 2 u of the truth.
    let effects = [(Effect::ZeroDrift, 0.1)];
    let seed = studies::dataset_seed(1, "power-axis-ZeroDrift-0.1", 13);
    let spec = xtask::realistic::Spec::new(Kind::Axis, &studies::hidden_of_seed(&effects, seed));
    let (truth, d) = truth_and_diagnosis(&spec, seed, false);
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["EXX offset drift"]);
    assert!(
        d.exchanged
            .iter()
            .any(|e| e.replaced == "EXX offset drift exp" && e.by == "EXX offset drift"),
        "{:?}",
        d.exchanged
    );
    let rate = &d.findings[0].estimates[0];
    let truth = &truth.effects[0];
    assert!(
        (rate.value - truth.value).abs() <= 2.0 * rate.uncertainty,
        "{}: truth {}",
        rate.text,
        truth.value
    );
    // Where a first-order drift of the zero would settle is stated beside it.
    assert!(d.findings[0].first_order.is_some());
}

/// In every dataset of a combined cell, each effect named or named among a finding's
/// alternatives the data cannot tell apart, and no finding that names none of them.
fn named_or_inseparable_and_nothing_else(c: &studies::CombinedCell) {
    assert_eq!(c.errors, 0);
    assert_eq!(
        c.effects_named + c.effects_as_alternative,
        c.effects.len() * c.n,
        "{}: {:?}",
        c.label(),
        c.names
    );
    assert_eq!(c.no_other, c.n, "{}: {:?}", c.label(), c.names);
}

#[test]
fn open_world_drift_that_rises_and_falls_is_reported_unexplained() {
    // A pivot drift that rises and falls over repeated R-test cycles has no candidate's shape:
    // the right answer is structure the library does not explain (with the nearest drift named
    // beside it), never a cause declared to explain the data, nor "no discrepancy". One dataset:
    // these multi-cycle datasets are the slowest to diagnose (the study runs many).
    let o = studies::openworld(Kind::Rtest, Effect::RiseFall, 15.0, 1, SEED);
    assert_eq!(o.errors, 0);
    assert_eq!(o.confident_wrong, 0, "{:?}", o.names);
    assert_eq!(o.nothing, 0, "{:?}", o.names);
}

#[test]
fn an_expansion_about_a_point_the_data_do_not_need_gives_way_to_a_simpler_drift() {
    // An axis' zero that rises and falls (open world): a search step may take the expansion
    // about a point (two coefficients, one time constant) for the part no single drift holds.
    // Once the model is complete, a simpler drift the data do not tell from it takes its place
    // (the exchange's parsimony), and what the data do not need leaves: no expansion is named.
    // (Seed 6 of `cargo xtask realistic axis 6 <dir> --hidden risefall 3`, a case where the
    // search took it.)
    let seed = 6;
    let hidden = studies::hidden_of_seed(&[(Effect::RiseFall, 3.0)], seed);
    let spec = xtask::realistic::Spec::new(Kind::Axis, &hidden);
    let d = diagnosed(&spec, seed);
    assert!(
        d.exchanged
            .iter()
            .any(|e| e.replaced.ends_with("about a point") && e.chi2_drop < 0.0),
        "{:?}",
        d.exchanged
    );
    assert!(
        d.findings
            .iter()
            .all(|f| !f.name.ends_with("about a point")),
        "{:?}",
        d.findings.iter().map(|f| &f.name).collect::<Vec<_>>()
    );
}

#[test]
fn an_expansion_about_a_point_standing_in_for_a_zero_that_rises_and_falls_is_qualified() {
    // The expansion about a point drifts the axis' zero as well as its scale. Where the search
    // keeps it for a zero that rises and falls (open world), the report must say that it and
    // any drift of the zero beside it are one drift of the zero of neither form — grouped by
    // the parameter they drift, not by their names' stems (seed 9: beside a linear drift of the
    // zero; seed 22: alone, with a smooth curve of the scale and the zero in time left over).
    // Before, both read as a thermal expansion that explains the data.
    for seed in [9, 22] {
        let hidden = studies::hidden_of_seed(&[(Effect::RiseFall, 3.0)], seed);
        let spec = xtask::realistic::Spec::new(Kind::Axis, &hidden);
        let d = diagnosed(&spec, seed);
        let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
        // The case this test is about: the expansion is among the findings.
        assert!(
            names.iter().any(|n| n.ends_with("about a point")),
            "seed {seed}: {names:?}"
        );
        for f in d
            .findings
            .iter()
            .filter(|f| f.name.ends_with("about a point"))
        {
            let qualified = d.compound.iter().any(|c| {
                c.findings.contains(&f.name)
                    && (c.note.contains("one drift of EXX offset")
                        || c.note.contains("drift of EXX scale and EXX offset"))
            });
            assert!(qualified, "seed {seed}: {names:?}\n{:#?}", d.compound);
        }
        assert!(
            d.findings
                .iter()
                .all(|f| d.compound.iter().any(|c| c.findings.contains(&f.name))),
            "seed {seed}: {names:?}\n{:#?}",
            d.compound
        );
    }
}

#[test]
fn an_error_of_two_axes_at_once_is_never_explained_by_a_named_cause() {
    // A Y positioning error growing from mid-Y at a rate that changes along X: no rigid-body
    // error of the axes has that shape, so the answer is structure the library does not
    // explain (the structure test of a Y error changing with X and Y jointly), never a cause
    // declared to explain the data. Its mean over X is an ordinary Y positioning error with a
    // kink, which the base's completion up to degree 15 holds; what is left of the joint part
    // is sometimes below the structure test's reach (at 5 µm, 21 of 30 datasets with base
    // seed 5 unexplained, 9 with nothing found; 23 and 7 with completions to degree 10): here
    // the third dataset, σ0 = 1.27.
    let o = studies::openworld(Kind::Tracker, Effect::TwoAxis, 5.0, 3, SEED);
    assert_eq!(o.errors, 0);
    assert_eq!(o.confident_wrong, 0, "{:?}", o.names);
    assert!(
        o.unexplained >= 2 && o.unexplained + o.nothing == o.n,
        "unexplained in {} of {}, nothing in {}",
        o.unexplained,
        o.n,
        o.nothing
    );
}

#[test]
fn a_sawtooth_is_never_a_sine_declared_to_explain_the_data() {
    // Open world on interferometer runs: a sawtooth positioning error of X (period 20–80 mm,
    // 15–25 irregular targets over 0.5–1 m) on top of every ordinary error. Found as one sine,
    // as sines at its harmonics or at their aliases: the report must say that they are one
    // error that is not a sine, or that the positions determine neither its period nor its
    // shape.
    let o = studies::openworld(Kind::Axis, Effect::Sawtooth, 2.0, 8, SEED);
    assert_eq!(o.errors, 0);
    assert_eq!(o.nothing, 0, "{:?}", o.names);
    assert_eq!(o.confident_wrong, 0, "{:?}", o.names);
}

/// A sawtooth pitch error (open world: no candidate has its shape) comes out as periodic
/// components at the period and its fractions, or at aliases of them on the irregular target
/// spacing; either way the report says they may be one non-sinusoidal error. A sinusoidal pitch
/// error gets no such sentence unless the search reported it at alias periods (then the
/// sentence is due: the positions cannot tell the two readings apart).
#[test]
fn harmonics_found_for_a_sawtooth_are_named_one_non_sinusoidal_error() {
    use xtask::realistic::{Hidden, Spec};
    // Whether a note calls components non-sinusoidal, and whether the first periodic finding
    // sits at the true period (within 2 u).
    let run = |hidden: Hidden, seed: u64, period_mm: f64| {
        let d = diagnosed(&Spec::new(Kind::Axis, &[hidden]), seed);
        let at_true_period = d
            .findings
            .iter()
            .find_map(|f| f.hyper_parameter.as_ref())
            .is_some_and(|h| (h.value - period_mm).abs() <= 2.0 * h.uncertainty);
        (
            d.notes.iter().any(|n| n.contains("that is not a sine")),
            at_true_period,
        )
    };
    let saw: usize = (0..3)
        .map(|s| {
            let period_mm = 25.0 + 5.0 * s as f64;
            let hidden = Hidden::Sawtooth {
                axis: 0,
                amplitude_um: 3.0,
                period_mm,
            };
            usize::from(run(hidden, SEED + s, period_mm).0)
        })
        .sum();
    let sine: Vec<(bool, bool)> = (0..3)
        .map(|s| {
            let period_mm = 25.0 + 5.0 * s as f64;
            let hidden = Hidden::Pitch {
                axis: 0,
                amplitude_um: 2.0,
                period_mm,
            };
            run(hidden, SEED + s, period_mm)
        })
        .collect();
    assert_eq!(saw, 3, "sawtooth named non-sinusoidal in {saw} of 3");
    assert!(
        sine.iter().any(|&(_, right)| right),
        "no sine pitch found at its period: {sine:?}"
    );
    assert!(
        sine.iter().all(|&(note, right)| !(note && right)),
        "a sine pitch found at its period called non-sinusoidal: {sine:?}"
    );
}

/// Against the full user model, an R-test cannot tell C's angular positioning at the low
/// harmonics, nor a B tilt, from the error motions and component errors the model has (with one
/// ball, a translation of the C line at each angle reproduces r·ε(c) exactly). A miss must then
/// be one the report owns up to: the cause listed as not separable, or its detection limit above
/// the effect's size (or not separable) at the effect's period.
#[test]
fn a_missed_rtest_effect_is_one_the_report_says_it_could_not_show() {
    for (effect, size, n) in [
        (Effect::AngularPositioning, 5.0, 3),
        (Effect::BTilt, 25.0, 2),
    ] {
        let c = &studies::power(Kind::Rtest, effect, &[size], n, SEED)[0];
        assert_eq!(c.errors, 0);
        let owned = c.named_right + c.named_as_alternative + c.out_of_reach + c.below_limit;
        assert_eq!(
            owned, c.n,
            "{effect:?} {size}: named {}, not separable {}, out of reach {}, below the limit {} of {}",
            c.named_right, c.named_as_alternative, c.out_of_reach, c.below_limit, c.n
        );
    }
}

/// On an R-test against the full user model, C's angular positioning is separated from the
/// base only through the orders the base stops at: the linear axes' higher orders along the
/// ball's circle reproduce almost all of it. A finding that names it must then carry that in
/// its uncertainty (the truth — the machine's total at the hidden harmonic — within 2 u), and
/// one those orders would hold is left out and listed as not separable. Base seed 1 is the
/// power study's: there, before the base's orders counted, the first dataset named it at
/// 11.9 ± 1.1 µrad against a true 8.1 µrad.
#[test]
fn an_effect_the_base_orders_could_hold_is_sized_with_them_or_owned_up_to() {
    let c = &studies::power(Kind::Rtest, Effect::AngularPositioning, &[10.0], 6, 1)[0];
    assert_eq!(c.errors, 0);
    assert_eq!(
        c.estimate_within_2u, c.named_right,
        "named {} of {}, within 2 u {}",
        c.named_right, c.n, c.estimate_within_2u
    );
    let owned = c.named_right + c.named_as_alternative + c.out_of_reach + c.below_limit;
    assert_eq!(
        owned, c.n,
        "named {}, not separable {}, out of reach {}, below the limit {} of {}",
        c.named_right, c.named_as_alternative, c.out_of_reach, c.below_limit, c.n
    );
}

/// The hidden pitch's true period (mm) and the diagnosis of dataset `index` of the axis' 2 µm
/// pitch power cell with base seed `base_seed`, against the user's model without it.
fn pitch_cell_dataset(base_seed: u64, index: usize) -> (f64, mte_diagnose::Diagnosis) {
    use xtask::realistic::Hidden;
    let (spec, seed) = studies::power_dataset(Kind::Axis, Effect::Pitch, 2.0, base_seed, index);
    let &[Hidden::Pitch { period_mm, .. }] = &spec.hidden[..] else {
        panic!("a pitch: {:?}", spec.hidden);
    };
    (period_mm, diagnosed(&spec, seed))
}

#[test]
fn a_component_held_by_another_leaves_and_the_one_that_stays_is_found_again_alone() {
    // Dataset 121 of the axis pitch coverage cell with base seed 3: the search ends with two
    // periodic components at periods that each hold part of the other on these positions; in
    // the complete model the base and one of them hold the other (its removal test gives
    // p = 1). Then the later one leaves, and
    // the one that stays is the pitch itself, its period chosen anew without the other, sized
    // within 2 u. (Dataset 179 of base seed 1 showed this before the completions had spans;
    // no dataset of that cell does now.)
    let (period_mm, d) = pitch_cell_dataset(3, 121);
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    // The situation this dataset is kept for: a component left the complete model, for its
    // removal test.
    assert!(
        d.pruned
            .iter()
            .any(|p| p.name == "EXX periodic #2"
                && matches!(p.reason, mte_diagnose::PruneReason::NotEarned { p_value, .. } if p_value >= 0.001)),
        "no component pruned (the dataset no longer shows the case): {:?}, findings {names:?}",
        d.pruned
    );
    assert_eq!(names, ["EXX periodic"], "notes {:?}", d.notes);
    assert_eq!(d.verdict, mte_diagnose::Verdict::Explained, "{:?}", d.notes);
    let f = &d.findings[0];
    let amplitude = f.estimates.iter().find(|e| e.name == "amplitude").unwrap();
    assert!(
        (amplitude.value.abs() - 2e-3).abs() <= 2.0 * amplitude.uncertainty,
        "amplitude {} ± {} mm against 0.002 mm",
        amplitude.value,
        amplitude.uncertainty
    );
    let period = f.hyper_parameter.as_ref().unwrap();
    assert!(
        (period.value - period_mm).abs() <= 2.0 * period.uncertainty,
        "period {} ± {} mm against {period_mm} mm",
        period.value,
        period.uncertainty
    );
    // No other period fits better than the one that stays (an ambiguity note's Δχ², relative
    // to it, are not below zero beyond rounding).
    let better: Vec<f64> = d
        .notes
        .iter()
        .flat_map(|n| n.split("Δχ² = ").skip(1))
        .filter_map(|s| s.split(',').next()?.parse::<f64>().ok())
        .filter(|&x| x < -1.0)
        .collect();
    assert!(
        better.is_empty(),
        "periods that fit better: {better:?}; {:?}",
        d.notes
    );
}

#[test]
fn every_cause_of_the_final_model_passes_its_removal_test_there() {
    // Seed 51 of a clean B/C trunnion against the R-test default base: in the final model the
    // base and the other causes hold a roll of Y (EBY poly2) the search had found, and it leaves.
    // The residual scatter grows with it, and a pitch of X (EBX poly1) that passed its removal
    // test in the search (p = 1.5e-6) fails it in the final model (p = 0.065): it leaves too,
    // as pruned, and no cause is reported that the final model's own test rejects.
    let mut spec = xtask::realistic::Spec::new(Kind::Rtest, &[]);
    spec.base_model = xtask::realistic::BaseModel::Omit;
    let d = diagnosed(&spec, 51);
    // The situation this dataset is kept for: a cause left the final model.
    assert!(
        d.pruned
            .iter()
            .any(|p| p.name == "EBY poly2" && p.reason == mte_diagnose::PruneReason::HeldByModel),
        "EBY poly2 not pruned (the dataset no longer shows the case): {:?}",
        d.pruned
    );
    let alpha = mte_diagnose::DiagnoseParams::default().alpha;
    for f in &d.findings {
        assert!(
            f.p_value_final < alpha,
            "{} stays at p = {} in the final model",
            f.name,
            f.p_value_final
        );
    }
    // It leaves for its test, with the p-value the test gave.
    assert!(
        d.pruned.iter().any(|p| p.name == "EBX poly1"
            && matches!(p.reason, mte_diagnose::PruneReason::NotSignificant { p_value } if p_value >= alpha)),
        "{:?}",
        d.pruned
    );
}

/// The combined study's cell of `kind` (several effects at once) whose last effect is `last`,
/// on `n` datasets.
fn combined_cell(kind: Kind, last: Effect, n: usize) -> studies::CombinedCell {
    let (kind, effects) = studies::combined_plan()
        .into_iter()
        .find(|c| c.0 == kind && c.1.last().is_some_and(|e| e.0 == last))
        .expect("a combined cell of the kind");
    studies::combined(
        kind,
        &effects,
        n,
        SEED,
        &xtask::realistic::BaseModel::Default,
    )
}

#[test]
fn a_pitch_a_reversal_and_a_drift_at_once_are_each_named_and_nothing_else() {
    let c = combined_cell(Kind::Axis, Effect::ZeroDrift, 6);
    assert_eq!(c.errors, 0);
    assert_eq!(c.all_named, c.n, "{}: {:?}", c.label(), c.names);
    assert_eq!(c.no_other, c.n, "{}: {:?}", c.label(), c.names);
    // Of 18 sizes, at 95 % coverage 3 or more outside 2 u happen with probability 0.06.
    assert!(
        c.within_2u + 2 >= c.effects_named,
        "{}: {} of {} within 2 u",
        c.label(),
        c.within_2u,
        c.effects_named
    );
}

#[test]
fn two_pivot_drifts_at_once_are_each_named_or_said_to_be_inseparable() {
    // The B and the C line both drift in X, each with its own time constant and sign. The lines
    // drifting the same way are, at first sight, the tool drifting the other way: the search's
    // exchange must put the pivots back where the tool stood in for them, and where the data
    // cannot tell the two apart the report must say so (a finding's alternatives).
    let c = combined_cell(Kind::Rtest, Effect::PivotDrift, 8);
    named_or_inseparable_and_nothing_else(&c);
    assert!(c.all_named + 2 >= c.n, "{}: {:?}", c.label(), c.names);
}

#[test]
fn two_lines_drifting_apart_are_named_as_the_two_lines() {
    // On the A/C trunnion the A and the C line drift in Y, each with its own time constant.
    // Entry by entry the search first takes their common part for the tool drifting, then needs
    // two forms of one line's drift for the rest: the reduction must find the two lines, which
    // say as much with one cause fewer, or split the tool's drift into the lines' (before,
    // half of these datasets gave the tool and a third cause). Where the lines' time constants
    // are too close for the data to need two, the tool's drift is what the data say, and the
    // lines are among what it cannot be told from.
    let c = combined_cell(Kind::RtestAc, Effect::PivotDrift, 4);
    assert_eq!(c.errors, 0);
    assert_eq!(
        c.effects_named + c.effects_as_alternative,
        2 * c.n,
        "{}: {:?}",
        c.label(),
        c.names
    );
    assert!(c.all_named + 1 >= c.n, "{}: {:?}", c.label(), c.names);
    assert!(c.within_2u == c.effects_named, "{c:?}");
}

#[test]
fn c_angular_positioning_on_3d_points_is_named_and_sized() {
    // 3-D points of a C table against the user's model without C's angular positioning (ECC):
    // the hidden harmonic and C's ordinary error motion about Z (harmonics 1–3 of a turn) are
    // all ECC's. The hidden one is named and, by the ECC finding nearest its frequency, sized
    // within 2 u (one miss of four allowed).
    let cells = studies::power(Kind::Points, Effect::AngularPositioning, &[20.0], 4, SEED);
    let c = &cells[0];
    assert_eq!(c.errors, 0);
    assert_eq!(c.named_right, c.n, "{:?}", c.names);
    assert!(c.estimate_within_2u + 1 >= c.n, "{:?}", c.names);
}

#[test]
fn a_harmonic_of_c_the_angles_cannot_resolve_does_not_stand_in_for_a_low_one() {
    // 3-D points of a C table at 24 angles, two set-ups' 12 each a few degrees off a 30° step,
    // against the user's model without ECC; hidden: 10 µrad at C's 4th harmonic, on top of its
    // ordinary 1st–3rd. Up to the 180th harmonic is scanned (the jitter hides the step), and a
    // harmonic far above what 24 angles resolve is a pattern of its own at them: on these two
    // datasets of the power study (base seed 1) ECC's best variant was such a pattern, and
    // since a cause was graded by its best variant alone, ECC entered at 105 and 112 per turn
    // and the like, six times, and the 4th was never tried on its own (sized 18.4 ± 0.45 and
    // 7.5 ± 0.19 µrad, by the finding nearest it, against the true 10). Its ordinary harmonics
    // are graded apart now and enter first, as every ordinary error does.
    use std::f64::consts::TAU;
    let work = std::env::temp_dir().join(format!("mte-test-ecc-{}", std::process::id()));
    for index in [35, 48] {
        let (spec, seed) =
            studies::power_dataset(Kind::Points, Effect::AngularPositioning, 10.0, 1, index);
        let r = studies::run_one(&spec, index, seed, &work);
        let o = r.outcome.as_ref().unwrap();
        let names: Vec<(&str, Option<f64>)> = o
            .findings
            .iter()
            .map(|f| (f.name.as_str(), f.period.map(|p| TAU / p)))
            .collect();
        let (v, u, t) = studies::scored(&r.effects[0], o).expect("named");
        assert!(
            (v - t).abs() <= 2.0 * u,
            "dataset {index}: {v:e} ± {u:e} against {t:e}; {names:?}"
        );
        assert!(
            names
                .iter()
                .all(|(_, per_turn)| per_turn.is_none_or(|k| k < 6.5)),
            "dataset {index}: {names:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn a_squareness_at_targets_apart_is_named_and_sized_against_the_reference_lines() {
    // 3-D points of realistic machines with 3–4 targets on a holder, against the full model
    // without the XY squareness: named alone, and within 2 u of ISO 230-1's angle between the
    // reference lines through the measured positions (a grid of 5 × 4 × 3; one miss of four
    // allowed). With Legendre's own polynomials, not orthogonal at 4–5 positions, a wavy
    // straightness's linear part went partly to its cubic and most of these were several u off.
    let cells = studies::power(Kind::PointsTargets, Effect::Squareness, &[30.0], 4, SEED);
    let c = &cells[0];
    assert_eq!(c.errors, 0);
    assert_eq!(c.named_right, c.n, "{:?}", c.names);
    assert_eq!(c.alone_explained, c.n, "{:?}", c.names);
    assert!(c.estimate_within_2u + 1 >= c.n, "{:?}", c.names);
}

#[test]
fn a_cause_takes_at_most_three_periodic_components() {
    // A sawtooth on tracker data with scattered targets shows many harmonics; one cause holds
    // at most three periodic components (pitch, a longer wave, a harmonic), each named once:
    // what the rest leaves is structure the report states, not a fourth sine.
    let o = studies::openworld(Kind::Tracker, Effect::Sawtooth, 3.0, 3, SEED);
    assert_eq!(o.errors, 0);
    assert_eq!(o.confident_wrong, 0, "{:?}", o.names);
    // (Names are counted over the datasets: one more than their number repeats in one.)
    assert!(
        o.names
            .iter()
            .all(|(name, count)| !name.contains(" #4") && *count <= o.n),
        "{:?}",
        o.names
    );
}

#[test]
fn wavier_ordinary_errors_on_a_tracker_are_completed_not_named() {
    // Clean tracker datasets whose ordinary errors have up to five waves over the stroke (the
    // studies' robustness rows): on these seeds a search that completed the base one block of
    // three degrees at a time, to degree 10, named a periodic error of 80–190 mm (4–5 waves
    // over the stroke), the shape of an ordinary error. The completion up to degree 15 on
    // densely sampled axes, all orders at once where no block alone is significant, holds them.
    let mut spec = xtask::realistic::Spec::new(Kind::Tracker, &[]);
    spec.waviness = xtask::realistic::smooth::Waviness::Wavy;
    for seed in [101, 114, 125] {
        let d = diagnosed(&spec, seed);
        let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
        assert!(names.is_empty(), "seed {seed}: {names:?}");
        assert!(
            d.base_completed.iter().any(|c| c.contains("P4-")),
            "seed {seed}: completed {:?}",
            d.base_completed
        );
    }
}

#[test]
fn a_rotary_tables_worm_gear_and_backlash_are_named_and_clean_tables_rarely_give_a_finding() {
    // ISO 230-2 runs of a C rotary table (arcsec) whose smooth angular positioning error — a
    // random function over a turn — the user's model holds up to the second harmonic: on clean
    // tables the diagnosis completes it and names nothing; a worm gear's tooth error of 5 µrad
    // (1″, 24–90 cycles per turn) is named and sized within 2 u, its period being exact.
    let f = studies::fdr(Kind::Rotary, 30, SEED);
    assert_eq!(f.errors, 0, "{:?}", f.first_error);
    assert!(f.with_finding <= 2, "{:?}", f.names);
    let c = &studies::power(Kind::Rotary, Effect::WormGear, &[5.0], 20, SEED)[0];
    assert_eq!(c.errors, 0);
    assert_eq!(c.named_right, c.n, "{:?}", c.names);
    // 20 datasets at a 95 % coverage: 16 or fewer within 2 u has probability 0.016.
    assert!(
        c.estimate_within_2u >= 17,
        "{} of {}",
        c.estimate_within_2u,
        c.n
    );
    // A worn worm drive: the tooth error and the backlash (5 µrad each) together, both named
    // and nothing else.
    let c = combined_cell(Kind::Rotary, Effect::RotaryReversal, 10);
    named_or_inseparable_and_nothing_else(&c);
    assert_eq!(c.all_named, c.n, "{:?}", c.names);
}

/// The bundled `fixtures/datasets/tracker-tools/` is what `cargo xtask realistic tracker-tools
/// 5 <dir> --hidden squareness 30` writes (checked file by file), and the diagnosis names its
/// XY squareness alone, within 2 u of the generator's truth (ISO 230-1's angle between the
/// axes' reference lines through the measured positions).
#[test]
fn the_bundled_tracker_tools_dataset_names_its_squareness() {
    const SEED: u64 = 5;
    let fixture =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/datasets/tracker-tools");
    let mut spec = xtask::realistic::Spec::new(
        Kind::TrackerTools,
        &[Effect::Squareness.hidden(30.0, &mut studies::spec_rng(SEED))],
    );
    spec.base_model = studies::user_model_lacking(Kind::TrackerTools, Effect::Squareness);
    let dir = std::env::temp_dir().join(format!("mte-tracker-tools-{}", std::process::id()));
    let truth = xtask::realistic::write_spec(&spec, SEED, &dir).unwrap();
    for f in [
        "manifest.json",
        "machine.json",
        "targets.csv",
        "lengths.csv",
    ] {
        assert!(
            std::fs::read(dir.join(f)).unwrap() == std::fs::read(fixture.join(f)).unwrap(),
            "{f} differs from the generator's: regenerate the fixture"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    let d = diagnosed_manifest(&fixture.join("manifest.json"));
    let report = mte_diagnose::report::markdown(&d, "tracker-tools");
    assert_eq!(d.findings.len(), 1, "{report}");
    let f = &d.findings[0];
    assert_eq!(f.name, "EC0Y", "{report}");
    let (e, t) = (&f.estimates[0], truth.effects[0].value);
    assert!(
        (e.value.abs() - t).abs() <= 2.0 * e.uncertainty,
        "{} against {t:e}",
        e.text
    );
}

#[test]
fn a_second_draw_of_the_noise_measures_the_same_machines_again() {
    // The coverage study's second draw: the same rotary tables with the same worm gears (the
    // same truth), read with other noise, so other estimates, which differ by about their
    // scatter (both u: a few tenths of a µrad against a 5 µrad gear).
    let spec_for = |rng: &mut rand_chacha::ChaCha8Rng| {
        xtask::realistic::Spec::new(Kind::Rotary, &[Effect::WormGear.hidden(5.0, rng)])
    };
    let [own, second] =
        [0, 1].map(|draw| studies::run_cell_drawn("test-second-draw", 4, SEED, draw, spec_for));
    for (a, b) in own.iter().zip(&second) {
        assert_eq!(a.effects, b.effects);
        let score = |r: &studies::Record| {
            studies::scored(&r.effects[0], r.outcome.as_ref().expect("diagnosed"))
                .expect("named right, compared as ± u")
        };
        let ((ea, ua, truth_a), (eb, ub, truth_b)) = (score(a), score(b));
        assert_eq!(truth_a, truth_b);
        assert_ne!(ea, eb);
        assert!(
            (ea - eb).abs() < 5.0 * ua.hypot(ub),
            "{ea} ± {ua} and {eb} ± {ub}"
        );
    }
}

#[test]
fn a_drift_found_linear_states_a_change_that_holds_the_curve_it_may_have() {
    // Dataset 4 of the A/C trunnion's 2 µm spindle-growth power cell (base seed 1): a
    // first-order growth of τ 2 500 s over a record of 2 040 s, found as a linear drift of the
    // tool's Z, the first-order form not earning its time constant. The straight line's change
    // over the record misses the curve's by more than 2 u; its 95 % interval, by the profile over
    // the time constant that admits the curve, holds it.
    let (spec, seed) = studies::power_dataset(Kind::RtestAc, Effect::SpindleDrift, 2.0, 1, 4);
    let (truth, d) = truth_and_diagnosis(&spec, seed, true);
    let truth = truth.effects[0]
        .drift
        .expect("a first-order drift")
        .record_change;
    let f = d
        .findings
        .iter()
        .find(|f| f.name == "EZ0[tool] drift")
        .unwrap_or_else(|| {
            panic!(
                "{:?}",
                d.findings.iter().map(|f| &f.name).collect::<Vec<_>>()
            )
        });
    let change = f
        .estimates
        .iter()
        .find(|e| e.name == "EZ0[tool] change over the measured time")
        .expect("a drift states its change");
    assert!(
        (change.value - truth).abs() > 2.0 * change.uncertainty,
        "{} against {truth}",
        change.text
    );
    let interval = change.interval.expect("profiled over the time constant");
    assert!(interval.contains(truth), "{} against {truth}", change.text);
}

/// The hidden pitch's true period (mm) and the found pitch's period and amplitude, of dataset
/// `index` of the axis' 2 µm pitch power cell (base seed 1), against the user's model without
/// it.
fn pitch_dataset(index: usize) -> (f64, mte_diagnose::Estimate, mte_diagnose::Estimate) {
    let (period_mm, d) = pitch_cell_dataset(1, index);
    let f = d
        .findings
        .iter()
        .find(|f| f.name == "EXX periodic")
        .expect("the pitch is found");
    let period = f.hyper_parameter.clone().expect("a period");
    let amplitude = f.estimates.iter().find(|e| e.name == "amplitude").unwrap();
    (period_mm, period, amplitude.clone())
}

#[test]
fn a_pitch_whose_true_period_is_not_among_the_best_grid_peaks_is_found_at_it() {
    // Dataset 1: a 22.78 mm pitch at 18 targets about 54 mm apart, beside EXX completed to
    // degree 9. Dozens of aliases come within 0.7 of the best on the period grid; with only
    // the first four refined, an alias of 1.47 mm was found with a third of the amplitude
    // (0.70 ± 0.24 µm). Every peak refined, the pitch itself is found.
    let (period_mm, period, amplitude) = pitch_dataset(1);
    assert!(
        (period.value - period_mm).abs() <= 2.0 * period.uncertainty,
        "period {} against {period_mm} mm",
        period.text
    );
    assert!(
        (amplitude.value - 2e-3).abs() <= 2.0 * amplitude.uncertainty,
        "amplitude {} against 2 µm",
        amplitude.text
    );
}

#[test]
fn a_pitch_whose_period_the_targets_leave_open_states_intervals_that_hold_it() {
    // Dataset 156: a 17.38 mm pitch at 18 targets, beside EXX completed to degree 10: the
    // profile over the period is flat from 17.40 to 17.60 mm (two shallow minima), and the
    // period found, 17.587 ± 0.034 mm, with an amplitude of 1.563 ± 0.071 µm, misses the truth
    // by 6 u. The 95 % intervals by the profile over the period hold both.
    let (period_mm, period, amplitude) = pitch_dataset(156);
    // The case the dataset is kept for: the linearisation misses.
    assert!(
        (amplitude.value - 2e-3).abs() > 2.0 * amplitude.uncertainty,
        "amplitude {} within 2 u of 2 µm (the dataset no longer shows the case)",
        amplitude.text
    );
    let interval = amplitude.interval.expect("an amplitude interval");
    assert!(interval.contains(2e-3), "amplitude {}", amplitude.text);
    let interval = period.interval.expect("a period interval");
    assert!(interval.contains(period_mm), "period {}", period.text);
}
