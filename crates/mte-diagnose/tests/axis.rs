//! Hidden effects in bidirectional axis data (laser interferometer runs, ISO 230-2 style).
//!
//! The generator below knows the effects; the diagnosis only reads the files it writes, and the
//! tests look at the named cause after the diagnosis has run.

mod common;

use mte_diagnose::{DiagnoseParams, Family, load};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const NOISE_UM: f64 = 0.3;

/// What the generator hides in the data (µm, mm, s).
#[derive(Default, Clone, Copy)]
struct Hidden {
    reversal_um: f64,
    /// The reversal's change from the middle of the targets to their far end (larger at +X).
    reversal_change_um: f64,
    pitch_amplitude_um: f64,
    pitch_period_mm: f64,
    scale_ppm: f64,
    zero_drift_um_per_min: f64,
    /// A first-order settling of the zero: its size and time constant.
    zero_settling_um: f64,
    zero_settling_tau_s: f64,
    /// The screw expanding about X = 0 as it warms: its final scale change (ppm) and time
    /// constant.
    expansion_ppm: f64,
    expansion_tau_s: f64,
    /// Where the screw is fixed (its bearing), mm: the expansion is about this point.
    expansion_fixed_mm: f64,
    /// One gross error: the reading at this index (in the order written) is off by µm.
    spike: Option<(usize, f64)>,
    /// A second, longer periodic error (a wave of the screw or the guideway).
    wave_amplitude_um: f64,
    wave_period_mm: f64,
}

/// The middle of [`dense_targets`] (0 to 701.3 mm).
const MIDDLE_MM: f64 = 350.65;

/// 101 targets over X ∈ [0, 700] mm at alternating steps of 8.3 and 5.7 mm.
fn dense_targets() -> Vec<f64> {
    (0..=100)
        .map(|i| i as f64 * 7.0 + if i % 2 == 1 { 1.3 } else { 0.0 })
        .collect()
}

/// Writes 5 bidirectional runs at `targets` and returns the manifest path.
fn write_dataset(name: &str, hidden: Hidden, seed: u64) -> common::Dataset {
    write_dataset_at(name, &dense_targets(), hidden, seed)
}

fn write_dataset_at(name: &str, targets: &[f64], hidden: Hidden, seed: u64) -> common::Dataset {
    write_runs(
        name,
        "X",
        targets,
        NOISE_UM,
        seed,
        4.0,
        |x, dir, t, index| {
            2.0 + hidden.reversal_um * 0.5 * dir
                + hidden.reversal_change_um * 0.5 * dir * (x - MIDDLE_MM) / MIDDLE_MM
                + hidden.pitch_amplitude_um
                    * (std::f64::consts::TAU * x / hidden.pitch_period_mm.max(1.0) + 0.7).sin()
                + hidden.wave_amplitude_um
                    * (std::f64::consts::TAU * x / hidden.wave_period_mm.max(1.0) - 1.1).sin()
                + hidden.scale_ppm * 1e-3 * x
                + hidden.zero_drift_um_per_min * t / 60.0
                + hidden.zero_settling_um * (1.0 - (-t / hidden.zero_settling_tau_s.max(1.0)).exp())
                + hidden.expansion_ppm
                    * 1e-3
                    * (x - hidden.expansion_fixed_mm)
                    * (1.0 - (-t / hidden.expansion_tau_s.max(1.0)).exp())
                + hidden.spike.filter(|s| s.0 == index).map_or(0.0, |s| s.1)
        },
    )
}

fn run(path: &std::path::Path) -> mte_diagnose::Diagnosis {
    let prepared = load(path).expect("dataset loads");
    prepared
        .diagnose(&DiagnoseParams::default())
        .expect("diagnosis runs")
}

/// Within `k` standard uncertainties.
fn within(value: f64, u: f64, truth: f64, k: f64) -> bool {
    (value - truth).abs() <= k * u
}

#[test]
fn clean_axis_data_yields_no_discovery() {
    for seed in 1..=3 {
        let d = run(&write_dataset(
            &format!("clean{seed}"),
            Hidden::default(),
            seed,
        ));
        assert!(
            d.no_discrepancy() && d.outliers.is_empty(),
            "seed {seed}: false discovery {:?}, outliers {:?}",
            d.findings.iter().map(|f| &f.name).collect::<Vec<_>>(),
            d.outliers
        );
    }
}

/// The progress a diagnosis reports adds up to its units ([`mte_diagnose::progress_units`]),
/// and reporting it changes nothing in the result.
#[test]
fn a_diagnosis_reports_each_of_its_progress_units_once() {
    use std::sync::atomic::{AtomicU64, Ordering};
    let path = clean_runs_scattering("progress", 0.0, 3000);
    for outer_folds in [5, 0] {
        let params = DiagnoseParams {
            outer_folds,
            ..DiagnoseParams::default()
        };
        let done = AtomicU64::new(0);
        let with = load(&path)
            .unwrap()
            .diagnose_with_progress(&params, &|n: u64| {
                done.fetch_add(n, Ordering::Relaxed);
            })
            .unwrap();
        assert_eq!(
            done.load(Ordering::Relaxed),
            mte_diagnose::progress_units(&params)
        );
        let without = load(&path).unwrap().diagnose(&params).unwrap();
        assert_eq!(
            serde_json::to_string(&with).unwrap(),
            serde_json::to_string(&without).unwrap()
        );
    }
    assert_eq!(mte_diagnose::progress_units(&DiagnoseParams::default()), 8);
}

/// Runs of a clean axis (a constant 2 µm) stating [`NOISE_UM`], whose readings scatter by
/// `extra_um` more (independent, from seeds `seed` + reading index).
fn clean_runs_scattering(name: &str, extra_um: f64, seed: u64) -> common::Dataset {
    let extra = Normal::new(0.0, extra_um).unwrap();
    write_runs(
        name,
        "X",
        &dense_targets(),
        NOISE_UM,
        5,
        4.0,
        |_, _, _, i| 2.0 + extra.sample(&mut ChaCha8Rng::seed_from_u64(seed + i as u64)),
    )
}

