//! Studies of the diagnosis on realistic datasets ([`crate::realistic`]): false discoveries on
//! clean machines ([`fdr`]), detection power per hidden effect and size ([`power`]), and what
//! the diagnosis says about effects no candidate has exactly ([`openworld`]).
//!
//! Each dataset is written to a temporary directory, read back with `mte_diagnose::load` (R-test:
//! `load_with_noise` with the true σ rounded to 0.1 µm, as a user would state it) and diagnosed
//! with `DiagnoseParams::default()`. Datasets run in parallel (rayon); each is drawn from its own
//! seed (a hash of the base seed, the study cell and the dataset index), and results are
//! collected in index order, so the figures do not depend on the thread count.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::realistic::{
    BaseModel, EffectKind, Hidden, Kind, Spec, TrueEffect, axis::stated_noise, smooth::Waviness,
    write_spec,
};

/// An estimate as recorded: `(name, value, standard uncertainty, 95 % interval where the report
/// states one)`, in internal units.
pub type Estimate = (String, f64, f64, Option<mte_diagnose::Interval>);

/// A finding as recorded: name and estimates in internal units.
#[derive(Debug, Clone, PartialEq)]
pub struct FoundEffect {
    /// Finding name.
    pub name: String,
    /// Its estimates.
    pub estimates: Vec<Estimate>,
    /// The alternatives the diagnosis reports it cannot separate from this finding.
    pub alternatives: Vec<String>,
    /// Its period (mm along a linear axis, rad of a turn), for a periodic finding.
    pub period: Option<f64>,
    /// For a linear drift: the 95 % interval the report states for the value a first-order
    /// drift of the same parameter would settle to ([`mte_diagnose::FirstOrderFit`]).
    pub first_order_final: Option<mte_diagnose::Interval>,
    /// Whether it is an ordinary error every machine has ([`mte_diagnose::Finding::ordinary`]).
    pub ordinary: bool,
}

/// What the diagnosis returned for one dataset.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Findings in the order reported.
    pub findings: Vec<FoundEffect>,
    /// σ0 of the extended fit.
    pub sigma0: f64,
    /// χ² p-value of the extended fit (when the noise is stated).
    pub chi2_p_value: Option<f64>,
    /// Held-out RMS of the base model, µm.
    pub base_held_out_rms_um: f64,
    /// Held-out RMS of the diagnosed model (the whole search repeated without each outer
    /// fold), µm.
    pub extended_held_out_rms_um: f64,
    /// The diagnosis' verdict.
    pub verdict: mte_diagnose::Verdict,
    /// Groups of findings the diagnosis says are one effect of a form no candidate has
    /// ([`mte_diagnose::Diagnosis::compound`]).
    pub compound: usize,
    /// The findings of those groups: the findings whose form the report qualifies (one effect
    /// of a form no candidate has, a period and shape the data do not determine, or a wave too
    /// long to tell from a smooth error).
    pub qualified: Vec<String>,
    /// Readings the diagnosis lists as outliers ([`mte_diagnose::Diagnosis::outliers`]).
    pub outliers: usize,
    /// The sizes the diagnosis states for such groups where it states one: the findings, the
    /// estimate's name, its value and standard uncertainty (a drift's change over the measured
    /// time of one parameter).
    pub compound_sizes: Vec<(Vec<String>, String, f64, f64)>,
    /// Candidates the report lists as not separable with these data (a combination of the
    /// model's terms).
    pub not_separable: Vec<String>,
    /// The periods along each axis the sampling let the diagnosis look for
    /// ([`mte_diagnose::Diagnosis::periodic_reach`]).
    pub periodic_reach: Vec<mte_diagnose::engine::PeriodicReach>,
    /// The sizes from which the causes not found would have been found
    /// ([`mte_diagnose::Diagnosis::detection_limits`]).
    pub detection_limits: Vec<mte_diagnose::DetectionLimit>,
}

/// One dataset of a study.
#[derive(Debug, Clone)]
pub struct Record {
    /// Index in the study cell.
    pub index: usize,
    /// Generator seed.
    pub seed: u64,
    /// True noise σ, µm.
    pub noise_um: f64,
    /// The hidden effects.
    pub effects: Vec<TrueEffect>,
    /// The diagnosis, or the error of load / diagnose.
    pub outcome: Result<Outcome, String>,
}

/// A seed for dataset `index` of the study cell `cell` (FNV-1a of the cell name, mixed with the
/// base seed and the index by SplitMix64).
pub fn dataset_seed(base_seed: u64, cell: &str, index: usize) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in cell.bytes() {
        h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
    }
    let mut z = h ^ base_seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ (index as u64).rotate_left(32);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A directory of its own for each cell run (cells run side by side in the tests: one that
/// removed a shared directory as it finished would pull it from under another's next dataset).
fn work_dir() -> PathBuf {
    static RUNS: AtomicUsize = AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("mte-studies-{}-{run}", std::process::id()))
}

/// Writes the dataset of `spec` drawn from `seed` under `work`, diagnoses it and records the
/// result (errors are recorded, not raised). The dataset directory is removed afterwards.
pub fn run_one(spec: &Spec, index: usize, seed: u64, work: &Path) -> Record {
    let dir = work.join(format!("d{seed:016x}"));
    let truth = match write_spec(spec, seed, &dir) {
        Ok(t) => t,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&dir);
            return Record {
                index,
                seed,
                noise_um: f64::NAN,
                effects: Vec::new(),
                outcome: Err(format!("generator: {e}")),
            };
        }
    };
    let prepared = if matches!(spec.kind, Kind::Rtest | Kind::RtestHead | Kind::RtestAc) {
        mte_diagnose::load_with_noise(&truth.manifest, Some(stated_noise(truth.noise_um)))
    } else {
        mte_diagnose::load(&truth.manifest)
    };
    let outcome = prepared
        .map_err(|e| format!("load: {e}"))
        .and_then(|p| {
            p.diagnose(&mte_diagnose::DiagnoseParams::default())
                .map_err(|e| format!("diagnose: {e}"))
        })
        .map(|d| Outcome {
            findings: d
                .findings
                .iter()
                .map(|f| FoundEffect {
                    name: f.name.clone(),
                    // (Those it cannot tell apart and those it hardly can.)
                    alternatives: f
                        .alternatives
                        .iter()
                        .cloned()
                        .chain(f.rivals.iter().map(|r| r.name.clone()))
                        .collect(),
                    period: match f.family {
                        mte_diagnose::Family::Periodic { period } => Some(period),
                        _ => None,
                    },
                    estimates: f
                        .estimates
                        .iter()
                        .map(|e| (e.name.clone(), e.value, e.uncertainty, e.interval))
                        .collect(),
                    first_order_final: f.first_order.as_ref().map(|f| f.final_value),
                    ordinary: f.ordinary,
                })
                .collect(),
            sigma0: d.extended.sigma0,
            chi2_p_value: d.extended.chi2_p_value,
            base_held_out_rms_um: d.held_out.as_ref().map_or(f64::NAN, |h| h.base_rms) * 1e3,
            extended_held_out_rms_um: d.held_out.as_ref().map_or(f64::NAN, |h| h.diagnosed_rms)
                * 1e3,
            verdict: d.verdict,
            compound: d.compound.len(),
            qualified: d
                .compound
                .iter()
                .flat_map(|c| c.findings.iter().cloned())
                .collect(),
            outliers: d.outliers.len(),
            compound_sizes: d
                .compound
                .iter()
                .filter_map(|c| {
                    let e = c.estimate.as_ref()?;
                    Some((c.findings.clone(), e.name.clone(), e.value, e.uncertainty))
                })
                .collect(),
            not_separable: d
                .base_not_separable
                .iter()
                .chain(&d.not_separable)
                .map(|n| n.name.clone())
                .collect(),
            periodic_reach: d.periodic_reach.clone(),
            detection_limits: d.detection_limits.clone(),
        });
    let _ = std::fs::remove_dir_all(&dir);
    Record {
        index,
        seed,
        noise_um: truth.noise_um,
        effects: truth.effects,
        outcome,
    }
}

/// The random stream of the spec's own draws (sizes, periods) for the dataset of generator
/// seed `seed` ([`run_cell`]): separate from the generator's.
pub fn spec_rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_5eed_5eed_5eed)
}

/// Runs `n` datasets of the cell `cell` in parallel; `spec_for(rng)` builds each spec from a
/// generator seeded for that dataset. Prints a progress line on stderr.
pub fn run_cell(
    cell: &str,
    n: usize,
    base_seed: u64,
    spec_for: impl Fn(&mut ChaCha8Rng) -> Spec + Sync,
) -> Vec<Record> {
    run_cell_drawn(cell, n, base_seed, 0, spec_for)
}

/// [`run_cell`] with draw `draw` of the noise: draw 0 is each dataset's own, draw k > 0 the
/// same machines and effects measured again with the noise of a stream of their own
/// ([`Spec::noise_seed`]).
pub fn run_cell_drawn(
    cell: &str,
    n: usize,
    base_seed: u64,
    draw: usize,
    spec_for: impl Fn(&mut ChaCha8Rng) -> Spec + Sync,
) -> Vec<Record> {
    let work = work_dir();
    let done = AtomicUsize::new(0);
    let label = match draw {
        0 => cell.to_string(),
        k => format!("{cell}, noise draw {k}"),
    };
    let records: Vec<Record> = (0..n)
        .into_par_iter()
        .map(|i| {
            let seed = dataset_seed(base_seed, cell, i);
            let mut spec = spec_for(&mut spec_rng(seed));
            spec.noise_seed = (draw > 0).then(|| dataset_seed(base_seed, &label, i));
            let r = run_one(&spec, i, seed, &work);
            let k = done.fetch_add(1, Ordering::Relaxed) + 1;
            eprint!("\r{label}: {k}/{n}   ");
            r
        })
        .collect();
    eprintln!();
    let _ = std::fs::remove_dir(&work);
    records
}

/// Quantiles (min, 10 %, median, 90 %, max) of the finite values.
pub fn quantiles(values: &[f64]) -> Option<[f64; 5]> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    Some([q(0.0), q(0.1), q(0.5), q(0.9), q(1.0)])
}

fn name_counts<'a>(names: impl Iterator<Item = &'a str>) -> Vec<(String, usize)> {
    let mut m: BTreeMap<String, usize> = BTreeMap::new();
    for n in names {
        *m.entry(n.to_string()).or_default() += 1;
    }
    let mut v: Vec<(String, usize)> = m.into_iter().collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    v
}

