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
pub mod export;
mod pod;
mod pod_reducer;
mod reduce;
mod reference;
mod simulate;
pub mod source;
mod spectral;

use std::path::PathBuf;
use std::time::Instant;

pub use error::JobError;
pub use spectral::Spectral;

use crate::analyses::{self, Context, Finished};
use crate::compare::instantaneous::{data_backbones, near_frequency, DataBackbone};
use crate::compare::pod::PodStudy;
use crate::compare::report::{report, Report, ReportInputs};
use crate::compare::validation::{validation, Validation};
use crate::continuation::Ledger;
use crate::fom::periodic::frc::{ReferenceFrc, ReferenceOrbit};
use crate::fom::periodic::OrbitInfo;
use crate::model::plugin::{PluginOrigin, Registry};
use crate::model::system::{OutputMap, System};
use crate::output::summary::{Summary, Timing};
use crate::output::{pod_only_files, result_files, OutputSet, Products};
use crate::plan::{self, AnswerSpecs};
use crate::reduce::Reduction;
use crate::rom::accuracy::{percent, Accuracy, AnswerEstimate, MeasuredError, OrdersTried};
use crate::rom::autonomous::{self, BackboneCurve, InvarianceEntry, LiftedTransient};
use crate::rom::forced_response::{forced_response, ForcedResponse};
use crate::scene::SceneFile;
use crate::spec::ValidationSpec;
use crate::spectrum::{MasterMode, Spectrum};
use crate::ssm::analysis::polar;
use crate::ssm::{self, Dynamics, SsmExpansion, SsmOptions};
use crate::C64;
use reduce::reduce_scene;
use source::build_model;

/// Stages reported to a progress display.
pub trait Progress {
    /// A new stage begins.
    fn stage(&self, name: &str);
    /// Where a long stage is (e.g. the frequency a continuation reached);
    /// a display may show it in place of the stage's name.
    fn detail(&self, _what: &str) {}
    /// One orbit of the full-system reference (`[reference]`), as it is
    /// accepted, with the names of its output amplitudes: a display may write
    /// it down, so that a run stopped before its outputs are written keeps
    /// what it computed.
    fn reference_orbit(&self, _outputs: &[String], _orbit: &ReferenceOrbit) {}
    /// The ledger of the full-system reference's continuation runs: a
    /// checkpoint that keeps each step, from which a stopped run resumes
    /// (none by default).
    fn checkpoint(&self) -> Option<&dyn Ledger<OrbitInfo>> {
        None
    }
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
    /// Finite spectrum (`None`: a `[pod]` scene that asks for no SSM answer).
    pub spectrum: Option<Spectrum>,
    /// Master modes.
    pub masters: Vec<MasterMode>,
    /// The SSM.
    pub ssm: Option<SsmExpansion>,
    /// The `[pod]` study.
    pub pod: Option<PodStudy>,
    /// Forced response curves of `[forcing]`.
    pub frc: Option<ForcedResponse>,
    /// The full system's forced responses of `[reference]`.
    pub reference: Option<ReferenceFrc>,
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

/// The SSM at one order and every answer read off it, with the seconds spent.
struct Reduced {
    expansion: SsmExpansion,
    answers: Autonomous,
    analyses: Vec<Box<dyn Finished>>,
    frc: Option<ForcedResponse>,
    estimates: Vec<AnswerEstimate>,
    ssm_s: f64,
    results_s: f64,
    frc_s: f64,
}

/// What every order tried shares.
struct Stage<'a> {
    scene: &'a SceneFile,
    specs: &'a AnswerSpecs,
    system: &'a System,
    sp: &'a Spectral,
    others: &'a [C64],
    coordinates: &'a [&'a OutputMap],
    progress: &'a dyn Progress,
    /// The highest order the analyses of `[analysis]` name.
    analysis_orders: usize,
}

