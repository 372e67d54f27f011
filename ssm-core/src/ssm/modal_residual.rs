//! The invariance residual of eq. (42) seen by one master mode, `u^* r(p)`,
//! sampled on a circle of one master pair, without forming the state-space
//! residual `r`.
//!
//! With `W(p) = sum_k w_k p^k` the residual of a flow's expansion truncated at
//! order `o` is `r = B DW(p) R(p) - A W(p) - F(W(p))`, that of a map's
//! (`B z_{k+1} = A z_k + F(z_k)`, Szalai et al. eq. 5.8)
//! `r = B W(R(p)) - A W(p) - F(W(p))`. Projected on the left vector `u` of a
//! master mode:
//!
//! - `u^* B DW(p) R(p) = sum_k (u^* B w_k) sum_v k_v p^{k - e_v} R_v(p)`,
//!   `u^* B W(R(p)) = sum_k (u^* B w_k) R(p)^k` and
//!   `u^* A W(p) = sum_k (u^* A w_k) p^k` need only the scalars `u^* B w_k`,
//!   `u^* A w_k`, computed once;
//! - `u^* F(W(p))` needs `W(p)` only on the states that `F` reads, and each
//!   distinct monomial of `F` once, its equations' weights `conj(u_eq) c`
//!   summed.
//!
//! On the circle `p_j -> p_j e^{i theta}` of pair `j`, `p^k` turns by
//! `e^{i h theta}` with `h = k_{2j} - k_{2j+1}`; the real state
//! `W(p) = Z_0 + 2 Re sum_{h > 0} Z_h e^{i h theta}` follows from the
//! harmonics `Z_h = sum_{h(k) = h} w_k p^k` of the states `F` reads, so all
//! phases cost one pass over `W` and a short inverse Fourier sum each.
//! The full residual costs `O(N)` vector operations per multi-index and phase;
//! this one `O(N)` per multi-index per circle, which is what makes the error
//! estimates of backbones and transients affordable at `10^5` states.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), eqs. (42),
//! (55); G. Szalai, D. Ehrhardt, G. Haller, *Nonlinear model identification
//! and spectral submanifolds for multi-degree-of-freedom mechanical
//! vibrations*, Proc. R. Soc. A 473 (2017), eq. (5.8).

use ssm_api::PolyVector;

use crate::model::system::System;
use crate::spectrum::modes::spmv_t;
use crate::ssm::{Dynamics, SsmExpansion};
use crate::C64;

/// `u^* r(p)` of one master mode for an autonomous expansion of a flow or a
/// map.
#[derive(Debug, Clone)]
pub struct ModalResidual {
    /// The expansion is of a map: `B W(R(p))` in place of `B DW(p) R(p)`.
    map: bool,
    /// `u^* B w_k` per multi-index.
    bw: Vec<C64>,
    /// `u^* A w_k` per multi-index.
    aw: Vec<C64>,
    /// Number of multi-indices kept (up to the expansion order).
    n_index: usize,
    /// `W` on the states `F` reads: `w_read[l * n_index + k] = w_k[reads[l]]`.
    w_read: Vec<C64>,
    /// Number of states `F` reads.
    n_read: usize,
    /// The distinct monomials of `F`, each with its weight `sum conj(u_eq) c`.
    monomials: Vec<WeightedMonomial>,
    /// Factors of all monomials: (position in the read states, power).
    factors: Vec<(u32, u32)>,
}

/// A distinct monomial of `F` projected on `u`.
#[derive(Debug, Clone, Copy)]
struct WeightedMonomial {
    weight: C64,
    /// Its factors: `factors[start..end]`.
    start: u32,
    end: u32,
}

