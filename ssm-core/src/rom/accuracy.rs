//! Error estimates of the answers read off an SSM, from the invariance
//! residual projected on the master modes.
//!
//! A truncated expansion `(W, R)` leaves the residual `r` of the invariance
//! equation (eq. 42 for the autonomous SSM, eq. 60 for the periodic one). On
//! a master pair `j` its modal part `u_j^* r` (with `u_j^* B v_j = 1`) acts
//! as an extra term of the reduced dynamics of `p_j`. Sampled along a circle
//! `p_j = q e^{i theta}`, its Fourier harmonics say what the extra term does:
//!
//! - the harmonic co-rotating with `p_j`, `c = kappa q`, shifts the eigenvalue
//!   by `kappa`: `Re kappa` changes the decay (the resonant amplitude of a
//!   forced response by `|Re kappa| / |Re lambda|`), `Im kappa` the
//!   instantaneous frequency (a backbone by `|Im kappa| / |Im lambda|`), and
//!   along a transient both accumulate, `int |kappa| dt`;
//! - every other harmonic `h` is detuned by `|h - h_co|` times the frequency
//!   unit and distorts the orbit by `|c_h| / (|h - h_co| unit |q|)`.
//!
//! This is the first-order perturbation of the reduced dynamics by the
//! first omitted terms. Near the edge of the convergence domain the terms
//! beyond fall slowly and add up, so the figure at order `O` is compared
//! with those at `O - 2` and `O - 4`: if they fall geometrically, by `q` per
//! two orders, the omitted tail is `e_O / (1 - q)` ([`tail`]). Measured on the
//! pendulum of Fig. 7 against its O(35) backbone, this lands within a factor
//! 0.5-2 of the true error at every order and amplitude up to the
//! convergence edge, where the first omitted term alone underestimates it
//! up to 4-fold. It is an estimate, not a bound. The
//! non-master part of the residual moves the outputs off the master
//! directions by `(Lambda_k B - A)^{-1} r_k` and is not included; it is of
//! the same order in `|p|` and does not touch the frequency or the decay.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), eqs. (41),
//! (42), (60), Fig. 6 (the residual grows in step with the error).

use crate::model::system::System;
use crate::spectrum::MasterMode;
use crate::ssm::modal_residual::ModalResidual;
use crate::ssm::{Dynamics, SsmExpansion};
use crate::C64;
use rayon::prelude::*;

/// Phases of a master pair sampled per turn (resolves harmonics up to 16,
/// beyond any order used in practice: order `O` has harmonics up to `O`).
pub(crate) const PHASES: usize = 32;

/// What a modal residual does to the motion of one master pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Defect {
    /// Relative eigenvalue perturbation `c_co / q` of the co-rotating
    /// harmonic, in the pair's own phase (`Re`: decay, `Im`: frequency).
    pub kappa: C64,
    /// Relative distortion of the orbit by the other harmonics.
    pub distortion: f64,
    /// The co-rotating harmonic `c_co` of the modal residual itself: in the
    /// rotating frame of a forced response, the constant perturbation of
    /// the pair's fixed-point equation.
    pub co_rotating: C64,
}

impl Defect {
    /// Relative error of a resonant forced amplitude: the relative changes
    /// of damping and frequency and the distortion.
    pub fn forced(&self, lambda: C64) -> f64 {
        self.kappa.re.abs() / lambda.re.abs()
            + self.kappa.im.abs() / lambda.im.abs()
            + self.distortion
    }

    /// Relative error of a backbone point: the frequency change and the
    /// distortion of the orbit.
    pub fn backbone(&self, lambda: C64) -> f64 {
        self.kappa.im.abs() / lambda.im.abs() + self.distortion
    }
}

/// Largest ratio `q` per two orders that [`tail`] trusts: beyond it the
/// series does not visibly converge at that amplitude.
pub const TAIL_RATIO_MAX: f64 = 0.9;

