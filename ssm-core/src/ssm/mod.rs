//! Autonomous spectral submanifolds of flows and maps: the parametrization
//! method to arbitrary order, in physical coordinates, with master modes only.
//!
//! Flows (eq. 55): `B DW(p) R(p) = A W(p) + F(W(p))`.
//! Maps (Szalai et al., eq. 5.8, with `B z_{k+1} = A z_k + F(z_k)`):
//! `B W(R(p)) = A W(p) + F(W(p))`.
//!
//! `W(p) = sum_k w_k p^k` and `R(p) = sum_k r_k p^k` are solved order by order.
//! At multi-index `k` of order `|k| >= 2` the homological equation is
//!
//! `(Lambda_k B - A) w_k + B V r_k = [F(W)]_k - B c_k`,
//!
//! with `Lambda_k = k . lambda` and `c_k = [sum_{j} DW_j R_l]_k` over the
//! nonlinear lower-order terms (flows), or `Lambda_k = mu^k` and
//! `c_k = sum_{2 <= |j| < |k|} w_j [R(p)^j]_k` (maps). It is solved by
//! `homological::Homological`. The normal-form style decides per multi-index
//! and master coordinate `i` whether the term is an inner resonance (eq. 15):
//! flows compare frequencies, `|Im(k . lambda) - Im(lambda_i)| <= tol |Im lambda_i|`,
//! maps compare arguments, `|arg(mu^k / mu_i)| <= tol |arg mu_i|`. Damping is
//! deliberately left out of this test: the backbone terms
//! `p1^{j+1} conj(p1)^j` differ from `lambda_1` by `2 j Re(lambda_1)`, which
//! grows with `j`, yet they must stay in `R` at every order, or their tiny
//! denominators would spoil `W` for lightly damped systems.
//!
//! Conjugate symmetry: `w_{conj k} = conj(w_k)` and the reduced dynamics of
//! `conj p_i` are the conjugates of those of `p_i`, so only half of the
//! multi-indices are solved.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sects. 3-4,
//! eqs. (15), (55), (39)-(42);
//! G. Haller, S. Ponsioen, Nonlinear Dyn. 86 (2016) (SSM existence);
//! R. Szalai, D. Ehrhardt, G. Haller, *Nonlinear model identification and
//! spectral submanifolds for multi-degree-of-freedom mechanical vibrations*,
//! Proc. R. Soc. A 473 (2017), Sects. 5-6 (maps).

pub mod analysis;
pub mod forced;
pub(crate) mod homological;
pub mod modal_residual;
pub mod nonautonomous;
pub(crate) mod rom;
pub mod spectral;

use std::time::Instant;

use ssm_api::{PolyVector, TimeKind};

use crate::model::system::System;
use crate::spectrum::modes::{spmv, spmv_many};
use crate::spectrum::MasterMode;
use crate::C64;
pub use homological::{
    band_vectors, lu_bytes_estimate, FactorBytes, SolveCounts, SolveStats, LU_BYTES_PER_ENTRY,
    SERIES_TERMS,
};
use homological::{Homological, HomologicalError};
use rayon::prelude::*;
use ssm_kernel::poly::{eval_poly_many, Composition, MultiIndexSet};

/// Continuous or discrete time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dynamics {
    /// `B z' = A z + F(z)`.
    Flow,
    /// `B z_{k+1} = A z_k + F(z_k)` sampled with period `period`.
    Map {
        /// Sampling period.
        period: f64,
    },
}

impl From<TimeKind> for Dynamics {
    fn from(t: TimeKind) -> Self {
        match t {
            TimeKind::Flow => Self::Flow,
            TimeKind::Map { period } => Self::Map { period },
        }
    }
}

/// Options of [`compute`].
#[derive(Debug, Clone, Copy)]
pub struct SsmOptions {
    /// Expansion order.
    pub order: usize,
    /// Relative tolerance of the inner-resonance test.
    pub resonance_tol: f64,
}

/// Right-hand sides beyond this size are taken as an overflow of the
/// expansion (a few more orders would reach infinity).
const OVERFLOW: f64 = 1e250;

