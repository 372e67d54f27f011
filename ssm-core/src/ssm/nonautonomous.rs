//! Higher-order non-autonomous terms of the periodic SSM, `O(eps |p|^k)`, beyond
//! the leading order `X0`, `S0` used by Li, Jain & Haller (2023).
//!
//! With `W_eps = W(p) + eps sum_h (X_h(p) e^{i kappa_h phi} + c.c.)` and
//! `R_eps = R(p) + eps sum_h (S_h(p) e^{i kappa_h phi} + c.c.)`,
//! `X_h = sum_k x_{h,k} p^k`, `S_h = sum_k s_{h,k} p^k`, the `eps e^{i kappa phi} p^k`
//! part of eq. (60) is, order by order in `|k|`,
//!
//! `(Lambda B - A) x_k + B V_I s_k = F_h delta_{k0} + [DF(W(p)) X(p)]_k
//!   - B [DX(p) R_nl(p) + DW_nl(p) S(p)]_k`,  `Lambda = i kappa Omega + k . lambda`,
//!
//! where `R_nl`, `W_nl` are `R`, `W` without their linear parts. Every term on the
//! right involves only `x_j`, `s_j` with `|j| < |k|` (because `DF(0) = 0`), so the
//! same bordered solver as for the autonomous SSM applies. Normal-form style: the
//! resonant set `I` holds the reduced coordinates `c` with
//! `kappa + k . r = r_c` (`r` of eq. (16), `-r` for conjugate coordinates), so
//! that the reduced dynamics are autonomous in the rotating frame. `k = 0`
//! reproduces [`super::forced::ForcedSsm::at`]. The model's forcing must not
//! depend on the state here.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Nonlinear analysis of forced mechanical systems
//! with internal resonance using spectral submanifolds, Part I*, Nonlinear Dyn.
//! 110 (2022), Sect. 3.2 and Appendix B (non-autonomous expansion);
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), eq. (60).

use super::forced::{ForcedError, ForcedSsm, ForcedTerms};
use super::{finish_residuals, SsmExpansion, RESIDUAL_GROUP};
use crate::model::system::System;
use crate::spectrum::modes::spmv;
use crate::C64;
use rayon::prelude::*;
use ssm_kernel::poly::{eval_poly, MultiIndexSet};

mod series;
pub use series::NaSeries;

/// One harmonic's expansion: coefficient of `e^{i kappa phi} p^k`.
#[derive(Debug, Clone)]
pub struct NaHarmonic {
    /// `kappa`.
    pub multiple: f64,
    /// `x_{h,k}` per multi-index of [`NonAutonomous::set`] (`N` states).
    pub x: Vec<Vec<C64>>,
    /// `s_{h,k}` per multi-index, per reduced coordinate (zero where not resonant).
    pub s: Vec<Vec<C64>>,
}

/// The non-autonomous part of the periodic SSM to order `order` in `p`, at one `Omega`.
#[derive(Debug, Clone)]
pub struct NonAutonomous {
    /// Forcing frequency.
    pub omega: f64,
    /// Highest order in `p`.
    pub order: usize,
    /// Multi-indices up to `order`.
    pub set: MultiIndexSet,
    /// One entry per forcing harmonic.
    pub harmonics: Vec<NaHarmonic>,
}

/// `sum_v sum_j j_v y_j f_v[k - j + e_v]`: the `p^k` coefficient (`ek`) of
/// `DY(p) f(p)` for a vector series `y` over `jset` (indices `1..jlen`, `None`
/// where absent) and scalar series `f_v` given by exponents.
fn derivative_apply<'y>(
    jset: &MultiIndexSet,
    jlen: usize,
    ek: &[u16],
    y: &dyn Fn(usize) -> Option<&'y [C64]>,
    f: &dyn Fn(usize, &[u16]) -> C64,
    n: usize,
) -> Vec<C64> {
    let nvar = jset.nvar();
    let mut out = vec![C64::new(0.0, 0.0); n];
    let mut m = vec![0u16; nvar];
    for j in 1..jlen {
        let ej = jset.exponents(j);
        let mut yj: Option<&[C64]> = None;
        for v in 0..nvar {
            if ej[v] == 0 {
                continue;
            }
            // m = k - j + e_v, all components non-negative
            let mut ok = true;
            for u in 0..nvar {
                let val = i32::from(ek[u]) - i32::from(ej[u]) + i32::from(u == v);
                if val < 0 {
                    ok = false;
                    break;
                }
                m[u] = val as u16;
            }
            if !ok {
                continue;
            }
            let c = f(v, &m) * f64::from(ej[v]);
            if c == C64::new(0.0, 0.0) {
                continue;
            }
            if yj.is_none() {
                yj = y(j);
            }
            if let Some(yv) = yj {
                for (o, yy) in out.iter_mut().zip(yv) {
                    *o += c * yy;
                }
            }
        }
    }
    out
}

