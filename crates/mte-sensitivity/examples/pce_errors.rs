//! Reported errors of sparse PCE against the error on 20000 fresh Monte Carlo runs, per selection
//! rule: the Sobol' G-function (41 inputs, degree 3, 1000 LHS runs) in detail, and on Ishigami
//! the ratio selection-aware / fresh over 10 seeds at 150, 300 and 800 runs; the figures quoted
//! in docs/formats.md ("What the reported errors mean").
//!
//! `cargo run --release -p mte-sensitivity --example pce_errors [seed]`

use mte_sensitivity::pce::{PceParams, Selection, build_pce, sample_runs};
use mte_sensitivity::testfn::{GFunction, Ishigami};
use mte_sensitivity::{Model, Problem, Sampling};

fn report<M: Model>(name: &str, f: &M, prob: &Problem, params: &PceParams, s1: &[f64]) {
    let (xv, yv) = sample_runs(f, prob, Sampling::MonteCarlo, 20_000, 12_345).unwrap();
    for selection in [Selection::KFold { folds: 5 }, Selection::CorrectedLoo] {
        let p = PceParams {
            selection,
            ..params.clone()
        };
        let r = build_pce(f, prob, &p).unwrap();
        let o = &r.outputs[0];
        let fresh = r.validation_error(prob, 0, &xv, &yv);
        println!(
            "{name}, {selection:?}: degree {}, {} terms; corrected LOO {:.3e}, CV {:.3e}, \
             selection-aware {:.3e}, fresh {fresh:.3e} (ratio {:.2}); mean {:.3}; S1 {:.3?} \
             (analytic {:.3?})",
            o.degree,
            o.terms.len(),
            o.loo_error,
            o.cv_error,
            o.selection_aware_error,
            o.selection_aware_error / fresh,
            o.mean,
            &o.first[..3],
            &s1[..3]
        );
        for w in &o.warnings {
            println!("    warning: {w}");
        }
    }
}

fn main() {
    let seed: u64 = std::env::args()
        .nth(1)
        .map_or(0, |s| s.parse().expect("a seed"));
    let g = GFunction::benchmark(41);
    let (s1, _) = g.analytic();
    let p = PceParams {
        degree: 3,
        n_samples: 1000,
        seed,
        ..Default::default()
    };
    report("G-function k = 41", &g, &g.problem(), &p, &s1);
    // Ishigami: the ratio selection-aware / fresh over 10 seeds, per run count and rule
    let f = Ishigami::default();
    let prob = Ishigami::problem();
    let (xv, yv) = sample_runs(&f, &prob, Sampling::MonteCarlo, 20_000, 12_345).unwrap();
    for (n, degree) in [(150, 6), (300, 8), (800, 10)] {
        for selection in [Selection::KFold { folds: 5 }, Selection::CorrectedLoo] {
            let ratios: Vec<f64> = (0..10)
                .map(|seed| {
                    let p = PceParams {
                        degree,
                        n_samples: n,
                        seed,
                        selection,
                        ..Default::default()
                    };
                    let r = build_pce(&f, &prob, &p).unwrap();
                    r.outputs[0].selection_aware_error / r.validation_error(&prob, 0, &xv, &yv)
                })
                .collect();
            println!(
                "Ishigami n = {n}, degree ≤ {degree}, {selection:?}, seeds 0–9: selection-aware / fresh {ratios:.2?}"
            );
        }
    }
}
