//! A sparse LU on a fixed pattern: analyzed once, refactored in place, on
//! the parallelism its caller chooses.
//!
//! The engine factors the same pattern thousands of times: the iteration
//! matrices of the Radau IIA and HHT integrators (once per step size), the
//! Jacobians of a continuation (once per corrector iterate). faer's
//! `Lu::try_new_with_symbolic` allocates a new numeric factor and its
//! workspace at each call and runs on faer's global parallelism (every core
//! through rayon). At the engine's sizes (a few hundred to some thousand
//! unknowns, supernodes of tens of columns) the threads of one factorization
//! wait on each other more than they compute: the harmonic-balance
//! continuation of the recast chain of pendulums (7695 unknowns) takes 37.5 s
//! on one thread and 35.6 s on two, using 1.5 cores for it, and a
//! test run or a study has other work for the second core. [`SparseLu`]
//! keeps its numeric storage and workspaces between factorizations and
//! factors and solves with the [`Par`] it was built with (callers pass
//! [`Par::Seq`] and share the cores across independent work instead).
//!
//! The symbolic analysis is faer's (COLAMD ordering, then a simplicial or a
//! supernodal factorization chosen by its flop ratio), the numeric one LU
//! with partial pivoting: the same arithmetic as `Lu::try_new_with_symbolic`.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::linalg::LuError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par};

/// Work done in linear algebra, without its seconds (by the SSM's
/// homological solves, the forced response, the spectrum).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SolveCounts {
    /// Symbolic factorizations.
    pub symbolic: usize,
    /// Numeric factorizations.
    pub factorizations: usize,
    /// Solves.
    pub solves: usize,
    /// Factorized solves at a nearby value: those that grew a band solve's
    /// search space and the Taylor coefficients of band series (both through
    /// one factorization for many frequencies).
    pub iterations: usize,
}

impl std::ops::Add for SolveCounts {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        SolveCounts {
            symbolic: self.symbolic + o.symbolic,
            factorizations: self.factorizations + o.factorizations,
            solves: self.solves + o.solves,
            iterations: self.iterations + o.iterations,
        }
    }
}

/// An LU factorization of square sparse matrices of one pattern.
pub struct SparseLu<T: ComplexField> {
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, T>,
    /// False until a factorization succeeds, and after one fails.
    factored: bool,
    par: Par,
    factor_scratch: MemBuffer,
    /// The solve's workspace and the number of right-hand sides it fits.
    solve_scratch: (MemBuffer, usize),
}

impl<T: ComplexField> SparseLu<T> {
    /// Analyzes `pattern` (square, rows sorted per column).
    pub fn analyze(
        pattern: SymbolicSparseColMatRef<'_, usize>,
        par: Par,
    ) -> Result<Self, faer::sparse::FaerError> {
        let symbolic = factorize_symbolic_lu(pattern, Default::default())?;
        let factor_scratch = MemBuffer::try_new(
            symbolic.factorize_numeric_lu_scratch::<T>(par, Default::default()),
        )?;
        let solve_scratch = MemBuffer::try_new(symbolic.solve_in_place_scratch::<T>(1, par))?;
        Ok(Self {
            symbolic,
            numeric: NumericLu::new(),
            factored: false,
            par,
            factor_scratch,
            solve_scratch: (solve_scratch, 1),
        })
    }

    /// The number of rows (and columns).
    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Factors `mat`, whose pattern is the analyzed one, replacing the
    /// previous factors. After an error no factors are held.
    pub fn factor(&mut self, mat: SparseColMatRef<'_, usize, T>) -> Result<(), LuError> {
        self.factored = false;
        self.symbolic.factorize_numeric_lu(
            &mut self.numeric,
            mat,
            self.par,
            MemStack::new(&mut self.factor_scratch),
            Default::default(),
        )?;
        self.factored = true;
        Ok(())
    }

    /// Whether factors are held.
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// Overwrites `rhs` (`dim x k`) with the solution of `A X = rhs`.
    ///
    /// # Panics
    /// Without factors (a caller's logic error), or if `rhs` has not
    /// [`Self::dim`] rows.
    pub fn solve_in_place(&mut self, rhs: MatMut<'_, T>) {
        assert!(self.factored, "SparseLu: solve without factors");
        let k = rhs.ncols();
        if k > self.solve_scratch.1 {
            self.solve_scratch = (
                MemBuffer::new(self.symbolic.solve_in_place_scratch::<T>(k, self.par)),
                k,
            );
        }
        // SAFETY of the pairing (checked by faer): `numeric` is the output of
        // `symbolic.factorize_numeric_lu` on a matrix of the analyzed pattern
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs,
            self.par,
            MemStack::new(&mut self.solve_scratch.0),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};
    use faer::Mat;

    /// Refactoring in place with new values solves the new system: a
    /// tridiagonal matrix and its residual, twice with different values.
    #[test]
    fn refactors_in_place_and_solves() {
        let n = 50;
        let matrix = |shift: f64| {
            let mut t = Vec::new();
            for i in 0..n {
                t.push(Triplet::new(i, i, shift + i as f64 * 0.01));
                if i + 1 < n {
                    t.push(Triplet::new(i + 1, i, 1.0));
                    t.push(Triplet::new(i, i + 1, -0.5));
                }
            }
            SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t).unwrap()
        };
        let mut lu = SparseLu::<f64>::analyze(matrix(1.0).symbolic(), Par::Seq).unwrap();
        assert!(!lu.is_factored());
        for shift in [4.0, -2.5] {
            let a = matrix(shift);
            lu.factor(a.as_ref()).unwrap();
            for k in [1, 3] {
                let x0 = Mat::<f64>::from_fn(n, k, |i, j| (i + 3 * j) as f64 - 7.0);
                let mut x = &a * &x0;
                lu.solve_in_place(x.as_mut());
                let err = (&x - &x0).norm_max();
                assert!(err < 1e-12, "{err}");
            }
        }
    }
}
