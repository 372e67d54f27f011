//! The POD study (`[pod]`): a training run of the full model (HHT-alpha),
//! its proper orthogonal decomposition, Galerkin models of each truncation
//! with the generalized constraint reduction, SSM models of the master
//! pairs asked for, and every model run on every load, each with its
//! seconds and its error against the full run.
//!
//! It is a study rather than an analysis of the run's SSM, so it is not in
//! [`super::REGISTRY`]: it runs first, before the spectrum, on the model as
//! its plugin gave it (the POD projects the plugin's matrices), builds the
//! SSMs of its own master pairs, and a scene may ask for it alone (then
//! `summary.json` holds the study and no SSM). The pipeline calls [`study`]
//! and the output layer [`files`]; its spec is [`ssm_core::spec::PodSpec`],
//! its numerics [`ssm_core::compare::pod`] and [`ssm_core::reduce::pod`].
//!
//! Its results are the key `pod` of `summary.json` ([`write::PodSummary`]);
//! files `pod_comparison.csv`, `pod_report.md`, `pod_povs.csv`/`.svg`,
//! `pod_errors.svg`, `pod_constraints.csv` and `pod_case_<k>.csv`.
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint
//! reduction method for reduced order MBS models*, Multibody Syst. Dyn.
//! (2017), Sects. 3-4 (the POD models and their constraint reduction).

mod run;
pub mod write;

use crate::plot::PlotError;
use crate::progress::Progress;
use ssm_core::compare::pod::{PodStudy, PodStudyError};
use ssm_core::model::system::{OutputMap, System};
use ssm_core::spec::{PodSpec, SpectrumSpec, SsmSpec};
use ssm_core::spectrum::SpectrumError;
use ssm_core::ssm::SsmError;

/// Why the study failed.
#[derive(Debug, thiserror::Error)]
pub enum PodError {
    /// A run or a POD model failed.
    #[error(transparent)]
    Study(#[from] PodStudyError),
    /// The spectrum of an SSM model failed (a pair of `ssm_pairs` beyond
    /// the spectrum is [`SpectrumError::PairOutOfRange`]).
    #[error(transparent)]
    Spectrum(#[from] SpectrumError),
    /// An SSM model could not be computed.
    #[error(transparent)]
    Ssm(#[from] SsmError),
}

/// Runs the study `spec` on the plugin's model `model` (validated into
/// `system`), comparing `outputs`; its SSM models take the rest of their
/// spec from `ssm` and the eigensolver's from `spectrum`. Returns the study
/// and its warnings (a load sampled too coarsely, a model that failed on a
/// load).
pub fn study(
    spec: &PodSpec,
    (ssm, spectrum): (&SsmSpec, &SpectrumSpec),
    model: &ssm_api::Model,
    system: &System,
    outputs: &[&OutputMap],
    progress: &dyn Progress,
) -> Result<(PodStudy, Vec<String>), PodError> {
    run::pod_stage(spec, (ssm, spectrum), model, system, outputs, progress)
}

/// The files of a study of the model named `model`.
pub fn files(model: &str, study: &PodStudy) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
    let mut files = vec![
        (
            "pod_comparison.csv".to_owned(),
            write::comparison_csv(study).into_bytes(),
        ),
        (
            "pod_report.md".to_owned(),
            write::report_md(model, study).into_bytes(),
        ),
        (
            "pod_povs.csv".to_owned(),
            write::povs_csv(study).into_bytes(),
        ),
        (
            "pod_povs.svg".to_owned(),
            write::povs_svg(study)?.into_bytes(),
        ),
        (
            "pod_errors.svg".to_owned(),
            write::errors_svg(study)?.into_bytes(),
        ),
        (
            "pod_constraints.csv".to_owned(),
            write::constraints_csv(study).into_bytes(),
        ),
    ];
    for (k, case) in study.cases.iter().enumerate() {
        files.push((
            format!("pod_case_{}.csv", k + 1),
            write::case_csv(study, case).into_bytes(),
        ));
    }
    Ok(files)
}
