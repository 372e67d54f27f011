//! A whole run from Python: a plan (the engine's `Plan`, as JSON: every
//! section a scene may hold, span-free, with the scene's defaults) executed
//! on a model by the engine's pipeline, the same call a scene's run makes.
//! Every analysis of the engine is reachable this way (the invariance
//! error, the reduced transient, the full-system reference, validation,
//! the report, the sampled runs, the damping curve, ...); the results come
//! back as `summary.json` and the files a scene's run writes, in memory.
//! A scene file is a door too: its model (a plugin's, a folder's, or the one
//! its `[reduce]` makes) and its whole run, as the command line runs it.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use pyo3::prelude::*;

use crate::errors::{raise, Failure, Family};
use crate::model::Model;
use ssm_core::model::plugin::Registry;
use ssm_engine::job;
use ssm_engine::pipeline::{self, JobError};
use ssm_engine::plan::budget::Limits;
use ssm_engine::plan::Plan;
use ssm_engine::scene::SceneFile;

/// What a run returns to Python: the files it wrote `(name, contents)` and
/// the seconds the engine's own call took.
type RunFiles = (Vec<(String, Vec<u8>)>, f64);

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
/// `(name, contents)`, `summary.json` among them, and the seconds the
/// engine took (the wall time of the Rust call alone, for the layer's
/// overhead).
#[pyfunction]
#[pyo3(signature = (model, plan, progress=None))]
pub(crate) fn run_plan(
    py: Python<'_>,
    model: &Model,
    plan: &str,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<RunFiles> {
    let plan: Plan =
        serde_json::from_str(plan).map_err(|e| raise(py, Family::Input, format!("plan: {e}")))?;
    if plan.pod.is_some() && model.full.is_none() {
        return Err(raise(
            py,
            Family::Input,
            "plan: pod: the POD study projects a model's matrices and forces; a model identified from data has none",
        ));
    }
    let system = (*model.system).clone();
    let full = model.full.as_deref().cloned();
    let outputs = crate::work::interruptible(py, progress.as_ref(), move |progress| {
        let started = Instant::now();
        let model = pipeline::Model {
            system,
            reduction: None,
            full,
            plugins: Vec::new(),
        };
        pipeline::execute(&plan, model, &Limits::of_machine(), progress, started)
            .map(|job| (job.outputs.files, started.elapsed().as_secs_f64()))
            .map_err(|e| Failure(family(&e), e.to_string()))
    })?
    .map_err(|f| f.raise(py))?;
    Ok(outputs)
}

/// The scene at `path`, read, and the plugin registry of `plugins` (paths)
/// and `SSM_PLUGIN_PATH`.
fn scene_and_registry(
    path: &std::path::Path,
    plugins: &[PathBuf],
) -> Result<(SceneFile, Registry), Failure> {
    let scene = SceneFile::load(path).map_err(|e| Failure::of(Family::Input, e))?;
    let registry = Registry::discover(plugins).map_err(|e| Failure::of(Family::Model, e))?;
    Ok((scene, registry))
}

/// The model of the scene at `path`: its `[model]` (a plugin's, a folder's)
/// or the model its `[reduce]` makes, with the reducer's diagnostics;
/// `plugins` are plugin paths beside those of `SSM_PLUGIN_PATH`.
#[pyfunction]
#[pyo3(signature = (path, plugins=Vec::new()))]
pub(crate) fn model_from_scene(
    py: Python<'_>,
    path: PathBuf,
    plugins: Vec<PathBuf>,
) -> PyResult<Model> {
    let (system, diagnostics, full) = crate::work::interruptible(py, None, move |_progress| {
        let (scene, mut registry) = scene_and_registry(&path, &plugins)?;
        let model = job::scene_model(&scene, &mut registry)
            .map_err(|e| Failure(family(&e), e.to_string()))?;
        let diagnostics = model
            .reduction
            .iter()
            .flat_map(|r| &r.diagnostics)
            .map(|d| (d.name.to_string(), d.values.to_vec(), d.text.to_string()))
            .collect::<Vec<_>>();
        Ok::<_, Failure>((model.system, diagnostics, model.full))
    })?
    .map_err(|f| f.raise(py))?;
    Ok(Model {
        system: Arc::new(system),
        diagnostics,
        full: full.map(Arc::new),
    })
}

/// Runs the scene at `path` as `ssm-engine SCENE.toml` does (its model, its
/// plan resolved against it, the engine's cost gate, the POD study
/// included); returns the files the run writes, in memory, and the seconds
/// the engine took (scene, plugins and run: what `ssm-engine` does but
/// write the files).
#[pyfunction]
#[pyo3(signature = (path, plugins=Vec::new(), progress=None))]
pub(crate) fn run_scene(
    py: Python<'_>,
    path: PathBuf,
    plugins: Vec<PathBuf>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<RunFiles> {
    crate::work::interruptible(py, progress.as_ref(), move |progress| {
        let started = Instant::now();
        let (scene, mut registry) = scene_and_registry(&path, &plugins)?;
        job::run(&scene, &mut registry, progress)
            .map(|job| (job.outputs.files, started.elapsed().as_secs_f64()))
            .map_err(|e| Failure(family(&e), e.to_string()))
    })?
    .map_err(|f| f.raise(py))
}
