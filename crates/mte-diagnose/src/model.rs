//! The observation model: the one trait an instrument implements ([`ObservationModel`]), and
//! [`prepare`], which turns any observation model into a base model and a candidate library.
//! The engine ([`crate::diagnose`]) sees only the result; it knows no instrument.

use crate::candidate::{BaseModelSpec, Candidate, SlotEffect, SlotRole, physical_effects};
use crate::data::Observations;
use crate::term::Term;
use crate::{DiagnoseError, Result};

/// An instrument's view of a machine, linearised at the nominal machine: what was measured,
/// and the Jacobian of the measurements with respect to every error the machine can have and
/// every parameter of the instrument's own set-up.
///
/// Implement it to diagnose data of an instrument of your own, then call [`prepare`]:
///
/// ```
/// use mte_diagnose::{
///     DiagnoseParams, Effects, Family, ObservationModel, Observations, Quantity, SlotEffect,
///     SlotRole, Term, Variable, VariableKind, prepare,
/// };
/// use mte_linalg::DVec;
///
/// /// A dial gauge against a straight edge along X: readings are the straightness EYX plus
/// /// the gauge's zero.
/// struct DialGauge {
///     obs: Observations,
/// }
///
/// impl ObservationModel for DialGauge {
///     fn observations(&self) -> &Observations {
///         &self.obs
///     }
///     fn effects(&self) -> Effects {
///         let n = self.obs.len();
///         let ones = DVec::from_element(n, 1.0);
///         Effects {
///             errors: vec![SlotEffect {
///                 name: "EYX".into(),
///                 label: "straightness in y of the X axis".into(),
///                 meaning: "the X carriage moves off its line in y".into(),
///                 quantity: Quantity::Length,
///                 role: SlotRole::Component { axis: "X".into(), positioning: false, straightness: true },
///                 column: ones.clone(),
///                 separated_by: None,
///                 reference: None,
///             }],
///             instrument: vec![Term::single("gauge zero", "dial gauge zero", "reading at rest", Family::Base, ones, Quantity::Length)],
///             ..Effects::default()
///         }
///     }
/// }
///
/// let x: Vec<f64> = (0..60).map(|i| 10.0 * i as f64).collect();
/// // 2 µm of sag (parabola) plus a little noise-like ripple, in mm
/// let y = DVec::from_fn(60, |i, _| {
///     let s = x[i] / 600.0;
///     2e-3 * 4.0 * s * (1.0 - s) + 1e-4 * ((i * 7919) % 13) as f64 / 13.0
/// });
/// let obs = Observations {
///     values: y,
///     sigma: None,
///     variables: vec![Variable { name: "X".into(), kind: VariableKind::LinearAxis, values: x }],
///     setup: vec![0; 60],
///     setup_names: vec!["run".into()],
///     channel: vec![0; 60],
///     channel_names: vec!["y".into()],
///     setup_kind: "run".into(),
///     quantity: Quantity::Length,
/// };
/// let base_model = serde_json::json!({ "components": { "degree": 2 } });
/// let prepared = prepare(&DialGauge { obs }, Some(&base_model), "gauge readings").unwrap();
/// assert!(prepared.base.iter().any(|t| t.name == "EYX poly2"));
/// let d = prepared.diagnose(&DiagnoseParams::default()).unwrap();
/// assert!(d.base.sigma0.is_finite());
/// ```
pub trait ObservationModel {
    /// The measured values (residuals from the nominal prediction, mm or rad), their stated
    /// noise and the variables that can expose an effect (axis positions, direction of
    /// approach, time), one value per observation.
    fn observations(&self) -> &Observations;

    /// The first-order change of every observation per unit of each machine error the
    /// instrument can see, named the ISO way, and of each of its own set-up parameters.
    fn effects(&self) -> Effects;

    /// A title for reports.
    fn title(&self) -> String {
        "measurements".into()
    }
}

