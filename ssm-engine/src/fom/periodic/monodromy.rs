//! Floquet multipliers of a harmonic-balance orbit from its monodromy
//! matrix, for orbits too large for the dense Hill eigenproblem.
//!
//! The perturbation `y` of the orbit `z(t)` obeys the linear periodic DAE
//! `B y' = J(t) y`, `J(t) = A + DF(z(t)) + eps DFext(z(t), Omega t)`, with
//! `z(t)` the orbit's own Fourier series (exact at every time). It is
//! integrated over one period `m T` from the identity with `S` fixed steps of
//! the three-stage Radau IIA method written for DAEs: with the stage values
//! `Y_j` and the method's matrix `A_R`,
//!
//! `sum_l (A_R^{-1})_{jl} B (Y_l - y_n) = h J(t_n + c_j h) Y_j`, `y_{n+1} = Y_3`,
//!
//! one sparse `3N x 3N` LU per step (its pattern, and so its symbolic
//! analysis, is the same at every step) solved for all `N` columns at once.
//! The product of the steps is the monodromy matrix `Phi`; its eigenvalues are
//! the multipliers. The method is stiffly accurate with `R(inf) = 0`: the
//! algebraic directions (constraint multipliers, recast auxiliaries) leave
//! `Phi` with zero eigenvalues, which are dropped with the multipliers below
//! [`NEGLIGIBLE_MULTIPLIER`] (modes damped by more than 20 e-folds per
//! period, which no bifurcation involves). The error of a multiplier falls as
//! `h^5` (order 5 of Radau IIA for the differential components).
//!
//! Cost: `S` sparse LUs of size `3N` and `S` solves with `N` right-hand sides,
//! against the dense Hill eigenproblem's `(N (2H + 1))^3`; the dense
//! `N x N` eigenproblem of `Phi` limits it to [`MAX_MONODROMY_STATES`].
//!
//! # References
//! E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd
//! ed., Springer (1996), Sects. IV.5, VI.6-VII.4 (Radau IIA, DAEs of index
//! up to 3); R. Seydel, *Practical Bifurcation and Stability Analysis*, 3rd
//! ed., Springer (2010), Sect. 7.1 (the monodromy matrix and its
//! multipliers); M. Krack, J. Gross, *Harmonic Balance for Nonlinear
//! Vibration Problems*, Springer (2019), Sect. 4.2 (monodromy of a harmonic
//! balance orbit by time integration).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, NumericLu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Mat, Par};

use super::floquet::{Floquet, FloquetError, UNIT_CIRCLE_TOL};
use super::HarmonicBalance;
use crate::fom::radau::{RADAU_A, RADAU_C};
use crate::C64;

/// Largest number of states `N` for which the monodromy matrix is formed.
pub const MAX_MONODROMY_STATES: usize = 200;

/// Multipliers of smaller modulus are dropped: the algebraic directions'
/// zeros (rounding leaves them near 1e-12, measured on the recast pendulum
/// slider) and modes damped by more than `-ln(1e-9) = 20.7` e-folds per
/// period.
pub const NEGLIGIBLE_MULTIPLIER: f64 = 1e-9;

/// Default steps per period of the orbit: enough to resolve the highest
/// harmonic of `J(t)` (`2 H m` for a quadratic `F`) with several steps per
/// oscillation, at least 64.
pub fn default_steps(hb: &HarmonicBalance<'_>) -> usize {
    (16 * hb.harmonics() * hb.period_multiple()).max(64)
}

