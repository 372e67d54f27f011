//! The identified sampling map as a discrete-time [`Model`], and its linear
//! figures: multipliers, frequencies, damping ratios and the relative
//! spectral quotients (5.4) of each mode pair.
//!
//! The map acts on delay vectors `xi = (y_k, ..., y_{k + 2 nu - 1})`:
//! `F_i(xi) = xi_{i+1}` for `i < 2 nu` and `F_{2 nu}(xi) = sum_m a_m xi^m`,
//! so `A = DF(0)` is a companion matrix whose eigenvalues are the multipliers
//! `mu = e^{lambda T}` of (4.2), (5.3).
//!
//! # References
//! R. Szalai, D. Ehrhardt, G. Haller, Proc. R. Soc. A 473 (2017) 20160759,
//! eqs. (3.1)-(3.2), (4.2), (5.3)-(5.4), (5.10).

use faer::{c64, Mat};
use ssm_api::{
    ExprVector, Model, MotionKind, Output, PolyVector, SparseMatrix, StateInfo, StateKind,
    TimeKind, Weight,
};

use crate::embedding::MonomialBasis;

/// Relative slack of the integer part in (5.4): identified multipliers carry
/// errors, and a ratio that is an integer in the true system (3 for the
/// Shaw-Pierre example of Sect. 9a) comes out just below it; the larger
/// quotient is the cautious one (it asks more smoothness of the SSM).
pub const QUOTIENT_SLACK: f64 = 1e-3;

/// Linear figures of one underdamped pair of the identified map.
#[derive(Debug, Clone, PartialEq)]
pub struct PairFigures {
    /// Multiplier `mu` with positive imaginary part.
    pub multiplier: c64,
    /// `lambda = log(mu) / T`.
    pub lambda: c64,
    /// Undamped natural frequency `|lambda|` (rad per unit time).
    pub omega: f64,
    /// Damping ratio `-Re lambda / |lambda|`.
    pub zeta: f64,
    /// Ratio of the strongest decay outside the pair to the decay inside it,
    /// `min_j log|mu_j| / log|mu_l|` (the argument of Int in (5.4)).
    pub decay_ratio: f64,
    /// Relative spectral quotient `sigma(E)` (5.4): the integer part of
    /// `decay_ratio`, where a ratio within [`QUOTIENT_SLACK`] below an
    /// integer counts as that integer.
    pub spectral_quotient: f64,
}

/// Multipliers of the identified map.
#[derive(Debug, Clone)]
pub struct Linear {
    /// All multipliers (eigenvalues of the companion matrix).
    pub multipliers: Vec<c64>,
    /// Underdamped pairs, slowest (lowest frequency) first.
    pub pairs: Vec<PairFigures>,
}

/// The companion matrix `A` of the fitted map (`dim x dim`, dense).
pub fn companion(basis: &MonomialBasis, coefficients: &[f64]) -> Mat<f64> {
    let dim = basis.n_vars;
    let mut a = Mat::<f64>::zeros(dim, dim);
    for i in 0..dim - 1 {
        a[(i, i + 1)] = 1.0;
    }
    for (k, e) in basis.exponents.iter().enumerate() {
        if basis.degree(k) == 1 {
            let v = e.iter().position(|&x| x == 1).unwrap_or(0);
            a[(dim - 1, v)] = coefficients[k];
        }
    }
    a
}

/// Multipliers, pairs and spectral quotients of `A` with sampling period `period`.
pub fn linear_figures(a: &Mat<f64>, period: f64) -> Option<Linear> {
    let multipliers = a.eigenvalues().ok()?;
    let log_mod = |m: &c64| m.norm().ln();
    let mut pairs: Vec<PairFigures> = Vec::new();
    for (i, mu) in multipliers.iter().enumerate() {
        if mu.im <= 0.0 {
            continue;
        }
        let lambda = c64::new(mu.norm().ln(), mu.im.atan2(mu.re)) / period;
        // strongest decay outside the pair over the decay inside it (5.4)
        let conj = multipliers
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .min_by(|a, b| {
                (*a.1 - mu.conj())
                    .norm()
                    .total_cmp(&(*b.1 - mu.conj()).norm())
            })
            .map(|(j, _)| j);
        let fastest = multipliers
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i && Some(*j) != conj)
            .map(|(_, m)| log_mod(m))
            .fold(f64::INFINITY, f64::min);
        let inside = log_mod(mu);
        let decay_ratio = if inside < 0.0 { fastest / inside } else { 0.0 };
        let spectral_quotient = if decay_ratio.is_finite() {
            (decay_ratio * (1.0 + QUOTIENT_SLACK)).floor().max(0.0)
        } else {
            f64::INFINITY
        };
        pairs.push(PairFigures {
            multiplier: *mu,
            lambda,
            omega: lambda.norm(),
            zeta: -lambda.re / lambda.norm(),
            decay_ratio,
            spectral_quotient,
        });
    }
    pairs.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    Some(Linear { multipliers, pairs })
}

