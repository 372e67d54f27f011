//! What stops a run: one error type for every stage, from the scene to the
//! files written.

use crate::output::OutputError;
use crate::plot::PlotError;
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
    /// The plan cannot run on its model or within the limits (a scene's
    /// run reports it as a [`JobError::Scene`] at the key's line).
    #[error(transparent)]
    Plan(#[from] crate::plan::PlanError),
}

impl JobError {
    /// The failure of an analysis: the typed error of its family where the
    /// engine has one (the answers older than the registry keep theirs, a
    /// [`ResultError`], an [`FrcError`], a failed full-system run of
    /// `[validate]`, `[reference]` or `[simulate]`, a failed report, with the
    /// same message),
    /// else [`JobError::Analysis`].
    pub(crate) fn of_analysis(e: crate::analyses::AnalysisError) -> Self {
        use crate::analyses::reference::ReferenceRunError;
        use crate::analyses::report::SpeedReportError;
        use crate::analyses::validation::ValidationError;
        use crate::analyses::AnalysisError;
        let AnalysisError::Failed { analysis, source } = e else {
            return JobError::Analysis(e);
        };
        let source = match source.downcast::<ValidationError>() {
            Ok(v) => match *v {
                ValidationError::Run(e) => return JobError::Validate(e),
                other => Box::new(other),
            },
            Err(other) => other,
        };
        let source = match source.downcast::<SpeedReportError>() {
            Ok(r) => match *r {
                SpeedReportError::Report(e) => return JobError::Report(e),
                other => Box::new(other),
            },
            Err(other) => other,
        };
        let source = match source.downcast::<ReferenceRunError>() {
            Ok(r) => match *r {
                ReferenceRunError::Frc(e) => return JobError::Reference(e),
                other => Box::new(other),
            },
            Err(other) => other,
        };
        let source = match source.downcast::<FrcError>() {
            Ok(f) => return JobError::Frc(*f),
            Err(other) => other,
        };
        let source = match source.downcast::<ResultError>() {
            Ok(r) => return JobError::Result(*r),
            Err(other) => other,
        };
        match source.downcast::<crate::analyses::simulate::SimulateError>() {
            Ok(e) => match *e {
                crate::analyses::simulate::SimulateError::Run { run, source } => {
                    JobError::Simulate { run, source }
                }
                other => JobError::Analysis(AnalysisError::Failed {
                    analysis,
                    source: Box::new(other),
                }),
            },
            Err(source) => JobError::Analysis(AnalysisError::Failed { analysis, source }),
        }
    }
}