/// Why an SSM could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SsmError {
    /// `Lambda_k` coincides with a non-master eigenvalue: an outer resonance
    /// makes the invariance equation unsolvable.
    #[error("order {order}, multi-index {exponents:?}: Lambda = {lambda:.6} equals the non-master eigenvalue {eigenvalue:.6} (outer resonance, relative distance {distance:.1e}); the SSM does not exist for this master subspace: add that mode's pair to [ssm] master_pairs")]
    OuterResonance {
        /// Order of the multi-index.
        order: usize,
        /// Exponents of `p1, conj p1, ...`.
        exponents: Vec<u16>,
        /// `Lambda_k`.
        lambda: C64,
        /// The resonant eigenvalue.
        eigenvalue: C64,
        /// `|Lambda_k - lambda| / |lambda|`.
        distance: f64,
    },
    /// The bordered system could not be solved.
    #[error("order {order}, multi-index {exponents:?}: {source}")]
    Solve {
        /// Order of the multi-index.
        order: usize,
        /// Exponents.
        exponents: Vec<u16>,
        /// Cause.
        source: HomologicalError,
    },
    /// The expansion coefficients outgrow floating point: the radius of
    /// convergence in this normalization is far below 1, so `|W_k|` grows
    /// like `radius^-k` until it overflows.
    #[error("order {order}: the expansion coefficients reach {size:.1e} and overflow floating point (the SSM's radius of convergence is far below 1 in this normalization); lower [ssm] order below {order}, or normalize the master modes to a larger scale")]
    Overflow {
        /// Order at which the right-hand side left the floating-point range.
        order: usize,
        /// Largest right-hand-side entry found.
        size: f64,
    },
    /// The master modes are unusable.
    #[error("master modes: {0}")]
    Masters(String),
    /// The work was asked to stop ([`ssm_kernel::cancel`]) before this order.
    #[error("interrupted before order {order}")]
    Interrupted {
        /// The first order not computed.
        order: usize,
    },
}

/// One term `coeff * p^k` of the reduced dynamics of coordinate `coord`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RTerm {
    /// 0-based reduced coordinate (`p1, conj p1, p2, ...`).
    pub coord: usize,
    /// Multi-index (into [`SsmExpansion::set`]).
    pub index: usize,
    /// Coefficient.
    pub coeff: C64,
}

/// Time spent, by stage, and the memory of each order.
#[derive(Debug, Clone, Default)]
pub struct SsmTiming {
    /// Composition `F(W)` and lower-order terms.
    pub compose_s: f64,
    /// Linear algebra.
    pub linear: SolveStats,
    /// Whole computation.
    pub total_s: f64,
    /// Orders `2..=order`, in order.
    pub orders: Vec<OrderWork>,
    /// Heap of the whole process when the computation began (the model,
    /// its spectrum and whatever the caller holds); `None` where the
    /// allocator does not count.
    pub heap_before: Option<usize>,
}

/// The work and memory of one order of the SSM: its coefficients, and the
/// sparse factors of its homological equations (kept while the order is
/// solved, dropped before the next one).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OrderWork {
    /// The order.
    pub order: usize,
    /// Its multi-indices (conjugates included).
    pub multi_indices: usize,
    /// Numeric factorizations it made.
    pub factorizations: usize,
    /// Bytes of its coefficients of `W` (`16 N` per multi-index).
    pub coefficient_bytes: usize,
    /// Heap its factors held, as the allocator counted it
    /// ([`ssm_kernel::heap`]); `None` where it does not count.
    pub factor_bytes: Option<usize>,
    /// Heap of the whole process once the order is solved, its factors
    /// still held; `None` where the allocator does not count.
    pub heap_bytes: Option<usize>,
}

/// A computed SSM: parametrization `W`, reduced dynamics `R`.
#[derive(Debug, Clone)]
pub struct SsmExpansion {
    /// Flow or map.
    pub dynamics: Dynamics,
    /// Multi-indices up to `order`.
    pub set: MultiIndexSet,
    /// Expansion order.
    pub order: usize,
    /// Eigenvalue (flow) or multiplier (map) of each reduced coordinate.
    pub lambda: Vec<C64>,
    /// `w[idx]`: coefficient (state vector) of `p^idx`.
    pub w: Vec<Vec<C64>>,
    /// Reduced dynamics, linear terms first, then by order.
    pub r: Vec<RTerm>,
    /// Timing.
    pub timing: SsmTiming,
}