impl ForcedSsm<'_> {
    /// The non-autonomous expansion to order `order` in `p` at `omega`, on top
    /// of the autonomous expansion `ssm` (`order <= ssm.order`).
    pub fn expansion(
        &mut self,
        ssm: &SsmExpansion,
        sys: &System,
        omega: f64,
        order: usize,
    ) -> Result<NonAutonomous, ForcedError> {
        let mut one = self.expansions(ssm, sys, &[omega], order, None)?;
        Ok(one.pop().expect("one frequency, one expansion"))
    }

    /// The expansions of [`ForcedSsm::expansion`] at every frequency of
    /// `omegas`, computed multi-index by multi-index for all of them; with
    /// `anchor` (a frequency of their band), each multi-index's equations at
    /// all frequencies are solved through one factorization at the anchor's
    /// `Lambda` and one shared search space (`ForcedSsm::solve_band`)
    /// instead of a factorization per frequency; multi-indices whose shifts
    /// differ by damping alone share the factorization, released after the
    /// last order that uses it. Without `anchor`, every frequency is solved
    /// directly. Holds every frequency's coefficients at once (`omegas.len()`
    /// times those of one expansion).
    pub fn expansions(
        &mut self,
        ssm: &SsmExpansion,
        sys: &System,
        omegas: &[f64],
        order: usize,
        anchor: Option<f64>,
    ) -> Result<Vec<NonAutonomous>, ForcedError> {
        let order = order.min(ssm.order);
        if order > 0 && !self.forcing_is_constant(sys) {
            return Err(ForcedError::StateDependentForcing);
        }
        // a band of frequencies on a model with dear factors: one Taylor
        // series per multi-index through one factorization per anchor
        if let Some(c) = anchor.filter(|_| omegas.len() > 1 && self.iterative()) {
            if let Some(series) = self.expansion_series(ssm, sys, omegas, order, c)? {
                return Ok(omegas.iter().map(|&w| series.at(w)).collect());
            }
        }
        self.expansions_solved(ssm, sys, omegas, order, anchor)
    }

    /// [`ForcedSsm::expansions`] solved frequency by frequency (directly,
    /// or with `anchor` through band solves), without a series.
    pub fn expansions_solved(
        &mut self,
        ssm: &SsmExpansion,
        sys: &System,
        omegas: &[f64],
        order: usize,
        anchor: Option<f64>,
    ) -> Result<Vec<NonAutonomous>, ForcedError> {
        let order = order.min(ssm.order);
        let nvar = ssm.dim();
        let cx = Rhs::new(ssm, sys, order);
        let set = &cx.set;
        let lambda = self.lambda().to_vec();
        let coord_ratio = self.coord_ratios().to_vec();
        let zero = C64::new(0.0, 0.0);
        let shift_of = |e: &[u16]| shift(&lambda, e);
        let mut out: Vec<NonAutonomous> = omegas
            .iter()
            .map(|&omega| NonAutonomous {
                omega,
                order,
                set: set.clone(),
                harmonics: Vec::new(),
            })
            .collect();
        for h in 0..self.n_harmonics() {
            let (multiple, f) = self.harmonic(h);
            let f = f.to_vec();
            // per frequency: x_k, s_k of every multi-index
            let mut xs: Vec<Vec<Vec<C64>>> = vec![vec![Vec::new(); set.len()]; omegas.len()];
            let mut ss: Vec<Vec<Vec<C64>>> = vec![vec![vec![zero; nvar]; set.len()]; omegas.len()];
            // the anchors and the last order each serves, to release its
            // factorization after that order
            // on the imaginary axis: multi-indices whose shifts differ by
            // damping alone share the anchor
            let at = |c: f64, e: &[u16]| C64::new(0.0, multiple * c + shift_of(e).im);
            let last = anchor.map_or_else(Vec::new, |c| band_anchors(set, &|e| at(c, e)));
            let anchor_of = |e: &[u16]| anchor.and_then(|c| anchor_for(&last, at(c, e)));
            for k in 0..=order {
                let done = set.of_order(k).start;
                for idx in set.of_order(k) {
                    let e = set.exponents(idx).to_vec();
                    let shift = shift_of(&e);
                    let set_res = resonant_set(&coord_ratio, multiple, &e);
                    // the lower multi-indices j with e - j in the set, and e - j
                    let below: Vec<(usize, usize)> = (0..done)
                        .filter_map(|j| sub_index(set, &e, set.exponents(j)).map(|t| (j, t)))
                        .collect();
                    let rhss: Vec<Vec<C64>> = (0..omegas.len())
                        .map(|node| {
                            let forcing = (k == 0).then_some(f.as_slice());
                            let x: Vec<&[C64]> = xs[node].iter().map(Vec::as_slice).collect();
                            let s: Vec<&[C64]> = ss[node].iter().map(Vec::as_slice).collect();
                            cx.rhs_known(&e, done, &below, &x, &s, forcing).0
                        })
                        .collect();
                    let bigs: Vec<C64> = omegas
                        .iter()
                        .map(|&omega| C64::new(0.0, multiple * omega) + shift)
                        .collect();
                    let fail = |source| ForcedError::Solve {
                        harmonic: h + 1,
                        omega: omegas[0],
                        source,
                    };
                    let solved = match anchor_of(&e) {
                        // the anchor on the imaginary axis: multi-indices
                        // whose shifts differ by damping alone share it
                        Some(at) => {
                            let refs: Vec<&[C64]> = rhss.iter().map(Vec::as_slice).collect();
                            self.solve_band(&bigs, at, &set_res, &refs).map_err(fail)?
                        }
                        None => bigs
                            .iter()
                            .zip(&rhss)
                            .zip(omegas)
                            .map(|((&big, rhs), &omega)| {
                                self.solve(big, &set_res, rhs).map_err(|source| {
                                    ForcedError::Solve {
                                        harmonic: h + 1,
                                        omega,
                                        source,
                                    }
                                })
                            })
                            .collect::<Result<Vec<_>, _>>()?,
                    };
                    for (node, (xk, sk)) in solved.into_iter().enumerate() {
                        xs[node][idx] = xk;
                        for (&c, v) in set_res.iter().zip(sk) {
                            ss[node][idx][c] = v;
                        }
                    }
                }
                for &(at, _) in last.iter().filter(|(_, l)| *l == k) {
                    self.release_anchor(at);
                }
                self.clear();
            }
            for ((o, x), s) in out.iter_mut().zip(xs).zip(ss) {
                o.harmonics.push(NaHarmonic { multiple, x, s });
            }
        }
        Ok(out)
    }
}

