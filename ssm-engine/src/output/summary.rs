//! `summary.json`: every typed result of a run, formatted; nothing is
//! computed here. The file is [`SummaryFile`] serialized; its JSON Schema
//! ([`schema_json`], kept in `docs/summary.schema.json`) is generated from
//! these types, and [`SCHEMA_VERSION`] changes with any change of shape.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::ssm::{PolarSummary, SsmSummary};
use crate::analyses::frc::FrcSummary;
use crate::analyses::invariance::InvarianceSummary;
use crate::analyses::pod::write::PodSummary;
use crate::analyses::reference::write::ReferenceSummary;
use crate::analyses::report::write::ReportSummary;
use crate::analyses::simulate::SimulationSummary;
use crate::analyses::validation::write::ValidationSummary;
use crate::analyses::Answers;
use crate::json::{diagnostics, Complex, Diagnostics, LinearWork};
use ssm_core::compare::pod::PodStudy;
use ssm_core::model::plugin::PluginOrigin;
use ssm_core::model::system::System;
use ssm_core::reduce::Reduction;
use ssm_core::rom::accuracy::Accuracy;
use ssm_core::spectrum::{MasterMode, SpectralQuotients, Spectrum};
use ssm_core::ssm::analysis::Polar;
use ssm_core::ssm::SsmExpansion;

/// Seconds spent per stage.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Timing {
    /// Spectrum and master modes.
    pub spectrum: f64,
    /// Non-resonance checks (eqs. 53, 57).
    pub resonance_check: f64,
    /// The SSM.
    pub ssm: f64,
    /// Backbone, invariance error, reduced transient.
    pub results: f64,
    /// Forced response curves.
    pub frc: f64,
    /// Full-system references.
    pub validation: f64,
    /// Speed-against-error report.
    pub report: f64,
    /// The `[pod]` study.
    pub pod: f64,
    /// The `[reference]` forced responses.
    pub reference: f64,
    /// The whole run.
    pub total: f64,
}

/// The results a run hands to `summary.json`.
pub(crate) struct Summary<'a> {
    /// The model analysed.
    pub system: &'a System,
    /// The plugin libraries that ran (model, reducer).
    pub plugins: &'a [PluginOrigin],
    /// Finite modes of the model (counted, or known from its structure).
    pub n_finite_modes: usize,
    /// The reduction that made the model, if any.
    pub reduction: Option<&'a Reduction>,
    /// The finite spectrum.
    pub spectrum: &'a Spectrum,
    /// Requested master pairs.
    pub master_pairs: &'a [usize],
    /// The master modes.
    pub masters: &'a [MasterMode],
    /// Spectral quotients (eqs. 54, 58).
    pub quotients: &'a SpectralQuotients,
    /// The SSM.
    pub ssm: &'a SsmExpansion,
    /// Polar form of a two-dimensional SSM of a flow.
    pub polar: Option<&'a Polar>,
    /// The `[pod]` study.
    pub pod: Option<&'a PodStudy>,
    /// What the analyses of the registry put into the summary.
    pub answers: &'a Answers,
    /// The accuracy target, the order and every answer's estimate.
    pub accuracy: &'a Accuracy,
    /// Warnings of the run.
    pub warnings: &'a [String],
    /// Stage timings.
    pub timing: Timing,
}

/// The version of the shape of `summary.json` (its `schema_version`); it
/// changes whenever a key is added, removed or changes its type.
pub const SCHEMA_VERSION: u32 = 6;

/// `summary.json`: a run's summary, or that of a `[pod]` scene that asks
/// for no SSM answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
#[schemars(title = "summary.json of ssm-engine")]
pub enum SummaryFile {
    /// A run with an SSM.
    Run(Box<RunSummary>),
    /// A `[pod]` study alone.
    PodOnly(Box<PodOnlySummary>),
}

