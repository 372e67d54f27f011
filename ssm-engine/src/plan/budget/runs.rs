//! The costs of the full-model runs that are not answers read off the SSM:
//! the `[pod]` study, the engine's `pod` reducer (`[reduce] reducer =
//! "pod"`) and `[simulate]`. Each is costed before it allocates anything;
//! the refusal names the key of the part that dominates the estimate.

use super::{ensure, ssm_cost, Cost, Limits, Sizes, OPS_PER_SECOND};
use crate::plan::{Plan, PlanError};
use ssm_core::model::system::System;
use ssm_kernel::number::short;

/// Newton iterations assumed per fixed HHT step (the iteration matrix is
/// factored once per step at a fixed step size, and again when Newton needs
/// more than three iterations; at most 8 iterations).
const HHT_NEWTON: f64 = 4.0;

/// Factor of the HHT step's operation count, fitted to a measured run
/// (release build; 2.05 s of CPU in all, at 39 % of a core on the loaded
/// machine, so the parts' wall times below are scaled by 0.39):
/// `zoo/pendulum_chain_pod.toml` with every `t_end` at 10 (405 states,
/// 1001 steps a run; three full runs, two POD and two SSM models run on
/// each load). Measured against estimated (with this factor):
/// - the three full runs: 0.39 s of CPU (1.0 s wall); 0.40 s;
/// - the POD models' runs: 1.2 s (3.0 s wall); 4.2 s (with the lift);
/// - the two POD reductions: 0.08 s (0.2 s wall); 4.8 s, since the
///   reduced coordinates (6 and 13) are bounded by the 122 displacements
///   before the training run has shown how few POD keeps;
/// - the SSM models and their runs: 0.03 s; 0.15 s.
const HHT_CALIBRATION: f64 = 0.16;

/// A POD model's fixed HHT step against the full model's (measured on the
/// chain of [`HHT_CALIBRATION`]: 0.7 and 2.4 times the full run for the
/// models of 6 and 13 coordinates (96 and 114 states with the recast's
/// auxiliaries), whose Galerkin projections are dense).
const REDUCED_RUN: f64 = 3.0;

/// Operations of one fixed HHT step of a model of `sizes`: one sparse LU of
/// the iteration matrix and [`HHT_NEWTON`] Newton iterations, each a
/// residual (the pencil's products and the nonlinearity) and a solve.
fn hht_step(s: &Sizes) -> f64 {
    HHT_CALIBRATION
        * (s.sparse_solve() + HHT_NEWTON * (10.0 * (s.nnz + s.states) + 4.0 * s.factors))
}

/// Bytes of one stored HHT step: the state and the accelerations (two
/// boxed vectors) and the time.
fn hht_bytes(s: &Sizes) -> f64 {
    2.0 * (8.0 * s.states + 40.0) + 8.0
}

/// One part of a request's cost, the key that drives it and the key a
/// refusal points at.
struct Part {
    cost: Cost,
    key: String,
    at: String,
    advice: &'static str,
}

/// Refuses `what` when the parts together exceed `limits`, at the key of
/// the part that takes the largest share of the time or memory allowed.
fn refuse_parts(what: String, parts: &[Part], limits: &Limits) -> Result<(), PlanError> {
    let total = Cost {
        ops: parts.iter().map(|p| p.cost.ops).sum(),
        bytes: parts.iter().map(|p| p.cost.bytes).sum(),
    };
    let share = |c: &Cost| (c.ops / OPS_PER_SECOND / limits.seconds).max(c.bytes / limits.bytes);
    let Some(top) = parts
        .iter()
        .max_by(|a, b| share(&a.cost).total_cmp(&share(&b.cost)))
    else {
        return Ok(());
    };
    ensure(&top.key, what, &total, limits, top.advice).map_err(|e| PlanError {
        at: top.at.clone(),
        ..e
    })
}

/// What a POD reduction is made from: the fixed step, the training run's
/// length, the Jacobian samples and the number of truncations.
struct Training {
    step: f64,
    t_end: f64,
    jacobian_samples: f64,
    truncations: f64,
}