/// A clean axis whose readings scatter 1.28 × the noise its manifest states (a stated noise is
/// rarely known better than that): no discrepancy is claimed, and the verdict says in words
/// that the χ² test rejects the stated noise, by how much, and what may hide in the excess. With
/// the noise stated right it says nothing of the kind.
#[test]
fn scatter_above_the_stated_noise_within_its_tolerance_is_said_in_words() {
    let excess = "× the stated noise: more than chance gives";
    for (extra, said) in [(0.8, true), (0.0, false)] {
        let path = clean_runs_scattering("scatter", extra * NOISE_UM, 1000);
        let d = run(&path);
        assert!(
            d.no_discrepancy(),
            "{:?}: {:?}",
            d.verdict,
            d.findings.iter().map(|f| &f.name).collect::<Vec<_>>()
        );
        let text = mte_diagnose::report::markdown(&d, "scatter");
        assert_eq!(
            text.contains(excess),
            said,
            "σ0 = {:.2}, χ² p = {:?}",
            d.base.sigma0,
            d.base.chi2_p_value
        );
        if said {
            assert!(d.base.chi2_p_value.is_some_and(|p| p < d.alpha));
        }
    }
}

/// A clean axis whose manifest states 4 × the noise its readings have: nothing is named, and the
/// verdict says that the scatter is below the stated noise by more than chance and that the
/// uncertainties, which take the stated noise, are wider than the data need.
#[test]
fn scatter_far_below_the_stated_noise_is_said_in_words() {
    let path = write_runs(
        "overstated",
        "X",
        &dense_targets(),
        NOISE_UM,
        6,
        4.0,
        |_, _, _, _| 2.0,
    );
    let manifest = std::fs::read_to_string(&*path).unwrap();
    let stated = manifest.replace(&format!("\"noise_um\": {NOISE_UM}"), "\"noise_um\": 1.2");
    assert_ne!(stated, manifest);
    std::fs::write(&*path, stated).unwrap();
    let d = run(&path);
    assert!(d.no_discrepancy(), "{:?}", d.verdict);
    assert!((0.2..0.3).contains(&d.base.sigma0), "σ0 {}", d.base.sigma0);
    let text = mte_diagnose::report::markdown(&d, "overstated");
    assert!(
        text.contains("× the stated noise: less than chance gives"),
        "{text}"
    );
}

/// A clean axis whose readings scatter 4 × the noise its manifest states (its resolution given
/// for its repeatability): nothing is named, and the verdict says that the scatter has no
/// structure, how large it is against the noise stated, and to check that noise.
#[test]
fn scatter_far_above_the_stated_noise_without_structure_points_at_the_stated_noise() {
    let path = clean_runs_scattering("scatter-4", 15f64.sqrt() * NOISE_UM, 2000);
    let d = run(&path);
    assert_eq!(d.verdict, mte_diagnose::Verdict::Unexplained);
    assert!(
        d.findings.is_empty() && d.remaining_structure.is_empty(),
        "{:?} {:?}",
        d.findings.iter().map(|f| &f.name).collect::<Vec<_>>(),
        d.remaining_structure
    );
    // The scatter stated is σ0 times the stated noise: about 4 × (σ0's own scatter over a few
    // hundred readings is a few %).
    assert!(
        (3.5..4.5).contains(&d.extended.sigma0),
        "σ0 {}",
        d.extended.sigma0
    );
    let text = mte_diagnose::report::markdown(&d, "scatter-4");
    let said = "a scatter without structure is the measurement's own, about ";
    let at = text
        .find(said)
        .unwrap_or_else(|| panic!("{said} not in:\n{text}"));
    let rest = &text[at + said.len()..];
    let (scatter, rest) = rest.split_once(" µm where ").unwrap();
    let scatter: f64 = scatter.parse().unwrap();
    assert!(
        (scatter - d.extended.sigma0 * NOISE_UM).abs() < 0.01,
        "{scatter} µm against σ0 {}",
        d.extended.sigma0
    );
    assert!(rest.starts_with("0.300 µm is stated"), "{rest}");
    assert!(text.contains("Check the stated noise"));
}

/// A screw worn where the axis works most: the reversal grows along X (ISO 230-2 states it at
/// every target). The reversal and its change along X are named, each within 2 u: the mean
/// reversal over the targets and the change from the middle to the end.
#[test]
fn a_reversal_changing_along_the_axis_is_named_with_its_change() {
    let d = run(&write_dataset(
        "reversal-changing",
        Hidden {
            reversal_um: 2.0,
            reversal_change_um: 1.2,
            ..Hidden::default()
        },
        12,
    ));
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["EXX reversal", "EXX reversal poly1"], "{names:?}");
    for (f, truth) in d.findings.iter().zip([2.0, 1.2]) {
        let e = &f.estimates[0];
        assert!(
            within(e.value * 1e3, e.uncertainty * 1e3, truth, 2.0),
            "{}: {}, truth {truth} µm",
            f.name,
            e.text
        );
    }
}

#[test]
fn hidden_reversal_is_found_and_sized() {
    let d = run(&write_dataset(
        "reversal",
        Hidden {
            reversal_um: 4.0,
            ..Hidden::default()
        },
        11,
    ));
    assert_eq!(
        d.findings.len(),
        1,
        "{:?}",
        d.findings.iter().map(|f| &f.name).collect::<Vec<_>>()
    );
    let f = &d.findings[0];
    assert_eq!(f.family, Family::Reversal);
    let e = &f.estimates[0];
    assert!(
        within(e.value * 1e3, e.uncertainty * 1e3, 4.0, 2.0),
        "{}",
        e.text
    );
    // Held-out RMS falls to the noise level (within 10 %).
    assert!(
        d.held_out.as_ref().unwrap().diagnosed_rms * 1e3 < 1.1 * NOISE_UM,
        "{}",
        d.held_out.as_ref().unwrap().diagnosed_rms
    );
}

/// Time of the last reading of these datasets (5 runs of 2 × 101 readings, 4 s apart).
const LAST_T_S: f64 = 4.0 * (5 * 2 * 101 - 1) as f64;

