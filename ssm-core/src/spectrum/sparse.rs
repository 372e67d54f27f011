//! Sparse path: shift-invert Krylov-Schur.
//!
//! The finite eigenvalues `lambda` of `(A, B)` nearest a real shift `sigma` are
//! the largest-magnitude eigenvalues `theta = 1 / (lambda - sigma)` of
//! `T = (A - sigma B)^{-1} B` (of a mechanical pencil, through the
//! factorization of its condensed `S(sigma)`, half the size:
//! `crate::model::condense`; Cholesky where that is symmetric positive
//! definite). Infinite
//! eigenvalues map to `theta = 0`, so they
//! are never among the wanted ones; the start vector is purified by applying `T`
//! twice so that Krylov vectors carry no constraint-mode components. `T` is
//! applied through one sparse LU of `A - sigma B` (symbolic and numeric phase
//! once), and faer's Krylov-Schur iteration (`partial_eigen`) keeps only the
//! Krylov basis: memory is `O(N k)` for `k` modes, never `O(N^2)`.
//!
//! # References
//! G. W. Stewart, *A Krylov-Schur algorithm for large eigenproblems*, SIAM J.
//! Matrix Anal. Appl. 23 (2001) 601-614; T. Ericsson, A. Ruhe, *The spectral
//! transformation Lanczos method*, Math. Comp. 35 (1980) 1251-1268 (shift-invert
//! and purification for singular `B`).

use std::ops::Range;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::Solve;
use faer::matrix_free::LinOp;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::solvers::Lu;
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Accum, Col, Mat, MatMut, MatRef, Par};
use ssm_kernel::sparse_sym::SpdFactor;

use super::{krylov, SpectrumError};
use crate::model::condense;
use crate::C64;

/// The factorization the shift-invert operator solves with: the Cholesky
/// factor of a symmetric positive definite condensed `S(sigma)` (a
/// finite-element model's stiffness at the default shift 0: a fraction of
/// an LU's entries and work, solved on one thread), an LU otherwise.
enum ShiftFactor {
    Lu(Lu<usize, f64>),
    Spd(SpdFactor),
}

impl ShiftFactor {
    fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        match self {
            Self::Lu(lu) => lu.solve_in_place(rhs),
            Self::Spd(f) => f.solve_in_place(rhs),
        }
    }
}

/// The operator `(A - sigma B)^{-1} B`: through the LU of `A - sigma B`,
/// or of a mechanical pencil's condensed `S(sigma)` (half the size).
struct ShiftInvert<'a> {
    lu: ShiftFactor,
    b: SparseColMatRef<'a, usize, f64>,
    condensed: Option<(condense::ShiftInvert, f64)>,
}

impl std::fmt::Debug for ShiftInvert<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShiftInvert")
            .field("n", &self.b.nrows())
            .field("condensed", &self.condensed.is_some())
            .finish()
    }
}

impl LinOp<f64> for ShiftInvert<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.b.nrows()
    }
    fn ncols(&self) -> usize {
        self.b.ncols()
    }
    fn apply(
        &self,
        mut out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        _stack: &mut MemStack,
    ) {
        faer::sparse::linalg::matmul::sparse_dense_matmul(
            out.rb_mut(),
            Accum::Replace,
            self.b,
            rhs,
            1.0,
            par,
        );
        let Some((c, sigma)) = &self.condensed else {
            self.lu.solve_in_place(out);
            return;
        };
        let cols: Vec<Vec<f64>> = (0..out.ncols())
            .map(|j| c.rhs(&out.rb().col(j).iter().copied().collect::<Vec<_>>(), *sigma))
            .collect();
        let rows = cols.first().map_or(0, Vec::len);
        let mut x = Mat::<f64>::from_fn(rows, cols.len(), |i, j| cols[j][i]);
        self.lu.solve_in_place(x.as_mut());
        for j in 0..out.ncols() {
            let xj: Vec<f64> = x.col(j).iter().copied().collect();
            let zj: Vec<f64> = rhs.col(j).iter().copied().collect();
            for (o, w) in out
                .rb_mut()
                .col_mut(j)
                .iter_mut()
                .zip(c.expand(&xj, &zj, *sigma))
            {
                *o = w;
            }
        }
    }
    fn conj_apply(
        &self,
        out: MatMut<'_, f64>,
        rhs: MatRef<'_, f64>,
        par: Par,
        stack: &mut MemStack,
    ) {
        self.apply(out, rhs, par, stack);
    }
}

