//! A validated scene's sections converted to specs: nothing but dropping
//! the spans (and filling in what a section leaves to another, e.g. the
//! steady states' frequencies of `omega_range` and `points`).

use toml::Spanned;

use crate::scene::{
    BackboneSection, ForcingSection, InvarianceErrorSection, PodRun, PodSection, ReferenceSection,
    SceneFile, SimulateRun, SimulateSection, SpectrumMethod, SteadyStateSection, TransientSection,
    ValidateSection,
};
use ssm_core::spec::{
    BackboneSpec, FrcSpec, InvarianceSpec, PodRunSpec, PodSpec, PodTruncations, ReferenceSpec,
    ReferenceStart, ReportSpec, SimulateSpec, SpectrumSpec, SsmSpec, SteadyStart, SteadyStateSpec,
    TransientSpec, ValidationSpec, ValidationStart, ValidationTransientSpec,
};
use ssm_core::spectrum::Method;

use super::Plan;

/// Every section of `scene` (checked by [`SceneFile::parse`]) as specs;
/// the analyses of `[analysis]` come separately (their tables are read by
/// their own specs, with errors at their lines).
pub(super) fn plan(scene: &SceneFile) -> Plan {
    let sc = &scene.scene;
    Plan {
        ssm: ssm(scene),
        spectrum: SpectrumSpec {
            method: match sc.spectrum.method {
                SpectrumMethod::Auto => None,
                SpectrumMethod::Dense => Some(Method::Dense),
                SpectrumMethod::Sparse => Some(Method::Sparse),
            },
            modes: sc.spectrum.modes.as_ref().map(|m| *m.get_ref()),
            shift: sc.spectrum.shift.unwrap_or(0.0),
        },
        coordinates: sc.outputs.coordinates.get_ref().clone(),
        invariance: sc.outputs.invariance_error.as_ref().map(invariance),
        backbone: sc.outputs.backbone.as_ref().map(backbone),
        transient: sc.outputs.transient.as_ref().map(transient),
        frc: sc.forcing.as_ref().map(frc),
        validation: sc.validate.as_ref().map(validation),
        reference: sc.reference.as_ref().map(reference),
        report: sc.report.as_ref().map(|r| ReportSpec {
            orders: r.orders.as_ref().map(|o| o.get_ref().clone()),
        }),
        simulate: sc.simulate.as_ref().map(simulate),
        pod: sc.pod.as_ref().map(pod),
        analyses: Vec::new(),
    }
}

/// `[ssm]`.
fn ssm(scene: &SceneFile) -> SsmSpec {
    let s = &scene.scene.ssm;
    SsmSpec {
        master_pairs: s.master_pairs.get_ref().clone(),
        order: s.order.as_ref().map(|o| *o.get_ref()),
        normalization: s.normalization,
        resonance_tol: *s.resonance_tol.get_ref(),
        tolerance: *s.tolerance.get_ref(),
    }
}

fn pair(v: &Spanned<Vec<f64>>) -> Option<[f64; 2]> {
    match v.get_ref()[..] {
        [a, b] => Some([a, b]),
        _ => None,
    }
}

/// `[reference]`.
fn reference(sec: &ReferenceSection) -> ReferenceSpec {
    ReferenceSpec {
        epsilon: sec.epsilon.get_ref().clone(),
        omega_range: sec.omega_range.as_ref().and_then(pair),
        harmonics: *sec.harmonics.get_ref(),
        step: *sec.step.get_ref(),
        tol: *sec.tol.get_ref(),
        max_steps: *sec.max_steps.get_ref(),
        period_doubling: *sec.period_doubling.get_ref(),
        stability: *sec.stability.get_ref(),
        outputs: sec.outputs.as_ref().map(|o| o.get_ref().clone()),
        start: sec.start.as_ref().map(|s| match s.get_ref().as_str() {
            "ssm" => ReferenceStart::Ssm,
            _ => ReferenceStart::Rest,
        }),
        amplitude_at: sec
            .amplitude_at
            .as_ref()
            .map_or_else(Vec::new, |a| a.get_ref().clone()),
        amplitude_range: sec.amplitude_range.as_ref().and_then(pair),
    }
}

/// `[simulate]`.
fn simulate(sec: &SimulateSection) -> SimulateSpec {
    SimulateSpec {
        period: *sec.period.get_ref(),
        samples: *sec.samples.get_ref(),
        outputs: sec.outputs.as_ref().map(|o| o.get_ref().clone()),
        noise: *sec.noise.get_ref(),
        seed: *sec.seed.get_ref(),
        rtol: *sec.rtol.get_ref(),
        atol: *sec.atol.get_ref(),
        hht_alpha: sec.hht_alpha.as_ref().map(|a| *a.get_ref()),
        runs: sec.run.get_ref().iter().map(simulate_start).collect(),
    }
}

fn simulate_start(run: &SimulateRun) -> ValidationStart {
    match &run.rho0 {
        Some(rho0) => ValidationStart::Ssm {
            rho0: rho0.clone(),
            theta0: run.theta0.clone(),
        },
        None => ValidationStart::Given {
            values: run.given_start(),
        },
    }
}

/// `[pod]`.
fn pod(sec: &PodSection) -> PodSpec {
    let run = |r: &PodRun| PodRunSpec {
        epsilon: r.epsilon,
        omega: *r.omega.get_ref(),
        t_end: r.t_end,
        start: r.given_start(),
        steps: r.steps.clone(),
    };
    PodSpec {
        truncations: match (&sec.energy, &sec.drop) {
            (Some(e), _) => PodTruncations::Energy(e.get_ref().clone()),
            (None, Some(d)) => PodTruncations::Drop(d.get_ref().clone()),
            (None, None) => PodTruncations::default(),
        },
        rank_tol: *sec.rank_tol.get_ref(),
        jacobian_samples: *sec.jacobian_samples.get_ref(),
        hyper: sec
            .hyper
            .as_ref()
            .map_or_else(Vec::new, |h| h.get_ref().clone()),
        step: *sec.step.get_ref(),
        hht_alpha: *sec.hht_alpha.get_ref(),
        outputs: sec.outputs.as_ref().map(|o| o.get_ref().clone()),
        ssm_pairs: sec
            .ssm_pairs
            .as_ref()
            .map_or_else(Vec::new, |s| s.get_ref().clone()),
        ssm_order: sec.ssm_order.as_ref().map(|o| *o.get_ref()),
        train: run(sec.train.get_ref()),
        tests: sec.test.get_ref().iter().map(run).collect(),
    }
}

/// `[outputs.backbone]`.
fn backbone(sec: &BackboneSection) -> BackboneSpec {
    BackboneSpec {
        rho_max: *sec.rho_max.get_ref(),
        points: *sec.points.get_ref(),
        orders: sec.orders.as_ref().map(|o| o.get_ref().clone()),
    }
}

/// `[outputs.invariance_error]`.
fn invariance(sec: &InvarianceErrorSection) -> InvarianceSpec {
    InvarianceSpec {
        radii: sec.radii.get_ref().clone(),
        orders: sec.orders.get_ref().clone(),
        n_alpha: *sec.n_alpha.get_ref(),
        n_theta: *sec.n_theta.get_ref(),
    }
}

/// `[outputs.transient]`.
fn transient(sec: &TransientSection) -> TransientSpec {
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
fn frc(sec: &ForcingSection) -> FrcSpec {
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
fn steady_state(sec: &SteadyStateSection) -> SteadyStateSpec {
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
fn validation(sec: &ValidateSection) -> ValidationSpec {
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
        outputs: sec.outputs.as_ref().map(|o| o.get_ref().clone()),
    }
}
