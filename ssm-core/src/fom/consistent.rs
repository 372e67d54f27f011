//! Consistent initial values of the constrained first-order DAE.
//!
//! For the mechanical layout `z = (x, x', mu, u)` (auxiliaries `u` of a recast
//! last), a guess `(x0, v0)`, typically a point `W(p0)` of an SSM, is made
//! consistent in three stages:
//! 1. positions: damped Newton projection onto `g(x) = 0` with minimal
//!    Euclidean correction, `[[I, G^T], [G, 0]] (dx, l) = (0, -g(x))`;
//! 2. velocities: `[[M, G^T], [G, 0]] (dv, l) = (0, -G v)`, so `G(x) v = 0`;
//! 3. multipliers from the acceleration-level constraint, eq. (90) with
//!    `alpha = beta = 0`: `M a - J_mu mu = f_hat`, `G a = -(d^2/ds^2) g(x + s v)`,
//!    where `J_mu` is the (exact) Jacobian of the momentum rows with respect to
//!    the multipliers.
//!
//! Auxiliary states follow their definitions exactly ([`crate::model::recast::RecastInfo::lift`]).
//! `g` is evaluated exactly; its Jacobian `G` is exact for polynomial models and
//! taken by central differences through the lift for recast ones (relative
//! accuracy about `1e-10`, which affects only the size of the correction, not
//! the residual Newton drives to zero). The curvature term `g''[v, v]` is a
//! Richardson-extrapolated second difference (about `1e-9` relative).
//!
//! # References
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), eqs. (88)-(93);
//! E. Hairer, G. Wanner, *Solving ODEs II*, Sect. VII.1 (hidden constraints).

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use super::{DaeProblem, SimError};

/// A consistent initial state and how far the guess had to move.
#[derive(Debug, Clone, PartialEq)]
pub struct Consistent {
    /// The consistent state.
    pub z: Vec<f64>,
    /// Largest change of a displacement.
    pub position_correction: f64,
    /// Largest change of a velocity.
    pub velocity_correction: f64,
    /// Largest `|g(x)|` left.
    pub constraint_residual: f64,
    /// Largest `|G(x) v|` left.
    pub velocity_residual: f64,
}

const MAX_NEWTON: usize = 25;

/// Makes `guess` consistent at time `t0` (see the module docs). Models
/// without configuration constraints only get their auxiliaries lifted; a
/// model with algebraic equations but no mechanical structure must be given
/// consistent values (checked).
pub fn consistent_initial(p: &DaeProblem, t0: f64, guess: &[f64]) -> Result<Consistent, SimError> {
    consistent_initial_keeping(p, t0, guess, &[])
}

/// The initial state of a run of `p.sys` from the named `(state, value)`
/// pairs: the origin (rest at the equilibrium) when there are none, else
/// the values made consistent with the displacements among them kept
/// (`consistent_initial_keeping`).
pub fn given_start(p: &DaeProblem, values: &[(String, f64)]) -> Result<Vec<f64>, SimError> {
    if values.is_empty() {
        return Ok(vec![0.0; p.n()]);
    }
    let (z, keep) = p.sys.given_state(values);
    Ok(consistent_initial_keeping(p, 0.0, &z, &keep)?.z)
}