/// A finding's stated change of the zero offset over the measured time, µm: (value, u).
fn change_over_the_measured_time_um(f: &mte_diagnose::Finding) -> Option<(f64, f64)> {
    f.estimates
        .iter()
        .find(|e| e.name == "EXX offset change over the measured time")
        .map(|e| (e.value * 1e3, e.uncertainty * 1e3))
}

/// A drift's size over the data: its change from the first reading (t = 0) to the last
/// (t = 4 036 s), whether it is found linear or first-order.
#[test]
fn a_drift_states_its_change_over_the_measured_time() {
    let settling = Hidden {
        zero_settling_um: 3.0,
        zero_settling_tau_s: 1500.0,
        ..Hidden::default()
    };
    let linear = Hidden {
        zero_drift_um_per_min: 0.05,
        ..Hidden::default()
    };
    for (name, hidden, found, truth_um) in [
        (
            "settling",
            settling,
            "EXX offset drift exp",
            3.0 * (1.0 - (-LAST_T_S / 1500.0_f64).exp()),
        ),
        ("linear", linear, "EXX offset drift", 0.05 * LAST_T_S / 60.0),
    ] {
        let d = run(&write_dataset(name, hidden, 21));
        let f = d
            .finding(found)
            .unwrap_or_else(|| panic!("{name}: {found} not found: {:?}", d.findings));
        let (v, u) = change_over_the_measured_time_um(f)
            .unwrap_or_else(|| panic!("{name}: no change over the measured time: {f:?}"));
        assert!(
            u > 0.0 && u < 0.2 * truth_um.abs() && within(v, u, truth_um, 3.0),
            "{name}: change {v:.3} ± {u:.3} µm, truth {truth_um:.3} µm"
        );
    }
}

/// The screw expands as the machine warms (semi-closed loop: the encoder on the motor does not
/// see it): the positioning error grows along X and in time. It is the scale drifting with a
/// time constant, sized as its final change and its change over the measured time, and nothing
/// else (not the zero drifting beside it).
#[test]
fn a_screw_expanding_as_it_warms_is_the_scale_drifting_with_its_time_constant() {
    let hidden = Hidden {
        expansion_ppm: 12.0,
        expansion_tau_s: 1200.0,
        ..Hidden::default()
    };
    let d = run(&write_dataset("expansion", hidden, 23));
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(
        names,
        ["EXX scale drift exp"],
        "{}",
        mte_diagnose::report::markdown(&d, "expansion")
    );
    let f = &d.findings[0];
    let estimate = |name: &str| {
        f.estimates
            .iter()
            .find(|e| e.name == name)
            .map(|e| (e.value * 1e6, e.uncertainty * 1e6))
            .unwrap_or_else(|| panic!("no {name}: {f:?}"))
    };
    let (v, u) = estimate("EXX scale change");
    assert!(within(v, u, 12.0, 2.0), "final change {v:.2} ± {u:.2} ppm");
    let (v, u) = estimate("EXX scale change over the measured time");
    let truth = 12.0 * (1.0 - (-LAST_T_S / 1200.0_f64).exp());
    assert!(
        within(v, u, truth, 2.0),
        "change over the measured time {v:.2} ± {u:.2} ppm, truth {truth:.2}"
    );
    // The final value and the time constant with their profile intervals, closed here (a time
    // constant of a third of the record).
    let interval = |e: &mte_diagnose::Estimate| e.interval.expect("a 95 % interval");
    let final_value = interval(&f.estimates[0]);
    assert!(
        final_value.lower.is_some() && final_value.upper.is_some() && final_value.contains(12e-6),
        "{}",
        f.estimates[0].text
    );
    let tau = f.hyper_parameter.as_ref().expect("a time constant");
    assert!(
        interval(tau).lower.is_some() && interval(tau).contains(1200.0),
        "{}",
        tau.text
    );
}

/// The diagnosis of a screw expanding by `ppm` with a time constant of `records` records about
/// `fixed_mm` (the test's dataset `name`, `seed`), and its report.
fn slow_expansion(
    name: &str,
    ppm: f64,
    records: f64,
    fixed_mm: f64,
    seed: u64,
) -> (mte_diagnose::Diagnosis, String) {
    let hidden = Hidden {
        expansion_ppm: ppm,
        expansion_tau_s: records * LAST_T_S,
        expansion_fixed_mm: fixed_mm,
        ..Hidden::default()
    };
    let d = run(&write_dataset(name, hidden, seed));
    let report = mte_diagnose::report::markdown(&d, name);
    (d, report)
}

/// Asserts that `f` states the scale's change over the measured time of an expansion by `ppm`
/// with a time constant of `records` records within 2 u.
fn assert_scale_change(f: &mte_diagnose::Finding, ppm: f64, records: f64) {
    let change = f
        .estimates
        .iter()
        .find(|e| e.name == "EXX scale change over the measured time")
        .unwrap_or_else(|| panic!("no change over the measured time: {f:?}"));
    let truth = ppm * (1.0 - (-1.0 / records).exp());
    assert!(
        within(change.value * 1e6, change.uncertainty * 1e6, truth, 2.0),
        "{}, truth {truth:.2} ppm",
        change.text
    );
}

/// A screw still expanding at the end of the record (time constant twice the record): the data
/// show its course better than where it settles. The final value's 95 % interval (profile
/// likelihood over the time constant) holds the truth and reaches further above than the
/// linearisation's ± 2 u (a longer time constant, a larger final value, fits almost as well),
/// and the change over the measured time is sized.
#[test]
fn a_drift_still_rising_at_the_end_of_the_record_has_a_final_value_interval_longer_above() {
    let (d, report) = slow_expansion("expansion-slow", 40.0, 2.0, 0.0, 24);
    let f = d
        .findings
        .iter()
        .find(|f| f.name == "EXX scale drift exp")
        .unwrap_or_else(|| panic!("{report}"));
    let e = &f.estimates[0];
    let i = e.interval.unwrap_or_else(|| panic!("{report}"));
    let (lower, upper) = (
        i.lower.unwrap_or(f64::NEG_INFINITY),
        i.upper.unwrap_or(f64::INFINITY),
    );
    assert!(
        i.contains(40e-6)
            && upper - e.value > 1.5 * (e.value - lower)
            && upper > e.value + 2.0 * e.uncertainty,
        "{}",
        e.text
    );
    assert_scale_change(f, 40.0, 2.0);
}

