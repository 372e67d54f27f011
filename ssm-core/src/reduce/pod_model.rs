//! The `pod` reducer on a mechanical model: POD of the velocity
//! snapshots of a training run per coordinate kind, the global projection
//! `U`, the generalized constraint reduction of the projected constraint
//! Jacobian over the run, and the reduced model of eq. (14)
//! ([`super::galerkin`]).
//!
//! The constraint Jacobian `C_q(q)` of a nonlinear constraint changes along
//! the motion, so the SVD of Sect. 3.4 is taken of the projected Jacobians
//! `C_q(q_k) U` of many snapshots side by side, `[C_q(q_1) U, ..., C_q(q_K) U]`:
//! its independent left singular vectors `L^i` span every combination of
//! constraints the reduced motion ever feels, and a constraint is removed
//! only when it is redundant along the whole training run.
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint reduction
//! method for reduced order MBS models*, Multibody Syst. Dyn. (2017), Sects.
//! 3.2-3.4, eqs. (7)-(14).

use faer::Mat;
use ssm_api::{Lift, Model, MotionKind};

use super::galerkin::{project, GalerkinError, ReducedCoordinates};
use super::pod::{global_projection, pod, reduce_constraints, vanishing_constraints};
use super::pod::{ConstraintReduction, PodBasis};
use super::pod::{PodError, Truncation};
use crate::fom::DaeProblem;
use crate::model::system::System;

/// Settings of the `pod` reducer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PodSettings {
    /// Truncation of the POVs of every kind.
    pub truncation: Truncation,
    /// Singular values of the stacked projected constraint Jacobian below
    /// this fraction of the largest count as zero (the constraint is redundant).
    pub rank_tol: f64,
    /// Snapshots (evenly spread over the run) at which `C_q(q) U` is stacked.
    pub jacobian_samples: usize,
}

impl Default for PodSettings {
    /// A drop of 6 decades, rank tolerance `1e-8`, 64 Jacobian samples.
    fn default() -> Self {
        Self {
            truncation: Truncation::Drop { decades: 6.0 },
            rank_tol: 1e-8,
            jacobian_samples: 64,
        }
    }
}

/// Why a POD reduction failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PodReduceError {
    /// The POD or the constraint reduction failed.
    #[error(transparent)]
    Pod(#[from] PodError),
    /// The projection failed.
    #[error(transparent)]
    Galerkin(#[from] GalerkinError),
    /// The training run is unusable.
    #[error("training run: {0}")]
    Training(String),
    /// The kept constraint combinations fix every reduced coordinate.
    #[error(
        "the {kept} reduced constraints fix all {r} reduced coordinates (no degree of freedom left): the nonlinear constraints, projected on the POD subspace, are all independent; the singular values of the stacked projected Jacobian are {values} (relative to the largest): raise rank_tol above the ones to drop (the paper's drop in the singular values), or keep more POMs"
    )]
    NoFreedom {
        /// Reduced coordinates.
        r: usize,
        /// Constraint combinations kept.
        kept: usize,
        /// Leading singular values, relative to the largest, written out.
        values: String,
    },
}

/// The POD of one coordinate kind.
#[derive(Debug, Clone)]
pub struct KindBasis {
    /// The kind.
    pub motion: MotionKind,
    /// Its displacements (indices into `0..n`).
    pub coordinates: Vec<usize>,
    /// Its POVs and kept POMs.
    pub basis: PodBasis,
}

/// What the `pod` reducer made.
#[derive(Debug, Clone)]
pub struct PodReduction {
    /// POD per coordinate kind, in the order translational, rotational,
    /// flexible, unspecified (kinds without coordinates left out).
    pub kinds: Vec<KindBasis>,
    /// The global projection `U` (`n x r`).
    pub u: Mat<f64>,
    /// The constraint reduction (`L^i`, singular values).
    pub constraints: ConstraintReduction,
    /// The constraints whose projected Jacobian rows vanish along the whole
    /// run: what the reduction along fixed axes of the paper's reference
    /// \[27\] removes ([`vanishing_constraints`]), for comparison.
    pub vanishing: Vec<usize>,
    /// The reduced model `(q_r, q_r', mu_l)`.
    pub model: Model,
    /// `z = V y`, `V = blkdiag(U, U, L)`.
    pub lift: Lift,
    /// `|R_q0| / max_t |q|` and `|R_q'0| / max_t |q'|`: what `U` misses of
    /// the training run's initial positions and velocities (eqs. 8-9).
    pub initial_residual: [f64; 2],
}

