//! The HHT-alpha integration in progress: one accepted step at a time,
//! behind the kernel's integrator interface ([`Stepper`]), with the
//! Hermite dense output between step ends.

use super::iteration::{initial_accelerations, layout, momentum_force, Iteration, Layout};
use super::{hermite, HhtOptions, HhtStats, MAX_STEPS};
use crate::fom::{consistent_initial, DaeProblem, SimError};
use ssm_kernel::stepper::{StepStats, Stepper};

/// An HHT-alpha integration in progress (the method of [`super`]).
pub struct Hht<'p, 'a> {
    p: &'p DaeProblem<'a>,
    o: HhtOptions,
    l: Layout,
    it: Iteration,
    gamma: f64,
    beta: f64,
    /// `1 + alpha`.
    w: f64,
    first_aux: usize,
    /// The time reached, its state `z = (q, q', mu, w)` and accelerations.
    t: f64,
    z: Vec<f64>,
    a: Vec<f64>,
    /// The start of the last step, for the dense output.
    t_prev: f64,
    z_prev: Vec<f64>,
    a_prev: Vec<f64>,
    /// The next step size to try.
    h: f64,
    /// The step size the iteration matrix was factored for; NaN: refactor
    /// (a new step size, or a Jacobian gone stale along the motion).
    h_factored: f64,
    /// Converged steps since the last change of step size.
    good: usize,
    /// The auxiliaries' last rates: they are predicted along them and
    /// corrected with the positions (`w = w_pred + beta h^2 w_hat`).
    w_rate: Vec<f64>,
    jac: Vec<f64>,
    f_old: Vec<f64>,
    f_new: Vec<f64>,
    bz: Vec<f64>,
    bw: Vec<f64>,
    acc: Vec<f64>,
    stats: HhtStats,
}

impl<'p, 'a> Hht<'p, 'a> {
    /// Starts at `t0` from `guess`, made consistent first (positions,
    /// velocities and multipliers), with the first accelerations from
    /// `M a_0 = f(z_0, t_0)`.
    ///
    /// # Errors
    /// [`SimError`] for settings out of range, a model that is not the
    /// mechanical builder's first-order form, or an inconsistent start.
    pub fn new(
        p: &'p DaeProblem<'a>,
        guess: &[f64],
        t0: f64,
        o: &HhtOptions,
    ) -> Result<Self, SimError> {
        o.check()?;
        let l = layout(p)?;
        let (n, big_n) = (l.n, p.n());
        let z0 = consistent_initial(p, t0, guess)?.z;
        let it = Iteration::new(p, &l)?;
        let mut f_old = vec![0.0; big_n];
        let mut bz = vec![0.0; big_n];
        let mut acc = vec![0.0; big_n];
        p.rhs(t0, &z0, &mut f_old);
        momentum_force(p, &z0, &mut f_old, &mut bz, &mut acc, n);
        let a0 = initial_accelerations(p, &l, &f_old, t0)?;
        let (gamma, beta) = o.newmark();
        let first_aux = 2 * n + l.n_c;
        Ok(Hht {
            p,
            o: *o,
            it,
            gamma,
            beta,
            w: 1.0 + o.alpha,
            first_aux,
            t: t0,
            z_prev: z0.clone(),
            a_prev: a0.clone(),
            z: z0,
            a: a0,
            t_prev: t0,
            h: o.step,
            h_factored: f64::NAN,
            good: 0,
            w_rate: vec![0.0; big_n - first_aux],
            jac: vec![0.0; p.b_values().len()],
            f_old,
            f_new: vec![0.0; big_n],
            bz,
            bw: vec![0.0; big_n],
            acc,
            stats: HhtStats::default(),
            l,
        })
    }

    /// The accelerations at [`Stepper::t`].
    pub fn accelerations(&self) -> &[f64] {
        &self.a
    }

    /// The counters so far.
    pub(crate) fn hht_stats(&self) -> HhtStats {
        self.stats
    }

