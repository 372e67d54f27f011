//! Answers of the autonomous reduced model: backbone curves, the invariance
//! error table, and reduced transients lifted to physical outputs.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023): backbone
//! curves from the polar form of the reduced dynamics (Sect. 3.3), the
//! invariance error eq. (41), reduced transients (Figs. 4, 10, 14); their
//! error estimates are those of [`crate::rom::accuracy`].

use rayon::prelude::*;

use crate::model::system::{OutputMap, System};
use crate::rom::accuracy;
use crate::spec::{BackboneSpec, InvarianceSpec, TransientSpec};
use crate::spectrum::MasterMode;
use crate::ssm::analysis::{amplitude, backbone_frequency, invariance_error, polar, PolarError};
use crate::ssm::modal_residual::ModalResidual;
use crate::ssm::rom::{integrate, RomError};
use crate::ssm::SsmExpansion;
use crate::C64;

/// Why a backbone, invariance table or transient could not be produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResultError {
    /// No polar form.
    #[error("backbone: {0}")]
    Polar(#[from] PolarError),
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

/// One point of a backbone curve.
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct BackbonePoint {
    /// Polar amplitude `rho` of the master pair.
    pub rho: f64,
    /// Instantaneous frequency `omega(rho)`.
    pub omega: f64,
    /// Amplitude of each requested output.
    pub amplitudes: Vec<f64>,
    /// Estimated relative error ([`accuracy::backbone_error`], interpolated
    /// between the amplitudes where it is evaluated).
    pub error_estimate: Option<f64>,
}

/// A backbone curve of one expansion order.
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct BackboneCurve {
    /// Expansion order.
    pub order: usize,
    /// Points from `rho = 0` to `rho_max`.
    pub points: Vec<BackbonePoint>,
    /// The largest estimated relative error on the curve.
    pub error_estimate: Option<f64>,
    /// The estimate exceeds the accuracy target (or is not finite).
    pub untrusted: bool,
    /// The largest `rho` up to which every point meets the accuracy target.
    pub trusted_up_to: Option<f64>,
}

/// Amplitudes of a backbone at which its error is evaluated (the rest are
/// interpolated: the estimate grows smoothly, like `rho^(order - 1)`).
const BACKBONE_ESTIMATES: usize = 17;

/// Backbone curves of `sec` (one per order) on `points` amplitudes in
/// `[0, rho_max]`; the amplitudes of `outputs` are read off `W`; each point
/// with its error estimate, each curve checked against the relative
/// `tolerance`.
pub fn backbone(
    ssm: &SsmExpansion,
    sys: &System,
    master: &MasterMode,
    sec: &BackboneSpec,
    outputs: &[&OutputMap],
    tolerance: f64,
) -> Result<Vec<BackboneCurve>, ResultError> {
    let p = polar(ssm)?;
    let orders = sec.orders.clone().unwrap_or_else(|| vec![ssm.order]);
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let n = sec.points;
    let rho_max = sec.rho_max;
    let modal = ModalResidual::new(ssm, sys, &master.left);
    let mut curves = Vec::with_capacity(orders.len());
    for &order in &orders {
        let mut points = Vec::with_capacity(n);
        for i in 0..n {
            let rho = rho_max * i as f64 / (n - 1) as f64;
            let omega = backbone_frequency(ssm, &p, rho, order);
            let amplitudes: Vec<f64> = series
                .iter()
                .map(|s| amplitude(ssm, s, rho, order))
                .collect();
            if !omega.is_finite() || amplitudes.iter().any(|a| !a.is_finite()) {
                return Err(ResultError::NonFinite {
                    what: "backbone".into(),
                    place: format!("order {order}, rho = {rho}"),
                });
            }
            points.push(BackbonePoint {
                rho,
                omega,
                amplitudes,
                error_estimate: None,
            });
        }
        let error_estimate = estimate_along(&mut points, |rho| {
            accuracy::backbone_error(ssm, &modal, master.lambda, rho, order)
        });
        let trusted_up_to = error_estimate.map(|_| {
            points
                .iter()
                .take_while(|p| {
                    p.error_estimate
                        .is_some_and(|e| !accuracy::exceeds(e, tolerance))
                })
                .last()
                .map_or(0.0, |p| p.rho)
        });
        curves.push(BackboneCurve {
            order,
            points,
            error_estimate,
            untrusted: error_estimate.is_some_and(|e| accuracy::exceeds(e, tolerance)),
            trusted_up_to,
        });
    }
    Ok(curves)
}

/// Fills the points' error estimates: `estimate` at
/// [`BACKBONE_ESTIMATES`] evenly spaced points, linear in `rho` in between;
/// returns the largest (NaN when one is not finite).
fn estimate_along(
    points: &mut [BackbonePoint],
    estimate: impl Fn(f64) -> Option<f64> + Sync,
) -> Option<f64> {
    let n = points.len();
    let stride = (n - 1).div_ceil(BACKBONE_ESTIMATES - 1).max(1);
    let at: Vec<(usize, f64)> = (0..n)
        .step_by(stride)
        .chain((!(n - 1).is_multiple_of(stride)).then_some(n - 1))
        .map(|i| (i, points[i].rho))
        .collect();
    let knots: Vec<(usize, f64)> = at
        .into_par_iter()
        .map(|(i, rho)| {
            let e = if rho == 0.0 { Some(0.0) } else { estimate(rho) };
            e.map(|e| (i, e))
        })
        .collect::<Option<Vec<_>>>()?;
    for w in knots.windows(2) {
        let ((i0, e0), (i1, e1)) = (w[0], w[1]);
        let (r0, r1) = (points[i0].rho, points[i1].rho);
        for p in &mut points[i0..=i1] {
            let s = if r1 > r0 {
                (p.rho - r0) / (r1 - r0)
            } else {
                0.0
            };
            p.error_estimate = Some(e0 + s * (e1 - e0));
        }
    }
    if let [(i, e)] = knots[..] {
        points[i].error_estimate = Some(e);
    }
    Some(
        knots
            .iter()
            .map(|k| k.1)
            .fold(0.0, |a, e| if e.is_nan() { e } else { a.max(e) }),
    )
}

/// One entry of the invariance-error table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvarianceEntry {
    /// Expansion order.
    pub order: usize,
    /// Radius of the sampled torus.
    pub radius: f64,
    /// Eq. (41) there.
    pub error: f64,
}

