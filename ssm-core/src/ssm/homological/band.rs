//! The bordered system at a band of values `Lambda_j`, solved through one
//! factorization at a nearby anchor `Lambda_0`.
//!
//! The bordered matrix of [`Homological::solve`] depends on `Lambda` through
//! its leading block only: `M(Lambda_j) = M_0 + (Lambda_j - Lambda_0) E` with
//! `M_0 = M(Lambda_0)` and `E = diag(B, 0)`. With `P^-1` the block solve at
//! the anchor (its LU, the border solves `Y` and the Schur complement), every
//! value's solution is sought in one growing space `Z`: `x_j = Z y_j`
//! minimizes `||b_j - M(Lambda_j) Z y_j||_2`, a small least-squares problem per
//! value once `M_0 Z` and `E Z` are known in an orthonormal basis `Q` that
//! also spans the right-hand sides (each value's QR factorization grown a
//! column per direction). The space grows by `P^-1 r_j` of the value whose
//! residual is largest (a flexible GMRES step for that value, the other
//! values' directions coming for free). When a value's least-squares
//! residual is below [`CHECK`] of its right-hand side (or has stalled at
//! its rounding floor, [`STALL`]), its correction is added and its true
//! componentwise backward error computed; above
//! [`ACCEPT`] the true residual becomes its next right-hand side in the
//! same space (iterative refinement with an inexact inner solve, at most
//! [`MAX_SWEEPS`] corrections), so that the band's answers meet the
//! componentwise accuracy direct solves are refined to. The rows of a fine
//! plate differ in scale by orders of magnitude, and a solution accepted on
//! its residual's 2-norm leaves the soft rows' equations, and with them the
//! coefficient vectors, inaccurate. The preconditioned operators `I +
//! (Lambda_j - Lambda_0) P^-1 E` share their Krylov spaces (shift
//! invariance), so the space grows with the number of pencil eigenvalues
//! near the band, the rank of the right-hand sides and a few refinement
//! directions per value: one factorization and factorized solves serve a
//! band of frequencies that would otherwise take a factorization each. Values still open when the space stops growing are
//! solved directly.
//!
//! # References
//! Y. Saad, *Iterative Methods for Sparse Linear Systems*, 2nd ed., SIAM
//! (2003), Sect. 9.4.1 (flexible GMRES); A. Frommer, U. Glässner, *Restarted
//! GMRES for shifted linear systems*, SIAM J. Sci. Comput. 19 (1998) 15-26
//! (shift-invariant Krylov spaces); M. L. Parks, E. de Sturler, G. Mackey,
//! D. D. Johnson, S. Maiti, *Recycling Krylov subspaces for sequences of
//! linear systems*, SIAM J. Sci. Comput. 28 (2006) 1651-1674 (one space for
//! a sequence of systems).

use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

use super::{dot, Homological, HomologicalError, Solution};
use crate::spectrum::modes::spmv;
use crate::C64;

/// Componentwise backward error a value is accepted at, so that answers
/// agree with refined direct ones to the conditioning of the system.
const ACCEPT: f64 = 1e-13;
/// Least-squares residual, relative to the current right-hand side, at
/// which a value's correction is added and its true backward error checked.
const CHECK: f64 = 1e-11;
/// Corrections (refinement sweeps) a value gets before it is solved
/// directly.
const MAX_SWEEPS: usize = 4;
/// Directions after which a value whose least-squares residual has not
/// halved counts as stalled: the residual's floor, about the unit roundoff
/// times the condition of `M(Lambda_j)` relative to the current right-hand
/// side, lies above [`CHECK`] (the 8 x 8 plate's band at -285i stalled at
/// 9e-10 from its 72nd direction to the 200th).
const STALL: usize = 8;
/// Least-squares residual, relative to the current right-hand side, below
/// which a stalled value's correction is added and its true backward error
/// checked: the correction still removes all but that fraction of the
/// residual, and the next sweep starts from the true one.
const STALL_CHECK: f64 = 1e-6;
/// Directions `Z` a band solve builds before the values still open are
/// solved directly (the basis `Q` holds at most twice as many plus the
/// right-hand sides and their refinements: [`band_vectors`]).
const MAX_SPACE: usize = 200;
/// Fraction of a vector that must remain after orthogonalization against a
/// basis for it to extend the basis.
const DROP: f64 = 1e-15;

/// A factorization kept for solves at values near `at`.
pub(super) struct AnchorLu {
    /// The anchor as requested.
    at: C64,
    pub(super) lu: super::Factor,
    /// Border solves and Schur complement of the last resonant set.
    pub(super) border: Option<Border>,
}

