//! The Hilber-Hughes-Taylor (HHT-alpha) method for index-3 multibody DAEs
//! `M q'' = Q(q, q', t) - G(q)^T mu`, `0 = g(q)`: the integrator of MSC Adams
//! and FreeDyn, used by Stadlmayr, Witteveen & Steiner (2017) for the full
//! and the POD-reduced models.
//!
//! # Method
//! With `f(z, t)` the force of the momentum rows, `A z + F(z) + eps Fext`
//! less the damping `C q'` that the first-order form (eqs. (4)-(5) of Li,
//! Jain & Haller 2023) keeps in `B` (so `f` holds the elastic, damping,
//! external and constraint forces; `z = (q, q', mu)`), one step solves for the new
//! accelerations `a` and multipliers `mu` (Negrut et al. 2007, eqs. (7)-(9)):
//!
//! - `M a_{n+1} - (1 + alpha) f(z_{n+1}, t_{n+1}) + alpha f(z_n, t_n) = 0`,
//! - `g(q_{n+1}) / (beta h^2) = 0`,
//! - `q_{n+1} = q_n + h q'_n + h^2/2 ((1 - 2 beta) a_n + 2 beta a_{n+1})`,
//!   `q'_{n+1} = q'_n + h ((1 - gamma) a_n + gamma a_{n+1})`,
//!
//! with `alpha` in `[-1/3, 0]`, `gamma = (1 - 2 alpha) / 2`,
//! `beta = (1 - alpha)^2 / 4`: second order, unconditionally stable on
//! linear problems, with spectral radius `(1 + alpha) / (1 - alpha)` at
//! infinite frequency (`alpha = 0`: the trapezoidal Newmark method, no
//! numerical damping). The constraint rows are divided by `beta h^2`, so the
//! iteration matrix
//! `[M - (1 + alpha)(beta h^2 f_q + gamma h f_q'), -(1 + alpha) f_mu; G, 0]`
//! keeps entries of order one as `h -> 0` (the scaling of the paper and of
//! Negrut et al.; unscaled, its condition grows like `h^-2`). Newton uses
//! the analytic sparse Jacobian of the polynomial model on one symbolic LU
//! for the run; a step whose Newton iteration fails is halved. Steps are
//! fixed (growing back after five converged ones), or controlled by the
//! local error of the positions, `(beta - 1/6) h^2 (a_{n+1} - a_n)`.
//!
//! A recast model's auxiliaries `w` (Li, Jain & Haller 2023, Sect. 4.2:
//! `u_s = sin a`, `u_c = 1 - cos a`, ...) are unknowns of the same Newton
//! iteration, moved with the positions (`w = w_pred + beta h^2 w_hat`, the
//! prediction along their last rate, so their columns scale like the
//! positions'): a differential auxiliary `B_w w' = f_w(z)` by the trapezoidal
//! rule, `B_w (w_{n+1} - w_n) = h/2 (f_w(z_{n+1}) + f_w(z_n))` (second order,
//! free of the HHT shift, which only the second-order rows need), an
//! algebraic one exactly; both rows are divided by `beta h^2` like the
//! constraints.
//!
//! Consistent starts come from [`super::consistent_initial`]
//! (positions, velocities and multipliers); the first accelerations from
//! `M a_0 = f(z_0, t_0)`.
//!
//! # References
//! H. M. Hilber, T. J. R. Hughes, R. L. Taylor, *Improved numerical
//! dissipation for time integration algorithms in structural dynamics*,
//! Earthq. Eng. Struct. Dyn. 5 (1977) 283-292; D. Negrut, R. Rampalli,
//! G. Ottarsson, A. Sajdak, *On an implementation of the Hilber-Hughes-Taylor
//! method in the context of index 3 differential-algebraic equations of
//! multibody dynamics*, J. Comput. Nonlinear Dyn. 2 (2007) 73-85;
//! M. Stadlmayr, W. Witteveen, W. Steiner, Multibody Syst. Dyn. (2017).

mod iteration;
mod step;

pub use step::Hht;

use super::{DaeProblem, SimError};
use ssm_kernel::stepper::Stepper;

/// Settings of an HHT run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HhtOptions {
    /// `alpha` in `[-1/3, 0]` (0: no numerical damping).
    pub alpha: f64,
    /// Step size `h`: fixed (halved where Newton fails), or the first and
    /// largest step with [`HhtOptions::local_error`].
    pub step: f64,
    /// Step-size control on the positions' local error, `(rtol, atol)`:
    /// `(beta - 1/6) h^2 |a_{n+1} - a_n|` (the leading term of the Newmark
    /// position formula's truncation error, Negrut et al. 2007, Sect. 4) kept
    /// below `atol + rtol |q|`; `None`: fixed steps.
    pub local_error: Option<(f64, f64)>,
    /// Newton stops when every correction is below `tol (1 + |value|)`.
    pub tol: f64,
    /// Newton iterations per attempt.
    pub max_newton: usize,
}

