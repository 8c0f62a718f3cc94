//! Tests of the least-squares module. Reference values are analytic formulas, the normal
//! equations solved by an independent route (nalgebra's Cholesky/LU), or the defining
//! properties (Penrose conditions, KKT conditions).

use super::*;
use approx::assert_relative_eq;

/// Tolerance for well-conditioned random problems (condition ≲ 1e2): a few hundred ulps.
const TIGHT: f64 = 1e-11;

/// SplitMix64: a deterministic generator for test matrices, independent of any crate.
struct Gen(u64);
impl Gen {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    fn mat(&mut self, m: usize, n: usize) -> DMat {
        DMat::from_fn(m, n, |_, _| self.next_f64())
    }
    fn vec(&mut self, m: usize) -> DVec {
        DVec::from_fn(m, |_, _| self.next_f64())
    }
}

fn normal_equation_solution(a: &DMat, b: &DVec) -> DVec {
    let ata = a.transpose() * a;
    ata.cholesky().expect("SPD").solve(&(a.transpose() * b))
}

/// Estimator map of a fit, column by column: x(b) is affine, so M eᵢ = x(eᵢ) − x(0).
fn estimator_matrix(fitter: &Lstsq, a: &DMat) -> DMat {
    let m = a.nrows();
    let x0 = fitter.fit(a, &DVec::zeros(m)).unwrap().x;
    let mut cols = Vec::new();
    for i in 0..m {
        let mut e = DVec::zeros(m);
        e[i] = 1.0;
        cols.push(fitter.fit(a, &e).unwrap().x - &x0);
    }
    DMat::from_columns(&cols)
}

#[test]
fn straight_line_matches_textbook_formulas() {
    // y = c0 + c1 t: c1 = Sty/Stt, c0 = ȳ − c1 t̄, Var(c1) = σ²/Stt, Var(c0) = σ²(1/n + t̄²/Stt)
    let t = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
    let y = [0.9, 3.2, 4.8, 7.1, 9.2, 10.8];
    let n = t.len() as f64;
    let tm = t.iter().sum::<f64>() / n;
    let ym = y.iter().sum::<f64>() / n;
    let stt: f64 = t.iter().map(|v| (v - tm).powi(2)).sum();
    let sty: f64 = t.iter().zip(&y).map(|(a, b)| (a - tm) * (b - ym)).sum();
    let c1 = sty / stt;
    let c0 = ym - c1 * tm;
    let rss: f64 = t
        .iter()
        .zip(&y)
        .map(|(a, b)| (b - c0 - c1 * a).powi(2))
        .sum();
    let s2 = rss / (n - 2.0);

    let a = DMat::from_fn(6, 2, |i, j| if j == 0 { 1.0 } else { t[i] });
    let b = DVec::from_column_slice(&y);
    let fit = lstsq(&a, &b).unwrap();
    assert_relative_eq!(fit.x[0], c0, max_relative = TIGHT);
    assert_relative_eq!(fit.x[1], c1, max_relative = TIGHT);
    assert_relative_eq!(fit.rss, rss, max_relative = 1e-10);
    assert_eq!(fit.dof, 4);
    assert_eq!(fit.rank, 2);
    assert_relative_eq!(fit.sigma0.unwrap(), s2.sqrt(), max_relative = 1e-10);
    let cov = fit.covariance.as_ref().unwrap();
    assert_relative_eq!(cov[(1, 1)], s2 / stt, max_relative = 1e-10);
    assert_relative_eq!(
        cov[(0, 0)],
        s2 * (1.0 / n + tm * tm / stt),
        max_relative = 1e-10
    );
    assert_relative_eq!(cov[(0, 1)], -s2 * tm / stt, max_relative = 1e-10);
    // QR route gives the same
    let xq = lstsq_qr(&a, &b).unwrap();
    assert_relative_eq!(xq, fit.x, max_relative = TIGHT);
}