/// `Y = M^-1 B V_I` and `S = U_I^* B Y` (row-major) at an anchor.
pub(super) struct Border {
    set: Vec<usize>,
    pub(super) y: Vec<Vec<C64>>,
    pub(super) schur: Vec<C64>,
}

/// `sum_i conj(a_i) b_i`.
fn cdot(a: &[C64], b: &[C64]) -> C64 {
    a.iter().zip(b).map(|(x, y)| x.conj() * y).sum()
}

fn norm(a: &[C64]) -> f64 {
    a.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt()
}

/// An orthonormal basis of long vectors, stored as the leading columns of a
/// matrix (products with it are matrix-vector products).
struct Basis {
    m: Mat<C64>,
    len: usize,
}

impl Basis {
    fn new(rows: usize) -> Self {
        Self {
            m: Mat::zeros(rows, 16),
            len: 0,
        }
    }

    fn len(&self) -> usize {
        self.len
    }

    /// `Q^* v`.
    fn project(&self, v: &[C64]) -> Vec<C64> {
        let q = self.m.get(.., ..self.len);
        let v = MatRef::from_column_major_slice(v, v.len(), 1);
        let mut h = Mat::<C64>::zeros(self.len, 1);
        matmul(
            h.as_mut(),
            Accum::Replace,
            q.adjoint(),
            v,
            C64::new(1.0, 0.0),
            Par::Seq,
        );
        (0..self.len).map(|i| h[(i, 0)]).collect()
    }

    /// `sum_k c_k q_k` (`c` at most as long as the basis).
    fn combine(&self, c: &[C64]) -> Vec<C64> {
        let k = c.len().min(self.len);
        let q = self.m.get(.., ..k);
        let c = MatRef::from_column_major_slice(&c[..k], k, 1);
        let mut out = Mat::<C64>::zeros(self.m.nrows(), 1);
        matmul(
            out.as_mut(),
            Accum::Replace,
            q,
            c,
            C64::new(1.0, 0.0),
            Par::Seq,
        );
        (0..self.m.nrows()).map(|i| out[(i, 0)]).collect()
    }

    /// Column `k`.
    fn col(&self, k: usize) -> Vec<C64> {
        (0..self.m.nrows()).map(|i| self.m[(i, k)]).collect()
    }

    /// Orthogonalizes `v` against the basis (classical Gram-Schmidt,
    /// twice) and extends the basis by what remains unless it is below
    /// [`DROP`] of `v`; returns `v`'s coefficients in the (extended) basis.
    fn extend(&mut self, v: Vec<C64>) -> Vec<C64> {
        let rows = self.m.nrows();
        let before = norm(&v);
        let mut w = Mat::<C64>::from_fn(rows, 1, |i, _| v[i]);
        let mut h = vec![C64::new(0.0, 0.0); self.len];
        let one = C64::new(1.0, 0.0);
        for _ in 0..2 {
            let q = self.m.get(.., ..self.len);
            let mut c = Mat::<C64>::zeros(self.len, 1);
            matmul(
                c.as_mut(),
                Accum::Replace,
                q.adjoint(),
                w.as_ref(),
                one,
                Par::Seq,
            );
            matmul(w.as_mut(), Accum::Add, q, c.as_ref(), -one, Par::Seq);
            h.iter_mut().enumerate().for_each(|(i, x)| *x += c[(i, 0)]);
        }
        let rest = w.col(0).norm_l2();
        if rest > DROP * before && rest > 0.0 {
            if self.len == self.m.ncols() {
                let mut grown = Mat::<C64>::zeros(rows, 2 * self.len);
                grown
                    .get_mut(.., ..self.len)
                    .copy_from(self.m.get(.., ..self.len));
                self.m = grown;
            }
            let scale = one / rest;
            self.m
                .col_mut(self.len)
                .copy_from(w.col(0) * faer::Scale(scale));
            self.len += 1;
            h.push(C64::new(rest, 0.0));
        }
        h
    }
}

/// The QR factorization of one value's least-squares matrix `G = [g_1 ..
/// g_s]`, grown a column at a time (modified Gram-Schmidt, twice); columns
/// may grow in length (rows added to the basis `Q` later are zero in the
/// earlier columns).
#[derive(Default)]
struct GrowingQr {
    /// Orthonormal columns (shorter ones padded with zeros).
    q: Vec<Vec<C64>>,
    /// `R` by kept columns: `r[a][b]` for `b <= a`, the coefficient of
    /// orthonormal column `b` in kept column `a`.
    r: Vec<Vec<C64>>,
    /// Index in `G` of each kept column (the others depend on them).
    kept: Vec<usize>,
    /// `Q^* c` of the current right-hand side.
    qc: Vec<C64>,
}

