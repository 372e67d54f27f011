//! The bordered systems `[J; e_k^T] x = r` of a sparse problem, `J` of size
//! `n x (n + 1)` on a fixed pattern.
//!
//! The border fixes `x_k = r_(n+1)`, so the system is the square one
//! `J_(-k) x_(-k) = r_(1..n) - J_k x_k`, `J_(-k)` the Jacobian without its
//! column `k`: no dense row enters the sparse LU (one would make the
//! structure of `J^T J`, on which the symbolic LU with partial pivoting
//! rests, dense). The symbolic analysis (COLAMD ordering and elimination
//! structure) is made once per local parameter `k` and reused; along a branch
//! `k` is the frequency but near folds, where an amplitude takes over, so a
//! handful of analyses serve a whole branch. Each analysis keeps its
//! factors' storage ([`SparseLu`], on one thread).

use std::collections::HashMap;

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{MatMut, Par};

use super::ProblemFailure;
use crate::sparse_lu::SparseLu;

/// A sparse `n x (n + 1)` Jacobian's bordered solves.
pub struct SparseBordered {
    pattern: SymbolicSparseColMat<usize>,
    /// `k -> (pattern without column k, its LU)`.
    analyses: HashMap<usize, (SymbolicSparseColMat<usize>, SparseLu<f64>)>,
    /// The local parameter of the last factorization, if it succeeded.
    factored: Option<usize>,
    /// Column `k` of the last factorization: `(row, value)`.
    column_k: Vec<(usize, f64)>,
    /// Numeric factorizations made.
    pub factorizations: usize,
    /// Symbolic analyses made.
    pub analyses_made: usize,
}

impl SparseBordered {
    /// For Jacobians on `pattern` (`n x (n + 1)`, rows sorted per column).
    pub fn new(pattern: SymbolicSparseColMat<usize>) -> Self {
        Self {
            pattern,
            analyses: HashMap::new(),
            factored: None,
            column_k: Vec::new(),
            factorizations: 0,
            analyses_made: 0,
        }
    }

    /// The pattern.
    pub fn pattern(&self) -> &SymbolicSparseColMat<usize> {
        &self.pattern
    }

    /// Factorizes `J_(-k)` from the values `vals` of `J` in the pattern's
    /// order.
    pub fn factor(&mut self, vals: &[f64], k: usize) -> Result<(), ProblemFailure> {
        let n = self.pattern.nrows();
        let cp = self.pattern.col_ptr();
        let ri = self.pattern.row_idx();
        if let std::collections::hash_map::Entry::Vacant(slot) = self.analyses.entry(k) {
            let mut col_ptr = Vec::with_capacity(n + 1);
            col_ptr.push(0);
            let mut rows = Vec::with_capacity(ri.len());
            for j in (0..=n).filter(|&j| j != k) {
                rows.extend_from_slice(&ri[cp[j]..cp[j + 1]]);
                col_ptr.push(rows.len());
            }
            let sq = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
            let lu = SparseLu::analyze(sq.as_ref(), Par::Seq).map_err(|e| {
                ProblemFailure(format!("symbolic LU of the Jacobian failed: {e:?}"))
            })?;
            slot.insert((sq, lu));
            self.analyses_made += 1;
        }
        self.factored = None;
        let (sq, lu) = self.analyses.get_mut(&k).expect("analyzed above");
        let mut v = Vec::with_capacity(vals.len());
        for j in (0..=n).filter(|&j| j != k) {
            v.extend_from_slice(&vals[cp[j]..cp[j + 1]]);
        }
        let m = SparseColMat::new(sq.clone(), v);
        lu.factor(m.as_ref())
            .map_err(|e| ProblemFailure(format!("sparse LU of the Jacobian failed: {e:?}")))?;
        self.column_k = (cp[k]..cp[k + 1]).map(|p| (ri[p], vals[p])).collect();
        self.factored = Some(k);
        self.factorizations += 1;
        Ok(())
    }

    /// Solves `[J; e_k^T] x = rhs` in place (`n + 1` values).
    pub fn solve(&mut self, rhs: &mut [f64]) -> Result<(), ProblemFailure> {
        let k = self
            .factored
            .ok_or_else(|| ProblemFailure("solve before factor".into()))?;
        let lu = &mut self.analyses.get_mut(&k).expect("factored").1;
        let n = rhs.len() - 1;
        let xk = rhs[n];
        let mut b = rhs[..n].to_vec();
        for &(r, v) in &self.column_k {
            b[r] -= v * xk;
        }
        lu.solve_in_place(MatMut::from_column_major_slice_mut(&mut b, n, 1));
        if !b.iter().all(|v| v.is_finite()) {
            return Err(ProblemFailure("the bordered Jacobian is singular".into()));
        }
        // reinsert x_k at its place
        rhs[..k].copy_from_slice(&b[..k]);
        rhs[k] = xk;
        rhs[k + 1..].copy_from_slice(&b[k..]);
        Ok(())
    }
}