/// The summary of a run with an SSM.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RunSummary {
    /// The version of the file's shape, `SCHEMA_VERSION`.
    #[schemars(schema_with = "version_schema")]
    pub schema_version: u32,
    /// The plugin libraries that ran (model, reducer).
    pub plugins: Vec<PluginSummary>,
    /// The model analysed.
    pub model: ModelSummary,
    /// The reduction that made the model (`[reduce]`), if any.
    pub reduction: Option<ReductionSummary>,
    /// The recast of a non-polynomial model, if any.
    pub recast: Option<RecastSummary>,
    /// The finite eigenvalues computed.
    pub spectrum: Vec<Complex>,
    /// How they were computed.
    pub spectrum_method: String,
    /// Every finite eigenvalue was computed.
    pub spectrum_complete: bool,
    /// The master pairs asked for (1-based).
    pub master_pairs: Vec<usize>,
    /// The master modes.
    pub master_modes: Vec<MasterModeSummary>,
    /// Spectral quotients (eqs. 54, 58).
    pub spectral_quotients: QuotientsSummary,
    /// The SSM.
    pub ssm: SsmSummary,
    /// Polar form of a two-dimensional SSM of a flow.
    pub polar: Option<Vec<PolarSummary>>,
    /// `[outputs.invariance_error]`.
    pub invariance_error: Option<Vec<InvarianceSummary>>,
    /// Steps of the reduced transient of `[outputs.transient]`.
    pub rom_steps: Option<usize>,
    /// `[forcing]`.
    pub frc: Option<FrcSummary>,
    /// `[validate]`.
    pub validation: Option<ValidationSummary>,
    /// `[report]`.
    pub report: Option<ReportSummary>,
    /// `[simulate]`.
    pub simulation: Option<SimulationSummary>,
    /// `[pod]`.
    pub pod: Option<PodSummary>,
    /// `[reference]`.
    pub reference: Option<ReferenceSummary>,
    /// The accuracy target, the order and every answer's estimate.
    pub accuracy: AccuracySummary,
    /// Warnings of the run.
    pub warnings: Vec<String>,
    /// Seconds per stage.
    pub timing_s: TimingSummary,
    /// Work of the sparse linear algebra of the SSM.
    pub linear_algebra: LinearAlgebraSummary,
    /// Memory: the SSM's coefficients and sparse factors per order, the
    /// forced response's factors and the process's peaks (run facts, like
    /// the timings).
    pub memory: MemorySummary,
    /// The results of the analyses of `[analysis]`, by name (absent without
    /// analyses).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    #[schemars(schema_with = "crate::analyses::outputs_schema")]
    pub analyses: BTreeMap<String, Value>,
}

/// The summary of a `[pod]` scene that asks for no SSM answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PodOnlySummary {
    /// The version of the file's shape, `SCHEMA_VERSION`.
    #[schemars(schema_with = "version_schema")]
    pub schema_version: u32,
    /// The plugin libraries that ran.
    pub plugins: Vec<PluginSummary>,
    /// The model.
    pub model: ModelSummary,
    /// The study (null when it was interrupted before its first case).
    pub pod: Option<PodSummary>,
    /// Warnings of the run.
    pub warnings: Vec<String>,
    /// Seconds.
    pub timing_s: PodTimingSummary,
}

/// A plugin library that ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PluginSummary {
    /// Its name.
    pub name: String,
    /// Its version.
    pub version: String,
    /// Its file.
    pub file: String,
}

/// The model analysed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelSummary {
    /// The plugin that built it.
    pub plugin: String,
    /// The model's name.
    pub name: String,
    /// States of its first-order form.
    pub n_states: usize,
    /// Finite modes (counted, or known from its structure; absent in a
    /// `[pod]`-only summary).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n_finite_modes: Option<usize>,
}

/// The reduction of `[reduce]` that made the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReductionSummary {
    /// The reducer's plugin.
    pub plugin: String,
    /// The reducer.
    pub reducer: String,
    /// States of the model it reduced (null: from data).
    pub n_input_states: Option<usize>,
    /// Trajectories it used.
    pub n_trajectories: usize,
    /// States of the reduced model.
    pub n_reduced_states: usize,
    /// The lift back to the full states, if any.
    pub lift: Option<LiftSummary>,
    /// Outputs of the full model lifted to the reduced one.
    pub lifted_outputs: Vec<String>,
    /// The reducer's diagnostics.
    pub diagnostics: Diagnostics,
}

/// A linear lift `x = V y (+ offset)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LiftSummary {
    /// Rows of `V`.
    pub n_full_states: usize,
    /// Columns of `V`.
    pub n_reduced_states: usize,
    /// The lift has an offset.
    pub offset: bool,
}