/// A screw expanding so slowly (time constant six records) that the data show an almost
/// straight rise: found as a linear drift of the scale, whose report says where a first-order
/// drift would settle — a 95 % range (open above where the data set no bound) that holds the
/// truth and lies beyond the change over the record.
#[test]
fn a_drift_found_linear_says_where_a_first_order_one_would_settle() {
    let (d, report) = slow_expansion("expansion-linear", 40.0, 6.0, 0.0, 25);
    assert!(
        d.findings.iter().any(|f| f.name == "EXX scale drift"),
        "{report}"
    );
    let note = d
        .notes
        .iter()
        .find(|n| n.starts_with("EXX scale drift: a first-order drift of EXX scale"))
        .unwrap_or_else(|| panic!("{report}"));
    // "final value between a ppm and b ppm" or "final value a ppm or above".
    let range = note.split("final value ").nth(1).unwrap_or_default();
    let numbers: Vec<f64> = range
        .split(|c: char| c.is_whitespace() || c == ')')
        .filter_map(|w| w.parse().ok())
        .take(if range.starts_with("between") { 2 } else { 1 })
        .collect();
    let (lower, upper) = match numbers[..] {
        [a, b] => (a, b),
        [a] if range.contains("or above") => (a, f64::INFINITY),
        _ => panic!("{note}"),
    };
    let change = 40.0 * (1.0 - (-1.0 / 6.0_f64).exp());
    assert!(
        lower <= 40.0 && 40.0 <= upper && lower > 0.8 * change,
        "{note}: change over the record {change:.2} ppm"
    );
}

/// A screw fixed mid-travel expanding slowly (time constant 1.5 records): the final scale and
/// zero changes are far beyond the record and within 2 u of zero each by the linearisation,
/// but the change over the record is plain in the data. The expansion is kept (a drift's size
/// the data determine is its change over the measured time), sized, and the final scale
/// change's 95 % interval holds the truth.
#[test]
fn a_slow_expansion_about_a_bearing_is_kept_by_its_change_over_the_record() {
    let (d, report) = slow_expansion("expansion-slow-bearing", 4.0, 1.5, 500.0, 26);
    let f = d
        .findings
        .iter()
        .find(|f| f.name.starts_with("EXX scale drift"))
        .unwrap_or_else(|| panic!("{report}"));
    assert_scale_change(f, 4.0, 1.5);
    let final_value = &f.estimates[0];
    assert!(
        final_value.interval.is_some_and(|i| i.contains(4e-6)),
        "{}",
        final_value.text
    );
}

/// An ISO 230-2 export without times: a zero drifting at 0.1 µm/min shows as the zero shifting
/// from run to run (808 s per run: 1.35 µm a run), each run's offset against the first within
/// 3 u, and the finding says that a reversal found beside it may be the drift within each run.
#[test]
fn a_drift_in_a_table_without_times_is_the_zero_shifting_from_run_to_run() {
    let path = write_dataset(
        "drift-no-times",
        Hidden {
            zero_drift_um_per_min: 0.1,
            ..Hidden::default()
        },
        24,
    );
    let csv = std::fs::read_to_string(path.with_file_name("runs.csv")).unwrap();
    let without_t: String = csv
        .lines()
        .map(|l| {
            let mut fields: Vec<&str> = l.split(',').collect();
            fields.remove(3); // run,direction,x_mm,t_s,deviation_um
            fields.join(",") + "\n"
        })
        .collect();
    std::fs::write(path.with_file_name("runs.csv"), without_t).unwrap();
    let d = run(&path);
    let f = d
        .finding("EXX offset per run")
        .unwrap_or_else(|| panic!("{:?}", d.findings));
    assert_eq!(f.estimates.len(), 4);
    for (k, e) in f.estimates.iter().enumerate() {
        let truth = (k + 1) as f64 * 808.0 * 0.1 / 60.0;
        assert!(
            within(e.value * 1e3, e.uncertainty * 1e3, truth, 3.0),
            "{}: {}, truth {truth:.2} µm",
            e.name,
            e.text
        );
    }
    assert!(f.meaning.contains("reversal"), "{}", f.meaning);
}

/// The screw fixed by its bearing at X = 600 mm, not at the axis' zero: its expansion moves the
/// zero too, with the same time constant. One cause, the expansion about a point, with its
/// scale change, the zero's change and the fixed point each within 2 u (not a scale drift and a
/// drift of the zero, each with a time constant of its own).
#[test]
fn a_screw_fixed_away_from_the_axis_zero_expands_about_its_bearing() {
    let hidden = Hidden {
        expansion_ppm: 12.0,
        expansion_tau_s: 1200.0,
        expansion_fixed_mm: 600.0,
        ..Hidden::default()
    };
    let d = run(&write_dataset("expansion-bearing", hidden, 25));
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["EXX scale drift exp about a point"], "{names:?}");
    let f = &d.findings[0];
    for (name, factor, truth) in [
        ("EXX scale change", 1e6, 12.0),
        ("EXX offset change", 1e3, -12e-3 * 600.0),
        ("EXX fixed point", 1.0, 600.0),
    ] {
        let e = f
            .estimates
            .iter()
            .find(|e| e.name == name)
            .unwrap_or_else(|| panic!("no {name}: {f:?}"));
        assert!(
            within(e.value * factor, e.uncertainty * factor, truth, 2.0),
            "{name}: {}, truth {truth}",
            e.text
        );
    }
}