/// Master eigenvectors of the reduced coordinates, conjugates included.
pub(crate) fn reduced_modes(masters: &[MasterMode]) -> (Vec<C64>, Vec<Vec<C64>>, Vec<Vec<C64>>) {
    let mut lambda = Vec::new();
    let mut right = Vec::new();
    let mut left = Vec::new();
    for m in masters {
        lambda.push(m.lambda);
        lambda.push(m.lambda.conj());
        right.push(m.right.clone());
        right.push(m.right.iter().map(|c| c.conj()).collect());
        left.push(m.left.clone());
        left.push(m.left.iter().map(|c| c.conj()).collect());
    }
    (lambda, right, left)
}

/// `Lambda_k`: `k . lambda` (flow) or `prod lambda_i^{k_i}` (map).
fn lambda_of(dynamics: Dynamics, lambda: &[C64], e: &[u16]) -> C64 {
    match dynamics {
        Dynamics::Flow => lambda.iter().zip(e).map(|(l, &k)| l * k as f64).sum(),
        Dynamics::Map { .. } => lambda
            .iter()
            .zip(e)
            .fold(C64::new(1.0, 0.0), |acc, (l, &k)| acc * l.powu(k as u32)),
    }
}

/// Inner resonance test of the normal-form style (see the module docs).
pub(crate) fn inner_resonant(dynamics: Dynamics, big_lambda: C64, lambda_i: C64, tol: f64) -> bool {
    match dynamics {
        Dynamics::Flow => (big_lambda.im - lambda_i.im).abs() <= tol * lambda_i.im.abs(),
        Dynamics::Map { .. } => {
            let d = (big_lambda / lambda_i).arg();
            d.abs() <= tol * lambda_i.arg().abs()
        }
    }
}

/// The eigenvalues of `spectrum` outside the master subspace (each master
/// pair occupies its index and the next one in a sorted spectrum).
pub fn non_master(spectrum: &[C64], masters: &[MasterMode]) -> Vec<C64> {
    spectrum
        .iter()
        .enumerate()
        .filter(|(i, _)| !masters.iter().any(|m| *i == m.index || *i == m.index + 1))
        .map(|(_, &l)| l)
        .collect()
}

/// Relative distance below which `Lambda_k` is taken to be exactly an
/// eigenvalue (the homological matrix is singular to working precision).
const EXACT_RESONANCE: f64 = 1e-10;