#[test]
fn agrees_with_normal_equations_on_random_problems() {
    let mut g = Gen(11);
    for &(m, n) in &[(8, 3), (30, 6), (50, 12), (7, 7)] {
        let a = g.mat(m, n);
        let b = g.vec(m);
        let x_ne = normal_equation_solution(&a, &b);
        let scale = x_ne.amax().max(1.0);
        // condition numbers of these matrices are < 1e3, the normal equations square it
        let tol = 1e-9 * scale;
        let fit = lstsq(&a, &b).unwrap();
        assert!((&fit.x - &x_ne).amax() < tol, "svd fit {m}×{n}");
        assert!(
            (lstsq_qr(&a, &b).unwrap() - &x_ne).amax() < tol,
            "qr {m}×{n}"
        );
        assert!(
            (lstsq_min_norm(&a, &b, RankTolerance::Auto).unwrap() - &x_ne).amax() < tol,
            "min-norm {m}×{n}"
        );
        let ata_inv = (a.transpose() * &a).try_inverse().unwrap();
        assert!((&fit.cofactor - &ata_inv).amax() < 1e-9 * ata_inv.amax());
        // residual orthogonal to the columns
        assert!((a.transpose() * &fit.residuals).amax() < 1e-12 * (m as f64));
    }
}

#[test]
fn rank_of_constructed_low_rank_products() {
    // A = B C with B m×r, C r×n random has rank r exactly (with probability 1)
    let mut g = Gen(3);
    for &(m, n) in &[(10, 6), (4, 9), (6, 6)] {
        for r in 1..=m.min(n) {
            let a = g.mat(m, r) * g.mat(r, n);
            assert_eq!(
                numerical_rank(&a, RankTolerance::Auto).unwrap(),
                r,
                "{m}×{n} rank {r}"
            );
            let ns = null_space(&a, RankTolerance::Auto).unwrap();
            assert_eq!(ns.ncols(), n - r);
            assert!((&a * &ns).amax() < 1e-12 * a.amax() * (n as f64));
            let ident = DMat::identity(n - r, n - r);
            assert!((ns.transpose() * &ns - ident).amax() < 1e-13);
        }
    }
}

#[test]
fn rank_tolerance_choices_are_respected() {
    // A = U diag(1, 1e-6, 1e-13) Vᵀ with orthogonal U, V from a QR of random matrices
    let mut g = Gen(5);
    let u = g.mat(5, 3).qr().q();
    let v = g.mat(3, 3).qr().q();
    let s = DMat::from_diagonal(&DVec::from_vec(vec![1.0, 1e-6, 1e-13]));
    let a = &u * s * v.transpose();
    assert_eq!(numerical_rank(&a, RankTolerance::Auto).unwrap(), 3); // τ = 5ε ≈ 1.1e-15
    assert_eq!(
        numerical_rank(&a, RankTolerance::Relative(1e-10)).unwrap(),
        2
    );
    assert_eq!(
        numerical_rank(&a, RankTolerance::Absolute(1e-3)).unwrap(),
        1
    );
    assert!(matches!(
        numerical_rank(&a, RankTolerance::Relative(-1.0)),
        Err(LinalgError::InvalidParameter { .. })
    ));
    let sv = svd(&a).unwrap();
    assert_relative_eq!(sv.singular_values[1], 1e-6, max_relative = 1e-8);
    assert_relative_eq!(sv.condition_number(), 1e13, max_relative = 1e-2);
}

#[test]
fn pseudo_inverse_satisfies_penrose_conditions() {
    let mut g = Gen(7);
    let cases = [
        g.mat(6, 4),               // tall, full rank
        g.mat(3, 7),               // wide
        g.mat(8, 2) * g.mat(2, 5), // rank 2
        DMat::zeros(3, 2),         // zero matrix: A⁺ = 0
    ];
    for a in &cases {
        let p = pinv(a, RankTolerance::Auto).unwrap();
        assert_eq!(p.shape(), (a.ncols(), a.nrows()));
        let tol = 1e-12 * (1.0 + a.amax()) * (1.0 + p.amax()).powi(2);
        assert!((a * &p * a - a).amax() < tol, "A A⁺ A = A");
        assert!((&p * a * &p - &p).amax() < tol, "A⁺ A A⁺ = A⁺");
        let ap = a * &p;
        assert!((&ap - ap.transpose()).amax() < tol, "(A A⁺)ᵀ = A A⁺");
        let pa = &p * a;
        assert!((&pa - pa.transpose()).amax() < tol, "(A⁺ A)ᵀ = A⁺ A");
    }
}