    /// One accepted step ending at `t_end` at the latest: Newton on
    /// `(a_{n+1}, mu_{n+1}, w_hat)`; a step whose iteration fails is retried
    /// with a fresh matrix, then halved; with `local_error` a step whose
    /// error is too large is retried shorter.
    ///
    /// # Errors
    /// [`SimError`] when the state turns non-finite, the step collapses or
    /// the steps run out.
    pub fn advance(&mut self, t_end: f64) -> Result<(), SimError> {
        if self.t >= t_end || t_end.is_nan() {
            return Err(SimError::Settings(format!(
                "HHT step asked to end at {t_end}, not after t = {}",
                self.t
            )));
        }
        let p = self.p;
        let o = self.o;
        let o = &o;
        let (gamma, beta, w, first_aux) = (self.gamma, self.beta, self.w, self.first_aux);
        let Hht {
            l,
            it,
            t: t_now,
            z,
            a,
            t_prev,
            z_prev,
            a_prev,
            h: h_next,
            h_factored: hf,
            good: good_n,
            w_rate,
            jac,
            f_old,
            f_new,
            bz,
            bw,
            acc,
            stats,
            ..
        } = self;
        let (n, big_n) = (l.n, p.n());
        let (mut t, mut h, mut h_factored, mut good) = (*t_now, *h_next, *hf, *good_n);
        if ssm_kernel::cancel::requested() {
            return Err(SimError::Interrupted { t });
        }
        loop {
            if stats.steps >= MAX_STEPS {
                return Err(SimError::TooManySteps {
                    t,
                    steps: stats.steps,
                    t_end,
                });
            }
            // the last step takes up what the sum of the steps leaves (no
            // sliver of round-off as a step of its own)
            let t1 = if t_end - t <= h * (1.0 + 1e-8) {
                t_end
            } else {
                t + h
            };
            let hs = t1 - t;
            // unknowns (a_{n+1}, mu_{n+1}, w_hat) from the predictor (a_n, mu_n, 0)
            let mut u: Vec<f64> = a
                .iter()
                .chain(&z[2 * n..first_aux])
                .copied()
                .chain(std::iter::repeat_n(0.0, big_n - first_aux))
                .collect();
            let w_pred: Vec<f64> = (first_aux..big_n)
                .map(|i| z[i] + hs * w_rate[i - first_aux])
                .collect();
            let step = Newmark {
                n,
                n_c: l.n_c,
                h: hs,
                gamma,
                beta,
                w_pred: &w_pred,
            };
            let mut z1 = z.clone();
            let mut converged = false;
            let mut fresh = false;
            let mut iterations = 0;
            let mut last_size = f64::INFINITY;
            for k in 0..o.max_newton {
                iterations = k + 1;
                step.state(z, a, &u, &mut z1);
                p.rhs(t1, &z1, f_new);
                if let Some(i) = f_new.iter().position(|v| !v.is_finite()) {
                    return Err(SimError::NonFinite {
                        t: t1,
                        state: p.state_name(i.min(big_n - 1)).to_owned(),
                    });
                }
                momentum_force(p, &z1, f_new, bz, acc, n);
                acc.iter_mut().for_each(|v| *v = 0.0);
                acc[n..2 * n].copy_from_slice(&u[..n]);
                p.b_mul(acc, bz);
                // B_w (w_{n+1} - w_n) of the differential auxiliaries (none
                // without a recast: no product)
                if first_aux < big_n {
                    acc.iter_mut().for_each(|v| *v = 0.0);
                    for i in first_aux..big_n {
                        acc[i] = z1[i] - z[i];
                    }
                    p.b_mul(acc, bw);
                }
                // residual: momentum rows, then the scaled constraint and
                // auxiliary rows
                let bh2 = beta * hs * hs;
                let mut r: Vec<f64> = (0..n)
                    .map(|i| -(bz[i] - w * f_new[i] + o.alpha * f_old[i]))
                    .chain((2 * n..big_n).map(|i| {
                        if i >= first_aux && l.differential[i - first_aux] {
                            -(bw[i] - 0.5 * hs * (f_new[i] + f_old[i])) / bh2
                        } else {
                            -f_new[i] / bh2
                        }
                    }))
                    .collect();
                if k == 0 && hs != h_factored {
                    p.jacobian(t1, &z1, jac);
                    it.factorize(p, jac, hs, o, t1)?;
                    stats.factorizations += 1;
                    h_factored = hs;
                    fresh = true;
                }
                it.solve(&mut r);
                stats.newton += 1;
                let mut small = true;
                let mut finite = true;
                for (ui, di) in u.iter_mut().zip(&r) {
                    if !di.is_finite() {
                        finite = false;
                        break;
                    }
                    *ui += di;
                    small &= di.abs() <= o.tol * (1.0 + ui.abs());
                }
                let size = r.iter().fold(0.0f64, |m, d| m.max(d.abs()));
                // at the round-off floor of the scaled system (the corrections
                // stop shrinking, small steps with large multipliers), accept
                // once they no longer move the step's states: `beta h^2 da`,
                // `gamma h da` in q and q', `gamma h dmu`, `beta h^2 dw_hat`
                let stalled = finite && k > 0 && size > 0.5 * last_size && {
                    let (bh2, gh) = (beta * hs * hs, gamma * hs);
                    (0..r.len()).all(|i| {
                        let d = r[i].abs();
                        if i < n {
                            // each state against its own size: an acceleration
                            // moves its position by beta h^2 da and its velocity
                            // by gamma h da
                            bh2 * d <= o.tol * (1.0 + z1[i].abs())
                                && gh * d <= o.tol * (1.0 + z1[n + i].abs())
                        } else if i < n + l.n_c {
                            gh * d <= o.tol * (1.0 + u[i].abs())
                        } else {
                            bh2 * d <= o.tol * (1.0 + z1[i + n].abs())
                        }
                    })
                };
                last_size = size;
                if finite && (small || stalled) {
                    step.state(z, a, &u, &mut z1);
                    converged = true;
                    break;
                }
            }
            // the next attempt or step refactors: at once after a failure or a
            // slow convergence with an old matrix, at half the step after a
            // failure with a fresh one
            if !converged || iterations > 3 {
                h_factored = f64::NAN;
            }
            if !converged && !fresh {
                continue;
            }
            if !converged {
                stats.rejected += 1;
                good = 0;
                h = 0.5 * hs;
                if h < o.step * 1e-8 {
                    return Err(SimError::StepCollapse {
                    t,
                    h,
                    cause: "the HHT Newton iteration does not converge (the motion may leave the model's range, or the step is far too large)".into(),
                });
                }
                continue;
            }
            if let Some((rtol, atol)) = o.local_error {
                let c = (beta - 1.0 / 6.0) * hs * hs;
                let err = (0..n)
                    .map(|i| {
                        let scale = atol + rtol * z[i].abs().max(z1[i].abs());
                        (c * (u[i] - a[i])).abs() / scale
                    })
                    .fold(0.0, f64::max);
                // the error is O(h^3): the classic controller with safety 0.9
                let factor = (0.9 * err.max(1e-10).powf(-1.0 / 3.0)).clamp(0.2, 2.0);
                if err > 1.0 {
                    stats.rejected += 1;
                    h = hs * factor.min(0.9);
                    continue;
                }
                // a growth below 20 % keeps the factored matrix
                h = if (1.0..1.2).contains(&factor) {
                    hs
                } else {
                    (hs * factor).min(o.step)
                };
            }
            for (k, rate) in w_rate.iter_mut().enumerate() {
                *rate = (z1[first_aux + k] - z[first_aux + k]) / hs;
            }
            *t_prev = t;
            t = t1;
            p.rhs(t, &z1, f_old);
            momentum_force(p, &z1, f_old, bz, acc, n);
            a_prev.copy_from_slice(a);
            a.copy_from_slice(&u[..n]);
            *z_prev = std::mem::replace(z, z1);
            stats.steps += 1;
            good += 1;
            if o.local_error.is_none() && h < o.step && good >= 5 {
                h = (2.0 * h).min(o.step);
                good = 0;
            }
            (*t_now, *h_next, *hf, *good_n) = (t, h, h_factored, good);
            return Ok(());
        }
    }
}