/// The recast of a non-polynomial model into a polynomial DAE.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RecastSummary {
    /// States before the recast.
    pub n_original_states: usize,
    /// The equilibrium was shifted to the origin.
    pub equilibrium_shifted: bool,
    /// The auxiliary variables added.
    pub auxiliaries: Vec<AuxiliarySummary>,
}

/// An auxiliary variable of the recast.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AuxiliarySummary {
    /// Its name.
    pub name: String,
    /// What it stands for.
    pub definition: String,
    /// `differential` or `algebraic`.
    pub equation: String,
}

/// A master mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MasterModeSummary {
    /// Its pair (1-based).
    pub pair: usize,
    /// Its eigenvalue.
    pub lambda: Complex,
    /// Residual of its eigenvector.
    pub residual: f64,
}

/// Spectral quotients (eqs. 54, 58; null: not bounded).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct QuotientsSummary {
    /// Relative spectral quotient.
    pub relative: Option<u64>,
    /// Absolute spectral quotient.
    pub absolute: Option<u64>,
    /// Computed over the whole finite spectrum.
    pub complete: bool,
}

/// The accuracy target, the order and every answer's estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AccuracySummary {
    /// Relative accuracy target (`[ssm] tolerance`).
    pub tolerance: f64,
    /// The expansion order of the answers.
    pub order: usize,
    /// `tolerance` (chosen) or `scene` (given).
    pub order_from: String,
    /// The orders tried while choosing.
    pub orders_tried: Vec<OrderTried>,
    /// Each answer's error estimate.
    pub answers: Vec<AnswerSummary>,
    /// Errors measured against the full system.
    pub measured: Vec<MeasuredSummary>,
}

/// An order tried while choosing it from the tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OrderTried {
    /// Expansion order.
    pub order: usize,
    /// Largest estimate of its answers (null: none, or diverged).
    pub largest_estimate: Option<f64>,
}

/// An answer's error estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AnswerSummary {
    /// `backbone`, `frc`, `transient`, ...
    pub answer: String,
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude (forced answers).
    pub epsilon: Option<f64>,
    /// Estimated relative error (null: none, or diverged).
    pub error_estimate: Option<f64>,
    /// The expansion diverged there.
    pub diverged: bool,
    /// The estimate exceeds the tolerance.
    pub untrusted: bool,
    /// Largest amplitude up to which it is within the tolerance.
    pub trusted_up_to_rho: Option<f64>,
}

/// An error measured against the full system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MeasuredSummary {
    /// The answer.
    pub answer: String,
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude (forced answers).
    pub epsilon: Option<f64>,
    /// Relative error measured.
    pub relative_error: Option<f64>,
    /// The output compared.
    pub output: Option<String>,
    /// What it was measured against.
    pub against: String,
}

/// Seconds per stage, and the SSM's split (serde cannot deny unknown keys
/// beside a flattened struct; the schema does).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[schemars(extend("additionalProperties" = false))]
pub struct TimingSummary {
    /// The stages.
    #[serde(flatten)]
    pub stages: Timing,
    /// Of the SSM: composing the nonlinearity.
    pub ssm_composition: f64,
    /// Of the SSM: factorizing.
    pub ssm_factorization: f64,
    /// Of the SSM: solving.
    pub ssm_solves: f64,
}

/// Seconds of a `[pod]`-only run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PodTimingSummary {
    /// The study.
    pub pod: f64,
    /// The whole run.
    pub total: f64,
}

/// Work of the sparse linear algebra with the full system's matrices, over
/// every stage that does some, and per stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LinearAlgebraSummary {
    /// Symbolic factorizations, all stages.
    pub symbolic_factorizations: usize,
    /// Numeric factorizations, all stages.
    pub numeric_factorizations: usize,
    /// Solves, all stages.
    pub solves: usize,
    /// Krylov steps of band solves, all stages.
    pub krylov_iterations: usize,
    /// Per stage: `spectrum` (the shifted pencil's factorization and the
    /// shift-invert solves, then the master modes' inverse iteration), `ssm`
    /// (the homological equations of every order), `frc` (the forced
    /// response's leading-order and non-autonomous terms), `validation`
    /// (the full-system Radau IIA runs of the transient and the steady
    /// states).
    pub stages: BTreeMap<String, LinearWork>,
}

