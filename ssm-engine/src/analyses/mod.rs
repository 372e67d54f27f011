//! Analyses as vertical slices: each folder holds one analysis whole (its
//! spec, its run on the core, its writer), and [`REGISTRY`] lists them, one
//! line each. A scene asks for one with a table `[analysis.<name>]`; its
//! spec is read from that table (or from JSON, by a study or a binding),
//! checked, costed by the run's one gate, and run on the SSM the run chose
//! (computed once and shared with the other answers). Its results land in
//! `summary.json` under `analyses.<name>` and in the files its writer names.
//! The answers older than the registry moved into it keeping their scene
//! table and their key of `summary.json` ([`Analysis::OWN_TABLE`]): the
//! backbone ([`backbone`]), the invariance error ([`invariance`]), the
//! reduced transient ([`transient`]), the forced response ([`frc`]), the
//! full-system comparisons ([`validation`]), the full system's forced
//! responses ([`reference`](mod@reference)), the speed-against-error report ([`report`])
//! and the sampled full-system runs ([`simulate`]). An analysis of the
//! reduced model runs on every SSM the run tries while it chooses the
//! expansion order; one of the full system runs once, on the SSM of the
//! order chosen ([`Phase`]). Each reads the results of those that ran
//! before it ([`Context::earlier`], [`output_of`]); a writer may draw the
//! full-system answers computed after its own ([`Beside`]). Estimates,
//! measured errors and warnings follow the order of
//! [`crate::plan::Plan::requested`].
//!
//! Adding an analysis: a folder with a type implementing [`Analysis`], and a
//! line in [`REGISTRY`] (and its section in `docs/scene.md`).

pub mod backbone;
pub mod damping;
pub mod frc;
pub mod invariance;
pub mod pod;
pub mod reference;
pub mod report;
pub mod simulate;
pub mod transient;
pub mod validation;

use std::any::Any;
use std::collections::BTreeMap;
use std::fmt::Debug;
use std::marker::PhantomData;

use schemars::{json_schema, JsonSchema, Schema, SchemaGenerator};
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::plot::PlotError;
use crate::progress::{Progress, Quiet};
use crate::C64;
use ssm_core::compare::validation::SteadyReference;
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::model::system::{OutputMap, System};
use ssm_core::rom::accuracy::{AnswerEstimate, MeasuredError};
use ssm_core::spec::SpecError;
use ssm_core::spectrum::MasterMode;
use ssm_core::ssm::{Dynamics, SsmExpansion};

/// The analyses the engine offers, one line each.
pub static REGISTRY: &[&dyn Entry] = &[
    &Slice::<backbone::Backbone>(PhantomData),
    &Slice::<invariance::Invariance>(PhantomData),
    &Slice::<transient::Transient>(PhantomData),
    &Slice::<frc::Frc>(PhantomData),
    &Slice::<validation::Validate>(PhantomData),
    &Slice::<reference::Reference>(PhantomData),
    &Slice::<report::SpeedReport>(PhantomData),
    &Slice::<simulate::Simulate>(PhantomData),
    &Slice::<damping::Damping>(PhantomData),
];

/// The analysis of `name` in [`REGISTRY`].
pub fn find(name: &str) -> Result<&'static dyn Entry, AnalysisError> {
    REGISTRY
        .iter()
        .copied()
        .find(|e| e.name() == name)
        .ok_or_else(|| AnalysisError::Unknown {
            name: name.to_owned(),
            offered: REGISTRY
                .iter()
                .map(|e| e.name())
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// What an analysis reads: the model, its master modes and the SSM at the
/// order the run chose, the results of the analyses that ran before it (and
/// the signals a model identified from data came from), and where it
/// reports its progress. Built with [`Context::new`] (its fields may grow).
#[derive(Clone, Copy)]
#[non_exhaustive]
pub struct Context<'a> {
    /// The model.
    pub system: &'a System,
    /// The master modes of the SSM.
    pub masters: &'a [MasterMode],
    /// The eigenvalues of the spectrum that are not masters (an SSM of
    /// another order is computed against them).
    pub others: &'a [C64],
    /// The SSM (shared with every other answer of the run).
    pub ssm: &'a SsmExpansion,
    /// The outputs of `[outputs] coordinates`.
    pub outputs: &'a [&'a OutputMap],
    /// The accuracy target (`[ssm] tolerance`, relative).
    pub tolerance: f64,
    /// The `[data]` signals of a model a reducer identified from them.
    pub signals: Option<&'a ssm_api::Signals>,
    /// The results of the analyses that ran before this one, on this SSM
    /// (read with [`output_of`]).
    pub earlier: &'a [Box<dyn Finished>],
    /// Where it reports its stages.
    pub progress: &'a dyn Progress,
}