/// What the right-hand side of one multi-index's equation is made of: the
/// autonomous SSM, the system, the multi-index sets of `X` and `W` and the
/// Jacobian series `DF(W(p))`.
pub(super) struct Rhs<'s> {
    pub ssm: &'s SsmExpansion,
    pub sys: &'s System,
    pub set: MultiIndexSet,
    pub wset: MultiIndexSet,
    pub jac: JacobianSeries,
}

/// `k . lambda` of multi-index `k` (exponents `e`).
pub(super) fn shift(lambda: &[C64], e: &[u16]) -> C64 {
    lambda.iter().zip(e).map(|(l, &kv)| l * f64::from(kv)).sum()
}

impl<'s> Rhs<'s> {
    /// The context of the equations to order `order` in `p` on top of `ssm`.
    pub fn new(ssm: &'s SsmExpansion, sys: &'s System, order: usize) -> Self {
        let set = MultiIndexSet::new(ssm.dim(), order);
        let wset = MultiIndexSet::new(ssm.dim(), order + 1);
        let jac = jacobian_series(ssm, sys, &set);
        Self {
            ssm,
            sys,
            set,
            wset,
            jac,
        }
    }

    /// The right-hand side at multi-index `e` (order `k`, the multi-indices
    /// of lower orders `..done`, `below` its pairs `(j, e - j)`) from the
    /// lower orders' `x` (an empty vector: zero) and `s`, with the forcing
    /// `F_h` at `k = 0`: `F_h delta_{k0} + [DF(W) X]_k - B [DX R_nl + DW_nl
    /// S]_k` (module docs). Linear in `x` and `s` but for the forcing.
    ///
    /// With it, `M^{-1} rhs_V` where the model is mechanical and the part of
    /// the right-hand side that `B` does not multiply has no velocity rows:
    /// then `rhs_V = -(B c)_V = -M c_x` for the correction `c`, and `M^{-1}
    /// rhs_V = -c_x` without a solve.
    pub(crate) fn rhs_known(
        &self,
        e: &[u16],
        done: usize,
        below: &[(usize, usize)],
        x: &[&[C64]],
        s: &[&[C64]],
        forcing: Option<&[C64]>,
    ) -> (Vec<C64>, Option<Vec<C64>>) {
        let (ssm, set, wset) = (self.ssm, &self.set, &self.wset);
        let n = self.sys.n_states();
        let zero = C64::new(0.0, 0.0);
        let k: u16 = e.iter().sum();
        let mut rhs = forcing.map_or_else(|| vec![zero; n], <[C64]>::to_vec);
        // [DF(W) X]_k = sum over (j, t) of J_t x_j
        for &(j, t) in below {
            let xj = x[j];
            if xj.is_empty() {
                continue;
            }
            for &(eq, var, v) in &self.jac.terms[t] {
                rhs[eq] += v * xj[var];
            }
        }
        // - B [DX R_nl + DW_nl S]_k
        let dx_r = derivative_apply(
            set,
            done,
            e,
            &|j| (!x[j].is_empty()).then_some(x[j]),
            &|v, m| r_nl(ssm, v, m),
            n,
        );
        let dw_s = derivative_apply(
            wset,
            wset.of_order(usize::from(k) + 1).end,
            e,
            &|j| {
                let ej = wset.exponents(j);
                let o: u16 = ej.iter().sum();
                if o < 2 {
                    return None;
                }
                ssm.set.index(ej).map(|si| ssm.w[si].as_slice())
            },
            &|v, m| {
                set.index(m)
                    .filter(|&mi| mi < done)
                    .map_or(zero, |mi| s[mi][v])
            },
            n,
        );
        let corr: Vec<C64> = dx_r.iter().zip(&dw_s).map(|(a, b)| a + b).collect();
        let known = self.sys.velocities().and_then(|v| {
            rhs[v.clone()]
                .iter()
                .all(|c| c.re == 0.0 && c.im == 0.0)
                .then(|| corr[..v.len()].iter().map(|c| -c).collect())
        });
        let bc = spmv(self.sys.b.as_ref(), &corr);
        for (r, c) in rhs.iter_mut().zip(&bc) {
            *r -= c;
        }
        (rhs, known)
    }
}

