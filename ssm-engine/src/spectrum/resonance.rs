//! Spectral quotients (eqs. 54, 58) and the non-resonance conditions of
//! Theorems 1-2 (eqs. 53, 57) for a master subspace `E` of mode pairs.
//!
//! - eq. (53): `a . lambda_E + b . conj(lambda_E) != lambda_k` for every finite
//!   `lambda_k` outside `E` and `2 <= |a + b|`. A near-equality makes the
//!   homological equation `(Lambda B - A) w = rhs` at that multi-index nearly
//!   singular in the direction of mode `k`, so it is checked for every
//!   `|a + b|` up to the requested expansion order.
//! - eq. (57): the same with real parts, for `2 <= |a + b| <= Sigma(E)`; it
//!   governs the periodic SSM under forcing.
//!
//! A combination counts as (near) resonant when its distance to `lambda_k` is
//! below `tol |lambda_k|` (eq. 53) or `tol |Re lambda_k|` (eq. 57). Only one
//! member of each conjugate pair is tested: `a.lambda + b.conj(lambda) ~ conj(lambda_k)`
//! is the same condition as `b.lambda + a.conj(lambda) ~ lambda_k`.
//!
//! # References
//! M. Li, S. Jain, G. Haller (2023), Appendix A, Theorems 1-2, eqs. (53)-(58);
//! G. Haller, S. Ponsioen, *Nonlinear normal modes and spectral submanifolds*,
//! Nonlinear Dyn. 86 (2016) 1493-1534.

use crate::C64;

/// Spectral quotients of the master subspace.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralQuotients {
    /// Relative spectral quotient `sigma(E)`, eq. (54) (`None` when no mode lies
    /// outside `E` or a master mode is not damped).
    pub relative: Option<u64>,
    /// Absolute spectral quotient `Sigma(E)`, eq. (58).
    pub absolute: Option<u64>,
    /// False when computed over a partial spectrum (sparse path): then the
    /// values are lower bounds.
    pub complete: bool,
}

/// One detected (near) resonance.
#[derive(Debug, Clone, PartialEq)]
pub struct Resonance {
    /// Which condition: 53 or 57.
    pub equation: u8,
    /// 0-based index of the non-master eigenvalue in the sorted spectrum.
    pub mode: usize,
    /// Exponents `a` on the master eigenvalues, one per master pair.
    pub a: Vec<u32>,
    /// Exponents `b` on their conjugates.
    pub b: Vec<u32>,
    /// Relative distance.
    pub distance: f64,
    /// Number of further (higher-order) combinations near the same eigenvalue.
    pub more: usize,
}

/// Quotients, resonances and the warnings they produce.
#[derive(Debug, Clone)]
pub struct ResonanceReport {
    /// Spectral quotients.
    pub quotients: SpectralQuotients,
    /// Lowest-order (near) resonance per non-master eigenvalue and condition.
    pub resonances: Vec<Resonance>,
    /// Human-readable warnings naming each resonance.
    pub warnings: Vec<String>,
}

/// Calls `f` with every multi-index of length `len` and total degree in `lo..=hi`,
/// by increasing degree.
pub fn for_each_multi_index(len: usize, lo: usize, hi: usize, mut f: impl FnMut(&[u32])) {
    fn rec(idx: &mut Vec<u32>, pos: usize, left: u32, f: &mut dyn FnMut(&[u32])) {
        if pos + 1 == idx.len() {
            idx[pos] = left;
            f(idx);
            return;
        }
        for k in (0..=left).rev() {
            idx[pos] = k;
            rec(idx, pos + 1, left - k, f);
        }
    }
    if len == 0 {
        return;
    }
    let mut idx = vec![0u32; len];
    for d in lo..=hi {
        rec(&mut idx, 0, d as u32, &mut f);
    }
}

