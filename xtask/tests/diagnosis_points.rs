//! 3-D points of a C rotary table with X, Y, Z linear stages, instrument on the table in an
//! unknown pose (two set-ups), target on the spindle side: the diagnosis identifies the C axis
//! line (position and direction: EX0C, EY0C, EA0C, EB0C) and the scale error of X within 2u of
//! the generator's truth. The generator (`xtask::realistic::points`) writes its own transforms;
//! the diagnosis reads only the files.

use mte_diagnose::{DiagnoseParams, Diagnosis, load};
use xtask::realistic::points::{PointsTruth, write_points};

fn run(seed: u64, state_offset: bool) -> (PointsTruth, Diagnosis) {
    let dir = std::env::temp_dir().join(format!(
        "mte-points-{}-{seed}-{state_offset}",
        std::process::id()
    ));
    let base = serde_json::json!({ "location": true, "terms": ["EXX scale"] });
    let truth = write_points(seed, &dir, state_offset, Some(base)).expect("write dataset");
    let p = load(&truth.manifest).expect("load points dataset");
    let _ = std::fs::remove_dir_all(&dir);
    let d = p.diagnose(&DiagnoseParams::default()).expect("diagnose");
    (truth, d)
}

/// The estimate of base term `name`: (value, u).
fn estimate(d: &Diagnosis, name: &str) -> Option<(f64, f64)> {
    d.base_parameters
        .iter()
        .find(|p| p.term == name)
        .and_then(|p| p.estimates.first())
        .map(|e| (e.value, e.uncertainty))
}

fn within_2u(d: &Diagnosis, name: &str, truth: f64) {
    let (v, u) = estimate(d, name).unwrap_or_else(|| panic!("{name} not estimated"));
    assert!(
        u > 0.0 && (v - truth).abs() <= 2.0 * u,
        "{name}: {v:.4e} ± {u:.2e}, truth {truth:.4e}"
    );
}

#[test]
fn axis_line_and_x_scale_from_points_with_a_calibrated_target() {
    for seed in [1, 2, 3] {
        let (truth, d) = run(seed, true);
        for (name, value) in &truth.location {
            within_2u(&d, name, *value);
        }
        within_2u(&d, "EXX scale", truth.x_scale);
        assert!(
            d.base.sigma0 < 1.3,
            "seed {seed}: σ0 = {} with the true model",
            d.base.sigma0
        );
        // Every location error is separable; only their absolute forms, which on a table are
        // the relative ones read with the instrument's pose, are left out.
        assert!(
            d.base_not_separable.iter().all(|n| n
                .name
                .strip_suffix(" abs")
                .is_some_and(|relative| n.confounded_with.iter().any(|c| c == relative))),
            "{:?}",
            d.base_not_separable
        );
    }
}

#[test]
fn an_unknown_target_offset_leaves_the_line_position_not_separable() {
    let (truth, d) = run(4, false);
    // The line's direction and the scale are still determined…
    for (name, value) in truth.location.iter().skip(2) {
        within_2u(&d, name, *value);
    }
    within_2u(&d, "EXX scale", truth.x_scale);
    // …its position is not: a target further out along X is the C line further in.
    let dropped: Vec<&str> = d
        .base_not_separable
        .iter()
        .map(|n| n.name.as_str())
        .collect();
    assert!(
        dropped
            .iter()
            .filter(|n| ["EX0C", "EY0C", "target offset x", "target offset y"].contains(n))
            .count()
            >= 2,
        "not separable: {dropped:?}"
    );
}

/// The realistic points generator (every ordinary error of the machine) against the diagnosis'
/// own kinematics: without errors and noise the points fit the nominal machine to rounding;
/// with all ordinary errors and the user's standard model nothing is named and σ0 ≈ 1.
#[test]
fn realistic_points_fit_the_nominal_machine_and_name_nothing_when_clean() {
    use xtask::realistic::{Kind, Spec, write_spec};
    let dir = std::env::temp_dir().join(format!("mte-points-realistic-{}", std::process::id()));
    let mut perfect = Spec::new(Kind::Points, &[]);
    perfect.ordinary_scale = 0.0;
    perfect.noise_scale = 0.0;
    let diagnosed = |spec: &Spec, seed: u64, name: &str| {
        let truth = write_spec(spec, seed, &dir.join(name)).unwrap();
        let p = load(&truth.manifest).unwrap();
        p.diagnose(&DiagnoseParams::default()).unwrap()
    };
    let d = diagnosed(&perfect, 5, "perfect");
    // Coordinates are printed to 0.01 µm.
    assert!(d.base.rms < 2e-5, "residual RMS {} mm", d.base.rms);

    let d = diagnosed(&Spec::new(Kind::Points, &[]), 6, "clean");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        d.findings.is_empty(),
        "{:?}",
        d.findings.iter().map(|f| &f.name).collect::<Vec<_>>()
    );
    assert!(
        (0.7..1.4).contains(&d.extended.sigma0),
        "σ0 = {}",
        d.extended.sigma0
    );
}

#[test]
fn a_linear_axis_error_seen_from_the_rotary_table_shows_along_its_axis_in_the_beds_directions() {
    // The user's model without the scale of X (the bundled c-stage dataset's case): it is found,
    // and its plot's channels are the bed's directions although the instrument rides on the C
    // table: the scale moves the target along X only, a line against X in `dx` and nothing in
    // `dy` and `dz` whatever C's angle (in the table's frame it spread over dx and dy with C).
    let dir = std::env::temp_dir().join(format!("mte-points-scale-{}", std::process::id()));
    let truth = write_points(1, &dir, true, None).expect("write dataset");
    let d = load(&truth.manifest)
        .expect("load points dataset")
        .diagnose(&DiagnoseParams::default())
        .expect("diagnose");
    let _ = std::fs::remove_dir_all(&dir);
    let plot = d
        .residual_series
        .iter()
        .find(|s| s.finding.as_deref() == Some("EXX scale"))
        .unwrap_or_else(|| panic!("no plot of EXX scale: {:?}", d.findings));
    let largest = |channel: usize| {
        plot.effect
            .iter()
            .zip(&plot.channel)
            .filter(|(_, c)| **c == channel)
            .fold(0.0_f64, |m, (e, _)| m.max(e.abs()))
    };
    assert!(
        largest(0) > 1e-3 && largest(1) < 1e-4 * largest(0) && largest(2) < 1e-4 * largest(0),
        "the scale's effect in dx, dy, dz up to {:.2e}, {:.2e}, {:.2e} mm",
        largest(0),
        largest(1),
        largest(2)
    );
}
