//! Running a scene, one stage after the other: the model (built by a plugin
//! or made by a reducer), the spectral stage, the SSM, the answers read off
//! the reduced model (backbone, invariance error, transient, forced response),
//! the full-system comparisons and the speed-against-error report. Each stage
//! returns typed results; [`crate::output`] turns them into files.
//!
//! Adding an analysis: its numerics in its module (returning a typed result),
//! its scene section in [`crate::scene`], its writer in [`crate::output`], and
//! one call in [`run`].

pub mod budget;
mod checks;
mod error;
mod spectral;

use std::path::PathBuf;
use std::time::Instant;

pub use error::JobError;
pub use spectral::Spectral;

use crate::compare::report::{report, Report, ReportInputs};
use crate::compare::validation::{validation, Validation};
use crate::model::plugin::{PluginOrigin, Registry};
use crate::model::source::build_model;
use crate::model::system::{OutputMap, System};
use crate::output::summary::{Summary, Timing};
use crate::output::{result_files, OutputSet, Products};
use crate::reduce::scene::reduce_scene;
use crate::reduce::Reduction;
use crate::rom::autonomous::{self, BackboneCurve, InvarianceEntry, LiftedTransient};
use crate::rom::forced_response::{forced_response, ForcedResponse};
use crate::scene::SceneFile;
use crate::spectrum::{MasterMode, Spectrum};
use crate::ssm::analysis::polar;
use crate::ssm::{self, Dynamics, SsmExpansion, SsmOptions};
use crate::C64;

/// Stages reported to a progress display.
pub trait Progress {
    /// A new stage begins.
    fn stage(&self, name: &str);
}

/// No progress display.
pub struct Quiet;

impl Progress for Quiet {
    fn stage(&self, _name: &str) {}
}

/// Everything a run computed.
#[derive(Debug)]
pub struct JobResult {
    /// The validated system.
    pub system: System,
    /// Finite spectrum.
    pub spectrum: Spectrum,
    /// Master modes.
    pub masters: Vec<MasterMode>,
    /// The SSM.
    pub ssm: SsmExpansion,
    /// Forced response curves of `[forcing]`.
    pub frc: Option<ForcedResponse>,
    /// Full-system comparisons of `[validate]`.
    pub validation: Option<Validation>,
    /// Speed-against-error report.
    pub report: Option<Report>,
    /// Warnings (resonances, ...).
    pub warnings: Vec<String>,
    /// The plugin libraries the run used (model, reducer).
    pub plugins: Vec<PluginOrigin>,
    /// Files to write.
    pub outputs: OutputSet,
}

/// The answers read off the autonomous reduced model.
struct Autonomous {
    invariance: Option<Vec<InvarianceEntry>>,
    backbone: Option<Vec<BackboneCurve>>,
    transient: Option<LiftedTransient>,
}

/// Backbone, invariance error and reduced transient of `[outputs]`.
fn autonomous_answers(
    scene: &SceneFile,
    expansion: &SsmExpansion,
    system: &System,
    coordinates: &[&OutputMap],
) -> Result<Autonomous, JobError> {
    let out = &scene.scene.outputs;
    Ok(Autonomous {
        invariance: out
            .invariance_error
            .as_ref()
            .map(|sec| autonomous::invariance_table(expansion, system, sec))
            .transpose()?,
        backbone: out
            .backbone
            .as_ref()
            .map(|sec| autonomous::backbone(expansion, sec, coordinates))
            .transpose()?,
        transient: out
            .transient
            .as_ref()
            .map(|sec| autonomous::transient(expansion, sec, coordinates))
            .transpose()?,
    })
}

/// The orders of the report: those of `[report]`, else the odd orders from 3
/// up to the `[ssm]` order, which is always included.
fn report_orders(scene: &SceneFile) -> Vec<usize> {
    let max = *scene.scene.ssm.order.get_ref();
    scene
        .scene
        .report
        .as_ref()
        .and_then(|r| r.orders.as_ref())
        .map_or_else(
            || {
                let mut o: Vec<usize> = (1..=max).filter(|k| k % 2 == 1 && *k >= 3).collect();
                if o.last() != Some(&max) {
                    o.push(max);
                }
                o
            },
            |o| o.get_ref().clone(),
        )
}