/// Checks eqs. (53) and (57) for master pairs starting at `master_indices`
/// (0-based positions of the positive-imaginary members in the sorted spectrum
/// `ev`), up to expansion order `order`.
pub fn check_resonances(
    ev: &[C64],
    master_indices: &[usize],
    order: usize,
    tol: f64,
    complete: bool,
) -> ResonanceReport {
    let in_e = |k: usize| master_indices.iter().any(|&i| k == i || k == i + 1);
    let lam: Vec<C64> = master_indices.iter().map(|&i| ev[i]).collect();
    let max_re_e = lam.iter().map(|l| l.re).fold(f64::NEG_INFINITY, f64::max);
    let min_re_out = (0..ev.len())
        .filter(|&k| !in_e(k))
        .map(|k| ev[k].re)
        .fold(f64::INFINITY, f64::min);
    let min_re_all = ev.iter().map(|l| l.re).fold(f64::INFINITY, f64::min);
    let quotient = |num: f64| {
        (max_re_e < 0.0 && num.is_finite() && num < 0.0)
            .then(|| (num / max_re_e + 1e-9).floor() as u64)
    };
    let quotients = SpectralQuotients {
        relative: quotient(min_re_out),
        absolute: quotient(min_re_all),
        complete,
    };
    let name = |k: usize| format!("lambda_{}", k + 1);
    let combo = |a: &[u32], b: &[u32]| {
        let mut parts = Vec::new();
        for (j, &i) in master_indices.iter().enumerate() {
            if a[j] > 0 {
                parts.push(format!("{} {}", a[j], name(i)));
            }
            if b[j] > 0 {
                parts.push(format!("{} conj({})", b[j], name(i)));
            }
        }
        parts.join(" + ")
    };
    let pair_of = |k: usize| ev[..=k].iter().filter(|l| l.im > 0.0).count();
    let m = master_indices.len();
    let mut resonances: Vec<Resonance> = Vec::new();
    let mut warnings = Vec::new();
    let mut skipped57 = 0usize;
    for k in (0..ev.len()).filter(|&k| !in_e(k) && ev[k].im >= 0.0) {
        let target = ev[k];
        for (equation, hi) in [
            (53u8, order),
            (57u8, quotients.absolute.unwrap_or(0) as usize),
        ] {
            let mut found: Option<Resonance> = None;
            for_each_multi_index(2 * m, 2, hi, |ab| {
                let (a, b) = ab.split_at(m);
                let combo_val: C64 = (0..m)
                    .map(|j| lam[j] * a[j] as f64 + lam[j].conj() * b[j] as f64)
                    .sum();
                let distance = if equation == 53 {
                    (combo_val - target).norm() / target.norm()
                } else {
                    (combo_val.re - target.re).abs() / target.re.abs()
                };
                if distance <= tol {
                    match &mut found {
                        Some(r) => r.more += 1,
                        None => {
                            found = Some(Resonance {
                                equation,
                                mode: k,
                                a: a.to_vec(),
                                b: b.to_vec(),
                                distance,
                                more: 0,
                            })
                        }
                    }
                }
            });
            if let Some(r) = found {
                let fix = if target.im > 0.0 {
                    format!("add pair {} to the master pairs", pair_of(k))
                } else {
                    "the resonant mode is real (overdamped); choose other master pairs".to_owned()
                };
                let what = if equation == 53 {
                    format!(
                        "{} ~ {} (relative distance {:.1e}, order {})",
                        name(k),
                        combo(&r.a, &r.b),
                        r.distance,
                        r.a.iter().chain(&r.b).sum::<u32>()
                    )
                } else {
                    format!(
                        "Re {} ~ Re({}) (relative distance {:.1e}; eq. 57, matters under forcing)",
                        name(k),
                        combo(&r.a, &r.b),
                        r.distance
                    )
                };
                let more = if r.more > 0 {
                    format!(" and {} higher-order combinations", r.more)
                } else {
                    String::new()
                };
                if equation == 57 && resonances.iter().filter(|r| r.equation == 57).count() >= 3 {
                    skipped57 += 1;
                } else {
                    warnings.push(format!("near resonance {what}{more}: {fix}"));
                }
                resonances.push(r);
            }
        }
    }
    if skipped57 > 0 {
        warnings.push(format!(
            "{skipped57} more modes have near resonances of eq. (57) (real parts only; they matter under forcing); the three closest to the master modes are listed above"
        ));
    }
    if max_re_e >= 0.0 {
        warnings.push(
            "a master mode is not damped (Re lambda >= 0): spectral quotients are undefined and the SSM theory of Theorems 1-2 does not apply".to_owned(),
        );
    }
    ResonanceReport {
        quotients,
        resonances,
        warnings,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn multi_indices_are_complete() {
        let mut count = 0;
        for_each_multi_index(4, 2, 3, |_| count += 1);
        // C(4+1,3) + C(4+2,3) = 10 + 20
        assert_eq!(count, 30);
    }

    /// Two pairs with lambda_3 = 2 lambda_1 + conj(lambda_1) exactly (up to the
    /// damping): the warning names it and suggests adding pair 2.
    #[test]
    fn one_to_one_resonance_is_named() {
        let l1 = C64::new(-0.01, 1.0);
        let l3 = 2.0 * l1 + l1.conj();
        let ev = vec![l1, l1.conj(), l3, l3.conj()];
        let rep = check_resonances(&ev, &[0], 5, 1e-6, true);
        let r53: Vec<_> = rep.resonances.iter().filter(|r| r.equation == 53).collect();
        assert_eq!(r53.len(), 1);
        assert_eq!(r53[0].a, vec![2]);
        assert_eq!(r53[0].b, vec![1]);
        assert!(rep.warnings[0].contains("lambda_3 ~ 2 lambda_1 + 1 conj(lambda_1)"));
        assert!(rep.warnings[0].contains("add pair 2"));
        // eq. (54): Int(Re l3 / Re l1) = Int(-0.03 / -0.01) = 3
        assert_eq!(rep.quotients.relative, Some(3));
    }
}
