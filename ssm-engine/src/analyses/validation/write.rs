//! Writers of `[validate]`: `validation.csv`, `validation.svg`,
//! `steady_state.csv` and the summary's `validation`. They format a
//! [`Validation`] and compute nothing.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::plot::{line_plot, Curve, PlotError, Scale};
use ssm_core::compare::validation::{
    SteadyReference, TransientComparison, TransientStart, Validation,
};

/// `validation.csv`: `t,<out>_full,<out>_rom,...,rel_error,manifold_distance,algebraic_residual`.
pub(crate) fn transient_csv(c: &TransientComparison) -> String {
    let tv = &c.result;
    let mut csv = String::from("t");
    for o in &c.outputs {
        csv.push_str(&format!(",{o}_full,{o}_rom"));
    }
    csv.push_str(",rel_error,manifold_distance,algebraic_residual\n");
    for (j, t) in tv.times.iter().enumerate() {
        csv.push_str(&format!("{t:.10e}"));
        for k in 0..c.outputs.len() {
            csv.push_str(&format!(",{:.10e},{:.10e}", tv.full[k][j], tv.rom[k][j]));
        }
        csv.push_str(&format!(
            ",{:.6e},{:.6e},{:.6e}\n",
            c.relative_error_series[j], tv.distance[j], tv.algebraic_residual[j]
        ));
    }
    csv
}

/// `validation.svg`: the compared outputs, full (thick and pale, beneath)
/// and reduced.
pub(crate) fn transient_svg(c: &TransientComparison) -> Result<String, PlotError> {
    let tv = &c.result;
    let mut curves = Vec::new();
    for (k, o) in c.outputs.iter().take(c.n_compared).enumerate() {
        let pts = |v: &[f64]| tv.times.iter().copied().zip(v.iter().copied()).collect();
        curves.push(Curve {
            label: format!("{o} full system"),
            points: pts(&tv.full[k]),
            full: true,
            color: Some(k),
            ..Curve::default()
        });
        curves.push(Curve {
            label: format!("{o} SSM O({})", c.order),
            points: pts(&tv.rom[k]),
            color: Some(k),
            ..Curve::default()
        });
    }
    line_plot(
        "full system (thick, pale) against the reduced model from W(p0)",
        "t",
        "output",
        &curves,
        Scale::Linear,
    )
}

/// `steady_state.csv`: `epsilon,omega,<out>_linf...,periods,period_multiple,change,steps`.
pub(crate) fn steady_csv(r: &SteadyReference) -> String {
    let mut csv = String::from("epsilon,omega");
    for o in &r.outputs {
        csv.push_str(&format!(",{o}_linf"));
    }
    csv.push_str(",periods,period_multiple,change,steps\n");
    for p in &r.points {
        csv.push_str(&format!("{:e},{:.10e}", r.epsilon, p.omega));
        for a in &p.amplitudes {
            csv.push_str(&format!(",{a:.10e}"));
        }
        csv.push_str(&format!(
            ",{},{},{:.3e},{}\n",
            p.periods, p.multiple, p.change, p.stats.accepted
        ));
    }
    csv
}

/// `"validation"` of `summary.json`: the full-system comparisons of
/// `[validate]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ValidationSummary {
    /// The transient from a start on (or near) the SSM.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transient: Option<TransientSummary>,
    /// The steady states of `[validate.steady_state]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steady_state: Option<SteadySummary>,
}

impl ValidationSummary {
    /// The summary of `v`.
    pub fn new(v: &Validation) -> Self {
        ValidationSummary {
            transient: v.transient.as_ref().map(TransientSummary::new),
            steady_state: v.steady.as_ref().map(SteadySummary::new),
        }
    }
}

