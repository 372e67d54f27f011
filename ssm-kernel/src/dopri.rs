//! The Dormand-Prince 5(4) pair on complex states, `p' = f(t, p)`: adaptive
//! step with the error per step below `rtol |p| + atol`, and the pair's free
//! fourth-order dense output. It integrates the reduced dynamics (a handful
//! of complex unknowns) behind the [`Stepper`] interface.
//!
//! # References
//! J. R. Dormand, P. J. Prince, *A family of embedded Runge-Kutta formulae*,
//! J. Comput. Appl. Math. 6 (1980) 19-26; E. Hairer, S. P. Norsett, G. Wanner,
//! *Solving Ordinary Differential Equations I*, Sect. II.5-II.6 (dense output).

use crate::stepper::{StepStats, Stepper};
use crate::C64;

/// Why a step failed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum DopriError {
    /// The state became non-finite at the smallest step.
    #[error("non-finite state at t = {t}")]
    NonFinite {
        /// Time reached.
        t: f64,
    },
    /// The step size fell below its floor.
    #[error("step size collapsed to {step:.2e} at t = {t}")]
    StepCollapse {
        /// Time reached.
        t: f64,
        /// Last step size tried.
        step: f64,
        /// `|p|` (largest component) there.
        norm: f64,
    },
    /// The work was asked to stop ([`crate::cancel`]).
    #[error("interrupted at t = {t}")]
    Interrupted {
        /// Time reached.
        t: f64,
    },
}

// Dormand-Prince 5(4) tableau.
const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
// error coefficients b5 - b4
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];
// dense output coefficients (Hairer-Norsett-Wanner, dopri5 contd5)
const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// A Dormand-Prince 5(4) integration in progress.
pub struct DormandPrince<F> {
    f: F,
    rtol: f64,
    atol: f64,
    t: f64,
    y: Vec<C64>,
    /// Start of the last accepted step, and its state.
    t_prev: f64,
    y_prev: Vec<C64>,
    /// The next step size to try, the last accepted one, the floor.
    h: f64,
    h_last: f64,
    h_min: f64,
    /// Stages of the last step (`k[6] = f` at its end: the next `k[0]`).
    k: Vec<Vec<C64>>,
    /// `k[0]` is still to be taken from `k[6]` (first same as last).
    fsal: bool,
    stage: Vec<C64>,
    stats: StepStats,
}

impl<F: Fn(f64, &[C64]) -> Vec<C64>> DormandPrince<F> {
    /// Starts at `(t0, p0)` towards `t_end`, to be read at about `samples`
    /// times (the first step is at most `(t_end - t0) / samples`); `scale`
    /// is the amplitude the absolute tolerance refers to, `atol = 1e-3 rtol
    /// scale` (the start may be the origin).
    pub fn new(
        f: F,
        t0: f64,
        p0: &[C64],
        t_end: f64,
        samples: usize,
        rtol: f64,
        scale: f64,
    ) -> Self {
        let dim = p0.len();
        let mut k: Vec<Vec<C64>> = vec![vec![C64::new(0.0, 0.0); dim]; 7];
        k[0] = f(t0, p0);
        let span = t_end - t0;
        let h = (span / samples as f64)
            .min(0.1 / k[0].iter().map(|c| c.norm()).fold(1e-12, f64::max) * scale.max(1e-12));
        DormandPrince {
            f,
            rtol,
            atol: rtol * scale.max(1e-12) * 1e-3,
            t: t0,
            y: p0.to_vec(),
            t_prev: t0,
            y_prev: p0.to_vec(),
            h,
            h_last: 0.0,
            h_min: 1e-12 * span.abs().max(1.0),
            k,
            fsal: false,
            stage: vec![C64::new(0.0, 0.0); dim],
            stats: StepStats {
                rhs: 1,
                ..StepStats::default()
            },
        }
    }
}

impl<F: Fn(f64, &[C64]) -> Vec<C64>> Stepper for DormandPrince<F> {
    type Scalar = C64;
    type Error = DopriError;

