//! The scene resolved to what the numerics are asked to compute: each
//! section of a validated [`SceneFile`] becomes its span-free
//! [`ssm_core::spec`]. Nothing below this layer reads TOML or its spans; code
//! that has no scene (a binding, a study, a test) builds the specs itself.
//!
//! The scene's checks against its model have run before (they name file,
//! line and key); these conversions only drop the spans.

mod analyses;

pub use analyses::{analyses, key_span, needs, PlannedAnalysis};

use crate::scene::{
    BackboneSection, ForcingSection, InvarianceErrorSection, SceneFile, SteadyStateSection,
    TransientSection, ValidateSection,
};
use ssm_core::spec::{
    BackboneSpec, FrcSpec, InvarianceSpec, SteadyStart, SteadyStateSpec, TransientSpec,
    ValidationSpec, ValidationStart, ValidationTransientSpec,
};

/// `[outputs.backbone]`.
pub fn backbone(sec: &BackboneSection) -> BackboneSpec {
    BackboneSpec {
        rho_max: *sec.rho_max.get_ref(),
        points: *sec.points.get_ref(),
        orders: sec.orders.as_ref().map(|o| o.get_ref().clone()),
    }
}

/// `[outputs.invariance_error]`.
pub fn invariance(sec: &InvarianceErrorSection) -> InvarianceSpec {
    InvarianceSpec {
        radii: sec.radii.get_ref().clone(),
        orders: sec.orders.get_ref().clone(),
        n_alpha: *sec.n_alpha.get_ref(),
        n_theta: *sec.n_theta.get_ref(),
    }
}

/// `[outputs.transient]`.
pub fn transient(sec: &TransientSection) -> TransientSpec {
    TransientSpec {
        rho0: sec.rho0.get_ref().clone(),
        theta0: sec.theta0.as_ref().map(|t| t.get_ref().clone()),
        t_end: *sec.t_end.get_ref(),
        samples: *sec.samples.get_ref(),
        order: sec.order.as_ref().map(|o| *o.get_ref()),
        rtol: *sec.rtol.get_ref(),
    }
}

/// `[forcing]` (its `omega_range` checked to hold two numbers).
pub fn frc(sec: &ForcingSection) -> FrcSpec {
    let range = sec.omega_range.get_ref();
    FrcSpec {
        epsilon: sec.epsilon.get_ref().clone(),
        omega_range: [range[0], range[1]],
        orders: sec.orders.as_ref().map(|o| o.get_ref().clone()),
        resonance: sec.resonance.as_ref().map(|r| r.get_ref().clone()),
        points: *sec.points.get_ref(),
        rho_max: sec.rho_max.as_ref().map(|r| *r.get_ref()),
        nonautonomous_order: sec.nonautonomous_order.as_ref().map(|k| *k.get_ref()),
    }
}

/// `[validate.steady_state]`.
pub fn steady_state(sec: &SteadyStateSection) -> SteadyStateSpec {
    let omegas = match (&sec.omega, &sec.omega_range) {
        (Some(o), _) => o.get_ref().clone(),
        (None, Some(r)) if r.get_ref().len() == 2 => {
            let r = r.get_ref();
            SteadyStateSpec::uniform([r[0], r[1]], *sec.points.get_ref())
        }
        _ => Vec::new(),
    };
    SteadyStateSpec {
        epsilon: *sec.epsilon.get_ref(),
        omegas,
        delta: *sec.delta.get_ref(),
        max_periods: *sec.max_periods.get_ref(),
        samples_per_period: *sec.samples_per_period.get_ref(),
        max_period_multiple: *sec.max_period_multiple.get_ref(),
        start: match sec.start.as_ref().map(|s| s.get_ref().as_str()) {
            Some("ssm") => SteadyStart::Ssm,
            _ => SteadyStart::Rest,
        },
    }
}

/// `[validate]`: the transient runs when `t_end` is given, from `rho0` on
/// the SSM or else from the given `x0`/`v0` (none: the equilibrium).
pub fn validation(sec: &ValidateSection) -> ValidationSpec {
    let transient = sec.t_end.as_ref().map(|t_end| ValidationTransientSpec {
        start: match &sec.rho0 {
            Some(rho0) => ValidationStart::Ssm {
                rho0: rho0.get_ref().clone(),
                theta0: sec.theta0.as_ref().map(|t| t.get_ref().clone()),
            },
            None => ValidationStart::Given {
                values: sec.given_start(),
            },
        },
        t_end: *t_end.get_ref(),
        samples: *sec.samples.get_ref(),
        order: sec.order.as_ref().map(|o| *o.get_ref()),
    });
    ValidationSpec {
        transient,
        steady_state: sec.steady_state.as_ref().map(steady_state),
        rtol: *sec.rtol.get_ref(),
        atol: *sec.atol.get_ref(),
    }
}

/// The outputs' specs of a scene, in one place for the pipeline.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AnswerSpecs {
    /// `[outputs.invariance_error]`.
    pub invariance: Option<InvarianceSpec>,
    /// `[outputs.backbone]`.
    pub backbone: Option<BackboneSpec>,
    /// `[outputs.transient]`.
    pub transient: Option<TransientSpec>,
    /// `[forcing]`.
    pub frc: Option<FrcSpec>,
    /// `[validate]`.
    pub validation: Option<ValidationSpec>,
    /// `[analysis.<name>]`: the analyses of [`crate::analyses::REGISTRY`].
    pub analyses: Vec<PlannedAnalysis>,
}

/// Every answer `scene` asks of the reduced model, as specs.
pub fn answers(scene: &SceneFile) -> Result<AnswerSpecs, crate::scene::SceneError> {
    let sc = &scene.scene;
    Ok(AnswerSpecs {
        invariance: sc.outputs.invariance_error.as_ref().map(invariance),
        backbone: sc.outputs.backbone.as_ref().map(backbone),
        transient: sc.outputs.transient.as_ref().map(transient),
        frc: sc.forcing.as_ref().map(frc),
        validation: sc.validate.as_ref().map(validation),
        analyses: analyses(scene)?,
    })
}