#[test]
fn minimum_norm_solution_is_orthogonal_to_null_space_and_solves_normal_equations() {
    let mut g = Gen(9);
    let a = g.mat(10, 3) * g.mat(3, 6); // rank 3, 6 unknowns
    let b = g.vec(10);
    let x = lstsq_min_norm(&a, &b, RankTolerance::Auto).unwrap();
    let ns = null_space(&a, RankTolerance::Auto).unwrap();
    assert!((ns.transpose() * &x).amax() < 1e-12);
    let grad = a.transpose() * (&a * &x - &b);
    assert!(grad.amax() < 1e-11);
    // the fit in minimum-norm mode gives the same and reports the null space
    let fit = Lstsq::new().minimum_norm().fit(&a, &b).unwrap();
    assert!((&fit.x - &x).amax() < 1e-12);
    assert_eq!(fit.rank, 3);
    assert_eq!(fit.null_space.ncols(), 3);
    assert_eq!(fit.dof, 7);
    // its cofactor is the pseudo-inverse of AᵀA = M Mᵀ of the estimator x = A⁺ b
    let p = pinv(&a, RankTolerance::Auto).unwrap();
    assert!((&fit.cofactor - &p * p.transpose()).amax() < 1e-9 * fit.cofactor.amax());
}

#[test]
fn diagonal_weights_equal_row_scaling() {
    let mut g = Gen(13);
    let a = g.mat(12, 4);
    let b = g.vec(12);
    let w = DVec::from_fn(12, |i, _| 0.5 + i as f64);
    let fit = weighted_lstsq(&a, &b, &Weights::Diagonal(w.clone())).unwrap();
    // whitened by hand: rows × √wᵢ
    let mut aw = a.clone();
    let mut bw = b.clone();
    for i in 0..12 {
        aw.row_mut(i).scale_mut(w[i].sqrt());
        bw[i] *= w[i].sqrt();
    }
    let plain = lstsq(&aw, &bw).unwrap();
    assert!((&fit.x - &plain.x).amax() < TIGHT);
    assert_relative_eq!(fit.rss, plain.rss, max_relative = 1e-10);
    assert!((&fit.cofactor - &plain.cofactor).amax() < 1e-10 * plain.cofactor.amax());
    // raw residuals are b − A x, weighted residuals are √w ⊙ that
    assert!((&fit.residuals - (&b - &a * &fit.x)).amax() < 1e-14);
    assert!((&fit.weighted_residuals - &plain.residuals).amax() < 1e-12);
    // normal equations AᵀWA x = AᵀWb
    let wm = DMat::from_diagonal(&w);
    let lhs = a.transpose() * &wm * &a;
    let rhs = a.transpose() * &wm * &b;
    let x_ne = lhs.clone().cholesky().unwrap().solve(&rhs);
    assert!((&fit.x - x_ne).amax() < 1e-10);
    // a diagonal covariance 1/w is the same problem
    let cov = DMat::from_diagonal(&w.map(|v| 1.0 / v));
    let fit_cov = weighted_lstsq(&a, &b, &Weights::Covariance(cov)).unwrap();
    assert!((&fit_cov.x - &fit.x).amax() < TIGHT);
    assert_relative_eq!(fit_cov.rss, fit.rss, max_relative = 1e-10);
}