/// A settling faster than the interval between two visits of a target (808 s) shows in how the
/// differences between consecutive visits shrink from the first target of a run to the last:
/// at τ = 400 s it is found, and its change over the measured time is sized. Faster than a third
/// of the interval (269 s), it is found at that shortest time constant, and the report says that
/// the drift may be faster.
#[test]
fn a_drift_faster_than_the_revisits_is_sized_or_said_to_be_possibly_faster() {
    let hidden = Hidden {
        zero_settling_um: 3.0,
        zero_settling_tau_s: 400.0,
        ..Hidden::default()
    };
    let d = run(&write_dataset("settling-400", hidden, 22));
    let f = d
        .finding("EXX offset drift exp")
        .unwrap_or_else(|| panic!("τ = 400 s: not found: {:?}", d.findings));
    let (v, u) = change_over_the_measured_time_um(f).expect("a change over the measured time");
    let truth_um = 3.0 * (1.0 - (-LAST_T_S / 400.0_f64).exp());
    assert!(
        within(v, u, truth_um, 3.0),
        "change {v:.3} ± {u:.3} µm, truth {truth_um:.3} µm"
    );
    let hidden = Hidden {
        zero_settling_um: 3.0,
        zero_settling_tau_s: 120.0,
        ..Hidden::default()
    };
    let d = run(&write_dataset("settling-120", hidden, 22));
    assert!(
        d.notes.iter().any(|n| n.starts_with(
            "the time constant of EXX offset drift exp is the shortest searched (269 s"
        )),
        "findings {:?}, notes {:?}",
        d.findings.iter().map(|f| &f.name).collect::<Vec<_>>(),
        d.notes
    );
}

/// One reading 6 µm off (20 σ) among 1 010 is listed with where it was taken, the cause
/// beside it is still found, and without it the residuals are consistent with the noise.
#[test]
fn a_gross_error_in_one_reading_is_listed_with_where_it_was_taken() {
    // Reading 250: run 2 (101 readings per direction, + first), direction +, its 49th target:
    // X = 7 · 48 mm.
    let hidden = Hidden {
        reversal_um: 2.0,
        spike: Some((250, 6.0)),
        ..Hidden::default()
    };
    let d = run(&write_dataset("spike", hidden, 23));
    assert!(d.finding("EXX reversal").is_some(), "{:?}", d.findings);
    assert_eq!(d.outliers.len(), 1, "{:?}", d.outliers);
    let o = &d.outliers[0];
    let x = o.at.iter().find(|(n, _)| n == "X").map(|a| a.1);
    assert!(
        o.observation == 250
            && o.setup == "2"
            && x == Some(336.0)
            && (o.residual * 1e3 - 6.0).abs() < 1.0
            && o.z > 10.0,
        "{o:?}"
    );
    let (sigma0, p) = d.without_outliers.expect("a fit without it");
    assert!(
        sigma0 < 1.2 && p.is_some_and(|p| p > 1e-3),
        "σ0 {sigma0}, p {p:?}"
    );
}

#[test]
fn hidden_pitch_error_and_reversal_are_both_found() {
    let hidden = Hidden {
        reversal_um: 3.0,
        pitch_amplitude_um: 1.5,
        pitch_period_mm: 25.0,
        ..Hidden::default()
    };
    let d = run(&write_dataset("pitch", hidden, 12));
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(d.findings.len(), 2, "{names:?}");
    let periodic = d
        .findings
        .iter()
        .find(|f| matches!(f.family, Family::Periodic { .. }))
        .expect("periodic found");
    let Family::Periodic { period } = periodic.family else {
        unreachable!()
    };
    assert!((period - 25.0).abs() < 0.25, "period {period}");
    let amp = &periodic.estimates[0];
    assert!(
        within(amp.value * 1e3, amp.uncertainty * 1e3, 1.5, 2.0)
            || (amp.value * 1e3 - 1.5).abs() < 0.05,
        "{}",
        amp.text
    );
    assert!(d.findings.iter().any(|f| f.family == Family::Reversal));
    assert!(d.held_out.as_ref().unwrap().diagnosed_rms * 1e3 < 1.1 * NOISE_UM);
}

/// A ball-screw pitch error and a longer wave of the screw in the same axis: two periodic
/// components, each found at its own period and named apart, beside the reversal. The 12 mm
/// pitch under 41 irregular targets 20 mm apart leaks into the long periods, so the wave's
/// period is only right once it is refined again with the pitch fitted.
#[test]
fn two_periodic_errors_of_one_axis_are_both_found() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let targets: Vec<f64> = (0..=40)
        .map(|i| {
            let jitter: f64 = rand::Rng::random_range(&mut rng, -6.0..6.0);
            let x = i as f64 * 20.0 + if i == 0 || i == 40 { 0.0 } else { jitter };
            (x * 10.0).round() / 10.0
        })
        .collect();
    let hidden = Hidden {
        reversal_um: 2.0,
        pitch_amplitude_um: 1.5,
        pitch_period_mm: 12.0,
        wave_amplitude_um: 2.5,
        wave_period_mm: 150.0,
        ..Hidden::default()
    };
    let d = run(&write_dataset_at("two-periods", &targets, hidden, 17));
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(d.findings.len(), 3, "{names:?}");
    let mut periodic: Vec<(f64, f64)> = d
        .findings
        .iter()
        .filter_map(|f| match f.family {
            Family::Periodic { period } => Some((period, f.estimates[0].value * 1e3)),
            _ => None,
        })
        .collect();
    periodic.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(periodic.len(), 2, "{names:?}");
    assert!((periodic[0].0 - 12.0).abs() < 0.05, "{periodic:?}");
    assert!((periodic[1].0 - 150.0).abs() < 2.0, "{periodic:?}");
    assert!((periodic[0].1 - 1.5).abs() < 0.15, "{periodic:?}");
    assert!((periodic[1].1 - 2.5).abs() < 0.15, "{periodic:?}");
    assert!(d.findings.iter().any(|f| f.family == Family::Reversal));
    assert_ne!(names[0], names[1], "components named apart: {names:?}");
    assert!(d.held_out.as_ref().unwrap().diagnosed_rms * 1e3 < 1.1 * NOISE_UM);
    // The wave repeats 5.3 times over the 800 mm travel: the report says that a smooth
    // positioning error of that shape fits as well; the pitch (67 repeats) stands as found.
    let qualified = |period: f64| {
        let f = d.findings.iter().find(
            |f| matches!(f.family, Family::Periodic { period: p } if (p - period).abs() < 2.0),
        );
        let name = &f.expect("found above").name;
        d.compound
            .iter()
            .find(|c| c.findings.contains(name))
            .map(|c| c.note.clone())
    };
    let note = qualified(150.0).expect("the long wave is qualified");
    assert!(note.contains("repeats only 5.3 times"), "{note}");
    assert_eq!(qualified(12.0), None);
    // The report says so beside the finding, in the verdict, and not again among the notes.
    let report = mte_diagnose::report::markdown(&d, "two periods");
    let caveat = format!("  Caveat: {note}.");
    assert_eq!(report.matches(&caveat).count(), 1, "{report}");
    assert!(!report.contains(&format!("Note: {note}")), "{report}");
    assert!(
        report.contains("named below (1 with a caveat on what these data can tell)"),
        "{report}"
    );
}

