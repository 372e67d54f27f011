//! A whole run from Python: a plan (the engine's `Plan`, as JSON: every
//! section a scene may hold, span-free, with the scene's defaults) executed
//! on a model by the engine's pipeline, the same call a scene's run makes.
//! Every analysis of the engine is reachable this way (the invariance
//! error, the reduced transient, the full-system reference, validation,
//! the report, the sampled runs, the damping curve, ...); the results come
//! back as `summary.json` and the files a scene's run writes, in memory.

use std::time::Instant;

use pyo3::prelude::*;

use crate::errors::{raise, Failure, Family};
use crate::model::Model;
use ssm_engine::pipeline::{self, JobError};
use ssm_engine::plan::budget::Limits;
use ssm_engine::plan::Plan;

/// The family of an engine error.
fn family(e: &JobError) -> Family {
    match e {
        JobError::Plan(_) | JobError::Scene(_) => Family::Input,
        JobError::Model(_) | JobError::Plugin(_) => Family::Model,
        JobError::Spectrum(_) => Family::Spectrum,
        JobError::Ssm(_) => Family::Expansion,
        _ => Family::Analysis,
    }
}

/// Runs the plan `plan` (JSON) on `model` within the machine's limits (the
/// engine's one cost gate); returns the files a scene's run writes, as
/// `(name, contents)`, `summary.json` among them.
#[pyfunction]
#[pyo3(signature = (model, plan, progress=None))]
pub(crate) fn run_plan(
    py: Python<'_>,
    model: &Model,
    plan: &str,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Vec<(String, Vec<u8>)>> {
    let plan: Plan =
        serde_json::from_str(plan).map_err(|e| raise(py, Family::Input, format!("plan: {e}")))?;
    if plan.pod.is_some() {
        return Err(raise(
            py,
            Family::Input,
            "plan: pod: the POD study projects a plugin's model; a model from arrays cannot run it yet",
        ));
    }
    let system = (*model.system).clone();
    let outputs = crate::work::interruptible(py, progress.as_ref(), move |progress| {
        let model = pipeline::Model {
            system,
            reduction: None,
            full: None,
            plugins: Vec::new(),
        };
        pipeline::execute(
            &plan,
            model,
            &Limits::of_machine(),
            progress,
            Instant::now(),
        )
        .map(|job| job.outputs.files)
        .map_err(|e| Failure(family(&e), e.to_string()))
    })?
    .map_err(|f| f.raise(py))?;
    Ok(outputs)
}