/// Computes the SSM of `masters` to `opts.order`.
///
/// `others` lists the finite eigenvalues (multipliers for maps) outside the
/// master subspace that are known; any of them hit exactly by some
/// `Lambda_k` is reported as [`SsmError::OuterResonance`].
pub fn compute(
    sys: &System,
    masters: &[MasterMode],
    others: &[C64],
    opts: &SsmOptions,
) -> Result<SsmExpansion, SsmError> {
    let t0 = Instant::now();
    let heap_before = ssm_kernel::heap::live();
    let dynamics = Dynamics::from(sys.time);
    if masters.is_empty() {
        return Err(SsmError::Masters("no master mode".into()));
    }
    let n = sys.n_states();
    let (lambda, right, left) = reduced_modes(masters);
    let nvar = lambda.len();
    let order = opts.order;
    let set = MultiIndexSet::cancellable(nvar, order).ok_or(SsmError::Interrupted { order: 1 })?;
    let zero = vec![C64::new(0.0, 0.0); n];
    let mut w: Vec<Vec<C64>> = vec![Vec::new(); set.len()];
    w[0] = zero.clone();
    let mut r: Vec<RTerm> = Vec::new();
    let mut unit = vec![0u16; nvar];
    for i in 0..nvar {
        unit.iter_mut().for_each(|x| *x = 0);
        unit[i] = 1;
        let idx = set.index(&unit).expect("order 1 is enumerated");
        w[idx] = right[i].clone();
        r.push(RTerm {
            coord: i,
            index: idx,
            coeff: lambda[i],
        });
    }
    let mut solver = Homological::new(
        sys.a.as_ref(),
        sys.b.as_ref(),
        sys.velocities(),
        &lambda,
        &right,
        &left,
    );
    let mut comp = Composition::new(&sys.nonlinearity, set.len());
    // maps: the monomials R(p)^j, 2 <= |j| < order, composed like F(W)
    let mut rpow = match dynamics {
        Dynamics::Map { .. } if order >= 3 => Some(RPowers::new(&set)),
        _ => None,
    };
    let mut rseries: Vec<Vec<C64>> = vec![vec![C64::new(0.0, 0.0); nvar]; set.len()];
    for t in &r {
        rseries[t.index][t.coord] = t.coeff;
    }
    let mut compose_s = 0.0;
    let mut orders = Vec::with_capacity(order.saturating_sub(1));
    for k in 2..=order {
        let tc = Instant::now();
        comp.load_leaves(&w, set.of_order(k - 1));
        comp.advance(&set, k);
        if let Some(rp) = rpow.as_mut() {
            rp.comp.load_leaves(&rseries, set.of_order(k - 1));
            rp.comp.advance(&set, k);
        }
        compose_s += tc.elapsed().as_secs_f64();
        solver.clear_numeric();
        let factorizations_before = solver.stats.factorizations;
        // the order's factorizations first, side by side: its systems'
        // values are known before any right-hand side is (an outer
        // resonance is left to the check below, and a failed factorization
        // to the solve that meets it, which names its multi-index)
        let systems: Vec<(C64, Vec<usize>)> = set
            .of_order(k)
            .filter(|&idx| set.conj(idx) >= idx)
            .map(|idx| lambda_of(dynamics, &lambda, set.exponents(idx)))
            .filter(|&big| {
                others.iter().all(|&ev| {
                    (big - ev).norm() / ev.norm().max(f64::MIN_POSITIVE) > EXACT_RESONANCE
                })
            })
            .map(|big| {
                let resonant = (0..nvar)
                    .filter(|&i| inner_resonant(dynamics, big, lambda[i], opts.resonance_tol))
                    .collect();
                (big, resonant)
            })
            .collect();
        let _ = solver.prefactor(&systems);
        let mut new_terms = Vec::new();
        for idx in set.of_order(k) {
            let cidx = set.conj(idx);
            if cidx < idx {
                continue;
            }
            if ssm_kernel::cancel::requested() {
                return Err(SsmError::Interrupted { order: k });
            }
            let tc = Instant::now();
            let e = set.exponents(idx).to_vec();
            let mut rhs = zero.clone();
            comp.accumulate(idx, &mut rhs);
            let mut corr = zero.clone();
            let mut any = false;
            match (&rpow, dynamics) {
                (_, Dynamics::Flow) => {
                    // [DW R]_k over nonlinear R terms of lower order:
                    // d/dp_i (w_j p^j) r p^l contributes j_i w_j r at j - e_i + l = k
                    for t in r.iter().filter(|t| set.order(t.index) >= 2) {
                        let l = set.exponents(t.index);
                        let mut j = e.clone();
                        let mut ok = true;
                        for v in 0..nvar {
                            let x = j[v] as i32 - l[v] as i32 + (v == t.coord) as i32;
                            if x < 0 {
                                ok = false;
                                break;
                            }
                            j[v] = x as u16;
                        }
                        if !ok || j[t.coord] == 0 {
                            continue;
                        }
                        let jdx = set.index(&j).expect("lower orders are enumerated");
                        let f = t.coeff * j[t.coord] as f64;
                        axpy(&mut corr, f, &w[jdx]);
                        any = true;
                    }
                }
                (Some(rp), Dynamics::Map { .. }) => {
                    let mut vals = vec![C64::new(0.0, 0.0); rp.monomials.len()];
                    rp.comp.accumulate(idx, &mut vals);
                    for (&jdx, &v) in rp.monomials.iter().zip(&vals) {
                        if set.order(jdx) < k && (v.re != 0.0 || v.im != 0.0) {
                            axpy(&mut corr, v, &w[jdx]);
                            any = true;
                        }
                    }
                }
                (None, Dynamics::Map { .. }) => {}
            }
            if any {
                let bc = spmv(sys.b.as_ref(), &corr);
                rhs.iter_mut().zip(&bc).for_each(|(x, y)| *x -= y);
            }
            compose_s += tc.elapsed().as_secs_f64();
            let size = rhs.iter().map(|c| c.norm()).fold(0.0, f64::max);
            if size.is_nan() || size >= OVERFLOW {
                return Err(SsmError::Overflow { order: k, size });
            }
            let big = lambda_of(dynamics, &lambda, &e);
            for &ev in others {
                let distance = (big - ev).norm() / ev.norm().max(f64::MIN_POSITIVE);
                if distance <= EXACT_RESONANCE {
                    return Err(SsmError::OuterResonance {
                        order: k,
                        exponents: e,
                        lambda: big,
                        eigenvalue: ev,
                        distance,
                    });
                }
            }
            let resonant: Vec<usize> = (0..nvar)
                .filter(|&i| inner_resonant(dynamics, big, lambda[i], opts.resonance_tol))
                .collect();
            let (wk, coeffs) =
                solver
                    .solve(big, &resonant, &rhs)
                    .map_err(|source| SsmError::Solve {
                        order: k,
                        exponents: e.clone(),
                        source,
                    })?;
            for (&i, &c) in resonant.iter().zip(&coeffs) {
                new_terms.push(RTerm {
                    coord: i,
                    index: idx,
                    coeff: c,
                });
                if cidx != idx {
                    new_terms.push(RTerm {
                        coord: i ^ 1,
                        index: cidx,
                        coeff: c.conj(),
                    });
                }
            }
            if cidx != idx {
                w[cidx] = wk.iter().map(|c| c.conj()).collect();
            }
            w[idx] = wk;
        }
        new_terms.sort_by_key(|t| (t.index, t.coord));
        for t in &new_terms {
            rseries[t.index][t.coord] = t.coeff;
        }
        r.extend(new_terms);
        let counted = ssm_kernel::heap::live();
        orders.push(OrderWork {
            order: k,
            multi_indices: set.of_order(k).len(),
            factorizations: solver.stats.factorizations - factorizations_before,
            coefficient_bytes: set.of_order(k).len() * n * std::mem::size_of::<C64>(),
            factor_bytes: counted.map(|_| solver.held_factor_bytes()),
            heap_bytes: counted,
        });
    }
    Ok(SsmExpansion {
        dynamics,
        set,
        order,
        lambda,
        w,
        r,
        timing: SsmTiming {
            compose_s,
            linear: solver.stats,
            total_s: t0.elapsed().as_secs_f64(),
            orders,
            heap_before,
        },
    })
}

