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
//! `NEGLIGIBLE_MULTIPLIER` (modes damped by more than 20 e-folds per
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
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Conj, Mat, Par};
use rayon::prelude::*;

use super::multipliers::{Floquet, FloquetError, UNIT_CIRCLE_TOL};
use super::HarmonicBalance;
use crate::fom::radau::{RADAU_A, RADAU_C};
use crate::C64;

/// Largest number of states `N` for which the monodromy matrix is formed.
pub const MAX_MONODROMY_STATES: usize = 200;

/// Each LU and solve sequential: at these sizes (3N of a few hundred) the
/// threads' synchronization inside one factorization costs more than the
/// second core gives (measured 1.8x slower on the divider's branch); the
/// cores share the steps and the columns instead.
const PAR: Par = Par::Seq;

/// Multipliers of smaller modulus are dropped: the algebraic directions'
/// zeros (rounding leaves them near 1e-12, measured on the recast pendulum
/// slider) and modes damped by more than `-ln(1e-9) = 20.7` e-folds per
/// period.
pub(crate) const NEGLIGIBLE_MULTIPLIER: f64 = 1e-9;

/// Default steps per period of the orbit: enough to resolve the highest
/// harmonic of `J(t)` (`2 H m` for a quadratic `F`) with several steps per
/// oscillation, at least 64.
pub fn default_steps(hb: &HarmonicBalance<'_>) -> usize {
    (16 * hb.harmonics() * hb.period_multiple()).max(64)
}

/// The Radau IIA steps of one period `m T` of the variational DAE of an
/// orbit, factored: one sparse `3N x 3N` LU of the stages per step (one
/// symbolic analysis for all), kept so that the period's map `Phi` can be
/// applied to blocks of perturbations again and again at the cost of the
/// triangular solves only.
pub struct PeriodSteps<'h, 'a> {
    hb: &'h HarmonicBalance<'a>,
    symbolic: SymbolicLu<usize>,
    numerics: Vec<NumericLu<usize, f64>>,
    /// Row sums of `A_R^{-1}` (the weights of `B y_n` in the stages).
    row_sums: Vec<f64>,
}