fn kind_label(m: MotionKind) -> &'static str {
    if m == MotionKind::Translational {
        "trans"
    } else if m == MotionKind::Rotational {
        "rot"
    } else if m == MotionKind::Flexible {
        "flex"
    } else {
        "pom"
    }
}

/// The `pod` reduction of the mechanical plugin model `full` (validated
/// into `sys`, possibly recast) from the states `run` of a training
/// simulation of `sys` (`z = (q, q', mu)`, then any auxiliaries, at each
/// snapshot, ideally uniformly spaced in time).
pub fn pod_reduce(
    full: &Model,
    sys: &System,
    run: &[Vec<f64>],
    settings: &PodSettings,
) -> Result<PodReduction, PodReduceError> {
    reduce(full, sys, run, settings, true)
}

/// [`pod_reduce`]; with `expand` false the reduced model's nonlinearity is
/// left to a lifted evaluation where the full model allows it
/// ([`super::galerkin::project`]).
pub(crate) fn reduce(
    full: &Model,
    sys: &System,
    run: &[Vec<f64>],
    settings: &PodSettings,
    expand: bool,
) -> Result<PodReduction, PodReduceError> {
    let (n, nc) = super::galerkin::supported(full)?;
    let original = sys
        .recast
        .as_ref()
        .map_or(sys.states.len(), |r| r.n_original);
    if original != 2 * n + nc || sys.mechanical.as_ref().map(|m| m.n_dof) != Some(n) {
        return Err(PodReduceError::Training(format!(
            "the validated system ({} states) is not the model '{}' ({} states)",
            sys.states.len(),
            full.name,
            full.states.len()
        )));
    }
    if run.len() < 2 {
        return Err(PodReduceError::Training(format!(
            "{} snapshots; POD needs at least two",
            run.len()
        )));
    }
    if let Some(k) = run.iter().position(|z| z.len() != sys.states.len()) {
        return Err(PodReduceError::Training(format!(
            "snapshot {k} has {} values, the model has {} states",
            run[k].len(),
            sys.states.len()
        )));
    }
    if settings.jacobian_samples == 0 {
        return Err(PodError::Truncation("jacobian_samples must be at least 1".into()).into());
    }
    let order = [
        MotionKind::Translational,
        MotionKind::Rotational,
        MotionKind::Flexible,
        MotionKind::Unspecified,
    ];
    let mut kinds = Vec::new();
    for motion in order {
        let coordinates: Vec<usize> = (0..n)
            .filter(|&i| {
                let m = sys.states[i].motion;
                m == motion || (motion == MotionKind::Unspecified && !order[..3].contains(&m))
            })
            .collect();
        if coordinates.is_empty() {
            continue;
        }
        let x = Mat::from_fn(coordinates.len(), run.len(), |i, j| {
            run[j][n + coordinates[i]]
        });
        let basis = pod(x.as_ref(), kind_label(motion), settings.truncation)?;
        kinds.push(KindBasis {
            motion,
            coordinates,
            basis,
        });
    }
    let groups: Vec<(&[usize], &PodBasis)> = kinds
        .iter()
        .map(|k| (k.coordinates.as_slice(), &k.basis))
        .collect();
    let u = global_projection(n, &groups);
    let r = u.ncols();
    if r == 0 {
        return Err(PodReduceError::Training(
            "the velocities are zero throughout: nothing moves, so POD keeps no mode".into(),
        ));
    }
    let mut coords = ReducedCoordinates {
        names: Vec::with_capacity(r),
        motion: Vec::with_capacity(r),
    };
    for k in &kinds {
        for j in 0..k.basis.kept() {
            coords
                .names
                .push(format!("{}{}", kind_label(k.motion), j + 1));
            coords.motion.push(k.motion);
        }
    }
    let stack = stacked_constraint_jacobian(sys, run, &u, settings.jacobian_samples);
    let mut constraints = reduce_constraints(stack.as_ref(), settings.rank_tol)?;
    let vanishing = vanishing_constraints(stack.as_ref(), settings.rank_tol);
    let instantaneous = instantaneous_rank(&stack, r, settings.rank_tol)?;
    let origin = vec![0.0; sys.states.len()];
    let at_origin = constraint_jacobian(sys, &origin) * &u;
    let regular = regular_count(
        &stack,
        at_origin.as_ref(),
        constraints.basis.as_ref(),
        instantaneous,
        settings.rank_tol,
    )?;
    if constraints.basis.ncols() > regular {
        let m = constraints.basis.nrows();
        constraints.basis = Mat::from_fn(m, regular, |i, j| constraints.basis[(i, j)]);
    }
    if constraints.basis.ncols() >= r {
        let largest = constraints.singular_values.first().copied().unwrap_or(1.0);
        return Err(PodReduceError::NoFreedom {
            r,
            kept: constraints.basis.ncols(),
            values: constraints
                .singular_values
                .iter()
                .take(r + 2)
                .map(|v| format!("{:.2e}", v / largest))
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    let (model, lift) = project(
        full,
        u.as_ref(),
        constraints.basis.as_ref(),
        &coords,
        expand,
    )?;
    let peak = |off: usize| {
        run.iter()
            .map(|z| norm(&z[off..off + n]))
            .fold(0.0f64, f64::max)
            .max(f64::MIN_POSITIVE)
    };
    let residual = |off: usize| {
        norm(&super::pod::residual_term(
            u.as_ref(),
            &run[0][off..off + n],
        ))
    };
    let initial_residual = [residual(0) / peak(0), residual(n) / peak(n)];
    Ok(PodReduction {
        kinds,
        u,
        constraints,
        vanishing,
        model,
        lift,
        initial_residual,
    })
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The largest rank of the blocks `C_q(q_k) U` (`n_c x r` each) of the
/// stacked Jacobian, by the relative tolerance `rank_tol`.
///
/// A nonlinear constraint's projected Jacobian turns along the motion, so
/// the stack can have a larger rank than any one instant (e.g. eight rods
/// whose piston motions span six POMs: rank 9 stacked, 7 at every
/// instant). A constant set of `l` combinations `L^T C` with `l` above the
/// instantaneous rank makes the reduced constraint Jacobian `L^T C_q U`
/// rank deficient at every instant, so the HHT iteration matrix
/// `[M, G^T; G, 0]` singular (the overdetermined case of Sect. 3.3); the
/// reduction keeps the `l` dominant combinations, at most that rank (the
/// paper's advice to look for a drop in the singular values of `D`).
fn instantaneous_rank(stack: &Mat<f64>, r: usize, rank_tol: f64) -> Result<usize, PodError> {
    let mut rank = 0;
    if r == 0 {
        return Ok(0);
    }
    for k in 0..stack.ncols() / r {
        let block = stack.as_ref().subcols(k * r, r);
        let s = block.singular_values().map_err(|_| PodError::Svd {
            what: "instantaneous rank of C_q U".into(),
        })?;
        let largest = s.first().copied().unwrap_or(0.0);
        rank = rank.max(
            s.iter()
                .take_while(|&&v| v > 0.0 && v > rank_tol * largest)
                .count(),
        );
    }
    Ok(rank)
}

/// How many of the leading combinations `L^i` (at most `cap`) keep
/// `(L^i)^T C_q U` of full row rank at every stacked instant and at the
/// model's origin (its reference configuration, where a run from rest
/// starts): a combination that loses rank anywhere makes the reduced HHT
/// iteration matrix singular there. The count falls until it holds.
fn regular_count(
    stack: &Mat<f64>,
    at_origin: faer::MatRef<'_, f64>,
    basis: faer::MatRef<'_, f64>,
    cap: usize,
    rank_tol: f64,
) -> Result<usize, PodError> {
    let r = at_origin.ncols();
    let mut l = cap.min(basis.ncols());
    if r == 0 {
        return Ok(0);
    }
    let blocks = stack.ncols() / r;
    loop {
        if l == 0 {
            return Ok(0);
        }
        let lt = basis.subcols(0, l).transpose();
        let mut worst = l;
        for k in 0..=blocks {
            let block = if k < blocks {
                stack.as_ref().subcols(k * r, r)
            } else {
                at_origin
            };
            let s = (lt * block).singular_values().map_err(|_| PodError::Svd {
                what: "rank of the reduced constraint Jacobian".into(),
            })?;
            let largest = s.first().copied().unwrap_or(0.0);
            let rank = s
                .iter()
                .take_while(|&&v| v > 0.0 && v > rank_tol * largest)
                .count();
            worst = worst.min(rank);
        }
        if worst == l {
            return Ok(l);
        }
        l = worst;
    }
}

/// The constraint Jacobian `C_q(q)` (`n_c x n`) of the mechanical `sys` at
/// the state `z = (q, q', mu)` (followed by a recast's auxiliaries, which
/// must then satisfy their definitions), from the analytic Jacobian of the
/// model: the total derivative, through the auxiliaries too.
pub fn constraint_jacobian(sys: &System, z: &[f64]) -> Mat<f64> {
    let p = DaeProblem::new(sys, 0.0, 0.0);
    let mut vals = vec![0.0; p.pattern().row_idx().len()];
    let mut cq = Mat::zeros(0, 0);
    constraint_jacobian_into(sys, &p, z, &mut vals, &mut cq);
    cq
}

/// The generalized reaction forces `C_q(q)^T mu` of a mechanical `sys` at
/// recast states `z` (shifted: `mu = mu_eq + mu_hat`), the analytic
/// Jacobian's pattern set up once for many states.
pub(crate) struct Reactions<'a> {
    sys: &'a System,
    problem: DaeProblem<'a>,
    vals: Vec<f64>,
    cq: Mat<f64>,
    mu_eq: Vec<f64>,
}

impl<'a> Reactions<'a> {
    /// Prepares the Jacobian of `sys`.
    pub fn new(sys: &'a System) -> Self {
        let problem = DaeProblem::new(sys, 0.0, 0.0);
        let vals = vec![0.0; problem.pattern().row_idx().len()];
        let (n, nc) = sys
            .mechanical
            .as_ref()
            .map_or((0, 0), |m| (m.n_dof, m.n_constraints));
        let mu_eq = sys
            .recast
            .as_ref()
            .and_then(|r| r.equilibrium.get(2 * n..2 * n + nc))
            .map_or_else(|| vec![0.0; nc], <[f64]>::to_vec);
        Self {
            sys,
            problem,
            vals,
            cq: Mat::zeros(0, 0),
            mu_eq,
        }
    }

    /// `C_q(q)^T mu` (`n` entries) at the recast state `z` (auxiliaries
    /// satisfying their definitions).
    pub fn at(&mut self, z: &[f64]) -> Vec<f64> {
        constraint_jacobian_into(self.sys, &self.problem, z, &mut self.vals, &mut self.cq);
        let (nc, n) = (self.cq.nrows(), self.cq.ncols());
        (0..n)
            .map(|j| {
                (0..nc)
                    .map(|c| self.cq[(c, j)] * (self.mu_eq[c] + z[2 * n + c]))
                    .sum()
            })
            .collect()
    }
}

fn constraint_jacobian_into(
    sys: &System,
    p: &DaeProblem,
    z: &[f64],
    vals: &mut [f64],
    cq: &mut Mat<f64>,
) {
    let (n, nc) = sys
        .mechanical
        .as_ref()
        .map_or((0, 0), |m| (m.n_dof, m.n_constraints));
    let pattern = p.pattern();
    p.jacobian(0.0, z, vals);
    *cq = Mat::zeros(nc, n);
    for col in 0..n {
        let range = pattern.col_range(col);
        for (&row, &v) in pattern.row_idx()[range.clone()].iter().zip(&vals[range]) {
            if (2 * n..2 * n + nc).contains(&row) {
                cq[(row - 2 * n, col)] += v;
            }
        }
    }
    // a recast's constraint rows depend on q also through its auxiliaries
    // (`u = sin phi`): `dC/dq = C_q + C_u du/dq` by the chain rule
    if let Some(recast) = &sys.recast {
        let first_aux = recast.n_original;
        let du_dz = recast.aux_jacobian(z);
        for (k, du) in du_dz.iter().enumerate() {
            let range = pattern.col_range(first_aux + k);
            for (&row, &v) in pattern.row_idx()[range.clone()].iter().zip(&vals[range]) {
                if (2 * n..2 * n + nc).contains(&row) {
                    for &(j, d) in du.iter().filter(|(j, _)| *j < n) {
                        cq[(row - 2 * n, j)] += v * d;
                    }
                }
            }
        }
    }
}

/// `[C_q(q_1) U, ..., C_q(q_K) U]` (`n_c x r K`) at `samples` snapshots
/// spread evenly over `run`, first and last included.
fn stacked_constraint_jacobian(
    sys: &System,
    run: &[Vec<f64>],
    u: &Mat<f64>,
    samples: usize,
) -> Mat<f64> {
    let nc = sys.mechanical.as_ref().map_or(0, |m| m.n_constraints);
    let r = u.ncols();
    let k = samples.min(run.len());
    let picks: Vec<usize> = if k == 1 {
        vec![0]
    } else {
        (0..k).map(|i| i * (run.len() - 1) / (k - 1)).collect()
    };
    let p = DaeProblem::new(sys, 0.0, 0.0);
    let mut vals = vec![0.0; p.pattern().row_idx().len()];
    let mut y = Mat::<f64>::zeros(nc, r * picks.len());
    let mut cq = Mat::<f64>::zeros(0, 0);
    for (s, &pick) in picks.iter().enumerate() {
        constraint_jacobian_into(sys, &p, &run[pick], &mut vals, &mut cq);
        let block = &cq * u;
        for c in 0..nc {
            for j in 0..r {
                y[(c, s * r + j)] = block[(c, j)];
            }
        }
    }
    y
}