#[test]
fn full_covariance_matches_generalised_normal_equations() {
    // x = (Aᵀ Σ⁻¹ A)⁻¹ Aᵀ Σ⁻¹ b, Q = (Aᵀ Σ⁻¹ A)⁻¹ (Aitken / GLS)
    let mut g = Gen(17);
    let a = g.mat(9, 3);
    let b = g.vec(9);
    let r = g.mat(9, 9);
    let sigma = &r * r.transpose() + DMat::identity(9, 9) * 0.5;
    let fit = weighted_lstsq(&a, &b, &Weights::Covariance(sigma.clone())).unwrap();
    let si = sigma.clone().try_inverse().unwrap();
    let n = a.transpose() * &si * &a;
    let q = n.clone().try_inverse().unwrap();
    let x = &q * a.transpose() * &si * &b;
    assert!((&fit.x - &x).amax() < 1e-10 * x.amax().max(1.0));
    assert!((&fit.cofactor - &q).amax() < 1e-10 * q.amax());
    let r = &b - &a * &x;
    let rss = (r.transpose() * &si * &r)[(0, 0)];
    assert_relative_eq!(fit.rss, rss, max_relative = 1e-9);
}

#[test]
fn equality_constrained_solution_satisfies_kkt() {
    // KKT: [AᵀA Cᵀ; C 0] [x; λ] = [Aᵀb; d], solved independently by nalgebra's LU
    let mut g = Gen(19);
    let (m, n, p) = (15, 6, 2);
    let a = g.mat(m, n);
    let b = g.vec(m);
    let c = g.mat(p, n);
    let d = g.vec(p);
    let fit = lstsq_constrained(&a, &b, &c, &d).unwrap();
    assert!((&c * &fit.x - &d).amax() < 1e-13, "constraints hold");
    let mut k = DMat::zeros(n + p, n + p);
    k.view_mut((0, 0), (n, n)).copy_from(&(a.transpose() * &a));
    k.view_mut((0, n), (n, p)).copy_from(&c.transpose());
    k.view_mut((n, 0), (p, n)).copy_from(&c);
    let mut rhs = DVec::zeros(n + p);
    rhs.rows_mut(0, n).copy_from(&(a.transpose() * &b));
    rhs.rows_mut(n, p).copy_from(&d);
    let sol = k.lu().solve(&rhs).unwrap();
    assert!((&fit.x - sol.rows(0, n)).amax() < 1e-10);
    // stationarity: Aᵀ(Ax − b) lies in the row space of C (projected gradient vanishes)
    let grad = a.transpose() * (&a * &fit.x - &b);
    let z = null_space(&c, RankTolerance::Auto).unwrap();
    assert!((z.transpose() * grad).amax() < 1e-12);
    assert_eq!(fit.dof, m - (n - p));
    assert_eq!(fit.n_free, n - p);
    // the cofactor is the estimator's M Mᵀ and is singular along Cᵀ: C Q Cᵀ = 0
    let fitter = Lstsq::new().constraints(c.clone(), d.clone());
    let mm = estimator_matrix(&fitter, &a);
    assert!((&fit.cofactor - &mm * mm.transpose()).amax() < 1e-10);
    assert!((&c * &fit.cofactor * c.transpose()).amax() < 1e-12);
}

#[test]
fn redundant_constraints_are_accepted_and_inconsistent_ones_rejected() {
    let a = DMat::identity(3, 3);
    let b = DVec::from_vec(vec![1.0, 2.0, 3.0]);
    // the same constraint twice (consistent): x0 − x1 = 0
    let c = DMat::from_row_slice(2, 3, &[1.0, -1.0, 0.0, 2.0, -2.0, 0.0]);
    let fit = lstsq_constrained(&a, &b, &c, &DVec::from_vec(vec![0.0, 0.0])).unwrap();
    // analytic: x0 = x1 = 1.5, x2 = 3
    assert_relative_eq!(fit.x, DVec::from_vec(vec![1.5, 1.5, 3.0]), epsilon = 1e-14);
    let err = lstsq_constrained(&a, &b, &c, &DVec::from_vec(vec![0.0, 1.0])).unwrap_err();
    assert!(
        matches!(err, LinalgError::InconsistentConstraints { .. }),
        "{err}"
    );
}