impl Stage<'_> {
    /// The SSM to `order`, the backbone, invariance error and transient of
    /// `[outputs]`, the forced response of `[forcing]`, and their estimates.
    fn at(&self, order: usize) -> Result<Reduced, JobError> {
        let sc = &self.scene.scene;
        let tolerance = *sc.ssm.tolerance.get_ref();
        let (sys, masters) = (self.system, &self.sp.masters);
        self.progress.stage(&format!("SSM to order {order}"));
        let t = Instant::now();
        let options = SsmOptions {
            order,
            resonance_tol: *sc.ssm.resonance_tol.get_ref(),
        };
        let expansion = ssm::compute(sys, masters, self.others, &options)?;
        let ssm_s = t.elapsed().as_secs_f64();

        self.progress
            .stage("backbone, invariance error, transients");
        let t = Instant::now();
        let specs = self.specs;
        let answers = Autonomous {
            invariance: specs
                .invariance
                .as_ref()
                .map(|sec| autonomous::invariance_table(&expansion, sys, sec))
                .transpose()?,
            backbone: specs
                .backbone
                .as_ref()
                .map(|sec| {
                    let coords = self.coordinates;
                    autonomous::backbone(&expansion, sys, &masters[0], sec, coords, tolerance)
                })
                .transpose()?,
            transient: specs
                .transient
                .as_ref()
                .map(|sec| {
                    let coords = self.coordinates;
                    autonomous::transient(&expansion, sys, masters, sec, coords, tolerance)
                })
                .transpose()?,
        };
        let cx = Context {
            system: sys,
            masters,
            ssm: &expansion,
            outputs: self.coordinates,
            tolerance,
        };
        let analyses = specs
            .analyses
            .iter()
            .map(|a| analyses::find(&a.name)?.run(&a.spec, &cx))
            .collect::<Result<Vec<_>, _>>()?;
        let results_s = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let frc = specs
            .frc
            .as_ref()
            .map(|sec| {
                self.progress.stage("forced response curves");
                forced_response(&expansion, sys, masters, sec, self.coordinates, tolerance)
            })
            .transpose()?;
        let frc_s = t.elapsed().as_secs_f64();
        let transient_order = specs
            .transient
            .as_ref()
            .and_then(|t| t.order)
            .unwrap_or(order);
        let mut estimates = estimates(&answers, transient_order, frc.as_ref());
        estimates.extend(analyses.iter().flat_map(|a| a.estimates()));
        Ok(Reduced {
            expansion,
            answers,
            analyses,
            frc,
            estimates,
            ssm_s,
            results_s,
            frc_s,
        })
    }

    /// Without an `[ssm] order`: the lowest odd order from the highest the
    /// answers name (at least 3) up to `ceiling` whose answers meet the
    /// tolerance; raising stops where two orders in a row bring no better
    /// estimate (the answers lie beyond the expansion's convergence radius)
    /// or an order cannot be computed, and the best order so far is kept.
    fn choose(
        &self,
        ceiling: usize,
        warnings: &mut Vec<String>,
    ) -> Result<(Reduced, OrdersTried), JobError> {
        let tolerance = *self.scene.scene.ssm.tolerance.get_ref();
        let named = self.scene.highest_named_order().max(self.analysis_orders);
        let mut order = named.max(3).min(ceiling);
        let mut tried = Vec::new();
        let mut best: Option<(f64, Reduced)> = None;
        let mut spent = [0.0; 3];
        let mut stalls = 0;
        loop {
            let reduced = match self.at(order) {
                Ok(r) => {
                    spent[0] += r.ssm_s;
                    spent[1] += r.results_s;
                    spent[2] += r.frc_s;
                    r
                }
                Err(e) if best.is_some() => {
                    warnings.push(format!(
                        "the engine could not raise the expansion order to {order} to meet [ssm] tolerance: {e}"
                    ));
                    break;
                }
                Err(e) => return Err(e),
            };
            let worst = Accuracy::worst(&reduced.estimates);
            tried.push((order, worst));
            let Some(e) = worst else {
                // nothing estimated: the lowest order serves
                best = Some((0.0, reduced));
                break;
            };
            if best.as_ref().is_none_or(|(b, _)| e < *b) {
                best = Some((e, reduced));
                stalls = 0;
            } else {
                stalls += 1;
            }
            // two orders in a row without a better estimate: the answers lie
            // beyond the convergence radius (one is not enough: the odd and
            // even halves of some series converge at different rates)
            if e <= tolerance || stalls == 2 || order + 2 > ceiling {
                break;
            }
            order += 2;
        }
        let (e, mut reduced) = best.expect("at least one order was computed");
        // the time of every order tried
        [reduced.ssm_s, reduced.results_s, reduced.frc_s] = spent;
        if e > tolerance {
            warnings.push(format!(
                "no expansion order up to {} meets the accuracy target {} ([ssm] tolerance); the answers are kept at order {} with an estimated error of {}: lower the amplitudes asked for (rho_max, rho0, epsilon) or widen the tolerance",
                tried.last().map_or(order, |t| t.0),
                percent(tolerance),
                reduced.expansion.order,
                percent(e),
            ));
        }
        Ok((reduced, tried))
    }
}

