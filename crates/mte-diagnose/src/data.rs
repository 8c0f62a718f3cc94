//! What the diagnosis works on: scalar observations with their covariates.

use crate::term::Quantity;
use mte_linalg::DVec;
use serde::Serialize;

use crate::{DiagnoseError, Result};

/// What a covariate is, which decides the structure tests and effects that apply to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub enum VariableKind {
    /// Commanded position of a linear axis (mm).
    LinearAxis,
    /// Commanded angle of a rotary axis (rad; reported in degrees).
    RotaryAxis,
    /// Time since the start of the measurement (s).
    Time,
    /// Direction of motion when the point was approached: +1 or −1.
    Direction,
}

/// One named covariate: a value per observation.
#[derive(Debug, Clone, Serialize)]
pub struct Variable {
    /// Name as users read it: the axis name (`X`, `B`), `t` or `direction`.
    pub name: String,
    /// What it is.
    pub kind: VariableKind,
    /// One value per observation, in mm, rad, s or ±1.
    pub values: Vec<f64>,
}

/// Scalar observations of one dataset, linearised around the nominal machine: `values` is what
/// the error model has to explain (measured minus nominal), with the covariates that structure
/// tests and candidate effects use.
#[derive(Debug, Clone)]
pub struct Observations {
    /// Measured minus nominal, one entry per scalar observation, in mm.
    pub values: DVec,
    /// Stated standard uncertainty of each observation (mm), from the instrument; `None` when
    /// the dataset states none (σ is then estimated from the residuals).
    pub sigma: Option<DVec>,
    /// Covariates: axis positions, time, direction.
    pub variables: Vec<Variable>,
    /// Setup index of each observation (ball position, tracker station, run …).
    pub setup: Vec<usize>,
    /// Names of the setups.
    pub setup_names: Vec<String>,
    /// Channel index of each observation (`dx`, `dy`, `dz`, `length` …).
    pub channel: Vec<usize>,
    /// Names of the channels.
    pub channel_names: Vec<String>,
    /// What kind of setup the dataset has, for reports ("ball position", "tracker station").
    pub setup_kind: String,
    /// What the observations are: lengths in mm ([`Quantity::Length`]) or angles in rad
    /// ([`Quantity::Angle`], e.g. a rotary axis' positioning deviations); sets the report's units.
    pub quantity: Quantity,
}

impl Observations {
    /// Number of scalar observations.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// `true` when there are no observations.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The observations `rows` only, in that order (setups and channels keep their names).
    pub fn select(&self, rows: &[usize]) -> Observations {
        let pick = |v: &DVec| DVec::from_iterator(rows.len(), rows.iter().map(|&i| v[i]));
        Observations {
            values: pick(&self.values),
            sigma: self.sigma.as_ref().map(pick),
            variables: self
                .variables
                .iter()
                .map(|v| Variable {
                    name: v.name.clone(),
                    kind: v.kind,
                    values: rows.iter().map(|&i| v.values[i]).collect(),
                })
                .collect(),
            setup: rows.iter().map(|&i| self.setup[i]).collect(),
            channel: rows.iter().map(|&i| self.channel[i]).collect(),
            ..self.clone_labels()
        }
    }

    fn clone_labels(&self) -> Observations {
        Observations {
            values: DVec::zeros(0),
            sigma: None,
            variables: Vec::new(),
            setup: Vec::new(),
            setup_names: self.setup_names.clone(),
            channel: Vec::new(),
            channel_names: self.channel_names.clone(),
            setup_kind: self.setup_kind.clone(),
            quantity: self.quantity,
        }
    }

    /// The covariate called `name`.
    pub fn variable(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }

    /// The covariate of the given kind (the first one).
    pub fn variable_of_kind(&self, kind: VariableKind) -> Option<&Variable> {
        self.variables.iter().find(|v| v.kind == kind)
    }