/// `A + s B` for real `s` (same sparsity as the union of both patterns).
pub(crate) fn combine(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    s: f64,
) -> SparseColMat<usize, f64> {
    let mut trip = Vec::with_capacity(a.compute_nnz() + b.compute_nnz());
    for (m, w) in [(a, 1.0), (b, s)] {
        for j in 0..m.ncols() {
            for (i, v) in m.row_idx_of_col(j).zip(m.val_of_col(j)) {
                trip.push(Triplet::new(i, j, w * v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(a.nrows(), a.ncols(), &trip)
        .expect("indices come from valid matrices of equal shape")
}

/// The `modes` finite eigenvalues of `(A, B)` nearest `shift`, unsorted
/// (conjugate partners included), and the sparse work done: one symbolic
/// and one numeric factorization at the shift, one solve per application
/// of the shift-invert operator.
pub(crate) fn eigenvalues_near_shift(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    velocities: Option<Range<usize>>,
    shift: f64,
    modes: usize,
) -> Result<(Vec<C64>, super::SolveCounts), SpectrumError> {
    let n = a.nrows();
    let condensed = velocities.and_then(|v| condense::ShiftInvert::detect(a, b, v));
    let shifted = match &condensed {
        Some(c) => c.real(shift),
        None => combine(a, b, -shift),
    };
    // symmetric positive definite (tried where the condensed pencil is
    // symmetric): Cholesky; otherwise, or where it is not definite, an LU
    let spd = condensed
        .as_ref()
        .filter(|c| n > super::DENSE_LIMIT && c.is_symmetric())
        .and_then(|_| SpdFactor::factor(shifted.as_ref()));
    let lu = match spd {
        Some(f) => ShiftFactor::Spd(f),
        None => ShiftFactor::Lu(shifted.sp_lu().map_err(|e| SpectrumError::SingularShift {
            shift,
            detail: lu_failure(&e),
            suggestion: None,
        })?),
    };
    drop(shifted);
    let op = ShiftInvert {
        lu,
        b,
        condensed: condensed.map(|c| (c, shift)),
    };
    // purified, deterministic start vector: T^2 x with x a fixed pseudo-random vector
    let mut x = Mat::<f64>::from_fn(n, 1, |i, _| pseudo_random(i));
    let mut y = Mat::<f64>::zeros(n, 1);
    let mut empty = MemBuffer::new(StackReq::EMPTY);
    for _ in 0..2 {
        op.apply(y.as_mut(), x.as_ref(), Par::Seq, MemStack::new(&mut empty));
        let norm = y.norm_l2();
        if !norm.is_finite() || norm == 0.0 {
            return Err(SpectrumError::SingularShift {
                shift,
                detail: "the factorization produced a non-finite solution".into(),
                suggestion: None,
            });
        }
        y /= faer::Scale(norm);
        std::mem::swap(&mut x, &mut y);
    }
    let v0: Col<f64> = x.col(0).to_owned();
    // a pair at the edge is taken whole by the iteration
    let want = modes.min(n);
    let applied = std::cell::Cell::new(2usize);
    let apply = |x: faer::ColRef<'_, f64>, out: MatMut<'_, f64>| {
        applied.set(applied.get() + 1);
        op.apply(
            out,
            x.as_mat(),
            Par::Seq,
            MemStack::new(&mut MemBuffer::new(StackReq::EMPTY)),
        );
    };
    let vals = krylov::largest_eigenvalues(&apply, n, v0.as_ref(), want, 1e-12, 2000).map_err(
        |e| match e {
            krylov::KrylovError::NotConverged { converged, .. } => SpectrumError::NotConverged {
                found: converged,
                requested: modes,
            },
            krylov::KrylovError::RayleighQuotient { .. } => SpectrumError::NotConverged {
                found: 0,
                requested: modes,
            },
        },
    )?;
    let found = vals.len();
    if found < modes.min(n) {
        return Err(SpectrumError::NotConverged {
            found,
            requested: modes,
        });
    }
    let theta_max = vals[..found].iter().map(|t| t.norm()).fold(0.0, f64::max);
    let mut out: Vec<C64> = vals[..found]
        .iter()
        .filter(|t| t.norm() > 1e-10 * theta_max)
        .map(|t| C64::new(shift, 0.0) + C64::new(1.0, 0.0) / C64::new(t.re, t.im))
        .collect();
    // keep the `modes` nearest the shift, counting a pair whole
    out.sort_by(|x, y| (x - shift).norm().total_cmp(&(y - shift).norm()));
    let mut kept = Vec::with_capacity(modes + 1);
    for l in out {
        if kept.len() >= modes
            && !(l.im < 0.0
                && kept
                    .iter()
                    .any(|k: &C64| (k.conj() - l).norm() <= 1e-8 * l.norm()))
        {
            break;
        }
        kept.push(l);
    }
    let work = super::SolveCounts {
        symbolic: 1,
        factorizations: 1,
        solves: applied.get(),
        iterations: 0,
    };
    Ok((kept, work))
}

/// A sparse LU failure in words.
fn lu_failure(e: &faer::sparse::linalg::LuError) -> String {
    match e {
        faer::sparse::linalg::LuError::SymbolicSingular { index } => {
            format!("every pivot candidate is zero at elimination step {index}")
        }
        faer::sparse::linalg::LuError::Generic(e) => format!("sparse LU failed: {e:?}"),
    }
}

/// True when `A - sigma B` factors with a finite, moderately sized solution
/// for a pseudo-random right-hand side (a growth above `1e14` relative to the
/// matrix scale counts as singular).
pub fn is_regular_at(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    sigma: f64,
) -> bool {
    let m = combine(a, b, -sigma);
    let Ok(lu) = m.sp_lu() else {
        return false;
    };
    let n = m.nrows();
    let rhs = Mat::<f64>::from_fn(n, 1, |i, _| pseudo_random(i));
    let x = lu.solve(&rhs);
    let scale = m
        .val()
        .iter()
        .fold(0.0_f64, |s, v| s.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    let growth = x.norm_l2() * scale / rhs.norm_l2().max(f64::MIN_POSITIVE);
    growth.is_finite() && growth < 1e14
}

/// A fixed pseudo-random sequence in (-1, 1) (SplitMix64), so that runs are
/// reproducible.
pub fn pseudo_random(i: usize) -> f64 {
    let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}