#[test]
fn free_network_datum_minimises_subset_norm() {
    // a levelling network: 5 heights, 7 height differences: rank 4 (a common shift is free)
    let pairs = [(0, 1), (1, 2), (2, 3), (3, 4), (0, 2), (1, 3), (2, 4)];
    let mut a = DMat::zeros(7, 5);
    for (k, &(i, j)) in pairs.iter().enumerate() {
        a[(k, i)] = -1.0;
        a[(k, j)] = 1.0;
    }
    let truth = DVec::from_vec(vec![0.3, 1.1, -0.4, 2.0, 0.7]);
    let mut g = Gen(23);
    let b = &a * &truth + g.vec(7) * 1e-3;
    let base = lstsq_min_norm(&a, &b, RankTolerance::Auto).unwrap();
    for subset in [vec![0usize, 1], vec![4], vec![0, 1, 2, 3, 4]] {
        let fit = lstsq_min_norm_subset(&a, &b, &subset, RankTolerance::Auto).unwrap();
        // same fit quality: only the datum differs
        assert!((&a * &fit.x - &a * &base).amax() < 1e-12);
        // the datum: x = base + t·1 with Σ_S x = 0 (analytic minimiser of ‖x_S‖ along 1)
        let sum_s: f64 = subset.iter().map(|&i| fit.x[i]).sum();
        assert!(sum_s.abs() < 1e-12, "{subset:?}");
        let t = fit.x[0] - base[0];
        assert!((&fit.x - &base - DVec::from_element(5, t)).amax() < 1e-12);
        // cofactor: the estimator's M Mᵀ
        let fitter = Lstsq::new().minimum_norm_on(&subset);
        let mm = estimator_matrix(&fitter, &a);
        assert!((&fit.cofactor - &mm * mm.transpose()).amax() < 1e-10);
        assert_eq!(fit.rank, 4);
        assert_eq!(fit.dof, 3);
    }
    // minimum norm on all unknowns is the plain minimum-norm solution
    let all = lstsq_min_norm_subset(&a, &b, &[0, 1, 2, 3, 4], RankTolerance::Auto).unwrap();
    assert!((&all.x - &base).amax() < 1e-12);
    let err = lstsq_min_norm_subset(&a, &b, &[5], RankTolerance::Auto).unwrap_err();
    assert!(matches!(err, LinalgError::DimensionMismatch { .. }));
}

#[test]
fn rank_deficient_error_names_the_combinations() {
    // columns: EX0B, EX0C (= EX0B), EY0C, EA0C (= 2·EY0C); observed from four rows
    let mut g = Gen(29);
    let base = g.mat(6, 2);
    let a = DMat::from_fn(6, 4, |i, j| match j {
        0 | 1 => base[(i, 0)],
        2 => base[(i, 1)],
        _ => 2.0 * base[(i, 1)],
    });
    let b = g.vec(6);
    let err = Lstsq::new()
        .column_names(["EX0B", "EX0C", "EY0C", "EA0C"])
        .fit(&a, &b)
        .unwrap_err();
    match &err {
        LinalgError::RankDeficient {
            rank,
            expected,
            combinations,
        } => {
            assert_eq!((*rank, *expected), (2, 4));
            let mut c = combinations.clone();
            c.sort();
            // null vectors: (1, −1, 0, 0) and (0, 0, 2, −1)
            assert_eq!(c.len(), 2);
            assert!(c.contains(&"EX0B − 1.00·EX0C".to_string()), "{c:?}");
            // EA0C = 2·EY0C: A (2 e₂ − e₃) = 0, written with the largest coefficient leading
            assert!(c.contains(&"EY0C − 0.50·EA0C".to_string()), "{c:?}");
        }
        other => panic!("unexpected {other}"),
    }
    assert!(err.to_string().contains("EX0B − 1.00·EX0C"));
    // the QR route detects it as well
    assert!(matches!(
        lstsq_qr(&a, &b),
        Err(LinalgError::RankDeficient {
            rank: 2,
            expected: 4,
            ..
        })
    ));
}