/// The memory of a run. Heap figures are counted by the engine's allocator
/// (`ssm_kernel::heap`) and are null where it is not the allocator (a
/// program that links the library with its own).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MemorySummary {
    /// The highest heap of the process so far, in bytes, without the dense
    /// kernels' buffers (`kernel_buffer_bytes`).
    pub peak_heap_bytes: Option<usize>,
    /// Heap of the process when the SSM began (the model, its spectrum),
    /// in bytes, without the kernels' buffers: what the peak holds besides
    /// the computation's own factors and coefficients.
    pub heap_before_ssm_bytes: Option<usize>,
    /// Heap the dense matrix kernels' per-thread buffers took (twice the L3
    /// cache per thread, reserved before the run; address space, mostly
    /// never touched).
    pub kernel_buffer_bytes: usize,
    /// The highest resident set of the process so far (`VmHWM`), in bytes.
    pub peak_resident_bytes: Option<f64>,
    /// The most heap the SSM's sparse factors held at once, in bytes.
    pub ssm_factor_bytes: Option<usize>,
    /// The most heap the forced response's sparse factors held at once, in
    /// bytes (absent without a forced response).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frc_factor_bytes: Option<usize>,
    /// Per order of the SSM, `2..=order`.
    pub ssm_orders: Vec<OrderMemorySummary>,
}

/// The work and memory of one order of the SSM.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OrderMemorySummary {
    /// The order.
    pub order: usize,
    /// Its multi-indices, conjugates included.
    pub multi_indices: usize,
    /// Numeric factorizations it made.
    pub factorizations: usize,
    /// Bytes of its coefficients of `W` (16 per state and multi-index).
    pub coefficient_bytes: usize,
    /// Heap its sparse factors held, in bytes (dropped before the next
    /// order).
    pub factor_bytes: Option<usize>,
    /// Heap of the process once the order was solved, its factors still
    /// held, in bytes (without the kernels' buffers).
    pub heap_bytes: Option<usize>,
}

impl MemorySummary {
    fn new(ssm: &ssm_core::ssm::SsmExpansion, frc_factor_bytes: Option<usize>) -> Self {
        let status = std::fs::read_to_string("/proc/self/status").ok();
        let peak_resident_bytes = status.as_deref().and_then(|t| {
            let rest = t.lines().find_map(|l| l.strip_prefix("VmHWM:"))?;
            let kib: f64 = rest.split_whitespace().next()?.parse().ok()?;
            Some(kib * 1024.0)
        });
        let buffers = ssm_kernel::workspace::reserved_bytes();
        MemorySummary {
            peak_heap_bytes: ssm_kernel::heap::peak().map(|b| b.saturating_sub(buffers)),
            heap_before_ssm_bytes: ssm.timing.heap_before.map(|b| b.saturating_sub(buffers)),
            kernel_buffer_bytes: buffers,
            peak_resident_bytes,
            ssm_factor_bytes: ssm.timing.linear.factor_bytes,
            frc_factor_bytes,
            ssm_orders: ssm
                .timing
                .orders
                .iter()
                .map(|o| OrderMemorySummary {
                    order: o.order,
                    multi_indices: o.multi_indices,
                    factorizations: o.factorizations,
                    coefficient_bytes: o.coefficient_bytes,
                    factor_bytes: o.factor_bytes,
                    heap_bytes: o.heap_bytes.map(|b| b.saturating_sub(buffers)),
                })
                .collect(),
        }
    }
}

/// The spectrum's factorizations and solves with those of the master
/// modes' inverse iteration.
fn spectrum_work(spectrum: &Spectrum, masters: &[MasterMode]) -> LinearWork {
    LinearWork::of(masters.iter().fold(spectrum.work, |acc, m| acc + m.work))
}

/// The full-system integrations of the validation (Radau IIA): per run
/// two symbolic analyses (the real and the complex iteration matrix), per
/// factorization pair two numeric ones, per Newton iteration two solves.
fn validation_work(v: &ValidationSummary) -> LinearWork {
    let transient = v.transient.as_ref().map(|t| &t.full_system);
    let steady = v.steady_state.as_ref();
    let runs = usize::from(transient.is_some()) + steady.map_or(0, |s| s.points);
    let factorizations =
        transient.map_or(0, |t| t.factorizations) + steady.map_or(0, |s| s.factorizations);
    let newton =
        transient.map_or(0, |t| t.newton_iterations) + steady.map_or(0, |s| s.newton_iterations);
    LinearWork {
        symbolic_factorizations: 2 * runs,
        numeric_factorizations: 2 * factorizations,
        solves: 2 * newton,
        krylov_iterations: 0,
    }
}

