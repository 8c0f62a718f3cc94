//! Speed of the hot paths used by volumetric maps (issue 2 targets: exact pose error of a
//! 5-axis machine ≤ 1 µs per pose; first-order with a precomputed Jacobian ≤ 0.1 µs).

#![allow(missing_docs)] // criterion macros generate undocumented items

use criterion::{Criterion, criterion_group, criterion_main};
use mte_kinematics::Machine;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

fn setup(name: &str) -> (Machine, Vec<Vec<f64>>, Vec<f64>) {
    let m = Machine::library(name).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let qs = (0..256)
        .map(|_| {
            m.axes()
                .iter()
                .map(|a| rng.random_range(a.stroke.0..=a.stroke.1))
                .collect()
        })
        .collect();
    // every slot non-zero: 50 µm / 100 µrad scale
    let e = m
        .error_slots()
        .iter()
        .map(|s| {
            let lim = if s.component.is_translation() {
                0.05
            } else {
                1e-4
            };
            rng.random_range(-lim..lim)
        })
        .collect();
    (m, qs, e)
}

fn benches(c: &mut Criterion) {
    for name in ["seed003-ac-table", "seed000-ca-gantry"] {
        let (m, qs, e) = setup(name);
        let mut i = 0;
        c.bench_function(
            &format!("pose_error exact {name} ({} slots)", m.n_slots()),
            |b| {
                b.iter(|| {
                    i = (i + 1) & 255;
                    black_box(m.pose_error(black_box(&qs[i]), black_box(&e)))
                })
            },
        );
        let j = m.jacobian(&qs[0]);
        c.bench_function(&format!("first_order J·e {name}"), |b| {
            b.iter(|| black_box(j.apply(black_box(&e))))
        });
        let mut out = mte_linalg::DMat::zeros(6, m.n_slots());
        c.bench_function(&format!("jacobian_into {name}"), |b| {
            b.iter(|| {
                i = (i + 1) & 255;
                m.jacobian_into(black_box(&qs[i]), &mut out);
                black_box(out[(0, 0)])
            })
        });
        c.bench_function(&format!("pose_error POE (reference) {name}"), |b| {
            b.iter(|| {
                i = (i + 1) & 255;
                black_box(m.pose_error_poe(black_box(&qs[i]), black_box(&e)))
            })
        });
    }
}

criterion_group! {
    name = kin;
    config = Criterion::default();
    targets = benches
}
criterion_main!(kin);
