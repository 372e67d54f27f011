//! Reduced-model transients: `p' = R(p)` (flows) or `p_{j+1} = R(p_j)`
//! (maps) from an initial point on the SSM, lifted to the outputs through
//! `W`; and forced flows `p' = R(p) + eps S(Omega t)` on the periodic SSM.
//!
//! Flows are integrated with the Dormand-Prince 5(4) pair of the kernel
//! ([`ssm_kernel::dopri`]: adaptive step, error per step below
//! `rtol |p| + atol`), and the solution is reported at equally spaced times
//! by the pair's free fourth-order dense output, read through the kernel's
//! one integrator interface ([`ssm_kernel::stepper`]). The reduced model has
//! `2m` complex unknowns (a handful): an explicit method on plain vectors.
//!
//! # References
//! J. R. Dormand, P. J. Prince, *A family of embedded Runge-Kutta formulae*,
//! J. Comput. Appl. Math. 6 (1980) 19-26; E. Hairer, S. P. Norsett, G. Wanner,
//! *Solving Ordinary Differential Equations I*, Sect. II.5-II.6 (dense output).

use super::{Dynamics, SsmExpansion};
use crate::C64;
use ssm_kernel::dopri::{DopriError, DormandPrince};
use ssm_kernel::stepper::{sample, Stepper};

/// Why a reduced trajectory could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RomError {
    /// The step size fell below its floor (blow-up or extreme stiffness).
    #[error("reduced dynamics: step size collapsed to {step:.2e} at t = {t:.6} (|p| = {norm:.3e}); the trajectory leaves the domain where the expansion is valid: start closer to the origin or use a lower order")]
    StepCollapse {
        /// Time reached.
        t: f64,
        /// Last step size tried.
        step: f64,
        /// `|p|` there.
        norm: f64,
    },
    /// The state became non-finite.
    #[error("reduced dynamics: non-finite state at t = {t:.6}: the trajectory diverged (initial amplitude outside the domain of convergence)")]
    NonFinite {
        /// Time reached.
        t: f64,
    },
    /// The work was asked to stop ([`ssm_kernel::cancel`]).
    #[error("reduced dynamics: interrupted at t = {t:.6}")]
    Interrupted {
        /// Time reached.
        t: f64,
    },
}

/// A reduced trajectory sampled at `times`.
#[derive(Debug, Clone)]
pub struct Trajectory {
    /// Sample times.
    pub times: Vec<f64>,
    /// Reduced coordinates `p(t)` (all `2m`, conjugates included).
    pub states: Vec<Vec<C64>>,
    /// Accepted integration steps.
    pub steps: usize,
}

/// One term `coeff * prod p_v^k` of coordinate `coord` of the reduced dynamics.
type RomTerm = (usize, C64, Vec<(usize, i32)>);

/// Integrates the reduced dynamics of `ssm` (truncated at `order`) from `p0`
/// over `[0, t_end]`, reporting `samples` equally spaced points (including
/// both ends). Maps are iterated: `t_end` is then a time, and the samples are
/// the iterates `t = j T` up to `t_end`.
pub fn integrate(
    ssm: &SsmExpansion,
    order: usize,
    p0: &[C64],
    t_end: f64,
    samples: usize,
    rtol: f64,
) -> Result<Trajectory, RomError> {
    let f = reduced_field(ssm, order, p0.len());
    if let Dynamics::Map { period } = ssm.dynamics {
        let n = (t_end / period).floor() as usize;
        let mut p = p0.to_vec();
        let mut times = vec![0.0];
        let mut states = vec![p.clone()];
        for j in 1..=n {
            p = f(&p);
            if p.iter().any(|c| !c.re.is_finite() || !c.im.is_finite()) {
                return Err(RomError::NonFinite {
                    t: j as f64 * period,
                });
            }
            times.push(j as f64 * period);
            states.push(p.clone());
        }
        return Ok(Trajectory {
            times,
            states,
            steps: n,
        });
    }
    let samples = samples.max(2);
    let out_t: Vec<f64> = (0..samples)
        .map(|i| t_end * i as f64 / (samples - 1) as f64)
        .collect();
    let norm0 = p0.iter().map(|c| c.norm()).fold(0.0, f64::max);
    dopri(|_, p| f(p), p0, &out_t, rtol, norm0)
}

/// Integrates the forced reduced flow `p' = R(p) + g(t)` of `ssm`
/// (truncated at `order`; `g` the forcing of the periodic SSM, e.g.
/// `eps S0(Omega t)`) from `p0` at `t = 0`, reporting the states at the
/// increasing times `out_t` (from 0). `scale` is the amplitude the absolute
/// tolerance refers to (the start may be the origin).
///
/// # Errors
/// [`RomError`] when the trajectory diverges or the step size collapses.
pub(crate) fn integrate_forced(
    ssm: &SsmExpansion,
    order: usize,
    p0: &[C64],
    out_t: &[f64],
    rtol: f64,
    scale: f64,
    g: impl Fn(f64) -> Vec<C64>,
) -> Result<Trajectory, RomError> {
    let f = reduced_field(ssm, order, p0.len());
    dopri(
        |t, p| {
            let mut v = f(p);
            for (vi, gi) in v.iter_mut().zip(g(t)) {
                *vi += gi;
            }
            v
        },
        p0,
        out_t,
        rtol,
        scale,
    )
}

