//! The products of `[validate]`: `validation.csv`, `validation.svg`,
//! `steady_state.csv`, the full-system reference drawn into `frc.svg`, and the
//! summary's `validation`.

use std::time::Instant;

use serde_json::{json, Value};
use ssm_api::StateKind;

use crate::compare::{self, TransientValidation, ValidateError};
use crate::fom::{
    consistent_initial_keeping, DaeProblem, RadauOptions, SteadyOptions, SteadyState,
};
use crate::model::system::{OutputMap, System};
use crate::output::plot::{line_plot, Curve, Scale};
use crate::results_frc::{frc_svg, FrcReport, FrcRow};
use crate::scene::{SteadyStart, ValidateSection};
use crate::spectrum::MasterMode;
use crate::ssm::SsmExpansion;
use crate::C64;

/// Steady-state reference points of one forcing amplitude.
#[derive(Debug, Clone)]
pub struct SteadyReference {
    /// Forcing amplitude.
    pub epsilon: f64,
    /// One converged response per frequency.
    pub points: Vec<SteadyState>,
    /// Names of the outputs whose amplitudes are in `points`.
    pub outputs: Vec<String>,
    /// Wall time of all points (run in parallel).
    pub wall_s: f64,
}

/// Everything `[validate]` produced.
#[derive(Debug, Clone)]
pub struct ValidationProducts {
    /// Files to write, `(name, contents)`.
    pub files: Vec<(String, String)>,
    /// `"validation"` of the summary.
    pub summary: Value,
    /// The transient comparison, if requested.
    pub transient: Option<TransientValidation>,
    /// The steady-state reference, if requested.
    pub steady: Option<SteadyReference>,
}

/// Multipliers added to `validation.csv` without being listed (the first ones).
const MAX_AUTO_MULTIPLIERS: usize = 8;

/// Multiplier outputs (`mu1`, ...) of the model, for the Appendix G.1 comparison.
fn multiplier_outputs(sys: &System) -> Vec<&OutputMap> {
    sys.states
        .iter()
        .enumerate()
        .filter(|(_, s)| s.kind == StateKind::Multiplier)
        .filter_map(|(i, s)| {
            sys.output(s.name.as_str())
                .filter(|o| o.weights.len() == 1 && o.weights[0].0 == i)
        })
        .collect()
}

