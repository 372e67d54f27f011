//! The bordered system along a segment of values, solved as a Taylor series
//! through one factorization.
//!
//! Along `Lambda(t) = Lambda_0 + delta + slope t`, `t` in `[-1, 1]`, the
//! bordered matrix of [`Homological::solve`] is `M(t) = M_0 + (delta + slope
//! t) E` with `M_0 = M(Lambda_0)` and `E = diag(B, 0)`. For a right-hand side
//! given by its Taylor coefficients, `b(t) = sum_m b_m t^m`, the solution
//! `y(t) = sum_m y_m t^m` satisfies, coefficient by coefficient,
//!
//! `(M_0 + delta E) y_m = b_m - slope E y_(m-1)`,
//!
//! a recursion of solves with one matrix: each is the block solve of the
//! factorization at `Lambda_0` refined against `M_0 + delta E` (`delta`, the
//! damping part of a shift, is small) until its componentwise backward error
//! reaches rounding. The series converges for `|t|` below the distance to the
//! nearest `t` where `M(t)` is singular, a non-master eigenvalue of the
//! pencil (the bordered master modes keep `M(t)` regular), geometrically, so
//! a band of frequencies a pencil eigenvalue is not near costs one
//! factorization and a few dozen solves instead of a factorization per
//! frequency. Truncated after `y_D` (with `deg b <= D`), the polynomial solves
//! the system with the residual `slope t^(D+1) E y_D` exactly; the recursion
//! stops when two successive terms are below [`TAIL`] of the largest, and the
//! caller checks the componentwise backward error of the values it uses
//! against the floor the coefficients' own refined solves reached.
//! The coefficients `y_m` span the Krylov space of `M_0^-1 E`: this is moment
//! matching, as in Krylov model reduction of frequency responses.
//!
//! # References
//! Z. Bai, *Krylov subspace techniques for reduced-order modeling of
//! large-scale dynamical systems*, Appl. Numer. Math. 43 (2002) 9-44, Sect. 3
//! (moments of a frequency response through one factorization); R. D. Skeel,
//! Math. Comp. 35 (1980) 817-832 (iterative refinement for componentwise
//! stability).

use std::time::Instant;

use super::{dot, solve_small, Homological, HomologicalError, Solution};
use crate::spectrum::modes::spmv;
use crate::C64;

/// Size of a term, relative to the largest, below which (twice in a row,
/// past the right-hand side's degree) the series stops. The truncated
/// polynomial's residual is `slope t^(D+1) E y_D` (module docs), so a last
/// term this small leaves a backward error about a hundred times below what
/// the values must meet ([`ACCEPT`]), which the callers check at every
/// value they use; smaller would spend solves on digits no check asks for
/// (at 1e-16 the 90 x 90 plate's forced response took 110 terms, at 1e-14
/// 98, its curve the same to the printed digit).
const TAIL: f64 = 1e-14;
/// Terms a series holds at most; a segment that needs more is too close to
/// an eigenvalue of the pencil for one expansion.
pub const MAX_TERMS: usize = 48;
/// Componentwise backward error at which a coefficient's refinement stops:
/// some 50 roundings, a hundred times below what the series' values must
/// meet ([`ACCEPT`]), so that on an equilibrated factorization most
/// coefficients take one solve.
const TERM_REFINED: f64 = 1e-14;
/// Refinement sweeps of one coefficient's solve at most.
const MAX_SWEEPS: usize = 6;

/// Componentwise backward error a value evaluated from a series may have
/// where the model's solves reach rounding (some 5000 roundings: a series
/// sums terms of decreasing size, each refined to rounding).
const ACCEPT: f64 = 1e-12;

/// The componentwise backward error a value evaluated from a series must
/// meet when the refined solves of its coefficients stopped at `floor`:
/// [`ACCEPT`], or ten times that floor on a model whose refined solves do
/// not reach rounding (a fine mesh's badly scaled rows; a direct solve at
/// that value stops at the same floor).
pub(crate) fn accept(floor: f64) -> f64 {
    ACCEPT.max(10.0 * floor)
}

/// `sum_m c_m t^m` for vectors `c_m` (Horner); empty for no terms.
pub(crate) fn horner(terms: &[Vec<C64>], t: f64) -> Vec<C64> {
    let Some(last) = terms.last() else {
        return Vec::new();
    };
    let mut out = last.clone();
    for c in terms.iter().rev().skip(1) {
        out.iter_mut().zip(c).for_each(|(o, ci)| *o = *o * t + ci);
    }
    out
}

