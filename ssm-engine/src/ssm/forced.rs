//! The periodic SSM of a harmonically forced flow at leading order in `eps`
//! (eqs. 19-20 and 60).
//!
//! With `Fext(z, phi) = sum_h cos_h cos(kappa_h phi) + sin_h sin(kappa_h phi)`,
//! each harmonic is `F_h e^{i kappa_h phi} + c.c.` with `F_h = (cos_h(0) - i sin_h(0)) / 2`.
//! Inserting `W_eps = W(p) + eps X0(phi)`, `R_eps = R(p) + eps S0(phi)` with
//! `X0 = sum_h x_h e^{i kappa_h phi} + c.c.`, `S0 = sum_h s_h e^{i kappa_h phi} + c.c.`
//! into eq. (60) and collecting `eps p^0 e^{i kappa_h phi}` gives
//!
//! `(i kappa_h Omega B - A) x_h + B V s_h = F_h`,
//!
//! the homological equation of [`super::homological`] at `Lambda = i kappa_h Omega`.
//! Normal-form style: `s_h` has a component on the master coordinate `p_j`
//! exactly when the harmonic is externally resonant with it, `kappa_h = r_j`
//! for the resonance ratio vector `r` of eq. (16) (`lambda_j ~ i r_j Omega`);
//! those components are `s_{h,j} = u_j^* F_h` and the rest of the response
//! goes into `x_h`, closed by `u_j^* B x_h = 0`. In the rotating frame
//! `p_j = q_j e^{i r_j Omega t}` the reduced dynamics are then autonomous.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), eqs. (16), (19)-(20),
//! (59)-(61); M. Li, S. Jain, G. Haller, *Nonlinear analysis of forced mechanical
//! systems with internal resonance using spectral submanifolds, Part I*,
//! Nonlinear Dyn. 110 (2022), Sect. 3.

use ssm_api::PolyVector;

use super::homological::{Homological, HomologicalError};
use super::reduced_modes;
use crate::spectrum::MasterMode;
use crate::system::System;
use crate::C64;

/// Why the forced SSM could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ForcedError {
    /// The model has no forcing.
    #[error("the model defines no external forcing (Fext); a forced response needs one")]
    NoForcing,
    /// The resonance ratios do not match the master pairs.
    #[error("{found} resonance ratios for {pairs} master pairs")]
    Ratios {
        /// Ratios given.
        found: usize,
        /// Master pairs.
        pairs: usize,
    },
    /// A harmonic's homological equation failed.
    #[error("harmonic {harmonic} at Omega = {omega}: {source}")]
    Solve {
        /// 1-based harmonic.
        harmonic: usize,
        /// Forcing frequency.
        omega: f64,
        /// Cause.
        source: HomologicalError,
    },
}

/// One forcing harmonic's leading-order terms at one `Omega`.
#[derive(Debug, Clone)]
pub struct ForcedHarmonic {
    /// `kappa_h`: frequency as a multiple of `Omega`.
    pub multiple: f64,
    /// `x_h`: coefficient of `e^{i kappa_h phi}` in `X0` (`N` states).
    pub x: Vec<C64>,
    /// `s_h`: coefficient of `e^{i kappa_h phi}` in `S0`, per reduced coordinate
    /// (`p1, conj p1, p2, ...`); zero where not externally resonant.
    pub s: Vec<C64>,
}

/// `X0`, `S0` at one forcing frequency.
#[derive(Debug, Clone)]
pub struct ForcedTerms {
    /// Forcing frequency `Omega`.
    pub omega: f64,
    /// One entry per forcing harmonic.
    pub harmonics: Vec<ForcedHarmonic>,
}

impl ForcedTerms {
    /// The scalar output `sum w_s X0_s` at phase `phi` (real).
    pub fn output_at(&self, weights: &[(usize, f64)], phi: f64) -> f64 {
        self.harmonics
            .iter()
            .map(|h| {
                let c: C64 = weights.iter().map(|&(s, w)| h.x[s] * w).sum();
                2.0 * (c * C64::from_polar(1.0, h.multiple * phi)).re
            })
            .sum()
    }

    /// Total forcing `eps * S0` coefficient on reduced coordinate `j` at ratio
    /// `r_j` (the sum over harmonics resonant with it).
    pub fn resonant_forcing(&self, coord: usize) -> C64 {
        self.harmonics.iter().map(|h| h.s[coord]).sum()
    }
}

/// Value of a forcing polynomial at the origin (its constant terms).
fn at_origin(p: &PolyVector, n: usize) -> Vec<f64> {
    let mut v = vec![0.0; n];
    for t in p.terms.iter().filter(|t| t.factors.is_empty()) {
        v[t.eq as usize] += t.coeff;
    }
    v
}

/// The leading-order periodic SSM of one system and master set, evaluated at
/// any forcing frequency; one symbolic LU serves every frequency.
pub struct ForcedSsm<'a> {
    solver: Homological<'a>,
    forcing: Vec<(f64, Vec<C64>, Vec<usize>)>,
    n_coords: usize,
}