impl<'h, 'a> PeriodSteps<'h, 'a> {
    /// Factors the `steps` steps over the period of the orbit `c` at
    /// `omega`.
    pub fn factor(
        hb: &'h HarmonicBalance<'a>,
        c: &[f64],
        omega: f64,
        steps: usize,
    ) -> Result<Self, FloquetError> {
        let n = hb.n_states();
        let ainv = inverse3(&RADAU_A);
        let m = hb.period_multiple() as f64;
        let period = 2.0 * std::f64::consts::PI * m / omega;
        let h = period / steps as f64;
        let sp = hb.prob.pattern();
        let (cp, ri) = (sp.col_ptr(), sp.row_idx());
        let nnz = ri.len();
        // the 3N x 3N pattern: block (j, l) has the system's pattern; column
        // l N + col holds the rows of column col shifted by j N, j = 0, 1, 2
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
        // supernodal even where faer's flop ratio would pick the simplicial
        // LU: the LUs are kept and solved with blocks of columns again and
        // again, which the supernodes turn into dense block solves (the
        // chain of pendulums' branch: 92 s -> 82 s, multipliers equal to
        // 1e-10)
        let symbolic = factorize_symbolic_lu(
            pattern.as_ref(),
            faer::sparse::linalg::lu::LuSymbolicParams {
                supernodal_flop_ratio_threshold:
                    faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| FloquetError::Spectrum(format!("symbolic LU of the Radau stages: {e:?}")))?;
        let b = hb.prob.b_values();
        // the steps are independent: factored on the pool's threads, each
        // with its own scratch (the same arithmetic, so the same bits, on
        // any number of threads)
        let numerics = (0..steps)
            .into_par_iter()
            .map_init(
                || {
                    (
                        MemBuffer::new(
                            symbolic.factorize_numeric_lu_scratch::<f64>(PAR, Default::default()),
                        ),
                        [vec![0.0; nnz], vec![0.0; nnz], vec![0.0; nnz]],
                    )
                },
                |(buffer, jac), step| {
                    let t0 = step as f64 * h;
                    for (j, jv) in jac.iter_mut().enumerate() {
                        let t = t0 + RADAU_C[j] * h;
                        // the orbit at psi = Omega t / m; the forcing's phase
                        // is Omega t
                        let z = hb.state_at(c, omega * t / m);
                        hb.prob.jacobian(omega * t, &z, jv);
                    }
                    let mut vals = Vec::with_capacity(9 * nnz);
                    for l in 0..3 {
                        for col in 0..n {
                            for (j, (jv, arow)) in jac.iter().zip(&ainv).enumerate() {
                                vals.extend((cp[col]..cp[col + 1]).map(|s| {
                                    let diag = if j == l { h * jv[s] } else { 0.0 };
                                    arow[l] * b[s] - diag
                                }));
                            }
                        }
                    }
                    let mat = SparseColMat::new(pattern.clone(), vals);
                    let mut numeric = NumericLu::<usize, f64>::new();
                    symbolic
                        .factorize_numeric_lu(
                            &mut numeric,
                            mat.as_ref(),
                            PAR,
                            MemStack::new(buffer),
                            Default::default(),
                        )
                        .map_err(|e| {
                            FloquetError::Spectrum(format!(
                                "LU of the Radau stages at t = {t0:.6} of the period failed: {e:?}"
                            ))
                        })?;
                    Ok(numeric)
                },
            )
            .collect::<Result<Vec<_>, FloquetError>>()?;
        Ok(PeriodSteps {
            hb,
            symbolic,
            numerics,
            row_sums: ainv.iter().map(|r| r.iter().sum()).collect(),
        })
    }

    /// `Phi x` for the block `x` (`N x k`), in place: the stages of each
    /// step solve `(A_R^{-1} (x) B - h diag(J_j)) Y = (sum_l A_R^{-1}_{jl}) B
    /// y_n`, and `y_{n+1} = Y_3`.
    pub fn apply(&self, x: &mut Mat<f64>) -> Result<(), FloquetError> {
        // the columns are independent: a share per thread of the pool
        let k = x.ncols();
        let share = k.div_ceil(rayon::current_num_threads().max(1)).max(1);
        let mut blocks: Vec<Mat<f64>> = (0..k)
            .step_by(share)
            .map(|q| x.subcols(q, share.min(k - q)).to_owned())
            .collect();
        blocks
            .par_iter_mut()
            .try_for_each(|block| self.apply_block(block))?;
        for (i, block) in blocks.iter().enumerate() {
            x.subcols_mut(i * share, block.ncols()).copy_from(block);
        }
        Ok(())
    }

    /// [`PeriodSteps::apply`] on one thread.
    fn apply_block(&self, x: &mut Mat<f64>) -> Result<(), FloquetError> {
        let n = self.hb.n_states();
        let k = x.ncols();
        let mut rhs = Mat::<f64>::zeros(3 * n, k);
        let mut buffer = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(k, PAR));
        for (step, numeric) in self.numerics.iter().enumerate() {
            let bx = b_times(self.hb, x);
            for (j, rs) in self.row_sums.iter().enumerate() {
                for q in 0..k {
                    for i in 0..n {
                        rhs[(j * n + i, q)] = rs * bx[(i, q)];
                    }
                }
            }
            LuRef::new_unchecked(&self.symbolic, numeric).solve_in_place_with_conj(
                Conj::No,
                rhs.as_mut(),
                PAR,
                MemStack::new(&mut buffer),
            );
            x.copy_from(rhs.subrows(2 * n, n));
            if !x.col_iter().all(|c| c.iter().all(|v| v.is_finite())) {
                return Err(FloquetError::Spectrum(format!(
                    "the monodromy map is not finite after step {} of {}",
                    step + 1,
                    self.numerics.len()
                )));
            }
        }
        Ok(())
    }
}

/// The monodromy matrix `Phi` (`N x N`) of the orbit `c` at `omega` over
/// its period `m T`, by `steps` Radau IIA steps.
pub(crate) fn monodromy_matrix(
    hb: &HarmonicBalance<'_>,
    c: &[f64],
    omega: f64,
    steps: usize,
) -> Result<Mat<f64>, FloquetError> {
    let n = hb.n_states();
    if n > MAX_MONODROMY_STATES {
        return Err(FloquetError::TooLarge {
            coefficients: hb.n_coefficients(),
            limit: super::multipliers::MAX_HILL_COEFFICIENTS,
        });
    }
    let period = PeriodSteps::factor(hb, c, omega, steps)?;
    let mut phi = Mat::<f64>::identity(n, n);
    period.apply(&mut phi)?;
    Ok(phi)
}