/// False discoveries on clean machines of one kind.
#[derive(Debug, Clone)]
pub struct FdrSummary {
    /// Kind of dataset.
    pub kind: Kind,
    /// How wavy its ordinary errors are.
    pub waviness: Waviness,
    /// Datasets run.
    pub n: usize,
    /// Datasets whose load or diagnosis failed.
    pub errors: usize,
    /// Datasets with at least one finding.
    pub with_finding: usize,
    /// Of those, datasets where the report qualifies every finding (a form, period or cause the
    /// data cannot tell: [`Outcome::qualified`]).
    pub all_qualified: usize,
    /// Datasets whose verdict is "no significant discrepancy".
    pub no_discrepancy: usize,
    /// Datasets where the diagnosis lists a reading as an outlier (clean data have none).
    pub with_outlier: usize,
    /// Finding names by frequency (datasets naming them).
    pub names: Vec<(String, usize)>,
    /// Datasets with a finding that is not an ordinary error ([`FoundEffect::ordinary`]): what
    /// counts as a false discovery against a base model that leaves ordinary errors out.
    pub with_other: usize,
    /// Of those, datasets where the report qualifies every such finding or lists what the
    /// data cannot tell it from ([`FoundEffect::alternatives`]).
    pub other_qualified: usize,
    /// Names of the findings that are not ordinary errors, by frequency.
    pub other_names: Vec<(String, usize)>,
    /// Datasets whose verdict is that the causes found explain the data.
    pub explained: usize,
    /// Quantiles of σ0 of the extended fit (min, 10 %, median, 90 %, max).
    pub sigma0: Option<[f64; 5]>,
    /// Median held-out RMS of the base and extended models divided by the true σ.
    pub held_out_over_noise: Option<(f64, f64)>,
    /// The first error message, if any.
    pub first_error: Option<String>,
    /// Every dataset.
    pub records: Vec<Record>,
}

impl FdrSummary {
    /// The table cells of σ0's quantiles and of the median held-out RMS ÷ σ, base → diagnosed.
    fn fit_cells(&self) -> (String, String) {
        let q = self.sigma0.map_or("–".into(), |q| {
            format!(
                "{:.2} / {:.2} / {:.2} / {:.2} / {:.2}",
                q[0], q[1], q[2], q[3], q[4]
            )
        });
        let h = self
            .held_out_over_noise
            .map_or("–".into(), |(a, b)| format!("{a:.2} → {b:.2}"));
        (q, h)
    }

    /// Fraction of the datasets that ran with at least one finding.
    pub fn fraction(&self) -> f64 {
        let ran = self.n - self.errors;
        if ran == 0 {
            f64::NAN
        } else {
            self.with_finding as f64 / ran as f64
        }
    }
}

/// [`fdr_with`] with the kind's default base model and gentle ordinary errors.
pub fn fdr(kind: Kind, n: usize, base_seed: u64) -> FdrSummary {
    fdr_with(kind, n, base_seed, &BaseModel::Default, Waviness::Gentle)
}

/// False discoveries: `n` clean realistic datasets of `kind` (ordinary errors only, no reversal
/// on axis data, of the given waviness) with the manifest's base model `base_model`.
pub fn fdr_with(
    kind: Kind,
    n: usize,
    base_seed: u64,
    base_model: &BaseModel,
    waviness: Waviness,
) -> FdrSummary {
    let cell = match waviness {
        Waviness::Gentle => format!("fdr-{}", kind.name()),
        Waviness::Wavy => format!("fdr-{}-wavy", kind.name()),
    };
    let records = run_cell(&cell, n, base_seed, |_| {
        let mut s = Spec::new(kind, &[]);
        s.base_model = base_model.clone();
        s.waviness = waviness;
        s
    });
    let ok: Vec<(&Record, &Outcome)> = records
        .iter()
        .filter_map(|r| r.outcome.as_ref().ok().map(|o| (r, o)))
        .collect();
    let ratio = |f: &dyn Fn(&Outcome) -> f64| {
        quantiles(
            &ok.iter()
                .map(|(r, o)| f(o) / r.noise_um)
                .collect::<Vec<_>>(),
        )
        .map(|q| q[2])
    };
    FdrSummary {
        kind,
        waviness,
        n,
        errors: records.len() - ok.len(),
        with_finding: ok.iter().filter(|(_, o)| !o.findings.is_empty()).count(),
        all_qualified: ok
            .iter()
            .filter(|(_, o)| {
                !o.findings.is_empty() && o.findings.iter().all(|f| o.qualified.contains(&f.name))
            })
            .count(),
        no_discrepancy: ok
            .iter()
            .filter(|(_, o)| o.verdict == mte_diagnose::Verdict::NoDiscrepancy)
            .count(),
        with_outlier: ok.iter().filter(|(_, o)| o.outliers > 0).count(),
        names: name_counts(
            ok.iter()
                .flat_map(|(_, o)| o.findings.iter().map(|f| f.name.as_str())),
        ),
        with_other: ok
            .iter()
            .filter(|(_, o)| o.findings.iter().any(|f| !f.ordinary))
            .count(),
        other_qualified: ok
            .iter()
            .filter(|(_, o)| {
                let mut other = o.findings.iter().filter(|f| !f.ordinary).peekable();
                other.peek().is_some()
                    && other.all(|f| o.qualified.contains(&f.name) || !f.alternatives.is_empty())
            })
            .count(),
        other_names: name_counts(ok.iter().flat_map(|(_, o)| {
            o.findings
                .iter()
                .filter(|f| !f.ordinary)
                .map(|f| f.name.as_str())
        })),
        explained: ok
            .iter()
            .filter(|(_, o)| o.verdict == mte_diagnose::Verdict::Explained)
            .count(),
        sigma0: quantiles(&ok.iter().map(|(_, o)| o.sigma0).collect::<Vec<_>>()),
        held_out_over_noise: ratio(&|o| o.base_held_out_rms_um)
            .zip(ratio(&|o| o.extended_held_out_rms_um)),
        first_error: records.iter().find_map(|r| r.outcome.clone().err()),
        records,
    }
}

/// A hidden effect family a study can put into datasets at a given size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effect {
    /// [`Hidden::Pitch`] of X, period 5–40 mm, amplitude µm.
    Pitch,
    /// [`Hidden::Reversal`], µm.
    Reversal,
    /// [`Hidden::Reversal`] of a rotary table, µrad.
    RotaryReversal,
    /// [`Hidden::ReversalGrowing`], µm at the end of the travel.
    ReversalGrowing,
    /// [`Hidden::ZeroDrift`], µm/min.
    ZeroDrift,
    /// [`Hidden::ScaleDrift`], τ 300–1800 s, ppm.
    ScaleDrift,
    /// [`Hidden::Squareness`] EC0Y (Y to X), µrad.
    Squareness,
    /// [`Hidden::TrackerScale`], ppm.
    TrackerScale,
    /// [`Hidden::PivotDrift`] of B (EX0B), τ 600–3600 s, µm.
    PivotDrift,
    /// [`Hidden::SpindleDrift`] along Z, τ 600–3600 s, µm.
    SpindleDrift,
    /// [`Hidden::AngularPositioning`] of C, harmonic 1–4, µrad.
    AngularPositioning,
    /// [`Hidden::AngularPositioning`] of C at 24–90 cycles per turn (a worm gear's tooth
    /// error), µrad.
    WormGear,
    /// [`Hidden::BTilt`], µrad.
    BTilt,
    /// [`Hidden::Sawtooth`] of X, period 20–80 mm, µm.
    Sawtooth,
    /// [`Hidden::RiseFall`], peak at 0.3–0.7 of the measuring time, µm.
    RiseFall,
    /// [`Hidden::TwoAxis`], µm.
    TwoAxis,
}

impl Effect {
    /// Every effect, in declaration order.
    pub const ALL: [Effect; 16] = [
        Effect::Pitch,
        Effect::Reversal,
        Effect::RotaryReversal,
        Effect::ReversalGrowing,
        Effect::ZeroDrift,
        Effect::ScaleDrift,
        Effect::Squareness,
        Effect::TrackerScale,
        Effect::PivotDrift,
        Effect::SpindleDrift,
        Effect::AngularPositioning,
        Effect::WormGear,
        Effect::BTilt,
        Effect::Sawtooth,
        Effect::RiseFall,
        Effect::TwoAxis,
    ];

    /// The effect whose `Debug` name is `name` (case-insensitive), e.g. `sawtooth`.
    pub fn parse(name: &str) -> Option<Effect> {
        Effect::ALL
            .into_iter()
            .find(|e| format!("{e:?}").eq_ignore_ascii_case(name))
    }

    /// Display name on datasets of `kind` (the A/C trunnion's tilting axis is A).
    pub fn name(self, kind: Kind) -> &'static str {
        match self {
            Effect::PivotDrift if kind == Kind::RtestAc => "thermal drift of EY0A",
            Effect::Pitch => "periodic pitch of X",
            Effect::Reversal => "reversal",
            Effect::RotaryReversal => "reversal of C",
            Effect::ReversalGrowing => "reversal growing along X",
            Effect::ZeroDrift => "linear zero drift",
            Effect::ScaleDrift => "thermal expansion of X growing in time",
            Effect::Squareness => "extra squareness EC0Y",
            Effect::TrackerScale => "tracker length scale",
            Effect::PivotDrift => "thermal drift of EX0B",
            Effect::SpindleDrift => "thermal growth of the spindle in Z",
            Effect::AngularPositioning => "angular positioning of C (harmonic)",
            Effect::WormGear => "worm-gear error of C (24–90 per turn)",
            Effect::BTilt => "B tilt EA0B",
            Effect::Sawtooth => "sawtooth positioning of X",
            Effect::RiseFall => "drift rising and falling",
            Effect::TwoAxis => "Y positioning changing along X",
        }
    }

    /// The hidden effect of size `size` (in [`Effect::unit`]), other parameters drawn from
    /// `rng`.
    pub fn hidden(self, size: f64, rng: &mut impl Rng) -> Hidden {
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        match self {
            Effect::Pitch => Hidden::Pitch {
                axis: 0,
                amplitude_um: size,
                period_mm: rng.random_range(5.0..=40.0),
            },
            Effect::Reversal | Effect::RotaryReversal => Hidden::Reversal { um: sign * size },
            Effect::ReversalGrowing => Hidden::ReversalGrowing { um: sign * size },
            Effect::ZeroDrift => Hidden::ZeroDrift {
                um_per_min: sign * size,
            },
            Effect::ScaleDrift => Hidden::ScaleDrift {
                ppm: sign * size,
                tau_s: rng.random_range(300.0..=1800.0),
                // The fixed bearing at the home end, or anywhere along the travel.
                fixed: if rng.random_bool(0.5) {
                    0.0
                } else {
                    rng.random_range(0.0..=1.0)
                },
            },
            Effect::Squareness => Hidden::Squareness {
                pair: 0,
                urad: sign * size,
            },
            Effect::TrackerScale => Hidden::TrackerScale { ppm: sign * size },
            Effect::PivotDrift => Hidden::PivotDrift {
                rotary: 0,
                um: sign * size,
                tau_s: rng.random_range(600.0..=3600.0),
            },
            Effect::SpindleDrift => Hidden::SpindleDrift {
                axis: 2,
                um: sign * size,
                tau_s: rng.random_range(600.0..=3600.0),
            },
            Effect::AngularPositioning => Hidden::AngularPositioning {
                rotary: 1,
                harmonic: rng.random_range(1..=4),
                urad: size,
            },
            Effect::WormGear => Hidden::AngularPositioning {
                rotary: 1,
                harmonic: rng.random_range(24..=90),
                urad: size,
            },
            Effect::BTilt => Hidden::BTilt { urad: sign * size },
            Effect::Sawtooth => Hidden::Sawtooth {
                axis: 0,
                amplitude_um: size,
                period_mm: rng.random_range(20.0..=80.0),
            },
            Effect::RiseFall => Hidden::RiseFall {
                um: sign * size,
                peak: rng.random_range(0.3..=0.7),
            },
            Effect::TwoAxis => Hidden::TwoAxis { um: sign * size },
        }
    }

    /// Unit of the sizes.
    pub fn unit(self) -> &'static str {
        match self {
            Effect::ZeroDrift => "µm/min",
            Effect::Squareness
            | Effect::AngularPositioning
            | Effect::WormGear
            | Effect::BTilt
            | Effect::RotaryReversal => "µrad",
            Effect::TrackerScale | Effect::ScaleDrift => "ppm",
            _ => "µm",
        }
    }
}

