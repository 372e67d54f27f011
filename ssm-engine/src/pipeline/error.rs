//! What stops a run.

use super::source::SourceError;
use crate::output::plot::PlotError;
use crate::output::OutputError;
use crate::scene::SceneError;
use ssm_core::compare::report::ReportError;
use ssm_core::compare::ValidateError;
use ssm_core::model::plugin::PluginLoadError;
use ssm_core::model::system::ModelError;
use ssm_core::reduce::SignalsError;
use ssm_core::rom::autonomous::ResultError;
use ssm_core::rom::forced_response::FrcError;
use ssm_core::spectrum::SpectrumError;
use ssm_core::ssm::SsmError;

/// Anything that stops a run; each variant says where.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The scene is malformed or inconsistent with the model.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A plugin could not be loaded, or returned an error or panicked.
    #[error(transparent)]
    Plugin(#[from] PluginLoadError),
    /// A `[data]` file cannot be used.
    #[error("data: {0}")]
    Signals(#[from] SignalsError),
    /// The plugin's model is inconsistent.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The spectrum could not be computed.
    #[error("spectrum: {0}")]
    Spectrum(#[from] SpectrumError),
    /// Outputs could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The SSM could not be computed.
    #[error("SSM: {0}")]
    Ssm(#[from] SsmError),
    /// A backbone, invariance error or reduced transient could not be produced.
    #[error(transparent)]
    Result(#[from] ResultError),
    /// The forced response could not be produced.
    #[error(transparent)]
    Frc(#[from] FrcError),
    /// A full-system reference failed.
    #[error("validation: {0}")]
    Validate(#[from] ValidateError),
    /// A `[simulate]` run failed.
    #[error("[simulate] run {run}: {source}")]
    Simulate {
        /// 1-based run.
        run: usize,
        /// What failed.
        source: ssm_core::fom::SimError,
    },
    /// The speed-against-error report failed.
    #[error(transparent)]
    Report(#[from] ReportError),
    /// The `[pod]` study failed.
    #[error("[pod] {0}")]
    Pod(#[from] ssm_core::compare::pod::PodStudyError),
    /// The `[reference]` forced response failed.
    #[error(transparent)]
    Reference(#[from] ssm_core::fom::periodic::ReferenceError),
    /// A plot could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// An analysis of `[analysis]` could not be planned or run.
    #[error(transparent)]
    Analysis(#[from] crate::analyses::AnalysisError),
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
pub enum ReduceError {
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
