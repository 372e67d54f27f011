//! Master modes: right and left eigenvectors of the chosen pairs, polished by
//! inverse iteration, normalized, with a residual check.
//!
//! For each master eigenvalue `lambda` (from the dense or sparse path), one
//! complex sparse LU of `A - sigma B` with `sigma` within `1e-10 |lambda|` of
//! `lambda` serves both inverse iterations:
//! `v <- (A - sigma B)^{-1} B v` (right) and `u <- (A - sigma B)^{-H} B^H u` (left),
//! followed by the two-sided Rayleigh quotient `lambda = u^* A v / u^* B v`.
//! A mechanical pencil is factorized through its condensed `S(sigma)`, half
//! the size (`crate::model::condense`), and the velocities of `v` and `u`
//! are then set from the velocity rows.
//!
//! Normalization (scene `[ssm] normalization`):
//! - `unit`: `||v||_2 = 1`;
//! - `mass`: `x^H M x = 1` for the displacement part `x` of `v`;
//! - `{ scale = s }`: `||v||_2 = s`;
//!
//! then the phase is fixed so that the largest-modulus component of `v` is real
//! and positive (first such component on ties), and `u` is scaled so that
//! `u^* B v = 1`. The conjugate mode is `(conj(lambda), conj(v), conj(u))`.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Mat, Par};
use ssm_kernel::sparse_sym::{symmetric_equilibrate, ComplexSymFactor, SymbolicComplexSym};
use std::sync::Arc;

use super::sparse::pseudo_random;
use super::Normalization;
use super::{pair_starts, Spectrum, SpectrumError};
use crate::model::condense::ShiftInvert;
use crate::model::system::System;
use crate::C64;

/// One master mode (the member of its pair with positive imaginary part).
#[derive(Debug, Clone)]
pub struct MasterMode {
    /// 1-based pair number.
    pub pair: usize,
    /// 0-based position of `lambda` in the sorted finite spectrum.
    pub index: usize,
    /// Eigenvalue (refined).
    pub lambda: C64,
    /// Right eigenvector `A v = lambda B v`, normalized.
    pub right: Vec<C64>,
    /// Left eigenvector `u^* A = lambda u^* B`, with `u^* B v = 1`.
    pub left: Vec<C64>,
    /// Relative residual `||A v - lambda B v|| / ((||A|| + |lambda| ||B||) ||v||)`.
    pub residual: f64,
    /// The inverse iteration's sparse LU and solves.
    pub work: super::SolveCounts,
}

/// `y = M x` for real sparse `M`, complex `x`.
pub fn spmv(m: SparseColMatRef<'_, usize, f64>, x: &[C64]) -> Vec<C64> {
    let mut y = vec![C64::new(0.0, 0.0); m.nrows()];
    for (j, xj) in x.iter().enumerate() {
        for (i, v) in m.row_idx_of_col(j).zip(m.val_of_col(j)) {
            y[i] += xj * v;
        }
    }
    y
}

/// [`spmv`] of each of `xs` with one pass over `M` for all of them (the
/// vectors side by side, so that each entry is read once): the same bits as
/// a call per vector.
pub fn spmv_many(m: SparseColMatRef<'_, usize, f64>, xs: &[&[C64]]) -> Vec<Vec<C64>> {
    let k = xs.len();
    let zero = C64::new(0.0, 0.0);
    let mut x = vec![zero; m.ncols() * k];
    for (p, xp) in xs.iter().enumerate() {
        for (j, v) in xp.iter().enumerate() {
            x[j * k + p] = *v;
        }
    }
    let mut y = vec![zero; m.nrows() * k];
    for j in 0..m.ncols() {
        let xj = &x[j * k..(j + 1) * k];
        for (i, v) in m.row_idx_of_col(j).zip(m.val_of_col(j)) {
            for (yy, xx) in y[i * k..(i + 1) * k].iter_mut().zip(xj) {
                *yy += xx * v;
            }
        }
    }
    (0..k)
        .map(|p| (0..m.nrows()).map(|i| y[i * k + p]).collect())
        .collect()
}

/// `y = M^T x` for real sparse `M`, complex `x`.
pub fn spmv_t(m: SparseColMatRef<'_, usize, f64>, x: &[C64]) -> Vec<C64> {
    (0..m.ncols())
        .map(|j| {
            m.row_idx_of_col(j)
                .zip(m.val_of_col(j))
                .map(|(i, v)| x[i] * v)
                .sum()
        })
        .collect()
}

fn dot_h(u: &[C64], v: &[C64]) -> C64 {
    u.iter().zip(v).map(|(a, b)| a.conj() * b).sum()
}

fn norm2(v: &[C64]) -> f64 {
    v.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt()
}

fn fro(m: SparseColMatRef<'_, usize, f64>) -> f64 {
    (0..m.ncols())
        .flat_map(|j| m.val_of_col(j).iter())
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt()
}