/// A 5 mm ball-screw pitch error under ISO 230-2 targets about 20 mm apart: four times shorter
/// than the mean step, so only the irregular spacing the standard asks for makes it visible
/// (targets on a 0.5 mm raster, as an engineer would write them).
#[test]
fn pitch_shorter_than_the_target_step_is_found_through_irregular_spacing() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let targets: Vec<f64> = (0..=35)
        .map(|i| {
            let jitter: f64 = rand::Rng::random_range(&mut rng, -7.0..7.0);
            if i == 0 || i == 35 {
                i as f64 * 20.0
            } else {
                ((i as f64 * 20.0 + jitter) * 2.0).round() / 2.0
            }
        })
        .collect();
    let hidden = Hidden {
        pitch_amplitude_um: 1.0,
        pitch_period_mm: 5.0,
        ..Hidden::default()
    };
    let d = run(&write_dataset_at("short-pitch", &targets, hidden, 22));
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(d.findings.len(), 1, "{names:?}");
    let Family::Periodic { period } = d.findings[0].family else {
        panic!("expected a periodic error, found {names:?}");
    };
    assert!((period - 5.0).abs() < 0.01, "period {period}");
    let amp = &d.findings[0].estimates[0];
    assert!(
        within(amp.value * 1e3, amp.uncertainty * 1e3, 1.0, 2.5),
        "{}",
        amp.text
    );
    assert!(d.held_out.as_ref().unwrap().diagnosed_rms * 1e3 < 1.1 * NOISE_UM);
}

#[test]
fn hidden_scale_error_is_named_scale() {
    let d = run(&write_dataset(
        "scale",
        Hidden {
            scale_ppm: 12.0,
            ..Hidden::default()
        },
        13,
    ));
    assert_eq!(
        d.findings.len(),
        1,
        "{:?}",
        d.findings.iter().map(|f| &f.name).collect::<Vec<_>>()
    );
    assert_eq!(d.findings[0].family, Family::Scale);
    let e = &d.findings[0].estimates[0];
    assert!(
        within(e.value * 1e6, e.uncertainty * 1e6, 12.0, 2.0),
        "{}",
        e.text
    );
}

/// A rotary table's positioning runs (ISO 230-2 for rotary axes, deviations in arcsec): a
/// worm-gear tooth error of 36 teeth per turn (period 10°) and a reversal, under 25 irregular
/// targets about 15° apart, so the tooth period is shorter than the mean step.
#[test]
fn rotary_axis_worm_gear_error_and_reversal_are_found_in_arcsec() {
    const NOISE_ARCSEC: f64 = 0.8;
    let (tooth_arcsec, reversal_arcsec) = (3.0, 4.0);
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let targets: Vec<f64> = (0..=24)
        .map(|i| {
            let jitter: f64 = rand::Rng::random_range(&mut rng, -5.0..5.0);
            let c = i as f64 * 15.0 + if i == 0 || i == 24 { 0.0 } else { jitter };
            (c * 10.0).round() / 10.0
        })
        .collect();
    let manifest = write_runs(
        "rotary",
        "C",
        &targets,
        NOISE_ARCSEC,
        31,
        10.0,
        |c, sign, _, _| {
            2.0 + 0.5 * sign * reversal_arcsec + tooth_arcsec * (36.0 * c.to_radians() + 1.0).sin()
        },
    );
    let d = run(&manifest);
    let names: Vec<&str> = d.findings.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(d.findings.len(), 2, "{names:?}");
    let arcsec = |rad: f64| rad.to_degrees() * 3600.0;
    let periodic = d
        .findings
        .iter()
        .find(|f| matches!(f.family, Family::Periodic { .. }))
        .expect("periodic found");
    let Family::Periodic { period } = periodic.family else {
        unreachable!()
    };
    assert!((period.to_degrees() - 10.0).abs() < 1e-9, "period {period}");
    let amp = &periodic.estimates[0];
    assert!(
        within(
            arcsec(amp.value),
            arcsec(amp.uncertainty),
            tooth_arcsec,
            2.5
        ),
        "{}",
        amp.text
    );
    let reversal = d
        .findings
        .iter()
        .find(|f| f.family == Family::Reversal)
        .expect("reversal found");
    let e = &reversal.estimates[0];
    assert!(
        within(arcsec(e.value), arcsec(e.uncertainty), reversal_arcsec, 2.5),
        "{}",
        e.text
    );
    let report = mte_diagnose::report::markdown(&d, "rotary");
    assert!(report.contains("″") && !report.contains(" µm"), "{report}");
}

#[test]
fn bad_axis_files_give_errors_naming_the_line() {
    let dir = common::scratch("axis-bad");
    std::fs::write(
        dir.join("runs.csv"),
        "run,direction,x_mm,deviation_um\n1,+,0,1.0\n1,+,10,abc\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("m.json"),
        r#"{"format": "mte-dataset/1", "kind": "axis", "axis": "X", "data": "runs.csv"}"#,
    )
    .unwrap();
    let err = load(&dir.join("m.json"))
        .err()
        .expect("bad number rejected")
        .to_string();
    assert!(
        err.contains("line 3") && err.contains("deviation_um"),
        "{err}"
    );
    std::fs::write(
        dir.join("m2.json"),
        r#"{"format": "mte-dataset/1", "kind": "axis", "data": "runs.csv"}"#,
    )
    .unwrap();
    let err = load(&dir.join("m2.json"))
        .err()
        .expect("missing axis rejected")
        .to_string();
    assert!(err.contains("axis"), "{err}");
    std::fs::write(
        dir.join("runs2.csv"),
        "run,direction,x_mm,deviation_um\n1,?,0,1.0\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("m3.json"),
        r#"{"format": "mte-dataset/1", "kind": "axis", "axis": "X", "data": "runs2.csv"}"#,
    )
    .unwrap();
    let err = load(&dir.join("m3.json"))
        .err()
        .expect("bad direction rejected")
        .to_string();
    assert!(err.contains("line 2") && err.contains("direction"), "{err}");
}