impl HhtOptions {
    /// `alpha` and `step` with Newton at `1e-10`, 8 iterations.
    pub fn new(alpha: f64, step: f64) -> Self {
        Self {
            alpha,
            step,
            local_error: None,
            tol: 1e-10,
            max_newton: 8,
        }
    }

    /// [`HhtOptions::new`] with step-size control at `(rtol, atol)`, `step`
    /// the first and largest step.
    pub fn adaptive(alpha: f64, step: f64, rtol: f64, atol: f64) -> Self {
        Self {
            local_error: Some((rtol, atol)),
            ..Self::new(alpha, step)
        }
    }

    /// `(gamma, beta)` of `alpha`.
    pub(crate) fn newmark(&self) -> (f64, f64) {
        (0.5 - self.alpha, 0.25 * (1.0 - self.alpha).powi(2))
    }

    fn check(&self) -> Result<(), SimError> {
        if !(-1.0 / 3.0..=0.0).contains(&self.alpha) {
            return Err(SimError::Settings(format!(
                "HHT alpha = {} must lie in [-1/3, 0]",
                self.alpha
            )));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(SimError::Settings(format!(
                "HHT step {} must be positive",
                self.step
            )));
        }
        if let Some((rtol, atol)) = self.local_error {
            if !(rtol > 0.0 && rtol < 1.0 && atol > 0.0 && atol.is_finite()) {
                return Err(SimError::Settings(format!(
                    "HHT tolerances must satisfy 0 < rtol < 1 and atol > 0 (rtol = {rtol}, atol = {atol})"
                )));
            }
        }
        if !(self.tol.is_finite() && self.tol > 0.0) || self.max_newton == 0 {
            return Err(SimError::Settings(
                "HHT Newton tolerance must be positive and iterations at least 1".into(),
            ));
        }
        Ok(())
    }
}

/// Counters of an HHT run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HhtStats {
    /// Steps taken.
    pub steps: usize,
    /// Step attempts whose Newton iteration failed (then halved).
    pub rejected: usize,
    /// Newton iterations.
    pub newton: usize,
    /// Numeric LU factorizations of the iteration matrix.
    pub factorizations: usize,
}

/// The states of an HHT run at its step ends.
#[derive(Debug, Clone, PartialEq)]
pub struct HhtSolution {
    /// Step end times, from `t0`.
    pub times: Vec<f64>,
    /// The full state `z = (q, q', mu)` at each time.
    pub states: Vec<Vec<f64>>,
    /// The accelerations `a` at each time.
    pub accelerations: Vec<Vec<f64>>,
    /// Counters.
    pub stats: HhtStats,
}

impl HhtSolution {
    /// The state at `t` inside the run: `q` and `q'` by cubic Hermite
    /// interpolation from `(q, q')` and `(q', a)` at the step ends (error
    /// `O(h^4)`, below the method's `O(h^2)`), `mu` linearly.
    pub fn at(&self, t: f64, n_dof: usize) -> Vec<f64> {
        let k = match self.times.partition_point(|&s| s <= t) {
            0 => 0,
            k if k >= self.times.len() => self.times.len().saturating_sub(2),
            k => k - 1,
        };
        if self.times.len() < 2 {
            return self.states[0].clone();
        }
        hermite(
            t,
            (self.times[k], &self.states[k], &self.accelerations[k]),
            (
                self.times[k + 1],
                &self.states[k + 1],
                &self.accelerations[k + 1],
            ),
            n_dof,
        )
    }
}

/// The state at `t` between the step ends `(t0, z0, a0)` and `(t1, z1, a1)`:
/// `q` and `q'` by cubic Hermite interpolation from `(q, q')` and `(q', a)`
/// (error `O(h^4)`, below the method's `O(h^2)`), `mu` linearly.
pub fn hermite(
    t: f64,
    (t0, z0, a0): (f64, &[f64], &[f64]),
    (t1, z1, a1): (f64, &[f64], &[f64]),
    n_dof: usize,
) -> Vec<f64> {
    let h = t1 - t0;
    let s = (t - t0) / h;
    let (h00, h10, h01, h11) = (
        (1.0 + 2.0 * s) * (1.0 - s).powi(2),
        s * (1.0 - s).powi(2),
        s * s * (3.0 - 2.0 * s),
        s * s * (s - 1.0),
    );
    let mut out = z0.to_vec();
    for i in 0..n_dof {
        let (v0, v1) = (z0[n_dof + i], z1[n_dof + i]);
        out[i] = h00 * z0[i] + h * h10 * v0 + h01 * z1[i] + h * h11 * v1;
        out[n_dof + i] = h00 * v0 + h * h10 * a0[i] + h01 * v1 + h * h11 * a1[i];
    }
    for i in 2 * n_dof..out.len() {
        out[i] = (1.0 - s) * z0[i] + s * z1[i];
    }
    out
}