/// The Jacobian series `DF(W(p)) = sum_t J_t p^t` to the order of a
/// multi-index set, as the entries `(equation, variable, value)` of each
/// `J_t` (`t` a multi-index of the set), the contributions of every term
/// and factor of the nonlinearity to one entry summed, sorted by equation:
/// applying `J_t` is one pass over its entries.
pub(super) struct JacobianSeries {
    terms: Vec<Vec<(usize, usize, C64)>>,
}

/// The Jacobian series `DF(W(p))` to the order of `set` (orders >= 1).
pub(super) fn jacobian_series(
    ssm: &SsmExpansion,
    sys: &System,
    set: &MultiIndexSet,
) -> JacobianSeries {
    let zero = C64::new(0.0, 0.0);
    let len = set.len();
    // the products of the set's monomials, and where each sits in the SSM's
    // set, found once for every term and factor
    let product: Vec<Option<usize>> = (0..len * len)
        .map(|ij| {
            let (ei, ej) = (set.exponents(ij / len), set.exponents(ij % len));
            let sum: Vec<u16> = ei.iter().zip(ej).map(|(x, y)| x + y).collect();
            set.index(&sum)
        })
        .collect();
    let in_ssm: Vec<Option<usize>> = (0..len)
        .map(|idx| {
            (idx > 0)
                .then(|| ssm.set.index(set.exponents(idx)))
                .flatten()
        })
        .collect();
    // the entries (equation, variable) of DF, one per term and factor,
    // numbered in order: each contribution is then summed into its entry's
    // series in the terms' order (no list of every contribution and
    // multi-index is held and sorted)
    let keys: Vec<u64> = sys
        .nonlinearity
        .terms
        .iter()
        .flat_map(|t| {
            t.factors
                .iter()
                .map(move |f| (u64::from(t.eq) << 32) | u64::from(f.var))
        })
        .collect();
    let mut entries = keys.clone();
    entries.par_sort_unstable();
    entries.dedup();
    let slot: Vec<usize> = keys
        .par_iter()
        .map(|k| entries.binary_search(k).expect("every key is an entry"))
        .collect();
    drop(keys);
    let mut values = vec![zero; entries.len() * len];
    let mut factor = vec![zero; len];
    let mut series = vec![zero; len];
    let mut next = 0;
    for t in sys.nonlinearity.terms.iter() {
        for (fi, fv) in t.factors.iter().enumerate() {
            series.iter_mut().for_each(|c| *c = zero);
            series[0] = C64::new(t.coeff * f64::from(fv.power), 0.0);
            for (gi, gv) in t.factors.iter().enumerate() {
                let pw = if gi == fi { gv.power - 1 } else { gv.power };
                if pw == 0 {
                    continue;
                }
                // the series of W's component gv.var (no constant term)
                for (f, si) in factor.iter_mut().zip(&in_ssm) {
                    *f = si.map_or(zero, |si| ssm.w[si][gv.var as usize]);
                }
                for _ in 0..pw {
                    series = mul_series(&product, &series, &factor);
                }
            }
            let at = slot[next] * len;
            next += 1;
            for (v, c) in values[at..at + len].iter_mut().zip(&series) {
                *v += c;
            }
        }
    }
    let terms: Vec<Vec<(usize, usize, C64)>> = (0..len)
        .map(|m| {
            entries
                .iter()
                .enumerate()
                .filter(|&(e, _)| values[e * len + m] != zero)
                .map(|(e, &key)| {
                    (
                        (key >> 32) as usize,
                        (key & 0xffff_ffff) as usize,
                        values[e * len + m],
                    )
                })
                .collect()
        })
        .collect();
    JacobianSeries { terms }
}