fn axpy(y: &mut [C64], a: C64, x: &[C64]) {
    y.iter_mut().zip(x).for_each(|(y, x)| *y += a * x);
}

/// The monomials `R(p)^j`, `2 <= |j| <= order - 1`, as a composition trie over
/// the reduced coordinates (maps only).
struct RPowers {
    comp: Composition,
    monomials: Vec<usize>,
}

impl RPowers {
    fn new(set: &MultiIndexSet) -> Self {
        let nvar = set.nvar();
        let monomials: Vec<usize> = (2..set.max_order()).flat_map(|k| set.of_order(k)).collect();
        let mut f = PolyVector::zeros(monomials.len(), nvar);
        for (t, &jdx) in monomials.iter().enumerate() {
            let factors: Vec<(usize, u32)> = set
                .exponents(jdx)
                .iter()
                .enumerate()
                .filter(|(_, &e)| e > 0)
                .map(|(v, &e)| (v, e as u32))
                .collect();
            f.push(t, 1.0, &factors);
        }
        Self {
            comp: Composition::new(&f, set.len()),
            monomials,
        }
    }
}

impl SsmExpansion {
    /// Dimension `2m` of the SSM.
    pub fn dim(&self) -> usize {
        self.lambda.len()
    }

    /// Number of states `N`.
    pub fn n_states(&self) -> usize {
        self.w[0].len()
    }

    /// Reduced-dynamics terms of order at least 2 (the resonant terms).
    pub fn nonlinear_terms(&self) -> impl Iterator<Item = &RTerm> {
        self.r.iter().filter(|t| self.set.order(t.index) >= 2)
    }

    /// `W(p)` truncated at `order`, with the monomials `mono` of `p`.
    pub fn w_at(&self, mono: &[C64], order: usize) -> Vec<C64> {
        let mut z = vec![C64::new(0.0, 0.0); self.n_states()];
        let end = self.set.of_order(order.min(self.order)).end;
        for (m, w) in mono[1..end].iter().zip(&self.w[1..end]) {
            axpy(&mut z, *m, w);
        }
        z
    }

    /// `R(p)` truncated at `order`, with the monomials `mono` of `p`.
    pub fn r_at(&self, mono: &[C64], order: usize) -> Vec<C64> {
        let mut out = vec![C64::new(0.0, 0.0); self.dim()];
        for t in &self.r {
            if self.set.order(t.index) <= order {
                out[t.coord] += t.coeff * mono[t.index];
            }
        }
        out
    }

