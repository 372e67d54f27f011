//! Dense path: all finite eigenvalues through the shift-inverted pencil,
//! restricted to its finite invariant subspace.
//!
//! With a real shift `sigma` that is not an eigenvalue,
//! `A v = lambda B v  <=>  T v = theta v`, `T = (A - sigma B)^{-1} B`,
//! `theta = 1 / (lambda - sigma)`. Infinite eigenvalues of the pencil (constraint
//! modes, eq. 87) form the nilpotent part of `T`; in an index-3 DAE its Jordan
//! blocks have size 3, and rounding would perturb their zero eigenvalues to
//! `|theta| ~ eps^(1/3) ||T|| ~ 1e-5 ||T||`, indistinguishable from fast finite
//! modes by any magnitude threshold. So the nilpotent part is removed exactly:
//! the finite invariant subspace is `range(T^nu)`, `nu` the index (the size of
//! the largest nilpotent block), found as the first power at which the
//! numerical rank of `T^k` stops falling. With `Q` an orthonormal basis of that
//! range (leading left singular vectors), the finite `theta` are the eigenvalues
//! of `Q^T T Q`. The rank uses a relative threshold `RANK_TOL` on singular
//! values of `T^k`; finite modes are kept as long as
//! `(|lambda_slowest| / |lambda_fastest|)^nu > RANK_TOL`, i.e. four decades of
//! frequency for an index-3 DAE and twelve for an ODE. Larger spreads belong to
//! the sparse path, which never needs the fast modes.
//!
//! Rank decisions are not invariant under a change of units: in `T` of a
//! mechanical pencil the position rows scale with `1/omega^2` against the
//! velocity rows, so at `omega = 3e7` (or `3e-8`) the singular values of an
//! undamped oscillator's `T` spread over thirty decades and one of them falls
//! below any relative threshold. `T` is therefore balanced first (a diagonal
//! similarity by powers of two, which changes neither eigenvalues nor
//! nilpotent structure and is exact in floating point), after which both
//! singular values of that oscillator are `1/omega`.
//!
//! # References
//! - B. N. Parlett, C. Reinsch, Balancing a matrix for calculation of
//!   eigenvalues and eigenvectors, Numer. Math. 13 (1969) 293-304 (the
//!   balancing sweep, as in LAPACK `dgebal` without its permutation step).

use faer::linalg::solvers::Solve;
use faer::sparse::SparseColMatRef;
use faer::Mat;

use super::SpectrumError;
use crate::C64;

/// Relative singular-value threshold for the numerical rank of `T^k`.
pub(crate) const RANK_TOL: f64 = 1e-12;

/// Largest index of a pencil this path accepts.
const MAX_INDEX: usize = 6;

/// Balances `t` in place by a diagonal similarity `D^{-1} T D` with powers of
/// two (Parlett-Reinsch): each off-diagonal row and column norm pair is made
/// equal to within a factor of two. Rows or columns that are zero off the
/// diagonal (nilpotent parts, decoupled states) are left alone.
fn balance(t: &mut Mat<f64>) {
    const RADIX: f64 = 2.0;
    const MAX_SWEEPS: usize = 200;
    let n = t.nrows();
    for _ in 0..MAX_SWEEPS {
        let mut converged = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0, 0.0);
            for j in (0..n).filter(|&j| j != i) {
                c += t[(j, i)].abs();
                r += t[(i, j)].abs();
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let s = c + r;
            let mut f = 1.0;
            while c < r / RADIX && f < 1e150 {
                c *= RADIX * RADIX;
                f *= RADIX;
            }
            while c >= r * RADIX && f > 1e-150 {
                c /= RADIX * RADIX;
                f /= RADIX;
            }
            if (c + r) / f < 0.95 * s {
                converged = false;
                for j in 0..n {
                    t[(i, j)] /= f;
                    t[(j, i)] *= f;
                }
            }
        }
        if converged {
            break;
        }
    }
}

fn numerical_rank(m: &Mat<f64>) -> Result<(usize, Mat<f64>), SpectrumError> {
    let svd = m
        .svd()
        .map_err(|_| SpectrumError::NoConvergence { n: m.nrows() })?;
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|i| s[i]).fold(0.0, f64::max);
    let rank = (0..s.nrows()).filter(|&i| s[i] > RANK_TOL * smax).count();
    Ok((rank, svd.U().subcols(0, rank).to_owned()))
}

/// The structure of the nilpotent part found by [`finite_eigenvalues`]:
/// `range(T^power)` is the finite invariant subspace, of dimension `rank`.
/// Pencils that differ by a smooth change of their entries (the Floquet
/// problems along a branch of periodic orbits) keep it, so it can be reused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct FiniteStructure {
    /// The index `nu`.
    pub power: usize,
    /// Dimension of the finite invariant subspace.
    pub rank: usize,
}