/// Runs a scene and assembles its outputs (nothing is written here).
pub fn run(
    scene: &SceneFile,
    registry: &mut Registry,
    progress: &dyn Progress,
) -> Result<JobResult, JobError> {
    let t0 = Instant::now();
    let sc = &scene.scene;
    let mut timing = Timing::default();
    progress.stage("building model");
    registry.take_used();
    let (system, reduction) = obtain_model(scene, registry)?;
    let plugins = registry.take_used();
    let coordinates = checks::coordinates(scene, &system)?;

    let limits = budget::Limits::of_machine();
    budget::check_spectrum(scene, &system, &limits)?;
    progress.stage("spectrum");
    let sp = spectral::spectral(scene, &system)?;
    timing.spectrum = sp.spectrum_s;
    timing.resonance_check = sp.resonance_s;
    budget::check(scene, &system, &sp.masters, &limits)?;

    progress.stage("SSM");
    let t = Instant::now();
    let others: Vec<C64> = ssm::non_master(&sp.spectrum.eigenvalues, &sp.masters);
    let ssm_options = SsmOptions {
        order: *sc.ssm.order.get_ref(),
        resonance_tol: *sc.ssm.resonance_tol.get_ref(),
    };
    let expansion = ssm::compute(&system, &sp.masters, &others, &ssm_options)?;
    timing.ssm = t.elapsed().as_secs_f64();

    progress.stage("backbone, invariance error, transients");
    let t = Instant::now();
    let answers = autonomous_answers(scene, &expansion, &system, &coordinates)?;
    timing.results = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let frc = sc
        .forcing
        .as_ref()
        .map(|sec| {
            progress.stage("forced response curves");
            forced_response(
                &expansion,
                &system,
                &sp.masters,
                sec,
                &coordinates,
                *sc.ssm.tolerance.get_ref(),
            )
        })
        .transpose()?;
    timing.frc = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut compared = coordinates.clone();
    let checked = match &sc.validate {
        Some(vsec) => {
            progress.stage("full-system validation");
            compared = checks::validation_outputs(scene, &system, vsec, &coordinates)?;
            Some(validation(
                &expansion,
                &system,
                vsec,
                &compared,
                &coordinates,
                &sp.masters,
                frc.as_ref().map(|f| f.rows.as_slice()),
            )?)
        }
        None => None,
    };
    timing.validation = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let speed = match &sc.report {
        Some(_) => {
            progress.stage("speed-against-error report");
            let orders = report_orders(scene);
            let inputs = ReportInputs {
                orders: &orders,
                masters: &sp.masters,
                others: &others,
                resonance_tol: ssm_options.resonance_tol,
                outputs: &compared,
                forcing: sc.forcing.as_ref(),
                validation: checked.as_ref(),
                p0: checked
                    .as_ref()
                    .and_then(|v| v.transient.as_ref())
                    .map(|t| t.result.p0.clone()),
                rtol: sc.validate.as_ref().map_or(1e-8, |v| *v.rtol.get_ref()),
                tolerance: *sc.ssm.tolerance.get_ref(),
            };
            Some(report(&system, &inputs)?)
        }
        None => None,
    };
    timing.report = t.elapsed().as_secs_f64();

    let mut warnings = sp.warnings.clone();
    if let Some(f) = &frc {
        warnings.extend(f.warnings.iter().cloned());
    }
    progress.stage("writing outputs");
    let polar_form = (expansion.dynamics == Dynamics::Flow)
        .then(|| polar(&expansion).ok())
        .flatten();
    let names: Vec<String> = coordinates.iter().map(|o| o.name.clone()).collect();
    let pairs = sc.ssm.master_pairs.get_ref();
    timing.total = t0.elapsed().as_secs_f64();
    let modal = sp.spectrum.modal_figures();
    let outputs = result_files(&Products {
        coordinates: &names,
        modal: &modal,
        backbone: answers.backbone.as_deref(),
        transient: answers.transient.as_ref(),
        summary: Summary {
            system: &system,
            plugins: &plugins,
            n_finite_modes: sp.n_finite,
            reduction: reduction.as_ref(),
            spectrum: &sp.spectrum,
            master_pairs: pairs,
            masters: &sp.masters,
            quotients: &sp.resonances.quotients,
            ssm: &expansion,
            polar: polar_form.as_ref(),
            invariance: answers.invariance.as_deref(),
            rom_steps: answers.transient.as_ref().map(|t| t.steps),
            frc: frc.as_ref(),
            validation: checked.as_ref(),
            report: speed.as_ref(),
            warnings: &warnings,
            timing,
        },
    })?;
    Ok(JobResult {
        system,
        spectrum: sp.spectrum,
        masters: sp.masters,
        ssm: expansion,
        frc,
        validation: checked,
        report: speed,
        warnings,
        plugins,
        outputs,
    })
}

/// The model the analyses run on: the plugin's model of `[model]`, or the
/// model the reducer of `[reduce]` makes from it and/or the `[data]` signals;
/// validated into a [`System`].
pub fn obtain_model(
    scene: &SceneFile,
    registry: &mut Registry,
) -> Result<(System, Option<Reduction>), JobError> {
    let sc = &scene.scene;
    let full = sc
        .model
        .as_ref()
        .map(|m| build_model(scene, m, registry))
        .transpose()?;
    match &sc.reduce {
        Some(red) => {
            let (system, reduction) = reduce_scene(scene, red, full, registry)?;
            Ok((system, Some(reduction)))
        }
        None => {
            let (plugin, model) = full.ok_or_else(|| {
                scene.invalid(0..0, "model", "the scene has no [model] section".into())
            })?;
            Ok((System::from_model(&plugin, model)?, None))
        }
    }
}

/// Default output directory of a scene: `./out/<scene name>`.
pub fn default_out_dir(scene: &SceneFile) -> PathBuf {
    PathBuf::from("out").join(scene.name())
}
