//! Running a [`Plan`] on a model, one stage after the other: the POD
//! study, the spectral stage, the SSM (one expansion per order tried), and
//! the analyses of [`crate::analyses`] in the plan's order: those of the
//! reduced model on every SSM tried while the expansion order is chosen
//! (backbone, invariance error, transient, forced response, ...), then,
//! once, those of the full system on the SSM chosen (`[validate]`,
//! `[reference]`, `[report]`, `[simulate]`). Each returns typed results;
//! [`crate::output`] and the analyses' writers turn them into files.
//! Nothing here reads a scene: a plan comes from code or from
//! [`crate::plan::resolve`].
//!
//! Adding an analysis: one folder under [`crate::analyses`] holding its spec,
//! run and writer, and one line in its registry; the scene's
//! `[analysis.<name>]` table reaches it through the plan and the one gate,
//! and [`execute`] needs no change.

use std::time::Instant;

pub use crate::error::JobError;
pub use crate::progress::{Progress, Quiet};
pub use ssm_core::ssm::spectral::Spectral;

use crate::analyses::frc::Frc;
use crate::analyses::pod::PodError;
use crate::analyses::reference::Reference;
use crate::analyses::report::SpeedReport;
use crate::analyses::validation::Validate;
use crate::analyses::{self, Analysis, Answers, Beside, Context, Finished, Phase};
use crate::output::summary::{Summary, Timing};
use crate::output::{pod_only_files, result_files, OutputSet, Products};
use crate::plan::budget::{self, Limits};
use crate::plan::{named_outputs, Plan};
use crate::C64;
use ssm_core::compare::pod::PodStudy;
use ssm_core::compare::report::Report;
use ssm_core::compare::validation::Validation;
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::model::plugin::PluginOrigin;
use ssm_core::model::system::{OutputMap, System};
use ssm_core::reduce::Reduction;
use ssm_core::rom::accuracy::{percent, Accuracy, AnswerEstimate, OrdersTried};
use ssm_core::rom::forced_response::ForcedResponse;
use ssm_core::spectrum::{MasterMode, Spectrum, SpectrumError};
use ssm_core::ssm::analysis::polar;
use ssm_core::ssm::{self, Dynamics, SsmExpansion, SsmOptions};

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

impl JobResult {
    /// The results of a `[pod]` scene that asks for no SSM answer.
    fn pod_only(
        system: System,
        pod: Option<PodStudy>,
        warnings: Vec<String>,
        plugins: Vec<PluginOrigin>,
        outputs: OutputSet,
    ) -> Self {
        Self {
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
        }
    }
}

/// The SSM at one order and every answer read off it, with the seconds spent.
struct Reduced {
    expansion: SsmExpansion,
    analyses: Vec<Box<dyn Finished>>,
    estimates: Vec<AnswerEstimate>,
    ssm_s: f64,
    results_s: f64,
    frc_s: f64,
}

/// The seconds of the analyses of one phase.
struct Ran {
    /// Seconds of all but the forced response.
    results_s: f64,
    /// Seconds of the forced response.
    frc_s: f64,
    /// Seconds of each analysis, by name.
    each: Vec<(&'static str, f64)>,
}

impl Ran {
    /// The seconds of the analysis `name` (0 when it did not run).
    fn of(&self, name: &str) -> f64 {
        self.each
            .iter()
            .filter(|(n, _)| *n == name)
            .map(|(_, s)| s)
            .sum()
    }
}

/// The model a plan runs on.
#[derive(Debug, Clone)]
pub struct Model {
    /// The validated system the analyses run on.
    pub system: System,
    /// The reducer's record when a reducer made `system`.
    pub reduction: Option<Reduction>,
    /// The model as its plugin gave it, for a POD study (which projects it).
    pub full: Option<ssm_api::Model>,
    /// The plugin libraries that made it.
    pub plugins: Vec<PluginOrigin>,
}

/// What every order tried shares.
struct Stage<'a> {
    plan: &'a Plan,
    system: &'a System,
    sp: &'a Spectral,
    others: &'a [C64],
    coordinates: &'a [&'a OutputMap],
    progress: &'a dyn Progress,
    /// The `[data]` signals of a model identified from them.
    signals: Option<&'a ssm_api::Signals>,
    /// The highest order the analyses of `[analysis]` name.
    analysis_orders: usize,
}

