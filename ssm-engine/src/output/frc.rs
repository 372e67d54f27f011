//! Writers of `[forcing]`: `frc.csv`, `frc.svg` (with the steady-state
//! reference of `[validate]` drawn in) and the summary's `frc`. They format a
//! [`ForcedResponse`] and compute nothing.

use serde_json::{json, Value};
use ssm_kernel::number::short;

use super::plot::{line_plot, Curve, PlotError, Scale};
use super::reference::reference_curves;
use ssm_core::compare::validation::SteadyReference;
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::rom::accuracy::percent;
use ssm_core::rom::forced_response::{CurveDetails, ForcedResponse};

/// `frc.csv`: `order,epsilon,omega,stable,branch,<out>_linf...,rho_1..rho_m,<out>_h1...`.
pub fn frc_csv(f: &ForcedResponse) -> String {
    let mut csv = String::from("order,epsilon,omega,stable,branch");
    for o in &f.outputs {
        csv.push_str(&format!(",{o}_linf"));
    }
    for j in 1..=f.forcing_on_master.len() {
        csv.push_str(&format!(",rho_{j}"));
    }
    for o in &f.outputs {
        csv.push_str(&format!(",{o}_h1"));
    }
    csv.push('\n');
    for r in &f.rows {
        csv.push_str(&format!(
            "{},{:e},{:.10e},{},{}",
            r.order,
            r.epsilon,
            r.omega,
            u8::from(r.stable),
            r.branch
        ));
        for v in r.linf.iter().chain(&r.pair_amplitudes).chain(&r.h1) {
            csv.push_str(&format!(",{v:.10e}"));
        }
        csv.push('\n');
    }
    csv
}

/// Drawn curves of `f`: per `(order, epsilon)` one segment per run of equal
/// stability on a branch (dashed when unstable; a segment shares its first
/// point with the previous one of its branch), and the bifurcations as circles.
fn curves(f: &ForcedResponse) -> Vec<Curve> {
    let mut drawn = Vec::new();
    let mut rows = f.rows.as_slice();
    for (ci, c) in f.curves.iter().enumerate() {
        let (mine, rest) = rows.split_at(c.points.min(rows.len()));
        rows = rest;
        let mut k = 0;
        let mut labelled = false;
        while k < mine.len() {
            let (st, br) = (mine[k].stable, mine[k].branch);
            let mut seg = Vec::new();
            if k > 0 && mine[k - 1].branch == br {
                seg.push((mine[k - 1].omega, mine[k - 1].plotted()));
            }
            while k < mine.len() && mine[k].stable == st && mine[k].branch == br {
                seg.push((mine[k].omega, mine[k].plotted()));
                k += 1;
            }
            drawn.push(Curve {
                label: if labelled {
                    String::new()
                } else {
                    format!(
                        "O({}), eps = {}, estimated error {}{}",
                        c.order,
                        short(c.epsilon),
                        percent(c.error_estimate()),
                        if c.untrusted {
                            "  UNTRUSTED: error estimate above [ssm] tolerance"
                        } else {
                            ""
                        }
                    )
                },
                points: seg,
                dashed: !st,
                markers: Vec::new(),
                color: Some(ci),
            });
            labelled = true;
        }
        drawn.push(Curve {
            label: String::new(),
            points: Vec::new(),
            dashed: false,
            markers: c
                .bifurcations
                .iter()
                .filter_map(|b| b.plotted.map(|y| (b.omega, y)))
                .collect(),
            color: Some(ci),
        });
    }
    drawn
}

/// `frc.svg`: amplitude of the first output (or `rho_1`) against `Omega`, with
/// the full-system steady states of `reference` as circles and the
/// full-system curves of `[reference]` in black.
pub fn frc_svg(
    f: &ForcedResponse,
    reference: Option<&SteadyReference>,
    full: Option<&ReferenceFrc>,
) -> Result<String, PlotError> {
    let mut drawn = curves(f);
    if let Some(r) = full {
        drawn.extend(reference_curves(r));
    }
    if let Some(r) = reference {
        drawn.push(Curve {
            label: format!("full system, eps = {} (steady state)", short(r.epsilon)),
            points: Vec::new(),
            markers: r
                .points
                .iter()
                .filter_map(|p| p.amplitudes.first().map(|&a| (p.omega, a)))
                .collect(),
            ..Curve::default()
        });
    }
    let y_label = f
        .outputs
        .first()
        .map_or("rho_1".to_owned(), |o| format!("max |{o}|"));
    line_plot(
        "forced response (dashed: unstable, circles: bifurcations)",
        "Omega",
        &y_label,
        &drawn,
        Scale::Linear,
    )
}

/// The summary's `frc`.
pub fn frc_json(f: &ForcedResponse) -> Value {
    let one_pair = f.forcing_on_master.len() == 1;
    let bifurcations: Vec<Value> = f
        .curves
        .iter()
        .flat_map(|c| {
            c.bifurcations.iter().map(move |b| {
                json!({
                    "kind": b.kind,
                    "omega": b.omega,
                    "epsilon": c.epsilon,
                    "order": c.order,
                    "rho": if one_pair { json!(b.rho[0]) } else { json!(b.rho) },
                    "branch": b.branch,
                })
            })
        })
        .collect();
    let curves: Vec<Value> = f
        .curves
        .iter()
        .map(|c| {
            let mut v = json!({
                "order": c.order,
                "epsilon": c.epsilon,
                "points": c.points,
                "branches": c.branches,
                "untrusted": c.untrusted,
            });
            match &c.details {
                CurveDetails::OnePair {
                    rho_peak,
                    invariance_error_at_peak,
                    residual_eq60_at_peak,
                    error_estimate,
                    nonautonomous_order,
                } => {
                    v["error_estimate"] =
                        json!(error_estimate.is_finite().then_some(error_estimate));
                    v["rho_peak"] = json!(rho_peak);
                    v["invariance_error_at_peak"] = json!(invariance_error_at_peak);
                    v["residual_eq60_at_peak"] = json!(residual_eq60_at_peak);
                    v["nonautonomous_order"] = json!(nonautonomous_order);
                }
                CurveDetails::Continuation {
                    branch_switches,
                    continuation_steps,
                    error_estimate,
                } => {
                    v["error_estimate"] =
                        json!(error_estimate.is_finite().then_some(error_estimate));
                    v["branch_switches"] = json!(branch_switches);
                    v["continuation_steps"] = json!(continuation_steps);
                }
            }
            v
        })
        .collect();
    let forcing: Vec<Value> = f
        .forcing_on_master
        .iter()
        .map(|s| json!({"re": s.re, "im": s.im}))
        .collect();
    let mut v = json!({
        "bifurcations": bifurcations,
        "points": f.rows.len(),
        "curves": curves,
        "resonance": f.resonance,
        "forcing_on_master": if one_pair { forcing[0].clone() } else { json!(forcing) },
        "warnings": f.warnings,
    });
    if let Some(r) = f.rho_max {
        v["rho_max"] = json!(r);
    }
    v
}