impl NonAutonomous {
    /// The expansion of order 0 in `p` (`nvar` reduced coordinates) that
    /// the leading-order terms `X0`, `S0` are.
    pub fn leading(terms: ForcedTerms, nvar: usize) -> Self {
        Self {
            omega: terms.omega,
            order: 0,
            set: MultiIndexSet::new(nvar, 0),
            harmonics: terms
                .harmonics
                .into_iter()
                .map(|h| NaHarmonic {
                    multiple: h.multiple,
                    x: vec![h.x],
                    s: vec![h.s],
                })
                .collect(),
        }
    }

    /// Residual of the invariance equation (60) of the periodic SSM (autonomous
    /// part truncated at `order`, this non-autonomous part at its own order),
    /// at reduced point `p` (conjugate pairs) and phase `phi`:
    /// `B [D_p W_eps R_eps + Omega D_phi W_eps] - A W_eps - F(W_eps) - eps Fext(phi)`.
    /// What remains is `O(eps |p|^(K+1))` and `O(eps^2)` (Fig. 6 for `K = 0`).
    #[allow(clippy::too_many_arguments)]
    pub fn residual(
        &self,
        ssm: &SsmExpansion,
        sys: &System,
        eps: f64,
        p: &[C64],
        phi: f64,
        order: usize,
    ) -> Vec<C64> {
        let mut one = self.residuals(ssm, sys, eps, &[(p.to_vec(), phi)], order);
        one.pop().expect("one point, one residual")
    }

