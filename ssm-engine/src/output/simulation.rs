//! `simulation_<k>.csv` (the `[data]` format: `t` and one column per output,
//! shortest round-trip numbers) and the `simulation` entry of `summary.json`.

use serde_json::{json, Value};

use ssm_core::fom::{SampledRun, Simulation};

/// File name of run `k` (0-based).
pub fn file_name(k: usize) -> String {
    format!("simulation_{}.csv", k + 1)
}

/// One run as a `[data]` CSV file.
pub fn run_csv(run: &SampledRun, outputs: &[String]) -> String {
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

/// The `simulation` entry of `summary.json`.
pub fn simulation_json(sim: &Simulation) -> Value {
    json!({
        "outputs": sim.outputs,
        "noise": sim.noise,
        "seed": sim.seed,
        "runs": sim.runs.iter().enumerate().map(|(k, r)| json!({
            "file": file_name(k),
            "samples": r.times.len(),
            "period": r.times.get(1).copied().unwrap_or(0.0) - r.times[0],
            "steps": r.steps,
            "start_correction": r.start_correction,
            "noise_sigma": sim.noise_sigma.get(k),
        })).collect::<Vec<_>>(),
    })
}