/// The truncation error of a series from its figures `e[0]` at the order
/// used, `e[1]` two orders lower and `e[2]` four orders lower (`e[1..]` may
/// be shorter): `e_0 / (1 - q)` with the ratio per two orders
/// `q = sqrt(e_0 / e_2)` (or `e_0 / e_1` without `e_2`). Over four orders,
/// so that series whose odd and even halves converge at different rates (the
/// cubic constraint of the spatial oscillator) are not taken for diverging;
/// `q` is capped at [`TAIL_RATIO_MAX`], so a diverging series gives ten
/// times `e_0`.
pub fn tail(e: &[f64]) -> f64 {
    let at = e[0];
    if e.iter().any(|x| !x.is_finite()) {
        return f64::INFINITY;
    }
    if at == 0.0 {
        return 0.0;
    }
    let q = match e {
        [_, _, far, ..] if *far > 0.0 => (at / far).sqrt(),
        [_, below, ..] if *below > 0.0 => at / below,
        [_] => 0.0,
        _ => TAIL_RATIO_MAX,
    };
    at / (1.0 - q.min(TAIL_RATIO_MAX))
}

/// `order` and the orders two and four below it that are at least 1, for [`tail`].
pub fn tail_orders(order: usize) -> Vec<usize> {
    [order, order.wrapping_sub(2), order.wrapping_sub(4)]
        .into_iter()
        .take_while(|o| (1..=order).contains(o))
        .collect()
}

/// The defect of the samples `modal[k] = u^* r(phi_k)`, `phi_k = 2 pi turns k
/// / n`, along an orbit whose pair runs through harmonic `co` (cycles per
/// sampled window) with complex amplitude `q0` at `phi = 0`; `scale` is the
/// amplitude the error is relative to (`|q0|` for one pair, `|q|` of all
/// pairs for several) and `unit` the frequency of one cycle per window.
pub fn defect(modal: &[C64], co: usize, q0: C64, scale: f64, unit: f64) -> Defect {
    let n = modal.len();
    let mut kappa = C64::new(0.0, 0.0);
    let mut co_rotating = C64::new(0.0, 0.0);
    let mut distortion = 0.0;
    for h in 0..n {
        let c: C64 = modal
            .iter()
            .enumerate()
            .map(|(k, r)| {
                r * C64::from_polar(1.0, -2.0 * std::f64::consts::PI * (h * k) as f64 / n as f64)
            })
            .sum::<C64>()
            / n as f64;
        // harmonics above n/2 are the negative ones
        let harmonic = if h <= n / 2 {
            h as f64
        } else {
            h as f64 - n as f64
        };
        if h == co {
            co_rotating = c;
            // in the pair's own phase when it moves; otherwise (a pair at
            // rest in a multi-pair orbit) the whole term counts in both parts
            kappa = if q0.norm() > 1e-3 * scale {
                c / q0 * (q0.norm() / scale)
            } else {
                let k = c.norm() / scale;
                C64::new(k, k)
            };
        } else {
            distortion += c.norm() / ((harmonic - co as f64).abs() * unit * scale);
        }
    }
    Defect {
        kappa,
        distortion,
        co_rotating,
    }
}

/// The defect of the autonomous expansion truncated at `order` on master
/// pair `j` (eigenvalue `lambda`, residual projected by `modal`) at the
/// reduced point `p` (conjugate pairs): the residual of eq. (42) with the
/// phase of pair `j` swept over a turn, the other pairs held. `None` at
/// `p_j = 0`.
///
/// For a map `lambda` is the multiplier `mu` and the residual perturbs the
/// reduced map `p -> mu p + ...`: its co-rotating part `c` moves the
/// multiplier to `mu (1 + c / (mu q))`, i.e. the exponent per step
/// `log mu` by `c / (mu q)`. The samples are divided by `mu` and the
/// detuning unit is `|log mu|`, so that the defect reads in the exponent
/// [`exponent`] as a flow's reads in its eigenvalue (the detuning of a
/// harmonic `h`, `|e^{i (h - 1) arg mu} - 1|`, is taken to first order).
pub fn pair_defect(
    ssm: &SsmExpansion,
    modal: &ModalResidual,
    lambda: C64,
    p: &[C64],
    j: usize,
    order: usize,
) -> Option<Defect> {
    let q0 = p[2 * j];
    if q0.norm() == 0.0 {
        return None;
    }
    let mut samples = modal.on_circle(ssm, p, j, order, PHASES);
    if ssm.dynamics != Dynamics::Flow {
        samples.iter_mut().for_each(|s| *s /= lambda);
    }
    let unit = exponent(ssm, lambda).norm();
    Some(defect(&samples, 1, q0, q0.norm(), unit))
}