/// Eleven irregular targets over 600 mm cannot pin down a 23 mm pitch: periods that fit them
/// about as well are named, and the amplitude's uncertainty is widened so that it covers the
/// truth, whichever of them the search chose.
#[test]
fn an_ambiguous_period_is_said_to_be_ambiguous_and_its_amplitude_covers_the_truth() {
    let targets = [
        0.0, 47.0, 121.0, 166.0, 228.0, 301.0, 349.0, 417.0, 468.0, 533.0, 600.0,
    ];
    let hidden = Hidden {
        pitch_amplitude_um: 2.0,
        pitch_period_mm: 23.0,
        ..Hidden::default()
    };
    let mut ambiguous = 0;
    for seed in 1..=4 {
        let d = run(&write_dataset_at("ambiguous", &targets, hidden, seed));
        let Some(f) = d.finding("EXX periodic") else {
            continue;
        };
        let amp = f.estimates.iter().find(|e| e.name == "amplitude").unwrap();
        let period = f.hyper_parameter.as_ref().unwrap().value;
        let noted = d
            .notes
            .iter()
            .any(|n| n.contains("is ambiguous with these positions"));
        ambiguous += usize::from(noted);
        if (period - 23.0).abs() > 0.5 {
            // An alias was chosen: the report must say the period is ambiguous.
            assert!(
                noted,
                "period {period} mm chosen without a word: {:?}",
                d.notes
            );
        }
        if noted {
            assert!(f.alternatives.iter().any(|a| a.contains("at a period of")));
            assert!(
                within(amp.value * 1e3, amp.uncertainty * 1e3, 2.0, 2.0),
                "{}",
                amp.text
            );
        }
    }
    assert!(
        ambiguous > 0,
        "eleven targets over 600 mm leave a 23 mm period ambiguous"
    );
}

/// The detection limits are what the search does: a cause of the size the report gives as
/// its limit is found in about [`mte_diagnose::DETECTION_POWER`] of the datasets (80 %), one of
/// half that size in few, one of twice that size in all. Checked for a reversal (one size) and
/// for a pitch error at one period of the scan.
#[test]
fn a_cause_at_its_stated_detection_limit_is_found_four_times_in_five() {
    const N: usize = 30;
    let clean = run(&write_dataset("limit-clean", Hidden::default(), 1));
    let limit = |name: &str, period: Option<f64>| -> f64 {
        let l = clean
            .detection_limits
            .iter()
            .find(|l| l.name == name)
            .unwrap_or_else(|| panic!("no detection limit for {name}"));
        match period {
            Some(p) => l.near(p),
            None => l.smallest().map(|s| s.1),
        }
        .expect("separable")
            * 1e3
    };
    let reversal = limit("EXX reversal", None);
    let pitch_period = 23.0;
    let pitch = limit("EXX periodic", Some(pitch_period));
    // Of the order of the noise (0.3 µm) over 1010 readings.
    assert!(
        reversal > 0.02 && reversal < 0.3,
        "reversal limit {reversal} µm"
    );
    assert!(pitch > 0.02 && pitch < 0.5, "pitch limit {pitch} µm");
    let found_share = |scale: f64, hidden: &dyn Fn(f64) -> Hidden, name: &str| {
        let found = (0..N)
            .filter(|&i| {
                let d = run(&write_dataset(
                    &format!("limit-{name}-{scale}-{i}"),
                    hidden(scale),
                    100 + i as u64,
                ));
                d.findings.iter().any(|f| f.name == name)
            })
            .count();
        found as f64 / N as f64
    };
    let with_reversal = |s: f64| Hidden {
        reversal_um: s * reversal,
        ..Default::default()
    };
    let with_pitch = |s: f64| Hidden {
        pitch_amplitude_um: s * pitch,
        pitch_period_mm: pitch_period,
        ..Default::default()
    };
    for (hidden, name) in [
        (&with_reversal as &dyn Fn(f64) -> Hidden, "EXX reversal"),
        (&with_pitch, "EXX periodic"),
    ] {
        let at = found_share(1.0, hidden, name);
        // 80 % of 30: a binomial standard deviation of 7 %.
        assert!(
            (0.6..=0.97).contains(&at),
            "{name} at its limit found in {:.0} %",
            100.0 * at
        );
        let half = found_share(0.5, hidden, name);
        assert!(
            half <= 0.4,
            "{name} at half its limit found in {:.0} %",
            100.0 * half
        );
        let twice = found_share(2.0, hidden, name);
        assert!(
            twice >= 0.97,
            "{name} at twice its limit found in {:.0} %",
            100.0 * twice
        );
    }
}

/// Five bidirectional runs of `axis` (`C`: a rotary table, ° and ″; else mm and µm) over
/// `targets`, readings `dt` s apart, with the deviation `f(position, direction ±1, time, index
/// of the reading)` plus noise `sigma`; returns the manifest.
fn write_runs(
    name: &str,
    axis: &str,
    targets: &[f64],
    sigma: f64,
    seed: u64,
    dt: f64,
    f: impl Fn(f64, f64, f64, usize) -> f64,
) -> common::Dataset {
    let dir = common::scratch(&format!("axis-{name}"));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma).unwrap();
    let rotary = axis == "C";
    let (position, deviation, noise_key) = if rotary {
        ("c_deg", "deviation_arcsec", "noise_arcsec")
    } else {
        ("x_mm", "deviation_um", "noise_um")
    };
    let mut csv = format!("run,direction,{position},t_s,{deviation}\n");
    let (mut t, mut written) = (0.0, 0);
    for run in 1..=5 {
        for sign in [1.0, -1.0] {
            let order: Vec<f64> = if sign > 0.0 {
                targets.to_vec()
            } else {
                targets.iter().rev().copied().collect()
            };
            for p in order {
                let dev = f(p, sign, t, written) + noise.sample(&mut rng);
                let d = if sign > 0.0 { "+" } else { "-" };
                csv.push_str(&format!("{run},{d},{p:.3},{t:.1},{dev:.4}\n"));
                written += 1;
                t += dt;
            }
        }
    }
    std::fs::write(dir.join("runs.csv"), csv).unwrap();
    let manifest = format!(
        r#"{{"format": "mte-dataset/1", "kind": "axis", "axis": "{axis}", "{noise_key}": {sigma}, "data": "runs.csv"}}"#
    );
    std::fs::write(dir.join("manifest.json"), manifest).unwrap();
    common::Dataset::new(dir)
}