impl LinearAlgebraSummary {
    /// The sum of `stages`, with them.
    fn of(stages: BTreeMap<String, LinearWork>) -> Self {
        let sum = |f: fn(&LinearWork) -> usize| stages.values().map(f).sum();
        LinearAlgebraSummary {
            symbolic_factorizations: sum(|w| w.symbolic_factorizations),
            numeric_factorizations: sum(|w| w.numeric_factorizations),
            solves: sum(|w| w.solves),
            krylov_iterations: sum(|w| w.krylov_iterations),
            stages,
        }
    }
}

impl RunSummary {
    /// The summary of the results `s`.
    pub(crate) fn new(s: &Summary<'_>) -> Self {
        let sys = s.system;
        let t = &s.timing;
        let lin = &s.ssm.timing.linear;
        RunSummary {
            schema_version: SCHEMA_VERSION,
            plugins: plugins(s.plugins),
            model: ModelSummary {
                plugin: sys.plugin.clone(),
                name: sys.name.clone(),
                n_states: sys.n_states(),
                n_finite_modes: Some(s.n_finite_modes),
            },
            reduction: s.reduction.map(reduction),
            recast: sys.recast.as_ref().map(|r| RecastSummary {
                n_original_states: r.n_original,
                equilibrium_shifted: r.equilibrium.iter().any(|&v| v != 0.0),
                auxiliaries: r
                    .auxiliaries
                    .iter()
                    .map(|a| AuxiliarySummary {
                        name: a.name.clone(),
                        definition: a.definition.clone(),
                        equation: if a.kind.is_differential() {
                            "differential"
                        } else {
                            "algebraic"
                        }
                        .to_owned(),
                    })
                    .collect(),
            }),
            spectrum: s.spectrum.eigenvalues.iter().map(|&l| l.into()).collect(),
            spectrum_method: s.spectrum.method.as_str().to_owned(),
            spectrum_complete: s.spectrum.complete,
            master_pairs: s.master_pairs.to_vec(),
            master_modes: s
                .masters
                .iter()
                .map(|m| MasterModeSummary {
                    pair: m.pair,
                    lambda: m.lambda.into(),
                    residual: m.residual,
                })
                .collect(),
            spectral_quotients: QuotientsSummary {
                relative: s.quotients.relative,
                absolute: s.quotients.absolute,
                complete: s.quotients.complete,
            },
            ssm: SsmSummary::new(s.ssm),
            polar: s.polar.map(PolarSummary::new),
            invariance_error: s.answers.invariance_error.clone(),
            rom_steps: s.answers.rom_steps,
            frc: s.answers.frc.clone(),
            validation: s.answers.validation.clone(),
            report: s.answers.report.clone(),
            simulation: s.answers.simulation.clone(),
            pod: s.pod.map(PodSummary::new),
            reference: s.answers.reference.clone(),
            accuracy: accuracy(s.accuracy),
            warnings: s.warnings.to_vec(),
            timing_s: TimingSummary {
                stages: *t,
                ssm_composition: s.ssm.timing.compose_s,
                ssm_factorization: lin.factor_s,
                ssm_solves: lin.solve_s,
            },
            linear_algebra: LinearAlgebraSummary::of(
                [
                    ("spectrum".to_owned(), spectrum_work(s.spectrum, s.masters)),
                    ("ssm".to_owned(), LinearWork::of(lin.counts())),
                ]
                .into_iter()
                .chain(
                    s.answers
                        .frc
                        .as_ref()
                        .map(|f| ("frc".to_owned(), f.linear_algebra)),
                )
                .chain(
                    s.answers
                        .validation
                        .as_ref()
                        .map(|v| ("validation".to_owned(), validation_work(v))),
                )
                .collect(),
            ),
            memory: MemorySummary::new(s.ssm, s.answers.frc.as_ref().and_then(|f| f.factor_bytes)),
            analyses: s.answers.analyses.clone(),
        }
    }
}