/// The exponent a defect is measured against: the eigenvalue `lambda` of a
/// flow, `log mu` (per step) of a map's multiplier `mu`.
pub fn exponent(ssm: &SsmExpansion, lambda: C64) -> C64 {
    match ssm.dynamics {
        Dynamics::Flow => lambda,
        Dynamics::Map { .. } => lambda.ln(),
    }
}

/// Estimated relative error of a backbone point at polar amplitude `rho` of
/// a one-pair SSM truncated at `order`, its master mode of eigenvalue (or
/// multiplier) `lambda` seen through `modal`: [`Defect::backbone`] at
/// `order`, with its [`tail`] from the orders below; `None` at `rho = 0`
/// (where the linear part is exact).
pub fn backbone_error(
    ssm: &SsmExpansion,
    modal: &ModalResidual,
    lambda: C64,
    rho: f64,
    order: usize,
) -> Option<f64> {
    let p = [C64::new(rho, 0.0), C64::new(rho, 0.0)];
    let reference = exponent(ssm, lambda);
    let figures = tail_orders(order)
        .into_par_iter()
        .map(|o| pair_defect(ssm, modal, lambda, &p, 0, o).map(|d| d.backbone(reference)))
        .collect::<Option<Vec<f64>>>()?;
    Some(tail(&figures))
}

/// Estimated relative error of a reduced transient through the sampled
/// reduced states `states` at `times`: the eigenvalue defects accumulated
/// along the motion, `sum_j int |kappa_j(t)| dt` (the relative drift of
/// amplitude and phase), plus the largest distortion, at `order` with its
/// [`tail`] from the orders below; `None` for maps.
pub fn transient_error(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    times: &[f64],
    states: &[Vec<C64>],
    order: usize,
) -> Option<f64> {
    if times.is_empty() || ssm.dynamics != Dynamics::Flow {
        return None;
    }
    let modal: Vec<(ModalResidual, C64)> = masters
        .iter()
        .map(|m| (ModalResidual::new(ssm, sys, &m.left), m.lambda))
        .collect();
    let figures: Vec<f64> = tail_orders(order)
        .into_iter()
        .map(|o| drift(ssm, &modal, times, states, o))
        .collect();
    Some(tail(&figures))
}

/// The change of a reduced transient from the expansion two orders lower
/// (`lower`, same reduced start and sample times) to `values`, in the
/// metric of the full-system comparison: the largest `|difference|` over
/// the output's largest `|value|`, the largest over outputs (rows are
/// samples, columns outputs). While the series converges it bounds the
/// error of the lower order and so that of `values`.
///
/// For several master pairs the run reports the smaller of this and
/// [`transient_error`]: each overstates in its own way. The modal defect
/// overstates where the residual of eq. (42) is dominated by terms that
/// barely move the answers (on the divider the residual overstates the
/// change of the forced response 13-80-fold, and along the transient of
/// Fig. 22 it estimated 11 % where the full system measured 0.24 %); the
/// order change overstates where the series converges fast (the pendulum
/// slider at O(13): 5.3e-3 against 1.1e-4 measured).
pub(crate) fn order_change(values: &[Vec<f64>], lower: &[Vec<f64>]) -> f64 {
    let outputs = values.first().map_or(0, Vec::len);
    (0..outputs)
        .map(|k| relative_gap(values.iter().zip(lower).map(|(a, b)| (a[k], b[k]))))
        .fold(0.0, f64::max)
}

