//! What a run is asked to compute, free of the scene: a [`Plan`] of
//! span-free specs ([`ssm_core::spec`]) that code builds directly (a
//! binding, a study, a test) or [`resolve`]s from a scene, and every check
//! of a plan against its model and every work and memory estimate
//! ([`budget`]), before anything is allocated.
//!
//! This is the only layer that sees both the scene and the numerics: the
//! pipeline below runs a plan and reads no scene type. A plan's errors
//! ([`PlanError`]) name keys as a scene spells them; [`resolve`] turns them
//! into scene errors at the key's file and line.

mod analyses;
pub mod budget;
mod checks;
mod convert;
mod error;

pub use analyses::{needs, PlannedAnalysis};
pub(crate) use checks::{named_outputs, pod_outputs};
pub use error::PlanError;

use serde::{Deserialize, Serialize};

use crate::scene::{SceneError, SceneFile};
use budget::Limits;
use ssm_core::model::system::System;
use ssm_core::spec::{
    BackboneSpec, FrcSpec, InvarianceSpec, PodSpec, ReferenceSpec, ReferenceStart, ReportSpec,
    SimulateSpec, SpecError, SpectrumSpec, SsmSpec, TransientSpec, ValidationSpec,
};

/// Everything a run computes, as specs: the SSM and its spectrum, the
/// answers read off the reduced model, the full-system comparisons, the
/// sampled runs, the POD study and the analyses of
/// [`crate::analyses::REGISTRY`]. Serializes to and from JSON (a field left
/// out takes its documented default; unknown fields are refused).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// The SSM (`[ssm]`).
    #[serde(default)]
    pub ssm: SsmSpec,
    /// The eigensolver (`[spectrum]`).
    #[serde(default)]
    pub spectrum: SpectrumSpec,
    /// The model's outputs the answers report (`[outputs] coordinates`).
    #[serde(default)]
    pub coordinates: Vec<String>,
    /// `[outputs.invariance_error]`.
    #[serde(default)]
    pub invariance: Option<InvarianceSpec>,
    /// `[outputs.backbone]`.
    #[serde(default)]
    pub backbone: Option<BackboneSpec>,
    /// `[outputs.transient]`.
    #[serde(default)]
    pub transient: Option<TransientSpec>,
    /// `[forcing]`.
    #[serde(default)]
    pub frc: Option<FrcSpec>,
    /// `[validate]`.
    #[serde(default)]
    pub validation: Option<ValidationSpec>,
    /// `[reference]`.
    #[serde(default)]
    pub reference: Option<ReferenceSpec>,
    /// `[report]`.
    #[serde(default)]
    pub report: Option<ReportSpec>,
    /// `[simulate]`.
    #[serde(default)]
    pub simulate: Option<SimulateSpec>,
    /// `[pod]`.
    #[serde(default)]
    pub pod: Option<PodSpec>,
    /// `[analysis.<name>]`: the analyses of [`crate::analyses::REGISTRY`].
    #[serde(default)]
    pub analyses: Vec<PlannedAnalysis>,
}

impl Plan {
    /// Whether the plan asks for an SSM answer: any plan without a POD
    /// study, and one with a POD study and any other request (the SSM
    /// models of the study's `ssm_pairs` are the study's own).
    pub(crate) fn wants_ssm(&self) -> bool {
        self.pod.is_none()
            || self.invariance.is_some()
            || self.backbone.is_some()
            || self.transient.is_some()
            || self.frc.is_some()
            || self.validation.is_some()
            || self.report.is_some()
            || self.simulate.is_some()
            || self.reference.is_some()
            || !self.analyses.is_empty()
    }

    /// Every analysis of [`crate::analyses::REGISTRY`] the plan asks for,
    /// its spec as JSON: the answers older than the registry that a field
    /// of their own asks for (`backbone`, `invariance`, `transient`, `frc`,
    /// `validation`, `reference`, `report`, `simulate`), then `analyses`. The analyses of each
    /// phase run in this order (an analysis reads the results of those
    /// before it), and the run's estimates, measured errors and warnings
    /// follow it.
    pub fn requested(&self) -> Vec<PlannedAnalysis> {
        use crate::analyses::backbone::Backbone;
        use crate::analyses::{frc::Frc, invariance::Invariance, simulate::Simulate};
        use crate::analyses::{reference::Reference, transient::Transient, Analysis};
        use crate::analyses::{report::SpeedReport, validation::Validate};
        fn own<S: serde::Serialize>(name: &str, spec: Option<&S>) -> Option<PlannedAnalysis> {
            spec.map(|s| PlannedAnalysis {
                name: name.to_owned(),
                // plain data: serializing cannot fail
                spec: serde_json::to_value(s).unwrap_or(serde_json::Value::Null),
            })
        }
        [
            own(Backbone::NAME, self.backbone.as_ref()),
            own(Invariance::NAME, self.invariance.as_ref()),
            own(Transient::NAME, self.transient.as_ref()),
            own(Frc::NAME, self.frc.as_ref()),
            own(Validate::NAME, self.validation.as_ref()),
            own(Reference::NAME, self.resolved_reference().as_ref()),
            own(SpeedReport::NAME, self.resolved_report().as_ref()),
            own(Simulate::NAME, self.simulate.as_ref()),
        ]
        .into_iter()
        .flatten()
        .chain(self.analyses.iter().cloned())
        .collect()
    }

