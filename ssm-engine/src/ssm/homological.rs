//! The homological equation of one multi-index, solved as a bordered sparse
//! system.
//!
//! At multi-index `k` the invariance equation (55) (or its map analogue) gives
//!
//! `(Lambda_k B - A) w_k + B V_I r_k = h_k`,
//!
//! with `Lambda_k = k . lambda` for flows (`mu^k` for maps), `h_k` the
//! right-hand side from lower orders and `V_I` the master eigenvectors whose
//! eigenvalues are (nearly) resonant with `Lambda_k` (inner resonances, eq. 15).
//! The normal-form choice puts the resonant part into the reduced dynamics
//! `r_k` and closes the system with `U_I^* B w_k = 0` (left eigenvectors with
//! `u_i^* B v_j = delta_ij`):
//!
//! ```text
//! [ Lambda_k B - A   B V_I ] [ w_k ]   [ h_k ]
//! [ U_I^* B          0     ] [ r_k ] = [ 0   ]
//! ```
//!
//! This bordered matrix is regular when `Lambda_k` is exactly an eigenvalue of
//! a master mode in `I` and when `B` is singular (constraint modes), so
//! exact inner resonances and DAEs need no special treatment. Multiplying the
//! first block row by `u_i^*` gives `r_i = u_i^* h_k` exactly.
//!
//! The sparsity pattern depends only on the resonant set `I`: the symbolic LU
//! is computed once per set and reused; numeric factorizations are cached per
//! distinct `(Lambda_k, I)` within an order (repeated values arise from
//! resonances among master eigenvalues).
//!
//! # References
//! S. Jain, G. Haller, *How to compute invariant manifolds and their reduced
//! dynamics in high-dimensional finite element models*, Nonlinear Dyn. 107
//! (2022), Sect. 3.2 (bordered system, physical coordinates, master modes only);
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), eqs. (15), (55).

use std::collections::HashMap;
use std::time::Instant;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::Mat;

use crate::C64;

/// Why a homological equation could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HomologicalError {
    /// The (bordered) matrix is singular or the solve lost all accuracy.
    #[error("singular homological equation ({detail})")]
    Singular {
        /// What was observed.
        detail: String,
    },
}

/// Time and work spent in linear algebra.
#[derive(Debug, Clone, Copy, Default)]
pub struct SolveStats {
    /// Symbolic factorizations (one per resonant set).
    pub symbolic: usize,
    /// Numeric factorizations.
    pub factorizations: usize,
    /// Solves.
    pub solves: usize,
    /// Seconds in symbolic and numeric factorization.
    pub factor_s: f64,
    /// Seconds in triangular solves and residual checks.
    pub solve_s: f64,
}

struct Pattern {
    symbolic: SymbolicSparseColMat<usize>,
    lu: SymbolicLu<usize>,
}

/// Solver for the homological equations of one SSM computation.
pub struct Homological<'a> {
    n: usize,
    a: SparseColMatRef<'a, usize, f64>,
    b: SparseColMatRef<'a, usize, f64>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    a_val: Vec<f64>,
    b_val: Vec<f64>,
    b_rows: Vec<usize>,
    b_col_nonempty: Vec<bool>,
    bv: Vec<Vec<C64>>,
    ub: Vec<Vec<C64>>,
    patterns: HashMap<Vec<usize>, Pattern>,
    numeric: HashMap<(u64, u64, Vec<usize>), Lu<usize, C64>>,
    /// Work counters.
    pub stats: SolveStats,
}

