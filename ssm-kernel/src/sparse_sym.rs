//! Symmetric sparse factorizations: complex symmetric matrices (`S^T = S`,
//! not Hermitian) through their real symmetric form ([`ComplexSymFactor`]),
//! and real symmetric positive definite ones by Cholesky ([`SpdFactor`]).
//!
//! A damped finite-element pencil `S(sigma) = K + sigma C + sigma^2 M` at a
//! complex `sigma` is complex symmetric. An LU ignores the symmetry: faer's
//! bounds its pattern by the Cholesky factor of `S^T S` in COLAMD order,
//! which on a plate of 48,242 unknowns holds 6 to 8 times the entries of the
//! Cholesky factor of `S` in minimum-degree order. faer's symmetric
//! factorizations are of Hermitian matrices, so `S = R + i T` is written as
//! the real symmetric (indefinite) matrix of twice the size
//!
//! ```text
//! [ R  -T ] [ x_r ]   [  h_r ]
//! [-T  -R ] [ x_i ] = [ -h_i ],
//! ```
//!
//! (the first block row is the real part of `S x = h`, the second minus its
//! imaginary part), with the two parts of each unknown interleaved so that
//! the ordering keeps them together, and factorized by faer's supernodal
//! `L B L^T` with Bunch-Kaufman pivoting inside the supernodes, in
//! approximate minimum degree order. Its singular values are those of `S`,
//! each twice, so the real form is as well conditioned as `S`.
//!
//! # References
//! D. Day, M. A. Heroux, *Solving complex-valued linear systems via
//! equivalent real formulations*, SIAM J. Sci. Comput. 23 (2001) 480-498
//! (the K4 form); J. R. Bunch, L. Kaufman, *Some stable methods for
//! calculating inertia and solving symmetric linear systems*, Math. Comp. 31
//! (1977) 163-179; P. R. Amestoy, T. A. Davis, I. S. Duff, *An approximate
//! minimum degree ordering algorithm*, SIAM J. Matrix Anal. Appl. 17 (1996).

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, IntranodeLbltRef, LltRef,
    SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, Mat, Par, Side};

use crate::C64;

/// Where an entry of the real form's upper triangle comes from: the entry
/// `source` of `S`'s values, its real or imaginary part, with a sign.
#[derive(Debug, Clone, Copy)]
struct Slot {
    source: usize,
    imaginary: bool,
    negate: bool,
}

/// The analysis of one pattern of `S`: the real form's upper triangle and
/// its symbolic factor (shared by every numeric factor of the pattern).
#[derive(Debug)]
pub struct SymbolicComplexSym {
    n: usize,
    pattern: SymbolicSparseColMat<usize>,
    slots: Vec<Slot>,
    symbolic: SymbolicCholesky<usize>,
}