/// `A - sigma B` as a complex sparse matrix.
fn shifted(sys: &System, sigma: C64) -> SparseColMat<usize, C64> {
    let (a, b) = (sys.a.as_ref(), sys.b.as_ref());
    let mut trip = Vec::with_capacity(a.compute_nnz() + b.compute_nnz());
    for j in 0..a.ncols() {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            trip.push(Triplet::new(i, j, C64::new(*v, 0.0)));
        }
        for (i, v) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
            trip.push(Triplet::new(i, j, -sigma * v));
        }
    }
    SparseColMat::try_new_from_triplets(a.nrows(), a.ncols(), &trip)
        .expect("indices come from valid matrices of equal shape")
}

/// Computes the master modes of `pairs` (1-based) from a sorted spectrum.
pub fn master_modes(
    sys: &System,
    spectrum: &Spectrum,
    pairs: &[usize],
    normalization: Normalization,
) -> Result<Vec<MasterMode>, SpectrumError> {
    let starts = pair_starts(&spectrum.eigenvalues);
    if normalization == Normalization::Mass && sys.mechanical.is_none() {
        return Err(SpectrumError::NoMassMatrix);
    }
    pairs
        .iter()
        .map(|&p| {
            let Some(&index) = starts.get(p - 1) else {
                let hint = if spectrum.complete {
                    String::new()
                } else {
                    format!(
                        " among the {} modes computed on the sparse path; raise [spectrum] modes",
                        spectrum.eigenvalues.len()
                    )
                };
                return Err(SpectrumError::PairOutOfRange {
                    pair: p,
                    available: starts.len(),
                    hint,
                });
            };
            let mut mode = refine(sys, spectrum.eigenvalues[index], normalization)?;
            mode.pair = p;
            mode.index = index;
            Ok(mode)
        })
        .collect()
}

/// The factorization of [`refine`]'s `S(sigma)` (or `A - sigma B`).
enum ShiftedFactor {
    Lu(Box<faer::sparse::linalg::solvers::Lu<usize, C64>>),
    /// The `L B L^T` of `D S D` and `D`.
    Symmetric(ComplexSymFactor, Vec<f64>),
}

impl ShiftedFactor {
    /// `S^{-1} r`, or `S^{-H} r` (`adjoint`): for a symmetric `S`,
    /// `S^{-H} r = conj(S^{-1} conj(r))`, and `S^{-1} = D (D S D)^{-1} D`.
    fn solve(&self, r: Vec<C64>, adjoint: bool) -> Vec<C64> {
        match self {
            Self::Lu(lu) => {
                let mut m = Mat::<C64>::from_fn(r.len(), 1, |i, _| r[i]);
                if adjoint {
                    lu.solve_adjoint_in_place(m.as_mut());
                } else {
                    lu.solve_in_place(m.as_mut());
                }
                (0..r.len()).map(|i| m[(i, 0)]).collect()
            }
            Self::Symmetric(f, d) => {
                let turn = |c: C64| if adjoint { c.conj() } else { c };
                let mut x: Vec<C64> = r.iter().zip(d).map(|(&c, &di)| turn(c) * di).collect();
                f.solve_in_place(&mut x);
                x.iter().zip(d).map(|(&c, &di)| turn(c * di)).collect()
            }
        }
    }
}

