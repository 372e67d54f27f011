//! What makes a plan impossible to run on its model or within the limits.

use std::ops::Range;

use crate::scene::{SceneError, SceneFile};

/// A plan that cannot run on its model or within the run's limits: the
/// key concerned (as a scene spells it, e.g. `reference.harmonics`), the
/// key whose place in a scene the message points at (usually the same),
/// and what is wrong and what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}`: {problem}")]
pub struct PlanError {
    /// The key concerned.
    pub key: String,
    /// The key path a scene's message points at (`simulate.run[2]`: the
    /// second `[[simulate.run]]`).
    pub at: String,
    /// What is wrong.
    pub problem: String,
}

impl From<ssm_core::spec::SpecError> for PlanError {
    fn from(e: ssm_core::spec::SpecError) -> Self {
        let at = e.at.unwrap_or_else(|| e.key.clone());
        Self {
            key: e.key,
            at,
            problem: e.problem,
        }
    }
}

impl PlanError {
    /// A problem of `key`, at `key`.
    pub fn new(key: &str, problem: String) -> Self {
        Self::at(key, key, problem)
    }

    /// A problem of `key`, pointed at `at`.
    pub fn at(key: &str, at: &str, problem: String) -> Self {
        Self {
            key: key.to_owned(),
            at: at.to_owned(),
            problem,
        }
    }

    /// The same problem as a scene error at the line of `at` in `scene`
    /// (the value's line, or the line of the nearest table that holds it).
    pub(crate) fn in_scene(&self, scene: &SceneFile) -> SceneError {
        let span: Range<usize> = scene.locate(&self.at);
        scene.invalid(span, &self.key, self.problem.clone())
    }
}
