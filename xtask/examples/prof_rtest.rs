use xtask::realistic::{Hidden, Kind, Spec, write_spec};
fn main() {
    let dir = std::env::temp_dir().join("prof-rtest");
    let mut rtest = Spec::new(
        Kind::Rtest,
        &[Hidden::PivotDrift {
            rotary: 0,
            um: 20.0,
            tau_s: 1800.0,
        }],
    );
    rtest.cycles = Some(8);
    let truth = (11..)
        .map(|seed| write_spec(&rtest, seed, &dir).unwrap())
        .find(|t| t.n_observations >= 4500)
        .unwrap();
    eprintln!("{} obs", truth.n_observations);
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(3);
    for _ in 0..n {
        let t = std::time::Instant::now();
        let p = mte_diagnose::load_with_noise(&truth.manifest, Some(0.5)).unwrap();
        let d = p
            .diagnose(&mte_diagnose::DiagnoseParams::default())
            .unwrap();
        eprintln!("{:?} findings {}", t.elapsed(), d.findings.len());
    }
}
