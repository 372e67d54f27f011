//! Results read off an SSM for the report: the `ssm`, `polar` and
//! `invariance_error` entries of `summary.json`, `backbone.csv`/`.svg` and
//! `rom_trajectory.csv`.

use serde_json::{json, Value};

use crate::model::system::{OutputMap, System};
use crate::output::plot::{line_plot, Curve, PlotError, Scale};
use crate::scene::{BackboneSection, InvarianceErrorSection, TransientSection};
use crate::ssm::analysis::{amplitude, backbone_frequency, invariance_error, polar, PolarError};
use crate::ssm::rom::{integrate, RomError};
use crate::ssm::{Dynamics, SsmExpansion};
use crate::C64;

/// `"ssm"`: order, dimension, resonant terms and reduced dynamics
/// (coordinates `p1, conj p1, ...`, 1-based equation numbers).
pub fn ssm_json(ssm: &SsmExpansion) -> Value {
    let term = |t: &crate::ssm::RTerm| {
        json!({
            "eq": t.coord + 1,
            "exponents": ssm.set.exponents(t.index),
            "re": t.coeff.re,
            "im": t.coeff.im,
        })
    };
    json!({
        "order": ssm.order,
        "dim": ssm.dim(),
        "time": match ssm.dynamics {
            Dynamics::Flow => json!("flow"),
            Dynamics::Map { period } => json!({"map_period": period}),
        },
        "resonant_terms": ssm.nonlinear_terms().map(|t| json!({
            "eq": t.coord + 1,
            "exponents": ssm.set.exponents(t.index),
        })).collect::<Vec<_>>(),
        "reduced_dynamics": ssm.r.iter().map(term).collect::<Vec<_>>(),
    })
}

/// `"polar"` for a two-dimensional SSM of a flow, `None` otherwise.
pub fn polar_json(ssm: &SsmExpansion) -> Option<Value> {
    if ssm.dynamics != Dynamics::Flow {
        return None;
    }
    let p = polar(ssm).ok()?;
    Some(json!([{ "pair": 1, "rho_dot": p.rho_dot(), "omega": p.omega() }]))
}

/// `"invariance_error"`: eq. (41) for every requested order and radius.
pub fn invariance_json(
    ssm: &SsmExpansion,
    sys: &System,
    sec: &InvarianceErrorSection,
) -> Result<Value, ResultError> {
    let mut rows = Vec::new();
    for &order in sec.orders.get_ref() {
        for &radius in sec.radii.get_ref() {
            let e = invariance_error(
                ssm,
                sys,
                order,
                radius,
                *sec.n_alpha.get_ref(),
                *sec.n_theta.get_ref(),
            );
            if !e.is_finite() {
                return Err(ResultError::NonFinite {
                    what: "invariance error".into(),
                    place: format!("order {order}, radius {radius}"),
                });
            }
            rows.push(json!({"order": order, "radius": radius, "error": e}));
        }
    }
    Ok(Value::Array(rows))
}

