//! The pose-error sensitivity model: its first-order map against central differences of the
//! exact pose error, and its input errors.

use mte_errors::Catalogue;
use mte_errors::pose_model::{Linearisation, PoseErrorModel, PoseModelError};
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

// ---- Error-set models: random entries as inputs, fixed entries held ----

use mte_errors::distribution::Distribution as ErrDist;
use mte_errors::errorset::ModelSpec;
use mte_errors::pose_model::{diagonal_points, generalised_index};
use mte_errors::units::Kind;
use mte_errors::{AxisState, ErrorSet, Evaluator};
use mte_sensitivity::sobol::{SobolParams, sobol};

/// Six random entries (one per pose direction at least, three distribution families) and three
/// fixed ones (a constant, a Legendre series, a Fourier series) on the seed 003 AC table.
fn error_set() -> ErrorSet {
    let um = 1e-3;
    let arcsec = std::f64::consts::PI / (180.0 * 3600.0);
    ErrorSet::new("test")
        .with_distribution(
            "EXX",
            ErrDist::Normal {
                mean: 1.0 * um,
                sd: 5.0 * um,
            },
            Kind::Length,
        )
        .with_constant("EYX", 3.0 * um, Kind::Length)
        .with_distribution(
            "EYY",
            ErrDist::Uniform {
                lo: -8.0 * um,
                hi: 4.0 * um,
            },
            Kind::Length,
        )
        .with_model(
            "EZZ",
            ModelSpec::Legendre {
                coefficients: vec![0.0, 6.0 * um, -2.0 * um],
                range: None,
            },
            Kind::Length,
        )
        .with_distribution(
            "EZY",
            ErrDist::TruncatedNormal {
                mean: 0.0,
                sd: 4.0 * um,
                lo: -6.0 * um,
                hi: 6.0 * um,
            },
            Kind::Length,
        )
        .with_distribution(
            "EAX",
            ErrDist::Normal {
                mean: 0.0,
                sd: 3.0 * arcsec,
            },
            Kind::Angle,
        )
        .with_distribution(
            "EBY",
            ErrDist::Normal {
                mean: 0.0,
                sd: 2.0 * arcsec,
            },
            Kind::Angle,
        )
        .with_distribution(
            "ECZ",
            ErrDist::Uniform {
                lo: -5.0 * arcsec,
                hi: 5.0 * arcsec,
            },
            Kind::Angle,
        )
        .with_model(
            "ECC",
            ModelSpec::Fourier {
                offset: 0.0,
                cos: vec![2.0 * arcsec],
                sin: vec![],
                period: 2.0 * std::f64::consts::PI,
                phase_origin: 0.0,
                position_kind: Kind::Angle,
            },
            Kind::Angle,
        )
}