impl Stepper for Hht<'_, '_> {
    type Scalar = f64;
    type Error = SimError;

    fn t(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[f64] {
        &self.z
    }

    fn step(&mut self, t_end: f64) -> Result<(), SimError> {
        self.advance(t_end)
    }

    /// [`hermite`] between the last step's ends.
    fn dense(&self, t: f64, out: &mut [f64]) {
        let z = hermite(
            t,
            (self.t_prev, &self.z_prev, &self.a_prev),
            (self.t, &self.z, &self.a),
            self.l.n,
        );
        out.copy_from_slice(&z);
    }

    fn stats(&self) -> StepStats {
        StepStats {
            accepted: self.stats.steps,
            rejected: self.stats.rejected,
            newton: self.stats.newton,
            factorizations: self.stats.factorizations,
            rhs: 0,
        }
    }
}

/// The Newmark formulas of one step.
struct Newmark<'a> {
    n: usize,
    n_c: usize,
    h: f64,
    gamma: f64,
    beta: f64,
    /// Predicted auxiliaries.
    w_pred: &'a [f64],
}

impl Newmark<'_> {
    /// `z1 = (q, q', mu, w)` from the step start `(z, a)` and the unknowns
    /// `u = (a_{n+1}, mu_{n+1}, w_hat)`.
    fn state(&self, z: &[f64], a: &[f64], u: &[f64], z1: &mut [f64]) {
        let (n, h, gamma, beta) = (self.n, self.h, self.gamma, self.beta);
        for i in 0..n {
            let (q, v, a0, a1) = (z[i], z[n + i], a[i], u[i]);
            z1[i] = q + h * v + 0.5 * h * h * ((1.0 - 2.0 * beta) * a0 + 2.0 * beta * a1);
            z1[n + i] = v + h * ((1.0 - gamma) * a0 + gamma * a1);
        }
        let first_aux = 2 * n + self.n_c;
        z1[2 * n..first_aux].copy_from_slice(&u[n..n + self.n_c]);
        for (k, wp) in self.w_pred.iter().enumerate() {
            z1[first_aux + k] = wp + beta * h * h * u[n + self.n_c + k];
        }
    }
}