/// [`consistent_initial`] with the displacements `keep` (state indices)
/// held at their given values where the constraints allow: they weigh `1e6`
/// in the position metric, so the other coordinates take up the correction
/// (a displaced slider moves its pendulums along).
pub(crate) fn consistent_initial_keeping(
    p: &DaeProblem,
    t0: f64,
    guess: &[f64],
    keep: &[usize],
) -> Result<Consistent, SimError> {
    let sys = p.sys;
    let big_n = p.n();
    if guess.len() != big_n {
        return Err(SimError::Settings(format!(
            "initial state has {} entries, the system {big_n}",
            guess.len()
        )));
    }
    if let Some(i) = guess.iter().position(|v| !v.is_finite()) {
        return Err(SimError::Inconsistent {
            t: t0,
            detail: format!("initial state '{}' is not finite", p.state_name(i)),
        });
    }
    let lift = |z: &mut Vec<f64>| {
        if let Some(r) = &sys.recast {
            let lifted = r.lift(&z[..r.n_original]);
            z[..lifted.len()].copy_from_slice(&lifted);
        }
    };
    let mech = match &sys.mechanical {
        Some(m) if m.n_constraints > 0 => m,
        _ => {
            let mut z = guess.to_vec();
            lift(&mut z);
            let residual = algebraic_residual(p, &z);
            if residual.0 > 1e-8 * (1.0 + inf_norm(&z)) {
                return Err(SimError::Inconsistent {
                    t: t0,
                    detail: format!(
                        "algebraic equation {} (state '{}') has residual {:.3e}, and the model has no \
                         mechanical structure (x, x', mu) to project with; give consistent values",
                        residual.1,
                        p.state_name(residual.1),
                        residual.0
                    ),
                });
            }
            return Ok(Consistent {
                z,
                position_correction: 0.0,
                velocity_correction: 0.0,
                constraint_residual: 0.0,
                velocity_residual: 0.0,
            });
        }
    };
    let n = mech.n_dof;
    let nc = mech.n_constraints;
    let g_rows = 2 * n..2 * n + nc;
    let assemble = |x: &[f64], v: &[f64], mu: &[f64]| {
        let mut z = guess.to_vec();
        z[..n].copy_from_slice(x);
        z[n..2 * n].copy_from_slice(v);
        z[2 * n..2 * n + nc].copy_from_slice(mu);
        lift(&mut z);
        z
    };
    let zeros_n = vec![0.0; n];
    let zeros_c = vec![0.0; nc];
    let mut buf = vec![0.0; big_n];
    let mut g_of = |x: &[f64]| -> Vec<f64> {
        let z = assemble(x, &zeros_n, &zeros_c);
        p.autonomous_rhs(&z, &mut buf);
        buf[g_rows.clone()].to_vec()
    };
    let x0 = guess[..n].to_vec();
    let mut x = x0.clone();
    // positions move as little as possible in the model's own coordinates
    // (Euclidean): the mass metric would put the correction into light
    // rotational coordinates, beyond where sin/cos linearize
    let identity = SparseColMat::<usize, f64>::try_new_from_triplets(
        n,
        n,
        &(0..n)
            .map(|i| Triplet::new(i, i, if keep.contains(&i) { 1e6 } else { 1.0 }))
            .collect::<Vec<_>>(),
    )
    .expect("diagonal pattern");
    // 1. positions
    let mut converged = false;
    let mut g = g_of(&x);
    if let Some(j) = g.iter().position(|v| !v.is_finite()) {
        return Err(SimError::Inconsistent {
            t: t0,
            detail: format!(
                "constraint {} ('{}') is not finite at the given point: it violates the \
                 constraints beyond repair",
                j + 1,
                p.state_name(2 * n + j)
            ),
        });
    }
    for _ in 0..MAX_NEWTON {
        let scale = 1.0 + inf_norm(&x);
        if inf_norm(&g) <= 1e-13 * scale {
            converged = true;
            break;
        }
        let gm = constraint_jacobian(p, &x, &mut g_of, &assemble);
        let rhs: Vec<f64> = vec![0.0; n]
            .into_iter()
            .chain(g.iter().map(|v| -v))
            .collect();
        let sol =
            saddle_solve(&identity, &gm, None, &rhs).ok_or_else(|| SimError::Inconsistent {
                t: t0,
                detail: "the constraint Jacobian G(x) is rank deficient at the initial position \
                     (redundant constraints or a singular configuration)"
                    .into(),
            })?;
        // damped Newton: halve the step until |g| falls (the linearization of
        // sin/cos constraints overshoots on large corrections)
        let g_norm = inf_norm(&g);
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let trial: Vec<f64> = (0..n).map(|i| x[i] + alpha * sol[i]).collect();
            let gt = g_of(&trial);
            if gt.iter().all(|v| v.is_finite()) && inf_norm(&gt) < g_norm {
                x = trial;
                g = gt;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    if !converged {
        let (worst, j) = g
            .iter()
            .enumerate()
            .map(|(j, v)| (v.abs(), j))
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
        return Err(SimError::Inconsistent {
            t: t0,
            detail: format!(
                "the position constraints cannot be satisfied near the given point: after \
                 {MAX_NEWTON} Newton projections constraint {} ('{}') still has residual {worst:.3e}; \
                 the initial point violates the constraints beyond repair (start closer to the \
                 constraint manifold)",
                j + 1,
                p.state_name(2 * n + j)
            ),
        });
    }
    // 2. velocities
    let gm = constraint_jacobian(p, &x, &mut g_of, &assemble);
    let v0 = guess[n..2 * n].to_vec();
    let gv = mat_vec(&gm, &v0);
    let rhs: Vec<f64> = vec![0.0; n]
        .into_iter()
        .chain(gv.iter().map(|v| -v))
        .collect();
    let sol = saddle_solve(&mech.mass, &gm, None, &rhs).ok_or_else(|| SimError::Inconsistent {
        t: t0,
        detail: "the constraint Jacobian G(x) is rank deficient at the projected position \
                 (redundant constraints or a singular configuration)"
            .into(),
    })?;
    let v: Vec<f64> = (0..n).map(|i| v0[i] + sol[i]).collect();
    let velocity_residual = inf_norm(&mat_vec(&gm, &v));
    // 3. multipliers
    let z = assemble(&x, &v, &zeros_c);
    let mut rhs_full = vec![0.0; big_n];
    p.rhs(t0, &z, &mut rhs_full);
    let mut vel = vec![0.0; big_n];
    vel[..n].copy_from_slice(&v);
    let mut cv = vec![0.0; big_n];
    p.b_mul(&vel, &mut cv);
    let f_hat: Vec<f64> = (0..n).map(|i| rhs_full[i] - cv[i]).collect();
    let curvature = second_directional(&mut g_of, &x, &v);
    let mut jvals = vec![0.0; p.b_values().len()];
    p.jacobian(t0, &z, &mut jvals);
    let pat = p.pattern().as_ref();
    let mut j_mu: Vec<(usize, usize, f64)> = Vec::new();
    for c in 0..nc {
        let col = 2 * n + c;
        let range = pat.col_ptr()[col]..pat.col_ptr()[col + 1];
        for (&r, &v) in pat.row_idx()[range.clone()].iter().zip(&jvals[range]) {
            if r < n && v != 0.0 {
                j_mu.push((r, c, -v));
            }
        }
    }
    let rhs: Vec<f64> = f_hat
        .into_iter()
        .chain(curvature.iter().map(|v| -v))
        .collect();
    let sol =
        saddle_solve(&mech.mass, &gm, Some(&j_mu), &rhs).ok_or_else(|| SimError::Inconsistent {
            t: t0,
            detail: "the multipliers are not determined: G M^-1 G^T is singular at the initial \
                 position (redundant constraints)"
                .into(),
        })?;
    let mu = &sol[n..];
    let z = assemble(&x, &v, mu);
    let constraint_residual = inf_norm(&g_of(&x));
    Ok(Consistent {
        z,
        position_correction: (0..n).map(|i| (x[i] - x0[i]).abs()).fold(0.0, f64::max),
        velocity_correction: (0..n).map(|i| (v[i] - v0[i]).abs()).fold(0.0, f64::max),
        constraint_residual,
        velocity_residual,
    })
}

/// Largest residual of the algebraic rows (rows of `B` that are zero) and its row.
pub fn algebraic_residual(p: &DaeProblem, z: &[f64]) -> (f64, usize) {
    let n = p.n();
    let mut out = vec![0.0; n];
    p.autonomous_rhs(z, &mut out);
    let mut differential = vec![false; n];
    let b = p.sys.b.as_ref();
    for j in 0..n {
        for (i, v) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
            if *v != 0.0 {
                differential[i] = true;
            }
        }
    }
    (0..n)
        .filter(|&i| !differential[i])
        .map(|i| (out[i].abs(), i))
        .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a })
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