impl Stage<'_> {
    /// The SSM to `order`, the analyses of the plan (among them the
    /// backbone, the invariance error and the transient of `[outputs]`), the
    /// forced response of `[forcing]`, and their estimates.
    fn at(&self, order: usize) -> Result<Reduced, JobError> {
        let (sys, masters) = (self.system, &self.sp.masters);
        self.progress.stage(&format!("SSM to order {order}"));
        let t = Instant::now();
        let options = SsmOptions {
            order,
            resonance_tol: self.plan.ssm.resonance_tol,
        };
        let expansion = ssm::compute(sys, masters, self.others, &options)?;
        let ssm_s = t.elapsed().as_secs_f64();

        self.progress
            .stage("backbone, invariance error, transients");
        let mut analyses = Vec::new();
        let Ran {
            results_s, frc_s, ..
        } = self.analyses(&expansion, Phase::Reduced, &mut analyses)?;
        let estimates = estimates(&analyses);
        Ok(Reduced {
            expansion,
            analyses,
            estimates,
            ssm_s,
            results_s,
            frc_s,
        })
    }

    /// The analyses of the plan of `phase` on `expansion`, in the plan's
    /// order, added to `done` (each reads the results of those before it);
    /// their seconds.
    fn analyses(
        &self,
        expansion: &SsmExpansion,
        phase: Phase,
        done: &mut Vec<Box<dyn Finished>>,
    ) -> Result<Ran, JobError> {
        let base = Context::new(
            self.system,
            &self.sp.masters,
            expansion,
            self.coordinates,
            self.plan.ssm.tolerance,
        )
        .with_signals(self.signals)
        .with_others(self.others)
        .with_progress(self.progress);
        let (mut results_s, mut frc_s) = (0.0, 0.0);
        let mut each = Vec::new();
        for a in self.plan.requested() {
            let entry = analyses::find(&a.name)?;
            if entry.phase() != phase {
                continue;
            }
            if let Some(stage) = entry.stage() {
                self.progress.stage(stage);
            }
            let t = Instant::now();
            let finished = entry.run(&a.spec, &base.with_earlier(done));
            done.push(finished.map_err(JobError::of_analysis)?);
            let spent = t.elapsed().as_secs_f64();
            each.push((entry.name(), spent));
            *if a.name == Frc::NAME {
                &mut frc_s
            } else {
                &mut results_s
            } += spent;
        }
        Ok(Ran {
            results_s,
            frc_s,
            each,
        })
    }

    /// The SSM at the `[ssm] order` (`ceiling`), or at the order chosen by
    /// [`Self::choose`], its answers, and the accuracy table of their
    /// estimates; the seconds spent go into `timing`.
    fn reduce(
        &self,
        ceiling: usize,
        warnings: &mut Vec<String>,
        timing: &mut Timing,
    ) -> Result<(Reduced, Accuracy), JobError> {
        let ssm = &self.plan.ssm;
        let (mut reduced, tried) = match &ssm.order {
            Some(_) => (self.at(ceiling)?, Vec::new()),
            None => self.choose(ceiling, warnings)?,
        };
        timing.ssm = reduced.ssm_s;
        timing.results = reduced.results_s;
        timing.frc = reduced.frc_s;
        let accuracy = Accuracy {
            tolerance: ssm.tolerance,
            order: reduced.expansion.order,
            chosen: ssm.order.is_none(),
            tried,
            answers: std::mem::take(&mut reduced.estimates),
            measured: Vec::new(),
        };
        Ok((reduced, accuracy))
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
        let tolerance = self.plan.ssm.tolerance;
        let named = self.plan.highest_named_order().max(self.analysis_orders);
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

/// The error estimate of every estimated answer, in the plan's order
/// ([`Plan::requested`]: backbone, transient, forced response, then the
/// analyses of `[analysis]`).
fn estimates(analyses: &[Box<dyn Finished>]) -> Vec<AnswerEstimate> {
    analyses.iter().flat_map(|a| a.estimates()).collect()
}

/// Runs `plan` on `model` within `limits` and assembles its outputs
/// (nothing is written here); `started` is when the run began (the model's
/// building counts in the total time). The plan is checked against the
/// model first ([`Plan::check`]); the estimates that need the master modes
/// run after the spectrum, before the SSM.
pub fn execute(
    plan: &Plan,
    model: Model,
    limits: &Limits,
    progress: &dyn Progress,
    started: Instant,
) -> Result<JobResult, JobError> {
    let t0 = started;
    let Model {
        system,
        reduction,
        full: full_model,
        plugins,
    } = model;
    let ceiling = plan.check(&system, limits)?;
    let analysis_orders = highest_analysis_order(plan)?;
    let mut timing = Timing::default();
    let mut warnings = Vec::new();
    // one gate: every request is costed against the same limits before it
    // runs (the POD study first, since it runs before the spectrum)
    let pod = pod_study(plan, &system, full_model.as_ref(), progress)?;
    let pod = pod.map(|(study, w, seconds)| {
        warnings.extend(w);
        timing.pod = seconds;
        study
    });
    if !plan.wants_ssm() {
        progress.stage("writing outputs");
        timing.total = t0.elapsed().as_secs_f64();
        let outputs = pod_only_files(&system, &plugins, pod.as_ref(), &warnings, timing)?;
        return Ok(JobResult::pod_only(system, pod, warnings, plugins, outputs));
    }
    let coordinates = named_outputs(&system, &plan.coordinates, "outputs.coordinates")?;

    progress.stage("spectrum");
    let sp = spectral(
        &plan.ssm,
        &plan.spectrum,
        &system,
        ceiling,
        "ssm.master_pairs",
    )?;
    timing.spectrum = sp.spectrum_s;
    timing.resonance_check = sp.resonance_s;
    budget::check(plan, &system, &sp.masters, ceiling, limits)?;
    budget::check_analyses(plan, &system, &sp.masters, ceiling, limits)?;

    let others: Vec<C64> = ssm::non_master(&sp.spectrum.eigenvalues, &sp.masters);
    let stage = Stage {
        plan,
        system: &system,
        sp: &sp,
        others: &others,
        coordinates: &coordinates,
        progress,
        signals: reduction.as_ref().and_then(|r| r.signals.as_ref()),
        analysis_orders,
    };
    warnings.extend(sp.warnings.iter().cloned());
    warnings.extend(reduction.iter().flat_map(reducer_warnings));
    let (reduced, mut accuracy) = stage.reduce(ceiling, &mut warnings, &mut timing)?;
    let Reduced {
        expansion,
        mut analyses,
        ..
    } = reduced;
    let full = stage.analyses(&expansion, Phase::FullSystem, &mut analyses)?;
    timing.validation = full.of(Validate::NAME);
    timing.reference = full.of(Reference::NAME);
    accuracy.measured = analyses.iter().flat_map(|a| a.measured()).collect();
    let validation = analyses::output_of::<Validate>(&analyses).map(|c| &c.0);
    let reference = analyses::output_of::<Reference>(&analyses).map(|r| &r.frc);
    timing.report = full.of(SpeedReport::NAME);

    warnings.extend(analyses.iter().flat_map(|a| a.warnings()));
    progress.stage("writing outputs");
    let polar_form = (expansion.dynamics == Dynamics::Flow)
        .then(|| polar(&expansion).ok())
        .flatten();
    let names: Vec<String> = coordinates.iter().map(|o| o.name.clone()).collect();
    let pairs = &plan.ssm.master_pairs;
    timing.total = t0.elapsed().as_secs_f64();
    let modal = sp.spectrum.modal_figures();
    let mut answers_of_analyses = Answers::default();
    for a in &analyses {
        a.summarize(&mut answers_of_analyses);
    }
    let mut outputs = result_files(&Products {
        modal: &modal,
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
            pod: pod.as_ref(),
            answers: &answers_of_analyses,
            accuracy: &accuracy,
            warnings: &warnings,
            timing,
        },
    })?;
    let beside = Beside {
        steady: validation.and_then(|v| v.steady.as_ref()),
        reference,
    };
    add_analysis_files(&mut outputs, &analyses, &names, &beside)?;
    Ok(JobResult {
        system,
        spectrum: Some(sp.spectrum),
        masters: sp.masters,
        ssm: Some(expansion),
        pod,
        frc: analyses::output_of::<Frc>(&analyses).map(|f| f.0.clone()),
        reference: reference.cloned(),
        validation: validation.cloned(),
        report: analyses::output_of::<SpeedReport>(&analyses).map(|r| r.report.clone()),
        warnings,
        plugins,
        outputs,
    })
}