/// Displacements and constraints of `system` (half the states and none
/// for a model that is not mechanical).
fn mechanical(system: &System) -> (f64, f64) {
    system.mechanical.as_ref().map_or_else(
        || ((system.n_states() / 2) as f64, 0.0),
        |m| (m.n_dof as f64, m.n_constraints as f64),
    )
}

/// The POD reductions from the training run `t`: per truncation, the thin
/// SVD of the velocity snapshots (`n x K`, `K` steps) and the SVDs of the
/// stacked projected constraint Jacobian (`m x r J`, `r <= min(n, K)`
/// reduced coordinates, `J` samples) and of each of its `J` blocks.
fn reduction_parts(system: &System, t: &Training, snapshots: &str, samples: &str) -> [Part; 2] {
    let (n, m) = mechanical(system);
    let k = t.t_end / t.step + 1.0;
    let svd = Cost {
        ops: t.truncations * (4.0 * n * k * n.min(k) + 8.0 * n.min(k).powi(3)),
        bytes: 8.0 * (n * k + (n + k) * n.min(k)),
    };
    let r = n.min(k);
    let cols = r * t.jacobian_samples;
    let stack = Cost {
        ops: t.truncations * 4.0 * (m * cols * m.min(cols) + t.jacobian_samples * m * r * m.min(r)),
        bytes: 3.0 * 8.0 * m * cols,
    };
    [
        Part {
            cost: svd,
            key: snapshots.to_owned(),
            at: snapshots.to_owned(),
            advice: "lengthen the step or shorten the training run (fewer snapshots)",
        },
        Part {
            cost: stack,
            key: samples.to_owned(),
            at: samples.to_owned(),
            advice: "lower jacobian_samples",
        },
    ]
}

/// Refuses a `[pod]` study that would not finish within `limits`, before
/// any of it runs: the full model's HHT runs (`t_end / step` steps each,
/// see `hht_step`) and their stored states; the POD reductions
/// (`reduction_parts`); each POD model's run on every load (bounded by
/// the full model's step, plus the lift to the full states, which are
/// stored); the SSM models of `ssm_pairs` and their runs, lifted through
/// `W` at every step end.
pub(crate) fn check_pod(plan: &Plan, system: &System, limits: &Limits) -> Result<(), PlanError> {
    let Some(p) = &plan.pod else {
        return Ok(());
    };
    let sizes = Sizes::of(system);
    let step = p.step;
    let runs: Vec<_> = std::iter::once(&p.train).chain(&p.tests).collect();
    let steps: Vec<f64> = runs.iter().map(|r| r.t_end / step + 1.0).collect();
    let all: f64 = steps.iter().sum();
    let longest_test = steps[1..].iter().copied().fold(0.0, f64::max);
    let truncations = p.truncations.len() as f64;
    let hyper = truncations * p.hyper.len() as f64;
    let pod_models = truncations + hyper;
    let sets = &p.ssm_pairs;
    let outputs = p.outputs.as_ref().unwrap_or(&plan.coordinates).len() as f64;
    let models = pod_models + sets.len() as f64;
    let step_key = "pod.step";
    let full = Part {
        cost: Cost {
            ops: all * hht_step(&sizes),
            bytes: (steps[0] + longest_test) * hht_bytes(&sizes)
                + all * (8.0 + (1.0 + models) * (8.0 * outputs + 40.0)),
        },
        key: step_key.to_owned(),
        at: step_key.to_owned(),
        advice: "lengthen the step or shorten the runs (t_end)",
    };
    let (n, _) = mechanical(system);
    let r = n.min(steps[0]);
    let reduced = Part {
        cost: Cost {
            ops: pod_models * all * (REDUCED_RUN * hht_step(&sizes) + 4.0 * n * r),
            bytes: steps[0].max(longest_test) * 2.0 * hht_bytes(&sizes),
        },
        key: step_key.to_owned(),
        at: step_key.to_owned(),
        advice: "lengthen the step, shorten the runs (t_end) or give fewer truncations",
    };
    let training = Training {
        step,
        t_end: runs[0].t_end,
        jacobian_samples: p.jacobian_samples as f64,
        truncations,
    };
    // each DEIM training: the force snapshots (at most 400 of the training
    // run's, rows up to 2n), their thin SVD, and a few trial samples of up
    // to that many rows (doubling, then bisection)
    let ks = steps[0].min(400.0);
    let nf = 2.0 * n;
    let trials = 2.0 * (nf.min(ks).log2().ceil() + 1.0);
    let deim = Part {
        cost: Cost {
            ops: hyper
                * (4.0 * nf * ks * nf.min(ks)
                    + trials * (nf.min(ks).powi(3) + 2.0 * nf.min(ks) * ks * 2.0 * r)),
            bytes: 8.0 * (3.0 * nf * ks + (nf + ks) * nf.min(ks)),
        },
        key: "pod.hyper".to_owned(),
        at: "pod.hyper".to_owned(),
        advice: "give fewer hyper tolerances or lengthen the step (fewer snapshots)",
    };
    let [svd, stack] = reduction_parts(system, &training, step_key, "pod.jacobian_samples");
    let order = p.ssm_order(plan.ssm.order);
    let forced = runs.iter().any(|r| r.epsilon != 0.0);
    let ssm = sets.iter().fold(
        Cost {
            ops: 0.0,
            bytes: 0.0,
        },
        |acc, set| {
            let c = ssm_cost(&sizes, set.len(), order, forced);
            let n_idx = super::multi_indices(2 * set.len(), order);
            // each step end: the reduced state lifted through W to the outputs
            Cost {
                ops: acc.ops + c.ops + all * 4.0 * n_idx * (outputs + 2.0 * set.len() as f64),
                bytes: acc.bytes + c.bytes,
            }
        },
    );
    let ssm_key = if p.ssm_order.is_some() {
        "pod.ssm_order"
    } else {
        "pod.ssm_pairs"
    };
    let parts = [
        full,
        reduced,
        svd,
        stack,
        deim,
        Part {
            cost: ssm,
            key: ssm_key.to_owned(),
            at: ssm_key.to_owned(),
            advice: "lower ssm_order or give fewer ssm_pairs",
        },
    ];
    refuse_parts(
        format!(
            "the [pod] study ({} full-model HHT run(s) of up to {} steps of a {}-state model, {} reduced model(s) run on each)",
            runs.len(),
            short(steps.iter().copied().fold(0.0, f64::max).floor()),
            sizes.states,
            models
        ),
        &parts,
        limits,
    )
}