impl SymbolicComplexSym {
    /// Analyzes the `n x n` pattern `s` of a complex symmetric matrix (both
    /// triangles, rows sorted in each column, structurally symmetric; its
    /// upper triangle is what the factorizations read).
    ///
    /// # Errors
    /// faer's symbolic analysis failed (out of memory, index overflow).
    pub fn analyze(s: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, faer::sparse::FaerError> {
        let n = s.nrows();
        let mut col_ptr = Vec::with_capacity(2 * n + 1);
        let mut row_idx = Vec::new();
        let mut slots = Vec::new();
        col_ptr.push(0);
        for j in 0..n {
            // column 2j (the real parts x_r,j) then 2j + 1 (x_i,j), rows in order
            for second in [false, true] {
                for k in s.col_range(j) {
                    let i = s.row_idx()[k];
                    if i > j {
                        break;
                    }
                    // rows 2i (the real part of row i) and 2i + 1 (minus its
                    // imaginary part): [[R, -T], [-T, -R]]
                    row_idx.push(2 * i);
                    slots.push(Slot {
                        source: k,
                        imaginary: second,
                        negate: second,
                    });
                    if i < j || second {
                        row_idx.push(2 * i + 1);
                        slots.push(Slot {
                            source: k,
                            imaginary: !second,
                            negate: true,
                        });
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let pattern = SymbolicSparseColMat::new_checked(2 * n, 2 * n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Upper,
            SymmetricOrdering::Amd,
            // the simplicial path factorizes without pivoting; the
            // supernodal one pivots (Bunch-Kaufman) inside each supernode
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )?;
        Ok(Self {
            n,
            pattern,
            slots,
            symbolic,
        })
    }

    /// Unknowns of `S`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Real entries of the factor `L` (its heap is eight bytes each, with
    /// the pivots' `3 dim` words beside them).
    pub fn factor_entries(&self) -> usize {
        self.symbolic.len_val()
    }
}

/// A numeric `L B L^T` factor of the real form of one complex symmetric `S`
/// (see the module).
#[derive(Debug)]
pub struct ComplexSymFactor {
    symbolic: Arc<SymbolicComplexSym>,
    values: Vec<f64>,
    subdiag: Vec<f64>,
    perm_fwd: Vec<usize>,
    perm_inv: Vec<usize>,
}

impl ComplexSymFactor {
    /// Factorizes `S` with values `vals` on the analyzed pattern (both
    /// triangles given; the upper one is read), on `par`.
    ///
    /// # Panics
    /// If `vals` does not have one value per entry of the pattern.
    pub fn factor(symbolic: Arc<SymbolicComplexSym>, vals: &[C64], par: Par) -> Self {
        let sym = &symbolic.symbolic;
        let real: Vec<f64> = symbolic
            .slots
            .iter()
            .map(|s| {
                let v = vals[s.source];
                let x = if s.imaginary { v.im } else { v.re };
                if s.negate {
                    -x
                } else {
                    x
                }
            })
            .collect();
        let mat = SparseColMatRef::new(symbolic.pattern.as_ref(), &real);
        let m = 2 * symbolic.n;
        let mut values = vec![0.0f64; sym.len_val()];
        let mut subdiag = vec![0.0f64; m];
        let mut perm_fwd = vec![0usize; m];
        let mut perm_inv = vec![0usize; m];
        let mut mem = MemBuffer::new(
            sym.factorize_numeric_intranode_lblt_scratch::<f64>(par, Default::default()),
        );
        sym.factorize_numeric_intranode_lblt(
            &mut values,
            &mut subdiag,
            &mut perm_fwd,
            &mut perm_inv,
            mat,
            Side::Upper,
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        Self {
            symbolic,
            values,
            subdiag,
            perm_fwd,
            perm_inv,
        }
    }

    /// Heap the factor holds: its values, the pivots' sub-diagonal and the
    /// permutation both ways (the shared symbolic analysis not included).
    /// Known from the factor itself, so factors made side by side with
    /// other work are measured exactly.
    pub fn heap_bytes(&self) -> usize {
        8 * (self.values.len() + self.subdiag.len())
            + std::mem::size_of::<usize>() * (self.perm_fwd.len() + self.perm_inv.len())
    }

    /// Overwrites `rhs` with `S^{-1} rhs`.
    ///
    /// # Panics
    /// If `rhs` does not have [`SymbolicComplexSym::dim`] entries.
    pub fn solve_in_place(&self, rhs: &mut [C64]) {
        let n = self.symbolic.n;
        assert_eq!(rhs.len(), n, "ComplexSymFactor: right-hand side size");
        let sym = &self.symbolic.symbolic;
        let mut x = Mat::<f64>::from_fn(2 * n, 1, |k, _| {
            let h = rhs[k / 2];
            if k % 2 == 0 {
                h.re
            } else {
                -h.im
            }
        });
        // SAFETY: `perm_fwd` and `perm_inv` are the inverse permutations the
        // numeric factorization wrote
        let perm = unsafe { PermRef::new_unchecked(&self.perm_fwd, &self.perm_inv, 2 * n) };
        let lblt = IntranodeLbltRef::new(sym, &self.values, &self.subdiag, perm);
        let mut mem = MemBuffer::new(sym.solve_in_place_scratch::<f64>(1, Par::Seq));
        lblt.solve_in_place_with_conj(Conj::No, x.as_mut(), Par::Seq, MemStack::new(&mut mem));
        for (k, r) in rhs.iter_mut().enumerate() {
            *r = C64::new(x[(2 * k, 0)], x[(2 * k + 1, 0)]);
        }
    }
}

/// The sparse Cholesky factor `L L^T` of a real symmetric positive
/// definite matrix (a mass matrix), in approximate minimum degree order,
/// solved on one thread: a solve is a pass over the factor's entries, and on
/// two cores faer's parallel sparse triangular solves of a plate's mass
/// matrix took 54 ms where one thread takes 11 ms.
#[derive(Debug)]
pub struct SpdFactor {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl SpdFactor {
    /// Factorizes `a` (square; its upper triangle is read), or `None` when
    /// it is not numerically positive definite or the analysis fails.
    pub fn factor(a: SparseColMatRef<'_, usize, f64>) -> Option<Self> {
        let symbolic = factorize_symbolic_cholesky(
            a.symbolic(),
            Side::Upper,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .ok()?;
        let par = faer::get_global_parallelism();
        let mut values = vec![0.0f64; symbolic.len_val()];
        let mut mem = MemBuffer::try_new(
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        )
        .ok()?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                a,
                Side::Upper,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .ok()?;
        Some(Self { symbolic, values })
    }

    /// Overwrites the columns of `rhs` with `A^{-1} rhs`.
    ///
    /// # Panics
    /// If `rhs` does not have the matrix's number of rows.
    pub fn solve_in_place(&self, rhs: faer::MatMut<'_, f64>) {
        let k = rhs.ncols();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }
}

/// The largest `|S_ij|` of each row `i` of the values `vals` on `pattern`.
pub fn row_max(pattern: SymbolicSparseColMatRef<'_, usize>, vals: &[C64]) -> Vec<f64> {
    let mut m = vec![0.0f64; pattern.nrows()];
    for j in 0..pattern.ncols() {
        for k in pattern.col_range(j) {
            let i = pattern.row_idx()[k];
            m[i] = m[i].max(vals[k].norm());
        }
    }
    m
}

/// Scales the values `vals` of the symmetric `pattern` to `D S D` and
/// returns `D`: powers of two near `m_i^(-1/2)`, `m_i` the largest entry of
/// row `i`, so that `|(D S D)_ij| <= 1` and scaling rounds nothing (the symmetric
/// counterpart of a row and column equilibration).
pub fn symmetric_equilibrate(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    vals: &mut [C64],
) -> Vec<f64> {
    let d: Vec<f64> = row_max(pattern, vals)
        .into_iter()
        .map(|m| crate::number::inverse_power_of_two(m.sqrt()))
        .collect();
    for j in 0..pattern.ncols() {
        for k in pattern.col_range(j) {
            vals[k] *= d[pattern.row_idx()[k]] * d[j];
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::linalg::solvers::Solve;

    /// A complex symmetric `S` (a damped, shifted chain of springs and masses
    /// with a longer-range coupling, indefinite in its real part) solved
    /// through the real form agrees with a dense complex LU's solution.
    #[test]
    fn the_real_form_solves_a_complex_symmetric_system() {
        let n = 60;
        let sigma = C64::new(-0.05, 1.7);
        let mut dense = faer::Mat::<C64>::zeros(n, n);
        for i in 0..n {
            let k = 2.0 + 0.01 * i as f64;
            dense[(i, i)] +=
                C64::new(k, 0.0) + sigma * 0.02 * k + sigma * sigma * (1.0 + 0.003 * i as f64);
            if i + 1 < n {
                let c = C64::new(-1.0, 0.0) - sigma * 0.01;
                dense[(i, i + 1)] += c;
                dense[(i + 1, i)] += c;
            }
            if i + 7 < n {
                let c = C64::new(0.3, 0.0);
                dense[(i, i + 7)] += c;
                dense[(i + 7, i)] += c;
            }
        }
        let mut col_ptr = vec![0usize];
        let mut rows = Vec::new();
        let mut vals = Vec::new();
        for j in 0..n {
            for i in 0..n {
                if dense[(i, j)] != C64::new(0.0, 0.0) {
                    rows.push(i);
                    vals.push(dense[(i, j)]);
                }
            }
            col_ptr.push(rows.len());
        }
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
        let symbolic = Arc::new(SymbolicComplexSym::analyze(pattern.as_ref()).unwrap());
        let f = ComplexSymFactor::factor(symbolic, &vals, Par::Seq);
        let h: Vec<C64> = (0..n)
            .map(|i| C64::new((i as f64).sin(), (0.3 * i as f64).cos()))
            .collect();
        let mut x = h.clone();
        f.solve_in_place(&mut x);
        let rhs = faer::Mat::<C64>::from_fn(n, 1, |i, _| h[i]);
        let reference = dense.partial_piv_lu().solve(&rhs);
        let scale = (0..n).map(|i| reference[(i, 0)].norm()).fold(0.0, f64::max);
        for i in 0..n {
            assert!(
                (x[i] - reference[(i, 0)]).norm() < 1e-12 * scale,
                "{i}: {} vs {}",
                x[i],
                reference[(i, 0)]
            );
        }
    }

    /// A mass-like matrix (tridiagonal, symmetric positive definite) solved
    /// by [`SpdFactor`] agrees with a dense LU's solution; an indefinite one
    /// is refused (the caller then takes an LU).
    #[test]
    fn the_cholesky_factor_solves_a_positive_definite_system_and_refuses_others() {
        let n = 40;
        let build = |diag: f64| {
            let mut trip = Vec::new();
            for i in 0..n {
                trip.push(faer::sparse::Triplet::new(i, i, diag + 0.01 * i as f64));
                if i + 1 < n {
                    trip.push(faer::sparse::Triplet::new(i, i + 1, 1.0));
                    trip.push(faer::sparse::Triplet::new(i + 1, i, 1.0));
                }
            }
            faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).unwrap()
        };
        let spd = build(4.0);
        let f = SpdFactor::factor(spd.as_ref()).expect("positive definite");
        let mut x = faer::Mat::<f64>::from_fn(n, 2, |i, k| (i + 3 * k) as f64 - 7.0);
        let rhs = x.clone();
        f.solve_in_place(x.as_mut());
        let reference = spd.to_dense().partial_piv_lu().solve(&rhs);
        for k in 0..2 {
            for i in 0..n {
                assert!(
                    (x[(i, k)] - reference[(i, k)]).abs() < 1e-12 * (1.0 + reference[(i, k)].abs())
                );
            }
        }
        assert!(SpdFactor::factor(build(-0.5).as_ref()).is_none());
    }
}