/// 40 targets about 9° apart, jittered by up to ±3° (ISO 230-2's irregular steps), from `seed`.
fn irregular_turn(seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..40)
        .map(|i| {
            let jitter: f64 = rand::Rng::random_range(&mut rng, -3.0..3.0);
            if i == 0 { 0.0 } else { i as f64 * 9.0 + jitter }
        })
        .collect()
}

#[test]
fn a_rotary_tables_smooth_errors_and_its_worm_gear_are_whole_harmonics_of_a_turn() {
    // A rotary table with no model of its own beyond a zero: eccentricity and the next two
    // harmonics of a turn (its smooth angular positioning error, a few arcsec), a 36-tooth worm
    // gear's 1.5″ and a reversal. Every harmonic is a whole number of cycles per turn, so its
    // period is exact and adds nothing to its amplitude's uncertainty (a free period would let
    // harmonic 1 take harmonic 2's place); and a rotary axis' error takes more than three
    // periodic components: the worm gear is found after the smooth part.
    let (smooth, tooth, reversal) = ([4.2, 2.2, -5.9], 1.5, 1.3);
    let d = run(&write_runs(
        "rotary-harmonics",
        "C",
        &irregular_turn(200),
        0.6,
        200,
        6.0,
        |c, sign, _, _| {
            let th = c.to_radians();
            (0..3)
                .map(|k| smooth[k] * ((k + 1) as f64 * th + 0.4 * k as f64 + 0.3).sin())
                .sum::<f64>()
                + tooth * (36.0 * th + 2.0).sin()
                - 0.5 * sign * reversal
        },
    ));
    let report = mte_diagnose::report::markdown(&d, "rotary harmonics");
    assert!(d.incomplete.is_none() && d.findings.len() == 5, "{report}");
    let arcsec = |rad: f64| rad.to_degrees() * 3600.0;
    for (per_turn, amplitude) in [(1.0, 4.2), (2.0, 2.2), (3.0, 5.9), (36.0, tooth)] {
        let f = d
            .findings
            .iter()
            .find(|f| match f.family {
                Family::Periodic { period } => {
                    (std::f64::consts::TAU / period - per_turn).abs() < 1e-9
                }
                _ => false,
            })
            .unwrap_or_else(|| panic!("{per_turn} per turn not found: {report}"));
        let h = f.hyper_parameter.as_ref().expect("its period");
        assert!(
            h.uncertainty == 0.0 && h.text.contains("per turn"),
            "{}",
            h.text
        );
        let a = &f.estimates[0];
        assert!(
            within(arcsec(a.value), arcsec(a.uncertainty), amplitude, 2.5),
            "{per_turn} per turn: {} against {amplitude}″",
            a.text
        );
    }
}

#[test]
fn a_periodic_error_beyond_the_most_components_makes_the_diagnosis_incomplete() {
    // Four waves of one linear axis' positioning (a screw's pitch and three longer waves), no
    // model of the axis: one error takes three periodic components, and the fourth, still
    // significant, is said to be left, not passed over in silence.
    let waves = [(2.0, 13.0), (2.5, 47.0), (2.0, 91.0), (1.5, 173.0)];
    let d = run(&write_runs(
        "four-waves",
        "X",
        &dense_targets(),
        NOISE_UM,
        7,
        6.0,
        |x, _, _, _| {
            waves
                .iter()
                .enumerate()
                .map(|(k, (a, p))| a * (std::f64::consts::TAU * x / p + k as f64).sin())
                .sum()
        },
    ));
    let report = mte_diagnose::report::markdown(&d, "four waves");
    let why = d
        .incomplete
        .as_deref()
        .unwrap_or_else(|| panic!("{report}"));
    assert!(
        why.contains("EXX periodic #4") && why.contains("at most 3 periodic components"),
        "{why}"
    );
    assert!(report.contains("stop at a limit"), "{report}");
}

#[test]
fn a_rotary_tables_smooth_error_of_many_harmonics_completes_the_model_and_names_nothing() {
    // The user's model holds the table's angular positioning error up to the second harmonic
    // of a turn; the table's error has a fifth too, and a third and fourth too small to show
    // alone. Together the higher harmonics are significant: they complete the model (every
    // harmonic beyond the base's at once), and no periodic cause is named for a smooth error.
    let path = write_runs(
        "rotary-smooth",
        "C",
        &irregular_turn(300),
        0.5,
        300,
        6.0,
        |c, _, _, _| {
            let th = c.to_radians();
            4.0 * (th + 0.3).sin() - 2.5 * (2.0 * th).cos()
                + 0.15 * (3.0 * th + 1.0).sin()
                + 0.15 * (4.0 * th).cos()
                + 0.5 * (5.0 * th + 2.0).sin()
        },
    );
    let mut manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    manifest["base_model"] = serde_json::json!({"components": {"degree": 3}});
    std::fs::write(&path, manifest.to_string()).unwrap();
    let d = run(&path);
    let report = mte_diagnose::report::markdown(&d, "rotary smooth");
    assert!(d.findings.is_empty() && d.no_discrepancy(), "{report}");
    assert!(
        d.base_completed.iter().any(|n| n.contains("-6")),
        "{:?}",
        d.base_completed
    );
}