impl GrowingQr {
    /// Appends column `index` of `G` (the projection on `c` updated).
    fn push(&mut self, index: usize, mut g: Vec<C64>, c: &[C64]) {
        let before = norm(&g);
        let mut h = vec![C64::new(0.0, 0.0); self.q.len() + 1];
        for _ in 0..2 {
            for (hi, qi) in h.iter_mut().zip(&self.q) {
                let d = cdot(qi, &g[..qi.len()]);
                *hi += d;
                g.iter_mut().zip(qi).for_each(|(x, q)| *x -= d * q);
            }
        }
        let rest = norm(&g);
        // a column dependent on the earlier ones adds nothing
        if rest > 1e-13 * before && rest > 0.0 {
            g.iter_mut().for_each(|x| *x /= rest);
            h[self.q.len()] = C64::new(rest, 0.0);
            self.qc
                .push(cdot(&g[..g.len().min(c.len())], &c[..g.len().min(c.len())]));
            self.q.push(g);
            self.r.push(h);
            self.kept.push(index);
        }
    }

    /// Sets the right-hand side.
    fn project(&mut self, c: &[C64]) {
        self.qc = self
            .q
            .iter()
            .map(|qi| {
                let m = qi.len().min(c.len());
                cdot(&qi[..m], &c[..m])
            })
            .collect();
    }

    /// `c - G y` at the least-squares `y`.
    fn residual(&self, c: &[C64]) -> Vec<C64> {
        let mut res = c.to_vec();
        for (qi, &a) in self.q.iter().zip(&self.qc) {
            if res.len() < qi.len() {
                res.resize(qi.len(), C64::new(0.0, 0.0));
            }
            res.iter_mut().zip(qi).for_each(|(x, q)| *x -= a * q);
        }
        res
    }

    /// The least-squares `y` (`s` entries, zero at dependent columns).
    fn solution(&self, s: usize) -> Vec<C64> {
        let k = self.q.len();
        let mut t = vec![C64::new(0.0, 0.0); k];
        for a in (0..k).rev() {
            let mut v = self.qc[a];
            for (rb, tb) in self.r[a + 1..].iter().zip(&t[a + 1..]) {
                v -= rb[a] * tb;
            }
            t[a] = v / self.r[a][a];
        }
        let mut y = vec![C64::new(0.0, 0.0); s];
        for (&idx, tv) in self.kept.iter().zip(t) {
            y[idx] = tv;
        }
        y
    }
}

/// Where one value of a band stands.
struct Value {
    /// `Lambda_j - Lambda_0`.
    delta: C64,
    /// The current right-hand side (the original, then the true residual of
    /// the last correction) in the basis `Q` (its part outside `Q` is below
    /// [`DROP`]), and its norm.
    c: Vec<C64>,
    c_norm: f64,
    /// The solution so far (`w` then `r`).
    x: Vec<C64>,
    /// Corrections made (refinement sweeps).
    sweeps: usize,
    /// QR of `M(Lambda_j) Z` in the basis `Q`.
    qr: GrowingQr,
    /// Space size at the last true check.
    checked_at: Option<usize>,
    /// The smallest least-squares residual of this right-hand side, and the
    /// directions since it last halved ([`STALL`]).
    best: f64,
    stalled: usize,
    solved: bool,
}

/// Vectors of the system's size a band solve of `values` values holds at
/// most (`Z`, `Q`, the values' solutions), for the memory estimate.
pub const fn band_vectors(values: usize) -> usize {
    3 * MAX_SPACE + values * (MAX_SWEEPS + 2)
}