/// Most steps of one run (the same budget as Radau's default).
const MAX_STEPS: usize = 2_000_000;

/// Integrates `p` from the start `guess` (made consistent first) over
/// `[t0, t_end]` with HHT-alpha and keeps every step end (memory grows with
/// the steps: `integrate_with` streams them instead).
pub fn integrate(
    p: &DaeProblem,
    guess: &[f64],
    t0: f64,
    t_end: f64,
    o: &HhtOptions,
) -> Result<HhtSolution, SimError> {
    let mut sol = HhtSolution {
        times: Vec::new(),
        states: Vec::new(),
        accelerations: Vec::new(),
        stats: HhtStats::default(),
    };
    sol.stats = integrate_with(p, guess, t0, t_end, o, |t, z, a| {
        sol.times.push(t);
        sol.states.push(z.to_vec());
        sol.accelerations.push(a.to_vec());
    })?;
    Ok(sol)
}

/// [`integrate`] without keeping the run: `on_step(t, z, a)` sees the
/// consistent start and then every step end, in order; returns the counters.
pub(crate) fn integrate_with(
    p: &DaeProblem,
    guess: &[f64],
    t0: f64,
    t_end: f64,
    o: &HhtOptions,
    mut on_step: impl FnMut(f64, &[f64], &[f64]),
) -> Result<HhtStats, SimError> {
    o.check()?;
    if !(t0.is_finite() && t_end.is_finite() && t_end > t0) {
        return Err(SimError::Settings(format!(
            "HHT interval [{t0}, {t_end}] is empty or not finite"
        )));
    }
    let mut hht = Hht::new(p, guess, t0, o)?;
    on_step(t0, hht.state(), hht.accelerations());
    while hht.t() < t_end {
        hht.advance(t_end)?;
        on_step(hht.t(), hht.state(), hht.accelerations());
    }
    Ok(hht.hht_stats())
}

/// Fewest HHT steps per forcing period without a warning. HHT is a
/// second-order Newmark method: on an undamped oscillation of frequency
/// `Omega` its period is too long by about `(Omega h)^2 / 12` relative
/// (Hilber, Hughes & Taylor 1977; Hughes, *The Finite Element Method*
/// (1987), Sect. 9.3), which is 0.8 % at 20 steps per period (`Omega h =
/// 2 pi / 20`) and grows fourfold at each halving of the steps: beyond a
/// few percent of phase per period the reduced and full responses compared
/// differ by the integrator, not by the reduction.
pub const MIN_STEPS_PER_PERIOD: f64 = 20.0;

/// What the fixed HHT step `step` makes of a load of frequency `omega`: an
/// error above the step's Nyquist frequency `pi / step` (fewer than two
/// steps per period: the load is sampled as a slower one, aliased), a
/// warning below [`MIN_STEPS_PER_PERIOD`] steps per period, nothing for
/// `omega = 0` (a free run) or finer steps.
pub fn load_sampling(step: f64, omega: f64) -> Result<Option<String>, String> {
    if omega <= 0.0 {
        return Ok(None);
    }
    let per_period = 2.0 * std::f64::consts::PI / (omega * step);
    if omega * step > std::f64::consts::PI {
        return Err(format!(
            "omega = {omega} is above the Nyquist frequency pi / step = {:.6} of the HHT step {step} ({per_period:.3} steps per forcing period; at least 2 are needed, {MIN_STEPS_PER_PERIOD} for a phase error below 1 % per period): the step cannot resolve the load; lower step to at most {:.3e}",
            std::f64::consts::PI / step,
            2.0 * std::f64::consts::PI / (MIN_STEPS_PER_PERIOD * omega)
        ));
    }
    if per_period < MIN_STEPS_PER_PERIOD {
        return Ok(Some(format!(
            "omega = {omega} gets {per_period:.1} HHT steps of {step} per forcing period, fewer than {MIN_STEPS_PER_PERIOD}: the integrator's period error, about (omega step)^2 / 12 = {:.1e} per period, is part of every response compared; lower step to at most {:.3e}",
            (omega * step).powi(2) / 12.0,
            2.0 * std::f64::consts::PI / (MIN_STEPS_PER_PERIOD * omega)
        )));
    }
    Ok(None)
}