/// Refuses the engine's `pod` reducer (`[reduce] reducer = "pod"`) when its
/// training run of `system` (`t_end / step` HHT steps, the states stored)
/// and its POD reduction (`reduction_parts`) would not finish within
/// `limits`; a refusal names `reduce.params.step` or
/// `reduce.params.jacobian_samples`.
pub(crate) fn check_pod_reducer(
    system: &System,
    (step, t_end, jacobian_samples): (f64, f64, usize),
    limits: &Limits,
) -> Result<(), PlanError> {
    let sizes = Sizes::of(system);
    let steps = t_end / step + 1.0;
    let step_key = "reduce.params.step";
    let training = Training {
        step,
        t_end,
        jacobian_samples: jacobian_samples as f64,
        truncations: 1.0,
    };
    let [svd, stack] = reduction_parts(
        system,
        &training,
        step_key,
        "reduce.params.jacobian_samples",
    );
    let run = Part {
        cost: Cost {
            ops: steps * hht_step(&sizes),
            bytes: steps * hht_bytes(&sizes),
        },
        key: step_key.to_owned(),
        at: step_key.to_owned(),
        advice: "lengthen the step or shorten the training run (t_end)",
    };
    refuse_parts(
        format!(
            "the pod reducer's training run ({} HHT steps of a {}-state model) and its POD",
            short(steps.floor()),
            sizes.states
        ),
        &[run, svd, stack],
        limits,
    )
}

/// Sparse solves of the pencil's size per adaptive Radau IIA step (a real
/// and a complex factorization of the stage system and the Newton solves),
/// fitted to two measured release runs of the zoo (CPU time, the machine
/// loaded): `pendulum_chain_data.toml` (405 states, 400 samples over 32
/// periods of the master mode) 2.1 s, estimated 3.3 s;
/// `spatial_oscillator_data.toml` (7 states, 2000 samples over 127
/// periods) 0.25 s, estimated 0.18 s.
pub(super) const RADAU_STEP: f64 = 4.0;