fn refine(
    sys: &System,
    lambda0: C64,
    normalization: Normalization,
) -> Result<MasterMode, SpectrumError> {
    let n = sys.n_states();
    let (a, b) = (sys.a.as_ref(), sys.b.as_ref());
    let fail = |detail: String| SpectrumError::Eigenvector {
        lambda: lambda0,
        detail,
    };
    let sigma = lambda0 + C64::new(1.0, 1.0) * (1e-10 * lambda0.norm().max(1e-300));
    // a mechanical pencil: the condensed S(sigma), half the size, as the
    // real form's L B L^T of its equilibrated D S D where it is symmetric
    // and the model past the dense path's size (the homological solves'
    // kernel; a small model's LU costs nothing, and its digits are kept),
    // an LU otherwise
    let condensed = sys.velocities().and_then(|r| ShiftInvert::detect(a, b, r));
    let lu = match &condensed {
        Some(c) if n > super::DENSE_LIMIT && c.is_symmetric() => {
            let s = c.complex(sigma);
            let mut vals = s.val().to_vec();
            let scale = symmetric_equilibrate(s.symbolic(), &mut vals);
            let symbolic = SymbolicComplexSym::analyze(s.symbolic())
                .map_err(|e| fail(format!("symbolic L B L^T of A - lambda B failed: {e:?}")))?;
            let f = ComplexSymFactor::factor(Arc::new(symbolic), &vals, Par::Seq);
            ShiftedFactor::Symmetric(f, scale)
        }
        other => {
            let m = match other {
                Some(c) => c.complex(sigma),
                None => shifted(sys, sigma),
            };
            let lu = m
                .sp_lu()
                .map_err(|e| fail(format!("sparse LU of A - lambda B failed: {e:?}")))?;
            ShiftedFactor::Lu(Box::new(lu))
        }
    };
    // (A - sigma B)^{-1} y, or (A - sigma B)^{-H} y, for y = B z (B^T z)
    let solves = std::cell::Cell::new(0usize);
    let solve = |y: Vec<C64>, z: &[C64], adjoint: bool| -> Vec<C64> {
        solves.set(solves.get() + 1);
        let s = if adjoint { sigma.conj() } else { sigma };
        let r = match &condensed {
            Some(c) => c.rhs(&y, s),
            None => y,
        };
        let x = lu.solve(r, adjoint);
        match &condensed {
            Some(c) => c.expand(&x, z, s),
            None => x,
        }
    };
    let mut v: Vec<C64> = (0..n)
        .map(|i| C64::new(pseudo_random(i), pseudo_random(i + n)))
        .collect();
    let mut u: Vec<C64> = (0..n)
        .map(|i| C64::new(pseudo_random(i + 2 * n), pseudo_random(i + 3 * n)))
        .collect();
    for _ in 0..3 {
        v = solve(spmv(b, &v), &v, false);
        let s = norm2(&v);
        if !(s.is_finite() && s > 0.0) {
            return Err(fail(
                "right inverse iteration produced a non-finite vector".into(),
            ));
        }
        v.iter_mut().for_each(|c| *c /= s);

        u = solve(spmv_t(b, &u), &u, true);
        let s = norm2(&u);
        if !(s.is_finite() && s > 0.0) {
            return Err(fail(
                "left inverse iteration produced a non-finite vector".into(),
            ));
        }
        u.iter_mut().for_each(|c| *c /= s);
    }
    let quotient = |u: &[C64], v: &[C64]| -> Result<C64, SpectrumError> {
        let ubv = dot_h(u, &spmv(b, v));
        if ubv.norm() < 1e-14 * norm2(u) * norm2(v) {
            return Err(fail(format!(
                "u^* B v = {ubv:.3e}: the eigenvalue is defective or infinite, not a master-mode candidate"
            )));
        }
        Ok(dot_h(u, &spmv(a, v)) / ubv)
    };
    let mut lambda = quotient(&u, &v)?;
    // a mechanical pencil's velocity rows say `v_V = lambda v_x` exactly;
    // inverse iteration finds the velocities only through `M`, whose
    // near-null directions (the slopes of a fine plate carry tiny masses)
    // it leaves to rounding: a change of `lambda0` in its 12th digit moved
    // the 8 x 8 plate's unit-norm `v` by 5e-5 along such a direction, and
    // with it the reduced coordinates' scale
    if let Some(vel) = sys.velocities().filter(|_| condensed.is_some()) {
        let n_dof = vel.len();
        for k in 0..n_dof {
            v[vel.start + k] = lambda * v[k];
            u[vel.start + k] = lambda.conj() * u[k];
        }
        lambda = quotient(&u, &v)?;
    }
    // normalization of v
    let scale = match normalization {
        Normalization::Unit => norm2(&v),
        Normalization::Scale(s) => norm2(&v) / s,
        Normalization::Mass => {
            let mech = sys.mechanical.as_ref().ok_or(SpectrumError::NoMassMatrix)?;
            let x = &v[..mech.n_dof];
            let mx = spmv(mech.mass.as_ref(), x);
            let q = dot_h(x, &mx).re;
            if q.is_nan() || q <= 0.0 {
                return Err(fail(format!("x^H M x = {q:.3e} is not positive")));
            }
            q.sqrt()
        }
    };
    let imax = {
        let m = v.iter().map(|c| c.norm()).fold(0.0, f64::max);
        v.iter()
            .position(|c| c.norm() >= m * (1.0 - 1e-8))
            .unwrap_or(0)
    };
    let phase = v[imax] / v[imax].norm();
    let factor = phase.conj() / scale;
    v.iter_mut().for_each(|c| *c *= factor);
    let bv = spmv(b, &v);
    let s = dot_h(&u, &bv);
    u.iter_mut().for_each(|c| *c /= s.conj());
    let av = spmv(a, &v);
    let r: Vec<C64> = av
        .iter()
        .zip(spmv(b, &v))
        .map(|(x, y)| x - lambda * y)
        .collect();
    let residual = norm2(&r) / ((fro(a) + lambda.norm() * fro(b)) * norm2(&v));
    if !residual.is_finite() || residual > 1e-8 {
        return Err(fail(format!(
            "relative residual {residual:.2e} after inverse iteration"
        )));
    }
    Ok(MasterMode {
        pair: 0,
        index: 0,
        lambda,
        right: v,
        left: u,
        residual,
        work: super::SolveCounts {
            symbolic: 1,
            factorizations: 1,
            solves: solves.get(),
            iterations: 0,
        },
    })
}
