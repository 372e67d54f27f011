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
//! the error by about `|delta| ||B|| ||K^{-1}||`). Where band solves run
//! (finite-element models, [`iterates`]) every solve is refined so until its
//! componentwise backward error reaches a few roundings or stops halving
//! ([`Homological::residual`]): the LU is backward stable in norm only, and
//! a badly scaled model's soft rows need the refinement.
//!
//! One symbolic LU (pattern of `A` and `B` together) serves every
//! factorization; numeric factorizations are cached per distinct value of the
//! factorized `Lambda` within an order (repeated values arise from resonances
//! among master eigenvalues).
//!
//! The forced response needs the same system at a band of nearby values (one
//! per frequency of its table); where the pattern's factors are expensive
//! (fill above [`pattern::NEAR_FILL`]) [`Homological::solve_band`] solves them all
//! through one factorization at an anchor of the band (module `band`).
//!
//! # References
//! S. Jain, G. Haller, *How to compute invariant manifolds and their reduced
//! dynamics in high-dimensional finite element models*, Nonlinear Dyn. 107
//! (2022), Sect. 3.2 (bordered system, physical coordinates, master modes only);
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), eqs. (15), (55).

use std::collections::HashMap;
use std::time::Instant;

use faer::sparse::linalg::solvers::SymbolicLu;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use ssm_kernel::sparse_sym::SymbolicComplexSym;

use factor::{kernel_solve, Factor};
use std::sync::Arc;

use crate::model::condense;
use crate::spectrum::modes::{spmv, spmv_t};

use crate::C64;

mod band;
mod factor;
mod pattern;
mod series;
pub use band::band_vectors;
use pattern::iterates;
pub use pattern::{lu_bytes_estimate, FactorBytes, LU_BYTES_PER_ENTRY};
pub use series::MAX_TERMS as SERIES_TERMS;
pub(crate) use series::{accept as series_accept, horner, SeriesRun};

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
    /// Of them, those of a symmetric condensed pencil's real form (`L B
    /// L^T`, [`ssm_kernel::sparse_sym`]) instead of an LU.
    pub symmetric_factorizations: usize,
    /// Solves.
    pub solves: usize,
    /// Factorized solves at a nearby value: those that grew a band solve's
    /// search space (`Homological::solve_band`) and the Taylor coefficients
    /// of band series (`Homological::solve_series`).
    pub iterations: usize,
    /// Seconds in symbolic and numeric factorization.
    pub factor_s: f64,
    /// Seconds in triangular solves and residual checks.
    pub solve_s: f64,
    /// The most heap the sparse factors held at once, in bytes, as the
    /// process's allocator counted them ([`ssm_kernel::heap`]); `None`
    /// where it does not count.
    pub factor_bytes: Option<usize>,
}

impl SolveStats {
    /// The counts alone (what is the same from run to run).
    pub fn counts(&self) -> SolveCounts {
        SolveCounts {
            symbolic: self.symbolic,
            factorizations: self.factorizations,
            solves: self.solves,
            iterations: self.iterations,
        }
    }
}

pub use ssm_kernel::sparse_lu::SolveCounts;

/// A bordered solve's `w_k` and reduced-dynamics coefficients `r_k`.
pub(crate) type Solution = (Vec<C64>, Vec<C64>);

/// The residual of the bordered system and its backward errors
/// ([`Homological::residual`]).
struct Residual {
    h: Vec<C64>,
    g: Vec<C64>,
    /// `||res||_2` against the 2-norm of the rows' Oettli-Prager bounds.
    normwise: f64,
    /// The largest row's Oettli-Prager ratio (with the `omega_2` guard).
    componentwise: f64,
}