impl<'a> ForcedSsm<'a> {
    /// Prepares the forcing amplitudes `F_h` and the resonant sets for master
    /// modes `masters` with external resonance ratios `ratios` (one per master
    /// pair, eq. 16).
    pub fn new(
        sys: &'a System,
        masters: &[MasterMode],
        ratios: &[f64],
    ) -> Result<Self, ForcedError> {
        if sys.forcing.is_empty() {
            return Err(ForcedError::NoForcing);
        }
        if ratios.len() != masters.len() {
            return Err(ForcedError::Ratios {
                found: ratios.len(),
                pairs: masters.len(),
            });
        }
        let n = sys.n_states();
        let (lambda, right, left) = reduced_modes(masters);
        let solver = Homological::new(sys.a.as_ref(), sys.b.as_ref(), &lambda, &right, &left);
        let forcing = sys
            .forcing
            .iter()
            .map(|h| {
                let c = at_origin(&h.cos, n);
                let s = at_origin(&h.sin, n);
                let f: Vec<C64> = c
                    .iter()
                    .zip(&s)
                    .map(|(&c, &s)| C64::new(0.5 * c, -0.5 * s))
                    .collect();
                // e^{i kappa phi} resonates with p_j when kappa = r_j (never with conj p_j)
                let set: Vec<usize> = ratios
                    .iter()
                    .enumerate()
                    .filter(|(_, &r)| (r - h.multiple).abs() <= 1e-12 * r.abs().max(1.0))
                    .map(|(pair, _)| 2 * pair)
                    .collect();
                (h.multiple, f, set)
            })
            .collect();
        Ok(Self {
            solver,
            forcing,
            n_coords: lambda.len(),
        })
    }

    /// `X0`, `S0` at forcing frequency `omega`.
    pub fn at(&mut self, omega: f64) -> Result<ForcedTerms, ForcedError> {
        let mut harmonics = Vec::with_capacity(self.forcing.len());
        for (k, (multiple, f, set)) in self.forcing.iter().enumerate() {
            let big = C64::new(0.0, multiple * omega);
            let (x, r) = self
                .solver
                .solve(big, set, f)
                .map_err(|source| ForcedError::Solve {
                    harmonic: k + 1,
                    omega,
                    source,
                })?;
            let mut s = vec![C64::new(0.0, 0.0); self.n_coords];
            for (&j, v) in set.iter().zip(r) {
                s[j] = v;
            }
            harmonics.push(ForcedHarmonic {
                multiple: *multiple,
                x,
                s,
            });
        }
        self.solver.clear_numeric();
        Ok(ForcedTerms { omega, harmonics })
    }
}

/// Residual of the invariance equation (60) of the leading-order periodic SSM
/// truncated at `order`, at reduced point `p` and phase `phi`:
///
/// `B [DW(p) (R(p) + eps S0(phi)) + eps Omega X0'(phi)]
///  - A (W(p) + eps X0(phi)) - F(W(p) + eps X0(phi)) - eps Fext(phi)`.
///
/// The neglected terms `O(eps |p|)` and `O(eps^2)` are what remains (Fig. 6).
pub fn residual(
    ssm: &super::SsmExpansion,
    sys: &System,
    terms: &ForcedTerms,
    eps: f64,
    p: &[C64],
    phi: f64,
    order: usize,
) -> Vec<C64> {
    use crate::poly::eval_poly;
    use crate::spectrum::modes::spmv;
    let order = order.min(ssm.order);
    let n = sys.n_states();
    let nvar = p.len();
    // S0(phi) per reduced coordinate, X0(phi) and its phase derivative
    let mut s0 = vec![C64::new(0.0, 0.0); nvar];
    let mut x0 = vec![C64::new(0.0, 0.0); n];
    let mut dx0 = vec![C64::new(0.0, 0.0); n];
    for h in &terms.harmonics {
        let e = C64::from_polar(1.0, h.multiple * phi);
        for (j, s) in h.s.iter().enumerate() {
            // conj p_j carries the conjugate harmonic
            let (src, ph) = if j % 2 == 0 {
                (*s, e)
            } else {
                (h.s[j - 1].conj(), e.conj())
            };
            s0[j] += src * ph;
        }
        for i in 0..n {
            let c = h.x[i] * e;
            x0[i] += 2.0 * c.re;
            dx0[i] += 2.0 * (c * C64::new(0.0, h.multiple)).re;
        }
    }
    let mono = ssm.set.monomials(p, order);
    let w = ssm.w_at(&mono, order);
    let mut r = ssm.r_at(&mono, order);
    for (rv, sv) in r.iter_mut().zip(&s0) {
        *rv += eps * sv;
    }
    // DW(p) r = sum_k w_k sum_v k_v p^{k - e_v} r_v
    let mut lhs = vec![C64::new(0.0, 0.0); n];
    let end = ssm.set.of_order(order).end;
    for idx in ssm.set.of_order(1).start..end {
        let e = ssm.set.exponents(idx);
        let mut s = C64::new(0.0, 0.0);
        for (v, &ev) in e.iter().enumerate() {
            if ev > 0 {
                let low = ssm.set.lower(idx, v).expect("k_v > 0");
                s += mono[low] * r[v] * f64::from(ev);
            }
        }
        for (l, wk) in lhs.iter_mut().zip(&ssm.w[idx]) {
            *l += s * wk;
        }
    }
    for (l, d) in lhs.iter_mut().zip(&dx0) {
        *l += eps * terms.omega * d;
    }
    let z: Vec<C64> = w.iter().zip(&x0).map(|(a, b)| a + eps * b).collect();
    let mut res = spmv(sys.b.as_ref(), &lhs);
    let az = spmv(sys.a.as_ref(), &z);
    let mut fz = vec![C64::new(0.0, 0.0); n];
    eval_poly(&sys.nonlinearity, &z, &mut fz);
    let mut fext = vec![C64::new(0.0, 0.0); n];
    for h in &sys.forcing {
        let (c, s) = ((h.multiple * phi).cos(), (h.multiple * phi).sin());
        let mut fc = vec![C64::new(0.0, 0.0); n];
        let mut fs = vec![C64::new(0.0, 0.0); n];
        eval_poly(&h.cos, &z, &mut fc);
        eval_poly(&h.sin, &z, &mut fs);
        for i in 0..n {
            fext[i] += c * fc[i] + s * fs[i];
        }
    }
    for i in 0..n {
        res[i] -= az[i] + fz[i] + eps * fext[i];
    }
    res
}
