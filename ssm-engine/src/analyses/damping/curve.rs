//! The damping curves `zeta(rho)` and their error estimates.

use rayon::prelude::*;
use schemars::JsonSchema;
use serde::Serialize;

use super::DampingSpec;
use crate::analyses::Context;
use crate::C64;
use ssm_core::rom::accuracy::{exceeds, exponent, pair_defect, tail, tail_orders, TAIL_RATIO_MAX};
use ssm_core::ssm::analysis::{amplitude, polar, Polar, PolarError};
use ssm_core::ssm::modal_residual::ModalResidual;
use ssm_core::ssm::{Dynamics, SsmExpansion};

/// Amplitudes of a curve at which its error is evaluated (linear in `rho`
/// in between: the estimate grows smoothly, like `rho^(order - 1)`).
const ESTIMATES: usize = 17;

/// Why the damping curves could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DampingError {
    /// The SSM has no polar form (not one master pair).
    #[error("{0}")]
    Polar(#[from] PolarError),
    /// The curve reaches a non-finite value.
    #[error("non-finite damping at order {order}, rho = {rho}; the expansion diverges there (lower rho_max or the order)")]
    NonFinite {
        /// Expansion order.
        order: usize,
        /// Polar amplitude.
        rho: f64,
    },
}

/// Damping curves of one master pair, one per expansion order.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct DampingCurves {
    /// The master pair (1-based).
    pub pair: usize,
    /// `zeta` at `rho = 0`: `-Re lambda / Im lambda` of the master
    /// eigenvalue (its exponent `ln mu / T` for a map).
    pub linear_zeta: f64,
    /// The accuracy target the estimates were checked against.
    pub tolerance: f64,
    /// One curve per order.
    pub curves: Vec<DampingCurve>,
}

/// The damping curve of one expansion order.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct DampingCurve {
    /// Expansion order.
    pub order: usize,
    /// Points from `rho = 0` to `rho_max`.
    pub points: Vec<DampingPoint>,
    /// The largest estimated relative error of `zeta` and `output_zeta` on
    /// the curve.
    pub error_estimate: Option<f64>,
    /// The estimate exceeds the accuracy target (or is not finite).
    pub untrusted: bool,
    /// The largest `rho` up to which every point meets the accuracy target.
    pub trusted_up_to: Option<f64>,
}

/// One point of a damping curve.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct DampingPoint {
    /// Polar amplitude `rho`.
    pub rho: f64,
    /// Instantaneous frequency `omega(rho)` (the backbone).
    pub omega: f64,
    /// Decay rate of the amplitude, `-rho' / rho`.
    pub decay_rate: f64,
    /// Damping ratio `zeta = -rho' / (rho omega)` of the polar amplitude.
    pub zeta: f64,
    /// Amplitude (largest value over a period) of each output of
    /// `[outputs] coordinates`, as on the backbone.
    pub amplitudes: Vec<f64>,
    /// Amplitude of the fundamental harmonic of each output,
    /// `A_1 = 2 |(1 / 2 pi) int y e^{-i theta} d theta|`.
    pub fundamentals: Vec<f64>,
    /// Damping ratio of each output's fundamental amplitude,
    /// `-A_1' / (A_1 omega) = zeta d ln A_1 / d ln rho`: what a Hilbert
    /// transform or a logarithmic decrement of that output's free decay
    /// reads. It differs from `zeta` where `A_1` is not proportional to
    /// `rho` (by 6 % at `x = 0.43` on the hardening Duffing oscillator).
    pub output_zeta: Vec<f64>,
    /// Estimated relative error of `zeta` plus that of the outputs' slopes
    /// `d ln A_1 / d ln rho`, so of every `output_zeta` (`None` at
    /// `rho = 0`, where the linear part is exact).
    pub error_estimate: Option<f64>,
}

/// The exponent of the reduced dynamics at amplitude `rho` truncated at
/// `order`, per step: `f(rho)` for a flow (`rho'/rho + i theta'`), `ln f`
/// for a map's multiplier `f`.
fn exponent_at(ssm: &SsmExpansion, p: &Polar, rho: f64, order: usize) -> C64 {
    let f = p.factor(rho, order);
    match ssm.dynamics {
        Dynamics::Flow => f,
        Dynamics::Map { .. } => f.ln(),
    }
}