impl ModalResidual {
    /// Projects the expansion `ssm` of `sys` on the left vector `left`
    /// (normalized `u^* B v = 1` for the master mode it belongs to).
    pub fn new(ssm: &SsmExpansion, sys: &System, left: &[C64]) -> Self {
        let u_conj: Vec<C64> = left.iter().map(|c| c.conj()).collect();
        let ub = spmv_t(sys.b.as_ref(), &u_conj);
        let ua = spmv_t(sys.a.as_ref(), &u_conj);
        let dot = |x: &[C64], w: &[C64]| -> C64 { x.iter().zip(w).map(|(a, b)| a * b).sum() };
        let bw = ssm.w.iter().map(|w| dot(&ub, w)).collect();
        let aw = ssm.w.iter().map(|w| dot(&ua, w)).collect();
        let (reads, monomials, factors) = project_nonlinearity(&sys.nonlinearity, &u_conj);
        let n_index = ssm.w.len();
        let mut w_read = Vec::with_capacity(reads.len() * n_index);
        for &s in &reads {
            w_read.extend(ssm.w.iter().map(|w| w[s]));
        }
        Self {
            map: ssm.dynamics != Dynamics::Flow,
            bw,
            aw,
            n_index,
            w_read,
            n_read: reads.len(),
            monomials,
            factors,
        }
    }

    /// `u^* r` of the expansion truncated at `order` at the points
    /// `p(theta_m)`, `theta_m = 2 pi m / phases`, where pair `pair` of the
    /// conjugate-paired point `p` is turned by `e^{i theta_m}` and the other
    /// pairs are held.
    pub fn on_circle(
        &self,
        ssm: &SsmExpansion,
        p: &[C64],
        pair: usize,
        order: usize,
        phases: usize,
    ) -> Vec<C64> {
        let order = order.min(ssm.order);
        let end = ssm.set.of_order(order).end.min(self.n_index);
        let turns: Vec<C64> = (0..phases)
            .map(|m| C64::from_polar(1.0, 2.0 * std::f64::consts::PI * m as f64 / phases as f64))
            .collect();
        // u^* (B DW R - A W), phase by phase: O(multi-indices) each
        let mut out: Vec<C64> = turns
            .iter()
            .map(|t| {
                let mut point = p.to_vec();
                point[2 * pair] *= t;
                point[2 * pair + 1] *= t.conj();
                self.linear_part(ssm, &point, order, end)
            })
            .collect();
        // harmonics Z_h (h = 0..=order) of W on the states F reads
        let mono = ssm.set.monomials(p, order);
        let harmonic: Vec<i64> = (0..end)
            .map(|k| {
                let e = ssm.set.exponents(k);
                i64::from(e[2 * pair]) - i64::from(e[2 * pair + 1])
            })
            .collect();
        let n_h = order + 1;
        // basis[h][m] = (2 - [h = 0]) e^{i h theta_m}, real and imaginary parts
        let mut cos = vec![0.0; n_h * phases];
        let mut sin = vec![0.0; n_h * phases];
        for h in 0..n_h {
            let f = if h == 0 { 1.0 } else { 2.0 };
            for m in 0..phases {
                let a = 2.0 * std::f64::consts::PI * (h * m) as f64 / phases as f64;
                cos[h * phases + m] = f * a.cos();
                sin[h * phases + m] = f * a.sin();
            }
        }
        let mut z = vec![0.0; self.n_read * phases];
        let mut zh = vec![C64::new(0.0, 0.0); n_h];
        for l in 0..self.n_read {
            zh.iter_mut().for_each(|c| *c = C64::new(0.0, 0.0));
            let w = &self.w_read[l * self.n_index..l * self.n_index + end];
            for ((wk, mk), &h) in w.iter().zip(&mono).zip(&harmonic) {
                if h >= 0 {
                    zh[h as usize] += wk * mk;
                }
            }
            let zl = &mut z[l * phases..(l + 1) * phases];
            for (h, c) in zh.iter().enumerate() {
                let (cr, sr) = (&cos[h * phases..], &sin[h * phases..]);
                for m in 0..phases {
                    zl[m] += c.re * cr[m] - c.im * sr[m];
                }
            }
        }
        // u^* F(W) over the phases, one distinct monomial at a time
        let mut value = vec![0.0; phases];
        let mut f_re = vec![0.0; phases];
        let mut f_im = vec![0.0; phases];
        for mono in &self.monomials {
            value.iter_mut().for_each(|v| *v = 1.0);
            for &(l, power) in &self.factors[mono.start as usize..mono.end as usize] {
                let zl = &z[l as usize * phases..(l as usize + 1) * phases];
                // powi of a run-time exponent is a library call: the powers
                // of mechanical nonlinearities (1 to 3) are multiplied out
                match power {
                    1 => value.iter_mut().zip(zl).for_each(|(v, x)| *v *= x),
                    2 => value.iter_mut().zip(zl).for_each(|(v, x)| *v *= x * x),
                    3 => value.iter_mut().zip(zl).for_each(|(v, x)| *v *= x * x * x),
                    _ => value
                        .iter_mut()
                        .zip(zl)
                        .for_each(|(v, x)| *v *= x.powi(power as i32)),
                }
            }
            for m in 0..phases {
                f_re[m] += mono.weight.re * value[m];
                f_im[m] += mono.weight.im * value[m];
            }
        }
        for (o, (re, im)) in out.iter_mut().zip(f_re.iter().zip(&f_im)) {
            *o -= C64::new(*re, *im);
        }
        out
    }