/// `R(p)` of `ssm` truncated at `order`, on `dim` reduced coordinates.
fn reduced_field(ssm: &SsmExpansion, order: usize, dim: usize) -> impl Fn(&[C64]) -> Vec<C64> {
    // R has few terms (normal-form style): evaluate them directly instead of
    // forming every monomial of the expansion at each stage
    let terms: Vec<RomTerm> = ssm
        .r
        .iter()
        .filter(|t| ssm.set.order(t.index) <= order && t.coeff != C64::new(0.0, 0.0))
        .map(|t| {
            let e = ssm.set.exponents(t.index);
            let factors = e
                .iter()
                .enumerate()
                .filter(|(_, &k)| k > 0)
                .map(|(v, &k)| (v, i32::from(k)))
                .collect();
            (t.coord, t.coeff, factors)
        })
        .collect();
    let top = order + 1;
    move |p: &[C64]| -> Vec<C64> {
        // powers p_v^k, k <= order, shared by all terms
        let mut pow = vec![C64::new(1.0, 0.0); dim * top];
        for v in 0..dim {
            for k in 1..top {
                pow[v * top + k] = pow[v * top + k - 1] * p[v];
            }
        }
        let mut out = vec![C64::new(0.0, 0.0); dim];
        for (coord, coeff, factors) in &terms {
            out[*coord] += factors
                .iter()
                .fold(*coeff, |acc, &(v, k)| acc * pow[v * top + k as usize]);
        }
        out
    }
}

/// Dormand-Prince 5(4) ([`DormandPrince`]) on `p' = f(t, p)` from `p0` at
/// `out_t[0]`, the states at the times `out_t` by its dense output; error
/// per step below `rtol |p| + atol`, `atol = 1e-3 rtol scale`.
fn dopri(
    f: impl Fn(f64, &[C64]) -> Vec<C64>,
    p0: &[C64],
    out_t: &[f64],
    rtol: f64,
    scale: f64,
) -> Result<Trajectory, RomError> {
    let t_start = out_t.first().copied().unwrap_or(0.0);
    let t_end = out_t.last().copied().unwrap_or(0.0);
    let mut times = vec![t_start];
    let mut states = vec![p0.to_vec()];
    let mut dp = DormandPrince::new(f, t_start, p0, t_end, out_t.len(), rtol, scale);
    sample(&mut dp, out_t.get(1..).unwrap_or(&[]), t_end, |t, p| {
        times.push(t);
        states.push(p.to_vec());
    })
    .map_err(|e| match e {
        DopriError::NonFinite { t } => RomError::NonFinite { t },
        DopriError::StepCollapse { t, step, norm } => RomError::StepCollapse { t, step, norm },
        DopriError::Interrupted { t } => RomError::Interrupted { t },
    })?;
    Ok(Trajectory {
        times,
        states,
        steps: dp.stats().accepted,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ssm::RTerm;
    use ssm_kernel::poly::MultiIndexSet;

    /// The linear reduced flow `p' = lambda p` of one pair.
    fn linear_pair(lambda: C64) -> SsmExpansion {
        let set = MultiIndexSet::new(2, 1);
        SsmExpansion {
            dynamics: Dynamics::Flow,
            lambda: vec![lambda, lambda.conj()],
            w: vec![vec![C64::new(0.0, 0.0)]; set.len()],
            r: vec![
                RTerm {
                    coord: 0,
                    index: set.index(&[1, 0]).unwrap(),
                    coeff: lambda,
                },
                RTerm {
                    coord: 1,
                    index: set.index(&[0, 1]).unwrap(),
                    coeff: lambda.conj(),
                },
            ],
            order: 1,
            set,
            timing: Default::default(),
        }
    }

    /// Reference: the linear flow `p' = lambda p` has `p(t) = p0 e^{lambda t}`;
    /// with `rtol = 1e-10` the error must stay below 1e-8 relative.
    #[test]
    fn linear_reduced_flow_matches_exponential() {
        let lambda = C64::new(-0.05, 2.0);
        let ssm = linear_pair(lambda);
        let p0 = [C64::new(0.3, 0.1), C64::new(0.3, -0.1)];
        let tr = integrate(&ssm, 1, &p0, 20.0, 41, 1e-10).unwrap();
        assert_eq!(tr.times.len(), 41);
        for (t, p) in tr.times.iter().zip(&tr.states) {
            let exact = p0[0] * (lambda * t).exp();
            assert!((p[0] - exact).norm() < 1e-8 * p0[0].norm(), "t = {t}");
        }
    }

    /// Reference: the forced linear flow `p' = lambda p + e^{i Omega t}` has
    /// `p(t) = (p0 - c) e^{lambda t} + c e^{i Omega t}`, `c = 1 / (i Omega -
    /// lambda)`; from the origin with `rtol = 1e-10` the error must stay
    /// below 1e-8 of `|c|` at the requested (unequally spaced) times.
    #[test]
    fn forced_linear_flow_matches_closed_form() {
        let lambda = C64::new(-0.05, 2.0);
        let ssm = linear_pair(lambda);
        let omega = 1.9;
        let c = 1.0 / (C64::new(0.0, omega) - lambda);
        let times: Vec<f64> = (0..60).map(|k| 0.01 * f64::from(k * k)).collect();
        let zero = C64::new(0.0, 0.0);
        let g = |t: f64| {
            let e = C64::from_polar(1.0, omega * t);
            vec![e, e.conj()]
        };
        let tr = integrate_forced(&ssm, 1, &[zero, zero], &times, 1e-10, c.norm(), g).unwrap();
        assert_eq!(tr.times, times);
        for (t, p) in tr.times.iter().zip(&tr.states) {
            let exact = -c * (lambda * t).exp() + c * C64::from_polar(1.0, omega * t);
            assert!((p[0] - exact).norm() < 1e-8 * c.norm(), "t = {t}");
            assert!((p[1] - exact.conj()).norm() < 1e-8 * c.norm(), "t = {t}");
        }
    }
}
