//! Designs that cannot show some effects, and settings out of range: a clear answer, never a
//! panic.

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
    assert!(
        d.notes.iter().any(|n| n.contains("time-dependent effects")),
        "{:?}",
        d.notes
    );
    // The reversal is in the data and in no candidate here: the verdict must not be "no
    // significant discrepancy".
    assert!(!d.no_discrepancy());
    assert!(!d.remaining_structure.is_empty());
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