/// Why a backbone or transient could not be produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResultError {
    /// No polar form.
    #[error("backbone: {0}")]
    Polar(#[from] PolarError),
    /// Plot failure.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// Reduced-model integration failed.
    #[error(transparent)]
    Rom(#[from] RomError),
    /// A computed value is not finite.
    #[error("{what}: non-finite value at {place}; the expansion diverges there (lower rho_max or the order)")]
    NonFinite {
        /// Which output.
        what: String,
        /// Where.
        place: String,
    },
}

/// `backbone.csv` (`order,rho,omega,<output>...`) and `backbone.svg` (omega
/// against the amplitude of the first output, or against `rho` without
/// outputs; one curve per order).
pub fn backbone(
    ssm: &SsmExpansion,
    sec: &BackboneSection,
    outputs: &[&OutputMap],
) -> Result<(String, String), ResultError> {
    let p = polar(ssm)?;
    let orders = sec
        .orders
        .as_ref()
        .map_or_else(|| vec![ssm.order], |o| o.get_ref().clone());
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let n = *sec.points.get_ref();
    let rho_max = *sec.rho_max.get_ref();
    let mut csv = String::from("order,rho,omega");
    for o in outputs {
        csv.push(',');
        csv.push_str(&o.name);
    }
    csv.push('\n');
    let mut curves = Vec::new();
    for &order in &orders {
        let mut pts = Vec::with_capacity(n);
        for i in 0..n {
            let rho = rho_max * i as f64 / (n - 1) as f64;
            let omega = backbone_frequency(ssm, &p, rho, order);
            let amps: Vec<f64> = series
                .iter()
                .map(|s| amplitude(ssm, s, rho, order))
                .collect();
            if !omega.is_finite() || amps.iter().any(|a| !a.is_finite()) {
                return Err(ResultError::NonFinite {
                    what: "backbone".into(),
                    place: format!("order {order}, rho = {rho}"),
                });
            }
            csv.push_str(&format!("{order},{rho:.10e},{omega:.10e}"));
            for a in &amps {
                csv.push_str(&format!(",{a:.10e}"));
            }
            csv.push('\n');
            pts.push((amps.first().copied().unwrap_or(rho), omega));
        }
        curves.push(Curve {
            label: format!("O({order})"),
            points: pts,
            ..Curve::default()
        });
    }
    let x_label = outputs
        .first()
        .map_or_else(|| "rho".to_owned(), |o| format!("amplitude of {}", o.name));
    let svg = line_plot("backbone", &x_label, "omega", &curves, Scale::Linear)?;
    Ok((csv, svg))
}

/// The reduced coordinates `p = (q_1, conj q_1, q_2, ...)` with
/// `q_j = rho_j e^{i theta_j}`.
pub fn polar_point(rho: &[f64], theta: &[f64]) -> Vec<C64> {
    rho.iter()
        .zip(theta)
        .flat_map(|(&r, &t)| {
            let q = C64::from_polar(r, t);
            [q, q.conj()]
        })
        .collect()
}

/// `rom_trajectory.csv`: `t,<output>...,rho_1,theta_1,...` of the reduced
/// model integrated from `(rho0, theta0)` and lifted by `W`.
pub fn transient(
    ssm: &SsmExpansion,
    sec: &TransientSection,
    outputs: &[&OutputMap],
) -> Result<(String, usize), ResultError> {
    let order = sec.order.as_ref().map_or(ssm.order, |o| *o.get_ref());
    let m = ssm.dim() / 2;
    let theta0 = sec
        .theta0
        .as_ref()
        .map_or_else(|| vec![0.0; m], |t| t.get_ref().clone());
    let p0 = polar_point(sec.rho0.get_ref(), &theta0);
    let tr = integrate(
        ssm,
        order,
        &p0,
        *sec.t_end.get_ref(),
        *sec.samples.get_ref(),
        *sec.rtol.get_ref(),
    )?;
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let end = ssm.set.of_order(order).end;
    let mut csv = String::from("t");
    for o in outputs {
        csv.push(',');
        csv.push_str(&o.name);
    }
    for i in 1..=m {
        csv.push_str(&format!(",rho_{i},theta_{i}"));
    }
    csv.push('\n');
    for (t, p) in tr.times.iter().zip(&tr.states) {
        let mono = ssm.set.monomials(p, order);
        csv.push_str(&format!("{t:.10e}"));
        for s in &series {
            let y: C64 = (0..end).map(|i| s[i] * mono[i]).sum();
            if !y.re.is_finite() {
                return Err(ResultError::NonFinite {
                    what: "reduced-model trajectory".into(),
                    place: format!("t = {t}"),
                });
            }
            csv.push_str(&format!(",{:.10e}", y.re));
        }
        for i in 0..m {
            csv.push_str(&format!(
                ",{:.10e},{:.10e}",
                p[2 * i].norm(),
                p[2 * i].arg()
            ));
        }
        csv.push('\n');
    }
    Ok((csv, tr.steps))
}