/// Variance of an error-set distribution, from the textbook formulas (truncated normal: Johnson,
/// Kotz & Balakrishnan, eq. 13.134; `mte_errors::Distribution::sd` gives the parent's sd there).
fn variance(d: ErrDist) -> f64 {
    use mte_linalg::stats::normal_cdf;
    let pdf = |z: f64| (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
    match d {
        ErrDist::Normal { sd, .. } => sd * sd,
        ErrDist::Uniform { lo, hi } => (hi - lo).powi(2) / 12.0,
        ErrDist::TruncatedNormal { mean, sd, lo, hi } => {
            let (a, b) = ((lo - mean) / sd, (hi - mean) / sd);
            let z = normal_cdf(b) - normal_cdf(a);
            let r = (pdf(a) - pdf(b)) / z;
            sd * sd * (1.0 + (a * pdf(a) - b * pdf(b)) / z - r * r)
        }
    }
}

fn points(m: &Machine) -> Vec<Vec<f64>> {
    let mut p = diagonal_points(m, 3).unwrap();
    p.push(vec![100.0, -50.0, 20.0, 0.5, 1.0]);
    p.push(vec![-300.0, 200.0, -100.0, -1.2, 4.0]);
    p
}

/// Effects a_oi of the random entries, taken from the catalogue's own effect matrix (found by
/// name, independently of the model's column bookkeeping), and the inputs' variances from the
/// error set's distributions (`mte_errors::Distribution::sd`).
fn analytic_parts(
    m: &Machine,
    c: &Catalogue,
    set: &ErrorSet,
    pts: &[Vec<f64>],
) -> (Vec<Vec<f64>>, Vec<f64>) {
    let random = set.random_entries();
    let var: Vec<f64> = random
        .iter()
        .map(|&i| variance(set.entries[i].distribution.unwrap()))
        .collect();
    let mut a = Vec::new();
    for q in pts {
        let e = c.effect_matrix(m, q).unwrap();
        for r in 0..6 {
            a.push(
                random
                    .iter()
                    .map(|&i| e[(r, c.index_of(&set.entries[i].name).unwrap())])
                    .collect(),
            );
        }
    }
    (a, var)
}

#[test]
fn error_set_inputs_follow_the_distributions_and_fixed_entries_are_held() {
    let m = Machine::library("seed003-ac-table").unwrap();
    let c = Catalogue::for_machine(&m);
    let set = error_set();
    let pts = points(&m);
    let (problem, exact) =
        PoseErrorModel::from_error_set(&m, &c, &set, pts.clone(), Linearisation::Exact).unwrap();
    assert_eq!(problem.names(), ["EXX", "EYY", "EZY", "EAX", "EBY", "ECZ"]);
    for (inp, &i) in problem.inputs().iter().zip(&set.random_entries()) {
        let v = variance(set.entries[i].distribution.unwrap());
        // Same spread as the error set's distribution (independent implementations).
        assert!(
            (inp.dist.sd().powi(2) - v).abs() < 1e-12 * v,
            "{}: {} vs {v}",
            inp.name,
            inp.dist.sd().powi(2)
        );
    }
    // At sampled values, the exact model equals the Evaluator's exact pose error of the whole
    // set with the random entries set to those values (fixed models evaluated by the Evaluator).
    let k = problem.dim();
    let mut y = vec![0.0; exact.n_outputs()];
    for s in 0..3u64 {
        let x = set.sample_values(7, s);
        assert_eq!(x.len(), k);
        exact.evaluate(&x, &mut y);
        let ev = Evaluator::new(&m, &set.with_values(&x)).unwrap();
        let mut e = vec![0.0; m.n_slots()];
        for (p, q) in pts.iter().enumerate() {
            let pe = ev.pose_error(&AxisState::at(q), &mut e).unwrap();
            let want = pe.to_vec6();
            for (o, w) in want.iter().enumerate() {
                // 1e-12 mm / rad: rounding of two summation orders of the same slot errors.
                assert!(
                    (y[6 * p + o] - w).abs() < 1e-12,
                    "sample {s} point {p} component {o}: {} vs {w}",
                    y[6 * p + o]
                );
            }
        }
    }
}

#[test]
fn sobol_of_the_first_order_error_set_model_is_analytic() {
    let m = Machine::library("seed003-ac-table").unwrap();
    let c = Catalogue::for_machine(&m);
    let set = error_set();
    let pts = points(&m);
    let (problem, model) =
        PoseErrorModel::from_error_set(&m, &c, &set, pts.clone(), Linearisation::FirstOrder)
            .unwrap();
    let (a, var) = analytic_parts(&m, &c, &set, &pts);
    let r = sobol(
        &model,
        &problem,
        &SobolParams {
            n: 1 << 14,
            seed: 11,
            n_bootstrap: 0,
            ..Default::default()
        },
    )
    .unwrap();
    // Linear model, independent inputs: S_i = S_Ti = a_i² V_i / Σ_j a_j² V_j for each output.
    // 0.01: measured 1.1e-3 for the Saltelli/Jansen estimators at N = 2^14 (Sobol' sequence,
    // seed 11); a wrong column or variance is off by ≥ 0.1.
    let tol = 0.01;
    let mut worst: f64 = 0.0;
    for (o, out) in r.outputs.iter().enumerate() {
        let v: Vec<f64> = a[o].iter().zip(&var).map(|(ai, vi)| ai * ai * vi).collect();
        let tot: f64 = v.iter().sum();
        for (i, vi) in v.iter().enumerate() {
            let s = vi / tot;
            worst = worst
                .max((out.first[i] - s).abs())
                .max((out.total[i] - s).abs());
        }
        // The output variance too (relative), which the aggregate below weights by.
        assert!(
            (out.variance - tot).abs() < 0.02 * tot,
            "output {o}: variance {} vs {tot}",
            out.variance
        );
    }
    assert!(worst < tol, "largest |S − analytic| = {worst}");
    // Generalised index per direction: Σ_p a_pi² V_i / Σ_p Σ_j a_pj² V_j.
    let weights: Vec<f64> = r.outputs.iter().map(|o| o.variance).collect();
    let firsts: Vec<Vec<f64>> = r.outputs.iter().map(|o| o.first.clone()).collect();
    for d in 0..6 {
        let members: Vec<usize> = (0..pts.len()).map(|p| 6 * p + d).collect();
        let (agg, ci) = generalised_index(&firsts, &[], &weights, &members).unwrap();
        assert!(ci.is_empty());
        let num: Vec<f64> = (0..problem.dim())
            .map(|i| members.iter().map(|&o| a[o][i] * a[o][i] * var[i]).sum())
            .collect();
        let den: f64 = num.iter().sum();
        for i in 0..problem.dim() {
            assert!(
                (agg[i] - num[i] / den).abs() < tol,
                "direction {d} input {i}: {} vs {}",
                agg[i],
                num[i] / den
            );
        }
        // With the exact per-output indices and variances the formula is exact.
        let exact_s: Vec<Vec<f64>> = a
            .iter()
            .map(|ao| {
                let v: Vec<f64> = ao.iter().zip(&var).map(|(x, vi)| x * x * vi).collect();
                let t: f64 = v.iter().sum();
                v.iter().map(|x| x / t).collect()
            })
            .collect();
        let exact_w: Vec<f64> = a
            .iter()
            .map(|ao| ao.iter().zip(&var).map(|(x, vi)| x * x * vi).sum())
            .collect();
        let (agg, _) = generalised_index(&exact_s, &[], &exact_w, &members).unwrap();
        for i in 0..problem.dim() {
            assert!(
                (agg[i] - num[i] / den).abs() < 1e-12,
                "direction {d} input {i}"
            );
        }
    }
}

#[test]
fn error_set_problems_give_clear_errors() {
    let m = Machine::library("seed003-ac-table").unwrap();
    let c = Catalogue::for_machine(&m);
    let pts = vec![vec![0.0; 5]];
    let fo = Linearisation::FirstOrder;
    let err = |set: &ErrorSet, pts: Vec<Vec<f64>>| {
        PoseErrorModel::from_error_set(&m, &c, set, pts, fo)
            .unwrap_err()
            .to_string()
    };
    let e = err(
        &ErrorSet::new("s").with_constant("EXX", 0.001, Kind::Length),
        pts.clone(),
    );
    assert!(
        e.contains("error set `s`") && e.contains("distribution"),
        "{e}"
    );
    let e = err(
        &ErrorSet::new("s").with_distribution(
            "EQQ",
            ErrDist::Normal {
                mean: 0.0,
                sd: 0.001,
            },
            Kind::Length,
        ),
        pts.clone(),
    );
    assert!(e.contains("unknown error parameter `EQQ`"), "{e}");
    let mut set = ErrorSet::new("s").with_distribution(
        "EXX",
        ErrDist::Normal {
            mean: 0.0,
            sd: 0.001,
        },
        Kind::Length,
    );
    set.entries[0].spec = ModelSpec::Legendre {
        coefficients: vec![0.0, 0.001],
        range: None,
    };
    let e = err(&set, pts.clone());
    assert!(
        e.contains("`EXX` (parameters[0])") && e.contains("not a constant"),
        "{e}"
    );
    let good = ErrorSet::new("s").with_distribution(
        "EXX",
        ErrDist::Normal {
            mean: 0.0,
            sd: 0.001,
        },
        Kind::Length,
    );
    let e = err(&good, vec![vec![0.0; 4]]);
    assert!(
        e.contains("test point 0: expected 5 axis commands, got 4"),
        "{e}"
    );
    // A fixed model outside its range at a test point is named.
    let table = ErrorSet::new("s")
        .with_distribution(
            "EXX",
            ErrDist::Normal {
                mean: 0.0,
                sd: 0.001,
            },
            Kind::Length,
        )
        .with_model(
            "EYX",
            ModelSpec::Table {
                positions: vec![0.0, 10.0],
                values: vec![0.0, 0.001],
                position_kind: Kind::Length,
            },
            Kind::Length,
        );
    let e = err(&table, vec![vec![50.0, 0.0, 0.0, 0.0, 0.0]]);
    assert!(e.contains("EYX") && e.contains("outside"), "{e}");
    assert!(
        diagonal_points(&m, 1)
            .unwrap_err()
            .to_string()
            .contains("at least 2")
    );
}

/// The bundled seed 003 tolerance set (41 entries under the paper's names) reproduces the
/// study's model: the same 41 parameters of `Catalogue::seed003` in the same order, σ = 5 µm and
/// 10/3″, and the same effect matrix at the study's 20 points.
#[test]
fn seed003_tolerance_fixture_is_the_study() {
    let m = Machine::library("seed003-ac-table").unwrap();
    let study = Catalogue::seed003(&m).unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/errors/seed003-tolerances.json");
    let set = mte_errors::ErrorSet::from_file(&path).unwrap();
    let points = mte_errors::pose_model::diagonal_points(&m, 5).unwrap();
    let (problem, model) = PoseErrorModel::from_error_set(
        &m,
        &Catalogue::for_machine(&m),
        &set,
        points.clone(),
        Linearisation::FirstOrder,
    )
    .unwrap();
    let reference = PoseErrorModel::new(&m, &study, points, Linearisation::FirstOrder).unwrap();
    assert_eq!(problem.dim(), 41);
    let arcsec = std::f64::consts::PI / 648_000.0;
    for (i, (name, input)) in problem.names().iter().zip(problem.inputs()).enumerate() {
        let param = &study.parameters()[i];
        assert!(
            *name == param.name || param.aliases.contains(name),
            "input {i}: {name} is not the study's {} ({:?})",
            param.name,
            param.aliases
        );
        let sd = input.dist.sd();
        let want = if param.quantity == mte_errors::units::Kind::Angle {
            10.0 / 3.0 * arcsec
        } else {
            0.005
        };
        assert!((sd - want).abs() < 1e-12 * want, "{name}: σ {sd} vs {want}");
    }
    let diff = (model.effect() - reference.effect()).abs().max();
    assert!(diff < 1e-12, "effect matrices differ by {diff}");
}