/// Eq. (41) for every requested order and radius of `sec`.
pub fn invariance_table(
    ssm: &SsmExpansion,
    sys: &System,
    sec: &InvarianceSpec,
) -> Result<Vec<InvarianceEntry>, ResultError> {
    let mut rows = Vec::new();
    for &order in &sec.orders {
        for &radius in &sec.radii {
            let error = invariance_error(ssm, sys, order, radius, sec.n_alpha, sec.n_theta);
            if !error.is_finite() {
                return Err(ResultError::NonFinite {
                    what: "invariance error".into(),
                    place: format!("order {order}, radius {radius}"),
                });
            }
            rows.push(InvarianceEntry {
                order,
                radius,
                error,
            });
        }
    }
    Ok(rows)
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

/// The outputs `Re sum_k s_k p^k` (series `s` of each output, truncated at
/// `order`) along the reduced states, one row per sample.
fn lift(
    ssm: &SsmExpansion,
    series: &[Vec<C64>],
    order: usize,
    times: &[f64],
    states: &[Vec<C64>],
) -> Result<Vec<Vec<f64>>, ResultError> {
    let end = ssm.set.of_order(order).end;
    times
        .iter()
        .zip(states)
        .map(|(t, p)| {
            let mono = ssm.set.monomials(p, order);
            series
                .iter()
                .map(|s| {
                    let y: C64 = (0..end).map(|i| s[i] * mono[i]).sum();
                    if y.re.is_finite() {
                        Ok(y.re)
                    } else {
                        Err(ResultError::NonFinite {
                            what: "reduced-model trajectory".into(),
                            place: format!("t = {t}"),
                        })
                    }
                })
                .collect()
        })
        .collect()
}

/// A reduced transient lifted to physical outputs.
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct LiftedTransient {
    /// Expansion order of the reduced model.
    pub order: usize,
    /// Sample times.
    pub times: Vec<f64>,
    /// Per sample: each output's value `Re (W(p(t)))` in the output's weights.
    pub outputs: Vec<Vec<f64>>,
    /// Per sample: `(rho_j, theta_j)` of each master pair.
    pub polar: Vec<Vec<(f64, f64)>>,
    /// Accepted steps of the reduced integration.
    pub steps: usize,
    /// Estimated relative error ([`accuracy::transient_error`]); `None` for maps.
    pub error_estimate: Option<f64>,
    /// The estimate exceeds the accuracy target (or is not finite).
    pub untrusted: bool,
}

/// The reduced model of `sec` integrated from `(rho0, theta0)` and lifted by
/// `W`, with its error estimate checked against the relative `tolerance`.
pub fn transient(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    sec: &TransientSpec,
    outputs: &[&OutputMap],
    tolerance: f64,
) -> Result<LiftedTransient, ResultError> {
    let order = sec.order.unwrap_or(ssm.order);
    let m = ssm.dim() / 2;
    let theta0 = sec.theta0.clone().unwrap_or_else(|| vec![0.0; m]);
    let p0 = polar_point(&sec.rho0, &theta0);
    let tr = integrate(ssm, order, &p0, sec.t_end, sec.samples, sec.rtol)?;
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let values = lift(ssm, &series, order, &tr.times, &tr.states)?;
    let polar = tr
        .states
        .iter()
        .map(|p| (0..m).map(|i| (p[2 * i].norm(), p[2 * i].arg())).collect())
        .collect();
    let defect = accuracy::transient_error(ssm, sys, masters, &tr.times, &tr.states, order);
    let error_estimate = match defect {
        // several pairs: the smaller of the modal defect and the change from
        // two orders lower (see accuracy::order_change)
        Some(d) if m > 1 && order >= 3 => {
            let lower = integrate(ssm, order - 2, &p0, sec.t_end, sec.samples, sec.rtol)
                .ok()
                .and_then(|l| lift(ssm, &series, order - 2, &l.times, &l.states).ok())
                .filter(|l| l.len() == values.len());
            // a lower order that blows up or stops early leaves the defect
            Some(lower.map_or(d, |l| d.min(accuracy::order_change(&values, &l))))
        }
        other => other,
    };
    Ok(LiftedTransient {
        order,
        times: tr.times,
        outputs: values,
        polar,
        steps: tr.steps,
        error_estimate,
        untrusted: error_estimate.is_some_and(|e| accuracy::exceeds(e, tolerance)),
    })
}
