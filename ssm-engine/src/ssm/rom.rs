//! Reduced-model transients: `p' = R(p)` (flows) or `p_{j+1} = R(p_j)`
//! (maps) from an initial point on the SSM, lifted to the outputs through
//! `W`.
//!
//! Flows are integrated with the Dormand-Prince 5(4) pair, adaptive step,
//! error per step below `rtol |p| + atol`, and the solution is reported at
//! equally spaced times by the pair's free fourth-order dense output. The
//! reduced model has `2m` complex unknowns (a handful), so a self-contained
//! explicit integrator is used here rather than pulling a linear-algebra
//! crate's vector types into the engine; the full-system DAE integrator is a
//! different, implicit method.
//!
//! # References
//! J. R. Dormand, P. J. Prince, *A family of embedded Runge-Kutta formulae*,
//! J. Comput. Appl. Math. 6 (1980) 19-26; E. Hairer, S. P. Norsett, G. Wanner,
//! *Solving Ordinary Differential Equations I*, Sect. II.5-II.6 (dense output).

use super::{Dynamics, SsmExpansion};
use crate::C64;

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

// Dormand-Prince 5(4) tableau (autonomous right-hand side: the nodes c_i are not needed).
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
    let dim = p0.len();
    let top = order + 1;
    let f = |p: &[C64]| -> Vec<C64> {
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
    };
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
    let mut times = vec![0.0];
    let mut states = vec![p0.to_vec()];
    let mut next_out = 1;
    let mut t = 0.0;
    let mut y = p0.to_vec();
    let norm0 = y.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let atol = rtol * norm0.max(1e-12) * 1e-3;
    let mut k: Vec<Vec<C64>> = vec![vec![C64::new(0.0, 0.0); dim]; 7];
    k[0] = f(&y);
    let mut h = (t_end / samples as f64)
        .min(0.1 / k[0].iter().map(|c| c.norm()).fold(1e-12, f64::max) * norm0.max(1e-12));
    let h_min = 1e-12 * t_end.abs().max(1.0);
    let mut steps = 0;
    let mut stage = vec![C64::new(0.0, 0.0); dim];
    while next_out < samples {
        h = h.min(t_end - t).max(h_min);
        for s in 1..7 {
            for i in 0..dim {
                let mut acc = y[i];
                for (j, kj) in k.iter().enumerate().take(s) {
                    acc += kj[i] * (h * A[s][j]);
                }
                stage[i] = acc;
            }
            k[s] = f(&stage);
        }
        let y_new = stage.clone();
        let mut err: f64 = 0.0;
        for i in 0..dim {
            let e: C64 = (0..7).map(|s| k[s][i] * E[s]).sum::<C64>() * h;
            let sc = atol + rtol * y[i].norm().max(y_new[i].norm());
            err = err.max(e.norm() / sc);
        }
        if !err.is_finite() || y_new.iter().any(|c| !c.re.is_finite() || !c.im.is_finite()) {
            if h <= h_min {
                return Err(RomError::NonFinite { t });
            }
            h *= 0.1;
            continue;
        }
        if err <= 1.0 {
            // dense output on [t, t + h] (continuous extension of order 4)
            while next_out < samples && out_t[next_out] <= t + h + 1e-14 * h {
                let th = ((out_t[next_out] - t) / h).clamp(0.0, 1.0);
                let th1 = 1.0 - th;
                let p: Vec<C64> = (0..dim)
                    .map(|i| {
                        let ydiff = y_new[i] - y[i];
                        let bspl = k[0][i] * h - ydiff;
                        let r5: C64 = (0..7).map(|s| k[s][i] * D[s]).sum::<C64>() * h;
                        y[i] + th
                            * (ydiff + th1 * (bspl + th * (ydiff - k[6][i] * h - bspl + th1 * r5)))
                    })
                    .collect();
                times.push(out_t[next_out]);
                states.push(p);
                next_out += 1;
            }
            t += h;
            y = y_new;
            k[0] = k[6].clone();
            steps += 1;
        } else if h <= h_min {
            return Err(RomError::StepCollapse {
                t,
                step: h,
                norm: y.iter().map(|c| c.norm()).fold(0.0, f64::max),
            });
        }
        let factor = if err == 0.0 {
            5.0
        } else {
            (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
        };
        h *= factor;
    }
    Ok(Trajectory {
        times,
        states,
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::poly::MultiIndexSet;
    use crate::ssm::RTerm;

    /// Reference: the linear flow `p' = lambda p` has `p(t) = p0 e^{lambda t}`;
    /// with `rtol = 1e-10` the error must stay below 1e-8 relative.
    #[test]
    fn linear_reduced_flow_matches_exponential() {
        let set = MultiIndexSet::new(2, 1);
        let lambda = C64::new(-0.05, 2.0);
        let ssm = SsmExpansion {
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
        };
        let p0 = [C64::new(0.3, 0.1), C64::new(0.3, -0.1)];
        let tr = integrate(&ssm, 1, &p0, 20.0, 41, 1e-10).unwrap();
        assert_eq!(tr.times.len(), 41);
        for (t, p) in tr.times.iter().zip(&tr.states) {
            let exact = p0[0] * (lambda * t).exp();
            assert!((p[0] - exact).norm() < 1e-8 * p0[0].norm(), "t = {t}");
        }
    }
}
