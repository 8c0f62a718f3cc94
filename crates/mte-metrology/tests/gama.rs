//! Cross-check against GNU Gama 2.03 (`gama-local --algorithm svd`), see
//! `fixtures/metrology-xcheck/README.md` and `shared/papers/CROSSCHECKS.md`
//! ("Free-network multilateration"). The Gama files are copied into the repository.

#![allow(clippy::needless_range_loop)]

use mte_metrology::adjust::{AdjustParams, Datum, adjust};
use mte_metrology::io::network_from_gama;
use std::collections::HashMap;

fn fixture(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/metrology-xcheck")
        .join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn tag_values(s: &str, tag: &str) -> Vec<String> {
    let open = format!("<{tag}>");
    let close = format!("</{tag}>");
    let mut out = Vec::new();
    let mut rest = s;
    while let Some(i) = rest.find(&open) {
        let a = i + open.len();
        let b = rest[a..].find(&close).unwrap() + a;
        out.push(rest[a..b].trim().to_string());
        rest = &rest[b..];
    }
    out
}

struct GamaOut {
    /// point id → (x, y, z) in m, in listing order
    points: Vec<(String, [f64; 3])>,
    cov: Vec<Vec<f64>>, // mm²
}

fn gama_output() -> GamaOut {
    let xml = fixture("mlat-free-4x24.gama-svd.xml");
    let adj = &xml[xml.find("<adjusted>").unwrap()..xml.find("</adjusted>").unwrap()];
    let mut points = Vec::new();
    for blk in adj.split("<point>").skip(1) {
        let id = tag_values(blk, "id")[0].clone();
        let get = |a: &str, b: &str| {
            let v = tag_values(blk, a);
            let v = if v.is_empty() { tag_values(blk, b) } else { v };
            v[0].parse::<f64>().unwrap()
        };
        points.push((id, [get("X", "x"), get("Y", "y"), get("Z", "z")]));
    }
    let cm = &xml[xml.find("<cov-mat>").unwrap()..xml.find("</cov-mat>").unwrap()];
    let dim: usize = tag_values(cm, "dim")[0].parse().unwrap();
    let band: usize = tag_values(cm, "band")[0].parse().unwrap();
    assert_eq!(band, dim - 1, "full upper triangle expected");
    let flt: Vec<f64> = tag_values(cm, "flt")
        .iter()
        .map(|s| s.parse().unwrap())
        .collect();
    assert_eq!(flt.len(), dim * (dim + 1) / 2);
    let mut cov = vec![vec![0.0; dim]; dim];
    let mut k = 0;
    for i in 0..dim {
        for j in i..dim {
            cov[i][j] = flt[k];
            cov[j][i] = flt[k];
            k += 1;
        }
    }
    GamaOut { points, cov }
}

#[test]
fn gama_free_network_matches() {
    let net = network_from_gama("mlat-free-4x24.gkf", &fixture("mlat-free-4x24.gkf")).unwrap();
    assert_eq!(
        (
            net.stations.len(),
            net.targets.len(),
            net.observations.len()
        ),
        (4, 24, 96)
    );
    let adj = adjust(
        &net,
        &AdjustParams {
            datum: Datum::NominalTargets,
            ..Default::default()
        },
    )
    .unwrap();
    let g = gama_output();

    // coordinates to 10 nm (README: an independent solver agreed to 1.4 nm; Gama stopped
    // after one re-linearisation, we iterate to 1e-9 mm)
    let mut ours: HashMap<String, [f64; 3]> = HashMap::new();
    for s in &adj.stations {
        ours.insert(
            s.id.clone(),
            [s.position_mm.x, s.position_mm.y, s.position_mm.z],
        );
    }
    for t in &adj.targets {
        ours.insert(
            t.id.clone(),
            [t.position_mm.x, t.position_mm.y, t.position_mm.z],
        );
    }
    let mut worst: f64 = 0.0;
    for (id, x) in &g.points {
        let o = ours[id];
        for c in 0..3 {
            worst = worst.max((o[c] - x[c] * 1000.0).abs());
        }
    }
    eprintln!("max coordinate difference vs Gama: {worst:e} mm");
    assert!(
        worst < 1e-5,
        "max coordinate difference {worst:e} mm > 10 nm"
    );

    // covariance to 1e-3 relative (elementwise, relative to √(C_ii C_jj))
    let names = adj.parameter_names();
    let idx: HashMap<&str, usize> = names
        .iter()
        .enumerate()
        .map(|(i, n)| (n.as_str(), i))
        .collect();
    let gnames: Vec<String> = g
        .points
        .iter()
        .flat_map(|(id, _)| ["x", "y", "z"].map(|c| format!("{id}.{c}")))
        .collect();
    let q = adj.dense_covariance().unwrap();
    let mut worst_rel: f64 = 0.0;
    for (a, na) in gnames.iter().enumerate() {
        for (b, nb) in gnames.iter().enumerate() {
            let (i, j) = (idx[na.as_str()], idx[nb.as_str()]);
            let scale = (g.cov[a][a] * g.cov[b][b]).sqrt();
            worst_rel = worst_rel.max((q[(i, j)] - g.cov[a][b]).abs() / scale);
        }
    }
    eprintln!(
        "max relative covariance difference vs Gama: {worst_rel:e}; pvv {}",
        adj.global.pvv
    );
    assert!(
        worst_rel < 1e-3,
        "covariance differs by {worst_rel:e} relative"
    );

    // per-target blocks (Schur route) equal the dense route
    for (j, t) in adj.targets.iter().enumerate() {
        let b = adj.covariance_block(j, j).unwrap();
        let k = idx[format!("{}.x", t.id).as_str()];
        for r in 0..3 {
            for c in 0..3 {
                assert!((b[(r, c)] - q[(k + r, k + c)]).abs() < 1e-9 * q[(k, k)]);
                assert!((t.covariance_mm2[r][c] - q[(k + r, k + c)]).abs() < 1e-9 * q[(k, k)]);
            }
        }
    }

    // [pvv] = 8.8494848e-08 mm² / sigma-apr² (1e-4 mm)² ; dof 18 ; m0'/m0 = 0.701 in (0.676, 1.323)
    assert!(
        (adj.global.pvv - 8.8494848).abs() < 5e-4 * 8.85,
        "pvv {}",
        adj.global.pvv
    );
    assert_eq!(adj.global.degrees_of_freedom, 18);
    assert!((adj.global.sigma0_ratio - 0.701).abs() < 5e-4);
    assert!(
        (adj.global.interval.0 - 0.676).abs() < 5e-4
            && (adj.global.interval.1 - 1.323).abs() < 5e-4
    );
    assert!(adj.global.passed);
    // redundancy numbers sum to the degrees of freedom (trace identity)
    let sr: f64 = adj.observations.iter().map(|o| o.redundancy).sum();
    assert!((sr - 18.0).abs() < 1e-6, "Σr = {sr}");

    // README figures: max |adjusted − nominal| = 17.948 µm at P24; trace 22.83 µm²; 3-D σ 0.672 … 1.551 µm
    let (jmax, dmax) = adj.max_deviation();
    assert_eq!(adj.targets[jmax].id, "P24");
    assert!((dmax * 1e3 - 17.948).abs() < 5e-3);
    let tr: f64 = adj
        .targets
        .iter()
        .map(|t| t.covariance().trace())
        .sum::<f64>()
        * 1e6;
    assert!((tr - 22.83).abs() < 0.01, "trace {tr}");
    let s3: Vec<f64> = adj.targets.iter().map(|t| t.sigma_3d_mm() * 1e3).collect();
    let (lo, hi) = s3
        .iter()
        .fold((f64::MAX, 0.0f64), |a, &b| (a.0.min(b), a.1.max(b)));
    assert!(
        (lo - 0.672).abs() < 1e-3 && (hi - 1.551).abs() < 1e-3,
        "{lo} {hi}"
    );
}
