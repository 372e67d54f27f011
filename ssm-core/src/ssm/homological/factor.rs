//! The factorizations of `sigma B - A` the homological solves go through:
//! an LU (of the equilibrated matrix where band solves run), or the real
//! form's `L B L^T` of a symmetric condensed pencil.

use std::sync::Arc;
use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::SparseColMat;
use faer::Par;
use rayon::prelude::*;
use ssm_kernel::number::inverse_power_of_two;
use ssm_kernel::sparse_sym::{
    row_max, symmetric_equilibrate, ComplexSymFactor, SymbolicComplexSym,
};

use super::{Homological, HomologicalError};
use crate::C64;

/// A sparse LU of `M = sigma B - A`, or of `D_r M D_c` with the diagonal
/// equilibration `scale = (D_r, D_c)` (each row, then each column, scaled
/// to a largest entry between 1/2 and 1 by a power of two, so that scaling
/// rounds nothing): where band solves run (finite-element models whose rows
/// differ in scale by orders of magnitude) the pivots of the equilibrated
/// matrix keep an unrefined solve's componentwise backward error small, and
/// a refined solve needs fewer sweeps.
///
/// # References
/// N. J. Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed.,
/// SIAM (2002), Sect. 9.8 (scaling and equilibration); E. Anderson et al.,
/// *LAPACK Users' Guide*, 3rd ed., SIAM (1999) (`xGEEQU`).
///
/// Where the velocities of a mechanical model are eliminated
/// ([`condense`](crate::model::condense)), the LU is of the condensed `S(sigma)`, half the size.
pub(in crate::ssm) struct Factor {
    pub(super) lu: Kernel,
    pub(super) scale: Option<(Vec<f64>, Vec<f64>)>,
    /// The value factorized (what [`Condensed`](crate::model::condense::Condensed) expands with).
    pub(super) sigma: C64,
    /// Heap the LU holds (0 where the allocator does not count).
    pub(super) bytes: usize,
}

/// The factorization of a [`Factor`]: an LU, or where the condensed pencil
/// is symmetric and its factors are dear, the `L B L^T` of its real form
/// ([`ssm_kernel::sparse_sym`]: a few times fewer entries, fewer flops).
pub(super) enum Kernel {
    Lu(Box<Lu<usize, C64>>),
    Symmetric(ComplexSymFactor),
}

/// Scales `vals` (the values of `pattern`) to `D_r M D_c` and returns `(D_r,
/// D_c)` (see [`Factor`]).
pub(super) fn equilibrate_in_place(
    pattern: faer::sparse::SymbolicSparseColMatRef<'_, usize>,
    vals: &mut [C64],
) -> (Vec<f64>, Vec<f64>) {
    let row: Vec<f64> = row_max(pattern, vals)
        .into_iter()
        .map(inverse_power_of_two)
        .collect();
    let mut col = vec![1.0f64; pattern.ncols()];
    for (j, cj) in col.iter_mut().enumerate() {
        let mut m = 0.0f64;
        for k in pattern.col_range(j) {
            vals[k] *= row[pattern.row_idx()[k]];
            m = m.max(vals[k].norm());
        }
        *cj = inverse_power_of_two(m);
        for k in pattern.col_range(j) {
            vals[k] *= *cj;
        }
    }
    (row, col)
}

/// `x` overwritten by the factorized matrix's inverse applied to it.
pub(super) fn kernel_solve(lu: &Kernel, mut x: Vec<C64>) -> Vec<C64> {
    match lu {
        Kernel::Lu(lu) => {
            let n = x.len();
            let mut m = faer::MatMut::from_column_major_slice_mut(&mut x, n, 1);
            lu.solve_in_place(m.as_mut());
        }
        Kernel::Symmetric(f) => f.solve_in_place(&mut x),
    }
    x
}

/// A numeric factorization as [`Homological::factorization`] makes it,
/// before it is counted.
struct Made {
    lu: Kernel,
    scale: Option<(Vec<f64>, Vec<f64>)>,
    sigma: C64,
}

