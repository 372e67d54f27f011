//! Checks of a plan against its model that the specs alone cannot make:
//! the named outputs and states exist, the model can be integrated,
//! validated and forced as asked, and sizes fixed by the model stay within
//! the engine's limits. Each failure names its key.

use ssm_api::{StateKind, TimeKind};
use ssm_core::model::system::{OutputMap, System};
use ssm_core::spec::{PodRunSpec, ValidationStart};

use super::{Plan, PlanError};
use crate::scene::{SceneError, SceneFile, MAX_REFERENCE_COEFFICIENTS};

/// Most sampled values of one `[simulate]` run (samples times outputs; 40
/// MB of doubles, some 150 MB of CSV text).
pub(crate) const MAX_SIMULATE_VALUES: usize = 5_000_000;

/// Every check of `plan` against `system`.
pub(super) fn check(plan: &Plan, system: &System) -> Result<(), PlanError> {
    named_outputs(system, &plan.coordinates, "outputs.coordinates")?;
    if let Some(m) = plan.spectrum.modes {
        let n = system.n_states();
        if m > n {
            return Err(PlanError::new(
                "spectrum.modes",
                format!(
                    "{m} modes asked for, but the model has {n} states and so at most {n} finite eigenvalues"
                ),
            ));
        }
    }
    check_validation(plan, system)?;
    check_reference(plan, system)?;
    check_simulate(plan, system)?;
    check_pod(plan, system)
}

/// The outputs `names` (the key `key`), each checked to exist.
pub(crate) fn named_outputs<'a>(
    system: &'a System,
    names: &[String],
    key: &str,
) -> Result<Vec<&'a OutputMap>, PlanError> {
    names
        .iter()
        .map(|name| {
            system.output(name).ok_or_else(|| {
                let known: Vec<&str> = system
                    .outputs
                    .iter()
                    .map(|o| o.name.as_str())
                    .take(40)
                    .collect();
                PlanError::new(
                    key,
                    format!(
                        "model '{}' has no output '{name}'; it has: {}",
                        system.name,
                        known.join(", ")
                    ),
                )
            })
        })
        .collect()
}

/// Each name of a given start is a state of `system`.
fn given_states(
    system: &System,
    values: &[(String, f64)],
    key: &str,
    at: &str,
) -> Result<(), PlanError> {
    match values
        .iter()
        .find(|(n, _)| !system.states.iter().any(|s| s.name.as_str() == n))
    {
        Some((name, _)) => Err(PlanError::at(
            key,
            at,
            format!("model '{}' has no state '{name}'", system.name),
        )),
        None => Ok(()),
    }
}

/// `[validate]`: a flow to integrate, a forcing for steady states, the
/// start's states and the compared outputs.
fn check_validation(plan: &Plan, system: &System) -> Result<(), PlanError> {
    let Some(v) = &plan.validation else {
        return Ok(());
    };
    if let TimeKind::Map { .. } = system.time {
        return Err(PlanError::new(
            "validate",
            format!(
                "model '{}' is a map; the full-system integrator needs a flow",
                system.name
            ),
        ));
    }
    if v.steady_state.is_some() && system.forcing.is_empty() {
        return Err(PlanError::at(
            "validate.steady_state",
            "validate.steady_state.epsilon",
            format!(
                "model '{}' has no forcing Fext to drive a steady state",
                system.name
            ),
        ));
    }
    if let Some(ValidationStart::Given { values }) = v.transient.as_ref().map(|t| &t.start) {
        given_states(system, values, "validate.x0", "validate.x0")?;
    }
    if let Some(names) = &v.outputs {
        if let Some(n) = names.iter().find(|n| system.output(n).is_none()) {
            return Err(PlanError::new(
                "validate.outputs",
                format!("model '{}' has no output '{n}'", system.name),
            ));
        }
    }
    Ok(())
}

/// `[reference]`: a forcing, a frequency range, the outputs, and a harmonic
/// balance of at most [`MAX_REFERENCE_COEFFICIENTS`] unknowns.
fn check_reference(plan: &Plan, system: &System) -> Result<(), PlanError> {
    let Some(r) = &plan.reference else {
        return Ok(());
    };
    if let Some(names) = &r.outputs {
        named_outputs(system, names, "reference.outputs")?;
    }
    let h = r.harmonics;
    let coefficients = system.n_states().saturating_mul(2 * h + 1);
    if coefficients > MAX_REFERENCE_COEFFICIENTS {
        return Err(PlanError::new(
            "reference.harmonics",
            format!(
                "{} states x {} Fourier functions = {coefficients} unknowns per orbit exceed the limit {MAX_REFERENCE_COEFFICIENTS}: lower harmonics",
                system.n_states(),
                2 * h + 1
            ),
        ));
    }
    if system.forcing.is_empty() {
        return Err(PlanError::at(
            "reference",
            "reference.epsilon",
            format!(
                "model '{}' has no forcing Fext to drive a forced response",
                system.name
            ),
        ));
    }
    if r.omega_range(plan.frc.as_ref().map(|f| f.omega_range))
        .is_none()
    {
        return Err(PlanError::new(
            "reference.omega_range",
            "give omega_range here or in [forcing]".into(),
        ));
    }
    Ok(())
}