/// The largest `|a - b|` over the samples `(a, b)` of one output, relative
/// to the largest `|a|` (absolute where `a` is zero throughout): the metric
/// of the full-system transient comparison and of [`order_change`].
pub(crate) fn relative_gap(samples: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (scale, gap) = samples.fold((0.0f64, 0.0f64), |(s, g), (a, b)| {
        (s.max(a.abs()), g.max((a - b).abs()))
    });
    if scale > 0.0 {
        gap / scale
    } else {
        gap
    }
}

/// The accumulated defect and distortion of [`transient_error`] at `order`.
fn drift(
    ssm: &SsmExpansion,
    modal: &[(ModalResidual, C64)],
    times: &[f64],
    states: &[Vec<C64>],
    order: usize,
) -> f64 {
    let mut accumulated = 0.0;
    let mut distortion = 0.0f64;
    let mut last: Option<(f64, f64)> = None;
    // the defect changes smoothly along the motion: a few dozen samples
    // integrate it well, whatever the number of output samples
    let stride = times.len().div_ceil(TRANSIENT_SAMPLES).max(1);
    let picked = (0..times.len())
        .step_by(stride)
        .chain((!(times.len() - 1).is_multiple_of(stride)).then_some(times.len() - 1));
    for i in picked {
        let (t, p) = (times[i], &states[i]);
        let mut rate = 0.0;
        for (j, (m, lambda)) in modal.iter().enumerate() {
            if let Some(d) = pair_defect(ssm, m, *lambda, p, j, order) {
                // the pair's share of the whole amplitude weighs its drift
                let share = p[2 * j].norm() / norm_of_pairs(p);
                rate += d.kappa.norm() * share;
                distortion = distortion.max(d.distortion * share);
            }
        }
        if let Some((t0, r0)) = last {
            accumulated += 0.5 * (rate + r0) * (t - t0);
        }
        last = Some((t, rate));
    }
    accumulated + distortion
}

/// The error estimate of one answer of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct AnswerEstimate {
    /// `"backbone"`, `"transient"` or `"frc"`.
    pub answer: &'static str,
    /// Expansion order of the answer.
    pub order: usize,
    /// Forcing amplitude (forced responses).
    pub epsilon: Option<f64>,
    /// Estimated relative error (`None` where none is available, e.g. maps;
    /// NaN or infinite where the expansion diverged).
    pub estimate: Option<f64>,
    /// The estimate exceeds the accuracy target.
    pub untrusted: bool,
    /// Backbones: the largest amplitude `rho` up to which the target is met.
    pub trusted_up_to: Option<f64>,
}

/// An error the run measured against a full-system reference (`[validate]`).
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredError {
    /// `"transient"` or `"frc"`.
    pub answer: &'static str,
    /// Expansion order of the answer.
    pub order: usize,
    /// Forcing amplitude (forced responses).
    pub epsilon: Option<f64>,
    /// The largest relative error found (`None`: no point could be compared).
    pub relative_error: Option<f64>,
    /// The output it was found on.
    pub output: Option<String>,
    /// What it was measured against: `"full_transient"`,
    /// `"steady_state"` or `"harmonic_balance"`.
    pub against: &'static str,
}

/// How the expansion order of a run was set and what its answers are worth.
#[derive(Debug, Clone, PartialEq)]
pub struct Accuracy {
    /// The accuracy target `[ssm] tolerance`.
    pub tolerance: f64,
    /// The expansion order used.
    pub order: usize,
    /// The order was chosen by the engine from the tolerance (the scene
    /// named none).
    pub chosen: bool,
    /// The orders tried, each with the largest estimate of its answers.
    pub tried: OrdersTried,
    /// Every estimated answer.
    pub answers: Vec<AnswerEstimate>,
    /// Every error measured against the full system.
    pub measured: Vec<MeasuredError>,
}

