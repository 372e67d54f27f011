//! What is read off an SSM: the polar form of two-dimensional reduced
//! dynamics, backbone curves, and the a-posteriori invariance error.
//!
//! Polar form (flows, one master pair): with `p = rho e^{i theta}` and
//! `R_1(p) = lambda p + sum_j c_j p^{j+1} conj(p)^j`,
//!
//! `rho' = Re(lambda) rho + sum_j Re(c_j) rho^{2j+1}`,
//! `theta' = Im(lambda) + sum_j Im(c_j) rho^{2j}` (eqs. 28-30).
//!
//! For maps the same coefficients give `rho -> rho |mu + sum_j c_j rho^{2j}|`
//! and the backbone frequency `omega = arg(mu + sum_j c_j rho^{2j}) / T`
//! (Szalai et al., eqs. 6.3-6.5, 6.11-6.13).
//!
//! Invariance error (eq. 41): the mean of `||Res(p)||_2 / N` over points on
//! the sphere of radius `varrho` in parametrization space, eq. (39)-(40)
//! generalized to `m` pairs with hyperspherical amplitude angles
//! `rho_1 = varrho cos a_1`, `rho_2 = varrho sin a_1 cos a_2`, ...,
//! each `a_i` on `n_alpha` points of `[0, pi/2]`, and `n_theta` phases per pair.
//!
//! # References
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), eqs. (28)-(30),
//! (39)-(42); R. Szalai, D. Ehrhardt, G. Haller, Proc. R. Soc. A 473 (2017),
//! eqs. (6.3)-(6.7).

use std::f64::consts::PI;

use super::{Dynamics, SsmExpansion};
use crate::model::system::System;
use crate::C64;

/// Coefficients of the polar reduced dynamics of a two-dimensional SSM.
#[derive(Debug, Clone, PartialEq)]
pub struct Polar {
    /// `c_0 = lambda` (or `mu`), `c_1`, `c_2`, ...: coefficient of
    /// `p^{j+1} conj(p)^j` in the equation of `p`.
    pub c: Vec<C64>,
    /// Order `2j + 1` of each coefficient.
    pub orders: Vec<usize>,
}

impl Polar {
    /// `[a1, a3, a5, ...]` of `rho' = a1 rho + a3 rho^3 + ...` (flows).
    pub fn rho_dot(&self) -> Vec<f64> {
        self.c.iter().map(|c| c.re).collect()
    }

    /// `[b0, b2, b4, ...]` of `theta' = b0 + b2 rho^2 + ...` (flows).
    pub fn omega(&self) -> Vec<f64> {
        self.c.iter().map(|c| c.im).collect()
    }

    /// `sum_j c_j rho^{2j}` over the terms of order `<= order`.
    pub fn factor(&self, rho: f64, order: usize) -> C64 {
        self.c
            .iter()
            .zip(&self.orders)
            .filter(|(_, &o)| o <= order)
            .map(|(c, &o)| c * rho.powi(o as i32 - 1))
            .sum()
    }
}

/// Why the polar form does not exist.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolarError {
    /// More than one master pair.
    #[error("the polar form and backbone curves need exactly one master pair (found {pairs})")]
    NotTwoDimensional {
        /// Number of pairs.
        pairs: usize,
    },
    /// A reduced-dynamics term that is not of the form `p^{j+1} conj(p)^j`.
    #[error("reduced-dynamics term with exponents {exponents:?} is not a backbone term p^(j+1) conj(p)^j")]
    NotPolar {
        /// Exponents.
        exponents: Vec<u16>,
    },
}

/// Polar coefficients of a two-dimensional SSM (one master pair).
pub fn polar(ssm: &SsmExpansion) -> Result<Polar, PolarError> {
    if ssm.dim() != 2 {
        return Err(PolarError::NotTwoDimensional {
            pairs: ssm.dim() / 2,
        });
    }
    let mut terms: Vec<(usize, C64)> = vec![(1, ssm.lambda[0])];
    for t in ssm.nonlinear_terms().filter(|t| t.coord == 0) {
        let e = ssm.set.exponents(t.index);
        if e[0] != e[1] + 1 {
            return Err(PolarError::NotPolar {
                exponents: e.to_vec(),
            });
        }
        terms.push(((e[0] + e[1]) as usize, t.coeff));
    }
    terms.sort_by_key(|t| t.0);
    // fill missing orders with zeros so that index j is always the rho^{2j+1} term
    let highest_odd = if ssm.order % 2 == 1 {
        ssm.order
    } else {
        ssm.order - 1
    };
    let max = terms.last().map_or(1, |t| t.0).max(highest_odd);
    let mut c = Vec::new();
    let mut orders = Vec::new();
    for o in (1..=max).step_by(2) {
        c.push(
            terms
                .iter()
                .find(|t| t.0 == o)
                .map_or(C64::new(0.0, 0.0), |t| t.1),
        );
        orders.push(o);
    }
    Ok(Polar { c, orders })
}