/// The fundamental harmonic of an output's series `s` at amplitude `rho`
/// truncated at `order`: `(A_1, d ln A_1 / d ln rho)`. Its terms
/// `s_m p^{m_1} conj(p)^{m_2}` with `m_1 - m_2 = 1` make the coefficient
/// `g = sum s_m rho^{m_1 + m_2}` of `e^{i theta}`, `A_1 = 2 |g|`, and
/// `d ln |g| / d ln rho = Re(sum (m_1 + m_2) s_m rho^{m_1 + m_2} / g)`.
fn fundamental(ssm: &SsmExpansion, s: &[C64], rho: f64, order: usize) -> (f64, f64) {
    let end = ssm.set.of_order(order.min(ssm.order)).end;
    let (mut g, mut dg) = (C64::new(0.0, 0.0), C64::new(0.0, 0.0));
    for (i, c) in s.iter().enumerate().take(end) {
        let e = ssm.set.exponents(i);
        if e[0] == e[1] + 1 {
            let n = i32::from(e[0] + e[1]);
            let term = c * rho.powi(n);
            g += term;
            dg += term * f64::from(n);
        }
    }
    (2.0 * g.norm(), (dg / g).re)
}

/// Steps per unit time: 1 for a flow, `1 / T` for a map of period `T`.
fn per_time(ssm: &SsmExpansion) -> f64 {
    match ssm.dynamics {
        Dynamics::Flow => 1.0,
        Dynamics::Map { period } => 1.0 / period,
    }
}

/// Estimated relative error of `zeta = -Re s / Im s` at `rho`: the modal
/// defect of eq. (42) on the circle of radius `rho` moves the exponent `s`
/// by `kappa`, so `zeta` by `|Re kappa| / |Re s| + |Im kappa| / |Im s|`
/// relatively (the decay rate measured against the larger of its value and
/// the linear one, so that a curve crossing zero damping is not called
/// infinitely wrong), plus the distortion of the orbit; with its tail over
/// the orders below ([`tail`]).
fn zeta_error(
    ssm: &SsmExpansion,
    p: &Polar,
    modal: &ModalResidual,
    lambda: C64,
    rho: f64,
    order: usize,
) -> Option<f64> {
    let linear = exponent(ssm, lambda);
    let q = [C64::new(rho, 0.0), C64::new(rho, 0.0)];
    let figures = tail_orders(order)
        .into_iter()
        .map(|o| {
            let d = pair_defect(ssm, modal, lambda, &q, 0, o)?;
            let s = exponent_at(ssm, p, rho, o);
            Some(
                d.kappa.re.abs() / s.re.abs().max(linear.re.abs())
                    + d.kappa.im.abs() / s.im.abs()
                    + d.distortion,
            )
        })
        .collect::<Option<Vec<f64>>>()?;
    Some(tail(&figures))
}

/// Estimated relative error of the outputs' damping `zeta d ln A_1 / d ln
/// rho` beyond that of `zeta`: the truncation of `W` moves the slope
/// `d ln A_1 / d ln rho`; its relative change from two orders below,
/// `Delta_k`, at `order` and the two orders below it, gives the rest of
/// the series (the largest over the outputs; 0 without outputs, `Delta_3`
/// at order 3).
fn slope_error(ssm: &SsmExpansion, series: &[Vec<C64>], rho: f64, order: usize) -> f64 {
    series
        .iter()
        .map(|x| {
            let changes: Vec<f64> = tail_orders(order)
                .into_iter()
                .filter(|&o| o >= 3)
                .map(|o| {
                    let (_, a) = fundamental(ssm, x, rho, o);
                    let (_, b) = fundamental(ssm, x, rho, o - 2);
                    (a / b - 1.0).abs()
                })
                .collect();
            // Delta_k is about the error of order k - 2; the error of order
            // k is the rest of the series, Delta_k q / (1 - q) at the ratio
            // q per two orders ([tail] times q; Delta_k itself without a
            // ratio)
            match changes.as_slice() {
                [] => 0.0,
                [one] => *one,
                [at, below, ..] => {
                    let q = (at / below).min(TAIL_RATIO_MAX);
                    if q.is_finite() {
                        tail(&changes) * q
                    } else {
                        *at
                    }
                }
            }
        })
        .fold(0.0, f64::max)
}