/// The monodromy matrix `Phi` (`N x N`) of the orbit `c` at `omega` over
/// its period `m T`, by `steps` Radau IIA steps.
pub fn monodromy_matrix(
    hb: &HarmonicBalance<'_>,
    c: &[f64],
    omega: f64,
    steps: usize,
) -> Result<Mat<f64>, FloquetError> {
    let n = hb.n_states();
    if n > MAX_MONODROMY_STATES {
        return Err(FloquetError::TooLarge {
            coefficients: hb.n_coefficients(),
            limit: super::floquet::MAX_HILL_COEFFICIENTS,
        });
    }
    let ainv = inverse3(&RADAU_A);
    let m = hb.period_multiple() as f64;
    let period = 2.0 * std::f64::consts::PI * m / omega;
    let h = period / steps as f64;
    let sp = hb.prob.pattern();
    let (cp, ri) = (sp.col_ptr(), sp.row_idx());
    let nnz = ri.len();
    // the 3N x 3N pattern: block (j, l) has the system's pattern; column l N
    // + col holds the rows of column col shifted by j N, j = 0, 1, 2
    let mut col_ptr = Vec::with_capacity(3 * n + 1);
    let mut row_idx = Vec::with_capacity(9 * nnz);
    col_ptr.push(0);
    for _l in 0..3 {
        for col in 0..n {
            for j in 0..3 {
                row_idx.extend(ri[cp[col]..cp[col + 1]].iter().map(|r| r + j * n));
            }
            col_ptr.push(row_idx.len());
        }
    }
    let pattern = SymbolicSparseColMat::new_checked(3 * n, 3 * n, col_ptr, None, row_idx);
    // sequential: at these sizes (3N of a few hundred) the threads'
    // synchronization costs more than the second core gives (measured 1.8x
    // slower on the divider's branch with both cores)
    let par = Par::Seq;
    let symbolic = factorize_symbolic_lu(pattern.as_ref(), Default::default())
        .map_err(|e| FloquetError::Spectrum(format!("symbolic LU of the Radau stages: {e:?}")))?;
    let mut numeric = NumericLu::<usize, f64>::new();
    let mut buffer = MemBuffer::new(
        symbolic
            .factorize_numeric_lu_scratch::<f64>(par, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(n, par)),
    );
    let b = hb.prob.b_values();
    let mut jac = [vec![0.0; nnz], vec![0.0; nnz], vec![0.0; nnz]];
    let mut vals = vec![0.0; 9 * nnz];
    let mut phi = Mat::<f64>::identity(n, n);
    let mut rhs = Mat::<f64>::zeros(3 * n, n);
    let row_sums: Vec<f64> = ainv.iter().map(|r| r.iter().sum()).collect();
    for step in 0..steps {
        let t0 = step as f64 * h;
        for (j, jv) in jac.iter_mut().enumerate() {
            let t = t0 + RADAU_C[j] * h;
            // the orbit at psi = Omega t / m; the forcing's phase is Omega t
            let z = hb.state_at(c, omega * t / m);
            hb.prob.jacobian(omega * t, &z, jv);
        }
        let mut p = 0;
        for l in 0..3 {
            for col in 0..n {
                for (j, (jv, arow)) in jac.iter().zip(&ainv).enumerate() {
                    for s in cp[col]..cp[col + 1] {
                        let diag = if j == l { h * jv[s] } else { 0.0 };
                        vals[p] = arow[l] * b[s] - diag;
                        p += 1;
                    }
                }
            }
        }
        let mat = SparseColMat::new(pattern.clone(), vals.clone());
        let lu = symbolic
            .factorize_numeric_lu(
                &mut numeric,
                mat.as_ref(),
                par,
                MemStack::new(&mut buffer),
                Default::default(),
            )
            .map_err(|e| {
                FloquetError::Spectrum(format!(
                    "LU of the Radau stages at t = {t0:.6} of the period failed: {e:?}"
                ))
            })?;
        // right-hand side: block j = (sum_l A_R^{-1}_{jl}) B Phi
        let bphi = b_times(hb, &phi);
        for (j, rs) in row_sums.iter().enumerate() {
            for k in 0..n {
                for i in 0..n {
                    rhs[(j * n + i, k)] = rs * bphi[(i, k)];
                }
            }
        }
        lu.solve_in_place_with_conj(Conj::No, rhs.as_mut(), par, MemStack::new(&mut buffer));
        for k in 0..n {
            for i in 0..n {
                phi[(i, k)] = rhs[(2 * n + i, k)];
            }
        }
        if !phi.col_iter().all(|c| c.iter().all(|v| v.is_finite())) {
            return Err(FloquetError::Spectrum(format!(
                "the monodromy matrix is not finite after step {} of {steps}",
                step + 1
            )));
        }
    }
    Ok(phi)
}

