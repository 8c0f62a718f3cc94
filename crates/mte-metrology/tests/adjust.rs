//! Multilateration adjustment: an independent dense formulation, recovery with ~95 % coverage,
//! S-transformation invariants, data snooping, and bad input.

use mte_metrology::adjust::{AdjustParams, Datum, adjust};
use mte_metrology::network::{LengthUncertainty, Network, Vec3, length_and_jacobian};
use mte_metrology::simulate::{
    SmoothErrorField, StationLayout, align_to_nominal, cube_edge_targets, simulate,
};
use nalgebra::{DMatrix, DVector};

fn sim(layout: StationLayout, free: bool, seed: u64, max_um: f64) -> (Network, Vec<Vec3>) {
    let targets = cube_edge_targets(500.0, 2);
    let field = SmoothErrorField::new(500.0, &targets, max_um);
    let s = simulate(
        &layout.stations(500.0, free),
        &targets,
        &|p: &Vec3| field.eval(p),
        LengthUncertainty::SEED004,
        seed,
    )
    .unwrap();
    (s.network, s.true_targets)
}

/// Independent formulation: dense Gauss–Newton on the bordered system [[N, D],[Dᵀ, 0]] with
/// D = rigid-motion rows at the nominal targets; covariance = top-left block of its inverse.
#[test]
fn schur_equals_dense_bordered_solution() {
    let (net, _) = sim(StationLayout::Six, true, 3, 20.0);
    let adj = adjust(&net, &AdjustParams::default()).unwrap();
    let m = net.stations.len();
    let n = net.targets.len();
    let u = 4 * m + 3 * n;
    let c: Vec3 = net.targets.iter().map(|t| t.nominal_mm).sum::<Vec3>() / n as f64;
    let mut x = DVector::<f64>::zeros(u);
    for (i, s) in net.stations.iter().enumerate() {
        x.rows_mut(4 * i, 3).copy_from(&s.position_mm);
        x[4 * i + 3] = s.dead_path_mm;
    }
    for (j, t) in net.targets.iter().enumerate() {
        x.rows_mut(4 * m + 3 * j, 3).copy_from(&t.nominal_mm);
    }
    let mut d = DMatrix::<f64>::zeros(u, 6);
    for (j, t) in net.targets.iter().enumerate() {
        let p = t.nominal_mm - c;
        let r = 4 * m + 3 * j;
        for k in 0..3 {
            d[(r + k, k)] = 1.0;
        }
        // −[p]×
        d[(r, 4)] = -p.z;
        d[(r, 5)] = p.y;
        d[(r + 1, 3)] = p.z;
        d[(r + 1, 5)] = -p.x;
        d[(r + 2, 3)] = -p.y;
        d[(r + 2, 4)] = p.x;
    }
    let scale = 1e4; // bring D to the size of N's entries for a well-conditioned bordered matrix
    let mut binv = DMatrix::<f64>::zeros(u + 6, u + 6);
    for _ in 0..10 {
        let mut a = DMatrix::<f64>::zeros(net.observations.len(), u);
        let mut f = DVector::<f64>::zeros(net.observations.len());
        for (k, o) in net.observations.iter().enumerate() {
            let q = Vec3::new(x[4 * o.station], x[4 * o.station + 1], x[4 * o.station + 2]);
            let p = Vec3::new(
                x[4 * m + 3 * o.target],
                x[4 * m + 3 * o.target + 1],
                x[4 * m + 3 * o.target + 2],
            );
            let (l, jac) = length_and_jacobian(&q, x[4 * o.station + 3], &p, 0.0).unwrap();
            let w = 1.0 / o.sigma_mm;
            for r in 0..3 {
                a[(k, 4 * o.station + r)] = jac.d_station[r] * w;
                a[(k, 4 * m + 3 * o.target + r)] = jac.d_target[r] * w;
            }
            a[(k, 4 * o.station + 3)] = jac.d_dead_path * w;
            f[k] = (o.length_mm - l) * w;
        }
        let nmat = a.transpose() * &a;
        let mut b = DMatrix::<f64>::zeros(u + 6, u + 6);
        b.view_mut((0, 0), (u, u)).copy_from(&nmat);
        b.view_mut((0, u), (u, 6)).copy_from(&(&d * scale));
        b.view_mut((u, 0), (6, u))
            .copy_from(&(d.transpose() * scale));
        let mut rhs = DVector::<f64>::zeros(u + 6);
        rhs.rows_mut(0, u).copy_from(&(a.transpose() * &f));
        let mut xr = x.clone();
        for (j, t) in net.targets.iter().enumerate() {
            for k in 0..3 {
                xr[4 * m + 3 * j + k] -= t.nominal_mm[k];
            }
        }
        let cons = -(d.transpose() * {
            let mut v = DVector::<f64>::zeros(u);
            v.rows_mut(4 * m, 3 * n).copy_from(&xr.rows(4 * m, 3 * n));
            v
        }) * scale;
        rhs.rows_mut(u, 6).copy_from(&cons);
        binv = b.clone().try_inverse().unwrap();
        let dx = (&binv * rhs).rows(0, u).into_owned();
        x += &dx;
        if dx.amax() < 1e-10 {
            break;
        }
    }
    for (j, t) in adj.targets.iter().enumerate() {
        for k in 0..3 {
            assert!(
                (t.position_mm[k] - x[4 * m + 3 * j + k]).abs() < 1e-8,
                "target {j}"
            );
        }
    }
    for (i, s) in adj.stations.iter().enumerate() {
        assert!((s.dead_path_mm - x[4 * i + 3]).abs() < 1e-8);
    }
    // covariance: top-left block of the bordered inverse (constrained g-inverse of N)
    let q = adj.dense_covariance().unwrap();
    let mut worst: f64 = 0.0;
    for r in 0..u {
        for cc in 0..u {
            let s = (q[(r, r)] * q[(cc, cc)]).sqrt();
            worst = worst.max((q[(r, cc)] - binv[(r, cc)]).abs() / s);
        }
    }
    assert!(worst < 1e-6, "covariance differs by {worst:e}");
}