/// Runs the comparisons of `sec`: `compared` are the outputs of the transient
/// (the multipliers are added), `coordinates` those of the steady state (the
/// FRC's outputs, in its order), `frc` the FRCs to draw the steady-state
/// reference into and to measure against it.
pub fn validation(
    ssm: &SsmExpansion,
    sys: &System,
    sec: &ValidateSection,
    compared: &[&OutputMap],
    coordinates: &[&OutputMap],
    masters: &[MasterMode],
    frc: Option<&mut FrcReport>,
) -> Result<ValidationProducts, ValidateError> {
    let mut files = Vec::new();
    let mut summary = serde_json::Map::new();
    let opts = RadauOptions {
        rtol: *sec.rtol.get_ref(),
        atol: *sec.atol.get_ref(),
        ..RadauOptions::default()
    };
    let mut transient = None;
    if let Some(t_end) = &sec.t_end {
        let order = sec.order.as_ref().map_or(ssm.order, |o| *o.get_ref());
        let (p0, full_start, start) = match &sec.rho0 {
            Some(rho0) => {
                let theta0 = sec
                    .theta0
                    .as_ref()
                    .map_or_else(|| vec![0.0; rho0.get_ref().len()], |t| t.get_ref().clone());
                let p0 = crate::results::polar_point(rho0.get_ref(), &theta0);
                let start = json!({"kind": "ssm", "rho0": rho0.get_ref(), "theta0": theta0});
                (p0, None, start)
            }
            None => {
                let mut z = vec![0.0; sys.n_states()];
                let mut keep = Vec::new();
                for (name, value) in sec.given_start() {
                    if let Some(i) = sys.states.iter().position(|s| s.name.as_str() == name) {
                        z[i] = value;
                        if sys.states[i].kind == ssm_api::StateKind::Displacement {
                            keep.push(i);
                        }
                    }
                }
                let problem = DaeProblem::new(sys, 0.0, 0.0);
                let c = consistent_initial_keeping(&problem, 0.0, &z, &keep)?;
                let (p0, distance) = compare::nearest_on_ssm(ssm, sys, order, masters, &c.z);
                let start = json!({
                    "kind": "given",
                    "values": sec.given_start().into_iter().map(|(k, v)| (k, json!(v))).collect::<serde_json::Map<_, _>>(),
                    "distance_to_ssm": distance,
                    "rho0": p0.iter().step_by(2).map(|q| q.norm()).collect::<Vec<_>>(),
                    "theta0": p0.iter().step_by(2).map(|q| q.arg()).collect::<Vec<_>>(),
                });
                // the raw values go to the full system, whose projection is reported
                (p0, Some((z, keep)), start)
            }
        };
        let mut outs: Vec<&OutputMap> = compared.to_vec();
        let multipliers = multiplier_outputs(sys);
        // a few multipliers are added (Appendix G.1); large models list the ones they want
        for m in multipliers.into_iter().take(MAX_AUTO_MULTIPLIERS) {
            if !outs.iter().any(|o| o.name == m.name) {
                outs.push(m);
            }
        }
        let tv = compare::transient(
            ssm,
            sys,
            &compare::TransientSettings {
                order,
                p0: &p0,
                t_end: *t_end.get_ref(),
                samples: *sec.samples.get_ref(),
                outputs: &outs,
                radau: opts,
                full_start: full_start
                    .as_ref()
                    .map(|(z, k)| (z.as_slice(), k.as_slice())),
            },
        )?;
        files.push(("validation.csv".to_owned(), transient_csv(&tv, &outs)));
        files.push((
            "validation.svg".to_owned(),
            transient_svg(&tv, &outs[..compared.len()], order)?,
        ));
        summary.insert(
            "transient".into(),
            transient_json(&tv, &outs, compared.len(), order, start, *t_end.get_ref()),
        );
        transient = Some(tv);
    }
    let mut steady = None;
    if let Some(ss) = &sec.steady_state {
        let eps = *ss.epsilon.get_ref();
        let omegas = ss.omegas();
        let sopts = SteadyOptions {
            delta: *ss.delta.get_ref(),
            max_periods: *ss.max_periods.get_ref(),
            samples_per_period: *ss.samples_per_period.get_ref(),
            max_multiple: *ss.max_period_multiple.get_ref(),
            radau: opts,
        };
        let starts = match (ss.start(), frc.as_deref()) {
            (SteadyStart::Ssm, Some(f)) => Some(ssm_starts(ssm, &f.rows, eps, &omegas)),
            _ => None,
        };
        let t0 = Instant::now();
        let points = compare::steady_state_reference(
            sys,
            eps,
            &omegas,
            coordinates,
            &sopts,
            starts.as_deref(),
        )?;
        let reference = SteadyReference {
            epsilon: eps,
            points,
            outputs: coordinates.iter().map(|o| o.name.clone()).collect(),
            wall_s: t0.elapsed().as_secs_f64(),
        };
        files.push(("steady_state.csv".to_owned(), steady_csv(&reference)));
        let mut js = steady_json(&reference, *ss.delta.get_ref());
        js["start"] = match &starts {
            Some(st) => st
                .iter()
                .map(|z| if z.is_some() { "ssm" } else { "rest" })
                .collect::<Vec<_>>()
                .into(),
            None => "rest".into(),
        };
        if let Some(frc) = frc {
            js["frc_error"] = frc_errors(&frc.rows, &reference).into();
            overlay(frc, &reference, coordinates)?;
        }
        summary.insert("steady_state".into(), js);
        steady = Some(reference);
    }
    Ok(ValidationProducts {
        files,
        summary: Value::Object(summary),
        transient,
        steady,
    })
}

