//! Writers of `[validate]`: `validation.csv`, `validation.svg`,
//! `steady_state.csv` and the summary's `validation`. They format a
//! [`Validation`] and compute nothing.

use serde_json::{json, Map, Value};

use super::plot::{line_plot, Curve, PlotError, Scale};
use ssm_core::compare::validation::{
    SteadyReference, TransientComparison, TransientStart, Validation,
};

/// `validation.csv`: `t,<out>_full,<out>_rom,...,rel_error,manifold_distance,algebraic_residual`.
pub fn transient_csv(c: &TransientComparison) -> String {
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

/// `validation.svg`: the compared outputs, full (dashed) and reduced.
pub fn transient_svg(c: &TransientComparison) -> Result<String, PlotError> {
    let tv = &c.result;
    let mut curves = Vec::new();
    for (k, o) in c.outputs.iter().take(c.n_compared).enumerate() {
        let pts = |v: &[f64]| tv.times.iter().copied().zip(v.iter().copied()).collect();
        curves.push(Curve {
            label: format!("{o} full system"),
            points: pts(&tv.full[k]),
            dashed: true,
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
        "full system (dashed) against the reduced model from W(p0)",
        "t",
        "output",
        &curves,
        Scale::Linear,
    )
}

fn start_json(s: &TransientStart) -> Value {
    match s {
        TransientStart::Ssm { rho0, theta0 } => {
            json!({"kind": "ssm", "rho0": rho0, "theta0": theta0})
        }
        TransientStart::Given {
            values,
            distance,
            rho0,
            theta0,
        } => json!({
            "kind": "given",
            "values": values.iter().map(|(k, v)| (k.clone(), json!(v))).collect::<Map<_, _>>(),
            "distance_to_ssm": distance,
            "rho0": rho0,
            "theta0": theta0,
        }),
    }
}

/// The summary's `validation.transient`.
fn transient_json(c: &TransientComparison) -> Value {
    let tv = &c.result;
    let named = |range: std::ops::Range<usize>| {
        range
            .map(|k| {
                json!({
                    "name": c.outputs[k],
                    "relative_error": c.relative_errors[k],
                    "rms_relative_error": c.rms_relative_errors[k],
                })
            })
            .collect::<Vec<_>>()
    };
    json!({
        "order": c.order,
        "start": start_json(&c.start),
        "t_end": c.t_end,
        "samples": tv.times.len(),
        "initial_projection": {
            "position_correction": tv.initial.position_correction,
            "velocity_correction": tv.initial.velocity_correction,
            "constraint_residual": tv.initial.constraint_residual,
            "velocity_constraint_residual": tv.initial.velocity_residual,
        },
        "full_system": {
            "steps": tv.stats.accepted,
            "rejected_steps": tv.stats.rejected,
            "jacobians": tv.stats.jacobians,
            "factorizations": tv.stats.factorizations,
            "newton_iterations": tv.stats.newton,
            "wall_s": tv.full_s,
            "steps_per_s": c.steps_per_s,
        },
        "rom_wall_s": tv.rom_s,
        "max_relative_error": c.max_relative_error,
        "max_manifold_distance": c.max_manifold_distance,
        "max_algebraic_residual": c.max_algebraic_residual,
        "outputs": named(0..c.n_compared),
        "multipliers": named(c.n_compared..c.outputs.len()),
    })
}

/// `steady_state.csv`: `epsilon,omega,<out>_linf...,periods,period_multiple,change,steps`.
pub fn steady_csv(r: &SteadyReference) -> String {
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

fn steady_json(r: &SteadyReference) -> Value {
    let mut v = json!({
        "epsilon": r.epsilon,
        "delta": r.delta,
        "points": r.points.len(),
        "wall_s": r.wall_s,
        "steps": r.steps,
        "responses": r.points.iter().map(|p| json!({
            "omega": p.omega,
            "periods": p.periods,
            "period_multiple": p.multiple,
            "change": p.change,
            "steps": p.stats.accepted,
            "amplitudes": r.outputs.iter().zip(&p.amplitudes)
                .map(|(n, a)| (n.clone(), json!(a))).collect::<Map<_, _>>(),
        })).collect::<Vec<_>>(),
        "start": match &r.from_ssm {
            Some(st) => st
                .iter()
                .map(|&s| if s { "ssm" } else { "rest" })
                .collect::<Vec<_>>()
                .into(),
            None => json!("rest"),
        },
    });
    if let Some(errs) = &r.frc_errors {
        v["frc_error"] = errs
            .iter()
            .map(|e| {
                json!({
                    "order": e.order,
                    "epsilon": e.epsilon,
                    "max_relative_error": e.max_relative_error,
                    "points_compared": e.points_compared,
                    "output": e.output,
                })
            })
            .collect();
    }
    v
}

/// The summary's `validation`.
pub fn validation_json(v: &Validation) -> Value {
    let mut m = Map::new();
    if let Some(t) = &v.transient {
        m.insert("transient".into(), transient_json(t));
    }
    if let Some(s) = &v.steady {
        m.insert("steady_state".into(), steady_json(s));
    }
    Value::Object(m)
}
