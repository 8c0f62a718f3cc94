//! Criterion benches: `cargo bench -p mte-metrology --bench metrology`.
//! * `adjust_8x100k`: 8 stations × 100 000 targets, free dead paths, full Gauss–Newton + statistics.
//! * `gum_seed004_1e4`: GUM-S1 Monte Carlo, 10⁴ trials of the seed 004 network (linearised, cached).
//! * `gum_seed004_1e5`, `gum_seed004_1e6`: the same with 10⁵ and 10⁶ trials (sensitivity prebuilt).

#![allow(missing_docs)] // criterion macros generate undocumented items

use criterion::{Criterion, criterion_group, criterion_main};
use mte_metrology::adjust::{AdjustParams, adjust};
use mte_metrology::gum::{McParams, monte_carlo};
use mte_metrology::network::{DeadPath, LengthUncertainty, Station, Target, Vec3};
use mte_metrology::simulate::{SmoothErrorField, StationLayout, cube_edge_targets, simulate};
use mte_metrology::uncertainty::{LinearisedTracker, TrackerQuantity};

fn big_network(n: usize) -> mte_metrology::network::Network {
    let l = 1000.0;
    let k = (n as f64).cbrt().ceil() as usize;
    let targets: Vec<Target> = (0..n)
        .map(|i| {
            let (a, b, c) = (i % k, (i / k) % k, i / (k * k));
            let f = |t: usize| l * (t as f64 + 0.5) / k as f64;
            Target {
                id: format!("T{i}"),
                nominal_mm: Vec3::new(f(a), f(b), f(c)),
            }
        })
        .collect();
    let rel = [
        [-0.2, -0.2, -0.3],
        [1.2, -0.2, -0.2],
        [1.2, 1.2, -0.3],
        [-0.2, 1.2, -0.1],
        [-0.2, -0.2, 1.3],
        [1.2, -0.2, 1.2],
        [1.2, 1.2, 1.3],
        [-0.2, 1.2, 1.1],
    ];
    let stations: Vec<Station> = rel
        .iter()
        .enumerate()
        .map(|(i, r)| Station {
            id: format!("S{i}"),
            position_mm: Vec3::new(r[0] * l, r[1] * l, r[2] * l),
            dead_path_mm: 0.0,
            dead_path: DeadPath::Free,
        })
        .collect();
    simulate(
        &stations,
        &targets,
        &|p: &Vec3| Vec3::new(1e-5 * p.y, -1e-5 * p.x, 2e-5 * p.z),
        LengthUncertainty::SEED004,
        1,
    )
    .unwrap()
    .network
}

fn benches(c: &mut Criterion) {
    let net = big_network(100_000);
    let mut g = c.benchmark_group("adjust");
    g.sample_size(10);
    g.bench_function("adjust_8x100k", |b| {
        b.iter(|| adjust(&net, &AdjustParams::default()).unwrap())
    });
    g.finish();

    let targets = cube_edge_targets(500.0, 2);
    let field = SmoothErrorField::new(500.0, &targets, 31.6);
    let sim = simulate(
        &StationLayout::FourLow.stations(500.0, true),
        &targets,
        &|p: &Vec3| field.eval(p),
        LengthUncertainty::SEED004,
        5,
    )
    .unwrap();
    let adj = adjust(&sim.network, &AdjustParams::default()).unwrap();
    let inputs = LinearisedTracker::inputs(&adj);
    let mut g = c.benchmark_group("gum");
    g.sample_size(10);
    g.bench_function("gum_seed004_1e4", |b| {
        b.iter(|| {
            // includes building the cached sensitivity from the adjustment
            let f = LinearisedTracker::new(&adj, TrackerQuantity::MaxDeviation).unwrap();
            monte_carlo(
                &f,
                &inputs,
                &McParams {
                    trials: 10_000,
                    coverage: 0.95,
                    seed: 1,
                },
            )
            .unwrap()
        })
    });
    let f = LinearisedTracker::new(&adj, TrackerQuantity::MaxDeviation).unwrap();
    for (name, trials) in [("gum_seed004_1e5", 100_000), ("gum_seed004_1e6", 1_000_000)] {
        g.bench_function(name, |b| {
            b.iter(|| {
                monte_carlo(
                    &f,
                    &inputs,
                    &McParams {
                        trials,
                        coverage: 0.95,
                        seed: 1,
                    },
                )
                .unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(b, benches);
criterion_main!(b);
