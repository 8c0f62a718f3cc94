//! The pose-error sensitivity model: its first-order map against central differences of the
//! exact pose error, and its input errors.

use mte::pose_model::{Linearisation, PoseErrorModel, PoseModelError};
use mte_errors::Catalogue;
use mte_kinematics::Machine;
use mte_sensitivity::Model;

fn setup() -> (Machine, Catalogue, Vec<Vec<f64>>) {
    let m = Machine::library("seed003-ac-table").unwrap();
    let c = Catalogue::seed003(&m).unwrap();
    let points = vec![
        vec![-400.0, -425.0, -275.0, 0.0, 0.0],
        vec![200.0, -100.0, 137.5, 0.7, 2.0],
    ];
    (m, c, points)
}

#[test]
fn first_order_is_the_derivative_of_the_exact_pose_error() {
    let (m, c, points) = setup();
    let lin = PoseErrorModel::new(&m, &c, points.clone(), Linearisation::FirstOrder).unwrap();
    let exact = PoseErrorModel::new(&m, &c, points, Linearisation::Exact).unwrap();
    let k = lin.n_inputs();
    assert_eq!(k, 41);
    assert_eq!(lin.n_outputs(), 12);
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for i in 0..k {
        let mut x = vec![0.0; k];
        x[i] = 1.0;
        let mut a = vec![0.0; 12];
        lin.evaluate(&x, &mut a);
        x[i] = h;
        let mut yp = vec![0.0; 12];
        exact.evaluate(&x, &mut yp);
        x[i] = -h;
        let mut ym = vec![0.0; 12];
        exact.evaluate(&x, &mut ym);
        for o in 0..12 {
            let fd = (yp[o] - ym[o]) / (2.0 * h);
            worst = worst.max((fd - a[o]).abs());
            scale = scale.max(a[o].abs());
        }
    }
    assert!(scale > 1.0, "effects too small: {scale}");
    assert!(
        worst < 1e-6 * scale,
        "first order vs differences: {worst} of {scale}"
    );
}

#[test]
fn batch_evaluation_matches_row_by_row() {
    let (m, c, points) = setup();
    let lin = PoseErrorModel::new(&m, &c, points, Linearisation::FirstOrder).unwrap();
    let k = lin.n_inputs();
    let xs: Vec<f64> = (0..3 * k)
        .map(|i| ((i * 37 % 11) as f64 - 5.0) * 1e-3)
        .collect();
    let mut batch = vec![0.0; 3 * 12];
    lin.evaluate_batch(3, &xs, &mut batch);
    for r in 0..3 {
        let mut y = [0.0; 12];
        // one input at a time, summed: the model is linear
        for i in 0..k {
            let mut x = vec![0.0; k];
            x[i] = xs[r * k + i];
            let mut yi = vec![0.0; 12];
            lin.evaluate(&x, &mut yi);
            y.iter_mut().zip(&yi).for_each(|(a, b)| *a += b);
        }
        for o in 0..12 {
            assert!(
                (y[o] - batch[r * 12 + o]).abs() < 1e-12,
                "row {r} output {o}"
            );
        }
    }
}

#[test]
fn bad_points_give_clear_errors() {
    let (m, c, _) = setup();
    let e = PoseErrorModel::new(&m, &c, vec![], Linearisation::Exact).unwrap_err();
    assert!(matches!(e, PoseModelError::NoPoints), "{e}");
    let e = PoseErrorModel::new(&m, &c, vec![vec![0.0; 4]], Linearisation::Exact).unwrap_err();
    assert!(
        e.to_string().contains("expected 5 axis commands, got 4"),
        "{e}"
    );
    let e = PoseErrorModel::new(
        &m,
        &c,
        vec![vec![0.0, f64::NAN, 0.0, 0.0, 0.0]],
        Linearisation::Exact,
    )
    .unwrap_err();
    assert!(e.to_string().contains("command 1 is not finite"), "{e}");
}