impl Homological<'_> {
    /// Solves the bordered system of [`Homological::solve`] at every value
    /// `lambdas[j]` with right-hand side `rhss[j]` through the factorization
    /// at the nearby `anchor` (kept until [`Homological::release_anchor`]),
    /// one search space for all values (module docs); directly, value by
    /// value, when the pattern factorizes cheaply ([`iterates`]) or the
    /// anchor cannot be factorized.
    pub fn solve_band(
        &mut self,
        lambdas: &[C64],
        anchor: C64,
        set: &[usize],
        rhss: &[&[C64]],
    ) -> Result<Vec<Solution>, HomologicalError> {
        let direct = !self.iterative();
        let slot = if direct || lambdas.is_empty() {
            None
        } else {
            self.anchor_slot(anchor, set).ok()
        };
        let mut out: Vec<Option<Solution>> = match slot {
            Some(slot) => {
                let t = Instant::now();
                let (values, steps) = self.band_space(slot, lambdas, anchor, set, rhss);
                self.stats.iterations += steps;
                self.stats.solves += values.iter().filter(|v| v.is_some()).count();
                self.stats.solve_s += t.elapsed().as_secs_f64();
                values
            }
            None => vec![None; lambdas.len()],
        };
        for (j, o) in out.iter_mut().enumerate() {
            if o.is_none() {
                *o = Some(self.solve(lambdas[j], set, rhss[j])?);
            }
        }
        Ok(out.into_iter().flatten().collect())
    }

    /// Forgets the factorization at `anchor` (its values will not recur).
    pub fn release_anchor(&mut self, anchor: C64) {
        self.anchors.retain(|a| a.at != anchor);
    }

    /// The factorizations at those of `anchors` not yet held, made side by
    /// side ([`Homological::fresh_lus`]) and kept for
    /// [`Homological::series_anchor`]: the anchors a non-autonomous order's
    /// series need, known before any of them runs. Anchors a master
    /// eigenvalue would shift are left out (their series are not run).
    ///
    /// # Errors
    /// A factorization failed.
    pub(crate) fn prefactor_anchors(&mut self, anchors: &[C64]) -> Result<(), HomologicalError> {
        let all: Vec<usize> = (0..self.lambda.len()).collect();
        let mut missing: Vec<C64> = Vec::new();
        for &a in anchors {
            let held = self.anchors.iter().any(|x| x.at == a) || missing.contains(&a);
            if !held && self.factorized_at(a, &all) == a {
                missing.push(a);
            }
        }
        if missing.is_empty() {
            return Ok(());
        }
        let factors = self.fresh_lus(&missing)?;
        for (at, lu) in missing.into_iter().zip(factors) {
            self.anchors.push(AnchorLu {
                at,
                lu,
                border: None,
            });
        }
        Ok(())
    }

    /// The cached factorization at `anchor` with the border of `set`,
    /// computed when missing: at `anchor`, or shifted off a master
    /// eigenvalue it hits (as in [`Homological::solve`]).
    pub(super) fn anchor_slot(
        &mut self,
        anchor: C64,
        set: &[usize],
    ) -> Result<usize, HomologicalError> {
        let slot = match self.anchors.iter().position(|a| a.at == anchor) {
            Some(slot) => slot,
            None => {
                let all: Vec<usize> = (0..self.lambda.len()).collect();
                let lu = self.fresh_lu(self.factorized_at(anchor, &all))?;
                self.anchors.push(AnchorLu {
                    at: anchor,
                    lu,
                    border: None,
                });
                self.anchors.len() - 1
            }
        };
        if self.anchors[slot]
            .border
            .as_ref()
            .is_none_or(|b| b.set != set)
        {
            let lu = &self.anchors[slot].lu;
            let y: Vec<Vec<C64>> = set
                .iter()
                .map(|&i| self.lu_solve(lu, &self.bv[i]))
                .collect();
            let r = set.len();
            let mut schur = vec![C64::new(0.0, 0.0); r * r];
            for (a, &i) in set.iter().enumerate() {
                for (c, yc) in y.iter().enumerate() {
                    schur[a * r + c] = dot(&self.ub[i], yc);
                }
            }
            self.stats.solves += r;
            self.anchors[slot].border = Some(Border {
                set: set.to_vec(),
                y,
                schur,
            });
        }
        Ok(slot)
    }

    /// The shared-space iteration of the module docs; returns each value's
    /// solution if it was accepted, and the factorized solves spent.
    fn band_space(
        &self,
        slot: usize,
        lambdas: &[C64],
        anchor: C64,
        set: &[usize],
        rhss: &[&[C64]],
    ) -> (Vec<Option<Solution>>, usize) {
        let zero = C64::new(0.0, 0.0);
        let (n, r) = (self.n, set.len());
        // P^-1: the bordered block solve at the anchor
        let precond = |v: &[C64]| -> Option<Vec<C64>> {
            let (mut w, r) = self.anchor_block_solve(slot, set, &v[..n], &v[n..], None)?;
            w.extend(r);
            Some(w)
        };
        let padded = |rhs: &[C64]| -> Vec<C64> {
            let mut b = rhs.to_vec();
            b.resize(n + r, zero);
            b
        };
        // Q spans the right-hand sides first
        let mut q = Basis::new(n + r);
        for rhs in rhss {
            q.extend(padded(rhs));
        }
        let mut values: Vec<Value> = lambdas
            .iter()
            .zip(rhss)
            .map(|(&l, rhs)| {
                let b = padded(rhs);
                Value {
                    delta: l - anchor,
                    c: q.project(&b),
                    c_norm: norm(&b),
                    x: vec![zero; n + r],
                    sweeps: 0,
                    qr: GrowingQr::default(),
                    checked_at: None,
                    best: f64::INFINITY,
                    stalled: 0,
                    solved: norm(&b) == 0.0,
                }
            })
            .collect();
        // Z orthonormal; M(Lambda_j) Z = (M_0 + delta_j E) Z in the basis Q,
        // factorized per value as the space grows
        let mut z = Basis::new(n + r);
        let mut steps = 0;
        loop {
            // every open value's least-squares correction; the worst one's
            // residual is the next direction
            let mut worst: Option<(f64, Vec<C64>)> = None;
            for (j, v) in values.iter_mut().enumerate() {
                if v.solved {
                    continue;
                }
                let res = v.qr.residual(&v.c);
                let rel = norm(&res) / v.c_norm;
                if rel < 0.5 * v.best {
                    (v.best, v.stalled) = (rel, 0);
                } else {
                    v.stalled += 1;
                }
                let stalled = v.stalled >= STALL && rel <= STALL_CHECK;
                if (rel <= CHECK || stalled)
                    && v.checked_at != Some(z.len())
                    && v.sweeps < MAX_SWEEPS
                {
                    // the correction is as good as the space allows: add it,
                    // and check the solution's true backward error
                    let y = v.qr.solution(z.len());
                    let dx = z.combine(&y);
                    v.x.iter_mut().zip(&dx).for_each(|(a, b)| *a += b);
                    v.sweeps += 1;
                    v.checked_at = Some(z.len());
                    let (w, coeffs) = v.x.split_at(n);
                    let res = self.residual(lambdas[j], set, w, coeffs, rhss[j]);
                    if res.componentwise <= ACCEPT {
                        v.solved = true;
                        continue;
                    }
                    if !res.componentwise.is_finite() {
                        continue;
                    }
                    // refine: the true residual is the next right-hand side
                    let mut b = res.h;
                    b.extend(res.g);
                    (v.best, v.stalled) = (f64::INFINITY, 0);
                    v.c_norm = norm(&b);
                    v.c = q.extend(b.clone());
                    v.qr.project(&v.c);
                    if worst.as_ref().is_none_or(|(w, _)| 1.0 > *w) {
                        worst = Some((1.0, b));
                    }
                    continue;
                }
                if !rel.is_finite() || v.sweeps >= MAX_SWEEPS {
                    continue;
                }
                if worst.as_ref().is_none_or(|(w, _)| rel > *w) {
                    let d = q.combine(&res);
                    worst = Some((rel, d));
                }
            }
            let Some((_, dir)) = worst else { break };
            if z.len() == MAX_SPACE {
                break;
            }
            let Some(zn) = precond(&dir) else { break };
            steps += 1;
            let before = z.len();
            z.extend(zn);
            if z.len() == before {
                break;
            }
            let zk = z.col(z.len() - 1);
            let (zw, zc) = zk.split_at(n);
            let bw = spmv(self.b, zw);
            let aw = spmv(self.a, zw);
            let mut az: Vec<C64> = bw.iter().zip(&aw).map(|(b, a)| anchor * b - a).collect();
            for (t, &k) in set.iter().enumerate() {
                az.iter_mut()
                    .zip(&self.bv[k])
                    .for_each(|(o, v)| *o += v * zc[t]);
            }
            az.extend(set.iter().map(|&k| dot(&self.ub[k], zw)));
            let mut ez = bw;
            ez.resize(n + r, zero);
            let ca = q.extend(az);
            let ce = q.extend(ez);
            let k = z.len() - 1;
            for v in values.iter_mut().filter(|v| !v.solved) {
                let mut g = ca.clone();
                g.resize(ce.len(), zero);
                g.iter_mut().zip(&ce).for_each(|(x, y)| *x += v.delta * y);
                v.qr.push(k, g, &v.c);
            }
        }
        let solutions = values
            .into_iter()
            .map(|v| {
                v.solved.then(|| {
                    let (w, coeffs) = v.x.split_at(n);
                    (w.to_vec(), coeffs.to_vec())
                })
            })
            .collect();
        (solutions, steps)
    }
}