/// `summary.json`, pretty-printed.
pub(crate) fn summary_json(s: &Summary<'_>) -> String {
    to_json(&SummaryFile::Run(Box::new(RunSummary::new(s))))
}

/// `summary.json` of a `[pod]` scene that asks for no SSM answer: the
/// model, the plugins, the study, the warnings and the times.
pub(crate) fn pod_only_summary_json(
    system: &System,
    plugins_ran: &[PluginOrigin],
    study: Option<&PodStudy>,
    warnings: &[String],
    timing: Timing,
) -> String {
    to_json(&SummaryFile::PodOnly(Box::new(PodOnlySummary {
        schema_version: SCHEMA_VERSION,
        plugins: plugins(plugins_ran),
        model: ModelSummary {
            plugin: system.plugin.clone(),
            name: system.name.clone(),
            n_states: system.n_states(),
            n_finite_modes: None,
        },
        pod: study.map(PodSummary::new),
        warnings: warnings.to_vec(),
        timing_s: PodTimingSummary {
            pod: timing.pod,
            total: timing.total,
        },
    })))
}

/// The JSON Schema of `summary.json` (draft 2020-12), pretty-printed: what
/// `docs/summary.schema.json` holds and `ssm-engine schema` prints.
pub fn schema_json() -> String {
    let schema = schemars::schema_for!(SummaryFile);
    let mut text = serde_json::to_string_pretty(&schema).expect("a schema is JSON");
    text.push('\n');
    text
}

/// `schema_version`: [`SCHEMA_VERSION`] and nothing else.
fn version_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
    schemars::json_schema!({ "const": SCHEMA_VERSION })
}

fn to_json(file: &SummaryFile) -> String {
    // non-finite numbers are written as null (serde_json's rule)
    serde_json::to_string_pretty(file).expect("a summary of numbers and strings is JSON")
}

/// `"accuracy"`: the target, the order (and how it was set), and the error
/// estimate of each answer.
fn accuracy(a: &Accuracy) -> AccuracySummary {
    let finite = |e: Option<f64>| e.filter(|x| x.is_finite());
    AccuracySummary {
        tolerance: a.tolerance,
        order: a.order,
        order_from: if a.chosen { "tolerance" } else { "scene" }.to_owned(),
        orders_tried: a
            .tried
            .iter()
            .map(|&(order, e)| OrderTried {
                order,
                largest_estimate: finite(e),
            })
            .collect(),
        answers: a
            .answers
            .iter()
            .map(|x| AnswerSummary {
                answer: x.answer.to_owned(),
                order: x.order,
                epsilon: x.epsilon,
                error_estimate: finite(x.estimate),
                diverged: x.estimate.is_some_and(|e| !e.is_finite()),
                untrusted: x.untrusted,
                trusted_up_to_rho: x.trusted_up_to,
            })
            .collect(),
        measured: a
            .measured
            .iter()
            .map(|m| MeasuredSummary {
                answer: m.answer.to_owned(),
                order: m.order,
                epsilon: m.epsilon,
                relative_error: m.relative_error,
                output: m.output.clone(),
                against: m.against.to_owned(),
            })
            .collect(),
    }
}

fn reduction(r: &Reduction) -> ReductionSummary {
    ReductionSummary {
        plugin: r.plugin.clone(),
        reducer: r.reducer.clone(),
        n_input_states: r.n_input_states,
        n_trajectories: r.n_trajectories,
        n_reduced_states: r.n_reduced_states,
        lift: r.lift.as_ref().map(|l| LiftSummary {
            n_full_states: l.basis.nrows as usize,
            n_reduced_states: l.basis.ncols as usize,
            offset: !l.offset.is_empty(),
        }),
        lifted_outputs: r.lifted_outputs.clone(),
        diagnostics: diagnostics(&r.diagnostics),
    }
}

/// The plugin libraries that ran, by name, version and file.
fn plugins(plugins: &[PluginOrigin]) -> Vec<PluginSummary> {
    plugins
        .iter()
        .map(|p| PluginSummary {
            name: p.name.clone(),
            version: p.version.clone(),
            file: p.file.display().to_string(),
        })
        .collect()
}