/// What [`Homological::series_at`] found: the terms and the floor of their
/// refined solves where the series converged, and the work it spent.
pub(crate) struct SeriesRun {
    solved: Option<(Vec<Solution>, f64)>,
    terms: usize,
    seconds: f64,
}

impl SeriesRun {
    /// The terms and floor where the series converged, taken out (its work
    /// stays, for [`Homological::series_counted`]).
    pub(crate) fn take(&mut self) -> Option<(Vec<Solution>, f64)> {
        self.solved.take()
    }
}

fn size(s: &Solution) -> f64 {
    s.0.iter()
        .chain(&s.1)
        .map(|c| c.norm_sqr())
        .sum::<f64>()
        .sqrt()
}

impl Homological<'_> {
    /// The block solve of the bordered system at the anchor of `slot` (its
    /// LU, border solves and Schur complement): `(w, r)` for the right-hand
    /// side `(h, g)`; `None` at a singular Schur complement.
    pub(super) fn anchor_block_solve(
        &self,
        slot: usize,
        set: &[usize],
        h: &[C64],
        g: &[C64],
        mass_part: Option<&[C64]>,
    ) -> Option<Solution> {
        let anc = &self.anchors[slot];
        let border = anc.border.as_ref().expect("set by anchor_slot");
        let w0 = self.lu_solve_known(&anc.lu, h, mass_part);
        let mut s_rhs: Vec<C64> = set
            .iter()
            .zip(g)
            .map(|(&i, &gi)| dot(&self.ub[i], &w0) - gi)
            .collect();
        solve_small(&border.schur, &mut s_rhs, set.len())?;
        let mut w = w0;
        for (yc, rc) in border.y.iter().zip(&s_rhs) {
            w.iter_mut().zip(yc).for_each(|(x, yv)| *x -= yv * rc);
        }
        Some((w, s_rhs))
    }

    /// The Taylor coefficients `y_0, .., y_D` of the module docs' solution
    /// along `Lambda(t) = anchor + delta + slope t` for the right-hand side
    /// coefficients `rhs` (`b_0, b_1, ..`; `D + 1 >= rhs.len()`), through
    /// the factorization at `anchor` (kept until
    /// [`Homological::release_anchor`]), with the largest componentwise
    /// backward error at which a coefficient's refinement stopped (the
    /// floor this model's solves reach, rounding where it is well scaled).
    /// `None` when the anchor would be
    /// factorized at a shifted value (it hits a master eigenvalue) or the
    /// series does not converge within [`MAX_TERMS`] terms.
    ///
    /// # Errors
    /// The anchor's factorization failed.
    pub(crate) fn solve_series(
        &mut self,
        anchor: C64,
        delta: C64,
        slope: C64,
        set: &[usize],
        rhs: &[Vec<C64>],
    ) -> Result<Option<(Vec<Solution>, f64)>, HomologicalError> {
        let Some(slot) = self.series_anchor(anchor, set)? else {
            return Ok(None);
        };
        let run = self.series_at(slot, anchor + delta, slope, set, rhs, &[]);
        Ok(self.series_counted(run))
    }

    /// The slot of the factorization at `anchor` with the border of `set`
    /// that [`Homological::series_at`] solves through (factorized if new);
    /// `None` when the anchor would be factorized at a shifted value (it
    /// hits a master eigenvalue).
    ///
    /// # Errors
    /// The anchor's factorization failed.
    pub(crate) fn series_anchor(
        &mut self,
        anchor: C64,
        set: &[usize],
    ) -> Result<Option<usize>, HomologicalError> {
        let all: Vec<usize> = (0..self.lambda.len()).collect();
        if self.factorized_at(anchor, &all) != anchor {
            return Ok(None);
        }
        self.anchor_slot(anchor, set).map(Some)
    }

    /// The series of [`Homological::solve_series`] along `Lambda(t) =
    /// lambda + slope t` through the factorization of `slot` (whose border
    /// is of `set`), uncounted: it reads the solver alone, so that series
    /// through different slots run side by side; its work goes to
    /// [`Homological::series_counted`].
    pub(crate) fn series_at(
        &self,
        slot: usize,
        lambda: C64,
        slope: C64,
        set: &[usize],
        rhs: &[Vec<C64>],
        mass_parts: &[Option<Vec<C64>>],
    ) -> SeriesRun {
        let disp = self.displacements();
        let t = Instant::now();
        let zero = C64::new(0.0, 0.0);
        let zero_g = vec![zero; set.len()];
        let mut terms: Vec<Solution> = Vec::new();
        let mut sizes: Vec<f64> = Vec::new();
        let mut largest = 0.0f64;
        let mut quiet = 0;
        let mut converged = false;
        let mut floor = 0.0f64;
        for m in 0..MAX_TERMS {
            let mut c = rhs.get(m).cloned().unwrap_or_else(|| vec![zero; self.n]);
            // M^{-1} c_V where it is known: the right-hand side's own (zero
            // past it), less slope w_x for the term's - slope B w
            let mut known: Option<Vec<C64>> = match disp {
                Some(n) if m >= rhs.len() => Some(vec![zero; n]),
                Some(_) => mass_parts.get(m).cloned().flatten(),
                None => None,
            };
            if let Some((w, _)) = terms.last() {
                let bw = spmv(self.b, w);
                c.iter_mut().zip(&bw).for_each(|(x, b)| *x -= slope * b);
                if let Some(u) = known.as_mut() {
                    u.iter_mut().zip(w).for_each(|(x, wx)| *x -= slope * wx);
                }
            }
            let refined = self.refined_at_anchor(slot, lambda, set, &c, &zero_g, known.as_deref());
            let Some((term, error)) = refined else {
                break;
            };
            floor = floor.max(error);
            let s = size(&term);
            if !s.is_finite() {
                break;
            }
            largest = largest.max(s);
            terms.push(term);
            sizes.push(s);
            if m + 1 < rhs.len() {
                continue;
            }
            if s <= TAIL * largest {
                quiet += 1;
                if quiet == 2 {
                    converged = true;
                    break;
                }
            } else {
                quiet = 0;
            }
            // past the right-hand side, a series outside its disc of
            // convergence grows: stop at once
            let past = m + 1 - rhs.len();
            if past >= 4 && s > sizes[m - 4] {
                break;
            }
        }
        let count = terms.len();
        SeriesRun {
            solved: converged.then_some((terms, floor)),
            terms: count,
            seconds: t.elapsed().as_secs_f64(),
        }
    }

    /// A series' work counted; its terms and floor if it converged.
    pub(crate) fn series_counted(&mut self, run: SeriesRun) -> Option<(Vec<Solution>, f64)> {
        self.stats.iterations += run.terms;
        self.stats.solve_s += run.seconds;
        run.solved
    }

    /// One coefficient's solve at `lambda` through the anchor's block solve,
    /// refined until its componentwise backward error is below
    /// [`TERM_REFINED`] or stops halving; with that error.
    fn refined_at_anchor(
        &self,
        slot: usize,
        lambda: C64,
        set: &[usize],
        h: &[C64],
        g: &[C64],
        mass_part: Option<&[C64]>,
    ) -> Option<(Solution, f64)> {
        let (mut w, mut r) = self.anchor_block_solve(slot, set, h, g, mass_part)?;
        let mut res = self.residual(lambda, set, &w, &r, h);
        for _ in 0..MAX_SWEEPS {
            if !res.componentwise.is_finite() || res.componentwise <= TERM_REFINED {
                break;
            }
            let (dw, dr) = self.anchor_block_solve(slot, set, &res.h, &res.g, None)?;
            let w1: Vec<C64> = w.iter().zip(&dw).map(|(x, d)| x + d).collect();
            let r1: Vec<C64> = r.iter().zip(&dr).map(|(x, d)| x + d).collect();
            let res1 = self.residual(lambda, set, &w1, &r1, h);
            if !(res1.componentwise < res.componentwise || res1.normwise < res.normwise) {
                break;
            }
            let halved = res1.componentwise <= 0.5 * res.componentwise;
            (w, r, res) = (w1, r1, res1);
            if !halved {
                break;
            }
        }
        Some(((w, r), res.componentwise))
    }

    /// The componentwise backward error of `(w, r)` as a solution of the
    /// bordered system at `lambda` with right-hand side `rhs`.
    pub(crate) fn backward_error(
        &self,
        lambda: C64,
        set: &[usize],
        w: &[C64],
        r: &[C64],
        rhs: &[C64],
    ) -> f64 {
        self.residual(lambda, set, w, r, rhs).componentwise
    }
}