/// Where the compared transient started.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum StartSummary {
    /// On the SSM at `W(p0)`, `p0` in polar form.
    Ssm {
        /// Polar amplitudes.
        rho0: Vec<f64>,
        /// Polar angles.
        theta0: Vec<f64>,
    },
    /// From given states; the reduced model starts at the nearest point of
    /// the SSM.
    Given {
        /// The given state values, by name.
        values: BTreeMap<String, f64>,
        /// Distance of the (projected) start to the SSM.
        distance_to_ssm: f64,
        /// Polar amplitudes of the nearest point.
        rho0: Vec<f64>,
        /// Polar angles of the nearest point.
        theta0: Vec<f64>,
    },
}

/// The consistent initial state of the full system.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ProjectionSummary {
    /// Norm of the position correction.
    pub position_correction: f64,
    /// Norm of the velocity correction.
    pub velocity_correction: f64,
    /// Constraint residual after the projection.
    pub constraint_residual: f64,
    /// Velocity-constraint residual after the projection.
    pub velocity_constraint_residual: f64,
}

/// The full-system integration (Radau IIA).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FullRunSummary {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected_steps: usize,
    /// Jacobian evaluations.
    pub jacobians: usize,
    /// LU factorizations.
    pub factorizations: usize,
    /// Newton iterations.
    pub newton_iterations: usize,
    /// Wall time in seconds.
    pub wall_s: f64,
    /// Accepted steps per second.
    pub steps_per_s: f64,
}

/// The error of one output over the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputError {
    /// The output.
    pub name: String,
    /// Relative error of the output over the run.
    pub relative_error: f64,
    /// Root-mean-square relative error over the run.
    pub rms_relative_error: f64,
}

/// `"validation.transient"`: the reduced transient against the full one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransientSummary {
    /// Expansion order of the reduced model.
    pub order: usize,
    /// The start.
    pub start: StartSummary,
    /// End time.
    pub t_end: f64,
    /// Samples compared.
    pub samples: usize,
    /// The full system's consistent start.
    pub initial_projection: ProjectionSummary,
    /// The full system's integration.
    pub full_system: FullRunSummary,
    /// Wall time of the reduced model in seconds.
    pub rom_wall_s: f64,
    /// Largest relative error of the compared outputs.
    pub max_relative_error: f64,
    /// Largest distance of the full trajectory to the SSM.
    pub max_manifold_distance: f64,
    /// Largest algebraic residual of the full trajectory.
    pub max_algebraic_residual: f64,
    /// The compared outputs.
    pub outputs: Vec<OutputError>,
    /// The Lagrange multipliers compared besides (Appendix G.1).
    pub multipliers: Vec<OutputError>,
}

impl TransientSummary {
    fn new(c: &TransientComparison) -> Self {
        let tv = &c.result;
        let named = |range: std::ops::Range<usize>| {
            range
                .map(|k| OutputError {
                    name: c.outputs[k].clone(),
                    relative_error: c.relative_errors[k],
                    rms_relative_error: c.rms_relative_errors[k],
                })
                .collect()
        };
        TransientSummary {
            order: c.order,
            start: match &c.start {
                TransientStart::Ssm { rho0, theta0 } => StartSummary::Ssm {
                    rho0: rho0.clone(),
                    theta0: theta0.clone(),
                },
                TransientStart::Given {
                    values,
                    distance,
                    rho0,
                    theta0,
                } => StartSummary::Given {
                    values: values.iter().cloned().collect(),
                    distance_to_ssm: *distance,
                    rho0: rho0.clone(),
                    theta0: theta0.clone(),
                },
            },
            t_end: c.t_end,
            samples: tv.times.len(),
            initial_projection: ProjectionSummary {
                position_correction: tv.initial.position_correction,
                velocity_correction: tv.initial.velocity_correction,
                constraint_residual: tv.initial.constraint_residual,
                velocity_constraint_residual: tv.initial.velocity_residual,
            },
            full_system: FullRunSummary {
                steps: tv.stats.accepted,
                rejected_steps: tv.stats.rejected,
                jacobians: tv.stats.jacobians,
                factorizations: tv.stats.factorizations,
                newton_iterations: tv.stats.newton,
                wall_s: tv.full_s,
                steps_per_s: c.steps_per_s,
            },
            rom_wall_s: tv.rom_s,
            max_relative_error: c.max_relative_error,
            max_manifold_distance: c.max_manifold_distance,
            max_algebraic_residual: c.max_algebraic_residual,
            outputs: named(0..c.n_compared),
            multipliers: named(c.n_compared..c.outputs.len()),
        }
    }
}

