//! Dense path: QZ of the whole pencil.
//!
//! The pencil is scaled to `(A / ||A||_F, B / ||B||_F)` so that the test for an
//! infinite eigenvalue is independent of units. QZ returns each eigenvalue as a
//! ratio `alpha / beta`; an eigenvalue is finite when `|beta| > FINITE_TOL |alpha|`
//! in the scaled pencil. Infinite eigenvalues of an index-3 mechanical DAE sit in
//! Jordan blocks of size 3 and are perturbed by rounding to `|beta/alpha| ~ eps^(1/3)
//! ~ 6e-6`, so the threshold must lie well above that; finite eigenvalues of the
//! scaled pencil are O(1) for any model whose frequencies span less than about
//! three decades around `||A|| / ||B||`. Models beyond that use the sparse path,
//! which separates infinite modes exactly (they map to 0 under shift-invert).

use faer::linalg::solvers::GeneralizedEigen;
use faer::sparse::SparseColMatRef;
use faer::Mat;

use super::SpectrumError;
use crate::C64;

/// Finite-eigenvalue threshold on `|beta / alpha|` of the scaled pencil.
pub const FINITE_TOL: f64 = 1e-3;

/// Dense copy of a sparse matrix.
pub fn to_dense(m: SparseColMatRef<'_, usize, f64>) -> Mat<f64> {
    m.to_dense()
}

/// All finite eigenvalues of `(A, B)`, unsorted.
pub fn finite_eigenvalues(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
) -> Result<Vec<C64>, SpectrumError> {
    let n = a.nrows();
    let mut ad = to_dense(a);
    let mut bd = to_dense(b);
    let na = ad.norm_l2();
    let nb = bd.norm_l2();
    if na == 0.0 || nb == 0.0 {
        return Err(SpectrumError::SingularPencil {
            detail: format!("||A|| = {na}, ||B|| = {nb}"),
        });
    }
    ad /= faer::Scale(na);
    bd /= faer::Scale(nb);
    let ge = GeneralizedEigen::new_from_real(ad.as_ref(), bd.as_ref())
        .map_err(|_| SpectrumError::NoConvergence { n })?;
    let (sa, sb) = (ge.S_a(), ge.S_b());
    let mut out = Vec::new();
    for i in 0..n {
        let alpha = sa[i];
        let beta = sb[i];
        if alpha.norm() <= 1e-13 && beta.norm() <= 1e-13 {
            return Err(SpectrumError::SingularPencil {
                detail: format!("QZ returned alpha = beta = 0 at position {i}"),
            });
        }
        if beta.norm() > FINITE_TOL * alpha.norm() {
            let l = alpha / beta * (na / nb);
            out.push(C64::new(l.re, l.im));
        }
    }
    Ok(out)
}