/// Solver for the homological equations of one SSM computation.
pub(crate) struct Homological<'a> {
    n: usize,
    a: SparseColMatRef<'a, usize, f64>,
    b: SparseColMatRef<'a, usize, f64>,
    symbolic: SymbolicSparseColMat<usize>,
    lu_symbolic: Option<SymbolicLu<usize>>,
    /// The real form's analysis where the condensed pencil is symmetric and
    /// its factors are dear (decided with [`Homological::iterative`]).
    sym_symbolic: Option<Arc<SymbolicComplexSym>>,
    /// Whether that has been decided.
    sym_checked: bool,
    a_val: Vec<f64>,
    b_val: Vec<f64>,
    /// `max_j |A_ij|` and `max_j |B_ij|` per row (the guard of the
    /// componentwise backward error, [`Homological::residual`]).
    row_max: (Vec<f64>, Vec<f64>),
    lambda: Vec<C64>,
    bv: Vec<Vec<C64>>,
    ub: Vec<Vec<C64>>,
    numeric: HashMap<(u64, u64), Factor>,
    /// Factorizations [`Homological::solve_band`] solves through.
    anchors: Vec<band::AnchorLu>,
    /// Whether [`Homological::solve_band`] iterates (decided once, from the
    /// fill of the pattern: [`iterates`]).
    iterative: Option<bool>,
    /// The velocities eliminated, where the model is mechanical.
    condensed: Option<condense::Condensed>,
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
/// Componentwise backward error at which iterative refinement stops where
/// band solves run (a few roundings).
const REFINED: f64 = 4.0 * f64::EPSILON;
/// Normwise backward error at which iterative refinement stops elsewhere.
const RESIDUAL_TOL: f64 = 1e-10;
impl<'a> Homological<'a> {
    /// Prepares the union pattern of `A` and `B` and the border vectors `B v_i`
    /// and `u_i^* B` of the master coordinates (`lambda[i]`, `right[i]`,
    /// `left[i]` for reduced coordinate `i`, conjugates included).
    /// `velocities` are the states of a mechanical model's velocities
    /// (displacements `0 .. velocities.len()`), eliminated from every solve
    /// where the pencil has their structure ([`condense`]).
    pub fn new(
        a: SparseColMatRef<'a, usize, f64>,
        b: SparseColMatRef<'a, usize, f64>,
        velocities: Option<std::ops::Range<usize>>,
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
            sym_symbolic: None,
            sym_checked: false,
            a_val,
            b_val,
            row_max: (row_max(a), row_max(b)),
            lambda: lambda.to_vec(),
            bv,
            ub,
            numeric: HashMap::new(),
            anchors: Vec::new(),
            iterative: None,
            condensed: velocities.and_then(|v| condense::Condensed::detect(a, b, v)),
            stats: SolveStats::default(),
        }
    }

    /// Whether band solves iterate through a factorization at an anchor
    /// ([`iterates`]: the pattern factorizes dearly), decided once.
    pub(crate) fn iterative(&mut self) -> bool {
        *self
            .iterative
            .get_or_insert_with(|| iterates(self.symbolic.as_ref()))
    }

    /// Forgets cached numeric factorizations (called between orders, where
    /// values of `Lambda` no longer repeat).
    pub(crate) fn clear_numeric(&mut self) {
        self.numeric.clear();
    }

    /// The LU of `sigma B - A`, computed or cached.
    fn factor(&mut self, sigma: C64) -> Result<&Factor, HomologicalError> {
        let key = (sigma.re.to_bits(), sigma.im.to_bits());
        if !self.numeric.contains_key(&key) {
            let lu = self.fresh_lu(sigma)?;
            self.numeric.insert(key, lu);
        }
        Ok(&self.numeric[&key])
    }

    /// The value factorized for `lambda` with resonant set `set`: `lambda`
    /// itself, or shifted by [`SHIFT`] when it is within [`SHIFT_BELOW`] of
    /// a resonant master eigenvalue.
    fn factorized_at(&self, lambda: C64, set: &[usize]) -> C64 {
        let mut sigma = lambda;
        for &i in set {
            let li = self.lambda[i];
            if (lambda - li).norm() <= SHIFT_BELOW * li.norm() {
                sigma = lambda + C64::new(SHIFT, SHIFT) * li.norm();
            }
        }
        sigma
    }

    /// `(sigma B - A)^{-1} rhs` through the factor `f` at `sigma`.
    fn lu_solve(&self, f: &Factor, rhs: &[C64]) -> Vec<C64> {
        self.lu_solve_known(f, rhs, None)
    }

    /// [`Homological::lu_solve`] where, for a condensed pencil, `mass_part`
    /// is `M^{-1} rhs_V` when the caller knows it (a right-hand side `g - B
    /// c` with `g_V = 0` has `M^{-1} rhs_V = -c_x`, since `(B c)_V = M c_x`),
    /// so that the mass matrix is not solved with.
    fn lu_solve_known(&self, f: &Factor, rhs: &[C64], mass_part: Option<&[C64]>) -> Vec<C64> {
        let reduced;
        let h = match &self.condensed {
            Some(c) => {
                reduced = c.reduce(f.sigma, rhs);
                &reduced[..]
            }
            None => rhs,
        };
        let x: Vec<C64> = match &f.scale {
            None => kernel_solve(&f.lu, h.to_vec()),
            Some((row, col)) => {
                let x = kernel_solve(&f.lu, h.iter().zip(row).map(|(v, r)| v * r).collect());
                x.into_iter().zip(col).map(|(v, c)| v * c).collect()
            }
        };
        match &self.condensed {
            Some(c) => c.expand(f.sigma, &x, rhs, mass_part),
            None => x,
        }
    }

    /// The displacements of a condensed pencil (`x` of `z = (x, x', ..)`),
    /// `None` where the whole pencil is solved.
    pub(crate) fn displacements(&self) -> Option<usize> {
        self.condensed.as_ref().map(|c| c.displacements())
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
        let sigma = self.factorized_at(lambda, set);
        self.iterative();
        self.factor(sigma)?;
        let t = Instant::now();
        let key = (sigma.re.to_bits(), sigma.im.to_bits());
        let lu = &self.numeric[&key];
        let r = set.len();
        // Y = M^{-1} B V_I and the Schur complement S = U_I^* B Y
        let y: Vec<Vec<C64>> = set
            .iter()
            .map(|&i| self.lu_solve(lu, &self.bv[i]))
            .collect();
        let mut schur = vec![C64::new(0.0, 0.0); r * r];
        for (a, &i) in set.iter().enumerate() {
            for (c, yc) in y.iter().enumerate() {
                schur[a * r + c] = dot(&self.ub[i], yc);
            }
        }
        let block_solve = |h: &[C64], g: &[C64]| -> Option<(Vec<C64>, Vec<C64>)> {
            let w0 = self.lu_solve(lu, h);
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
        // where band solves run (dear factors: finite-element models, whose
        // rows differ in scale by orders of magnitude), refine until the
        // componentwise backward error reaches rounding or neither backward
        // error halves any more (Arioli, Demmel and Duff's stagnation test,
        // with the normwise error the one that converges at a shifted
        // factorization), keeping an update unless it worsens both; elsewhere
        // until the normwise error is below RESIDUAL_TOL
        let componentwise = self.iterative == Some(true);
        let mut res = self.residual(lambda, set, &w, &coeffs, rhs);
        for _ in 0..MAX_REFINE {
            let done = if componentwise {
                !res.componentwise.is_finite() || res.componentwise <= REFINED
            } else {
                !res.normwise.is_finite() || res.normwise <= RESIDUAL_TOL
            };
            if done {
                break;
            }
            let Some((dw, dr)) = block_solve(&res.h, &res.g) else {
                break;
            };
            let w1: Vec<C64> = w.iter().zip(&dw).map(|(x, d)| x + d).collect();
            let c1: Vec<C64> = coeffs.iter().zip(&dr).map(|(x, d)| x + d).collect();
            let res1 = self.residual(lambda, set, &w1, &c1, rhs);
            if !componentwise {
                (w, coeffs, res) = (w1, c1, res1);
                continue;
            }
            let progress = res1.componentwise <= 0.5 * res.componentwise
                || res1.normwise <= 0.5 * res.normwise;
            // an update is kept unless it worsens both (a NaN one worsens)
            let better = |a: f64, b: f64| a.partial_cmp(&b).is_some_and(|o| o.is_le());
            let worse = !better(res1.componentwise, res.componentwise)
                && !better(res1.normwise, res.normwise);
            if !worse {
                (w, coeffs, res) = (w1, c1, res1);
            }
            if !progress {
                break;
            }
        }
        let rel = res.normwise;
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

    /// `(Lambda B - A) w` and `(|Lambda| |B| + |A|) |w|`, in one pass over
    /// the union pattern of `A` and `B`.
    fn pencil_apply(&self, lambda: C64, w: &[C64]) -> (Vec<C64>, Vec<f64>) {
        let mut mw = vec![C64::new(0.0, 0.0); self.n];
        let mut abs = vec![0.0f64; self.n];
        let l_abs = lambda.norm();
        let p = self.symbolic.as_ref();
        let rows = p.row_idx();
        for (j, &wj) in w.iter().enumerate() {
            if wj.re == 0.0 && wj.im == 0.0 {
                continue;
            }
            let wj_abs = wj.norm();
            for k in p.col_range(j) {
                let (a, b) = (self.a_val[k], self.b_val[k]);
                let i = rows[k];
                mw[i] += (lambda * b - a) * wj;
                abs[i] += (l_abs * b.abs() + a.abs()) * wj_abs;
            }
        }
        (mw, abs)
    }

    /// Residual `(h - M w - B V r, -U^* B w)` of the bordered system with
    /// its normwise and componentwise backward errors.
    ///
    /// The componentwise one is the Oettli-Prager error `max_i |res_i| /
    /// (|h| + |M| |w| + |B V| |r|)_i` (border rows against `|U^* B| |w|`),
    /// where a row whose bound is below `1000 N eps` of `max_j |M_ij|
    /// ||w||_inf + |h_i|` (a component that vanishes, e.g. by symmetry, whose
    /// bound is rounding) is measured against `|M| |w| + max_j |M_ij|
    /// ||w||_inf` instead (Arioli, Demmel and Duff's `omega_2`). It is what a
    /// backward-stable solve of a badly scaled system does not guarantee and
    /// iterative refinement restores: a fine plate's rows couple
    /// displacements, slopes and membrane motion whose stiffnesses differ by
    /// orders of magnitude, and an unrefined LU solve leaves `1e-7` to `1e-4`
    /// there (forward errors to match) at a normwise `1e-15`.
    ///
    /// # References
    /// W. Oettli, W. Prager, Numer. Math. 6 (1964) 405-409; M. Arioli, J.
    /// Demmel, I. Duff, SIAM J. Matrix Anal. Appl. 10 (1989) 165-190
    /// (stopping iterative refinement of sparse solves); R. D. Skeel, Math.
    /// Comp. 35 (1980) 817-832 (one step of refinement in working precision
    /// suffices for componentwise stability).
    fn residual(
        &self,
        lambda: C64,
        set: &[usize],
        w: &[C64],
        coeffs: &[C64],
        rhs: &[C64],
    ) -> Residual {
        let (mw, mw_abs) = self.pencil_apply(lambda, w);
        let mut h: Vec<C64> = rhs.iter().zip(&mw).map(|(r, m)| r - m).collect();
        for (t, &c) in set.iter().enumerate() {
            h.iter_mut()
                .zip(&self.bv[c])
                .for_each(|(x, v)| *x -= v * coeffs[t]);
        }
        let g: Vec<C64> = set.iter().map(|&c| -dot(&self.ub[c], w)).collect();
        let (den, scale) = self.bounds(lambda, set, w, &mw_abs, coeffs, rhs);
        let mut componentwise = 0.0f64;
        let mut norm2 = 0.0;
        for (x, d) in h.iter().chain(&g).zip(&den) {
            norm2 += x.norm_sqr();
            if x.norm() > 0.0 {
                componentwise = componentwise.max(if *d > 0.0 {
                    x.norm() / d
                } else {
                    f64::INFINITY
                });
            }
        }
        Residual {
            h,
            g,
            normwise: norm2.sqrt() / scale.max(f64::MIN_POSITIVE),
            componentwise,
        }
    }

    /// The rows' Oettli-Prager bounds of [`Homological::residual`] (leading
    /// rows, then border rows, with the `omega_2` guard) and the 2-norm of
    /// `(|h| + |M| |w| + |B V| |r|, ||U^* B|| ||w||)`, the normwise scale.
    fn bounds(
        &self,
        lambda: C64,
        set: &[usize],
        w: &[C64],
        mw_abs: &[f64],
        coeffs: &[C64],
        rhs: &[C64],
    ) -> (Vec<f64>, f64) {
        let w_abs: Vec<f64> = w.iter().map(|c| c.norm()).collect();
        let w_inf = w_abs.iter().fold(0.0f64, |m, &x| m.max(x));
        let w_norm = w_abs.iter().map(|x| x * x).sum::<f64>().sqrt();
        let guard = 1000.0 * self.n as f64 * f64::EPSILON;
        let guarded = |bound: f64, row_inf: f64, rhs_abs: f64| {
            let cap = row_inf * w_inf;
            if bound <= guard * (cap + rhs_abs) {
                bound + cap
            } else {
                bound
            }
        };
        let mut scale2 = 0.0;
        let mut den: Vec<f64> = (0..self.n)
            .map(|i| {
                let mut bound = mw_abs[i];
                for (t, &c) in set.iter().enumerate() {
                    bound += (self.bv[c][i] * coeffs[t]).norm();
                }
                let rhs_abs = rhs[i].norm();
                scale2 += rhs_abs * rhs_abs + bound * bound;
                let row_inf = self.row_max.0[i].max(lambda.norm() * self.row_max.1[i]);
                guarded(bound + rhs_abs, row_inf, rhs_abs)
            })
            .collect();
        // each border row `u^* B w = 0` is measured against `|u^* B| |w|`:
        // `u` carries the units of `1/v`, which differ from those of `h` by
        // powers of the frequency
        den.extend(set.iter().map(|&c| {
            let ub = &self.ub[c];
            let ub_norm = ub.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt();
            scale2 += (ub_norm * w_norm).powi(2);
            let bound: f64 = ub.iter().zip(&w_abs).map(|(u, x)| u.norm() * x).sum();
            let row_inf = ub.iter().fold(0.0f64, |m, u| m.max(u.norm()));
            guarded(bound, row_inf, 0.0)
        }));
        (den, scale2.sqrt())
    }
}

/// `max_j |m_ij|` per row.
fn row_max(m: SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
    let mut out = vec![0.0f64; m.nrows()];
    for j in 0..m.ncols() {
        for (i, v) in m.row_idx_of_col(j).zip(m.val_of_col(j)) {
            out[i] = out[i].max(v.abs());
        }
    }
    out
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