/// `[simulate]`: the outputs sampled (within [`MAX_SIMULATE_VALUES`]) and
/// each given start's states.
fn check_simulate(plan: &Plan, system: &System) -> Result<(), PlanError> {
    let Some(s) = &plan.simulate else {
        return Ok(());
    };
    let outputs = match &s.outputs {
        Some(names) => named_outputs(system, names, "simulate.outputs")?.len(),
        None => plan.coordinates.len(),
    };
    if outputs == 0 {
        return Err(PlanError::at(
            "simulate.outputs",
            "simulate.run",
            "no output to sample: name them here or in [outputs] coordinates".into(),
        ));
    }
    if s.samples.saturating_mul(outputs) > MAX_SIMULATE_VALUES {
        return Err(PlanError::new(
            "simulate.samples",
            format!(
                "{} samples of {outputs} outputs per run exceed {MAX_SIMULATE_VALUES} values: sample fewer points or outputs",
                s.samples
            ),
        ));
    }
    for (k, run) in s.runs.iter().enumerate() {
        if let ValidationStart::Given { values } = run {
            let key = format!("simulate.run[{}]", k + 1);
            given_states(system, values, &key, &key)?;
        }
    }
    Ok(())
}

/// `[pod]`: the outputs compared and each run's given states.
fn check_pod(plan: &Plan, system: &System) -> Result<(), PlanError> {
    let Some(p) = &plan.pod else {
        return Ok(());
    };
    pod_outputs(plan, system)?;
    let runs = std::iter::once(("pod.train".to_owned(), "pod.train".to_owned(), &p.train)).chain(
        p.tests.iter().enumerate().map(|(k, r)| {
            (
                format!("pod.test{}", k + 1),
                format!("pod.test[{}]", k + 1),
                r,
            )
        }),
    );
    for (key, at, run) in runs {
        let run: &PodRunSpec = run;
        given_states(system, &run.start, &key, &at)?;
    }
    Ok(())
}

/// The outputs the POD study compares (its `outputs`, else the plan's
/// coordinates), each checked to exist.
pub(crate) fn pod_outputs<'a>(
    plan: &Plan,
    system: &'a System,
) -> Result<Vec<&'a OutputMap>, PlanError> {
    let Some(p) = &plan.pod else {
        return Ok(Vec::new());
    };
    let (names, key) = match &p.outputs {
        Some(o) => (o, "pod.outputs"),
        None => (&plan.coordinates, "outputs.coordinates"),
    };
    if names.is_empty() {
        return Err(PlanError::at(
            "pod.outputs",
            "pod.step",
            "name the outputs to compare: [pod] outputs or [outputs] coordinates".into(),
        ));
    }
    named_outputs(system, names, key)
}

/// The given starts of the scene's `[validate]` and `[[simulate.run]]`:
/// displacements in `x0`, velocities in `v0` (a plan holds them as one
/// list, so only the scene can tell a velocity given as a displacement).
pub(super) fn given_tables(scene: &SceneFile, system: &System) -> Result<(), SceneError> {
    let sc = &scene.scene;
    if let Some(v) = &sc.validate {
        for (table, key) in [(&v.x0, "validate.x0"), (&v.v0, "validate.v0")] {
            if let Some(t) = table {
                given_kinds(system, t.get_ref(), key)
                    .map_err(|m| scene.invalid(t.span(), key, m))?;
            }
        }
    }
    if let Some(s) = &sc.simulate {
        for (k, run) in s.run.get_ref().iter().enumerate() {
            for (table, part) in [(&run.x0, "x0"), (&run.v0, "v0")] {
                if let Some(t) = table {
                    let key = format!("simulate.run[{}].{part}", k + 1);
                    given_kinds(system, t, &key).map_err(|m| {
                        scene.invalid(scene.locate(&format!("simulate.run[{}]", k + 1)), &key, m)
                    })?;
                }
            }
        }
    }
    Ok(())
}

/// The keys of `table` name states of the kind the last part of `key`
/// says: displacements in `x0`, velocities in `v0`.
fn given_kinds(system: &System, table: &toml::Table, key: &str) -> Result<(), String> {
    let kind = if key.ends_with("v0") {
        StateKind::Velocity
    } else {
        StateKind::Displacement
    };
    for name in table.keys() {
        if !system
            .states
            .iter()
            .any(|s| s.name.as_str() == name && s.kind == kind)
        {
            return Err(format!(
                "model '{}' has no {kind:?} state '{name}'",
                system.name
            ));
        }
    }
    Ok(())
}