/// The damping curves of `spec` on the SSM of `cx` (one master pair).
pub fn damping_curves(spec: &DampingSpec, cx: &Context<'_>) -> Result<DampingCurves, DampingError> {
    let ssm = cx.ssm;
    let p = polar(ssm)?;
    let master = &cx.masters[0];
    let modal = ModalResidual::new(ssm, cx.system, &master.left);
    let series: Vec<Vec<C64>> = cx
        .outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let rate = per_time(ssm);
    let orders = spec.orders.clone().unwrap_or_else(|| vec![ssm.order]);
    let n = spec.points;
    let mut curves = Vec::with_capacity(orders.len());
    for &order in &orders {
        let mut points = Vec::with_capacity(n);
        for i in 0..n {
            let rho = spec.rho_max * i as f64 / (n - 1) as f64;
            let s = exponent_at(ssm, &p, rho, order);
            let amplitudes: Vec<f64> = series
                .iter()
                .map(|x| amplitude(ssm, x, rho, order))
                .collect();
            let zeta = -s.re / s.im;
            // at rho = 0 the output's amplitude is linear in rho
            let (fundamentals, output_zeta): (Vec<f64>, Vec<f64>) = series
                .iter()
                .map(|x| match fundamental(ssm, x, rho, order) {
                    (a, _) if rho == 0.0 => (a, zeta),
                    (a, slope) => (a, zeta * slope),
                })
                .unzip();
            let finite = |v: &[f64]| v.iter().all(|a| a.is_finite());
            if !zeta.is_finite() || !finite(&amplitudes) || !finite(&fundamentals) {
                return Err(DampingError::NonFinite { order, rho });
            }
            points.push(DampingPoint {
                rho,
                omega: s.im * rate,
                decay_rate: -s.re * rate,
                zeta,
                amplitudes,
                fundamentals,
                output_zeta,
                error_estimate: None,
            });
        }
        // the estimate at ESTIMATES knots, linear in rho in between
        let stride = (n - 1).div_ceil(ESTIMATES - 1).max(1);
        let mut knots: Vec<usize> = (0..n).step_by(stride).collect();
        if knots.last() != Some(&(n - 1)) {
            knots.push(n - 1);
        }
        let at: Vec<Option<f64>> = knots
            .par_iter()
            .map(|&i| {
                let rho = points[i].rho;
                zeta_error(ssm, &p, &modal, master.lambda, rho, order)
                    .map(|e| e + slope_error(ssm, &series, rho, order))
            })
            .collect();
        for w in knots.windows(2).zip(at.windows(2)) {
            let ([i, j], [a, b]) = w else { continue };
            for (k, point) in points.iter_mut().enumerate().take(*j + 1).skip(*i) {
                let s = (k - i) as f64 / (j - i) as f64;
                point.error_estimate = match (a, b) {
                    (Some(a), Some(b)) => Some(a + s * (b - a)),
                    (None, Some(b)) if k > 0 => Some(s * b),
                    _ => None,
                };
            }
        }
        let error_estimate = points
            .iter()
            .filter_map(|p| p.error_estimate)
            .reduce(|a, b| {
                if a.is_nan() || b.is_nan() {
                    f64::NAN
                } else {
                    a.max(b)
                }
            });
        let trusted_up_to = error_estimate.map(|_| {
            points
                .iter()
                .take_while(|p| p.error_estimate.is_none_or(|e| !exceeds(e, cx.tolerance)))
                .last()
                .map_or(0.0, |p| p.rho)
        });
        curves.push(DampingCurve {
            order,
            points,
            error_estimate,
            untrusted: error_estimate.is_some_and(|e| exceeds(e, cx.tolerance)),
            trusted_up_to,
        });
    }
    let linear = exponent(ssm, master.lambda);
    Ok(DampingCurves {
        pair: master.pair,
        linear_zeta: -linear.re / linear.im,
        tolerance: cx.tolerance,
        curves,
    })
}