/// Instantaneous frequency on the backbone at amplitude `rho`, expansion
/// truncated at `order`.
pub fn backbone_frequency(ssm: &SsmExpansion, polar: &Polar, rho: f64, order: usize) -> f64 {
    let f = polar.factor(rho, order);
    match ssm.dynamics {
        Dynamics::Flow => f.im,
        Dynamics::Map { period } => f.arg() / period,
    }
}

/// `max over theta of |s(rho e^{i theta}, rho e^{-i theta})|` for a scalar
/// series `s` (an output of `W`) truncated at `order`: 96 samples, then a
/// golden-section refinement around the best one.
pub fn amplitude(ssm: &SsmExpansion, series: &[C64], rho: f64, order: usize) -> f64 {
    let eval = |theta: f64| -> f64 {
        let q = C64::from_polar(rho, theta);
        let mono = ssm.set.monomials(&[q, q.conj()], order);
        let end = ssm.set.of_order(order.min(ssm.order)).end;
        (0..end).map(|i| series[i] * mono[i]).sum::<C64>().re.abs()
    };
    let n = 96;
    let h = 2.0 * PI / n as f64;
    let (mut best_t, mut best) = (0.0, eval(0.0));
    for i in 1..n {
        let t = i as f64 * h;
        let v = eval(t);
        if v > best {
            best = v;
            best_t = t;
        }
    }
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (best_t - h, best_t + h);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (eval(c), eval(d));
    for _ in 0..40 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = eval(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = eval(d);
        }
    }
    best.max(fc).max(fd)
}

/// Sample points of eq. (39)-(40) generalized to `m` pairs, radius `radius`.
pub(crate) fn sphere_points(
    m: usize,
    radius: f64,
    n_alpha: usize,
    n_theta: usize,
) -> Vec<Vec<C64>> {
    let n_alpha = n_alpha.max(2);
    let alpha: Vec<f64> = (0..n_alpha)
        .map(|i| i as f64 * PI / (2.0 * (n_alpha - 1) as f64))
        .collect();
    let theta: Vec<f64> = (0..n_theta)
        .map(|j| 2.0 * PI * j as f64 / n_theta as f64)
        .collect();
    // amplitude vectors on the positive orthant of the (m-1)-sphere
    let mut amps: Vec<Vec<f64>> = vec![vec![radius]];
    for _ in 1..m {
        let mut next = Vec::with_capacity(amps.len() * n_alpha);
        for a in &amps {
            let last = *a.last().expect("non-empty");
            for &al in &alpha {
                let mut v = a[..a.len() - 1].to_vec();
                v.push(last * al.cos());
                v.push(last * al.sin());
                next.push(v);
            }
        }
        amps = next;
    }
    let mut points = Vec::new();
    let mut phase_idx = vec![0usize; m];
    for a in &amps {
        phase_idx.iter_mut().for_each(|x| *x = 0);
        loop {
            let mut p = Vec::with_capacity(2 * m);
            for i in 0..m {
                let q = C64::from_polar(a[i], theta[phase_idx[i]]);
                p.push(q);
                p.push(q.conj());
            }
            points.push(p);
            let mut i = 0;
            while i < m {
                phase_idx[i] += 1;
                if phase_idx[i] < n_theta {
                    break;
                }
                phase_idx[i] = 0;
                i += 1;
            }
            if i == m {
                break;
            }
        }
    }
    points
}

/// Invariance error of eq. (41) at `radius` for the expansion truncated at `order`
/// (points evaluated in parallel).
pub fn invariance_error(
    ssm: &SsmExpansion,
    sys: &System,
    order: usize,
    radius: f64,
    n_alpha: usize,
    n_theta: usize,
) -> f64 {
    let points = sphere_points(ssm.dim() / 2, radius, n_alpha, n_theta);
    let n = ssm.n_states() as f64;
    // sample points are independent: spread over the cores in groups
    // (SsmExpansion::residuals), then summed in the points' order (the same
    // bits on any number of threads and in every run)
    let norms: Vec<f64> = ssm
        .residuals(sys, &points, order)
        .iter()
        .map(|r| r.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt())
        .collect();
    norms.iter().sum::<f64>() / (n * points.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_points_have_the_radius_and_count_of_eq_39() {
        let pts = sphere_points(2, 0.3, 10, 30);
        assert_eq!(pts.len(), 10 * 30 * 30);
        for p in &pts {
            let r2: f64 = p.iter().step_by(2).map(|q| q.norm_sqr()).sum();
            assert!((r2.sqrt() - 0.3).abs() < 1e-14);
            assert_eq!(p[1], p[0].conj());
        }
        assert_eq!(sphere_points(1, 1.0, 10, 30).len(), 30);
        assert_eq!(sphere_points(3, 1.0, 4, 5).len(), 16 * 125);
    }
}