    /// [`NonAutonomous::residual`] at each `(p, phi)` of `points`: groups
    /// of [`RESIDUAL_GROUP`] points evaluate the nonlinearity together, one
    /// group per core; the same bits as a call per point.
    pub fn residuals(
        &self,
        ssm: &SsmExpansion,
        sys: &System,
        eps: f64,
        points: &[(Vec<C64>, f64)],
        order: usize,
    ) -> Vec<Vec<C64>> {
        let n = sys.n_states();
        points
            .par_chunks(RESIDUAL_GROUP)
            .flat_map_iter(|group| {
                let parts: Vec<(Vec<C64>, Vec<C64>)> = group
                    .iter()
                    .map(|(p, phi)| self.residual_parts(ssm, eps, p, *phi, order))
                    .collect();
                // the external forcing at each point's phase
                let forcing = |k: usize, fz: &mut [C64]| {
                    let (z, phi) = (&parts[k].1, group[k].1);
                    for h in &sys.forcing {
                        let (c, s) = ((h.multiple * phi).cos(), (h.multiple * phi).sin());
                        let mut fc = vec![C64::new(0.0, 0.0); n];
                        let mut fs = vec![C64::new(0.0, 0.0); n];
                        eval_poly(&h.cos, z, &mut fc);
                        eval_poly(&h.sin, z, &mut fs);
                        for i in 0..n {
                            fz[i] += eps * (c * fc[i] + s * fs[i]);
                        }
                    }
                };
                finish_residuals(sys, &parts, forcing)
            })
            .collect()
    }

    /// `(B`-side, state) of [`NonAutonomous::residual`] at `(p, phi)`:
    /// `D_p W_eps R_eps + Omega D_phi W_eps` and `W_eps`.
    fn residual_parts(
        &self,
        ssm: &SsmExpansion,
        eps: f64,
        p: &[C64],
        phi: f64,
        order: usize,
    ) -> (Vec<C64>, Vec<C64>) {
        let order = order.min(ssm.order);
        let n = ssm.n_states();
        let nvar = p.len();
        let mono = self.set.monomials(p, self.order);
        // reduced dynamics with forcing
        let mono_ssm = ssm.set.monomials(p, order);
        let mut r = ssm.r_at(&mono_ssm, order);
        for h in &self.harmonics {
            let e = C64::from_polar(1.0, h.multiple * phi);
            for c in 0..nvar {
                let own: C64 = h.s.iter().zip(&mono).map(|(sk, m)| sk[c] * m).sum();
                let partner: C64 = h.s.iter().zip(&mono).map(|(sk, m)| sk[c ^ 1] * m).sum();
                r[c] += eps * (own * e + partner.conj() * e.conj());
            }
        }
        // z = W + eps sum 2 Re(X e^{i kappa phi}); lhs = Dz r + eps Omega d_phi
        let mut z = ssm.w_at(&mono_ssm, order);
        let mut lhs = vec![C64::new(0.0, 0.0); n];
        let end = ssm.set.of_order(order).end;
        for idx in ssm.set.of_order(1).start..end {
            let s = ssm.set.derivative_along(idx, &mono_ssm, &r);
            for (l, wk) in lhs.iter_mut().zip(&ssm.w[idx]) {
                *l += s * wk;
            }
        }
        for h in &self.harmonics {
            let e = C64::from_polar(1.0, h.multiple * phi);
            let mut xp = vec![C64::new(0.0, 0.0); n];
            let mut dxr = vec![C64::new(0.0, 0.0); n];
            for (idx, xk) in h.x.iter().enumerate() {
                let d = if idx == 0 {
                    C64::new(0.0, 0.0)
                } else {
                    self.set.derivative_along(idx, &mono, &r)
                };
                for i in 0..n {
                    xp[i] += mono[idx] * xk[i];
                    dxr[i] += d * xk[i];
                }
            }
            for i in 0..n {
                z[i] += 2.0 * eps * (xp[i] * e).re;
                lhs[i] += 2.0 * eps * (dxr[i] * e).re;
                lhs[i] += 2.0 * eps * self.omega * (xp[i] * e * C64::new(0.0, h.multiple)).re;
            }
        }
        (lhs, z)
    }
}

impl NonAutonomous {
    /// One master pair, first harmonic, `r = 1`: the coefficients of the
    /// rotating-frame forcing `sigma(u) + q^2 tau(u)` (`u = |q|^2`) of
    /// [`crate::rom::frc::ForcedCoefficients`]: `sigma_a = s_{(a,a)}` of `p`,
    /// `tau_b = conj(s_{(b,b+2)})` of `conj p` (the conjugate harmonic's terms
    /// in the equation of `p`).
    pub fn rotating_frame_coefficients(&self) -> (Vec<C64>, Vec<C64>) {
        rotating_frame(&self.set, self.order, &|i, c| self.harmonics[0].s[i][c])
    }
}