    /// `[reference]` with what it takes from the forced response resolved:
    /// its frequency range (the forced response's when it gives none) and
    /// where its branches start (also from the forced response's branches
    /// when the plan has one and the spec does not say).
    fn resolved_reference(&self) -> Option<ReferenceSpec> {
        self.reference.as_ref().map(|r| {
            let forcing = self.frc.as_ref().map(|f| f.omega_range);
            ReferenceSpec {
                omega_range: r.omega_range(forcing).map(|(a, b)| [a, b]),
                start: Some(if r.from_ssm(self.frc.is_some()) {
                    ReferenceStart::Ssm
                } else {
                    ReferenceStart::Rest
                }),
                ..r.clone()
            }
        })
    }

    /// `[report]` with what it takes from the rest of the plan: the forced
    /// response it recomputes, the outputs and integrator tolerance of
    /// `[validate]`, the SSM's resonance tolerance.
    fn resolved_report(&self) -> Option<crate::analyses::report::ReportRequest> {
        let validation = self.validation.as_ref();
        self.report
            .as_ref()
            .map(|r| crate::analyses::report::ReportRequest {
                orders: r.orders.clone(),
                forcing: self.frc.clone(),
                outputs: validation.and_then(|v| v.outputs.clone()),
                rtol: validation.map_or(ValidationSpec::DEFAULT_RTOL, |v| v.rtol),
                resonance_tol: self.ssm.resonance_tol,
            })
    }

    /// The highest expansion order an answer names itself (`orders` lists,
    /// `order` keys, `nonautonomous_order + 1`); 1 when none does. A chosen
    /// SSM order is never below it.
    pub(crate) fn highest_named_order(&self) -> usize {
        let lists = [
            self.frc.as_ref().and_then(|f| f.orders.as_ref()),
            self.invariance.as_ref().map(|i| &i.orders),
            self.backbone.as_ref().and_then(|b| b.orders.as_ref()),
            self.report.as_ref().and_then(|r| r.orders.as_ref()),
        ];
        let singles = [
            self.transient.as_ref().and_then(|t| t.order),
            self.validation
                .as_ref()
                .and_then(|v| v.transient.as_ref())
                .and_then(|t| t.order),
        ];
        let na = self
            .frc
            .as_ref()
            .and_then(|f| f.nonautonomous_order)
            .map(|k| k + 1);
        lists
            .iter()
            .flatten()
            .flat_map(|o| o.iter().copied())
            .chain(singles.into_iter().flatten())
            .chain(na)
            .fold(1, usize::max)
    }

    /// Checks every spec's values (the checks of `ssm_core::spec`, with the
    /// plan's master pairs and highest order) and the analyses' specs: what
    /// a scene's sections are checked for, with the same keys and messages.
    pub fn validate(&self) -> Result<(), SpecError> {
        self.ssm.check()?;
        self.spectrum.check()?;
        let (pairs, max_order) = (self.ssm.master_pairs.len(), self.ssm.max_order());
        if let Some(s) = &self.invariance {
            s.check(max_order)?;
        }
        if let Some(s) = &self.backbone {
            s.check(pairs, max_order)?;
        }
        if let Some(s) = &self.transient {
            s.check(pairs, max_order)?;
        }
        if let Some(s) = &self.frc {
            s.check(pairs, max_order)?;
        }
        if let Some(s) = &self.validation {
            s.check(pairs, max_order, self.frc.is_some())?;
        }
        if let Some(s) = &self.reference {
            s.check(self.frc.as_ref().map(|f| f.omega_range))?;
        }
        if let Some(s) = &self.report {
            s.check(max_order)?;
        }
        if let Some(s) = &self.simulate {
            s.check(pairs)?;
        }
        if let Some(s) = &self.pod {
            s.check()?;
        }
        analyses::check(&self.analyses, &self.ssm)
    }

    /// Checks the plan against `system` and, for what can be costed
    /// before the spectrum (the POD study, the dense spectrum, the SSM
    /// order), against `limits`: the named outputs and states exist, the
    /// model can be validated and forced as asked, and the requests fit.
    /// The pipeline runs these checks on every plan it is given; the
    /// estimates that need the master modes run after the spectrum
    /// ([`budget::check`]). Returns the highest SSM order the run may
    /// compute ([`budget::check_spectrum`]).
    pub fn check(&self, system: &System, limits: &Limits) -> Result<usize, PlanError> {
        self.validate().map_err(PlanError::from)?;
        checks::check(self, system)?;
        budget::check_pod(self, system, limits)?;
        budget::check_spectrum(self, system, limits)
    }
}

/// The plan of a scene whose model is `system`: its sections as specs,
/// checked against the model and `limits`; every error names the scene's
/// file, line and key.
pub fn resolve(scene: &SceneFile, system: &System, limits: &Limits) -> Result<Plan, SceneError> {
    let plan = of_scene(scene)?;
    // what only the scene can tell: which table a given start came from
    checks::given_tables(scene, system)?;
    plan.check(system, limits).map_err(|e| e.in_scene(scene))?;
    Ok(plan)
}

/// The plan of a scene before its model is built (its sections as specs,
/// the analyses' tables read and checked): what a scene asks is known, and
/// its mistakes reported, before any plugin runs. [`resolve`] adds the
/// checks against the model.
pub fn of_scene(scene: &SceneFile) -> Result<Plan, SceneError> {
    let mut plan = convert::plan(scene);
    plan.validate().map_err(|e| {
        scene.invalid(
            scene.locate(e.at.as_ref().unwrap_or(&e.key)),
            &e.key,
            e.problem,
        )
    })?;
    plan.analyses = analyses::analyses(scene, &plan.ssm)?;
    Ok(plan)
}