/// The Floquet multipliers of the orbit `c` at `omega` from its monodromy
/// map with `steps` steps per period ([`default_steps`] when `None`): all of
/// them from the matrix `Phi` up to [`MAX_MONODROMY_STATES`] states, the
/// dominant ones by subspace iteration above (`dominant_multipliers`).
pub fn floquet_by_monodromy(
    hb: &HarmonicBalance<'_>,
    c: &[f64],
    omega: f64,
    steps: Option<usize>,
) -> Result<Floquet, FloquetError> {
    let steps = steps.unwrap_or_else(|| default_steps(hb)).max(1);
    let rho = if hb.n_states() <= MAX_MONODROMY_STATES {
        let phi = monodromy_matrix(hb, c, omega, steps)?;
        let l = gauge_basis(hb, c);
        let phi = match &l {
            // on an orthonormal basis Q of the gauges' complement
            Some(l) => {
                let g = l.ncols();
                let q = l.qr().compute_Q();
                let qc = q.subcols(g, hb.n_states() - g);
                qc.transpose() * &phi * qc
            }
            None => phi,
        };
        phi.eigenvalues()
            .map_err(|_| {
                FloquetError::Spectrum(
                    "eigenvalues of the monodromy matrix did not converge".into(),
                )
            })?
            .iter()
            .map(|r| C64::new(r.re, r.im))
            .collect()
    } else {
        dominant_multipliers(&PeriodSteps::factor(hb, c, omega, steps)?, c)?
    };
    let period = 2.0 * std::f64::consts::PI * hb.period_multiple() as f64 / omega;
    let multipliers: Vec<C64> = rho
        .into_iter()
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

/// The multipliers of the orbit `c` at `omega` again by the monodromy map
/// with twice [`default_steps`], and their [`Floquet::distance`] from
/// `floquet` (the orbit's multipliers as the branch has them): returns the
/// steps and the distance.
pub fn check_multipliers(
    hb: &HarmonicBalance<'_>,
    c: &[f64],
    omega: f64,
    floquet: &Floquet,
) -> Result<(usize, f64), FloquetError> {
    let steps = 2 * default_steps(hb);
    let again = floquet_by_monodromy(hb, c, omega, Some(steps))?;
    Ok((steps, floquet.distance(&again)))
}

/// Columns of the first block of [`dominant_multipliers`].
const SUBSPACE_BLOCK: usize = 16;

/// [`dominant_multipliers`] holds a block when its smallest Ritz value is
/// below this modulus: every multiplier it misses is smaller, far from the
/// unit circle where stability changes.
const SUBSPACE_FLOOR: f64 = 0.25;

/// [`dominant_multipliers`] gives the multipliers above this modulus: the
/// Ritz values below it belong to the block's unconverged tail (its last
/// columns carry the strongly damped modes, which no bifurcation involves).
pub(crate) const DOMINANT_FLOOR: f64 = 1e-3;

/// Relative residual `||Phi x - rho x|| / ||Phi||` below which a Ritz pair
/// counts as converged.
const SUBSPACE_TOL: f64 = 1e-10;

/// Subspace iterations before giving up.
const SUBSPACE_PASSES: usize = 12;

/// The dominant multipliers of the factored period `steps` of the orbit `c`
/// by subspace iteration with Rayleigh-Ritz: `Y = Phi X` on an orthonormal
/// block `X` (a deterministic pseudo-random start in the gauges'
/// complement, which `Phi` keeps), the Ritz values of `X^T Y`, and `X` the
/// orthonormal basis of `Y` for the next pass. A block is enough when its
/// smallest Ritz value is below `SUBSPACE_FLOOR` (else it doubles), and
/// the iteration stops when every Ritz pair above [`DOMINANT_FLOOR`] has a
/// residual below `SUBSPACE_TOL`; those are the multipliers returned. Each pass costs `k` solves per step
/// of the stored LUs, against `N` for the matrix: the lightly damped modes
/// are few, and the multipliers of the rest fall below `1e-6` per period
/// (measured on the chain of pendulums), so a pass gains six digits.
///
/// # References
/// Y. Saad, *Numerical Methods for Large Eigenvalue Problems*, 2nd ed., SIAM
/// (2011), Sect. 5.2 (subspace iteration, Rayleigh-Ritz); K. Lust, D. Roose,
/// A. Spence, A. R. Champneys, An adaptive Newton-Picard algorithm with
/// subspace iteration for computing periodic solutions, SIAM J. Sci. Comput.
/// 19 (1998) 1188-1209 (the dominant Floquet multipliers of large systems).
pub(crate) fn dominant_multipliers(
    steps: &PeriodSteps<'_, '_>,
    c: &[f64],
) -> Result<Vec<C64>, FloquetError> {
    let n = steps.hb.n_states();
    let gauges = gauge_basis(steps.hb, c).map(|l| {
        let g = l.ncols();
        l.qr().compute_thin_Q().subcols(0, g).to_owned()
    });
    let keep = |x: &mut Mat<f64>| {
        if let Some(l) = &gauges {
            let along = l.transpose() * &*x;
            *x -= l * along;
        }
    };
    let orthonormal = |x: &Mat<f64>| x.qr().compute_thin_Q();
    let fresh = |k: usize, from: usize| {
        Mat::<f64>::from_fn(n, k, |i, q| {
            crate::spectrum::sparse::pseudo_random(i + n * (q + from))
        })
    };
    let mut k = SUBSPACE_BLOCK.min(n);
    let mut x = fresh(k, 0);
    keep(&mut x);
    x = orthonormal(&x);
    for pass in 0..SUBSPACE_PASSES {
        let mut y = x.clone();
        steps.apply(&mut y)?;
        keep(&mut y);
        let eig = (x.transpose() * &y).eigen().map_err(|_| {
            FloquetError::Spectrum(format!(
                "eigenvalues of the {k} x {k} Rayleigh quotient of the monodromy map did not converge"
            ))
        })?;
        let (values, vectors) = (eig.S().column_vector(), eig.U());
        let scale = y.norm_l2().max(f64::MIN_POSITIVE);
        // ||Y v - rho X v|| / ||v|| per Ritz pair (v complex, X and Y real)
        let residual = |i: usize| {
            let v = vectors.col(i);
            let (re, im) = (
                Mat::<f64>::from_fn(k, 1, |q, _| v[q].re),
                Mat::<f64>::from_fn(k, 1, |q, _| v[q].im),
            );
            let rho = values[i];
            let (yr, yi, xr, xi) = (&y * &re, &y * &im, &x * &re, &x * &im);
            let r2: f64 = (0..n)
                .map(|p| {
                    let a = yr[(p, 0)] - (rho.re * xr[(p, 0)] - rho.im * xi[(p, 0)]);
                    let b = yi[(p, 0)] - (rho.re * xi[(p, 0)] + rho.im * xr[(p, 0)]);
                    a * a + b * b
                })
                .sum();
            r2.sqrt() / v.norm_l2().max(f64::MIN_POSITIVE)
        };
        let smallest = (0..k)
            .map(|i| values[i].norm())
            .fold(f64::INFINITY, f64::min);
        let dominant: Vec<usize> = (0..k)
            .filter(|&i| values[i].norm() > DOMINANT_FLOOR)
            .collect();
        let converged = dominant
            .iter()
            .all(|&i| residual(i) <= SUBSPACE_TOL * scale);
        if smallest <= SUBSPACE_FLOOR || k == n {
            if converged {
                return Ok(dominant
                    .iter()
                    .map(|&i| C64::new(values[i].re, values[i].im))
                    .collect());
            }
            x = orthonormal(&y);
        } else {
            // the block may miss a multiplier near the unit circle: double it
            let more = fresh(k.min(n - k), pass + 1);
            let mut wider = Mat::<f64>::zeros(n, k + more.ncols());
            wider.subcols_mut(0, k).copy_from(&y);
            wider.subcols_mut(k, more.ncols()).copy_from(&more);
            keep(&mut wider);
            k = wider.ncols();
            x = orthonormal(&wider);
        }
    }
    Err(FloquetError::Spectrum(format!(
        "the subspace iteration for the dominant multipliers did not converge in {SUBSPACE_PASSES} passes (block of {k})"
    )))
}

/// A basis `l` (`N x g`, not orthonormal) of the gradients of the recast's
/// gauges on the orbit `c` at `t = 0`, `None` for a model without gauges: a
/// differential auxiliary `u = g(a)` conserves `u - g(a)` along every
/// solution, so `l^T y` is conserved by the variational equation, `l^T Phi
/// = l^T`: a spurious multiplier 1 per gauge, whose complement `l^T y = 0` is
/// invariant and carries the physical multipliers.
fn gauge_basis(hb: &HarmonicBalance<'_>, c: &[f64]) -> Option<Mat<f64>> {
    if hb.gauges.is_empty() {
        return None;
    }
    let z0 = hb.state_at(c, 0.0);
    Some(Mat::<f64>::from_fn(
        hb.n_states(),
        hb.gauges.len(),
        |i, k| {
            hb.gauges[k]
                .gradient(&z0)
                .iter()
                .find(|(j, _)| *j == i)
                .map_or(0.0, |(_, d)| *d)
        },
    ))
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