/// How the steady-state runs started: all from rest, or per frequency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum SteadyStarts {
    /// `"rest"` (all of them) or `"ssm"`.
    All(String),
    /// `"ssm"` or `"rest"`, one per frequency.
    Each(Vec<String>),
}

/// One converged steady state of the full system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SteadyResponse {
    /// Forcing frequency.
    pub omega: f64,
    /// Forcing periods integrated.
    pub periods: usize,
    /// The response's period in forcing periods (1, or 2, 3, ... after a
    /// period doubling).
    pub period_multiple: usize,
    /// Relative change between the last two periods (eq. 47).
    pub change: f64,
    /// Accepted steps.
    pub steps: usize,
    /// Largest `|output|` over the response period, by output.
    pub amplitudes: BTreeMap<String, f64>,
}

/// The reduced FRC's error against the steady states, for one order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrcErrorSummary {
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Largest relative amplitude error (null: no reference point covered).
    pub max_relative_error: Option<f64>,
    /// Reference points the FRC covers.
    pub points_compared: usize,
    /// The output compared.
    pub output: Option<String>,
}

/// `"validation.steady_state"`: full-system steady states by long
/// integration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SteadySummary {
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Convergence threshold of eq. (47).
    pub delta: f64,
    /// Responses computed.
    pub points: usize,
    /// Wall time of all of them (run in parallel), seconds.
    pub wall_s: f64,
    /// Accepted steps of all of them.
    pub steps: usize,
    /// LU factorizations of all of them (Radau IIA: pairs, real and
    /// complex).
    pub factorizations: usize,
    /// Newton iterations of all of them.
    pub newton_iterations: usize,
    /// One per frequency.
    pub responses: Vec<SteadyResponse>,
    /// Where the runs started.
    pub start: SteadyStarts,
    /// The reduced FRCs' errors against these points (when there are FRCs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frc_error: Option<Vec<FrcErrorSummary>>,
}

impl SteadySummary {
    fn new(r: &SteadyReference) -> Self {
        let start = |s: bool| if s { "ssm" } else { "rest" }.to_owned();
        SteadySummary {
            epsilon: r.epsilon,
            delta: r.delta,
            points: r.points.len(),
            wall_s: r.wall_s,
            steps: r.steps,
            factorizations: r.points.iter().map(|p| p.stats.factorizations).sum(),
            newton_iterations: r.points.iter().map(|p| p.stats.newton).sum(),
            responses: r
                .points
                .iter()
                .map(|p| SteadyResponse {
                    omega: p.omega,
                    periods: p.periods,
                    period_multiple: p.multiple,
                    change: p.change,
                    steps: p.stats.accepted,
                    amplitudes: r
                        .outputs
                        .iter()
                        .cloned()
                        .zip(p.amplitudes.clone())
                        .collect(),
                })
                .collect(),
            start: match &r.from_ssm {
                Some(st) => SteadyStarts::Each(st.iter().map(|&s| start(s)).collect()),
                None => SteadyStarts::All(start(false)),
            },
            frc_error: r.frc_errors.as_ref().map(|errs| {
                errs.iter()
                    .map(|e| FrcErrorSummary {
                        order: e.order,
                        epsilon: e.epsilon,
                        max_relative_error: e.max_relative_error,
                        points_compared: e.points_compared,
                        output: e.output.clone(),
                    })
                    .collect()
            }),
        }
    }
}