    /// Coefficients of the scalar output `sum_s weight_s z_s` of `W`.
    pub fn output_series(&self, weights: &[(usize, f64)]) -> Vec<C64> {
        self.w
            .iter()
            .map(|wk| weights.iter().map(|&(s, c)| wk[s] * c).sum())
            .collect()
    }

    /// Invariance residual (eq. 42 for flows; `B W(R(p)) - A W(p) - F(W(p))`
    /// for maps) of the expansion truncated at `order`, at the point `p`.
    pub fn residual(&self, sys: &System, p: &[C64], order: usize) -> Vec<C64> {
        let mut one = self.residuals(sys, std::slice::from_ref(&p.to_vec()), order);
        one.pop().expect("one point, one residual")
    }

    /// [`SsmExpansion::residual`] at each of `points`: groups of
    /// [`RESIDUAL_GROUP`] points evaluate the nonlinearity together (one
    /// pass over its terms, [`eval_poly_many`]), one group per core; the
    /// same bits as a call per point.
    pub fn residuals(&self, sys: &System, points: &[Vec<C64>], order: usize) -> Vec<Vec<C64>> {
        points
            .par_chunks(RESIDUAL_GROUP)
            .flat_map_iter(|group| {
                let parts: Vec<(Vec<C64>, Vec<C64>)> = group
                    .iter()
                    .map(|p| self.residual_parts(p, order))
                    .collect();
                finish_residuals(sys, &parts, |_, _| {})
            })
            .collect()
    }

    /// `(B`-side, state) of [`SsmExpansion::residual`] at `p`: `DW(p) R(p)`
    /// (`W(R(p))` for maps) and `W(p)`.
    fn residual_parts(&self, p: &[C64], order: usize) -> (Vec<C64>, Vec<C64>) {
        let order = order.min(self.order);
        let mono = self.set.monomials(p, order);
        let z = self.w_at(&mono, order);
        let rp = self.r_at(&mono, order);
        let lhs_state = match self.dynamics {
            Dynamics::Flow => {
                // DW(p) R(p) = sum_k w_k sum_i k_i p^{k - e_i} R_i(p)
                let mut d = vec![C64::new(0.0, 0.0); self.n_states()];
                let end = self.set.of_order(order).end;
                for idx in self.set.of_order(1).start..end {
                    let s = self.set.derivative_along(idx, &mono, &rp);
                    axpy(&mut d, s, &self.w[idx]);
                }
                d
            }
            Dynamics::Map { .. } => {
                let mono_r = self.set.monomials(&rp, order);
                self.w_at(&mono_r, order)
            }
        };
        (lhs_state, z)
    }
}

/// Points of a residual evaluation whose nonlinearity is evaluated
/// together ([`eval_poly_many`]): its terms are read once per group.
pub const RESIDUAL_GROUP: usize = 8;

/// `B l - A z - F(z) - g` for each `(l, z)` of `parts` (one group of
/// points), where `extra(k, F)` adds point `k`'s `g` to its `F(z)` (the
/// external forcing of a non-autonomous residual): the nonlinearity of the
/// whole group in one pass ([`eval_poly_many`]).
pub(crate) fn finish_residuals(
    sys: &System,
    parts: &[(Vec<C64>, Vec<C64>)],
    extra: impl Fn(usize, &mut [C64]),
) -> Vec<Vec<C64>> {
    let zero = C64::new(0.0, 0.0);
    let zs: Vec<&[C64]> = parts.iter().map(|(_, z)| z.as_slice()).collect();
    let lhs: Vec<&[C64]> = parts.iter().map(|(l, _)| l.as_slice()).collect();
    let mut fz: Vec<Vec<C64>> = parts.iter().map(|(_, z)| vec![zero; z.len()]).collect();
    eval_poly_many(&sys.nonlinearity, &zs, &mut fz);
    let bl = spmv_many(sys.b.as_ref(), &lhs);
    let az = spmv_many(sys.a.as_ref(), &zs);
    bl.into_iter()
        .zip(az)
        .zip(fz)
        .enumerate()
        .map(|(k, ((mut res, az), mut f))| {
            extra(k, &mut f);
            for i in 0..res.len() {
                res[i] -= az[i] + f[i];
            }
            res
        })
        .collect()
}