    /// `u^* (B DW(p) R(p) - A W(p))` of a flow, `u^* (B W(R(p)) - A W(p))`
    /// of a map, truncated at `order` (`end` multi-indices).
    fn linear_part(&self, ssm: &SsmExpansion, p: &[C64], order: usize, end: usize) -> C64 {
        let mono = ssm.set.monomials(p, order);
        let rp = ssm.r_at(&mono, order);
        let range = ssm.set.of_order(1).start..end;
        if self.map {
            let image = ssm.set.monomials(&rp, order);
            return range
                .map(|k| self.bw[k] * image[k] - self.aw[k] * mono[k])
                .sum();
        }
        range
            .map(|k| self.bw[k] * ssm.set.derivative_along(k, &mono, &rp) - self.aw[k] * mono[k])
            .sum()
    }
}

/// The states `F` reads, its distinct monomials (factors renumbered to
/// positions among those states) with weights `sum conj(u_eq) c` over the
/// equations they appear in, and the flat factor list.
type ProjectedNonlinearity = (Vec<usize>, Vec<WeightedMonomial>, Vec<(u32, u32)>);

fn project_nonlinearity(f: &PolyVector, u_conj: &[C64]) -> ProjectedNonlinearity {
    let mut position = vec![u32::MAX; f.n_vars as usize];
    let mut reads = Vec::new();
    // terms sorted by their monomial, so that repeated monomials are adjacent
    let mut order: Vec<usize> = (0..f.terms.len())
        .filter(|&t| u_conj[f.terms[t].eq as usize] != C64::new(0.0, 0.0))
        .collect();
    let key = |t: usize| f.terms[t].factors.iter().map(|v| (v.var, v.power));
    order.sort_by(|&a, &b| key(a).cmp(key(b)));
    let mut monomials: Vec<WeightedMonomial> = Vec::new();
    let mut factors: Vec<(u32, u32)> = Vec::new();
    let mut previous: Option<usize> = None;
    for t in order {
        let term = &f.terms[t];
        let weight = u_conj[term.eq as usize] * term.coeff;
        if previous.is_some_and(|p| key(p).eq(key(t))) {
            monomials.last_mut().expect("a previous monomial").weight += weight;
            continue;
        }
        previous = Some(t);
        let start = factors.len() as u32;
        for v in term.factors.iter() {
            let slot = &mut position[v.var as usize];
            if *slot == u32::MAX {
                *slot = reads.len() as u32;
                reads.push(v.var as usize);
            }
            factors.push((*slot, v.power));
        }
        monomials.push(WeightedMonomial {
            weight,
            start,
            end: factors.len() as u32,
        });
    }
    (reads, monomials, factors)
}