    fn t(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[C64] {
        &self.y
    }

    fn step(&mut self, t_end: f64) -> Result<(), DopriError> {
        let dim = self.y.len();
        if self.fsal {
            self.k[0] = self.k[6].clone();
            self.fsal = false;
        }
        if crate::cancel::requested() {
            return Err(DopriError::Interrupted { t: self.t });
        }
        loop {
            let (t, h_min) = (self.t, self.h_min);
            let h = self.h.min(t_end - t).max(h_min);
            self.h = h;
            for s in 1..7 {
                for i in 0..dim {
                    let mut acc = self.y[i];
                    for (j, kj) in self.k.iter().enumerate().take(s) {
                        acc += kj[i] * (h * A[s][j]);
                    }
                    self.stage[i] = acc;
                }
                self.k[s] = (self.f)(t + C[s] * h, &self.stage);
            }
            self.stats.rhs += 6;
            let y_new = self.stage.clone();
            let mut err: f64 = 0.0;
            for (i, yn) in y_new.iter().enumerate() {
                let e: C64 = (0..7).map(|s| self.k[s][i] * E[s]).sum::<C64>() * h;
                let sc = self.atol + self.rtol * self.y[i].norm().max(yn.norm());
                err = err.max(e.norm() / sc);
            }
            if !err.is_finite() || y_new.iter().any(|c| !c.re.is_finite() || !c.im.is_finite()) {
                if h <= h_min {
                    return Err(DopriError::NonFinite { t });
                }
                self.stats.rejected += 1;
                self.h = h * 0.1;
                continue;
            }
            let accepted = err <= 1.0;
            if accepted {
                self.t_prev = t;
                self.y_prev = std::mem::replace(&mut self.y, y_new);
                self.t += h;
                self.h_last = h;
                self.fsal = true;
                self.stats.accepted += 1;
            } else if h <= h_min {
                return Err(DopriError::StepCollapse {
                    t,
                    step: h,
                    norm: self.y.iter().map(|c| c.norm()).fold(0.0, f64::max),
                });
            } else {
                self.stats.rejected += 1;
            }
            let factor = if err == 0.0 {
                5.0
            } else {
                (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
            };
            self.h = h * factor;
            if accepted {
                return Ok(());
            }
        }
    }

    fn covers(&self, t: f64) -> bool {
        t <= self.t + 1e-14 * self.h_last
    }

    /// The continuous extension of order 4 on the last step.
    fn dense(&self, t: f64, out: &mut [C64]) {
        let h = self.h_last;
        let th = ((t - self.t_prev) / h).clamp(0.0, 1.0);
        let th1 = 1.0 - th;
        let k = &self.k;
        for (i, o) in out.iter_mut().enumerate() {
            let ydiff = self.y[i] - self.y_prev[i];
            let bspl = k[0][i] * h - ydiff;
            let r5: C64 = (0..7).map(|s| k[s][i] * D[s]).sum::<C64>() * h;
            *o = self.y_prev[i]
                + th * (ydiff + th1 * (bspl + th * (ydiff - k[6][i] * h - bspl + th1 * r5)));
        }
    }

    fn stats(&self) -> StepStats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stepper::sample;

    /// `p' = lambda p` sampled through the interface: the closed form
    /// `p0 e^{lambda t}` at every time, to the tolerance, and the error
    /// falls with it at the pair's order.
    #[test]
    fn linear_flow_matches_the_exponential() {
        let lambda = C64::new(-0.1, 2.0);
        let p0 = [C64::new(1.0, 0.5)];
        let times: Vec<f64> = (1..=40).map(|k| 0.25 * k as f64).collect();
        let worst = |rtol: f64| {
            let mut dp = DormandPrince::new(
                |_, p: &[C64]| vec![lambda * p[0]],
                0.0,
                &p0,
                10.0,
                41,
                rtol,
                1.0,
            );
            let mut worst: f64 = 0.0;
            let mut seen = 0;
            sample(&mut dp, &times, 10.0, |t, p| {
                worst = worst.max((p[0] - p0[0] * (lambda * t).exp()).norm());
                seen += 1;
            })
            .unwrap();
            assert_eq!(seen, times.len());
            assert!(dp.stats().accepted > 0 && dp.stats().rhs > 6 * dp.stats().accepted);
            worst
        };
        let (coarse, fine) = (worst(1e-6), worst(1e-10));
        assert!(coarse < 1e-4 && fine < 1e-8, "{coarse:e} {fine:e}");
        assert!(fine < coarse * 1e-2, "{coarse:e} {fine:e}");
    }

    /// A blow-up `p' = p^2` from 1 (infinite at t = 1) ends in a typed error
    /// before t = 1.
    #[test]
    fn a_blow_up_is_an_error() {
        let mut dp = DormandPrince::new(
            |_, p: &[C64]| vec![p[0] * p[0]],
            0.0,
            &[C64::new(1.0, 0.0)],
            2.0,
            10,
            1e-8,
            1.0,
        );
        let e = sample(&mut dp, &[0.5, 2.0], 2.0, |_, _| {}).unwrap_err();
        let t = match e {
            DopriError::NonFinite { t } | DopriError::StepCollapse { t, .. } => t,
            DopriError::Interrupted { .. } => panic!("not cancellable: {e}"),
        };
        assert!(t < 1.0 + 1e-6, "{e:?}");
    }
}
