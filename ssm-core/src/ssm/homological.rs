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
//! The bordered system is solved by block elimination with a sparse LU of the
//! leading block `M = Lambda B - A` only: `Y = M^{-1} B V_I`,
//! `S = U_I^* B Y` (`|I| x |I|`), `r = S^{-1} U_I^* B M^{-1} h`,
//! `w = M^{-1} h - Y r`. Factorizing the bordered matrix itself would put a
//! dense row and column into the sparse LU, and partial pivoting on the dense
//! row fills the factors quadratically in `N` (measured: 3.5 GB at
//! `N = 2 10^4`). When `Lambda_k` is within `1e-8` of a resonant master
//! eigenvalue (exact inner resonance, e.g. conservative systems), `M` is
//! singular and is factorized at the nearby `Lambda_k + delta` instead; the
//! bordered system stays regular, and iterative refinement with the true
//! residual of the bordered system recovers full accuracy (each sweep reduces
//! the error by about `|delta| ||B|| ||K^{-1}||`).
//!
//! One symbolic LU (pattern of `A` and `B` together) serves every
//! factorization; numeric factorizations are cached per distinct value of the
//! factorized `Lambda` within an order (repeated values arise from resonances
//! among master eigenvalues).
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

use crate::spectrum::modes::{spmv, spmv_t};

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

impl SolveStats {
    /// The counts alone (what is the same from run to run).
    pub fn counts(&self) -> SolveCounts {
        SolveCounts {
            symbolic: self.symbolic,
            factorizations: self.factorizations,
            solves: self.solves,
        }
    }
}

/// Work done in linear algebra, without its seconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SolveCounts {
    /// Symbolic factorizations.
    pub symbolic: usize,
    /// Numeric factorizations.
    pub factorizations: usize,
    /// Solves.
    pub solves: usize,
}

/// Solver for the homological equations of one SSM computation.
pub(crate) struct Homological<'a> {
    n: usize,
    a: SparseColMatRef<'a, usize, f64>,
    b: SparseColMatRef<'a, usize, f64>,
    symbolic: SymbolicSparseColMat<usize>,
    lu_symbolic: Option<SymbolicLu<usize>>,
    a_val: Vec<f64>,
    b_val: Vec<f64>,
    lambda: Vec<C64>,
    bv: Vec<Vec<C64>>,
    ub: Vec<Vec<C64>>,
    numeric: HashMap<(u64, u64), Lu<usize, C64>>,
    /// Work counters.
    pub stats: SolveStats,
}

/// Relative distance to a resonant master eigenvalue below which the leading
/// block is factorized at a shifted value.
const SHIFT_BELOW: f64 = 1e-8;
/// Relative size of that shift.
const SHIFT: f64 = 1e-6;
/// Iterative-refinement sweeps at most.
const MAX_REFINE: usize = 6;
/// Accepted relative residual of the bordered system.
const RESIDUAL_TOL: f64 = 1e-10;