/// `T = (A - sigma B)^{-1} B`, balanced.
fn shifted_inverse(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    shift: f64,
) -> Result<Mat<f64>, SpectrumError> {
    let shifted = super::sparse::combine(a, b, -shift).to_dense();
    let lu = shifted.partial_piv_lu();
    let mut t: Mat<f64> = b.to_dense();
    lu.solve_in_place(t.as_mut());
    let norm = t.norm_l2();
    if !norm.is_finite() {
        return Err(SpectrumError::SingularShift {
            shift,
            detail: "A - sigma B is numerically singular".into(),
            suggestion: None,
        });
    }
    if norm == 0.0 {
        return Err(SpectrumError::SingularPencil {
            detail: "B = 0: the model has no dynamics".into(),
        });
    }
    balance(&mut t);
    Ok(t)
}

/// The finite eigenvalues `sigma + 1/theta` from the eigenvalues `theta` of
/// `T` on the orthonormal basis `q` of its finite invariant subspace.
fn eigenvalues_on(t: &Mat<f64>, q: &Mat<f64>, shift: f64) -> Result<Vec<C64>, SpectrumError> {
    let h = q.transpose() * t * q;
    let theta = h
        .eigenvalues()
        .map_err(|_| SpectrumError::NoConvergence { n: t.nrows() })?;
    Ok(theta
        .iter()
        .map(|t| C64::new(shift, 0.0) + C64::new(1.0, 0.0) / C64::new(t.re, t.im))
        .collect())
}

/// [`finite_eigenvalues`] reusing a known [`FiniteStructure`]: the basis of
/// `range(T^power)` from a column-pivoted QR instead of the rank search by
/// SVDs of every power. The structure is checked (a gap of six decades in
/// the diagonal of `R` after `rank` columns) and searched anew, and
/// `structure` updated, when it does not hold. The eigenvalues come from the
/// QR basis whether the structure was known or just found, so that they do
/// not depend on which earlier pencil set it (a branch resumed from a
/// checkpoint computes the same numbers as the uninterrupted one).
pub(crate) fn finite_eigenvalues_with(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    shift: f64,
    structure: &mut Option<FiniteStructure>,
) -> Result<Vec<C64>, SpectrumError> {
    let t = shifted_inverse(a, b, shift)?;
    if let Some(q) = structure.and_then(|st| basis_by_qr(&t, st)) {
        return eigenvalues_on(&t, &q, shift);
    }
    let (q, st) = finite_subspace(&t)?;
    *structure = Some(st);
    match basis_by_qr(&t, st) {
        Some(qr) => eigenvalues_on(&t, &qr, shift),
        None => eigenvalues_on(&t, &q, shift),
    }
}

/// The orthonormal basis of `range(T^power)` of the structure `st` by a
/// column-pivoted QR of `T^power`, if the structure holds for `t`.
fn basis_by_qr(t: &Mat<f64>, st: FiniteStructure) -> Option<Mat<f64>> {
    let mut power = t.clone();
    for _ in 1..st.power {
        power = t * &power;
    }
    let qr = power.col_piv_qr();
    let r = qr.R();
    let d = |i: usize| r[(i, i)].abs();
    let n = r.nrows().min(r.ncols());
    let holds = st.rank >= 1
        && st.rank <= n
        && d(st.rank - 1) > RANK_TOL * d(0)
        && (st.rank == n || d(st.rank) < 1e-6 * d(st.rank - 1));
    holds.then(|| qr.compute_thin_Q().subcols(0, st.rank).to_owned())
}

/// All finite eigenvalues of `(A, B)`, unsorted.
pub fn finite_eigenvalues(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    shift: f64,
) -> Result<Vec<C64>, SpectrumError> {
    let t = shifted_inverse(a, b, shift)?;
    let (q, _) = finite_subspace(&t)?;
    eigenvalues_on(&t, &q, shift)
}

/// An orthonormal basis of the finite invariant subspace `range(T^nu)` and
/// the structure found: the first power at which the numerical rank stops
/// falling.
fn finite_subspace(t: &Mat<f64>) -> Result<(Mat<f64>, FiniteStructure), SpectrumError> {
    let (mut rank, mut q) = numerical_rank(t)?;
    let mut power = t.clone();
    let mut stable = false;
    let mut nu = 1;
    for _ in 1..MAX_INDEX {
        power = t * &power;
        let (r, qq) = numerical_rank(&power)?;
        if r == rank {
            stable = true;
            break;
        }
        rank = r;
        q = qq;
        nu += 1;
    }
    if !stable {
        return Err(SpectrumError::SingularPencil {
            detail: format!(
                "the rank of T^k still falls at k = {MAX_INDEX} (index above {MAX_INDEX})"
            ),
        });
    }
    Ok((q, FiniteStructure { power: nu, rank }))
}