impl<'a> Homological<'a> {
    /// Prepares the union pattern of `A` and `B` and the border vectors `B v_i`
    /// and `u_i^* B` of the master coordinates (`right[i]`, `left[i]` for
    /// reduced coordinate `i`, conjugates included).
    pub fn new(
        a: SparseColMatRef<'a, usize, f64>,
        b: SparseColMatRef<'a, usize, f64>,
        right: &[Vec<C64>],
        left: &[Vec<C64>],
    ) -> Self {
        let n = a.nrows();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut a_val = Vec::new();
        let mut b_val = Vec::new();
        col_ptr.push(0);
        let mut b_row_used = vec![false; n];
        let mut b_col_nonempty = vec![false; n];
        for (j, nonempty) in b_col_nonempty.iter_mut().enumerate() {
            let mut entries: Vec<(usize, f64, f64)> = a
                .row_idx_of_col(j)
                .zip(a.val_of_col(j))
                .map(|(i, &v)| (i, v, 0.0))
                .collect();
            for (i, &v) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
                b_row_used[i] = true;
                *nonempty = true;
                entries.push((i, 0.0, v));
            }
            entries.sort_unstable_by_key(|e| e.0);
            let mut last = usize::MAX;
            for (i, av, bv) in entries {
                if i == last {
                    *a_val.last_mut().expect("an entry was pushed") += av;
                    *b_val.last_mut().expect("an entry was pushed") += bv;
                } else {
                    row_idx.push(i);
                    a_val.push(av);
                    b_val.push(bv);
                    last = i;
                }
            }
            col_ptr.push(row_idx.len());
        }
        let b_rows = (0..n).filter(|&i| b_row_used[i]).collect();
        let bv = right
            .iter()
            .map(|v| crate::spectrum::modes::spmv(b, v))
            .collect();
        // (u^* B)_j = sum_r conj(u_r) B_rj = conj((B^T u)_j) for real B
        let ub = left
            .iter()
            .map(|u| {
                crate::spectrum::modes::spmv_t(b, u)
                    .into_iter()
                    .map(|c| c.conj())
                    .collect()
            })
            .collect();
        Self {
            n,
            a,
            b,
            col_ptr,
            row_idx,
            a_val,
            b_val,
            b_rows,
            b_col_nonempty,
            bv,
            ub,
            patterns: HashMap::new(),
            numeric: HashMap::new(),
            stats: SolveStats::default(),
        }
    }

    /// Forgets cached numeric factorizations (called between orders, where
    /// values of `Lambda` no longer repeat).
    pub fn clear_numeric(&mut self) {
        self.numeric.clear();
    }

    fn pattern(&mut self, set: &[usize]) -> Result<&Pattern, HomologicalError> {
        if !self.patterns.contains_key(set) {
            let t = Instant::now();
            let n = self.n;
            let r = set.len();
            let mut col_ptr = Vec::with_capacity(n + r + 1);
            let mut row_idx = Vec::with_capacity(self.row_idx.len() + 2 * r * n);
            col_ptr.push(0);
            for j in 0..n {
                row_idx.extend_from_slice(&self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]]);
                if self.b_col_nonempty[j] {
                    row_idx.extend(n..n + r);
                }
                col_ptr.push(row_idx.len());
            }
            for _ in 0..r {
                row_idx.extend_from_slice(&self.b_rows);
                col_ptr.push(row_idx.len());
            }
            let symbolic = SymbolicSparseColMat::new_checked(n + r, n + r, col_ptr, None, row_idx);
            let lu =
                SymbolicLu::try_new(symbolic.as_ref()).map_err(|e| HomologicalError::Singular {
                    detail: format!("symbolic LU failed: {e:?}"),
                })?;
            self.patterns.insert(set.to_vec(), Pattern { symbolic, lu });
            self.stats.symbolic += 1;
            self.stats.factor_s += t.elapsed().as_secs_f64();
        }
        Ok(&self.patterns[set])
    }

    fn values(&self, lambda: C64, set: &[usize]) -> Vec<C64> {
        let n = self.n;
        let mut vals = Vec::with_capacity(self.row_idx.len() + 2 * set.len() * n);
        for j in 0..n {
            for e in self.col_ptr[j]..self.col_ptr[j + 1] {
                vals.push(lambda * self.b_val[e] - self.a_val[e]);
            }
            if self.b_col_nonempty[j] {
                vals.extend(set.iter().map(|&i| self.ub[i][j]));
            }
        }
        for &i in set {
            vals.extend(self.b_rows.iter().map(|&r| self.bv[i][r]));
        }
        vals
    }

    /// Solves the bordered system at `lambda` with resonant master coordinates
    /// `set` (sorted). Returns `w_k` and the reduced-dynamics coefficients
    /// `r_k` (one per entry of `set`).
    pub fn solve(
        &mut self,
        lambda: C64,
        set: &[usize],
        rhs: &[C64],
    ) -> Result<(Vec<C64>, Vec<C64>), HomologicalError> {
        let n = self.n;
        let key = (lambda.re.to_bits(), lambda.im.to_bits(), set.to_vec());
        if !self.numeric.contains_key(&key) {
            let vals = self.values(lambda, set);
            let (symbolic, lu_sym) = {
                let p = self.pattern(set)?;
                (p.symbolic.clone(), p.lu.clone())
            };
            let t = Instant::now();
            let mat = SparseColMat::new(symbolic, vals);
            let lu = Lu::try_new_with_symbolic(lu_sym, mat.as_ref()).map_err(|e| {
                HomologicalError::Singular {
                    detail: format!("sparse LU at Lambda = {lambda:.6} failed: {e:?}"),
                }
            })?;
            self.stats.factorizations += 1;
            self.stats.factor_s += t.elapsed().as_secs_f64();
            self.numeric.insert(key.clone(), lu);
        }
        let t = Instant::now();
        let r = set.len();
        let mut x = Mat::<C64>::from_fn(
            n + r,
            1,
            |i, _| {
                if i < n {
                    rhs[i]
                } else {
                    C64::new(0.0, 0.0)
                }
            },
        );
        self.numeric[&key].solve_in_place(x.as_mut());
        let w: Vec<C64> = (0..n).map(|i| x[(i, 0)]).collect();
        let coeffs: Vec<C64> = (0..r).map(|t| x[(n + t, 0)]).collect();
        self.stats.solves += 1;
        let check = self.residual(lambda, set, &w, &coeffs, rhs);
        self.stats.solve_s += t.elapsed().as_secs_f64();
        check?;
        Ok((w, coeffs))
    }

    /// Relative residual of the bordered system; rejects non-finite solutions
    /// and solutions that do not satisfy the equations (singular matrix).
    fn residual(
        &self,
        lambda: C64,
        set: &[usize],
        w: &[C64],
        coeffs: &[C64],
        rhs: &[C64],
    ) -> Result<(), HomologicalError> {
        let finite = |v: &[C64]| v.iter().all(|c| c.re.is_finite() && c.im.is_finite());
        if !finite(w) || !finite(coeffs) {
            return Err(HomologicalError::Singular {
                detail: format!("the solve at Lambda = {lambda:.6} produced non-finite values"),
            });
        }
        let bw = crate::spectrum::modes::spmv(self.b, w);
        let aw = crate::spectrum::modes::spmv(self.a, w);
        let mut res2 = 0.0;
        let mut scale2 = 0.0;
        for i in 0..self.n {
            let mut v = lambda * bw[i] - aw[i];
            for (t, &c) in set.iter().enumerate() {
                v += self.bv[c][i] * coeffs[t];
            }
            res2 += (v - rhs[i]).norm_sqr();
            scale2 += rhs[i].norm_sqr() + v.norm_sqr();
        }
        for &c in set {
            let s: C64 = self.ub[c].iter().zip(w).map(|(u, x)| u * x).sum();
            res2 += s.norm_sqr();
        }
        let rel = (res2 / scale2.max(f64::MIN_POSITIVE)).sqrt();
        if rel.is_nan() || rel > 1e-6 {
            return Err(HomologicalError::Singular {
                detail: format!(
                    "relative residual {rel:.2e} of the solve at Lambda = {lambda:.6}: the matrix is numerically singular"
                ),
            });
        }
        Ok(())
    }
}