/// Recovery within the stated uncertainty: 200 simulated networks (4 low stations, free dead
/// paths, 20 µm field, seed-004 noise). Each coordinate error (adjusted − truth in the datum)
/// lies within ±1.96σ in ~95 % of cases; mean σ₀'² ≈ 1.
#[test]
fn recovery_coverage_near_95_percent() {
    let mut inside = 0usize;
    let mut inside3 = 0usize;
    let mut total = 0usize;
    let mut s0 = 0.0;
    let runs = 200;
    let chi3 = mte_metrology::stats::chi2_quantile(0.95, 3.0);
    for seed in 0..runs {
        let (net, truth) = sim(StationLayout::FourLow, true, 1000 + seed, 20.0);
        let adj = adjust(&net, &AdjustParams::default()).unwrap();
        let nominal: Vec<Vec3> = net.targets.iter().map(|t| t.nominal_mm).collect();
        let aligned = align_to_nominal(&truth, &nominal);
        for (t, tr) in adj.targets.iter().zip(&aligned) {
            let e = t.position_mm - tr;
            let c = t.covariance();
            for k in 0..3 {
                total += 1;
                if e[k].abs() <= 1.959964 * c[(k, k)].sqrt() {
                    inside += 1;
                }
            }
            let m2 = e.dot(&(c.try_inverse().unwrap() * e));
            if m2 <= chi3 {
                inside3 += 1;
            }
        }
        s0 += adj.global.sigma0_ratio.powi(2);
    }
    let cov1 = inside as f64 / total as f64;
    let cov3 = inside3 as f64 * 3.0 / total as f64;
    s0 /= runs as f64;
    eprintln!("coverage per coordinate {cov1:.4}, 3-D ellipsoid {cov3:.4}, mean σ0'² {s0:.3}");
    assert!((cov1 - 0.95).abs() < 0.015, "coverage {cov1}");
    assert!((cov3 - 0.95).abs() < 0.02, "ellipsoid coverage {cov3}");
    // σ0'² ~ χ²_f/f with f = 14: mean 1, sd of the mean over 200 runs = √(2/14/200) = 0.027
    assert!((s0 - 1.0).abs() < 0.1, "mean σ0'² {s0}");
}