/// Starting states from the FRC: at each `omega`, the point `W(p0)` of the
/// largest stable response (first output) of the highest-order curve at
/// `epsilon`, `p0` the rotating-frame fixed point interpolated along the
/// branch; `None` where no stable branch crosses `omega`.
fn ssm_starts(
    ssm: &SsmExpansion,
    rows: &[FrcRow],
    epsilon: f64,
    omegas: &[f64],
) -> Vec<Option<Vec<f64>>> {
    let same_eps = |r: &FrcRow| (r.epsilon - epsilon).abs() <= 1e-12 * epsilon;
    let Some(order) = rows.iter().filter(|r| same_eps(r)).map(|r| r.order).max() else {
        return vec![None; omegas.len()];
    };
    let curve: Vec<&FrcRow> = rows
        .iter()
        .filter(|r| same_eps(r) && r.order == order)
        .collect();
    omegas
        .iter()
        .map(|&w| {
            let best = curve
                .windows(2)
                .filter(|c| c[0].branch == c[1].branch && c[0].stable && c[1].stable)
                .filter(|c| (c[0].omega - w) * (c[1].omega - w) <= 0.0 && c[0].omega != c[1].omega)
                .map(|c| {
                    let s = (w - c[0].omega) / (c[1].omega - c[0].omega);
                    let amp = c[0]
                        .linf
                        .first()
                        .map_or(c[0].rho, |a| a + s * (c[1].linf[0] - a));
                    let q: Vec<C64> = c[0]
                        .q
                        .iter()
                        .zip(&c[1].q)
                        .map(|(a, b)| a + (b - a) * s)
                        .collect();
                    (amp, q)
                })
                .max_by(|a, b| a.0.total_cmp(&b.0))?;
            let p0: Vec<C64> = best.1.iter().flat_map(|q| [*q, q.conj()]).collect();
            Some(
                ssm.w_at(&ssm.set.monomials(&p0, order), order)
                    .iter()
                    .map(|c| c.re)
                    .collect(),
            )
        })
        .collect()
}

/// `t,<out>_full,<out>_rom,...,rel_error,manifold_distance,algebraic_residual`.
fn transient_csv(tv: &TransientValidation, outs: &[&OutputMap]) -> String {
    let mut csv = String::from("t");
    for o in outs {
        csv.push_str(&format!(",{0}_full,{0}_rom", o.name));
    }
    csv.push_str(",rel_error,manifold_distance,algebraic_residual\n");
    for (j, t) in tv.times.iter().enumerate() {
        csv.push_str(&format!("{t:.10e}"));
        for k in 0..outs.len() {
            csv.push_str(&format!(",{:.10e},{:.10e}", tv.full[k][j], tv.rom[k][j]));
        }
        csv.push_str(&format!(
            ",{:.6e},{:.6e},{:.6e}\n",
            tv.relative_error_at(j),
            tv.distance[j],
            tv.algebraic_residual[j]
        ));
    }
    csv
}

fn transient_svg(
    tv: &TransientValidation,
    outs: &[&OutputMap],
    order: usize,
) -> Result<String, ValidateError> {
    let mut curves = Vec::new();
    for (k, o) in outs.iter().enumerate() {
        let pts = |v: &[f64]| tv.times.iter().copied().zip(v.iter().copied()).collect();
        curves.push(Curve {
            label: format!("{} full system", o.name),
            points: pts(&tv.full[k]),
            dashed: true,
            color: Some(k),
            ..Curve::default()
        });
        curves.push(Curve {
            label: format!("{} SSM O({order})", o.name),
            points: pts(&tv.rom[k]),
            color: Some(k),
            ..Curve::default()
        });
    }
    Ok(line_plot(
        "full system (dashed) against the reduced model from W(p0)",
        "t",
        "output",
        &curves,
        Scale::Linear,
    )?)
}

/// The summary's `validation.transient`; `outs[..n_compared]` are the compared
/// outputs, the rest multipliers added for Appendix G.1.
fn transient_json(
    tv: &TransientValidation,
    outs: &[&OutputMap],
    n_compared: usize,
    order: usize,
    start: Value,
    t_end: f64,
) -> Value {
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let errs: Vec<f64> = (0..outs.len()).map(|k| tv.relative_error(k)).collect();
    let named = |range: std::ops::Range<usize>| {
        range
            .map(|k| json!({"name": outs[k].name, "relative_error": errs[k]}))
            .collect::<Vec<_>>()
    };
    json!({
        "order": order,
        "start": start,
        "t_end": t_end,
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
            "steps_per_s": tv.stats.accepted as f64 / tv.full_s.max(1e-12),
        },
        "rom_wall_s": tv.rom_s,
        "max_relative_error": max(&errs[..n_compared]),
        "max_manifold_distance": max(&tv.distance),
        "max_algebraic_residual": max(&tv.algebraic_residual),
        "outputs": named(0..n_compared),
        "multipliers": named(n_compared..outs.len()),
    })
}