    /// Checks lengths, finiteness and positivity of σ.
    ///
    /// # Errors
    /// [`DiagnoseError::InvalidData`] naming the offending field and observation.
    pub fn validate(&self) -> Result<()> {
        let n = self.len();
        let bad = |field: &str, detail: String| DiagnoseError::InvalidData {
            field: field.to_string(),
            detail,
        };
        if let Some(i) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(bad(
                "values",
                format!("observation {i} is {}", self.values[i]),
            ));
        }
        if let Some(sigma) = &self.sigma {
            if sigma.len() != n {
                return Err(bad(
                    "sigma",
                    format!("{} entries for {n} observations", sigma.len()),
                ));
            }
            if let Some(i) = sigma.iter().position(|s| !(s.is_finite() && *s > 0.0)) {
                return Err(bad(
                    "sigma",
                    format!("observation {i}: {} is not a positive length", sigma[i]),
                ));
            }
        }
        for v in &self.variables {
            if v.values.len() != n {
                return Err(bad(
                    &v.name,
                    format!("{} values for {n} observations", v.values.len()),
                ));
            }
            if let Some(i) = v.values.iter().position(|x| !x.is_finite()) {
                return Err(bad(&v.name, format!("observation {i} is {}", v.values[i])));
            }
        }
        if self.setup.len() != n || self.setup.iter().any(|&s| s >= self.setup_names.len()) {
            return Err(bad(
                "setup",
                "one setup index per observation, below the number of setups".into(),
            ));
        }
        if self.channel.len() != n || self.channel.iter().any(|&c| c >= self.channel_names.len()) {
            return Err(bad(
                "channel",
                "one channel index per observation, below the number of channels".into(),
            ));
        }
        Ok(())
    }

    /// The typical interval between two visits of the same pose (same channel, commanded axes
    /// and direction, in any setup): the median over consecutive repeat visits, in s. `None`
    /// without a time column, or when no pose is measured twice — time-dependent effects are then
    /// indistinguishable from pose-dependent ones.
    pub fn revisit_interval(&self) -> Option<f64> {
        let t = self.variable_of_kind(VariableKind::Time)?;
        let pose = self.poses();
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.sort_by(|&a, &b| {
            pose[a]
                .cmp(&pose[b])
                .then(t.values[a].total_cmp(&t.values[b]))
        });
        let mut gaps: Vec<f64> = order
            .windows(2)
            .filter(|w| pose[w[0]] == pose[w[1]])
            .map(|w| t.values[w[1]] - t.values[w[0]])
            .filter(|g| *g > 0.0)
            .collect();
        if gaps.is_empty() {
            return None;
        }
        gaps.sort_by(f64::total_cmp);
        Some(gaps[gaps.len() / 2])
    }

    /// The pose of each observation, as an index: observations of the same channel at the same
    /// values of every variable but time (commanded axes, direction; compared to a nanometre /
    /// microradian, as commanded values repeat exactly) share it, whatever their set-up.
    pub(crate) fn poses(&self) -> Vec<usize> {
        let pose: Vec<&Variable> = self
            .variables
            .iter()
            .filter(|v| v.kind != VariableKind::Time)
            .collect();
        let mut index: std::collections::HashMap<Vec<i64>, usize> = Default::default();
        (0..self.len())
            .map(|i| {
                let mut k = vec![self.channel[i] as i64];
                k.extend(pose.iter().map(|v| (v.values[i] * 1e6).round() as i64));
                let next = index.len();
                *index.entry(k).or_insert(next)
            })
            .collect()
    }

    /// The order in which observations were taken: by time when the data have a time column,
    /// else by row. Cross-validation folds are contiguous blocks of this order.
    pub(crate) fn acquisition_order(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.len()).collect();
        if let Some(t) = self.variable_of_kind(VariableKind::Time) {
            order.sort_by(|&a, &b| {
                (self.setup[a], t.values[a])
                    .partial_cmp(&(self.setup[b], t.values[b]))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
        } else {
            order.sort_by_key(|&i| (self.setup[i], i));
        }
        order
    }
}