/// The error estimate of every estimated answer.
fn estimates(
    answers: &Autonomous,
    transient_order: usize,
    frc: Option<&ForcedResponse>,
) -> Vec<AnswerEstimate> {
    let mut list = Vec::new();
    for c in answers.backbone.iter().flatten() {
        list.push(AnswerEstimate {
            answer: "backbone",
            order: c.order,
            epsilon: None,
            estimate: c.error_estimate,
            untrusted: c.untrusted,
            trusted_up_to: c.trusted_up_to,
        });
    }
    if let Some(t) = &answers.transient {
        list.push(AnswerEstimate {
            answer: "transient",
            order: transient_order,
            epsilon: None,
            estimate: t.error_estimate,
            untrusted: t.untrusted,
            trusted_up_to: None,
        });
    }
    for c in frc.iter().flat_map(|f| &f.curves) {
        list.push(AnswerEstimate {
            answer: "frc",
            order: c.order,
            epsilon: Some(c.epsilon),
            estimate: Some(c.error_estimate()),
            untrusted: c.untrusted,
            trusted_up_to: None,
        });
    }
    list
}

/// The errors `[validate]` measured against the full system: the
/// transient's and each forced response curve's against the steady states.
fn measured_errors(v: &Validation) -> Vec<MeasuredError> {
    let mut list: Vec<MeasuredError> = v
        .transient
        .iter()
        .map(|t| MeasuredError {
            answer: "transient",
            order: t.order,
            epsilon: None,
            relative_error: Some(t.max_relative_error),
            output: t.relative_errors[..t.n_compared]
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map(|(k, _)| t.outputs[k].clone()),
            against: "full_transient",
        })
        .collect();
    for e in v.steady.iter().flat_map(|s| s.frc_errors.iter().flatten()) {
        list.push(MeasuredError {
            answer: "frc",
            order: e.order,
            epsilon: Some(e.epsilon),
            relative_error: e.max_relative_error,
            output: e.output.clone(),
            against: "steady_state",
        });
    }
    list
}

/// Loud warnings for the autonomous answers whose estimate exceeds the
/// tolerance (forced responses warn where they are computed).
fn untrusted_warnings(estimates: &[AnswerEstimate], tolerance: f64) -> Vec<String> {
    estimates
        .iter()
        .filter(|a| a.untrusted && matches!(a.answer, "backbone" | "transient"))
        .map(|a| {
            format!(
                "{} O({}): the estimated error, {}, exceeds the accuracy target {} ([ssm] tolerance){}; do not trust it: {}",
                a.answer,
                a.order,
                percent(a.estimate.unwrap_or(f64::NAN)),
                percent(tolerance),
                a.trusted_up_to
                    .map_or(String::new(), |r| format!(" beyond rho = {r:.4}")),
                if a.answer == "backbone" {
                    "lower [outputs.backbone] rho_max or raise the expansion order"
                } else {
                    "start nearer the equilibrium (rho0), shorten t_end or raise the expansion order"
                }
            )
        })
        .collect()
}