fn mat_vec(rows: &[Vec<(usize, f64)>], v: &[f64]) -> Vec<f64> {
    rows.iter()
        .map(|r| r.iter().map(|&(k, g)| g * v[k]).sum())
        .collect()
}

/// `G(x)` as sparse rows: exact from the Jacobian for polynomial models,
/// central differences through the lift for recast ones.
fn constraint_jacobian(
    p: &DaeProblem,
    x: &[f64],
    g_of: &mut impl FnMut(&[f64]) -> Vec<f64>,
    assemble: &impl Fn(&[f64], &[f64], &[f64]) -> Vec<f64>,
) -> Vec<Vec<(usize, f64)>> {
    let mech = p.sys.mechanical.as_ref().expect("checked by the caller");
    let (n, nc) = (mech.n_dof, mech.n_constraints);
    let mut rows = vec![Vec::new(); nc];
    if p.sys.recast.is_none() {
        let z = assemble(x, &vec![0.0; n], &vec![0.0; nc]);
        let mut vals = vec![0.0; p.b_values().len()];
        p.jacobian(0.0, &z, &mut vals);
        let pat = p.pattern().as_ref();
        for col in 0..n {
            let range = pat.col_ptr()[col]..pat.col_ptr()[col + 1];
            for (&r, &v) in pat.row_idx()[range.clone()].iter().zip(&vals[range]) {
                if (2 * n..2 * n + nc).contains(&r) && v != 0.0 {
                    rows[r - 2 * n].push((col, v));
                }
            }
        }
        return rows;
    }
    let mut xp = x.to_vec();
    for col in 0..n {
        let h = 1e-6 * (1.0 + x[col].abs());
        xp[col] = x[col] + h;
        let gp = g_of(&xp);
        xp[col] = x[col] - h;
        let gm = g_of(&xp);
        xp[col] = x[col];
        for j in 0..nc {
            let d = (gp[j] - gm[j]) / (2.0 * h);
            if d != 0.0 {
                rows[j].push((col, d));
            }
        }
    }
    rows
}