#[test]
fn s_transformation_keeps_invariants_and_equals_direct_datum() {
    let (net, _) = sim(StationLayout::FourLow, true, 21, 20.0);
    let a = adjust(&net, &AdjustParams::default()).unwrap();
    let idx = |id: &str| net.target_index(id).unwrap();
    for datum in [
        Datum::ThreeTwoOne {
            origin: idx("P5"),
            x_axis: idx("P6"),
            xy_plane: idx("P3"),
        },
        Datum::TargetSubset(vec![0, 5, 9, 14, 19, 23]),
    ] {
        let b = a.s_transform(datum.clone()).unwrap();
        let direct = adjust(
            &net,
            &AdjustParams {
                datum: datum.clone(),
                ..Default::default()
            },
        )
        .unwrap();
        assert_ne!(a.datum_description, b.datum_description);
        // invariant: residuals, σ0, redundancy, distances
        assert!((a.global.pvv - b.global.pvv).abs() < 1e-9 * a.global.pvv);
        for (x, y) in a.observations.iter().zip(&b.observations) {
            assert!((x.residual_mm - y.residual_mm).abs() < 1e-10);
            assert!((x.redundancy - y.redundancy).abs() < 1e-8);
        }
        for (p, q) in [(0, 23), (3, 17), (8, 12)] {
            assert!((a.target_distance_mm(p, q) - b.target_distance_mm(p, q)).abs() < 1e-10);
        }
        // datum-dependent: coordinates and covariance equal the direct adjustment in that datum
        for (t, u) in b.targets.iter().zip(&direct.targets) {
            assert!((t.position_mm - u.position_mm).amax() < 1e-8);
            let (c1, c2) = (t.covariance(), u.covariance());
            // relative to the largest target variance (the 3-2-1 origin block is exactly 0)
            assert!(
                (c1 - c2).amax() < 1e-6 * 1e-6,
                "{datum:?} {}: {:e}",
                t.id,
                (c1 - c2).amax()
            );
        }
        if let Datum::ThreeTwoOne { origin, .. } = datum {
            assert!(b.targets[origin].deviation_mm.amax() < 1e-12);
            assert!(b.targets[origin].covariance().amax() < 1e-16);
            // the datum moved: P5 had a non-zero error in the nominal datum
            assert!(a.targets[origin].deviation_mm.norm() > 1e-4);
        }
        // the distance's variance is invariant too: var(|Pa − Pb|) from blocks
        let (p, q) = (2, 20);
        // (each network uses its own direction: the two datums differ by a rotation of ~4e-5 rad)
        let var = |adj: &mte_metrology::adjust::Adjustment| {
            let dir = (adj.targets[p].position_mm - adj.targets[q].position_mm).normalize();
            let cpp = adj.covariance_block(p, p).unwrap();
            let cqq = adj.covariance_block(q, q).unwrap();
            let cpq = adj.covariance_block(p, q).unwrap();
            dir.dot(&((cpp + cqq - cpq - cpq.transpose()) * dir))
        };
        assert!(
            (var(&a) - var(&b)).abs() < 1e-8 * var(&a),
            "{} {}",
            var(&a),
            var(&b)
        );
    }
}

#[test]
fn data_snooping_finds_a_gross_error() {
    let (mut net, _) = sim(StationLayout::Six, true, 5, 20.0);
    let k = 37;
    net.observations[k].length_mm += 30.0 * net.observations[k].sigma_mm;
    let a = adjust(&net, &AdjustParams::default()).unwrap();
    let worst = a
        .observations
        .iter()
        .enumerate()
        .max_by(|x, y| {
            x.1.standardised_residual
                .abs()
                .total_cmp(&y.1.standardised_residual.abs())
        })
        .unwrap();
    assert_eq!(worst.0, k);
    assert!(worst.1.suspect);
    assert!(!a.global.passed);
    let sr: f64 = a.observations.iter().map(|o| o.redundancy).sum();
    assert!((sr - a.global.degrees_of_freedom as f64).abs() < 1e-6);
}

#[test]
fn observation_jacobian_matches_finite_differences() {
    let q = Vec3::new(-75.0, 30.0, -150.0);
    let p = Vec3::new(210.0, 400.0, 333.0);
    let (d, k) = (41.0, 2e-6);
    let (_, j) = length_and_jacobian(&q, d, &p, k).unwrap();
    let f = |q: Vec3, d: f64, p: Vec3, k: f64| mte_metrology::network::predict_length(&q, d, &p, k);
    let h = 1e-4;
    for r in 0..3 {
        let e = Vec3::ith(r, h);
        assert!(((f(q, d, p + e, k) - f(q, d, p - e, k)) / (2.0 * h) - j.d_target[r]).abs() < 1e-8);
        assert!(
            ((f(q + e, d, p, k) - f(q - e, d, p, k)) / (2.0 * h) - j.d_station[r]).abs() < 1e-8
        );
    }
    assert!(((f(q, d, p, k + 1e-6) - f(q, d, p, k - 1e-6)) / 2e-6 - j.d_scale).abs() < 1e-5);
    assert_eq!(j.d_dead_path, -1.0);
    assert!(length_and_jacobian(&q, d, &q, 0.0).is_err());
}