/// The orders of the report: those of `[report]`, else the odd orders from 3
/// up to the expansion order `max`, which is always included.
fn report_orders(scene: &SceneFile, max: usize) -> Vec<usize> {
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
    // the scene resolved to specs first: a mistake in an analysis's table
    // is reported before any model is built
    let specs = plan::answers(scene)?;
    let analysis_orders = specs
        .analyses
        .iter()
        .map(|a| analyses::find(&a.name)?.orders(&a.spec))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
        .fold(1, usize::max);
    let mut timing = Timing::default();
    progress.stage("building model");
    registry.take_used();
    let (system, reduction, full_model) = obtain_model(scene, registry)?;
    let plugins = registry.take_used();
    let mut warnings = Vec::new();
    // one gate: every request is costed against the same limits before it
    // runs ([pod] first, since it runs before the spectrum)
    let limits = budget::Limits::of_machine();
    let pod = match (&sc.pod, &full_model) {
        (Some(sec), Some(model)) => {
            budget::check_pod(scene, &system, &limits)?;
            let t = Instant::now();
            let (study, w) = pod::pod_stage(scene, sec, model, &system, progress)?;
            warnings.extend(w);
            timing.pod = t.elapsed().as_secs_f64();
            Some(study)
        }
        _ => None,
    };
    if !scene.wants_ssm() {
        progress.stage("writing outputs");
        timing.total = t0.elapsed().as_secs_f64();
        let outputs = pod_only_files(&system, &plugins, pod.as_ref(), &warnings, timing)?;
        return Ok(JobResult {
            system,
            spectrum: None,
            masters: Vec::new(),
            ssm: None,
            pod,
            frc: None,
            reference: None,
            validation: None,
            report: None,
            warnings,
            plugins,
            outputs,
        });
    }
    let coordinates = checks::coordinates(scene, &system)?;

    let ceiling = budget::check_spectrum(scene, &system, &limits)?;
    progress.stage("spectrum");
    let sp = spectral::spectral(scene, &system, ceiling)?;
    timing.spectrum = sp.spectrum_s;
    timing.resonance_check = sp.resonance_s;
    budget::check(scene, &system, &sp.masters, ceiling, &limits)?;
    budget::check_reference(scene, &system, &limits)?;
    budget::check_analyses(
        scene,
        &specs.analyses,
        &sp.masters,
        ceiling,
        &coordinates,
        &limits,
    )?;

    let others: Vec<C64> = ssm::non_master(&sp.spectrum.eigenvalues, &sp.masters);
    let stage = Stage {
        scene,
        specs: &specs,
        system: &system,
        sp: &sp,
        others: &others,
        coordinates: &coordinates,
        progress,
        analysis_orders,
    };
    warnings.extend(sp.warnings.iter().cloned());
    if let Some(r) = &reduction {
        warnings.extend(
            r.diagnostics
                .iter()
                .filter(|d| d.name.starts_with("warning"))
                .map(|d| format!("reducer '{}': {}", r.reducer, d.text)),
        );
    }
    let tolerance = *sc.ssm.tolerance.get_ref();
    let (reduced, tried) = match &sc.ssm.order {
        Some(_) => (stage.at(ceiling)?, Vec::new()),
        None => stage.choose(ceiling, &mut warnings)?,
    };
    let Reduced {
        expansion,
        answers,
        analyses,
        frc,
        estimates,
        ..
    } = reduced;
    timing.ssm = reduced.ssm_s;
    timing.results = reduced.results_s;
    timing.frc = reduced.frc_s;
    let mut accuracy = Accuracy {
        tolerance,
        order: expansion.order,
        chosen: sc.ssm.order.is_none(),
        tried,
        answers: estimates,
        measured: Vec::new(),
    };

    let full_frc = match &sc.reference {
        Some(sec) => {
            let (r, w) = reference::reference_stage(
                scene,
                sec,
                &system,
                &coordinates,
                frc.as_ref().map(|f| (&expansion, f)),
                tolerance,
                progress,
            )?;
            warnings.extend(w);
            timing.reference = r.seconds;
            Some(r)
        }
        None => None,
    };

    let t = Instant::now();
    let mut compared = coordinates.clone();
    let checked = match (&sc.validate, &specs.validation) {
        (Some(vsec), Some(vspec)) => {
            progress.stage("full-system validation");
            compared = checks::validation_outputs(scene, &system, vsec, &coordinates)?;
            Some(validation(
                &expansion,
                &system,
                vspec,
                &compared,
                &coordinates,
                &sp.masters,
                frc.as_ref().map(|f| f.rows.as_slice()),
            )?)
        }
        _ => None,
    };
    accuracy.measured = checked.as_ref().map_or_else(Vec::new, measured_errors);
    if let (Some(f), Some(r)) = (&frc, &full_frc) {
        accuracy.measured.extend(reference::reference_errors(f, r));
    }
    timing.validation = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let speed = match &sc.report {
        Some(_) => {
            progress.stage("speed-against-error report");
            let orders = report_orders(scene, expansion.order);
            let inputs = ReportInputs {
                orders: &orders,
                masters: &sp.masters,
                others: &others,
                resonance_tol: *sc.ssm.resonance_tol.get_ref(),
                outputs: &compared,
                forcing: specs.frc.as_ref(),
                validation: checked.as_ref(),
                p0: checked
                    .as_ref()
                    .and_then(|v| v.transient.as_ref())
                    .map(|t| t.result.p0.clone()),
                rtol: specs
                    .validation
                    .as_ref()
                    .map_or(ValidationSpec::DEFAULT_RTOL, |v| v.rtol),
                tolerance: *sc.ssm.tolerance.get_ref(),
                reference: full_frc.as_ref(),
            };
            Some(report(&system, &inputs)?)
        }
        None => None,
    };
    timing.report = t.elapsed().as_secs_f64();

    let simulation = match &sc.simulate {
        Some(sec) => {
            progress.stage("sampling full-system runs");
            Some(simulate::simulate(
                scene,
                sec,
                &system,
                &expansion,
                &coordinates,
            )?)
        }
        None => None,
    };

    if let Some(f) = &frc {
        warnings.extend(f.warnings.iter().cloned());
    }
    warnings.extend(untrusted_warnings(&accuracy.answers, tolerance));
    warnings.extend(analyses.iter().flat_map(|a| a.warnings()));
    // the signals' own backbones, those decaying near the master pair's frequency
    let data_backbones = match (&reduction, answers.backbone.as_deref()) {
        (Some(r), Some([first, ..])) => r
            .signals
            .as_ref()
            .map(|sig| {
                let all = signal_backbones(sig, coordinates.first().map(|o| o.name.as_str()));
                let omega0 = first.points.first().map_or(0.0, |p| p.omega);
                near_frequency(all, omega0, 0.25)
            })
            .unwrap_or_default(),
        _ => Vec::new(),
    };
    progress.stage("writing outputs");
    let polar_form = (expansion.dynamics == Dynamics::Flow)
        .then(|| polar(&expansion).ok())
        .flatten();
    let names: Vec<String> = coordinates.iter().map(|o| o.name.clone()).collect();
    let pairs = sc.ssm.master_pairs.get_ref();
    timing.total = t0.elapsed().as_secs_f64();
    let modal = sp.spectrum.modal_figures();
    let analysis_summaries: Vec<(&str, serde_json::Value)> =
        analyses.iter().map(|a| (a.name(), a.summary())).collect();
    let mut outputs = result_files(&Products {
        coordinates: &names,
        modal: &modal,
        backbone: answers.backbone.as_deref(),
        data_backbones: &data_backbones,
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
            simulation: simulation.as_ref(),
            pod: pod.as_ref(),
            reference: full_frc.as_ref(),
            analyses: &analysis_summaries,
            accuracy: &accuracy,
            warnings: &warnings,
            timing,
        },
    })?;
    for a in &analyses {
        for (name, contents) in a.files(&names)? {
            outputs.add(&name, contents);
        }
    }
    Ok(JobResult {
        system,
        spectrum: Some(sp.spectrum),
        masters: sp.masters,
        ssm: Some(expansion),
        pod,
        frc,
        reference: full_frc,
        validation: checked,
        report: speed,
        warnings,
        plugins,
        outputs,
    })
}

/// The zero-crossing and Hilbert backbones of each `[data]` signal of the
/// observable `name` (the backbone's first output), when the data have it.
fn signal_backbones(sig: &ssm_api::Signals, name: Option<&str>) -> Vec<DataBackbone> {
    let Some(j) = name.and_then(|n| sig.names.iter().position(|c| c.as_str() == n)) else {
        return Vec::new();
    };
    let series: Vec<(String, Vec<f64>)> = (0..sig.trajectories.len())
        .map(|k| {
            let y = (0..sig.n_samples(k)).map(|i| sig.sample(k, i)[j]).collect();
            (sig.trajectories[k].source.to_string(), y)
        })
        .collect();
    data_backbones(&series, sig.period)
}

/// The model the analyses run on: the plugin's model of `[model]`, or the
/// model the reducer of `[reduce]` makes from it and/or the `[data]` signals;
/// validated into a [`System`]. With `[pod]`, the plugin's model as it was
/// given too (the POD reducer projects it).
pub fn obtain_model(
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