/// The power cells of the study: kind, effect, sizes.
pub fn power_plan() -> Vec<(Kind, Effect, Vec<f64>)> {
    vec![
        (Kind::Axis, Effect::Pitch, vec![0.5, 1.0, 2.0, 3.0]),
        (Kind::Axis, Effect::Reversal, vec![0.5, 1.0, 2.0, 3.0]),
        (Kind::Axis, Effect::ReversalGrowing, vec![1.0, 2.0, 4.0]),
        (Kind::Axis, Effect::ZeroDrift, vec![0.02, 0.05, 0.1, 0.2]),
        (Kind::Axis, Effect::ScaleDrift, vec![2.0, 5.0, 10.0, 20.0]),
        (Kind::Tracker, Effect::Pitch, vec![0.5, 1.0, 2.0, 3.0]),
        (
            Kind::Tracker,
            Effect::TrackerScale,
            vec![1.0, 2.0, 5.0, 10.0],
        ),
        (
            Kind::TrackerTools,
            Effect::Squareness,
            vec![10.0, 20.0, 40.0, 60.0],
        ),
        (
            Kind::PointsTargets,
            Effect::Squareness,
            vec![10.0, 20.0, 40.0, 60.0],
        ),
        (Kind::Rtest, Effect::PivotDrift, vec![5.0, 10.0, 20.0, 30.0]),
        (
            Kind::Rtest,
            Effect::SpindleDrift,
            vec![2.0, 5.0, 10.0, 20.0],
        ),
        (
            Kind::Rtest,
            Effect::AngularPositioning,
            vec![5.0, 10.0, 20.0, 30.0],
        ),
        (Kind::Rtest, Effect::BTilt, vec![10.0, 25.0, 50.0, 100.0]),
        (
            Kind::Rtest,
            Effect::Squareness,
            vec![10.0, 20.0, 40.0, 60.0],
        ),
        (
            Kind::RtestHead,
            Effect::PivotDrift,
            vec![5.0, 10.0, 20.0, 30.0],
        ),
        (
            Kind::RtestHead,
            Effect::SpindleDrift,
            vec![2.0, 5.0, 10.0, 20.0],
        ),
        (
            Kind::RtestAc,
            Effect::PivotDrift,
            vec![5.0, 10.0, 20.0, 30.0],
        ),
        (
            Kind::RtestAc,
            Effect::SpindleDrift,
            vec![2.0, 5.0, 10.0, 20.0],
        ),
        (
            Kind::Points,
            Effect::AngularPositioning,
            vec![5.0, 10.0, 20.0, 30.0],
        ),
        (Kind::Rotary, Effect::WormGear, vec![1.0, 2.5, 5.0, 10.0]),
        (
            Kind::Rotary,
            Effect::RotaryReversal,
            vec![1.0, 2.5, 5.0, 10.0],
        ),
    ]
}

/// The coverage cells: kind, effect, size (run with the FDR study's number of datasets).
pub fn coverage_plan() -> Vec<(Kind, Effect, f64)> {
    vec![
        (Kind::Axis, Effect::Pitch, 2.0),
        (Kind::Axis, Effect::Reversal, 1.0),
        (Kind::Axis, Effect::ZeroDrift, 0.1),
        (Kind::Axis, Effect::ScaleDrift, 10.0),
        // A size whose power cell showed fewer than 95 % within 2 u (about a second each).
        (Kind::Rtest, Effect::PivotDrift, 10.0),
        // A harmonic of a turn, whose period is exact (no period uncertainty in its size's).
        (Kind::Rotary, Effect::WormGear, 5.0),
        (Kind::Rotary, Effect::RotaryReversal, 5.0),
        // A squareness against the full model: the estimate against ISO 230-1's angle between
        // the reference lines through the measured positions.
        (Kind::TrackerTools, Effect::Squareness, 20.0),
        (Kind::PointsTargets, Effect::Squareness, 20.0),
    ]
}

/// Studies against the instrument's default base model (`--base-model omit`), which leaves
/// most of a real machine's ordinary errors out (an R-test's: all but the rotary axes' location
/// errors; a tracker's: all): the kinds whose clean datasets are run so, and the power cells.
/// What the diagnosis finds then is mostly those ordinary errors, which it names as such; a
/// drift or a periodic error on a clean machine is a false discovery.
pub fn default_base_plan() -> (Vec<Kind>, Vec<(Kind, Effect, f64)>) {
    (
        vec![Kind::Rtest, Kind::RtestHead, Kind::Tracker],
        vec![
            (Kind::Rtest, Effect::PivotDrift, 10.0),
            (Kind::RtestHead, Effect::SpindleDrift, 10.0),
            (Kind::Tracker, Effect::TrackerScale, 5.0),
        ],
    )
}

/// The open-world cells: kind, effect, size.
pub fn openworld_plan() -> Vec<(Kind, Effect, f64)> {
    vec![
        (Kind::Axis, Effect::Sawtooth, 2.0),
        (Kind::Axis, Effect::RiseFall, 3.0),
        (Kind::Tracker, Effect::Sawtooth, 3.0),
        (Kind::Tracker, Effect::TwoAxis, 5.0),
        (Kind::Rtest, Effect::RiseFall, 15.0),
        (Kind::Points, Effect::TwoAxis, 5.0),
    ]
}

/// Whether a finding's name names the true effect. The mapping (documented in
/// `docs/diagnosis-studies.md`):
/// periodic → the name contains the axis' ISO positioning name and `periodic` (`EXX periodic`);
/// squareness → the ISO name or its equivalent in the other axis (`EC0Y` ≡ `EC0X`,
/// `EA0Z` ≡ `EA0Y`, `EB0Z` ≡ `EB0X`); reversal → contains `reversal`; instrument scale →
/// `tracker scale`; drift → contains `drift` (and the parameter's name where there is one, e.g.
/// `EX0B … drift`; a scale drift for the axis' thermal expansion, whose hint is `EXX scale`,
/// else not a scale drift); angular positioning → contains `ECC`/`EBB` (not a drift,
/// reversal or scale of it) or the axis' name with `periodic`/`harmonic`; location → starts with the ISO name (`EA0B`, `EA0B abs`),
/// not a drift of it;
/// open-world effects are never named right.
pub fn names_effect(effect: &TrueEffect, finding: &str) -> bool {
    let hint = effect.iso_name_hint.as_str();
    match effect.kind {
        EffectKind::Periodic => finding.contains(hint) && finding.contains("periodic"),
        EffectKind::Squareness => {
            let alt = match hint {
                "EC0Y" => "EC0X",
                "EA0Z" => "EA0Y",
                "EB0Z" => "EB0X",
                other => other,
            };
            finding.starts_with(hint) || finding.starts_with(alt)
        }
        EffectKind::Reversal => finding.contains("reversal"),
        EffectKind::InstrumentScale => finding.contains("tracker scale"),
        EffectKind::Drift => {
            finding.contains("drift")
                && finding.contains("scale") == hint.contains("scale")
                && (hint == "drift" || finding.contains(hint))
        }
        EffectKind::AngularPositioning => {
            let axis = &hint[1..2];
            let other = ["drift", "reversal", "scale"]
                .iter()
                .any(|w| finding.contains(w));
            (finding.contains(hint) && !other)
                || (finding.contains(axis)
                    && (finding.contains("periodic") || finding.contains("harmonic")))
        }
        EffectKind::Location => finding.starts_with(hint) && !finding.contains("drift"),
        EffectKind::OpenWorld => false,
    }
}

/// Whether the finding's estimate matches the truth within `k` standard uncertainties: the
/// estimate named `amplitude` if there is one, else the first; magnitudes are compared where the
/// truth's sign is not defined the diagnosis's way ([`TrueEffect::signed`]). Where the report
/// states a 95 % interval (a first-order drift's final value, beyond the record; a periodic
/// error's amplitude whose period the data leave open within its main lobe), with `k` = 2
/// the truth must lie in it. A first-order drift found linear, whose estimate is a rate, is
/// compared with `k` = 2 through the interval the report states for the value a first-order
/// drift of the parameter would settle to ([`FoundEffect::first_order_final`]); a linear drift's
/// rate is not compared with a final value (found first-order): no match.
pub fn estimate_matches(effect: &TrueEffect, finding: &FoundEffect, k: f64) -> bool {
    let Some((name, v, u, interval)) = compared_estimate(finding) else {
        return false;
    };
    let in_interval = |i: &mte_diagnose::Interval| {
        i.contains(effect.value) || (!effect.signed && i.contains(-effect.value))
    };
    // A rate (a linear drift's) and a final value (a first-order one's) are not compared.
    let truth_is_rate = effect.unit.ends_with("/min");
    if name.ends_with(" rate") != truth_is_rate {
        return match &finding.first_order_final {
            Some(i) if k == 2.0 && !truth_is_rate => in_interval(i),
            _ => false,
        };
    }
    match interval {
        Some(i) if k == 2.0 => in_interval(i),
        _ => {
            let (v, t) = if effect.signed {
                (*v, effect.value)
            } else {
                (v.abs(), effect.value.abs())
            };
            (v - t).abs() <= k * u
        }
    }
}

/// For a drift with a known change over the record
/// ([`TrueDrift::record_change`](crate::realistic::TrueDrift::record_change)): whether the
/// diagnosis' change over the measured time lies within `k` standard uncertainties of it — the
/// finding's first (an expansion about a point states its scale's, then its zero's), or that
/// parameter's change by the group of findings the diagnosis says are one drift of it when
/// `finding` is in one; with `k` = 2, where the report states a 95 % interval of the change (by
/// the profile over the time constant, which admits the other form of drift), the truth must
/// lie in it. `None` for other effects.
pub fn change_matches(
    effect: &TrueEffect,
    finding: &FoundEffect,
    outcome: &Outcome,
    k: f64,
) -> Option<bool> {
    let truth = effect.drift?.record_change;
    let stated = stated_change(finding, outcome);
    Some(stated.is_some_and(|(v, u, interval)| match interval {
        Some(i) if k == 2.0 => i.contains(truth),
        _ => (v - truth).abs() <= k * u,
    }))
}

/// The estimate of a finding that is compared with the truth ([`estimate_matches`]): the one
/// named `amplitude` if there is one, else the first.
fn compared_estimate(finding: &FoundEffect) -> Option<&Estimate> {
    finding
        .estimates
        .iter()
        .find(|e| e.0.contains("amplitude"))
        .or(finding.estimates.first())
}

