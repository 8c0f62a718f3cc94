//! The diagnosis on realistic datasets (issue targets: an 8-cycle R-test thermal dataset of
//! about 5 000 observations in ≤ 3 s, tracker data with a volumetric base and about 2 000
//! lengths in ≤ 5 s, release, 2 cores). Load and diagnosis, including the 5 outer searches of
//! the honest held-out figures. Each is reported beside its baseline from the same run, the
//! load alone (`*_load`): quote the ratio, the machine is noisy.
//!
//! cargo bench -p xtask --bench diagnose
#![allow(missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use xtask::realistic::{Hidden, Kind, Spec, write_spec};

fn bench(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("mte-bench-diagnose-{}", std::process::id()));
    let mut group = c.benchmark_group("diagnose");
    group.sample_size(10);
    let mut rtest = Spec::new(
        Kind::Rtest,
        &[Hidden::PivotDrift {
            rotary: 0,
            um: 20.0,
            tau_s: 1800.0,
        }],
    );
    rtest.cycles = Some(8);
    let tracker = Spec::new(Kind::Tracker, &[]);
    // The size: about 2 000 lengths (400 targets from 4–6 stations).
    let mut tracker_2000 = Spec::new(Kind::Tracker, &[]);
    tracker_2000.targets = Some(400);
    // A volumetric calibration's: 130 positions, each at the tool tip and 2–3 tool offsets
    // (about 3 000 lengths).
    let mut tools = Spec::new(Kind::TrackerTools, &[]);
    tools.targets = Some(130);
    // The first seed from 11 whose programme is at least `min_obs` observations (the R-test
    // issue's dataset has about 5 000, the tracker's about 2 000 lengths; the generator's
    // programmes and stations vary with the seed).
    for (name, spec, noise, min_obs) in [
        ("rtest_8_cycles", rtest, Some(0.5), 4_500),
        ("tracker_volumetric", tracker, None, 0),
        ("tracker_volumetric_2000", tracker_2000, None, 1_900),
        ("tracker_tools", tools, None, 1_900),
    ] {
        let truth = (11..)
            .map(|seed| write_spec(&spec, seed, &dir.join(name)).expect("dataset written"))
            .find(|t| t.n_observations >= min_obs)
            .expect("a seed with enough observations");
        let prepared =
            || mte_diagnose::load_with_noise(&truth.manifest, noise).expect("dataset loads");
        eprintln!("{name}: {} observations", truth.n_observations);
        // The baseline of the same run: reading and preparing the dataset alone.
        group.bench_function(format!("{name}_load"), |b| b.iter(|| black_box(prepared())));
        group.bench_function(name, |b| {
            b.iter(|| {
                let p = prepared();
                black_box(
                    p.diagnose(&mte_diagnose::DiagnoseParams::default())
                        .expect("diagnosis runs"),
                )
            })
        });
    }
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