/// The Jacobian of an instrument's observations, named ([`ObservationModel::effects`]).
#[derive(Default)]
pub struct Effects {
    /// Machine errors the instrument can see: component, location and squareness errors (ISO
    /// 230-1 names). The base model picks its terms from these; the rest are candidates.
    pub errors: Vec<SlotEffect>,
    /// The instrument's own parameters, always fitted: sensor zeros, station positions, the
    /// instrument's pose.
    pub instrument: Vec<Term>,
    /// Further candidate causes that are not machine errors of the list above (set-up offsets
    /// the instrument cannot tell, a scale drift).
    pub candidates: Vec<Box<dyn Candidate>>,
    /// The location errors that `"location": true` of a base model stands for (those the
    /// instrument's set-ups can separate).
    pub location: Vec<String>,
    /// The base model when the dataset states none.
    pub default_base: BaseModelSpec,
    /// Which base terms may drift in time.
    pub drift: DriftOf,
}

/// Which terms of the base model are candidates for a thermal drift.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum DriftOf {
    /// None.
    #[default]
    Nothing,
    /// The instrument's own parameters (a zero that drifts).
    Instrument,
    /// Every base term (an R-test's pivots move as the machine warms).
    WholeBase,
}

/// A dataset ready to diagnose.
pub struct Prepared {
    /// The observations.
    pub observations: Observations,
    /// The base model.
    pub base: Vec<Term>,
    /// The candidate library.
    pub candidates: Vec<Box<dyn Candidate>>,
    /// A title for reports.
    pub title: String,
    /// The base model in the user's terms, for the report.
    pub base_model: BaseModelUsed,
}

/// The base model a diagnosis started from, as the user states it (or the instrument's default
/// where the dataset states none); in [`crate::Diagnosis::base_model`] and the report.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BaseModelUsed {
    /// `true` when the dataset stated it, `false` for the instrument's default.
    pub stated: bool,
    /// The spec.
    pub spec: BaseModelSpec,
    /// The spec in words ([`BaseModelSpec::describe`]).
    pub description: String,
    /// The base's terms that are the instrument's own parameters (sensor zeros, stations, the
    /// instrument's pose), always fitted.
    pub instrument_terms: Vec<String>,
}

impl Prepared {
    /// Diagnoses the dataset with `params` ([`crate::diagnose`] on its observations, base model
    /// and candidates).
    ///
    /// # Errors
    /// As [`crate::diagnose`].
    pub fn diagnose(self, params: &crate::DiagnoseParams) -> Result<crate::Diagnosis> {
        self.diagnose_with_progress(params, &crate::NoProgress)
    }

    /// [`Prepared::diagnose`], reporting to `progress` ([`crate::diagnose_with_progress`]; its
    /// units in all: [`crate::progress_units`]).
    ///
    /// # Errors
    /// As [`crate::diagnose`].
    pub fn diagnose_with_progress(
        self,
        params: &crate::DiagnoseParams,
        progress: &dyn crate::Progress,
    ) -> Result<crate::Diagnosis> {
        let mut d = crate::diagnose_with_progress(
            &self.observations,
            self.base,
            &self.candidates,
            params,
            progress,
        )?;
        if let Some(note) = ordinary_errors_note(&self.observations, &self.base_model.spec, &d) {
            d.notes.push(note);
        }
        d.base_model = Some(self.base_model);
        Ok(d)
    }
}

/// A note for findings that are ordinary errors every machine has — component errors,
/// squareness, location errors — of a kind the base model `spec` leaves out
/// ([`BaseModelSpec::would_hold`]): the base that holds them, for the search to look past them.
fn ordinary_errors_note(
    obs: &Observations,
    spec: &BaseModelSpec,
    d: &crate::Diagnosis,
) -> Option<String> {
    let mut names = Vec::new();
    let mut fuller = spec.clone();
    for f in &d.findings {
        if let Some(shorthand) = spec.would_hold(
            &f.family,
            &f.name,
            crate::candidate::per_turn(obs, &f.family, f.exposed_by.as_deref()),
        ) {
            fuller = fuller.with(shorthand);
            names.push(f.name.as_str());
        }
    }
    if names.is_empty() {
        return None;
    }
    let shorthand = serde_json::to_string(&fuller).unwrap_or_default();
    let which = if names.len() == d.findings.len() {
        format!(
            "the cause{} found ({}) {}",
            if names.len() == 1 { "" } else { "s" },
            names.join(", "),
            if names.len() == 1 {
                "is an ordinary error"
            } else {
                "are ordinary errors"
            }
        )
    } else {
        format!(
            "{} of the {} causes found ({}) are ordinary errors",
            names.len(),
            d.findings.len(),
            names.join(", ")
        )
    };
    Some(format!(
        "{which} of the machine's axes, which every machine has and the base model leaves out: a base model that holds {them} (`\"base_model\": {shorthand}` in the dataset's manifest) takes {them} in, and the search then looks past {them} for what that model gets wrong",
        them = if names.len() == 1 { "it" } else { "them" }
    ))
}