/// A drift finding's change over the measured time with its u and the 95 % interval the report
/// states ([`change_matches`]): its own, or its parameter's by the group of findings the
/// diagnosis says are one drift of it (without an interval).
fn stated_change(
    finding: &FoundEffect,
    outcome: &Outcome,
) -> Option<(f64, f64, Option<mte_diagnose::Interval>)> {
    let own = finding
        .estimates
        .iter()
        .find(|e| e.0.ends_with("change over the measured time"))?;
    outcome
        .compound_sizes
        .iter()
        .find(|(members, name, _, _)| members.contains(&finding.name) && *name == own.0)
        .map(|(_, _, v, u)| (*v, *u, None))
        .or(Some((own.1, own.2, own.3)))
}

/// The estimate of a dataset's hidden effect that is compared with the truth as estimate ± k u,
/// with the truth: `(estimate, u, truth)` — a drift's change over the measured time (its size
/// whatever form it is found in, [`change_matches`]), else the naming finding's estimate where
/// [`estimate_matches`] compares it so (not through a stated interval, not a rate against a
/// final value), as magnitudes where the truth's sign is not the diagnosis's
/// ([`TrueEffect::signed`]). `None` where no finding names the effect or its estimate is
/// compared otherwise.
pub fn scored(effect: &TrueEffect, outcome: &Outcome) -> Option<(f64, f64, f64)> {
    let Account::Named(finding) = account(effect, outcome) else {
        return None;
    };
    if let Some(drift) = effect.drift {
        let (v, u, _) = stated_change(finding, outcome)?;
        return Some((v, u, drift.record_change));
    }
    let (name, v, u, interval) = compared_estimate(finding)?;
    if interval.is_some() || name.ends_with(" rate") != effect.unit.ends_with("/min") {
        return None;
    }
    Some(if effect.signed {
        (*v, *u, effect.value)
    } else {
        (v.abs(), *u, effect.value.abs())
    })
}

/// A coverage cell ([`coverage_with`]): the power table's row of the datasets with their own
/// noise, the row of the same machines and effects with a second draw of the noise, and the
/// two draws of each machine compared: a u too small for the scatter makes both draws' z large,
/// a bias of the machine's own (its errors left in the model) makes them agree.
#[derive(Debug, Clone)]
pub struct CoverageCell {
    /// The datasets with their own noise.
    pub own: PowerCell,
    /// The same machines and effects with a second draw of the noise.
    pub second: PowerCell,
    /// Machines whose effect both draws name right with an estimate compared as ± u
    /// ([`scored`]).
    pub paired: usize,
    /// Over both draws of those, the RMS of `z = (e − truth)/u`: 1 for an honest u without bias.
    pub z_rms: f64,
    /// The correlation of the two draws' z over those machines: near 0 without a bias of each
    /// machine's own, towards 1 with one.
    pub z_correlation: f64,
}

/// Coverage of the stated uncertainties of `effect` at `size`: `n` machines of `kind`, each
/// with its own noise and with a second draw of it, against the base `base_model`.
pub fn coverage_with(
    kind: Kind,
    effect: Effect,
    size: f64,
    n: usize,
    base_seed: u64,
    base_model: &BaseModel,
) -> CoverageCell {
    let draws =
        [0, 1].map(|draw| power_records(kind, effect, size, n, base_seed, base_model, draw));
    let score = |r: &Record| scored(r.effects.first()?, r.outcome.as_ref().ok()?);
    let pairs: Vec<[(f64, f64, f64); 2]> = draws[0]
        .iter()
        .zip(&draws[1])
        .filter_map(|(a, b)| Some([score(a)?, score(b)?]))
        .collect();
    let z = |(v, u, truth): (f64, f64, f64)| (v - truth) / u;
    let rms = |x: &[f64]| (x.iter().map(|x| x * x).sum::<f64>() / x.len() as f64).sqrt();
    let zs: Vec<[f64; 2]> = pairs.iter().map(|&[a, b]| [z(a), z(b)]).collect();
    CoverageCell {
        own: power_cell(kind, effect, size, &draws[0]),
        second: power_cell(kind, effect, size, &draws[1]),
        paired: pairs.len(),
        z_rms: rms(&zs.concat()),
        z_correlation: correlation(&zs),
    }
}

/// The correlation of the pairs' two members (NaN for fewer than two pairs or no spread).
fn correlation(pairs: &[[f64; 2]]) -> f64 {
    let n = pairs.len() as f64;
    let mean = |k: usize| pairs.iter().map(|p| p[k]).sum::<f64>() / n;
    let (m0, m1) = (mean(0), mean(1));
    let (mut s01, mut s00, mut s11) = (0.0, 0.0, 0.0);
    for p in pairs {
        let (a, b) = (p[0] - m0, p[1] - m1);
        s01 += a * b;
        s00 += a * a;
        s11 += b * b;
    }
    s01 / (s00 * s11).sqrt()
}

/// Detection power of one effect at one size.
#[derive(Debug, Clone)]
pub struct PowerCell {
    /// Kind of dataset.
    pub kind: Kind,
    /// The effect.
    pub effect: Effect,
    /// Its size, in `effect.unit()`.
    pub size: f64,
    /// Datasets run.
    pub n: usize,
    /// Load / diagnosis errors.
    pub errors: usize,
    /// Datasets with any finding.
    pub any_finding: usize,
    /// Datasets with a finding naming the effect.
    pub named_right: usize,
    /// Datasets without such a finding but with one whose reported not-separable
    /// alternatives name the effect (the data cannot tell them apart, and the report says so);
    /// for an instrument's scale, which no data of its own can separate from a common scale of
    /// the axes, the report's list of what is not separable naming it.
    pub named_as_alternative: usize,
    /// Datasets without a finding naming the effect (or an alternative), whose report says
    /// that the sampling along the effect's axis cannot show its period
    /// ([`stated_out_of_reach`]).
    pub out_of_reach: usize,
    /// Datasets of none of the above whose report states that the effect is smaller than what
    /// the data would show ([`stated_below_limit`]).
    pub below_limit: usize,
    /// Of those named right, datasets whose estimate is within 2 u of the truth.
    pub estimate_within_2u: usize,
    /// For a drift, of those named right, datasets whose stated change over the measured time
    /// holds the truth's in its 95 % interval ([`change_matches`]); `None` for other effects.
    pub change_in_interval: Option<usize>,
    /// Of those named right, datasets where the report qualifies the form of the finding that
    /// names it (one effect of a form no candidate has, or a shape the data do not determine:
    /// [`Outcome::qualified`]).
    pub form_qualified: usize,
    /// Datasets whose findings all name the effect (no other cause) and whose verdict is that
    /// the causes found explain the data.
    pub alone_explained: usize,
    /// Most frequent finding names.
    pub names: Vec<(String, usize)>,
}

/// The user's model of a power cell: the standard model (every ordinary error,
/// [`BaseModel::standard`]) less the errors that would already hold the hidden effect
/// (`except`), with the errors an R-test cannot tell from them: for a squareness cell the XY
/// squareness (`EC0Y`, `EC0X`) and the orientation of the B line about Z (`EC0B`, on machines
/// with a B axis); for an angular positioning cell the angular positioning error of C (`ECC`);
/// for a B tilt the tilt (`EA0B`), B's error motion about X (`EAB`, whose harmonics over B's
/// range hold most of a constant tilt) and the YZ squareness (`EA0Y`, `EA0Z`). A finding then names one of them and
/// lists the others as not separable. What the user's model lacks is what a diagnosis can find.
pub fn user_model_lacking(kind: Kind, effect: Effect) -> BaseModel {
    let except: &[&str] = match effect {
        // (The points and tracker machines have no B.)
        Effect::Squareness
            if matches!(
                kind,
                Kind::Points | Kind::PointsTargets | Kind::Tracker | Kind::TrackerTools
            ) =>
        {
            &["EC0Y", "EC0X"]
        }
        Effect::Squareness => &["EC0Y", "EC0X", "EC0B"],
        Effect::AngularPositioning => &["ECC"],
        Effect::BTilt => &["EA0B", "EAB", "EA0Y", "EA0Z"],
        _ => return BaseModel::Default,
    };
    let mut model = BaseModel::standard();
    model["except"] = serde_json::json!(except);
    BaseModel::Given(model)
}

/// [`power_with`] with the user's model lacking the effect ([`user_model_lacking`]).
pub fn power(
    kind: Kind,
    effect: Effect,
    sizes: &[f64],
    n: usize,
    base_seed: u64,
) -> Vec<PowerCell> {
    power_with(
        kind,
        effect,
        sizes,
        n,
        base_seed,
        &user_model_lacking(kind, effect),
    )
}

/// Power of `effect` in `kind` datasets at each of `sizes`, `n` datasets per size.
pub fn power_with(
    kind: Kind,
    effect: Effect,
    sizes: &[f64],
    n: usize,
    base_seed: u64,
    base_model: &BaseModel,
) -> Vec<PowerCell> {
    sizes
        .iter()
        .map(|&size| {
            let records = power_records(kind, effect, size, n, base_seed, base_model, 0);
            power_cell(kind, effect, size, &records)
        })
        .collect()
}

/// The datasets of a power cell ([`power_with`]), with draw `draw` of the noise
/// ([`run_cell_drawn`]).
fn power_records(
    kind: Kind,
    effect: Effect,
    size: f64,
    n: usize,
    base_seed: u64,
    base_model: &BaseModel,
    draw: usize,
) -> Vec<Record> {
    let cell = power_cell_name(kind, effect, size);
    run_cell_drawn(&cell, n, base_seed, draw, |rng| {
        power_spec(kind, effect, size, base_model, rng)
    })
}

/// The name of the power cell of `effect` at `size` on `kind`, from which with the base seed
/// its datasets' seeds are drawn ([`dataset_seed`]).
fn power_cell_name(kind: Kind, effect: Effect, size: f64) -> String {
    format!("power-{}-{:?}-{size}", kind.name(), effect)
}

/// A power cell's dataset: `effect` at `size` hidden, its other parameters drawn from `rng`,
/// against `base_model`.
fn power_spec(
    kind: Kind,
    effect: Effect,
    size: f64,
    base_model: &BaseModel,
    rng: &mut ChaCha8Rng,
) -> Spec {
    let mut s = Spec::new(kind, &[effect.hidden(size, rng)]);
    s.base_model = base_model.clone();
    s
}

/// Dataset `index` of the power cell of `effect` at `size` on `kind` with base seed
/// `base_seed` (the power study's, against the user's model lacking the effect:
/// [`user_model_lacking`]), and its seed.
pub fn power_dataset(
    kind: Kind,
    effect: Effect,
    size: f64,
    base_seed: u64,
    index: usize,
) -> (Spec, u64) {
    let seed = dataset_seed(base_seed, &power_cell_name(kind, effect, size), index);
    let base_model = user_model_lacking(kind, effect);
    (
        power_spec(kind, effect, size, &base_model, &mut spec_rng(seed)),
        seed,
    )
}