/// The Floquet multipliers of the orbit `c` at `omega` from its monodromy
/// matrix with `steps` steps per period ([`default_steps`] when `None`).
pub fn floquet_by_monodromy(
    hb: &HarmonicBalance<'_>,
    c: &[f64],
    omega: f64,
    steps: Option<usize>,
) -> Result<Floquet, FloquetError> {
    let steps = steps.unwrap_or_else(|| default_steps(hb)).max(1);
    let phi = deflated(hb, c, monodromy_matrix(hb, c, omega, steps)?);
    let rho = phi.eigenvalues().map_err(|_| {
        FloquetError::Spectrum("eigenvalues of the monodromy matrix did not converge".into())
    })?;
    let period = 2.0 * std::f64::consts::PI * hb.period_multiple() as f64 / omega;
    let multipliers: Vec<C64> = rho
        .iter()
        .map(|r| C64::new(r.re, r.im))
        .filter(|r| r.norm() > NEGLIGIBLE_MULTIPLIER)
        .collect();
    let exponents = multipliers.iter().map(|r| r.ln() / period).collect();
    let unstable = multipliers
        .iter()
        .filter(|r| r.norm() > 1.0 + UNIT_CIRCLE_TOL)
        .count();
    Ok(Floquet {
        exponents,
        multipliers,
        unstable,
    })
}

/// `Phi` restricted to the perturbations that keep the recast's gauges: a
/// differential auxiliary `u = g(a)` conserves `u - g(a)` along every
/// solution, so `l^T y` with `l` its gradient on the orbit is conserved by
/// the variational equation, `l(0)^T Phi = l(0)^T`: a spurious multiplier 1
/// per gauge, whose complement `l(0)^T y = 0` is invariant. On an orthonormal
/// basis `Q` of that complement, `Q^T Phi Q` has the physical multipliers.
/// `Phi` itself for a model without gauges.
fn deflated(hb: &HarmonicBalance<'_>, c: &[f64], phi: Mat<f64>) -> Mat<f64> {
    if hb.gauges.is_empty() {
        return phi;
    }
    let n = hb.n_states();
    let z0 = hb.state_at(c, 0.0);
    let g = hb.gauges.len();
    let l = Mat::<f64>::from_fn(n, g, |i, k| {
        hb.gauges[k]
            .gradient(&z0)
            .iter()
            .find(|(j, _)| *j == i)
            .map_or(0.0, |(_, d)| *d)
    });
    let q = l.qr().compute_Q();
    let qc = q.subcols(g, n - g);
    qc.transpose() * &phi * qc
}

/// `B Phi` with the system's sparse `B`.
fn b_times(hb: &HarmonicBalance<'_>, phi: &Mat<f64>) -> Mat<f64> {
    let n = hb.n_states();
    let b = hb.prob.sys.b.as_ref();
    let mut out = Mat::<f64>::zeros(n, phi.ncols());
    for k in 0..phi.ncols() {
        for j in 0..n {
            let v = phi[(j, k)];
            if v != 0.0 {
                for (i, bij) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
                    out[(i, k)] += bij * v;
                }
            }
        }
    }
    out
}

/// The inverse of a regular 3 x 3 matrix by its adjugate.
fn inverse3(a: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let cof = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]
    };
    let det: f64 = (0..3).map(|j| a[0][j] * cof(0, j)).sum();
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = cof(j, i) / det;
        }
    }
    inv
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `A_R^{-1} A_R = I` to rounding, and the nodes are the row sums of
    /// `A_R` (the method's consistency condition).
    #[test]
    fn radau_matrix_inverse_and_nodes() {
        let inv = inverse3(&RADAU_A);
        for (i, row) in inv.iter().enumerate() {
            for j in 0..3 {
                let v: f64 = row.iter().zip(&RADAU_A).map(|(r, a)| r * a[j]).sum();
                assert!(
                    (v - f64::from(u8::from(i == j))).abs() < 1e-13,
                    "{i} {j}: {v}"
                );
            }
        }
        for (row, c) in RADAU_A.iter().zip(RADAU_C) {
            assert!((row.iter().sum::<f64>() - c).abs() < 1e-15);
        }
    }
}