/// `epsilon,omega,<out>_linf...,periods,period_multiple,change,steps`.
fn steady_csv(r: &SteadyReference) -> String {
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

fn steady_json(r: &SteadyReference, delta: f64) -> Value {
    let steps: usize = r.points.iter().map(|p| p.stats.accepted).sum();
    json!({
        "epsilon": r.epsilon,
        "delta": delta,
        "points": r.points.len(),
        "wall_s": r.wall_s,
        "steps": steps,
        "responses": r.points.iter().map(|p| json!({
            "omega": p.omega,
            "periods": p.periods,
            "period_multiple": p.multiple,
            "change": p.change,
            "steps": p.stats.accepted,
            "amplitudes": r.outputs.iter().zip(&p.amplitudes)
                .map(|(n, a)| (n.clone(), json!(a))).collect::<serde_json::Map<_, _>>(),
        })).collect::<Vec<_>>(),
    })
}

/// The FRC amplitude of output `k` at `omega` on the curve `(order, epsilon)`:
/// linear interpolation on every branch segment that crosses `omega`, the
/// crossing nearest `near` (the reference from rest sits on one branch).
pub fn frc_amplitude_at(
    rows: &[FrcRow],
    order: usize,
    epsilon: f64,
    k: usize,
    omega: f64,
    near: f64,
) -> Option<f64> {
    let same = |r: &FrcRow| r.order == order && (r.epsilon - epsilon).abs() <= 1e-12 * epsilon;
    let curve: Vec<&FrcRow> = rows.iter().filter(|r| same(r)).collect();
    curve
        .windows(2)
        .filter(|w| w[0].branch == w[1].branch)
        .filter(|w| (w[0].omega - omega) * (w[1].omega - omega) <= 0.0 && w[0].omega != w[1].omega)
        .map(|w| {
            let s = (omega - w[0].omega) / (w[1].omega - w[0].omega);
            w[0].linf[k] + s * (w[1].linf[k] - w[0].linf[k])
        })
        .min_by(|a, b| (a - near).abs().total_cmp(&(b - near).abs()))
}

/// Per FRC order at the reference's epsilon: the largest relative amplitude
/// error against the reference over the frequencies the FRC covers.
pub fn frc_errors(rows: &[FrcRow], r: &SteadyReference) -> Vec<Value> {
    let mut orders: Vec<usize> = rows
        .iter()
        .filter(|w| (w.epsilon - r.epsilon).abs() <= 1e-12 * r.epsilon)
        .map(|w| w.order)
        .collect();
    orders.sort_unstable();
    orders.dedup();
    orders
        .into_iter()
        .map(|order| {
            let (err, compared) = frc_error(rows, r, order);
            json!({
                "order": order,
                "epsilon": r.epsilon,
                "max_relative_error": err,
                "points_compared": compared,
                "output": r.outputs.first(),
            })
        })
        .collect()
}

/// Largest `|A_frc - A_ref| / max A_ref` of the first output over the
/// reference points covered by the FRC of `order`, and how many were covered.
pub fn frc_error(rows: &[FrcRow], r: &SteadyReference, order: usize) -> (Option<f64>, usize) {
    let scale = r
        .points
        .iter()
        .map(|p| p.amplitudes.first().copied().unwrap_or(0.0))
        .fold(0.0, f64::max);
    let errs: Vec<f64> = r
        .points
        .iter()
        .filter_map(|p| {
            let a = *p.amplitudes.first()?;
            frc_amplitude_at(rows, order, r.epsilon, 0, p.omega, a).map(|f| (f - a).abs() / scale)
        })
        .collect();
    let n = errs.len();
    ((n > 0).then(|| errs.into_iter().fold(0.0, f64::max)), n)
}

/// Draws the reference points into `frc.svg`.
fn overlay(
    frc: &mut FrcReport,
    r: &SteadyReference,
    outputs: &[&OutputMap],
) -> Result<(), ValidateError> {
    frc.curves.push(Curve {
        label: format!("full system, eps = {} (steady state)", r.epsilon),
        points: Vec::new(),
        markers: r
            .points
            .iter()
            .filter_map(|p| p.amplitudes.first().map(|&a| (p.omega, a)))
            .collect(),
        ..Curve::default()
    });
    frc.svg = frc_svg(&frc.curves, outputs)?;
    Ok(())
}