/// The power table's row of the datasets `records` of `effect` at `size`.
fn power_cell(kind: Kind, effect: Effect, size: f64, records: &[Record]) -> PowerCell {
    let mut c = PowerCell {
        kind,
        effect,
        size,
        n: records.len(),
        errors: 0,
        any_finding: 0,
        named_right: 0,
        named_as_alternative: 0,
        out_of_reach: 0,
        below_limit: 0,
        estimate_within_2u: 0,
        change_in_interval: None,
        form_qualified: 0,
        alone_explained: 0,
        names: Vec::new(),
    };
    let mut all_names = Vec::new();
    for r in records {
        let Ok(o) = &r.outcome else {
            c.errors += 1;
            continue;
        };
        let Some(truth) = r.effects.first() else {
            c.errors += 1;
            continue;
        };
        c.any_finding += usize::from(!o.findings.is_empty());
        match account(truth, o) {
            Account::Named(f) => {
                c.named_right += 1;
                c.estimate_within_2u += usize::from(estimate_matches(truth, f, 2.0));
                if let Some(hit) = change_matches(truth, f, o, 2.0) {
                    *c.change_in_interval.get_or_insert(0) += usize::from(hit);
                }
                c.form_qualified += usize::from(o.qualified.contains(&f.name));
                c.alone_explained += usize::from(
                    o.verdict == mte_diagnose::Verdict::Explained
                        && o.findings.iter().all(|f| names_effect(truth, &f.name)),
                );
            }
            Account::NotSeparable => c.named_as_alternative += 1,
            Account::OutOfReach => c.out_of_reach += 1,
            Account::BelowLimit => c.below_limit += 1,
            Account::Missed => {}
        }
        all_names.extend(o.findings.iter().map(|f| f.name.clone()));
    }
    c.names = name_counts(all_names.iter().map(String::as_str));
    c
}

/// How a dataset's report stands to one hidden effect: the power table's columns, each taken
/// only where the ones before it are not.
pub enum Account<'o> {
    /// A finding names it ([`names_effect`]).
    Named(&'o FoundEffect),
    /// A finding's alternatives the data cannot tell apart name it, or, for an instrument's
    /// scale, the report's list of what is not separable does.
    NotSeparable,
    /// The report says the sampling cannot show its period ([`stated_out_of_reach`]).
    OutOfReach,
    /// The report states it below what the data would show ([`stated_below_limit`]).
    BelowLimit,
    /// None of these: missed without a word.
    Missed,
}

/// [`Account`] of the hidden effect `truth` in the outcome `o`.
pub fn account<'o>(truth: &TrueEffect, o: &'o Outcome) -> Account<'o> {
    let naming: Vec<&FoundEffect> = o
        .findings
        .iter()
        .filter(|f| names_effect(truth, &f.name))
        .collect();
    // Of several findings naming a periodic effect (a rotary axis' ordinary harmonics beside the
    // hidden one), the one nearest its frequency; else the first.
    let nearest = truth.period.as_ref().and_then(|(_, p)| {
        naming
            .iter()
            .filter_map(|f| Some((*f, (1.0 / f.period? - 1.0 / p).abs())))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(f, _)| f)
    });
    if let Some(f) = nearest.or(naming.first().copied()) {
        return Account::Named(f);
    }
    let listed = truth.kind == EffectKind::InstrumentScale
        && o.not_separable.iter().any(|a| names_effect(truth, a));
    if listed
        || o.findings
            .iter()
            .any(|f| f.alternatives.iter().any(|a| names_effect(truth, a)))
    {
        Account::NotSeparable
    } else if stated_out_of_reach(truth, o) {
        Account::OutOfReach
    } else if stated_below_limit(truth, o) {
        Account::BelowLimit
    } else {
        Account::Missed
    }
}

/// Whether the report says that the sampling cannot show the effect's period: the effect
/// repeats along an axis whose periodic reach, as the diagnosis reports it, is limited by the
/// sampling (too few positions, a regular step) and does not cover the period.
pub fn stated_out_of_reach(effect: &TrueEffect, o: &Outcome) -> bool {
    effect.period.as_ref().is_some_and(|(axis, p)| {
        o.periodic_reach
            .iter()
            .any(|r| &r.variable == axis && r.limited_by_sampling() && !r.covers(*p))
    })
}

/// Whether the report says the effect is too small for these data: a cause of the library that
/// would name it is listed as not separable from the model, or those that would name it have
/// detection limits ([`mte_diagnose::DetectionLimit`]) and at the effect's period (where it has
/// one, at its time constant where it is a first-order drift, else at the variant the data are
/// most sensitive to) each is above the effect's size or not separable from the model. A
/// first-order drift's size (its asymptote) is compared with the first-order candidates' limits
/// only.
pub fn stated_below_limit(effect: &TrueEffect, o: &Outcome) -> bool {
    if o.not_separable.iter().any(|n| names_effect(effect, n)) {
        return true;
    }
    // A first-order drift's size is its asymptote, which the limits of the first-order
    // candidates state at each time constant (a linear drift's limit is a rate).
    let mut limits = o
        .detection_limits
        .iter()
        .filter(|l| names_effect(effect, &l.name))
        .filter(|l| effect.drift.is_none() || l.name.ends_with(" exp"))
        .peekable();
    limits.peek().is_some()
        && limits.all(|l| {
            let at = match (&effect.period, effect.drift) {
                (Some((_, p)), _) => Some(*p),
                (None, Some(d)) => Some(d.tau_s),
                (None, None) => None,
            };
            let size = match at {
                Some(at) => l.near(at),
                None => l.smallest().map(|s| s.1),
            };
            size.is_none_or(|s| effect.value.abs() < s)
        })
}

/// What the diagnosis said about an open-world effect.
#[derive(Debug, Clone)]
pub struct OpenWorldSummary {
    /// Kind of dataset.
    pub kind: Kind,
    /// The effect.
    pub effect: Effect,
    /// Its size.
    pub size: f64,
    /// Datasets run.
    pub n: usize,
    /// Load / diagnosis errors.
    pub errors: usize,
    /// No finding.
    pub nothing: usize,
    /// Of those, datasets whose report says the sampling cannot show the effect's period
    /// ([`stated_out_of_reach`]).
    pub nothing_out_of_reach: usize,
    /// Findings, but the extended model still fails the χ² test (p < 0.01) or its σ0 > 1.5:
    /// the report shows a residual it does not explain.
    pub unexplained: usize,
    /// Findings the diagnosis itself calls one effect of a form no candidate has (harmonics of a
    /// periodic error that is not a sine; a drift neither linear nor first-order), and an
    /// extended model that passes: the cause named with its shape stated.
    pub shape_stated: usize,
    /// Findings and an extended model that passes, with no such statement: a confident (wrong)
    /// cause.
    pub confident_wrong: usize,
    /// Most frequent finding names.
    pub names: Vec<(String, usize)>,
}

/// [`openworld_with`] with the kind's default base model.
pub fn openworld(
    kind: Kind,
    effect: Effect,
    size: f64,
    n: usize,
    base_seed: u64,
) -> OpenWorldSummary {
    openworld_with(kind, effect, size, n, base_seed, &BaseModel::Default)
}

/// Open world: `n` datasets of `kind` with `effect` of `size`.
pub fn openworld_with(
    kind: Kind,
    effect: Effect,
    size: f64,
    n: usize,
    base_seed: u64,
    base_model: &BaseModel,
) -> OpenWorldSummary {
    let cell = format!("openworld-{}-{:?}", kind.name(), effect);
    let records = run_cell(&cell, n, base_seed, |rng| {
        let mut s = Spec::new(kind, &[effect.hidden(size, rng)]);
        s.base_model = base_model.clone();
        s
    });
    let mut s = OpenWorldSummary {
        kind,
        effect,
        size,
        n,
        errors: 0,
        nothing: 0,
        nothing_out_of_reach: 0,
        unexplained: 0,
        shape_stated: 0,
        confident_wrong: 0,
        names: Vec::new(),
    };
    let mut all_names = Vec::new();
    for r in &records {
        let Ok(o) = &r.outcome else {
            s.errors += 1;
            continue;
        };
        match o.verdict {
            mte_diagnose::Verdict::NoDiscrepancy => {
                s.nothing += 1;
                s.nothing_out_of_reach += usize::from(
                    r.effects
                        .first()
                        .is_some_and(|truth| stated_out_of_reach(truth, o)),
                );
            }
            mte_diagnose::Verdict::Unexplained => s.unexplained += 1,
            _ if o.compound > 0 => s.shape_stated += 1,
            _ => s.confident_wrong += 1,
        }
        all_names.extend(o.findings.iter().map(|f| f.name.clone()));
    }
    s.names = name_counts(all_names.iter().map(String::as_str));
    s
}

/// The cells of the combined study: several effects hidden in each dataset at once, with their
/// sizes. A second effect of one family goes to the next axis ([`combined_hidden`]): a second
/// pitch is Y's, a second pivot drift the C line's.
pub fn combined_plan() -> Vec<(Kind, Vec<(Effect, f64)>)> {
    vec![
        (
            Kind::Axis,
            vec![
                (Effect::Pitch, 2.0),
                (Effect::Reversal, 1.0),
                (Effect::ZeroDrift, 0.1),
            ],
        ),
        (
            Kind::Tracker,
            vec![(Effect::Pitch, 2.0), (Effect::Pitch, 2.0)],
        ),
        (
            Kind::Rtest,
            vec![(Effect::PivotDrift, 10.0), (Effect::PivotDrift, 10.0)],
        ),
        // A thermal test's usual pair: the spindle grows while the table's pivot moves.
        (
            Kind::Rtest,
            vec![(Effect::PivotDrift, 10.0), (Effect::SpindleDrift, 10.0)],
        ),
        (
            Kind::RtestAc,
            vec![(Effect::PivotDrift, 10.0), (Effect::PivotDrift, 10.0)],
        ),
        // A worn worm drive: its tooth error and its backlash.
        (
            Kind::Rotary,
            vec![(Effect::WormGear, 5.0), (Effect::RotaryReversal, 5.0)],
        ),
    ]
}

/// The hidden effects `cargo xtask realistic <kind> <seed> <dir> --hidden …` writes into the
/// dataset of `seed` ([`combined_hidden`], drawn from the seed).
pub fn hidden_of_seed(effects: &[(Effect, f64)], seed: u64) -> Vec<Hidden> {
    combined_hidden(
        effects,
        &mut ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_5eed_5eed_5eed),
    )
}

/// The hidden effects of a combined cell, their other parameters drawn from `rng`: the k-th
/// effect of one family on the k-th axis (pitch: X, Y, Z; pivot drift: B, C).
pub fn combined_hidden(effects: &[(Effect, f64)], rng: &mut impl Rng) -> Vec<Hidden> {
    effects
        .iter()
        .enumerate()
        .map(|(k, &(effect, size))| {
            let before = of_its_family_before(effects, k);
            let mut h = effect.hidden(size, rng);
            match &mut h {
                Hidden::Pitch { axis, .. } => *axis = before,
                Hidden::PivotDrift { rotary, .. } => *rotary = before,
                _ => {}
            }
            h
        })
        .collect()
}

/// How many effects of the family of `effects[k]` come before it: the axis it goes on
/// ([`combined_hidden`]).
fn of_its_family_before(effects: &[(Effect, f64)], k: usize) -> usize {
    effects[..k]
        .iter()
        .filter(|(e, _)| *e == effects[k].0)
        .count()
}