#[test]
fn bad_input_gives_clear_errors() {
    let (net, _) = sim(StationLayout::FourLow, true, 2, 20.0);
    let p = AdjustParams::default();
    let msg = |n: &Network| adjust(n, &p).unwrap_err().to_string();

    let mut n = net.clone();
    n.stations.truncate(3);
    n.observations.retain(|o| o.station < 3);
    assert!(msg(&n).contains("at least 4"), "{}", msg(&n));

    let mut n = net.clone();
    for s in &mut n.stations {
        s.position_mm.z = -100.0;
    }
    assert!(msg(&n).contains("coplanar"), "{}", msg(&n));

    let mut n = net.clone();
    n.targets[3].id = "P1".into();
    assert!(msg(&n).contains("duplicate target id `P1`"));
    let mut n = net.clone();
    n.stations[2].id = "S1".into();
    assert!(msg(&n).contains("duplicate station id `S1`"));

    let mut n = net.clone();
    n.observations[5].length_mm = -3.0;
    assert!(
        msg(&n).contains("negative length") && msg(&n).contains("S1 → P6"),
        "{}",
        msg(&n)
    );

    let mut n = net.clone();
    n.observations[7].length_mm = f64::NAN;
    assert!(msg(&n).contains("NaN"));
    let mut n = net.clone();
    n.targets[0].nominal_mm.x = f64::NAN;
    assert!(msg(&n).contains("P1"));
    let mut n = net.clone();
    n.observations[0].sigma_mm = 0.0;
    assert!(msg(&n).contains("standard deviation"));

    // too few targets for 4 stations with dead paths: 4·5 = 20 < 16 + 15 − 6 = 25
    let mut n = net.clone();
    n.targets.truncate(5);
    n.observations.retain(|o| o.target < 5);
    assert!(msg(&n).contains("m·n ≥ 4m + 3n − 6"), "{}", msg(&n));

    // a target seen from 2 stations only
    let mut n = net.clone();
    n.observations
        .retain(|o| !(o.target == 4 && o.station >= 2));
    assert!(msg(&n).contains("`P5` is seen from 2"), "{}", msg(&n));

    let bad = AdjustParams {
        datum: Datum::ThreeTwoOne {
            origin: 0,
            x_axis: 0,
            xy_plane: 1,
        },
        ..Default::default()
    };
    assert!(
        adjust(&net, &bad)
            .unwrap_err()
            .to_string()
            .contains("datum")
    );
    // 3-2-1 with an x_axis target straight above the origin (differs only in z) cannot fix rotation about z
    let bad = AdjustParams {
        datum: Datum::ThreeTwoOne {
            origin: 0,
            x_axis: 1,
            xy_plane: 2,
        },
        ..Default::default()
    };
    assert!(
        adjust(&net, &bad)
            .unwrap_err()
            .to_string()
            .contains("datum")
    );
    let bad = AdjustParams {
        datum: Datum::TargetSubset(vec![0, 99]),
        ..Default::default()
    };
    assert!(adjust(&net, &bad).is_err());
}

#[test]
fn cross_blocks_equal_dense_covariance() {
    let (net, _) = sim(StationLayout::FourLow, false, 4, 20.0);
    for datum in [
        Datum::NominalTargets,
        Datum::ThreeTwoOne {
            origin: 4,
            x_axis: 5,
            xy_plane: 2,
        },
    ] {
        let a = adjust(
            &net,
            &AdjustParams {
                datum,
                ..Default::default()
            },
        )
        .unwrap();
        let q = a.dense_covariance().unwrap();
        let ns = 3 * net.stations.len();
        for (p, r) in [(2, 20), (0, 23), (7, 7)] {
            let b = a.covariance_block(p, r).unwrap();
            for i in 0..3 {
                for j in 0..3 {
                    assert!(
                        (b[(i, j)] - q[(ns + 3 * p + i, ns + 3 * r + j)]).abs() < 1e-12,
                        "{p} {r}"
                    );
                }
            }
        }
    }
}

#[test]
fn scale_95_is_the_chi2_quantile() {
    let q = mte_metrology::stats::chi2_quantile(0.95, 3.0).sqrt();
    assert!(
        (mte_metrology::adjust::Ellipsoid::SCALE_95 - q).abs() < 1e-12,
        "{q}"
    );
}

#[test]
fn stations_placed_roughly_converge_to_the_same_adjustment() {
    // A user's approximate station positions half a metre to a metre off, dead paths unknown
    // (0): the adjustment starts from the stations the lengths give in closed form and lands
    // where it lands from good start values.
    let (net, _) = sim(StationLayout::Six, true, 5, 20.0);
    let good = adjust(&net, &AdjustParams::default()).unwrap();
    let mut rough = net.clone();
    for (i, s) in rough.stations.iter_mut().enumerate() {
        let k = i as f64;
        s.position_mm += Vec3::new(800.0 - 300.0 * k, 600.0 * (k % 2.0) - 300.0, 500.0);
        s.dead_path_mm = 0.0;
    }
    let from_rough = adjust(&rough, &AdjustParams::default()).unwrap();
    for (a, b) in good.targets.iter().zip(&from_rough.targets) {
        assert!(
            (a.position_mm - b.position_mm).amax() < 1e-9,
            "{} {}",
            a.id,
            b.id
        );
    }
    for (a, b) in good.stations.iter().zip(&from_rough.stations) {
        assert!((a.position_mm - b.position_mm).amax() < 1e-6);
        assert!((a.dead_path_mm - b.dead_path_mm).abs() < 1e-6);
    }
}