/// `d^2/ds^2 g(x + s v)` at `s = 0`, Richardson-extrapolated second differences
/// along the unit direction.
fn second_directional(g_of: &mut impl FnMut(&[f64]) -> Vec<f64>, x: &[f64], v: &[f64]) -> Vec<f64> {
    let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
    let g0 = g_of(x);
    if norm == 0.0 {
        return vec![0.0; g0.len()];
    }
    let mut d2 = |e: f64| {
        let xp: Vec<f64> = x.iter().zip(v).map(|(a, b)| a + e * b / norm).collect();
        let xm: Vec<f64> = x.iter().zip(v).map(|(a, b)| a - e * b / norm).collect();
        let (gp, gm) = (g_of(&xp), g_of(&xm));
        (0..g0.len())
            .map(|j| (gp[j] - 2.0 * g0[j] + gm[j]) / (e * e))
            .collect::<Vec<f64>>()
    };
    let e = 1e-3;
    let coarse = d2(e);
    let fine = d2(0.5 * e);
    coarse
        .iter()
        .zip(&fine)
        .map(|(c, f)| (4.0 * f - c) / 3.0 * norm * norm)
        .collect()
}

/// Solves `[[M, K], [G, 0]] (a, l) = rhs` where `K = G^T`, or `K = extra`
/// (given as `(row, col, value)`) when present. `None` when singular.
fn saddle_solve(
    mass: &SparseColMat<usize, f64>,
    g: &[Vec<(usize, f64)>],
    extra: Option<&[(usize, usize, f64)]>,
    rhs: &[f64],
) -> Option<Vec<f64>> {
    let n = mass.nrows();
    let nc = g.len();
    let mut trip = Vec::new();
    let m = mass.as_ref();
    for j in 0..n {
        for (i, v) in m.row_idx_of_col(j).zip(m.val_of_col(j)) {
            trip.push(Triplet::new(i, j, *v));
        }
    }
    for (r, row) in g.iter().enumerate() {
        for &(k, v) in row {
            trip.push(Triplet::new(n + r, k, v));
            if extra.is_none() {
                trip.push(Triplet::new(k, n + r, v));
            }
        }
    }
    if let Some(e) = extra {
        for &(i, c, v) in e {
            trip.push(Triplet::new(i, n + c, v));
        }
    }
    let mat = SparseColMat::try_new_from_triplets(n + nc, n + nc, &trip).ok()?;
    let lu = mat.sp_lu().ok()?;
    let mut x = Mat::<f64>::from_fn(n + nc, 1, |i, _| rhs[i]);
    lu.solve_in_place(x.as_mut());
    let sol: Vec<f64> = (0..n + nc).map(|i| x[(i, 0)]).collect();
    // a singular saddle matrix shows as non-finite or huge values
    let scale = 1.0 + rhs.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    if sol.iter().all(|v| v.is_finite() && v.abs() < 1e12 * scale) {
        Some(sol)
    } else {
        None
    }
}