/// Several effects hidden at once in each dataset.
#[derive(Debug, Clone)]
pub struct CombinedCell {
    /// Kind of dataset.
    pub kind: Kind,
    /// The effects and their sizes ([`combined_hidden`]).
    pub effects: Vec<(Effect, f64)>,
    /// Datasets run.
    pub n: usize,
    /// Load / diagnosis errors.
    pub errors: usize,
    /// Datasets with every effect named right.
    pub all_named: usize,
    /// Effects, over all datasets, named right by a finding.
    pub effects_named: usize,
    /// Effects not named right that a finding's not-separable alternatives name.
    pub effects_as_alternative: usize,
    /// Effects neither named nor an alternative, whose period the report says the sampling
    /// cannot show ([`stated_out_of_reach`]).
    pub effects_out_of_reach: usize,
    /// Of the effects named right, those whose size lies within 2 u of the truth (for a drift,
    /// its change over the measured time, [`change_matches`]; else [`estimate_matches`]).
    pub within_2u: usize,
    /// Datasets whose every finding names one of the effects.
    pub no_other: usize,
    /// Datasets with every effect named right, no other finding, and the verdict that the causes
    /// found explain the data.
    pub all_alone_explained: usize,
    /// Most frequent finding names.
    pub names: Vec<(String, usize)>,
}

impl CombinedCell {
    /// The effects as the page names them (`periodic pitch of X 2 µm + …`).
    pub fn label(&self) -> String {
        self.effects
            .iter()
            .enumerate()
            .map(|(k, &(e, size))| {
                let name = match (e, of_its_family_before(&self.effects, k)) {
                    (Effect::Pitch, 1) => "periodic pitch of Y",
                    (Effect::Pitch, 2) => "periodic pitch of Z",
                    (Effect::PivotDrift, 1) if self.kind == Kind::RtestAc => {
                        "thermal drift of EY0C"
                    }
                    (Effect::PivotDrift, 1) => "thermal drift of EX0C",
                    _ => e.name(self.kind),
                };
                format!("{name} {size} {}", e.unit())
            })
            .collect::<Vec<_>>()
            .join(" + ")
    }
}

/// `n` datasets of `kind` with every effect of `effects` at once, diagnosed against
/// `base_model` (the study's: the user's model of a real machine, [`BaseModel::Default`]).
pub fn combined(
    kind: Kind,
    effects: &[(Effect, f64)],
    n: usize,
    base_seed: u64,
    base_model: &BaseModel,
) -> CombinedCell {
    let tag: Vec<String> = effects.iter().map(|(e, s)| format!("{e:?}-{s}")).collect();
    let cell = format!("combined-{}-{}", kind.name(), tag.join("-"));
    let records = run_cell(&cell, n, base_seed, |rng| {
        let mut s = Spec::new(kind, &combined_hidden(effects, rng));
        s.base_model = base_model.clone();
        s
    });
    let mut c = CombinedCell {
        kind,
        effects: effects.to_vec(),
        n,
        errors: 0,
        all_named: 0,
        effects_named: 0,
        effects_as_alternative: 0,
        effects_out_of_reach: 0,
        within_2u: 0,
        no_other: 0,
        all_alone_explained: 0,
        names: Vec::new(),
    };
    let mut all_names = Vec::new();
    for r in &records {
        let Ok(o) = &r.outcome else {
            c.errors += 1;
            continue;
        };
        if r.effects.len() != effects.len() {
            c.errors += 1;
            continue;
        }
        let mut named = 0;
        for truth in &r.effects {
            match account(truth, o) {
                Account::Named(f) => {
                    named += 1;
                    let sized = change_matches(truth, f, o, 2.0)
                        .unwrap_or_else(|| estimate_matches(truth, f, 2.0));
                    c.within_2u += usize::from(sized);
                }
                Account::NotSeparable => c.effects_as_alternative += 1,
                Account::OutOfReach => c.effects_out_of_reach += 1,
                Account::BelowLimit | Account::Missed => {}
            }
        }
        c.effects_named += named;
        let all = named == r.effects.len();
        c.all_named += usize::from(all);
        let no_other = o
            .findings
            .iter()
            .all(|f| r.effects.iter().any(|t| names_effect(t, &f.name)));
        c.no_other += usize::from(no_other);
        c.all_alone_explained +=
            usize::from(all && no_other && o.verdict == mte_diagnose::Verdict::Explained);
        all_names.extend(o.findings.iter().map(|f| f.name.clone()));
    }
    c.names = name_counts(all_names.iter().map(String::as_str));
    c
}

/// The section of [`StudyReport::default_base`] and [`StudyReport::default_base_power`].
fn default_base_section(s: &mut String, r: &StudyReport) {
    let _ = writeln!(
        s,
        "## Against the instrument's default base model\n\n\
The same realistic machines, diagnosed against the base model a dataset gets when it states \
none (`--base-model omit`): for R-test the location errors of the rotary axes that the set-ups \
separate, as R-test practice identifies them; for tracker lengths the stations alone. A real \
machine has every ordinary error besides, so the diagnosis finds them — component errors as \
polynomials, squareness, error motions of a rotary axis over a turn — and names them as \
ordinary errors the base leaves out (`Finding::ordinary`; the report says which base would hold \
them). It adds those first: while one still earns its place no drift, no periodic error at \
a free period and no set-up error of the instrument goes in, which would otherwise take the \
shape of a missing ordinary error for its own (a pitch of Y at a period of 1.17 mm, a drift of \
EA0C over a single cycle, a ball's centring offset, all on clean machines); a drift must show \
in the differences between visits of the same pose, and a pitch must predict the residuals \
at positions of its axis it was not fitted to (the report lists those passed over). *with a finding other than an ordinary error*: a false discovery on a clean \
machine; *of which every such finding qualified*: the report says of each that its period \
and shape are not determined, or that it is one effect of a form no candidate has, or it lists \
what these data cannot tell the finding from; \
*verdict \"explained\"*: the causes found leave residuals consistent with the noise (the rest \
say that structure remains: the polynomials of degree 3 and the first harmonics do not hold \
all of a machine's smooth errors). On clean tracker data a tracker's length scale named is \
the common part of the axes' scale errors, which lengths cannot tell from it: the report lists \
with it the axes' scales the model lacks, together (an identity of the geometry, not a near \
miss of the data: with the stations free, lengths too long in proportion are a common scale of \
X, Y and Z). The power cells below put the effect on the same machines \
as the power table's cells of that effect and size; *named alone, explained* there counts \
the ordinary errors found as other findings.\n\n\
| kind | datasets | errors | with a finding | with a finding other than an ordinary error | of which every such finding qualified | verdict \"explained\" | most frequent findings other than ordinary errors | σ0 (min / 10 % / median / 90 % / max) | held-out RMS ÷ σ, base → diagnosed (median) |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    for f in &r.default_base {
        let (q, h) = f.fit_cells();
        let ran = f.n - f.errors;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {q} | {h} |",
            f.kind.name(),
            f.n,
            f.errors,
            pct(f.with_finding, ran),
            pct(f.with_other, ran),
            pct(f.other_qualified, f.with_other),
            pct(f.explained, ran),
            top(&f.other_names, 5)
        );
    }
    s.push('\n');
    if !r.default_base_power.is_empty() {
        power_table(s, &r.default_base_power);
        s.push('\n');
    }
}

fn power_table<'a>(s: &mut String, cells: impl IntoIterator<Item = &'a PowerCell>) {
    let _ = writeln!(
        s,
        "| kind | effect | size | datasets | errors | any finding | named right | else reported as not separable | else period stated out of reach | else stated below detection limit | within 2 u | drift: change over the measured time in its 95 % interval | named, form qualified | named alone, explained | most frequent findings |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for c in cells {
        let ran = c.n - c.errors;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            cell_columns(c.kind, c.effect, c.size),
            c.n,
            c.errors,
            pct(c.any_finding, ran),
            pct(c.named_right, ran),
            pct(c.named_as_alternative, ran),
            pct(c.out_of_reach, ran),
            pct(c.below_limit, ran),
            pct(c.estimate_within_2u, c.named_right),
            c.change_in_interval
                .map_or("–".into(), |k| pct(k, c.named_right)),
            pct(c.form_qualified, c.named_right),
            pct(c.alone_explained, ran),
            top(&c.names, 3)
        );
    }
    s.push('\n');
}

/// A cell's first three columns: kind, effect, size with its unit.
fn cell_columns(kind: Kind, effect: Effect, size: f64) -> String {
    format!(
        "{} | {} | {} {}",
        kind.name(),
        effect.name(kind),
        size,
        effect.unit()
    )
}

/// The coverage cells' second draws of the noise and the two draws compared
/// ([`CoverageCell`]).
fn coverage_draws_table(s: &mut String, cells: &[CoverageCell]) {
    let _ = writeln!(
        s,
        "The same machines and hidden effects measured again, with a second draw of the noise \
(`xtask realistic … --noise-seed`: the machine, its errors and the effect as before; what a \
generator draws with the noise, an R-test's pauses between cycles, a points dataset's set-up \
poses and C angles, drawn anew). Over the machines whose effect both draws name right: \
*z, RMS* over both draws of z = (e − truth)/u, each draw against its own truth (an R-test's \
record, and with it a drift's change, lasts as its pauses do), 1 for an honest u without bias; \
the *correlation of the draws' z* near 0 where no machine has a bias of its own, towards 1 \
where the machine's errors left in the model bias its estimate (a u right for the scatter then \
still misses the truth). The estimate compared is a drift's change over the measured time (the size the data \
determine whatever the form found), else the one the *within 2 u* column compares as ± 2 u \
(a first-order drift's final value, compared through its stated interval, has no such z). \
*within 2 u, both draws*: of all draws where the effect is named right.\n\n\
| kind | effect | size | machines | second draw: named right | second draw: within 2 u | second draw: drift change in its interval | both draws: within 2 u | both draws: drift change in its interval | compared in both draws | z, RMS | correlation of the draws' z |\n\
|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for c in cells {
        let (a, b) = (&c.own, &c.second);
        let ran = b.n - b.errors;
        let named = a.named_right + b.named_right;
        let both_changes = a.change_in_interval.zip(b.change_in_interval);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.2} |",
            cell_columns(a.kind, a.effect, a.size),
            a.n,
            pct(b.named_right, ran),
            pct(b.estimate_within_2u, b.named_right),
            b.change_in_interval
                .map_or("–".into(), |k| pct(k, b.named_right)),
            pct(a.estimate_within_2u + b.estimate_within_2u, named),
            both_changes.map_or("–".into(), |(x, y)| pct(x + y, named)),
            c.paired,
            c.z_rms,
            c.z_correlation,
        );
    }
    s.push('\n');
}

/// Everything one `cargo xtask study` run produced.
#[derive(Debug, Clone, Default)]
pub struct StudyReport {
    /// The command that produced it.
    pub command: String,
    /// Base seed.
    pub base_seed: u64,
    /// FDR summaries.
    pub fdr: Vec<FdrSummary>,
    /// Power cells.
    pub power: Vec<PowerCell>,
    /// Coverage cells (power cells with many datasets at one size, each measured twice).
    pub coverage: Vec<CoverageCell>,
    /// Open-world summaries.
    pub openworld: Vec<OpenWorldSummary>,
    /// Cells of several effects at once.
    pub combined: Vec<CombinedCell>,
    /// Clean machines against the instrument's default base model, which leaves most ordinary
    /// errors out ([`default_base_plan`]).
    pub default_base: Vec<FdrSummary>,
    /// Power cells against the instrument's default base model.
    pub default_base_power: Vec<PowerCell>,
}