impl Made {
    /// The heap it holds where its own structure tells (a symmetric `L B
    /// L^T` and its scaling), so that it can be made beside other work;
    /// `None` for an LU (measured by the counting allocator instead).
    fn known_bytes(&self) -> Option<usize> {
        let Kernel::Symmetric(f) = &self.lu else {
            return None;
        };
        let scale = self
            .scale
            .as_ref()
            .map_or(0, |(r, c)| 8 * (r.len() + c.len()));
        Some(f.heap_bytes() + scale)
    }
}

impl Homological<'_> {
    /// A new factorization of `sigma B - A` (counted); where band solves
    /// run, of the equilibrated matrix (see [`Factor`]).
    pub(super) fn fresh_lu(&mut self, sigma: C64) -> Result<Factor, HomologicalError> {
        let t = Instant::now();
        let equilibrate = self.analyzed()?;
        let (made, bytes) =
            ssm_kernel::heap::held(|| self.factorization(sigma, equilibrate, Some(Par::Seq)));
        let made = made?;
        let bytes = made.known_bytes().or(bytes);
        Ok(self.counted(t.elapsed().as_secs_f64(), made, bytes, 0))
    }

    /// Whether the factorizations are symmetric `L B L^T`s (the symbolic
    /// analysis made first), which [`Homological::fresh_lus`] makes side by
    /// side and measures from their own structure: other work may then run
    /// beside them.
    ///
    /// # Errors
    /// The symbolic analysis failed.
    pub(crate) fn factors_concurrent(&mut self) -> Result<bool, HomologicalError> {
        self.analyzed()?;
        Ok(self.sym_symbolic.is_some())
    }

    /// New factorizations at each of `sigmas`, made side by side (one per
    /// core, each on one thread) where they are symmetric `L B L^T`s, whose
    /// numeric phase runs mostly on one thread whatever it is given; one by
    /// one otherwise. Counted in order, with the wall time of the batch
    /// shared out evenly and each factor's heap from its structure.
    pub(super) fn fresh_lus(&mut self, sigmas: &[C64]) -> Result<Vec<Factor>, HomologicalError> {
        let t = Instant::now();
        let equilibrate = self.analyzed()?;
        if self.sym_symbolic.is_none() || sigmas.len() < 2 {
            return sigmas.iter().map(|&s| self.fresh_lu(s)).collect();
        }
        let this = &*self;
        let made = sigmas
            .par_iter()
            .map(|&s| this.factorization(s, equilibrate, Some(Par::Seq)))
            .collect::<Result<Vec<Made>, HomologicalError>>()?;
        let count = made.len().max(1);
        let secs = t.elapsed().as_secs_f64() / count as f64;
        let mut factors = Vec::with_capacity(count);
        for m in made {
            // the batch's factors are all held once it returns
            let pending = factors.iter().map(|f: &Factor| f.bytes).sum();
            let bytes = m.known_bytes();
            factors.push(self.counted(secs, m, bytes, pending));
        }
        Ok(factors)
    }

    /// The factorizations [`Homological::solve`] will need for each value
    /// `lambda` with resonant set `set` of `systems` (those of one order,
    /// known before any is solved), made side by side where not cached
    /// ([`Homological::fresh_lus`]) and cached for it.
    ///
    /// # Errors
    /// A factorization failed.
    pub(crate) fn prefactor(
        &mut self,
        systems: &[(C64, Vec<usize>)],
    ) -> Result<(), HomologicalError> {
        let key = |s: C64| (s.re.to_bits(), s.im.to_bits());
        let mut missing: Vec<C64> = Vec::new();
        for (lambda, set) in systems {
            let sigma = self.factorized_at(*lambda, set);
            if !self.numeric.contains_key(&key(sigma))
                && !missing.iter().any(|&m| key(m) == key(sigma))
            {
                missing.push(sigma);
            }
        }
        if missing.len() < 2 {
            return Ok(());
        }
        let factors = self.fresh_lus(&missing)?;
        for (sigma, f) in missing.into_iter().zip(factors) {
            self.numeric.insert(key(sigma), f);
        }
        Ok(())
    }

    /// The symbolic analysis every factorization shares, made once
    /// (counted): the real form's `L B L^T` where the condensed pencil is
    /// symmetric and the factors dear, an LU's otherwise. Returns whether
    /// the factorizations equilibrate (where band solves run).
    fn analyzed(&mut self) -> Result<bool, HomologicalError> {
        let equilibrate = self.iterative();
        if equilibrate && !self.sym_checked {
            self.sym_checked = true;
            if let Some(c) = self.condensed.as_ref().filter(|c| c.is_symmetric()) {
                let sym = SymbolicComplexSym::analyze(c.symbolic.as_ref()).map_err(|e| {
                    HomologicalError::Singular {
                        detail: format!("symbolic L B L^T failed: {e:?}"),
                    }
                })?;
                self.sym_symbolic = Some(Arc::new(sym));
                self.stats.symbolic += 1;
            }
        }
        if self.sym_symbolic.is_none() && self.lu_symbolic.is_none() {
            let pattern = match &self.condensed {
                Some(c) => c.symbolic.as_ref(),
                None => self.symbolic.as_ref(),
            };
            let sym = SymbolicLu::try_new(pattern).map_err(|e| HomologicalError::Singular {
                detail: format!("symbolic LU failed: {e:?}"),
            })?;
            self.lu_symbolic = Some(sym);
            self.stats.symbolic += 1;
        }
        Ok(equilibrate)
    }

    /// The numeric factorization at `sigma` once [`Homological::analyzed`]
    /// ran, reading the solver alone; `par` is the `L B L^T`'s parallelism
    /// (faer's global one where `None`).
    fn factorization(
        &self,
        sigma: C64,
        equilibrate: bool,
        par: Option<Par>,
    ) -> Result<Made, HomologicalError> {
        let pattern = match &self.condensed {
            Some(c) => c.symbolic.as_ref(),
            None => self.symbolic.as_ref(),
        };
        if let Some(sym) = self.sym_symbolic.clone() {
            let mut vals = self
                .condensed
                .as_ref()
                .expect("symmetric: condensed")
                .values(sigma);
            let scale = symmetric_equilibrate(pattern, &mut vals);
            let par = par.unwrap_or_else(faer::get_global_parallelism);
            let f = ComplexSymFactor::factor(sym, &vals, par);
            return Ok(Made {
                lu: Kernel::Symmetric(f),
                scale: Some((scale.clone(), scale)),
                sigma,
            });
        }
        let mut vals: Vec<C64> = match &self.condensed {
            Some(c) => c.values(sigma),
            None => self
                .a_val
                .iter()
                .zip(&self.b_val)
                .map(|(&a, &b)| sigma * b - a)
                .collect(),
        };
        let scale = equilibrate.then(|| equilibrate_in_place(pattern, &mut vals));
        let mat = SparseColMat::new(pattern.to_owned().expect("a valid pattern"), vals);
        let lu =
            Lu::try_new_with_symbolic(self.lu_symbolic.clone().expect("analyzed"), mat.as_ref())
                .map_err(|e| HomologicalError::Singular {
                    detail: format!(
                        "sparse LU of Lambda B - A at Lambda = {sigma:.4e} failed: {e:?}"
                    ),
                })?;
        Ok(Made {
            lu: Kernel::Lu(Box::new(lu)),
            scale,
            sigma,
        })
    }

    /// A factorization that took `secs` counted, with the heap it holds
    /// (`bytes`) and that of the factors made with it and not yet kept
    /// (`pending`).
    fn counted(&mut self, secs: f64, made: Made, bytes: Option<usize>, pending: usize) -> Factor {
        if matches!(made.lu, Kernel::Symmetric(_)) {
            self.stats.symmetric_factorizations += 1;
        }
        self.stats.factorizations += 1;
        self.stats.factor_s += secs;
        if let Some(b) = bytes {
            let held = self.held_factor_bytes() + pending + b;
            self.stats.factor_bytes = Some(self.stats.factor_bytes.unwrap_or(0).max(held));
        }
        Factor {
            lu: made.lu,
            scale: made.scale,
            sigma: made.sigma,
            bytes: bytes.unwrap_or(0),
        }
    }

    /// Heap the factors kept now hold (cached values and band anchors), as
    /// counted when they were made; 0 where the allocator does not count.
    pub(crate) fn held_factor_bytes(&self) -> usize {
        self.numeric.values().map(|f| f.bytes).sum::<usize>()
            + self.anchors.iter().map(|a| a.lu.bytes).sum::<usize>()
            + self.condensed.as_ref().map_or(0, |c| c.mass_bytes)
    }
}
