//! scratch
use xtask::realistic::{BaseModel, Kind, smooth::Waviness};
fn main() {
    let f = xtask::studies::fdr_with(Kind::Rotary, 100, 1, &BaseModel::Default, Waviness::Wavy);
    for r in &f.records {
        if let Ok(o) = &r.outcome {
            if !o.findings.is_empty() {
                println!(
                    "{} {:?}",
                    r.seed,
                    o.findings
                        .iter()
                        .map(|f| (&f.name, f.period))
                        .collect::<Vec<_>>()
                );
                let mut s = xtask::realistic::Spec::new(Kind::Rotary, &[]);
                s.waviness = Waviness::Wavy;
                xtask::realistic::write_spec(
                    &s,
                    r.seed,
                    std::path::Path::new(&format!("/tmp/wr/{}", r.seed)),
                )
                .unwrap();
            }
        }
    }
}