fn pct(k: usize, n: usize) -> String {
    if n == 0 {
        return "–".into();
    }
    let p = 100.0 * k as f64 / n as f64;
    if (k > 0 && p < 1.0) || (k < n && p > 99.0) {
        // Some but not all never reads as "0 %" or "100 %".
        format!("{p:.1} %")
    } else {
        format!("{p:.0} %")
    }
}

fn top(names: &[(String, usize)], k: usize) -> String {
    if names.is_empty() {
        return "–".into();
    }
    names
        .iter()
        .take(k)
        .map(|(n, c)| format!("`{n}` ({c})"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The Markdown page `docs/diagnosis-studies.md`.
pub fn render_markdown(r: &StudyReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Diagnosis studies on realistic machines\n\n\
Generated by `{} --out docs/diagnosis-studies.md` (base seed {}). Regenerate with the same \
command (defaults: `--n 200` clean datasets per kind, `--n-power 30` datasets per power and \
open-world cell); the figures depend only on the seed and the engine, not on the number of \
threads. With `--n-power 10` a run takes 50–110 minutes on two cores (the longer with other work on the machine).\n\n\
The datasets come from `xtask::realistic`: every machine carries all its ordinary errors at once, \
each a random smooth function of its axis coordinate (random cubic plus two or three random-phase \
waves of wavelength ½–2 strokes, scaled to a random size), at realistic sizes (positioning 3–20 µm, \
straightness 1–8 µm, angular 2–25 µrad, squareness 5–60 µrad; R-test (`rtest`: a B/C trunnion, \
table–table; `rtest-head`: a B swivel head with a pivot length of 150–350 mm over a C table, \
head–table, whose B location errors EX0B, EZ0B place the B line against the tool it carries; \
`rtest-ac`: an A/C trunnion, A tilting the cradle about X, its pivot drift that of the A line in \
Y, `EY0A`): location errors 5–40 µm and \
10–100 µrad, rotary error motions 1–5 µm / 2–20 µrad periodic over a turn, small linear-axis errors; \
tracker: a three-axis machine measured from 4–6 stations at a grid of 5–7 × 4–5 × 3–4 positions \
or 60–150 scattered ones, the reflector at the tool tip (`tracker`) or, as a volumetric \
calibration does, at 3–4 offsets of 80–200 mm from it at every position (`tracker-tools`: the \
tip, across in X, across in Y, further down the tool); \
3-D points: a C table with X, Y, Z stages, every component error of X, Y, Z, three squareness \
errors, the C line's location errors and C's six error motions, measured from two unknown \
instrument poses with a calibrated target (`points`) or 3–4 targets on a holder turned by up \
to 0.5 mrad, as a volumetric calibration with a tracker in 3-D mode measures (`points-targets`: \
one on the holder's reference, across in X, across in Y, further down the tool, 80–200 mm \
apart), at 12 angles of C and 5 × 4 × 3 positions of X, Y, Z; `rotary`: ISO 230-2 runs of a C rotary table with an autocollimator and a polygon, its angular \
positioning error a zero offset and a random function over a turn (harmonics 1–3 of random \
size and phase) of 2–15″, at 24–48 irregularly spaced angles in 3–5 bidirectional runs), \
and noise whose σ is drawn per dataset (interferometer 0.1–0.6 µm, tracker 0.2–1.0 µm, R-test \
0.2–0.8 µm, 3-D points 0.5–2 µm, rotary table 0.2–1.0″; the manifest, or for R-test the `noise_um` passed to `load_with_noise`, states the true \
σ rounded to 0.1 µm or 0.1″). Machines, strokes, programmes and instrument placement are drawn per dataset \
too. The truth is computed with the generator's own homogeneous transforms, not with \
mte-kinematics or mte-rtest. Each dataset is diagnosed with `DiagnoseParams::default()`. \
Base model written in the manifests (the user's model of a real machine, which has every \
ordinary error): `{{\"components\": {{\"degree\": 3}}, \"squareness\": true, \"location\": true}}` \
for every kind, unless the command says `--base-model omit`; a power cell whose effect the standard \
model would already hold leaves those errors out (`\"except\"`) with the errors an R-test cannot \
tell from them: `EC0Y`, `EC0X`, `EC0B` for a squareness cell, C's angular positioning `ECC` for an \
angular positioning cell, `EA0B`, B's error motion about X `EAB` and `EA0Y`, `EA0Z` for a B tilt \
(`studies::user_model_lacking`). On R-test data that model is nearly degenerate (the linear axes \
move only along the ball's path, so their component errors and the rotary error motions hold \
almost any function of the angles): with the hidden B tilt's or squareness's own errors left out \
it still fits such datasets to the noise, and those cells show what an R-test can tell a user of \
the full model about them: nothing. An R-test finds a B tilt against the location-only model of \
R-test practice (`tests/rtest.rs` in mte-diagnose). On 3-D points and tracker lengths the full \
model is not degenerate that way, but with one target it has no squareness the data could show \
apart from an axis' yaw growing along it (through the target's lever arm) and the instrument's \
pose or the stations (the report lists `EC0X` and `EC0Y` as not separable; the tracker test \
finds a squareness against the stations-only model, `tests/tracker.rs`); with the reflector at \
several offsets from the tool tip, or targets apart on a holder, the yaw shows apart, and the \
`tracker-tools` and `points-targets` power cells are the XY squareness against the full model \
without it. Their truth is the angle between the axes' least-squares reference lines through \
what the measured positions show, as ISO 230-1 defines squareness: the directions of motion, \
the straightness's linear parts and the mean yaw of the carriage the other axis rides on \
(over the whole stroke the lines differ by what the errors do between the positions, which no \
measurement at them shows; the report says so for an axis of fewer than six positions). The \
diagnosis' polynomials are orthogonal at the measured positions, so its squareness is that \
angle; with Legendre's own polynomials, orthogonal over the interval but not at 4–5 positions, \
a wavy straightness's linear part went partly to its cubic and on such grids most estimates \
were several u off. The points' power cell is C's angular \
positioning, against the model without `ECC`, which lacks C's ordinary error motion about Z \
too (harmonics 1–3 of a turn, a few µrad): findings of those harmonics name `ECC` as well.\n",
        r.command, r.base_seed
    );
    if !r.fdr.is_empty() {
        let _ = writeln!(
            s,
            "## False discoveries on clean machines\n\n\
Clean = ordinary errors only (no reversal on axis data). A dataset counts as a false discovery \
when the diagnosis reports any finding; the verdict column counts \"no significant discrepancy\" \
(the rest of the datasets without a finding are reported as unexplained structure). Completions \
of the base's component errors are not findings. *with a reading listed as an outlier*: the \
report lists a reading the final model misses by far more than the rest (the generators write \
none). *wavier ordinary errors*: the same kind with every ordinary error drawn with two to \
five waves of ⅕–2 strokes (instead of two or three of ½–2) and rotary error motions up to the \
5th harmonic of a turn (instead of the 3rd), at the same sizes — smooth errors with more shape \
than the user's cubic; the base's completions must hold them (on densely sampled axes up to \
degree 15, and all their orders at once where no block of three alone is significant; a rotary \
axis' error motions up to the 6th harmonic, all at once where no single next one is). Along an \
ISO 230-2 axis of 15–25 targets a wave of ⅕ stroke is three to five targets long, a shape no \
polynomial the targets can carry holds: it is found as a periodic error of that length, which \
it is, and the report says that these data cannot tell it from a smooth error of that shape \
(fewer than six repeats over the travel) or that its period is one of several aliases. *of \
which every finding qualified*: of the datasets with a finding, those whose report qualifies \
each finding so (no confident name).\n\n\
| kind | datasets | errors | with a finding | of which every finding qualified | verdict \"no significant discrepancy\" | with a reading listed as an outlier | most frequent findings | σ0 (min / 10 % / median / 90 % / max) | held-out RMS ÷ σ, base → diagnosed (median) |\n|---|---|---|---|---|---|---|---|---|---|"
        );
        for f in &r.fdr {
            let (q, h) = f.fit_cells();
            let _ = writeln!(
                s,
                "| {}{} | {} | {} | {} | {} | {} | {} | {} | {q} | {h} |",
                f.kind.name(),
                match f.waviness {
                    Waviness::Gentle => "",
                    Waviness::Wavy => ", wavier ordinary errors",
                },
                f.n,
                f.errors,
                pct(f.with_finding, f.n - f.errors),
                pct(f.all_qualified, f.with_finding),
                pct(f.no_discrepancy, f.n - f.errors),
                pct(f.with_outlier, f.n - f.errors),
                top(&f.names, 5)
            );
        }
        for f in r.fdr.iter().filter(|f| f.first_error.is_some()) {
            let _ = writeln!(
                s,
                "\nFirst error ({}): `{}`",
                f.kind.name(),
                f.first_error
                    .as_deref()
                    .unwrap_or_default()
                    .replace('`', "'")
            );
        }
        s.push('\n');
    }
    if !r.default_base.is_empty() || !r.default_base_power.is_empty() {
        default_base_section(&mut s, r);
    }
    if !r.power.is_empty() {
        let _ = writeln!(
            s,
            "## Power\n\n\
One hidden effect on top of the ordinary errors. *any finding*: the diagnosis reported \
something; *named right*: a finding names the effect (mapping: `xtask::studies::names_effect` — \
periodic → `E<ax><ax> periodic`; squareness → `EC0Y`/`EC0X` …; reversal → `… reversal`; tracker \
scale → `tracker scale`; drift → `… drift` naming the parameter, e.g. `EX0B … drift`, \
`EZ0[tool] … drift`, `EXX scale drift …` for a thermal expansion; angular \
positioning of C (a harmonic, a worm gear) → `ECC …` (not a drift, reversal or scale of it) or a C `periodic`/`harmonic` finding; B tilt → `EA0B …`); *else \
reported as not separable*: no finding names it, but a finding's alternatives the data cannot tell \
apart, or its rivals they hardly tell apart (in its place χ² within 6.63), do, or — for the tracker's length scale, which the user's model with every axis' scale can \
never separate from a common scale of X, Y and Z — the report's list of what is not separable \
names it (that list is the same on clean data: it says what the data cannot show, not that the \
effect was seen); *else period stated out of reach*: neither, and the report's notes say that the \
sampling along the effect's axis cannot show its period (fewer than six positions, or a regular \
step whose aliases hide it: `Diagnosis::periodic_reach`; a tracker dataset on a grid of 5–7 X \
positions cannot show a 5–40 mm pitch, one on scattered targets can); *else stated below \
detection limit*: none of these, and the report's table of what the data could have shown \
(`Diagnosis::detection_limits`: for each cause not found, the size the search would find 80 \
times in 100) gives, for every cause that would name the effect, at the effect's period or a \
first-order drift's time constant (the tested one nearest it), a size above the effect's or says that period is not separable from the model, or the report lists \
such a cause as not separable \
(`xtask::studies::stated_below_limit`) — a miss the report owns up to; *within 2 u*: \
of those named right, |estimate − truth| ≤ 2 u (the `amplitude` estimate or the first; \
magnitudes for periodic amplitudes and squareness, whose sign convention is the engine's; \
for B tilt and squareness the truth is the machine's total, ordinary + hidden, for C's angular \
positioning the amplitude of the machine's total at the hidden harmonic, where its ordinary \
error motion about Z has a component too; for a first-order drift's final value, beyond the \
record, the report states a 95 % interval by profile likelihood over the time constant, and the \
truth must lie in it, as for a periodic error's amplitude where the report states one by the \
profile over the period (flat near the period found: at few irregular targets); a first-order \
drift found as a linear one, whose estimate is a rate, is compared through the report's statement beside it of where a first-order drift of the parameter \
would settle (a 95 % interval of the final value by the same profile, one-sided where the drift \
has not settled within the record), and a linear one found as first-order counts as outside); \
*drift: change over the measured time in its 95 % interval*: \
for a drift, of those named right, the drift's true change from the first reading to the last \
within the stated one's 95 % interval — the finding's *change over the measured time*, whose \
interval the report states by the profile over the time constant, which admits the other form \
of drift (a linear one's, a first-order course of a time constant near the record's; never \
narrower than ± 2 u) — or, where the report says that drift findings of the parameter are one \
drift of neither form, within 2 u of their change together: the drift's size whatever form it \
is found in; *named, form qualified*: of those named right, the \
share whose naming finding the report qualifies — one effect with other findings of a form no \
candidate has (a periodic error that is not a sine, a drift of neither form), a periodic \
error whose period and shape the positions do not determine, or one repeating fewer than six \
times over the travel, which a smooth error of that shape fits as well — right for the open world's \
effects, a caveat too many for a sine or a drift of the candidates' own form; *named alone, \
explained*: of all datasets, those where the effect is named right, no finding names anything \
else, and the verdict is that the causes found explain the data (residuals consistent with the \
noise, no structure left) — what a user should see. Pitch periods \
5–40 mm, pivot drift τ 600–3600 s, C harmonics 1–4, a rotary table's worm gear 24–90 teeth \
(cycles per turn) drawn per dataset; the spindle's thermal growth moves the tool point along \
the spindle (on the head, turned with B), first order with τ 600–3600 s, named by a drift of \
the tool's place `EZ0[tool]`; an axis' thermal expansion is its screw growing about its \
fixed bearing (in half the datasets at the home end, the axis' zero, in the others anywhere \
along the travel), `ppm · (x − x₀) · (1 − e^(−t/τ))` with τ 300–1800 s, named by a drift of its \
scale (`EXX scale drift`, or `EXX scale drift exp about a point` with the zero's change and the \
fixed point; its size the final scale change); a reversal \
growing along X from none at the start of the travel to its size at the end is named by the \
reversal (its truth the mean over the targets) with its change along X (`EXX reversal poly1`); the rotary table's user model has its smooth angular \
positioning error (harmonics up to the second, completed by the diagnosis as the data ask), \
not the worm gear's, nor its reversal (the worm's backlash, named by `ECC reversal`).\n\n\
"
        );
        power_table(&mut s, &r.power);
    }
    if !r.coverage.is_empty() {
        let _ = writeln!(
            s,
            "## Coverage of the stated uncertainties\n\n\
The power study's cells at one size with many datasets: of the datasets where the effect is \
named right, the share whose estimate lies within 2 u of the truth (95 % expected for an honest \
u; with n datasets the binomial standard error is about √(0.05·0.95/n)). The squareness cells \
(a hidden 20 µrad on top of the ordinary XY squareness, against the full model without it) \
compare with the machine's total between the reference lines through the measured positions. \
R-test pivot drift \
(τ drawn from 600 to 3 600 s) and thermal expansion (300–1 800 s): a first-order drift's own \
size is its final value, beyond the data, which the report states with its 95 % interval by \
profile likelihood over the time constant (a slow drift's is longer above than ± 2 u: a longer \
time constant with a larger final value fits almost as well), and *within 2 u* asks that the \
truth lie in it. A first-order form must earn its time constant: it holds only where it leaves \
χ² lower than the linear drift of the parameter by more than 6.63 (χ² 99 %, one degree of \
freedom), so a drift slow against the record is found as a linear one, whose estimate is a \
rate; the report then states beside it where a first-order drift would settle (95 %, by the \
same profile, mostly a bound on one side), and *within 2 u* asks that the truth lie in that. \
The change over the measured time, which the report states for every \
drift, is the size the data determine whatever the form found: read that column. The drifts \
searched settle no faster than a third of the interval between repeated visits of a pose (one \
programme cycle, about 900–1 600 s here): the differences between a pose's consecutive visits, \
from the first pose of a cycle to the last, trace a faster drift's settling too (with the \
interval itself as the shortest time constant, the change's coverage in this cell was 92 %, its \
misses drifts faster than the cycle, found at that floor with their first minutes left out of \
the stated change).\n"
        );
        power_table(&mut s, r.coverage.iter().map(|c| &c.own));
        coverage_draws_table(&mut s, &r.coverage);
    }
    if !r.combined.is_empty() {
        let _ = writeln!(
            s,
            "## Several effects at once\n\n\
Every effect of a cell hidden in each dataset together, on top of the ordinary errors, against \
the user's model of a real machine (no power cell's `except`: none of these effects is in it). A \
second effect of one family sits on the next axis: the tracker's second pitch is Y's, the \
R-test's second pivot drift the C line's (`EX0C`; on the A/C trunnion the lines drift in Y, `EY0A` and `EY0C`), each with its own period or time constant \
and sign. *every effect named*: datasets where a finding names each effect \
(`names_effect`, as in the power table); *effects named*: of all hidden effects; *else \
reported as not separable*: of the effects not named, those a finding's alternatives or rivals name — on \
an R-test the lines of B and C drifting together in X are the tool drifting the other way, and \
the report says which drifts together give the same readings; *else period stated out of reach*: of the effects neither named nor an alternative, those whose \
period the report says the sampling cannot show (a tracker grid of 5–7 positions along the \
axis, as in the power table); *within 2 u*: of the effects \
named, |estimate − truth| ≤ 2 u (a drift's change over the measured time in its stated 95 % \
interval, else as in the power table); *no other finding*: datasets whose every finding names one of the effects; *all named \
alone, explained*: every effect named, no other finding, and the verdict that the causes found \
explain the data.\n\n\
| kind | effects | datasets | errors | every effect named | effects named | else reported as not separable | else period stated out of reach | within 2 u | no other finding | all named alone, explained | most frequent findings |\n|---|---|---|---|---|---|---|---|---|---|---|---|"
        );
        for c in &r.combined {
            let ran = c.n - c.errors;
            let effects = ran * c.effects.len();
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                c.kind.name(),
                c.label(),
                c.n,
                c.errors,
                pct(c.all_named, ran),
                pct(c.effects_named, effects),
                pct(c.effects_as_alternative, effects - c.effects_named),
                pct(
                    c.effects_out_of_reach,
                    effects - c.effects_named - c.effects_as_alternative
                ),
                pct(c.within_2u, c.effects_named),
                pct(c.no_other, ran),
                pct(c.all_alone_explained, ran),
                top(&c.names, 4)
            );
        }
        s.push('\n');
    }
    if !r.openworld.is_empty() {
        let _ = writeln!(
            s,
            "## Open world\n\n\
Effects no candidate has exactly (sawtooth positioning error, a drift that rises and falls, \
a Y positioning error that grows from mid-Y at a rate changing along X, which no rigid-body \
error of the axes has). By the diagnosis' verdict: *nothing*: \"no significant \
discrepancy\" (the effect is missed); *unexplained*: structure is reported that nothing in the \
library explains, with or without the nearest candidates named beside it — the right answer; \
*shape stated*: causes named, and the report says that some of them are one effect of a form \
no candidate has (the harmonics of a periodic error that is not a sine; a drift of one \
parameter that is neither linear nor first-order) — also a right answer; *confident wrong \
cause*: causes named, the residuals declared consistent with the noise, and no such \
statement. *of which period stated out of reach*: of the datasets with nothing found, those whose \
report says that the sampling cannot show the effect's period (as in the power table).\n\n\
| kind | effect | size | datasets | errors | nothing | of which period stated out of reach | unexplained | shape stated | confident wrong cause | most frequent findings |\n|---|---|---|---|---|---|---|---|---|---|---|"
        );
        for o in &r.openworld {
            let ran = o.n - o.errors;
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                cell_columns(o.kind, o.effect, o.size),
                o.n,
                o.errors,
                pct(o.nothing, ran),
                pct(o.nothing_out_of_reach, o.nothing),
                pct(o.unexplained, ran),
                pct(o.shape_stated, ran),
                pct(o.confident_wrong, ran),
                top(&o.names, 3)
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use mte_diagnose::Interval;

    fn drift(unit: &'static str, value: f64) -> TrueEffect {
        TrueEffect {
            iso_name_hint: "EXX".into(),
            kind: EffectKind::Drift,
            size: 10.0,
            unit,
            value,
            signed: true,
            detail: String::new(),
            period: None,
            drift: None,
        }
    }

    fn found(estimate: &str, value: f64, first_order_final: Option<Interval>) -> FoundEffect {
        FoundEffect {
            name: "EXX scale drift".into(),
            estimates: vec![(estimate.into(), value, 1e-7, None)],
            alternatives: Vec::new(),
            period: None,
            first_order_final,
            ordinary: false,
        }
    }

    #[test]
    fn correlation_of_pairs() {
        // Means 2.5 and 2.5; products of the deviations 0.75 each; sums of squares 5 and 5.
        let pairs = [[1.0, 2.0], [2.0, 1.0], [3.0, 4.0], [4.0, 3.0]];
        approx::assert_relative_eq!(correlation(&pairs), 0.6, epsilon = 1e-12);
        let line: Vec<[f64; 2]> = (0..5).map(|i| [i as f64, 1.0 - 2.0 * i as f64]).collect();
        approx::assert_relative_eq!(correlation(&line), -1.0, epsilon = 1e-12);
        assert!(correlation(&[[1.0, 2.0]]).is_nan());
    }

    #[test]
    fn a_first_order_drift_found_linear_is_judged_by_where_the_report_says_it_would_settle() {
        // A 10 ppm final scale change found as a linear drift (its estimate a rate).
        let truth = drift("ppm", 10e-6);
        let bound = |lower, upper| Some(Interval { lower, upper });
        // At least 6 ppm: the truth lies in the one-sided interval.
        assert!(estimate_matches(
            &truth,
            &found("EXX scale rate", 3e-9, bound(Some(6e-6), None)),
            2.0
        ));
        // At most 8 ppm: it does not.
        assert!(!estimate_matches(
            &truth,
            &found("EXX scale rate", 3e-9, bound(Some(2e-6), Some(8e-6))),
            2.0
        ));
        // Without that statement a rate is no final value.
        assert!(!estimate_matches(
            &truth,
            &found("EXX scale rate", 3e-9, None),
            2.0
        ));
        // A linear drift's rate is never compared with a first-order finding's final value.
        let linear = drift("um/min", 0.1 / 60e3);
        assert!(!estimate_matches(
            &linear,
            &found("EXX change", 1.7e-6, None),
            2.0
        ));
        assert!(estimate_matches(
            &linear,
            &found("EXX rate", 0.1 / 60e3, None),
            2.0
        ));
    }
}