impl<'a> Homological<'a> {
    /// Prepares the union pattern of `A` and `B` and the border vectors `B v_i`
    /// and `u_i^* B` of the master coordinates (`lambda[i]`, `right[i]`,
    /// `left[i]` for reduced coordinate `i`, conjugates included).
    pub fn new(
        a: SparseColMatRef<'a, usize, f64>,
        b: SparseColMatRef<'a, usize, f64>,
        lambda: &[C64],
        right: &[Vec<C64>],
        left: &[Vec<C64>],
    ) -> Self {
        let n = a.nrows();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        let mut a_val = Vec::new();
        let mut b_val = Vec::new();
        col_ptr.push(0);
        for j in 0..n {
            let mut entries: Vec<(usize, f64, f64)> = a
                .row_idx_of_col(j)
                .zip(a.val_of_col(j))
                .map(|(i, &v)| (i, v, 0.0))
                .collect();
            entries.extend(
                b.row_idx_of_col(j)
                    .zip(b.val_of_col(j))
                    .map(|(i, &v)| (i, 0.0, v)),
            );
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
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let bv = right.iter().map(|v| spmv(b, v)).collect();
        // (u^* B)_j = sum_r conj(u_r) B_rj = conj((B^T u)_j) for real B
        let ub = left
            .iter()
            .map(|u| spmv_t(b, u).into_iter().map(|c| c.conj()).collect())
            .collect();
        Self {
            n,
            a,
            b,
            symbolic,
            lu_symbolic: None,
            a_val,
            b_val,
            lambda: lambda.to_vec(),
            bv,
            ub,
            numeric: HashMap::new(),
            stats: SolveStats::default(),
        }
    }

    /// Forgets cached numeric factorizations (called between orders, where
    /// values of `Lambda` no longer repeat).
    pub(crate) fn clear_numeric(&mut self) {
        self.numeric.clear();
    }

    /// The LU of `sigma B - A`, computed or cached.
    fn factor(&mut self, sigma: C64) -> Result<&Lu<usize, C64>, HomologicalError> {
        let key = (sigma.re.to_bits(), sigma.im.to_bits());
        if !self.numeric.contains_key(&key) {
            let t = Instant::now();
            if self.lu_symbolic.is_none() {
                let sym = SymbolicLu::try_new(self.symbolic.as_ref()).map_err(|e| {
                    HomologicalError::Singular {
                        detail: format!("symbolic LU failed: {e:?}"),
                    }
                })?;
                self.lu_symbolic = Some(sym);
                self.stats.symbolic += 1;
            }
            let vals: Vec<C64> = self
                .a_val
                .iter()
                .zip(&self.b_val)
                .map(|(&a, &b)| sigma * b - a)
                .collect();
            let mat = SparseColMat::new(self.symbolic.clone(), vals);
            let lu = Lu::try_new_with_symbolic(
                self.lu_symbolic.clone().expect("computed above"),
                mat.as_ref(),
            )
            .map_err(|e| HomologicalError::Singular {
                detail: format!("sparse LU of Lambda B - A at Lambda = {sigma:.4e} failed: {e:?}"),
            })?;
            self.stats.factorizations += 1;
            self.stats.factor_s += t.elapsed().as_secs_f64();
            self.numeric.insert(key, lu);
        }
        Ok(&self.numeric[&key])
    }

    fn lu_solve(lu: &Lu<usize, C64>, rhs: &[C64]) -> Vec<C64> {
        let mut x = Mat::<C64>::from_fn(rhs.len(), 1, |i, _| rhs[i]);
        lu.solve_in_place(x.as_mut());
        (0..rhs.len()).map(|i| x[(i, 0)]).collect()
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
        // factorize at a shifted value when Lambda hits a resonant eigenvalue
        let mut sigma = lambda;
        for &i in set {
            let li = self.lambda[i];
            if (lambda - li).norm() <= SHIFT_BELOW * li.norm() {
                sigma = lambda + C64::new(SHIFT, SHIFT) * li.norm();
            }
        }
        self.factor(sigma)?;
        let t = Instant::now();
        let key = (sigma.re.to_bits(), sigma.im.to_bits());
        let lu = &self.numeric[&key];
        let r = set.len();
        // Y = M^{-1} B V_I and the Schur complement S = U_I^* B Y
        let y: Vec<Vec<C64>> = set
            .iter()
            .map(|&i| Self::lu_solve(lu, &self.bv[i]))
            .collect();
        let mut schur = vec![C64::new(0.0, 0.0); r * r];
        for (a, &i) in set.iter().enumerate() {
            for (c, yc) in y.iter().enumerate() {
                schur[a * r + c] = dot(&self.ub[i], yc);
            }
        }
        let block_solve = |h: &[C64], g: &[C64]| -> Option<(Vec<C64>, Vec<C64>)> {
            let w0 = Self::lu_solve(lu, h);
            let mut s_rhs: Vec<C64> = set
                .iter()
                .zip(g)
                .map(|(&i, &gi)| dot(&self.ub[i], &w0) - gi)
                .collect();
            solve_small(&schur, &mut s_rhs, r)?;
            let mut w = w0;
            for (yc, rc) in y.iter().zip(&s_rhs) {
                w.iter_mut().zip(yc).for_each(|(x, yv)| *x -= yv * rc);
            }
            Some((w, s_rhs))
        };
        let singular = |detail: String| HomologicalError::Singular { detail };
        let zero_g = vec![C64::new(0.0, 0.0); r];
        let (mut w, mut coeffs) = block_solve(rhs, &zero_g).ok_or_else(|| {
            singular(format!(
                "the bordered system at Lambda = {lambda:.4e} has a singular Schur complement (a resonant master eigenvalue is not simple)"
            ))
        })?;
        let mut rel = f64::INFINITY;
        for _ in 0..MAX_REFINE {
            let (res_h, res_g, scale) = self.residual(lambda, set, &w, &coeffs, rhs);
            let norm = (res_h
                .iter()
                .chain(&res_g)
                .map(|c| c.norm_sqr())
                .sum::<f64>())
            .sqrt();
            rel = norm / scale.max(f64::MIN_POSITIVE);
            if !rel.is_finite() || rel <= RESIDUAL_TOL {
                break;
            }
            let Some((dw, dr)) = block_solve(&res_h, &res_g) else {
                break;
            };
            w.iter_mut().zip(&dw).for_each(|(x, d)| *x += d);
            coeffs.iter_mut().zip(&dr).for_each(|(x, d)| *x += d);
        }
        self.stats.solves += 1;
        self.stats.solve_s += t.elapsed().as_secs_f64();
        let finite = |v: &[C64]| v.iter().all(|c| c.re.is_finite() && c.im.is_finite());
        if !finite(&w) || !finite(&coeffs) || !rel.is_finite() {
            return Err(singular(format!(
                "the solve at Lambda = {lambda:.4e} produced non-finite values"
            )));
        }
        if rel > 1e-6 {
            return Err(singular(format!(
                "relative residual {rel:.2e} of the bordered system at Lambda = {lambda:.4e} after refinement: the matrix is numerically singular"
            )));
        }
        Ok((w, coeffs))
    }

    /// Residual `(h - M w - B V r, -U^* B w)` of the bordered system and the
    /// scale `||(|h| + |M| |w| + |B V| |r|, ||U^* B|| ||w||)||` it is
    /// measured against (the Oettli-Prager componentwise backward error,
    /// aggregated in the 2-norm).
    ///
    /// # References
    /// W. Oettli, W. Prager, Numer. Math. 6 (1964) 405-409; M. Arioli, J.
    /// Demmel, I. Duff, SIAM J. Matrix Anal. Appl. 10 (1989) 165-190
    /// (stopping iterative refinement of sparse solves).
    fn residual(
        &self,
        lambda: C64,
        set: &[usize],
        w: &[C64],
        coeffs: &[C64],
        rhs: &[C64],
    ) -> (Vec<C64>, Vec<C64>, f64) {
        let bw = spmv(self.b, w);
        let aw = spmv(self.a, w);
        // Oettli-Prager: each row against `(|Lambda| |B| + |A|) |w|`, what
        // rounding in a backward-stable solve leaves (not `|Lambda B w - A
        // w|`, which cancels in the stiff rows of a fine mesh and would ask
        // for more than double precision can give)
        let w_abs: Vec<f64> = w.iter().map(|c| c.norm()).collect();
        let bw_abs = abs_spmv(self.b, &w_abs);
        let aw_abs = abs_spmv(self.a, &w_abs);
        let mut scale2 = 0.0;
        let res_h: Vec<C64> = (0..self.n)
            .map(|i| {
                let mut v = lambda * bw[i] - aw[i];
                let mut bound = lambda.norm() * bw_abs[i] + aw_abs[i];
                for (t, &c) in set.iter().enumerate() {
                    v += self.bv[c][i] * coeffs[t];
                    bound += (self.bv[c][i] * coeffs[t]).norm();
                }
                scale2 += rhs[i].norm_sqr() + bound * bound;
                rhs[i] - v
            })
            .collect();
        // each border row `u^* B w = 0` is measured against `||u^* B|| ||w||`,
        // its own backward-error scale: `u` carries the units of `1/v`, which
        // differ from those of `h` by powers of the frequency
        let w_norm = w.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
        let res_g: Vec<C64> = set
            .iter()
            .map(|&c| {
                let ub_norm = self.ub[c].iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
                scale2 += (ub_norm * w_norm).powi(2);
                -dot(&self.ub[c], w)
            })
            .collect();
        (res_h, res_g, scale2.sqrt())
    }
}

/// `|M| x` for a non-negative `x`.
fn abs_spmv(m: SparseColMatRef<'_, usize, f64>, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; m.nrows()];
    for (j, &xj) in x.iter().enumerate() {
        for (i, v) in m.row_idx_of_col(j).zip(m.val_of_col(j)) {
            y[i] += v.abs() * xj;
        }
    }
    y
}

/// `sum_i a_i b_i` (no conjugation: `ub` rows already hold `conj(u)^T B`).
fn dot(a: &[C64], b: &[C64]) -> C64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves the small dense system `S x = b` (`r x r`, row-major) in place by
/// Gaussian elimination with partial pivoting; `None` if singular.
fn solve_small(s: &[C64], b: &mut [C64], r: usize) -> Option<()> {
    let mut m = s.to_vec();
    let scale = m.iter().map(|c| c.norm()).fold(0.0, f64::max);
    for col in 0..r {
        let piv =
            (col..r).max_by(|&x, &y| m[x * r + col].norm().total_cmp(&m[y * r + col].norm()))?;
        if m[piv * r + col].norm() <= 1e-14 * scale || !m[piv * r + col].norm().is_finite() {
            return None;
        }
        for k in 0..r {
            m.swap(col * r + k, piv * r + k);
        }
        b.swap(col, piv);
        for row in col + 1..r {
            let f = m[row * r + col] / m[col * r + col];
            for k in col..r {
                let v = m[col * r + k];
                m[row * r + k] -= f * v;
            }
            let bc = b[col];
            b[row] -= f * bc;
        }
    }
    for col in (0..r).rev() {
        let mut v = b[col];
        for k in col + 1..r {
            v -= m[col * r + k] * b[k];
        }
        b[col] = v / m[col * r + col];
    }
    Some(())
}
