//! A scene's run, the engine's door for TOML: the model built from
//! `[model]` (a plugin, model files) or made by the reducer of `[reduce]`,
//! the scene resolved to a [`Plan`] against it ([`plan::resolve`]), and the
//! plan run by [`pipeline::execute`]; a plan's error comes back as a scene
//! error at the key's file and line.

pub mod export;
mod pod_reducer;
mod reduce;
pub mod source;

use std::path::PathBuf;
use std::time::Instant;

use crate::pipeline::{self, JobError, JobResult, Model, Progress};
use crate::plan::{self, budget::Limits, Plan};
use crate::scene::{SceneError, SceneFile};
use reduce::reduce_scene;
use source::{build_model, SourceError};
use ssm_core::model::plugin::Registry;
use ssm_core::model::system::{ModelError, System};
use ssm_core::reduce::{Reduction, SignalsError};

/// Runs a scene and assembles its outputs (nothing is written here).
pub fn run(
    scene: &SceneFile,
    registry: &mut Registry,
    progress: &dyn Progress,
) -> Result<JobResult, JobError> {
    let started = Instant::now();
    // what the scene asks, first: a mistake in an analysis's table is
    // reported before any model is built
    let asked = plan::of_scene(scene)?;
    // ... and an order that fits no model, before one is built
    plan::budget::check_before_model(&asked, &Limits::of_machine())
        .map_err(|e| JobError::Scene(e.in_scene(scene)))?;
    progress.stage("building model");
    let model = scene_model(scene, registry)?;
    let limits = Limits::of_machine();
    let plan: Plan = plan::resolve(scene, &model.system, &limits)?;
    pipeline::execute(&plan, model, &limits, progress, started).map_err(|e| match e {
        JobError::Plan(e) => JobError::Scene(e.in_scene(scene)),
        other => other,
    })
}

/// The model a scene's analyses run on (its `[model]`, or the model its
/// `[reduce]` makes), with the plugins that made it: what a scene's run
/// builds before it resolves its plan, for a binding that takes the model
/// of a scene file.
///
/// # Errors
/// The scene's model or reducer failed (a scene error at its key, a plugin's
/// or the model's error).
pub fn scene_model(scene: &SceneFile, registry: &mut Registry) -> Result<Model, JobError> {
    registry.take_used();
    let (system, reduction, full) = obtain_model(scene, registry)?;
    Ok(Model {
        system,
        reduction,
        full,
        plugins: registry.take_used(),
    })
}

/// The model the analyses run on: the plugin's model of `[model]`, or the
/// model the reducer of `[reduce]` makes from it and/or the `[data]` signals;
/// validated into a [`System`]. With `[pod]`, the plugin's model as it was
/// given too (the POD reducer projects it).
fn obtain_model(
    scene: &SceneFile,
    registry: &mut Registry,
) -> Result<(System, Option<Reduction>, Option<ssm_api::Model>), JobError> {
    let sc = &scene.scene;
    let full = sc
        .model
        .as_ref()
        .map(|m| build_model(scene, m, registry))
        .transpose()?;
    match &sc.reduce {
        Some(red) => {
            let (system, reduction) = reduce_scene(scene, red, full, registry)?;
            Ok((system, Some(reduction), None))
        }
        None => {
            let (plugin, model) = full.ok_or_else(|| {
                scene.invalid(0..0, "model", "the scene has no [model] section".into())
            })?;
            let raw = sc.pod.as_ref().map(|_| model.clone());
            Ok((System::from_model(&plugin, model)?, None, raw))
        }
    }
}

/// Default output directory of a scene: `./out/<scene name>`.
pub fn default_out_dir(scene: &SceneFile) -> PathBuf {
    PathBuf::from("out").join(scene.name())
}

impl From<SourceError> for JobError {
    fn from(e: SourceError) -> Self {
        match e {
            SourceError::Scene(e) => Self::Scene(e),
            SourceError::Plugin(e) => Self::Plugin(e),
        }
    }
}

impl From<ReduceError> for JobError {
    fn from(e: ReduceError) -> Self {
        match e {
            ReduceError::Source(e) => e.into(),
            ReduceError::Signals(e) => Self::Signals(e),
            ReduceError::Model(e) => Self::Model(e),
        }
    }
}

/// Why a reduced model could not be had.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ReduceError {
    /// The scene or the reducer's plugin failed.
    #[error(transparent)]
    Source(#[from] SourceError),
    /// A `[data]` file cannot be used.
    #[error("data: {0}")]
    Signals(#[from] SignalsError),
    /// The reduced model is inconsistent.
    #[error(transparent)]
    Model(#[from] ModelError),
}

impl From<SceneError> for ReduceError {
    fn from(e: SceneError) -> Self {
        Self::Source(SourceError::Scene(e))
    }
}
