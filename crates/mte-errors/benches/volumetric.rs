//! 10^6 poses of the 5-axis (seed 003 AC table) volumetric error with the seed003-demo error
//! set: slot evaluation + exact pose error, in parallel over fixed chunks.
//! Run: `cargo bench -p mte-errors --bench volumetric`.
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use mte_errors::volumetric::{Method, Point, simulate};
use mte_errors::{ErrorSet, Evaluator};
use mte_kinematics::Machine;
use std::path::Path;

fn points(n: usize) -> Vec<Point> {
    // Deterministic spread over the strokes (golden-ratio sequence per axis).
    let g = [
        0.618_033_988_7,
        0.754_877_666_2,
        0.569_840_290_9,
        0.822_486_786_4,
        0.691_453_044_8,
    ];
    let lo = [-400.0, -425.0, -275.0, (-130f64).to_radians(), 0.0];
    let hi = [
        400.0,
        425.0,
        275.0,
        130f64.to_radians(),
        360f64.to_radians(),
    ];
    (0..n)
        .map(|i| Point {
            q: (0..5)
                .map(|k| lo[k] + (hi[k] - lo[k]) * ((i as f64 + 0.5) * g[k]).fract())
                .collect(),
            time_s: 0.0,
            directions: vec![],
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let m = Machine::library("seed003-ac-table").unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/errors/seed003-demo.json");
    let set = ErrorSet::from_file(&dir).unwrap();
    let ev = Evaluator::new(&m, &set).unwrap();
    let pts = points(1_000_000);
    let mut g = c.benchmark_group("volumetric");
    g.sample_size(10);
    g.bench_function("seed003_1e6_poses_exact", |b| {
        b.iter(|| simulate(&ev, &pts, Method::Exact).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