impl Debug for Context<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("system", &self.system.name)
            .field("masters", &self.masters.len())
            .field("order", &self.ssm.order)
            .field("tolerance", &self.tolerance)
            .field(
                "earlier",
                &self.earlier.iter().map(|e| e.name()).collect::<Vec<_>>(),
            )
            .finish_non_exhaustive()
    }
}

impl<'a> Context<'a> {
    /// The context of an SSM `ssm` of `system` on its `masters`, the answers
    /// read at `outputs` and held to the relative `tolerance`; no other
    /// eigenvalues, no signals, no earlier results, no progress display.
    pub fn new(
        system: &'a System,
        masters: &'a [MasterMode],
        ssm: &'a SsmExpansion,
        outputs: &'a [&'a OutputMap],
        tolerance: f64,
    ) -> Self {
        Self {
            system,
            masters,
            others: &[],
            ssm,
            outputs,
            tolerance,
            signals: None,
            earlier: &[],
            progress: &Quiet,
        }
    }

    /// With the `[data]` signals of a model identified from them.
    pub fn with_signals(self, signals: Option<&'a ssm_api::Signals>) -> Self {
        Self { signals, ..self }
    }

    /// With the non-master eigenvalues `others` of the spectrum.
    pub fn with_others(self, others: &'a [C64]) -> Self {
        Self { others, ..self }
    }

    /// With the results of the analyses that ran before.
    pub fn with_earlier(self, earlier: &'a [Box<dyn Finished>]) -> Self {
        Self { earlier, ..self }
    }

    /// Reporting to `progress`.
    pub fn with_progress(self, progress: &'a dyn Progress) -> Self {
        Self { progress, ..self }
    }
}

/// What an analysis's spec is checked against before anything runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Needs {
    /// Master pairs of the SSM.
    pub pairs: usize,
    /// The highest expansion order the run may compute.
    pub max_order: usize,
}

/// The work and memory of an analysis, for the run's one gate.
#[derive(Debug, Clone, PartialEq)]
pub struct Work {
    /// Floating-point operations, roughly.
    pub ops: f64,
    /// Bytes held at once.
    pub bytes: f64,
    /// The key that sets the size (relative to the analysis's table).
    pub key: &'static str,
    /// The request in words (e.g. "a damping curve of 1e9 points").
    pub what: String,
    /// How to make it smaller.
    pub advice: &'static str,
}

/// What sizes the cost of an analysis run on an SSM.
#[derive(Debug, Clone, Copy)]
pub struct Sizes<'a> {
    /// Multi-indices of the expansion up to its order.
    pub multi_indices: f64,
    /// Outputs of `[outputs] coordinates`.
    pub outputs: usize,
    /// Master pairs of the SSM.
    pub pairs: usize,
    /// States of the model.
    pub states: f64,
    /// Factors of all monomials of the model's nonlinearity (a bound on
    /// the nodes of one evaluation).
    pub factors: f64,
    /// Flow or map.
    pub dynamics: Dynamics,
    /// Periods of the fastest master mode per unit time (a map: steps per
    /// unit time).
    pub periods_per_time: f64,
    /// Integration steps per period assumed for an adaptive integrator.
    pub steps_per_period: f64,
    /// Operations of one step of an implicit integrator of the full model
    /// (its sparse factorizations and solves).
    pub implicit_step: f64,
    /// Stored entries of the model's matrices `A` and `B`.
    pub nnz: f64,
    /// Operations of one sparse factorization and solve of the pencil's
    /// size.
    pub sparse_solve: f64,
    /// The master modes.
    pub masters: &'a [MasterMode],
    /// The expansion order when `[ssm] order` fixes it.
    pub fixed_order: Option<usize>,
}

/// The full-system answers a writer may draw beside an analysis's own
/// results (they are computed after the reduced answers).
#[derive(Debug, Clone, Copy, Default)]
pub struct Beside<'a> {
    /// The steady states of `[validate.steady_state]`.
    pub steady: Option<&'a SteadyReference>,
    /// The forced responses of `[reference]`.
    pub reference: Option<&'a ReferenceFrc>,
}

