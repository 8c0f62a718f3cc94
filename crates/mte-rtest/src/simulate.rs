//! Simulation of R-test measurements with the exact kinematics, sensor noise and setup offsets.

use crate::error::{Result, RtestError};
use crate::kin;
use crate::model::{Dataset, ErrorField, ObservationModel, Reading, Setup, SetupNuisance};
use crate::program::{Program, command_linear_axes, command_program};
use mte_kinematics::Machine;
use mte_linalg::Vec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

/// Where the ball is and how it is centred.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetupSpec {
    /// Setup identifier.
    pub id: String,
    /// Nominal ball centre, table coordinates, mm.
    pub ball_mm: Vec3,
    /// Nominal nest centre, tool coordinates, mm.
    pub nest_mm: Vec3,
    /// Rotary angles at the centring (others 0), degrees.
    pub centring_deg: Vec<(String, f64)>,
}

impl SetupSpec {
    /// A setup with the nest at the tool point, centred with all rotary axes at 0.
    pub fn new(id: &str, ball_mm: Vec3) -> SetupSpec {
        SetupSpec {
            id: id.into(),
            ball_mm,
            nest_mm: Vec3::zeros(),
            centring_deg: vec![],
        }
    }
    /// The same setup centred with `axis` at `deg`.
    pub fn centred_at(mut self, axis: &str, deg: f64) -> SetupSpec {
        self.centring_deg.retain(|(a, _)| a != axis);
        self.centring_deg.push((axis.into(), deg));
        self
    }
}

/// One setup and the programs run in it, in order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanItem {
    /// The setup.
    pub setup: SetupSpec,
    /// Programs run after its centring.
    pub programs: Vec<Program>,
}

/// Simulation knobs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimOptions {
    /// Standard deviation of the sensor noise per component, mm.
    pub noise_sd_mm: f64,
    /// Standard deviation of the random sensor zero offset per setup and component, mm.
    pub sensor_zero_sd_mm: f64,
    /// Explicit nuisance values per setup (overrides the random sensor zero when given).
    pub nuisance: Option<Vec<SetupNuisance>>,
    /// The controller's slot values (its kinematic description; empty = nominal). Compensation
    /// puts the identified location values here.
    pub controller_errors: Vec<f64>,
    /// Start time, s.
    pub start_t_s: f64,
    /// Pause between programs and before each setup's first program, s.
    pub gap_s: f64,
    /// Seed of the ChaCha8 stream for noise and offsets.
    pub seed: u64,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            noise_sd_mm: 0.0005,
            sensor_zero_sd_mm: 0.0,
            nuisance: None,
            controller_errors: vec![],
            start_t_s: 0.0,
            gap_s: 2.0,
            seed: 1,
        }
    }
}

/// What a simulation returns: the dataset and the nuisance values it used (the truth).
#[derive(Debug, Clone, PartialEq)]
pub struct Simulated {
    /// The simulated measurement.
    pub dataset: Dataset,
    /// The nuisance values per setup.
    pub nuisance: Vec<SetupNuisance>,
}

/// Builds the commanded rows of a plan (readings zero) — the data skeleton a controller produces.
///
/// # Errors
/// Program, stroke and inverse-kinematics errors; [`RtestError::Invalid`] for an empty plan.
pub fn command_plan(m: &Machine, plan: &[PlanItem], opts: &SimOptions) -> Result<Dataset> {
    if plan.is_empty() {
        return Err(RtestError::Invalid {
            field: "plan".into(),
            message: "no setup".into(),
        });
    }
    let axes = kin::axes(m);
    let mut setups = Vec::new();
    let mut readings = Vec::new();
    let mut t = opts.start_t_s;
    for (si, item) in plan.iter().enumerate() {
        let s = &item.setup;
        let mut q = vec![0.0; axes.len()];
        for (a, v) in &s.centring_deg {
            let i = axes
                .iter()
                .position(|x| &x.name == a && x.rotary)
                .ok_or_else(|| {
                    kin::unknown_axis(
                        m,
                        a,
                        &format!("setup `{}`.centring_deg: not a rotary axis", s.id),
                    )
                })?;
            q[i] = v.to_radians();
        }
        command_linear_axes(m, &opts.controller_errors, &s.ball_mm, &s.nest_mm, &mut q)?;
        setups.push(Setup {
            id: s.id.clone(),
            ball_mm: s.ball_mm,
            nest_mm: s.nest_mm,
            centring_q: q,
            centring_t_s: t,
        });
        for p in &item.programs {
            t += opts.gap_s;
            let samples = command_program(m, p, &opts.controller_errors, &s.ball_mm, &s.nest_mm)?;
            let mut last = 0.0;
            for smp in samples {
                readings.push(Reading {
                    setup: si,
                    test: p.name.clone(),
                    t_s: t + smp.t_s,
                    q: smp.q,
                    d_mm: Vec3::zeros(),
                });
                last = smp.t_s;
            }
            t += last;
        }
    }
    Ok(Dataset {
        machine: m.name().to_string(),
        axis_names: kin::axis_names(m),
        setups,
        readings,
        note: String::new(),
    })
}

/// Simulates a plan on a machine whose true slot errors are `truth` (any function of q and t).
///
/// # Errors
/// As [`command_plan`]; [`RtestError::Invalid`] for a negative noise level or a nuisance list of
/// the wrong length.
pub fn simulate<E: ErrorField + ?Sized>(
    m: &Machine,
    plan: &[PlanItem],
    truth: &E,
    opts: &SimOptions,
) -> Result<Simulated> {
    if !(opts.noise_sd_mm >= 0.0 && opts.sensor_zero_sd_mm >= 0.0) {
        return Err(RtestError::Invalid {
            field: "noise_sd_mm/sensor_zero_sd_mm".into(),
            message: "must be ≥ 0".into(),
        });
    }
    let mut ds = command_plan(m, plan, opts)?;
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let nuisance = match &opts.nuisance {
        Some(n) => {
            if n.len() != ds.setups.len() {
                return Err(RtestError::Invalid {
                    field: "nuisance".into(),
                    message: format!("{} values for {} setups", n.len(), ds.setups.len()),
                });
            }
            n.clone()
        }
        None => {
            let nd = Normal::new(0.0, opts.sensor_zero_sd_mm.max(1e-300)).map_err(|e| {
                RtestError::Invalid {
                    field: "sensor_zero_sd_mm".into(),
                    message: e.to_string(),
                }
            })?;
            (0..ds.setups.len())
                .map(|_| SetupNuisance {
                    sensor_zero_mm: if opts.sensor_zero_sd_mm > 0.0 {
                        Vec3::from_fn(|_, _| nd.sample(&mut rng))
                    } else {
                        Vec3::zeros()
                    },
                    ..Default::default()
                })
                .collect()
        }
    };
    let pred = ObservationModel::new(m, &ds)?.predict(truth, &nuisance)?;
    let noise =
        Normal::new(0.0, opts.noise_sd_mm.max(1e-300)).map_err(|e| RtestError::Invalid {
            field: "noise_sd_mm".into(),
            message: e.to_string(),
        })?;
    for (r, p) in ds.readings.iter_mut().zip(pred) {
        r.d_mm = if opts.noise_sd_mm > 0.0 {
            p + Vec3::from_fn(|_, _| noise.sample(&mut rng))
        } else {
            p
        };
    }
    ds.note = format!(
        "simulated with the exact kinematics; sensor noise sd {} µm per component; seed {}",
        opts.noise_sd_mm * 1e3,
        opts.seed
    );
    Ok(Simulated {
        dataset: ds,
        nuisance,
    })
}
