//! ISO 230-2:2014 evaluation: a worked example computed by hand and the standard's invariants.

use approx::assert_relative_eq;
use mte_metrology::iso230_2::{Direction, Reading, evaluate, readings_from_csv};
use proptest::prelude::*;

fn readings(data: &[(f64, Vec<f64>, Vec<f64>)]) -> Vec<Reading> {
    let mut r = Vec::new();
    for (t, up, dn) in data {
        for (j, (u, d)) in up.iter().zip(dn).enumerate() {
            r.push(Reading {
                target_mm: *t,
                run: j + 1,
                direction: Direction::Up,
                deviation_um: *u,
            });
            r.push(Reading {
                target_mm: *t,
                run: j + 1,
                direction: Direction::Down,
                deviation_um: *d,
            });
        }
    }
    r
}

/// Hand computation (3 targets, 3 runs):
/// P=0:   ↑ 2,4,3 → x̄↑=3, s↑=1;  ↓ 0,1,2 → x̄↓=1, s↓=1;  B=2,  R↑=4, R↓=4, R=max(2+2+2,4,4)=6, x̄=2
/// P=100: ↑ 5,5,5 → 5, 0;        ↓ 6,7,8 → 7, 1;         B=−2, R↑=0, R↓=4, R=max(0+2+2,0,4)=4, x̄=6
/// P=200: ↑ −1,0,1 → 0, 1;       ↓ −2,−2,−2 → −2, 0;     B=2,  R↑=4, R↓=0, R=4,               x̄=−1
/// Axis: B=2, B̄=2/3, R↑=4, R↓=4, R=6, E↑=5−0=5, E↓=7−(−2)=9, E=7−(−2)=9, M=6−(−1)=7,
/// A↑=max(5,5,2)−min(1,5,−2)=7, A↓=max(3,9,−2)−min(−1,5,−2)=11, A=9−(−2)=11.
#[test]
fn worked_example_by_hand() {
    let r = readings(&[
        (0.0, vec![2.0, 4.0, 3.0], vec![0.0, 1.0, 2.0]),
        (100.0, vec![5.0, 5.0, 5.0], vec![6.0, 7.0, 8.0]),
        (200.0, vec![-1.0, 0.0, 1.0], vec![-2.0, -2.0, -2.0]),
    ]);
    let a = evaluate(&r).unwrap();
    let eps = 1e-12;
    assert_relative_eq!(a.reversal_b_um, 2.0, epsilon = eps);
    assert_relative_eq!(a.mean_reversal_um, 2.0 / 3.0, epsilon = eps);
    assert_relative_eq!(a.repeatability_up_um, 4.0, epsilon = eps);
    assert_relative_eq!(a.repeatability_down_um, 4.0, epsilon = eps);
    assert_relative_eq!(a.repeatability_um, 6.0, epsilon = eps);
    assert_relative_eq!(a.systematic_up_um, 5.0, epsilon = eps);
    assert_relative_eq!(a.systematic_down_um, 9.0, epsilon = eps);
    assert_relative_eq!(a.systematic_um, 9.0, epsilon = eps);
    assert_relative_eq!(a.mean_range_um, 7.0, epsilon = eps);
    assert_relative_eq!(a.accuracy_up_um, 7.0, epsilon = eps);
    assert_relative_eq!(a.accuracy_down_um, 11.0, epsilon = eps);
    assert_relative_eq!(a.accuracy_um, 11.0, epsilon = eps);
    assert_relative_eq!(a.targets[1].r_um, 4.0, epsilon = eps);
    assert_relative_eq!(a.targets[0].mean_um, 2.0, epsilon = eps);
}

#[test]
fn csv_round_trip_and_errors() {
    let csv = "# axis X\ntarget_mm,run,direction,deviation_um\n0,1,up,2\n0,1,down,0\n0,2,up,4\n0,2,down,1\n100,1,up,5\n100,1,down,6\n100,2,+,5\n100,2,-,7\n";
    let r = readings_from_csv("x.csv", csv).unwrap();
    assert_eq!(r.len(), 8);
    let a = evaluate(&r).unwrap();
    assert_relative_eq!(a.systematic_up_um, 5.0 - 3.0, epsilon = 1e-12);
    let bad = "target_mm,run,direction,deviation_um\n0,1,sideways,2\n";
    let e = readings_from_csv("x.csv", bad).unwrap_err().to_string();
    assert!(e.contains("x.csv:2") && e.contains("direction"), "{e}");
    let bad = "target_mm,run,direction,deviation_um\n0,1,up,NaN\n";
    assert!(
        readings_from_csv("x.csv", bad)
            .unwrap_err()
            .to_string()
            .contains("deviation_um")
    );
    // a single run per direction cannot give s
    let one = readings(&[(0.0, vec![1.0], vec![1.0]), (10.0, vec![1.0], vec![1.0])]);
    assert!(evaluate(&one).is_err());
    // unequal runs are named
    let mut r = readings(&[
        (0.0, vec![1.0, 2.0], vec![1.0, 2.0]),
        (10.0, vec![1.0, 2.0], vec![1.0, 2.0]),
    ]);
    r.pop();
    assert!(evaluate(&r).unwrap_err().to_string().contains("10 mm"));
}

proptest! {
    /// ISO 230-2 invariants: M ≤ E, E ≥ max(E↑, E↓), R ≥ max(R↑, R↓), A ≥ E, A ≥ max(A↑, A↓), B ≤ E.
    #[test]
    fn invariants(vals in prop::collection::vec(-20.0f64..20.0, 60)) {
        // 6 targets × 5 runs × 2 directions
        let data: Vec<(f64, Vec<f64>, Vec<f64>)> = (0..6)
            .map(|i| (i as f64 * 50.0, vals[i * 10..i * 10 + 5].to_vec(), vals[i * 10 + 5..i * 10 + 10].to_vec()))
            .collect();
        let a = evaluate(&readings(&data)).unwrap();
        let tol = 1e-9;
        prop_assert!(a.mean_range_um <= a.systematic_um + tol);
        prop_assert!(a.systematic_um + tol >= a.systematic_up_um.max(a.systematic_down_um));
        prop_assert!(a.repeatability_um + tol >= a.repeatability_up_um.max(a.repeatability_down_um));
        prop_assert!(a.accuracy_um + tol >= a.systematic_um);
        prop_assert!(a.accuracy_um + tol >= a.accuracy_up_um.max(a.accuracy_down_um));
        prop_assert!(a.reversal_b_um <= a.systematic_um + tol);
    }
}
