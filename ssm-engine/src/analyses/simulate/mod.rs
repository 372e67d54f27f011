//! Sampled full-system runs (`[simulate]`): the full model integrated
//! (Radau IIA, or HHT-alpha for a mechanical model) from given states or
//! from points on the SSM, its outputs sampled at a fixed period, with
//! optional additive Gaussian noise of a given relative level and seed: the
//! training and test data of the data-driven reducers (`[data]`, NAR
//! identification). It runs once, on the SSM of the order chosen, after the
//! reduced answers ([`super::Phase::FullSystem`]).
//!
//! Its results keep the key `simulation` of `summary.json` (older than the
//! registry); files `simulation_<k>.csv` in the `[data]` format.

mod run;
mod write;

pub use write::{file_name, SampledRunSummary, SimulationSummary};

use ssm_kernel::number::short;

use super::{Analysis, Answers, Beside, Context, Needs, Phase, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::fom::{SimError, Simulation};
use ssm_core::spec::{SimulateSpec, SpecError};

/// The sampled runs as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Simulate;

/// The sampled runs; as JSON, their summary ([`SimulationSummary`]).
#[derive(Debug, Clone)]
pub struct SampledRuns(pub Simulation);

super::serialized_as!(SampledRuns, SimulationSummary, |s| SimulationSummary::new(
    &s.0
));

/// Why a sampled run failed.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// An output the spec names is not the model's.
    #[error("the model has no output named '{0}'")]
    Output(String),
    /// A run's integration failed.
    #[error("[simulate] run {run}: {source}")]
    Run {
        /// 1-based run.
        run: usize,
        /// What failed.
        source: SimError,
    },
}

impl Analysis for Simulate {
    const NAME: &'static str = "simulate";
    const OWN_TABLE: Option<&'static str> = Some("simulate");
    const PHASE: Phase = Phase::FullSystem;
    const STAGE: Option<&'static str> = Some("sampling full-system runs");
    type Spec = SimulateSpec;
    type Output = SampledRuns;
    type Error = SimulateError;

    fn check(spec: &SimulateSpec, needs: &Needs) -> Result<(), SpecError> {
        spec.check(needs.pairs)
    }

    /// `runs` full-model runs over `(samples - 1) period`, each of the
    /// adaptive steps expected at the fastest master mode's frequency or at
    /// least one step a sample; the runs share the machine's cores; memory
    /// for the sampled outputs of every run.
    fn work(spec: &SimulateSpec, sizes: &Sizes<'_>) -> Work {
        let length = spec.period * (spec.samples as f64 - 1.0);
        let periods = length * sizes.periods_per_time;
        let steps = match sizes.dynamics {
            ssm_core::ssm::Dynamics::Map { .. } => periods,
            ssm_core::ssm::Dynamics::Flow => periods * sizes.steps_per_period,
        };
        let outputs = spec.outputs.as_ref().map_or(sizes.outputs, Vec::len) as f64;
        let runs = spec.runs.len() as f64;
        let samples = spec.samples as f64;
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
        let per_run = steps.max(samples) * sizes.implicit_step + samples * 8.0 * outputs;
        let (key, advice) = if steps > samples {
            (
                "simulate.period",
                "shorten the runs: a smaller period or fewer samples",
            )
        } else {
            ("simulate.samples", "take fewer samples (or fewer runs)")
        };
        Work {
            ops: per_run * runs / cores.min(runs).max(1.0),
            bytes: runs * samples * (8.0 * outputs + 8.0) + cores.min(runs) * 64.0 * sizes.states,
            key,
            what: format!(
                "{} full-system run(s) of {} samples over {} periods of the fastest master mode",
                short(runs),
                short(samples),
                short(periods.round())
            ),
            advice,
        }
    }

    fn run(spec: &SimulateSpec, cx: &Context<'_>) -> Result<SampledRuns, SimulateError> {
        run::simulate(spec, cx.system, cx.ssm, cx.outputs).map(SampledRuns)
    }

    fn summarize(output: &SampledRuns, answers: &mut Answers) {
        answers.simulation = Some(SimulationSummary::new(&output.0));
    }

    fn files(
        output: &SampledRuns,
        _outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        let sim = &output.0;
        Ok(sim
            .runs
            .iter()
            .enumerate()
            .map(|(k, run)| (file_name(k), write::run_csv(run, &sim.outputs).into_bytes()))
            .collect())
    }
}