/// The answers' part of `summary.json` that the analyses fill: each
/// analysis's results under `analyses.<name>`, and the keys that answers
/// older than the registry keep.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Answers {
    /// `analyses`: the results of each analysis, by name.
    pub analyses: BTreeMap<String, serde_json::Value>,
    /// `invariance_error`: the rows of [`invariance`].
    pub invariance_error: Option<Vec<invariance::InvarianceSummary>>,
    /// `rom_steps`: the steps of [`transient`].
    pub rom_steps: Option<usize>,
    /// `frc`: the summary of [`frc`].
    pub frc: Option<frc::FrcSummary>,
    /// `simulation`: the summary of [`simulate`].
    pub simulation: Option<simulate::SimulationSummary>,
    /// `validation`: the summary of [`validation`].
    pub validation: Option<validation::write::ValidationSummary>,
    /// `reference`: the summary of [`reference`](mod@reference).
    pub reference: Option<reference::write::ReferenceSummary>,
    /// `report`: the summary of [`report`].
    pub report: Option<report::write::ReportSummary>,
}

/// The loud warning for an answer (`"backbone O(5)"`, ...) whose error
/// estimate exceeds the accuracy target `tolerance`, trusted up to an
/// amplitude or not at all, with the `advice` that makes it trustworthy.
pub(crate) fn untrusted_warning(
    answer: &str,
    estimate: Option<f64>,
    tolerance: f64,
    trusted_up_to: Option<f64>,
    advice: &str,
) -> String {
    format!(
        "{answer}: the estimated error, {}, exceeds the accuracy target {} ([ssm] tolerance){}; do not trust it: {advice}",
        ssm_core::rom::accuracy::percent(estimate.unwrap_or(f64::NAN)),
        ssm_core::rom::accuracy::percent(tolerance),
        trusted_up_to.map_or(String::new(), |r| format!(" beyond rho = {r:.4}")),
    )
}

/// The outputs `names` of `system` (`None`: `default`, the plan's
/// coordinates); an unknown name is `missing(name)`.
pub(crate) fn outputs_named<'a, E>(
    system: &'a System,
    names: Option<&[String]>,
    default: &[&'a OutputMap],
    missing: impl Fn(String) -> E,
) -> Result<Vec<&'a OutputMap>, E> {
    match names {
        None => Ok(default.to_vec()),
        Some(names) => names
            .iter()
            .map(|n| system.output(n).ok_or_else(|| missing(n.clone())))
            .collect(),
    }
}

/// `Serialize` and `JsonSchema` for an analysis's output `$output` as its
/// summary `$summary`, made by `$new` from a `&$output` (the shape
/// `summary.json` keeps for the answers older than the registry).
macro_rules! serialized_as {
    ($output:ty, $summary:ty, $new:expr) => {
        impl serde::Serialize for $output {
            fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                let new: fn(&$output) -> $summary = $new;
                serde::Serialize::serialize(&new(self), serializer)
            }
        }

        impl schemars::JsonSchema for $output {
            fn schema_name() -> std::borrow::Cow<'static, str> {
                <$summary as schemars::JsonSchema>::schema_name()
            }

            fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
                <$summary as schemars::JsonSchema>::json_schema(generator)
            }
        }
    };
}
pub(crate) use serialized_as;

/// When an analysis runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// On every SSM the run tries while it chooses the expansion order (its
    /// estimates take part in the choice).
    Reduced,
    /// Once, on the SSM of the order chosen, after the reduced answers and
    /// the full-system comparisons (a run of the full model).
    FullSystem,
}

/// One analysis: its spec, its run and its writer.
pub trait Analysis {
    /// `[analysis.<NAME>]`, and the key of its results in `summary.json`.
    const NAME: &'static str;
    /// The scene table of an answer older than the registry (e.g.
    /// `outputs.invariance_error`), which also keeps its own key of
    /// `summary.json` (set by its [`Analysis::summarize`]); `None` for
    /// `[analysis.<NAME>]` and `analyses.<NAME>`.
    const OWN_TABLE: Option<&'static str> = None;
    /// When it runs.
    const PHASE: Phase = Phase::Reduced;
    /// The progress stage it is shown as, when it is one of its own.
    const STAGE: Option<&'static str> = None;
    /// What is asked (serde: from the scene's table or from JSON; unknown
    /// keys are refused, defaults documented on the fields).
    type Spec: Serialize + DeserializeOwned;
    /// What it computed (serialized into `summary.json`; its schema is part
    /// of `summary.json`'s).
    type Output: Serialize + JsonSchema + Debug + Send + 'static;
    /// Why it failed.
    type Error: std::error::Error + Send + Sync + 'static;