/// The map model: states `xi_1 .. xi_{2 nu}` named `<obs>[k]`, `<obs>[k+1]`,
/// ..., the output `<obs>` = `xi_1`.
pub fn map_model(
    observable: &str,
    basis: &MonomialBasis,
    coefficients: &[f64],
    period: f64,
) -> Model {
    let dim = basis.n_vars;
    let a_dense = companion(basis, coefficients);
    let mut a = SparseMatrix::zeros(dim, dim);
    for c in 0..dim {
        for r in 0..dim {
            if a_dense[(r, c)] != 0.0 {
                a.push(r, c, a_dense[(r, c)]);
            }
        }
    }
    let mut f = PolyVector::zeros(dim, dim);
    for (k, e) in basis.exponents.iter().enumerate() {
        if basis.degree(k) >= 2 && coefficients[k] != 0.0 {
            let factors: Vec<(usize, u32)> = e
                .iter()
                .enumerate()
                .filter(|(_, &p)| p > 0)
                .map(|(v, &p)| (v, p))
                .collect();
            f.push(dim - 1, coefficients[k], &factors);
        }
    }
    let states = (0..dim)
        .map(|j| StateInfo {
            name: if j == 0 {
                format!("{observable}[k]")
            } else {
                format!("{observable}[k+{j}]")
            }
            .as_str()
            .into(),
            kind: StateKind::Other,
            motion: MotionKind::Unspecified,
        })
        .collect();
    Model {
        name: format!("NAR map of {observable} (2nu = {dim})")
            .as_str()
            .into(),
        a,
        b: SparseMatrix::diagonal(&vec![1.0; dim]),
        nonlinearity: f,
        forcing: Default::default(),
        states,
        outputs: vec![Output {
            name: observable.into(),
            weights: vec![Weight {
                state: 0,
                value: 1.0,
            }]
            .into_iter()
            .collect(),
        }]
        .into_iter()
        .collect(),
        time: TimeKind::Map { period },
        mechanical: None.into(),
        expressions: ExprVector::zeros(dim, dim),
        equilibrium: Default::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The companion matrix of a sampled damped oscillator pair has the
    /// multipliers `e^{lambda T}` (closed form), and the figures recover
    /// `omega` and `zeta` to rounding.
    #[test]
    fn companion_multipliers_give_frequency_and_damping() {
        let (omega, zeta, t) = (1.3f64, 0.02f64, 0.4f64);
        let lambda = c64::new(-zeta * omega, omega * (1.0 - zeta * zeta).sqrt());
        let mu = (lambda * t).exp();
        // y_{k+2} = 2 Re(mu) y_{k+1} - |mu|^2 y_k
        let basis = MonomialBasis::new(2, 1);
        let a = companion(&basis, &[-mu.norm_sqr(), 2.0 * mu.re]);
        let lin = linear_figures(&a, t).unwrap();
        assert_eq!(lin.pairs.len(), 1);
        let p = &lin.pairs[0];
        assert!((p.omega - omega).abs() < 1e-12 * omega);
        assert!((p.zeta - zeta).abs() < 1e-12);
    }

    /// Two pairs with decay rates 1 and 3.5 have spectral quotients
    /// Int[3.5] = 3 (slow pair) and 0 (fast pair), eq. (5.4).
    #[test]
    fn spectral_quotients_follow_eq_5_4() {
        let t = 0.5;
        let l1 = c64::new(-0.01, 1.0);
        let l2 = c64::new(-0.035, 1.7);
        let (m1, m2) = ((l1 * t).exp(), (l2 * t).exp());
        // characteristic polynomial (z - m1)(z - m1*)(z - m2)(z - m2*)
        let p1 = [m1.norm_sqr(), -2.0 * m1.re, 1.0];
        let p2 = [m2.norm_sqr(), -2.0 * m2.re, 1.0];
        let mut poly = [0.0; 5];
        for i in 0..3 {
            for j in 0..3 {
                poly[i + j] += p1[i] * p2[j];
            }
        }
        let basis = MonomialBasis::new(4, 1);
        let coeffs: Vec<f64> = (0..4).map(|k| -poly[k]).collect();
        let lin = linear_figures(&companion(&basis, &coeffs), t).unwrap();
        assert_eq!(lin.pairs.len(), 2);
        assert_eq!(lin.pairs[0].spectral_quotient, 3.0);
        assert_eq!(lin.pairs[1].spectral_quotient, 0.0);
    }
}