/// The highest expansion order the analyses of `[analysis]` name (1
/// without any).
fn highest_analysis_order(plan: &Plan) -> Result<usize, JobError> {
    let mut highest = 1;
    for a in plan.requested() {
        let orders = analyses::find(&a.name)?.orders(&a.spec)?;
        highest = orders.into_iter().fold(highest, usize::max);
    }
    Ok(highest)
}

/// The files of the analyses, added to `out`; `names` are those of
/// `[outputs] coordinates`, `beside` the full-system answers they may draw.
fn add_analysis_files(
    out: &mut OutputSet,
    analyses: &[Box<dyn Finished>],
    names: &[String],
    beside: &Beside<'_>,
) -> Result<(), JobError> {
    for a in analyses {
        for (name, contents) in a.files(names, beside)? {
            out.add(&name, contents);
        }
    }
    Ok(())
}

/// The POD study of the plugin's `model` (costed by [`Plan::check`]), its
/// warnings and seconds.
fn pod_study(
    plan: &Plan,
    system: &System,
    model: Option<&ssm_api::Model>,
    progress: &dyn Progress,
) -> Result<Option<(PodStudy, Vec<String>, f64)>, JobError> {
    let (Some(spec), Some(model)) = (&plan.pod, model) else {
        return Ok(None);
    };
    let t = Instant::now();
    let outputs = crate::plan::pod_outputs(plan, system)?;
    let (study, w) = analyses::pod::study(
        spec,
        (&plan.ssm, &plan.spectrum),
        model,
        system,
        &outputs,
        progress,
    )
    .map_err(|e| match e {
        PodError::Study(e) => JobError::Pod(e),
        PodError::Ssm(e) => JobError::Ssm(e),
        PodError::Spectrum(e @ SpectrumError::PairOutOfRange { .. }) => {
            JobError::Plan(crate::plan::PlanError::new("pod.ssm_pairs", e.to_string()))
        }
        PodError::Spectrum(e) => JobError::Spectrum(e),
    })?;
    Ok(Some((study, w, t.elapsed().as_secs_f64())))
}

/// The warnings among a reducer's diagnostics.
fn reducer_warnings(r: &Reduction) -> Vec<String> {
    r.diagnostics
        .iter()
        .filter(|d| d.name.starts_with("warning"))
        .map(|d| format!("reducer '{}': {}", r.reducer, d.text))
        .collect()
}

/// The spectral stage of `ssm` ([`ssm_core::ssm::spectral::spectral`]); a
/// master pair beyond the spectrum is the plan's error at `key`.
pub(crate) fn spectral(
    ssm: &ssm_core::spec::SsmSpec,
    spectrum: &ssm_core::spec::SpectrumSpec,
    system: &System,
    order: usize,
    key: &str,
) -> Result<Spectral, JobError> {
    ssm_core::ssm::spectral::spectral(ssm, spectrum, system, order).map_err(|e| match e {
        ssm_core::spectrum::SpectrumError::PairOutOfRange { .. } => {
            JobError::Plan(crate::plan::PlanError::new(key, e.to_string()))
        }
        other => JobError::Spectrum(other),
    })
}