#[test]
fn identifiability_report_vif_and_correlation() {
    let mut g = Gen(31);
    let m = 40;
    let c0 = g.vec(m);
    let c1 = g.vec(m);
    let c2 = &c0 * 0.999 + &c1 * 0.02 + g.vec(m) * 0.01; // nearly collinear with c0
    let c3 = &c1 * 3.0; // exactly dependent on c1
    let a = DMat::from_columns(&[c0, c1, c2, c3]);
    let names = ["P0", "P1", "P2", "P3"];
    let rep = identifiability(&a, &names, RankTolerance::Auto).unwrap();
    assert_eq!(rep.rank, 3);
    assert!(!rep.is_identifiable());
    assert_eq!(rep.identifiable, vec![true, false, true, false]);
    let texts = rep.combination_strings();
    // A (3 e₁ − e₃) = 3 c1 − c3 = 0; the leading parameter is the largest coefficient
    assert_eq!(texts, vec!["P1 − 0.33·P3".to_string()], "{texts:?}");
    assert!(rep.condition_number.is_infinite() || rep.condition_number > 1e14);
    assert!(rep.vif[1].is_infinite() && rep.vif[3].is_infinite());
    // VIF by its definition: regress column j on the identifiable others through the origin
    // (P1 and P3 contribute one direction: use P1), VIF = ‖aⱼ‖² / RSSⱼ
    for (j, others) in [(0usize, [1usize, 2]), (2, [0, 1])] {
        let x = DMat::from_columns(&[
            a.column(others[0]).into_owned(),
            a.column(others[1]).into_owned(),
        ]);
        let y = a.column(j).into_owned();
        let f = lstsq(&x, &y).unwrap();
        let vif = y.norm_squared() / f.rss;
        assert_relative_eq!(rep.vif[j], vif, max_relative = 1e-8);
    }
    assert!(rep.vif[0] > 100.0);
    // the nearly collinear pair is flagged, with the sign of the estimates' correlation (< 0)
    assert_eq!(rep.correlated_pairs.len(), 1);
    let pair = &rep.correlated_pairs[0];
    assert_eq!((pair.first.as_str(), pair.second.as_str()), ("P0", "P2"));
    assert!(pair.correlation < -0.99);
    // a well-posed design: no combinations, no pairs, VIF = 1 for orthogonal columns
    let q = g.mat(10, 3).qr().q();
    let rep = identifiability(&q, &["a", "b", "c"], RankTolerance::Auto).unwrap();
    assert!(rep.is_identifiable());
    for v in &rep.vif {
        assert_relative_eq!(*v, 1.0, max_relative = 1e-12);
    }
    assert!(rep.correlated_pairs.is_empty());
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let a = DMat::identity(3, 2);
    let b = DVec::from_vec(vec![1.0, 2.0, 3.0]);
    let mut an = a.clone();
    an[(2, 1)] = f64::NAN;
    match lstsq(&an, &b) {
        Err(LinalgError::NonFinite { row: 2, col: 1, .. }) => {}
        other => panic!("{other:?}"),
    }
    let mut bi = b.clone();
    bi[1] = f64::INFINITY;
    assert!(matches!(
        lstsq(&a, &bi),
        Err(LinalgError::NonFinite { row: 1, .. })
    ));
    assert!(matches!(
        lstsq_qr(&an, &b),
        Err(LinalgError::NonFinite { .. })
    ));
    assert!(matches!(svd(&an), Err(LinalgError::NonFinite { .. })));
    assert!(matches!(
        pinv(&an, RankTolerance::Auto),
        Err(LinalgError::NonFinite { .. })
    ));
    let short = DVec::from_vec(vec![1.0, 2.0]);
    assert!(matches!(
        lstsq(&a, &short),
        Err(LinalgError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        lstsq(&DMat::zeros(0, 2), &DVec::zeros(0)),
        Err(LinalgError::Empty { .. })
    ));
    let wide = DMat::from_row_slice(1, 2, &[1.0, 2.0]);
    let one = DVec::from_vec(vec![1.0]);
    assert!(matches!(
        lstsq(&wide, &one),
        Err(LinalgError::TooFewRows { rows: 1, needed: 2 })
    ));
    assert!(matches!(
        lstsq_qr(&wide, &one),
        Err(LinalgError::TooFewRows { .. })
    ));
    let neg = Weights::Diagonal(DVec::from_vec(vec![1.0, -1.0, 1.0]));
    assert!(matches!(
        weighted_lstsq(&a, &b, &neg),
        Err(LinalgError::InvalidValue { index: 1, .. })
    ));
    let nanw = Weights::Diagonal(DVec::from_vec(vec![1.0, 1.0, f64::NAN]));
    assert!(matches!(
        weighted_lstsq(&a, &b, &nanw),
        Err(LinalgError::NonFinite { .. })
    ));
    let wlen = Weights::Diagonal(DVec::from_vec(vec![1.0]));
    assert!(matches!(
        weighted_lstsq(&a, &b, &wlen),
        Err(LinalgError::DimensionMismatch { .. })
    ));
    let indefinite = DMat::from_row_slice(3, 3, &[1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0]);
    assert!(matches!(
        weighted_lstsq(&a, &b, &Weights::Covariance(indefinite)),
        Err(LinalgError::NotPositiveDefinite { .. })
    ));
    let asym = DMat::from_row_slice(3, 3, &[2.0, 0.5, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0]);
    assert!(matches!(
        weighted_lstsq(&a, &b, &Weights::Covariance(asym)),
        Err(LinalgError::NotPositiveDefinite { .. })
    ));
    let c_bad = DMat::from_row_slice(1, 3, &[1.0, 0.0, 0.0]);
    assert!(matches!(
        lstsq_constrained(&a, &b, &c_bad, &one),
        Err(LinalgError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        Lstsq::new().column_names(["only one"]).fit(&a, &b),
        Err(LinalgError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        identifiability(&a, &["x"], RankTolerance::Auto),
        Err(LinalgError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        Lstsq::new()
            .rank_tolerance(RankTolerance::Absolute(f64::NAN))
            .fit(&a, &b),
        Err(LinalgError::InvalidParameter { .. })
    ));
}

#[test]
fn exactly_determined_problem_has_no_sigma0() {
    let a = DMat::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 3.0]);
    let b = DVec::from_vec(vec![3.0, 5.0]);
    let fit = lstsq(&a, &b).unwrap();
    // analytic: x = (4/5, 7/5)
    assert_relative_eq!(fit.x, DVec::from_vec(vec![0.8, 1.4]), epsilon = 1e-14);
    assert_eq!(fit.dof, 0);
    assert!(fit.sigma0.is_none() && fit.covariance.is_none() && fit.std_errors().is_none());
}

#[test]
fn constraints_fixing_everything_leave_no_free_unknowns() {
    let a = DMat::identity(2, 2);
    let b = DVec::from_vec(vec![5.0, 6.0]);
    let c = DMat::identity(2, 2);
    let d = DVec::from_vec(vec![1.0, 2.0]);
    let fit = lstsq_constrained(&a, &b, &c, &d).unwrap();
    assert_relative_eq!(fit.x, d, epsilon = 1e-15);
    assert_eq!((fit.n_free, fit.rank, fit.dof), (0, 0, 2));
    assert_relative_eq!(fit.rss, 16.0 + 16.0, epsilon = 1e-12);
    assert!(fit.cofactor.amax() < 1e-15);
}

#[test]
fn spd_inverse_equals_the_lu_inverse_past_the_blocked_size() {
    // 150 × 150 takes faer's blocked, recursive factorisation (not the 2 × 2 of the doc
    // example); the reference is nalgebra's LU inverse, an independent route.
    let mut g = Gen(17);
    let a = g.mat(400, 150);
    let spd = a.transpose() * &a + DMat::identity(150, 150);
    let inverse = spd_inverse(&spd).expect("positive definite");
    let reference = spd.clone().try_inverse().expect("invertible");
    assert_relative_eq!(inverse, reference, max_relative = 1e-10, epsilon = 1e-14);
    assert_eq!(inverse, inverse.transpose(), "symmetric to the bit");
    // Only the lower triangle is read.
    let mut upper_junk = spd.clone();
    upper_junk[(0, 149)] = 1e9;
    assert_eq!(spd_inverse(&upper_junk), Some(inverse));
    // Indefinite: no inverse.
    let mut indefinite = spd;
    indefinite[(75, 75)] = -1.0;
    assert!(spd_inverse(&indefinite).is_none());
}