/// The base model and the candidate library of an observation model: the instrument's own
/// parameters plus the terms of `base_model` (a [`BaseModelSpec`] in JSON; the model's
/// default without one) form the base; the physical effects of every machine error not in
/// the base, the model's further candidates and the completions of the base's component
/// errors form the library. `source` names the data in messages.
///
/// # Errors
/// [`DiagnoseError::Dataset`] for a malformed `base_model` (naming `source`), or
/// [`DiagnoseError::InvalidData`] for observations that fail [`Observations::validate`].
pub fn prepare(
    model: &dyn ObservationModel,
    base_model: Option<&serde_json::Value>,
    source: &str,
) -> Result<Prepared> {
    let observations = model.observations().clone();
    observations.validate()?;
    let effects = model.effects();
    let field_error = |detail: String| DiagnoseError::Dataset {
        path: source.to_string(),
        detail: format!("field `base_model`: {detail}"),
    };
    let spec = match base_model {
        Some(v) => BaseModelSpec::from_json(v).map_err(field_error)?,
        None => effects.default_base.clone(),
    };
    let base_model = BaseModelUsed {
        stated: base_model.is_some(),
        description: spec.describe(&observations, &effects.location),
        spec: spec.clone(),
        instrument_terms: effects.instrument.iter().map(|t| t.name.clone()).collect(),
    };
    let named = if spec.terms.is_empty() {
        Vec::new()
    } else {
        physical_effects(&observations, &effects.errors, &[])
    };
    let mut base = effects.instrument;
    let n_instrument = base.len();
    // (Independent: built together.)
    let (terms, completions) = rayon::join(
        || spec.terms(&observations, &effects.errors, &effects.location, &named),
        || spec.completions(&observations, &effects.errors),
    );
    base.extend(terms.map_err(field_error)?);
    let drifting: Vec<&Term> = match effects.drift {
        DriftOf::Nothing => Vec::new(),
        DriftOf::Instrument => base[..n_instrument].iter().collect(),
        DriftOf::WholeBase => base.iter().collect(),
    };
    // A base error drifts from its value at the instrument's reference pose, where it was zeroed.
    let references: Vec<Option<crate::candidate::Reference>> = drifting
        .iter()
        .map(|t| {
            effects
                .errors
                .iter()
                .find(|e| e.name == t.name)
                .and_then(|e| e.reference.clone())
        })
        .collect();
    let drifting: Vec<_> = drifting
        .into_iter()
        .zip(references.iter().map(Option::as_ref))
        .collect();
    // A constant in the base is no candidate; its drift is (as one of the base's).
    let errors: Vec<SlotEffect> = effects
        .errors
        .into_iter()
        .filter(|e| {
            !(matches!(e.role, SlotRole::Constant { .. }) && base.iter().any(|b| b.name == e.name))
        })
        .collect();
    let mut candidates = physical_effects(&observations, &errors, &drifting);
    candidates.extend(effects.candidates);
    candidates.extend(completions);
    candidates.extend(spec.cause_completions(&observations, &errors));
    candidates.extend(crate::candidate::interaction_probes(&observations, &errors));
    Ok(Prepared {
        observations,
        base,
        candidates,
        title: model.title(),
        base_model,
    })
}