/// [`NonAutonomous::rotating_frame_coefficients`] of the expansion to
/// `order` over `set` whose first harmonic's `s_{k,c}` is `s(k, c)`.
fn rotating_frame(
    set: &MultiIndexSet,
    order: usize,
    s: &dyn Fn(usize, usize) -> C64,
) -> (Vec<C64>, Vec<C64>) {
    let zero = C64::new(0.0, 0.0);
    let mut sigma = Vec::new();
    let mut tau = Vec::new();
    for a in 0..=(order / 2) as u16 {
        sigma.push(set.index(&[a, a]).map_or(zero, |i| s(i, 0)));
        if 2 * a + 2 <= order as u16 {
            tau.push(set.index(&[a, a + 2]).map_or(zero, |i| s(i, 1).conj()));
        }
    }
    if tau.is_empty() {
        tau.push(zero);
    }
    (sigma, tau)
}

/// The anchors `at(k)` of the multi-indices `k` of `set` (values equal up
/// to rounding are one, and share a factorization), each with the last
/// order it serves (its factorization is released after it).
pub(super) fn band_anchors(set: &MultiIndexSet, at: &dyn Fn(&[u16]) -> C64) -> Vec<(C64, usize)> {
    let mut last: Vec<(C64, usize)> = Vec::new();
    for k in 0..=set.max_order() {
        for idx in set.of_order(k) {
            let at = at(set.exponents(idx));
            match last.iter_mut().find(|(a, _)| near(*a, at)) {
                Some(entry) => entry.1 = k,
                None => last.push((at, k)),
            }
        }
    }
    last
}

/// The anchor of [`band_anchors`] equal to `at` up to rounding.
pub(super) fn anchor_for(anchors: &[(C64, usize)], at: C64) -> Option<C64> {
    anchors.iter().find(|(a, _)| near(*a, at)).map(|(a, _)| *a)
}

fn near(a: C64, b: C64) -> bool {
    (a - b).norm() <= 1e-12 * a.norm().max(b.norm())
}

/// The reduced coordinates `c` resonant with harmonic `multiple` at
/// multi-index `e`: `kappa + k . r = r_c` (module docs).
pub(super) fn resonant_set(coord_ratio: &[f64], multiple: f64, e: &[u16]) -> Vec<usize> {
    let phase: f64 = multiple
        + coord_ratio
            .iter()
            .zip(e)
            .map(|(r, &kv)| r * f64::from(kv))
            .sum::<f64>();
    coord_ratio
        .iter()
        .enumerate()
        .filter(|(_, &rc)| (phase - rc).abs() <= 1e-9 * rc.abs().max(1.0))
        .map(|(c, _)| c)
        .collect()
}

/// Coefficient of `p^m` in the nonlinear part of `R_v`.
fn r_nl(ssm: &SsmExpansion, v: usize, m: &[u16]) -> C64 {
    let o: u16 = m.iter().sum();
    if o < 2 {
        return C64::new(0.0, 0.0);
    }
    match ssm.set.index(m) {
        Some(mi) => ssm
            .r
            .iter()
            .filter(|t| t.coord == v && t.index == mi)
            .map(|t| t.coeff)
            .sum(),
        None => C64::new(0.0, 0.0),
    }
}

/// Index of `e - f` when it is a multi-index of the set.
pub(super) fn sub_index(set: &MultiIndexSet, e: &[u16], f: &[u16]) -> Option<usize> {
    let mut d = Vec::with_capacity(e.len());
    for (a, b) in e.iter().zip(f) {
        if b > a {
            return None;
        }
        d.push(a - b);
    }
    set.index(&d)
}

/// `a * b` truncated to a multi-index set of `a.len()` monomials, where
/// `product[i * len + j]` is the index of monomial `i` times monomial `j`.
fn mul_series(product: &[Option<usize>], a: &[C64], b: &[C64]) -> Vec<C64> {
    let zero = C64::new(0.0, 0.0);
    let len = a.len();
    let mut out = vec![zero; len];
    for (i, ai) in a.iter().enumerate().filter(|(_, x)| **x != zero) {
        for (j, bj) in b.iter().enumerate().filter(|(_, x)| **x != zero) {
            if let Some(t) = product[i * len + j] {
                out[t] += ai * bj;
            }
        }
    }
    out
}
