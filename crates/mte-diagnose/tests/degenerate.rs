//! Designs that cannot show some effects, and settings out of range: a clear answer, never a
//! panic.

mod common;
use mte_diagnose::{
    DiagnoseError, DiagnoseParams, Family, Observations, Quantity, Term, Variable, VariableKind,
    diagnose,
};
use mte_linalg::DVec;

/// Bidirectional runs of X with a 2 µm reversal, every reading at the same time stamp.
fn runs(time: impl Fn(usize) -> f64) -> Observations {
    let n = 240;
    let x: Vec<f64> = (0..n).map(|i| ((i * 37) % 60) as f64 * 10.0).collect();
    let dir: Vec<f64> = (0..n)
        .map(|i| if (i / 60) % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    // Deterministic ±0.1 µm noise.
    let noise = |i: usize| 1e-4 * (((i * 7919) % 101) as f64 / 50.5 - 1.0);
    Observations {
        values: DVec::from_fn(n, |i, _| 1e-3 * dir[i] + noise(i)),
        sigma: Some(DVec::from_element(n, 0.06e-3)),
        variables: vec![
            Variable {
                name: "X".into(),
                kind: VariableKind::LinearAxis,
                values: x,
            },
            Variable {
                name: "direction".into(),
                kind: VariableKind::Direction,
                values: dir.clone(),
            },
            Variable {
                name: "t".into(),
                kind: VariableKind::Time,
                values: (0..n).map(time).collect(),
            },
            Variable {
                name: "C".into(),
                kind: VariableKind::RotaryAxis,
                values: vec![0.3; n],
            },
        ],
        setup: vec![0; n],
        setup_names: vec!["run".into()],
        channel: vec![0; n],
        channel_names: vec!["deviation".into()],
        setup_kind: "run".into(),
        quantity: Quantity::Length,
    }
}

fn offset(n: usize) -> Term {
    Term::single(
        "offset",
        "zero offset",
        "instrument zero",
        Family::Base,
        DVec::from_element(n, 1.0),
        Quantity::Length,
    )
}

#[test]
fn variables_without_spread_are_not_a_panic() {
    // One time stamp and a rotary axis at one angle: their structure tests have nothing to
    // test, and time effects cannot be tested without a pose measured twice at different times.
    let obs = runs(|_| 12.0);
    let d = diagnose(
        &obs,
        vec![offset(obs.len())],
        &[],
        &DiagnoseParams::default(),
    )
    .expect("diagnosis runs");
    assert!(
        d.structure
            .iter()
            .all(|t| t.variable != "t" && t.variable != "C")
    );
    for said in [
        "single time value: time-dependent effects (thermal drift) cannot be tested",
        "C has a single value in these data",
        "one run: errors that differ between runs",
    ] {
        assert!(
            d.notes.iter().any(|n| n.contains(said)),
            "{said}: {:?}",
            d.notes
        );
    }
    // The reversal is in the data and in no candidate here: the verdict must not be "no
    // significant discrepancy".
    assert!(!d.no_discrepancy());
    assert!(!d.remaining_structure.is_empty());
    // Its plot draws the dependence the structure test found: the ±1 µm of the reversal
    // (the base's offset takes the mean; the runs are balanced).
    let series = d
        .residual_series
        .iter()
        .find(|s| s.finding.is_none())
        .expect("a series of the unexplained structure");
    assert_eq!(series.structure.as_deref(), Some("direction"));
    for (e, x) in series.effect.iter().zip(&series.x) {
        assert!((e - 1e-3 * x).abs() < 1e-5, "{e} at direction {x}");
    }
}

#[test]
fn a_regular_grid_says_which_periods_it_cannot_show() {
    // X on a 10 mm grid (60 positions, 590 mm): a pitch shorter than 25 mm aliases; the report
    // says so, and the scan covers 25–295 mm.
    // X's reach and the notes of a diagnosis of `obs`.
    let reach = |obs: &Observations| {
        let d = diagnose(
            obs,
            vec![offset(obs.len())],
            &[],
            &DiagnoseParams::default(),
        )
        .expect("diagnosis runs");
        let x = d.periodic_reach.iter().find(|r| r.variable == "X").cloned();
        (x.expect("X varies"), d.notes)
    };
    let mut obs = runs(|i| i as f64);
    let (x, notes) = reach(&obs);
    let (lo, hi) = x.periods.expect("X has periods to scan");
    assert!(
        (lo - 25.0).abs() < 0.5 && (hi - 295.0).abs() < 1e-9,
        "{lo} {hi}"
    );
    assert!(x.alias_step.is_some_and(|a| (a - 10.0).abs() < 0.2));
    assert!(x.limited_by_sampling() && x.covers(30.0) && !x.covers(20.0));
    assert!(
        notes.iter().any(|n| n.contains(
            "the X positions repeat on a step of about 10 mm: periodic errors along X shorter than 25"
        )),
        "{notes:?}"
    );
    // Five positions: no period at all.
    obs.variables[0].values = (0..obs.len()).map(|i| (i % 5) as f64 * 100.0).collect();
    let (x, notes) = reach(&obs);
    assert_eq!((x.positions, x.periods), (5, None));
    assert!(
        notes
            .iter()
            .any(|n| n.contains("X takes only 5 distinct positions")),
        "{notes:?}"
    );
}

#[test]
fn significance_level_outside_zero_to_one_half_is_an_error() {
    let obs = runs(|i| i as f64);
    for alpha in [0.0, 0.5, 2.0, f64::NAN, f64::INFINITY] {
        let params = DiagnoseParams {
            alpha,
            ..DiagnoseParams::default()
        };
        let err = diagnose(&obs, vec![offset(obs.len())], &[], &params).unwrap_err();
        assert!(
            matches!(&err, DiagnoseError::InvalidData { field, .. } if field == "alpha"),
            "{alpha}: {err}"
        );
    }
}

/// A continuous log too large for the memory limit is refused before the candidates' designs
/// are built, with the figure; under the limit the same data load and the estimate is stated.
#[test]
fn a_log_beyond_the_memory_limit_is_refused_with_the_figure() {
    let dir = common::scratch("large");
    let rows = 50_000;
    let mut csv = String::from("run,direction,x_mm,deviation_um\n");
    for i in 0..rows {
        let x = 700.0 * (i % 10_000) as f64 / 10_000.0 + 0.013 * (i / 10_000) as f64;
        let dir = if (i / 10_000) % 2 == 0 { "+" } else { "-" };
        csv.push_str(&format!("{},{dir},{x:.4},{:.3}\n", i / 10_000, 0.001 * x));
    }
    std::fs::write(dir.join("runs.csv"), csv).unwrap();
    std::fs::write(
        dir.join("manifest.json"),
        r#"{"format": "mte-dataset/1", "kind": "axis", "axis": "X", "data": "runs.csv", "noise_um": 0.5}"#,
    )
    .unwrap();
    let p = mte_diagnose::load(&dir.join("manifest.json")).unwrap();
    let params = DiagnoseParams {
        max_memory_gb: 0.05,
        ..DiagnoseParams::default()
    };
    let err = p.diagnose(&params).unwrap_err();
    let DiagnoseError::TooLarge {
        observations,
        columns,
        needed_gb,
        ..
    } = &err
    else {
        panic!("expected TooLarge, got {err}");
    };
    assert_eq!(*observations, rows);
    // The periodic scan alone has hundreds of sine/cosine pairs.
    assert!(*columns > 200, "{columns}");
    // The search's variants are kept for the thinned copy it runs on.
    let searched = rows.min(params.search_rows) as f64;
    assert!((*needed_gb - searched * *columns as f64 * 8.0 / 1e9).abs() < 0.1 * needed_gb);
    assert!(err.to_string().contains("GB"), "{err}");
}