    /// Checks `spec` against what the run offers (by default nothing: an
    /// answer older than the registry is checked by the plan).
    fn check(_spec: &Self::Spec, _needs: &Needs) -> Result<(), SpecError> {
        Ok(())
    }
    /// The expansion orders the spec names (the run computes at least the
    /// highest; by default none).
    fn orders(_spec: &Self::Spec) -> Vec<usize> {
        Vec::new()
    }
    /// Its work and memory.
    fn work(spec: &Self::Spec, sizes: &Sizes<'_>) -> Work;
    /// Runs it.
    fn run(spec: &Self::Spec, cx: &Context<'_>) -> Result<Self::Output, Self::Error>;
    /// The error estimates of its answers (they take part in choosing the
    /// expansion order; by default none).
    fn estimates(_output: &Self::Output) -> Vec<AnswerEstimate> {
        Vec::new()
    }
    /// Its warnings (e.g. an answer whose estimate exceeds the tolerance).
    fn warnings(_output: &Self::Output) -> Vec<String> {
        Vec::new()
    }
    /// The errors it measured of the reduced answers against the full
    /// system (they join `accuracy.measured`).
    fn measured(_output: &Self::Output) -> Vec<MeasuredError> {
        Vec::new()
    }
    /// Puts its results into the summary: `analyses.<NAME>` unless it has
    /// an [`Analysis::OWN_TABLE`].
    fn summarize(output: &Self::Output, answers: &mut Answers) {
        // plain data of numbers and strings: serializing cannot fail (a
        // non-finite float becomes null)
        let value = serde_json::to_value(output).unwrap_or(serde_json::Value::Null);
        answers.analyses.insert(Self::NAME.to_owned(), value);
    }
    /// Its files `(name, contents)`; `outputs` are the names of
    /// `[outputs] coordinates`, `beside` the full-system answers it may
    /// draw in.
    fn files(
        output: &Self::Output,
        outputs: &[String],
        beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError>;
}

/// An analysis whose spec and results are seen through JSON: what the
/// pipeline and [`REGISTRY`] hold.
pub trait Entry: Sync {
    /// Its name.
    fn name(&self) -> &'static str;
    /// The scene table it is asked for with: `analysis.<name>`, or the
    /// table of an answer older than the registry.
    fn table(&self) -> String;
    /// When it runs.
    fn phase(&self) -> Phase;
    /// Its progress stage, when it is one of its own.
    fn stage(&self) -> Option<&'static str>;
    /// Reads `json` into its spec and checks it; the spec with every default
    /// filled in.
    fn spec(
        &self,
        json: serde_json::Value,
        needs: &Needs,
    ) -> Result<serde_json::Value, AnalysisError>;
    /// The expansion orders a spec names.
    fn orders(&self, spec: &serde_json::Value) -> Result<Vec<usize>, AnalysisError>;
    /// The work and memory of a spec.
    fn work(&self, spec: &serde_json::Value, sizes: &Sizes<'_>) -> Result<Work, AnalysisError>;
    /// Runs a (read) spec.
    fn run(
        &self,
        spec: &serde_json::Value,
        cx: &Context<'_>,
    ) -> Result<Box<dyn Finished>, AnalysisError>;
    /// The JSON Schema of its results (`analyses.<name>` of `summary.json`).
    fn output_schema(&self, generator: &mut SchemaGenerator) -> Schema;
}

/// The schema of `analyses` of `summary.json`: an object with one optional
/// key per analysis of [`REGISTRY`], holding its results.
pub(crate) fn outputs_schema(generator: &mut SchemaGenerator) -> Schema {
    let properties: serde_json::Map<String, serde_json::Value> = REGISTRY
        .iter()
        .filter(|e| e.table() == format!("analysis.{}", e.name()))
        .map(|e| (e.name().to_owned(), e.output_schema(generator).to_value()))
        .collect();
    json_schema!({
        "type": "object",
        "properties": properties,
        "additionalProperties": false,
    })
}

/// The results of an analysis, for the run's summary, accuracy and files.
pub trait Finished: Debug + Send {
    /// The analysis's name.
    fn name(&self) -> &'static str;
    /// Puts its results into the summary.
    fn summarize(&self, answers: &mut Answers);
    /// Its error estimates.
    fn estimates(&self) -> Vec<AnswerEstimate>;
    /// Its warnings.
    fn warnings(&self) -> Vec<String>;
    /// The errors it measured against the full system.
    fn measured(&self) -> Vec<MeasuredError>;
    /// Its files.
    fn files(
        &self,
        outputs: &[String],
        beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError>;
    /// Its results as JSON, in the shape `summary.json` keeps them (for a
    /// binding that runs one analysis on its own).
    fn to_json(&self) -> serde_json::Value;
    /// Itself, for [`output_of`].
    fn as_any(&self) -> &dyn Any;
}

/// The results of the analysis `A` among `done`, if it ran.
pub fn output_of<A: Analysis + 'static>(done: &[Box<dyn Finished>]) -> Option<&A::Output> {
    done.iter()
        .find_map(|d| d.as_any().downcast_ref::<Done<A>>())
        .map(|d| &d.0)
}

/// Why an analysis could not be planned or run.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// No analysis of that name.
    #[error("no analysis named '{name}'; the engine offers: {offered}")]
    Unknown {
        /// The name asked for.
        name: String,
        /// The names offered.
        offered: String,
    },
    /// The spec could not be read (a missing or mistyped key).
    #[error("analysis '{analysis}': {message}")]
    Unreadable {
        /// The analysis.
        analysis: &'static str,
        /// The reader's message.
        message: String,
    },
    /// The spec was read but asks for something the run cannot do.
    #[error("analysis '{analysis}': {source}")]
    Spec {
        /// The analysis.
        analysis: &'static str,
        /// The key and what is wrong.
        source: SpecError,
    },
    /// The analysis ran and failed.
    #[error("analysis '{analysis}': {source}")]
    Failed {
        /// The analysis.
        analysis: &'static str,
        /// Its error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

/// [`Entry`] for an [`Analysis`] `A`.
struct Slice<A>(PhantomData<fn() -> A>);

/// [`Finished`] for an [`Analysis`] `A`.
struct Done<A: Analysis>(A::Output);

impl<A: Analysis> Debug for Done<A> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl<A: Analysis> Slice<A> {
    fn read(json: serde_json::Value) -> Result<A::Spec, AnalysisError> {
        serde_json::from_value(json).map_err(|e| AnalysisError::Unreadable {
            analysis: A::NAME,
            message: e.to_string(),
        })
    }
}

impl<A: Analysis + 'static> Entry for Slice<A> {
    fn name(&self) -> &'static str {
        A::NAME
    }

    fn table(&self) -> String {
        A::OWN_TABLE.map_or_else(|| format!("analysis.{}", A::NAME), str::to_owned)
    }

    fn phase(&self) -> Phase {
        A::PHASE
    }

    fn stage(&self) -> Option<&'static str> {
        A::STAGE
    }

    fn spec(
        &self,
        json: serde_json::Value,
        needs: &Needs,
    ) -> Result<serde_json::Value, AnalysisError> {
        let spec = Self::read(json)?;
        A::check(&spec, needs).map_err(|source| AnalysisError::Spec {
            analysis: A::NAME,
            source,
        })?;
        serde_json::to_value(&spec).map_err(|e| AnalysisError::Unreadable {
            analysis: A::NAME,
            message: e.to_string(),
        })
    }

    fn orders(&self, spec: &serde_json::Value) -> Result<Vec<usize>, AnalysisError> {
        Ok(A::orders(&Self::read(spec.clone())?))
    }

    fn work(&self, spec: &serde_json::Value, sizes: &Sizes<'_>) -> Result<Work, AnalysisError> {
        Ok(A::work(&Self::read(spec.clone())?, sizes))
    }

    fn run(
        &self,
        spec: &serde_json::Value,
        cx: &Context<'_>,
    ) -> Result<Box<dyn Finished>, AnalysisError> {
        let spec = Self::read(spec.clone())?;
        let out = A::run(&spec, cx).map_err(|e| AnalysisError::Failed {
            analysis: A::NAME,
            source: Box::new(e),
        })?;
        Ok(Box::new(Done::<A>(out)))
    }

    fn output_schema(&self, generator: &mut SchemaGenerator) -> Schema {
        generator.subschema_for::<A::Output>()
    }
}

impl<A: Analysis + 'static> Finished for Done<A> {
    fn name(&self) -> &'static str {
        A::NAME
    }

    fn summarize(&self, answers: &mut Answers) {
        A::summarize(&self.0, answers);
    }

    fn estimates(&self) -> Vec<AnswerEstimate> {
        A::estimates(&self.0)
    }

    fn warnings(&self) -> Vec<String> {
        A::warnings(&self.0)
    }

    fn measured(&self) -> Vec<MeasuredError> {
        A::measured(&self.0)
    }

    fn files(
        &self,
        outputs: &[String],
        beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        A::files(&self.0, outputs, beside)
    }

    fn to_json(&self) -> serde_json::Value {
        // plain data of numbers and strings: serializing cannot fail (a
        // non-finite float becomes null)
        serde_json::to_value(&self.0).unwrap_or(serde_json::Value::Null)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}
