//! `simulation_<k>.csv` (the `[data]` format: `t` and one column per output,
//! shortest round-trip numbers) and the `simulation` entry of `summary.json`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use ssm_core::fom::{SampledRun, Simulation};

/// File name of run `k` (0-based).
pub fn file_name(k: usize) -> String {
    format!("simulation_{}.csv", k + 1)
}

/// One run as a `[data]` CSV file.
pub(super) fn run_csv(run: &SampledRun, outputs: &[String]) -> String {
    let mut s = String::with_capacity(run.times.len() * 24 * (outputs.len() + 1));
    s.push('t');
    for o in outputs {
        s.push(',');
        s.push_str(o);
    }
    s.push('\n');
    for (k, t) in run.times.iter().enumerate() {
        s.push_str(&t.to_string());
        for v in &run.values {
            s.push(',');
            s.push_str(&v[k].to_string());
        }
        s.push('\n');
    }
    s
}

/// `"simulation"` of `summary.json`: the sampled full-system runs of
/// `[simulate]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SimulationSummary {
    /// The sampled outputs (the columns of each file).
    pub outputs: Vec<String>,
    /// Relative noise level added to the samples.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// One entry per run.
    pub runs: Vec<SampledRunSummary>,
}

/// One sampled run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SampledRunSummary {
    /// Its file (`simulation_<k>.csv`).
    pub file: String,
    /// Samples.
    pub samples: usize,
    /// Sampling period.
    pub period: f64,
    /// Integrator steps.
    pub steps: usize,
    /// Norm of the correction that made the start consistent.
    pub start_correction: f64,
    /// Standard deviation of the noise added to each output (null without
    /// noise).
    pub noise_sigma: Option<Vec<f64>>,
}

impl SimulationSummary {
    /// The summary of `sim`.
    pub fn new(sim: &Simulation) -> Self {
        SimulationSummary {
            outputs: sim.outputs.clone(),
            noise: sim.noise,
            seed: sim.seed,
            runs: sim
                .runs
                .iter()
                .enumerate()
                .map(|(k, r)| SampledRunSummary {
                    file: file_name(k),
                    samples: r.times.len(),
                    period: r.times.get(1).copied().unwrap_or(0.0) - r.times[0],
                    steps: r.steps,
                    start_correction: r.start_correction,
                    noise_sigma: sim.noise_sigma.get(k).cloned(),
                })
                .collect(),
        }
    }
}
