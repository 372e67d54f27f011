//! Validation of reduced models against the full system: a full trajectory
//! started on the SSM against the reduced trajectory (Figs. 4, 10, 14, 20),
//! the distance of the full trajectory to the manifold, and steady-state
//! forced responses at given frequencies (the reference of Fig. 15).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sects.
//! 5.1.1, 5.2.2, 5.2.3, Appendix G.1, eq. (47).

pub mod instantaneous;
pub mod pod;
pub mod report;
pub mod seeds;
pub mod ssm_run;
pub mod validation;

use std::time::Instant;

use rayon::prelude::*;
use ssm_api::StateKind;

use crate::fom::{
    consistent_initial, consistent_initial_keeping, steady_state, Consistent, DaeProblem, Radau,
    RadauOptions, RadauStats, SimError, SteadyOptions, SteadyState,
};
use crate::model::system::{OutputMap, System};
use crate::rom::accuracy::relative_gap;
use crate::ssm::rom::{integrate, RomError};
use crate::ssm::SsmExpansion;
use crate::C64;
use ssm_kernel::stepper::sample;

/// Why a validation could not be produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ValidateError {
    /// The full-system simulation failed.
    #[error(transparent)]
    Simulation(#[from] SimError),
    /// The reduced trajectory failed.
    #[error(transparent)]
    Reduced(#[from] RomError),
    /// A steady-state point failed.
    #[error("steady-state reference at Omega = {}: {source}", ssm_kernel::number::short(.omega))]
    SteadyPoint {
        /// Forcing frequency of the failed point.
        omega: f64,
        /// What failed.
        source: SimError,
    },
}

/// Full against reduced trajectory from the same point `W(p0)`.
#[derive(Debug, Clone)]
pub struct TransientValidation {
    /// Initial reduced coordinates of the reduced model.
    pub p0: Vec<C64>,
    /// Sample times.
    pub times: Vec<f64>,
    /// Full-system outputs, `full[k][j]` for output `k` at time `j`.
    pub full: Vec<Vec<f64>>,
    /// Reduced-model outputs (`W(p(t))`), same layout.
    pub rom: Vec<Vec<f64>>,
    /// Distance of the full state to the manifold, relative to the largest
    /// physical state norm of the run, per sample.
    pub distance: Vec<f64>,
    /// Largest `|g|` or recast algebraic residual of the full state, per sample.
    pub algebraic_residual: Vec<f64>,
    /// The initial state and its projection.
    pub initial: Consistent,
    /// Integrator work.
    pub stats: RadauStats,
    /// Seconds in the full-system integration.
    pub full_s: f64,
    /// Seconds in the reduced-model integration and lifting.
    pub rom_s: f64,
}

impl TransientValidation {
    /// Largest `|full - rom|` of output `k` over the run relative to the
    /// largest `|full|` of that output.
    pub fn relative_error(&self, k: usize) -> f64 {
        relative_gap(
            self.full[k]
                .iter()
                .copied()
                .zip(self.rom[k].iter().copied()),
        )
    }

    /// Root-mean-square `|full - rom|` of output `k` over the samples,
    /// relative to the largest `|full|` of that output: the time-averaged
    /// error, which a brief spike does not dominate. The multipliers of a
    /// stiff model answer the start's small distance from the true invariant
    /// manifold with a fast transient that no reduced model resolves: on the
    /// divider of Fig. 22 (IC2) `mu1` is off by 0.999 of its largest value at
    /// t = 0 and on the reduced trend within 1.3 ms, before the next sample;
    /// over the run its RMS error is 1.8e-2, all of it from that sample.
    pub fn rms_relative_error(&self, k: usize) -> f64 {
        let scale = self.full[k].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let n = self.full[k].len().max(1) as f64;
        let rms = (self.full[k]
            .iter()
            .zip(&self.rom[k])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            / n)
            .sqrt();
        if scale > 0.0 {
            rms / scale
        } else {
            rms
        }
    }

    /// Relative error over all outputs at sample `j` (the largest over outputs
    /// of `|full - rom|` divided by that output's largest `|full|`).
    pub(crate) fn relative_error_at(&self, j: usize) -> f64 {
        (0..self.full.len())
            .map(|k| {
                let scale = self.full[k].iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let e = (self.full[k][j] - self.rom[k][j]).abs();
                if scale > 0.0 {
                    e / scale
                } else {
                    e
                }
            })
            .fold(0.0, f64::max)
    }
}

/// States that carry the motion (displacements and velocities).
pub(crate) fn physical_states(sys: &System) -> Vec<usize> {
    sys.states
        .iter()
        .enumerate()
        .filter(|(_, s)| !matches!(s.kind, StateKind::Multiplier | StateKind::Auxiliary))
        .map(|(i, _)| i)
        .collect()
}

/// Distance `min_p |z_phys - W_phys(p)|` of the state `z` to the SSM truncated
/// at `order`, by Gauss-Newton in the real coordinates `(Re q_j, Im q_j)` of
/// the master pairs from `p_guess`; returns the distance and the foot point.
pub fn manifold_distance(
    ssm: &SsmExpansion,
    order: usize,
    phys: &[usize],
    z: &[f64],
    p_guess: &[C64],
) -> (f64, Vec<C64>) {
    let m = ssm.dim() / 2;
    let mut q: Vec<f64> = (0..m)
        .flat_map(|j| [p_guess[2 * j].re, p_guess[2 * j].im])
        .collect();
    let residual = |q: &[f64]| -> Vec<f64> {
        let p: Vec<C64> = (0..m)
            .flat_map(|j| {
                let c = C64::new(q[2 * j], q[2 * j + 1]);
                [c, c.conj()]
            })
            .collect();
        let w = ssm.w_at(&ssm.set.monomials(&p, order), order);
        phys.iter().map(|&i| z[i] - w[i].re).collect()
    };
    let norm = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut r = residual(&q);
    // the reduced trajectory's p(t) is a close start: a few steps suffice
    for _ in 0..4 {
        let scale = q.iter().fold(1e-3f64, |a, v| a.max(v.abs()));
        let h = 1e-7 * scale;
        let cols: Vec<Vec<f64>> = (0..2 * m)
            .map(|k| {
                let mut qp = q.clone();
                qp[k] += h;
                let rp = residual(&qp);
                rp.iter().zip(&r).map(|(a, b)| (a - b) / h).collect()
            })
            .collect();
        // normal equations J^T J d = -J^T r (J = d r / d q)
        let nq = 2 * m;
        let mut a = vec![vec![0.0; nq + 1]; nq];
        for i in 0..nq {
            for j in 0..nq {
                a[i][j] = cols[i].iter().zip(&cols[j]).map(|(x, y)| x * y).sum();
            }
            a[i][nq] = -cols[i].iter().zip(&r).map(|(x, y)| x * y).sum::<f64>();
        }
        let Some(d) = solve_small(a) else { break };
        let trial: Vec<f64> = q.iter().zip(&d).map(|(a, b)| a + b).collect();
        let rt = residual(&trial);
        if norm(&rt) >= norm(&r) {
            break;
        }
        q = trial;
        r = rt;
        if d.iter().fold(0.0f64, |a, v| a.max(v.abs())) < 1e-9 * scale {
            break;
        }
    }
    let p = (0..m)
        .flat_map(|j| {
            let c = C64::new(q[2 * j], q[2 * j + 1]);
            [c, c.conj()]
        })
        .collect();
    (norm(&r), p)
}

/// Gaussian elimination with partial pivoting on an augmented `n x (n+1)` system.
fn solve_small(mut a: Vec<Vec<f64>>) -> Option<Vec<f64>> {
    let n = a.len();
    for c in 0..n {
        let piv = (c..n).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[piv][c].abs() < 1e-300 {
            return None;
        }
        a.swap(c, piv);
        let (top, rest) = a.split_at_mut(c + 1);
        let pivot = &top[c];
        for row in rest.iter_mut() {
            let f = row[c] / pivot[c];
            for (x, p) in row[c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * p;
            }
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (a[r][n] - s) / a[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// What [`transient`] compares.
#[derive(Debug, Clone, Copy)]
pub struct TransientSettings<'a> {
    /// Expansion order of the reduced model.
    pub order: usize,
    /// Initial reduced coordinates `p0` (conjugates included).
    pub p0: &'a [C64],
    /// Final time.
    pub t_end: f64,
    /// Equally spaced samples, both ends included.
    pub samples: usize,
    /// Outputs compared.
    pub outputs: &'a [&'a OutputMap],
    /// Full-system integrator settings.
    pub radau: RadauOptions,
    /// The full system's initial state, when it is not `W(p0)` (given
    /// displacements and velocities; made consistent here, keeping the
    /// displacements listed in the second entry where the constraints allow).
    pub full_start: Option<(&'a [f64], &'a [usize])>,
}

/// Integrates the full system and the reduced model (truncated at `order`)
/// from `W(p0)` over `[0, t_end]` and samples both at `samples` equally spaced
/// times.
pub fn transient(
    ssm: &SsmExpansion,
    sys: &System,
    set: &TransientSettings<'_>,
) -> Result<TransientValidation, ValidateError> {
    let TransientSettings {
        order,
        p0,
        t_end,
        samples,
        outputs,
        radau: opts,
        full_start,
    } = *set;
    let t_rom = Instant::now();
    // the reduced model at the full system's tolerance: a like-for-like timing
    let rom_tr = integrate(ssm, order, p0, t_end, samples, opts.rtol)?;
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let end = ssm.set.of_order(order.min(ssm.order)).end;
    let monos: Vec<Vec<C64>> = rom_tr
        .states
        .iter()
        .map(|p| ssm.set.monomials(p, order))
        .collect();
    let rom: Vec<Vec<f64>> = series
        .iter()
        .map(|s| {
            monos
                .iter()
                .map(|mono| (1..end).map(|i| s[i] * mono[i]).sum::<C64>().re)
                .collect()
        })
        .collect();
    let rom_s = t_rom.elapsed().as_secs_f64();

    let t_full = Instant::now();
    let problem = DaeProblem::new(sys, 0.0, 0.0);
    let (w0, keep): (Vec<f64>, &[usize]) = match full_start {
        Some((z, keep)) => (z.to_vec(), keep),
        None => (
            ssm.w_at(&ssm.set.monomials(p0, order), order)
                .iter()
                .map(|c| c.re)
                .collect(),
            &[],
        ),
    };
    let initial = consistent_initial_keeping(&problem, 0.0, &w0, keep)?;
    let mut radau = Radau::new(&problem, 0.0, &initial.z, t_end, opts)?;
    let times = rom_tr.times.clone();
    let mut states: Vec<Vec<f64>> = Vec::with_capacity(times.len());
    states.push(initial.z.clone());
    sample(&mut radau, times.get(1..).unwrap_or(&[]), t_end, |_, z| {
        states.push(z.to_vec());
    })?;
    let full_s = t_full.elapsed().as_secs_f64();
    let full: Vec<Vec<f64>> = outputs
        .iter()
        .map(|o| {
            states
                .iter()
                .map(|z| o.weights.iter().map(|&(s, w)| w * z[s]).sum())
                .collect()
        })
        .collect();
    let phys = physical_states(sys);
    let scale = states
        .iter()
        .map(|z| phys.iter().map(|&i| z[i] * z[i]).sum::<f64>().sqrt())
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let distance: Vec<f64> = states
        .par_iter()
        .zip(&rom_tr.states)
        .map(|(z, p)| manifold_distance(ssm, order, &phys, z, p).0 / scale)
        .collect();
    let algebraic_residual = states
        .iter()
        .map(|z| crate::fom::consistent::algebraic_residual(&problem, z).0)
        .collect();
    Ok(TransientValidation {
        p0: p0.to_vec(),
        times,
        full,
        rom,
        distance,
        algebraic_residual,
        initial,
        stats: radau.stats,
        full_s,
        rom_s,
    })
}

/// The reduced coordinates of the SSM point nearest the consistent state `z`
/// (physical states): the linear modal projection `p_j = u_j^* B z` refined by
/// [`manifold_distance`]; returns `p0` and the distance relative to `|z|`.
pub(crate) fn nearest_on_ssm(
    ssm: &SsmExpansion,
    sys: &System,
    order: usize,
    masters: &[crate::spectrum::MasterMode],
    z: &[f64],
) -> (Vec<C64>, f64) {
    let zc: Vec<C64> = z.iter().map(|&v| C64::new(v, 0.0)).collect();
    let bz = crate::spectrum::modes::spmv(sys.b.as_ref(), &zc);
    let guess: Vec<C64> = masters
        .iter()
        .flat_map(|m| {
            let q: C64 = m.left.iter().zip(&bz).map(|(u, b)| u.conj() * b).sum();
            [q, q.conj()]
        })
        .collect();
    let phys = physical_states(sys);
    let (d, p) = manifold_distance(ssm, order, &phys, z, &guess);
    let norm = phys.iter().map(|&i| z[i] * z[i]).sum::<f64>().sqrt();
    (p, d / norm.max(f64::MIN_POSITIVE))
}

/// Steady-state amplitudes of `outputs` at each frequency of `omegas`,
/// forcing `epsilon`, by integration until criterion (47) holds, from rest or
/// from `starts[i]` (made consistent) where given; frequencies run in parallel.
pub fn steady_state_reference(
    sys: &System,
    epsilon: f64,
    omegas: &[f64],
    outputs: &[&OutputMap],
    opts: &SteadyOptions,
    starts: Option<&[Option<Vec<f64>>]>,
) -> Result<Vec<SteadyState>, ValidateError> {
    // each steady state is a long integration: the caller's cancellation
    // flag goes along to the threads that run them
    let flag = ssm_kernel::cancel::current();
    omegas
        .par_iter()
        .enumerate()
        .map(|(i, &omega)| {
            ssm_kernel::cancel::within(flag.as_ref(), || {
                let problem = DaeProblem::new(sys, epsilon, omega);
                let z0 = starts
                    .and_then(|s| s.get(i).cloned().flatten())
                    .unwrap_or_else(|| vec![0.0; sys.n_states()]);
                let start = consistent_initial(&problem, 0.0, &z0)
                    .map_err(|source| ValidateError::SteadyPoint { omega, source })?;
                steady_state(&problem, &start.z, outputs, opts)
                    .map_err(|source| ValidateError::SteadyPoint { omega, source })
            })
        })
        .collect()
}