impl Accuracy {
    /// The largest estimate of `answers` (a NaN as infinity), `None` when
    /// none has one.
    pub fn worst(answers: &[AnswerEstimate]) -> Option<f64> {
        answers
            .iter()
            .filter_map(|a| a.estimate)
            .map(|e| if e.is_nan() { f64::INFINITY } else { e })
            .reduce(f64::max)
    }
}

/// An estimate above the tolerance, or not a number (the expansion diverged).
pub fn exceeds(estimate: f64, tolerance: f64) -> bool {
    estimate.is_nan() || estimate > tolerance
}

/// The orders tried by the engine, each with the largest estimate of its
/// answers.
pub type OrdersTried = Vec<(usize, Option<f64>)>;

/// A relative error for messages: a percentage, a plain number below 1e-4
/// (`"(diverged)"` when not finite).
pub fn percent(x: f64) -> String {
    if !x.is_finite() {
        "(diverged)".into()
    } else if x >= 1e-4 || x == 0.0 {
        format!("{:.2} %", 100.0 * x)
    } else {
        format!("{x:.1e}")
    }
}

/// Samples of a transient at which its defect is evaluated.
const TRANSIENT_SAMPLES: usize = 48;

/// `|q|` over all pairs of the reduced point `p`.
fn norm_of_pairs(p: &[C64]) -> f64 {
    p.iter()
        .step_by(2)
        .map(|q| q.norm_sqr())
        .sum::<f64>()
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A residual `kappa q e^{i phi} + c2 e^{2 i phi}` is read back as its
    /// eigenvalue shift and the distortion `|c2| / (1 * unit * |q|)`.
    /// A geometric series `sum_k a q^k` truncated after `k = K` leaves
    /// `a q^(K+1) / (1 - q)`; its first omitted terms at three truncations
    /// (or two) give that tail exactly.
    #[test]
    fn tail_of_a_geometric_series() {
        let (a, q) = (0.3, 0.6f64);
        let first_omitted = |k: i32| a * q.powi(k + 1);
        let exact = a * q.powi(6) / (1.0 - q);
        let three = [first_omitted(5), first_omitted(4), first_omitted(3)];
        assert!((tail(&three) - exact).abs() < 1e-15);
        assert!((tail(&three[..2]) - exact).abs() < 1e-15);
        assert!(
            (tail(&[1e-3, 1e-4]) - 1e-2).abs() < 1e-15,
            "a growing figure: ten times"
        );
        assert_eq!(tail(&[2e-3]), 2e-3, "nothing to compare: the figure");
        assert_eq!(tail(&[0.0, 0.0]), 0.0);
        assert!(tail(&[f64::NAN, 1.0]).is_infinite());
        assert_eq!(tail_orders(7), [7, 5, 3]);
        assert_eq!(tail_orders(3), [3, 1]);
        assert_eq!(tail_orders(1), [1]);
    }

    #[test]
    fn defect_separates_the_co_rotating_harmonic() {
        let q0 = C64::from_polar(0.5, 0.3);
        let kappa = C64::new(-1e-3, 2e-3);
        let c2 = C64::new(0.0, 4e-4);
        let modal: Vec<C64> = (0..PHASES)
            .map(|k| {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / PHASES as f64;
                kappa * q0 * C64::from_polar(1.0, phi) + c2 * C64::from_polar(1.0, 2.0 * phi)
            })
            .collect();
        let d = defect(&modal, 1, q0, q0.norm(), 2.0);
        assert!((d.kappa - kappa).norm() < 1e-15, "{:?}", d.kappa);
        assert!((d.distortion - 4e-4 / (2.0 * 0.5)).abs() < 1e-15);
        let lambda = C64::new(-0.01, 1.0);
        assert!((d.forced(lambda) - (0.1 + 2e-3 + 4e-4)).abs() < 1e-12);
        assert!((d.backbone(lambda) - (2e-3 + 4e-4)).abs() < 1e-12);
    }
}
