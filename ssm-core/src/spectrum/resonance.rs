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
pub(crate) fn for_each_multi_index(len: usize, lo: usize, hi: usize, mut f: impl FnMut(&[u32])) {
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
    let targets: Vec<usize> = (0..ev.len())
        .filter(|&k| !in_e(k) && ev[k].im >= 0.0)
        .collect();
    let sigma = quotients.absolute.unwrap_or(0) as usize;
    let hi57 = order57_within_budget(m, sigma.min(u32::MAX as usize), targets.len());
    for &k in &targets {
        let target = ev[k];
        for equation in [53u8, 57] {
            let found = if equation == 53 {
                lowest_resonance_53(&lam, target, k, order, tol)
            } else {
                let re: Vec<f64> = lam.iter().map(|l| l.re).collect();
                lowest_resonance_57(&re, target.re, k, hi57, tol)
            };
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
    if hi57 < sigma {
        warnings.push(format!(
            "eq. (57) was checked up to order {hi57} of Sigma(E) = {sigma}: with {m} master pairs the combinations grow like order^{}; higher orders matter only for forcing at the amplitudes where they are excited",
            m - 1
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

/// Work allowed for the eq. (57) check, in closed-form interval evaluations
/// summed over all targets (about 0.1 s).
const EQ57_BUDGET: f64 = 2e7;

/// Highest order up to which eq. (57) is checked: `Sigma(E)` itself when the
/// `n_targets * C(K + m - 1, m - 1)` interval evaluations of
/// [`lowest_resonance_57`] fit in [`EQ57_BUDGET`], else the largest `K` that
/// does (one master pair always checks the whole range, at O(1) per target).
fn order57_within_budget(m: usize, sigma: usize, n_targets: usize) -> usize {
    if m <= 1 || n_targets == 0 {
        return sigma;
    }
    // number of prefixes (s_1, ..., s_{m-1}) of total degree <= k
    let prefixes = |k: usize| -> f64 { (1..m).fold(1.0, |acc, j| acc * (k + j) as f64 / j as f64) };
    let fits = |k: usize| n_targets as f64 * prefixes(k) <= EQ57_BUDGET;
    if fits(sigma) {
        return sigma;
    }
    let (mut lo, mut hi) = (0usize, sigma);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The first (lowest-order) `(a, b)` of eq. (53) near `target`, by enumeration
/// of all multi-indices of order `2..=order` (what the expansion itself solves).
fn lowest_resonance_53(
    lam: &[C64],
    target: C64,
    mode: usize,
    order: usize,
    tol: f64,
) -> Option<Resonance> {
    let m = lam.len();
    let mut found: Option<Resonance> = None;
    for_each_multi_index(2 * m, 2, order, |ab| {
        let (a, b) = ab.split_at(m);
        let combo: C64 = (0..m)
            .map(|j| lam[j] * a[j] as f64 + lam[j].conj() * b[j] as f64)
            .sum();
        let distance = (combo - target).norm() / target.norm();
        if distance <= tol {
            match &mut found {
                Some(r) => r.more += 1,
                None => {
                    found = Some(Resonance {
                        equation: 53,
                        mode,
                        a: a.to_vec(),
                        b: b.to_vec(),
                        distance,
                        more: 0,
                    })
                }
            }
        }
    });
    found
}

/// The first (lowest-order, then largest `a` in lexicographic order) solution
/// of eq. (57), `|sum_j (a_j + b_j) Re lambda_j - Re lambda_k| <= tol |Re lambda_k|`
/// with `2 <= |a + b| <= hi`, and the number of further `(a, b)`.
///
/// Only the real parts enter, so a combination depends on `s_j = a_j + b_j`
/// alone (each `s` stands for `prod_j (s_j + 1)` pairs `(a, b)`). All
/// `Re lambda_j < 0`, so partial sums only decrease: the first `m - 1` entries
/// of `s` are enumerated with pruning, and the admissible `s_m` form an
/// interval solved in closed form. The cost is O(1) per target for one master
/// pair whatever `Sigma(E)` is (a lightly damped master mode makes it 1e9), and
/// O(hi^(m-1)) for `m` pairs, instead of the O(hi^(2m-1)) of enumerating `(a, b)`.
fn lowest_resonance_57(re: &[f64], t: f64, mode: usize, hi: usize, tol: f64) -> Option<Resonance> {
    let m = re.len();
    if m == 0 || hi < 2 || t >= 0.0 || re.iter().any(|&r| r >= 0.0) {
        return None;
    }
    let band = tol * t.abs();
    let distance = |s: &[u64]| {
        let c: f64 = s.iter().zip(re).map(|(&k, &r)| r * k as f64).sum();
        (c - t).abs() / t.abs()
    };
    struct Search<'a> {
        re: &'a [f64],
        t: f64,
        band: f64,
        hi: u64,
        tol: f64,
        best: Option<Vec<u64>>,
        count: u128,
    }
    impl Search<'_> {
        fn level(
            &mut self,
            s: &mut Vec<u64>,
            partial: f64,
            deg: u64,
            dist: &dyn Fn(&[u64]) -> f64,
        ) {
            let m = self.re.len();
            let j = s.len();
            if j + 1 == m {
                self.last(s, partial, deg, dist);
                return;
            }
            let mut k = 0u64;
            while deg + k <= self.hi {
                let p = partial + self.re[j] * k as f64;
                // later terms only decrease the sum
                if p < self.t - self.band * (1.0 + 1e-12) - 1e-300 {
                    break;
                }
                s.push(k);
                self.level(s, p, deg + k, dist);
                s.pop();
                k += 1;
            }
        }
        fn last(&mut self, s: &mut Vec<u64>, partial: f64, deg: u64, dist: &dyn Fn(&[u64]) -> f64) {
            let q = -self.re[self.re.len() - 1];
            let lower = ((partial - self.t - self.band) / q).ceil().max(0.0);
            let upper = ((partial - self.t + self.band) / q).floor();
            let min_k = 2u64.saturating_sub(deg);
            let max_k = self.hi - deg;
            if upper.is_nan()
                || lower.is_nan()
                || upper < lower
                || upper < min_k as f64
                || lower > max_k as f64
            {
                return;
            }
            let mut lo = (lower as u64).max(min_k);
            let mut up = (upper.min(max_k as f64)) as u64;
            // the closed form is exact up to rounding: confirm both ends
            let mut probe = |k: u64| {
                s.push(k);
                let ok = dist(s) <= self.tol;
                s.pop();
                ok
            };
            while lo <= up && !probe(lo) {
                lo += 1;
            }
            while up >= lo && !probe(up) {
                if up == 0 {
                    break;
                }
                up -= 1;
            }
            if lo > up || !probe(lo) {
                return;
            }
            while lo > min_k && probe(lo - 1) {
                lo -= 1;
            }
            while up < max_k && probe(up + 1) {
                up += 1;
            }
            let prefix: u128 = s.iter().map(|&k| k as u128 + 1).product();
            let n = (up - lo + 1) as u128;
            let sum_k1 = n * (lo as u128 + up as u128 + 2) / 2;
            self.count = self.count.saturating_add(prefix.saturating_mul(sum_k1));
            let mut cand = s.clone();
            cand.push(lo);
            let better = match &self.best {
                None => true,
                Some(b) => {
                    let (db, dc) = (b.iter().sum::<u64>(), cand.iter().sum::<u64>());
                    dc < db || (dc == db && cand > *b)
                }
            };
            if better {
                self.best = Some(cand);
            }
        }
    }
    let mut search = Search {
        re,
        t,
        band,
        hi: hi as u64,
        tol,
        best: None,
        count: 0,
    };
    search.level(&mut Vec::with_capacity(m), 0.0, 0, &distance);
    let s = search.best?;
    let distance = distance(&s);
    Some(Resonance {
        equation: 57,
        mode,
        a: s.iter().map(|&k| k as u32).collect(),
        b: vec![0; m],
        distance,
        more: usize::try_from(search.count - 1).unwrap_or(usize::MAX),
    })
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

    /// Eq. (57) by brute-force enumeration of every `(a, b)`: the reference
    /// for the closed-form interval search.
    fn brute_57(re: &[f64], t: f64, hi: usize, tol: f64) -> Option<(Vec<u32>, usize)> {
        let m = re.len();
        let mut first: Option<Vec<u32>> = None;
        let mut count = 0usize;
        for_each_multi_index(2 * m, 2, hi, |ab| {
            let (a, b) = ab.split_at(m);
            let c: f64 = (0..m)
                .map(|j| re[j] * a[j] as f64 + re[j] * b[j] as f64)
                .sum();
            if (c - t).abs() / t.abs() <= tol {
                count += 1;
                if first.is_none() {
                    first = Some(ab.to_vec());
                }
            }
        });
        first.map(|f| (f, count - 1))
    }

    /// The interval search finds the same first combination and the same
    /// number of further ones as enumerating all `(a, b)`, for one and two
    /// master pairs over a grid of targets.
    #[test]
    fn eq57_closed_form_matches_enumeration() {
        for (re, hi) in [
            (vec![-0.013], 40usize),
            (vec![-0.01, -0.037], 25),
            (vec![-0.02, -0.031, -0.05], 12),
        ] {
            for k in 1..60 {
                let t = -0.0071 * k as f64;
                let tol = 0.02;
                let fast = lowest_resonance_57(&re, t, 0, hi, tol);
                let slow = brute_57(&re, t, hi, tol);
                match (fast, slow) {
                    (None, None) => {}
                    (Some(r), Some((ab, more))) => {
                        let m = re.len();
                        assert_eq!(r.a, ab[..m].to_vec(), "re {re:?} t {t}");
                        assert_eq!(r.b, ab[m..].to_vec(), "re {re:?} t {t}");
                        assert_eq!(r.more, more, "re {re:?} t {t}");
                    }
                    (f, s) => panic!("re {re:?} t {t}: {f:?} vs {s:?}"),
                }
            }
        }
    }

    /// A master mode with zeta = 1e-9 makes Sigma(E) about 1e9: the check
    /// (which enumerated every combination up to it) now costs O(1) per
    /// target, and finds the resonance `s Re lambda_1 ~ Re lambda_2` at the
    /// order the closed form gives, `ceil(0.98 * 0.05 / 1e-9)`.
    #[test]
    fn lightly_damped_master_is_checked_quickly() {
        let l1 = C64::new(-1e-9, 1.0);
        let l2 = C64::new(-0.05, 3.0);
        let ev = vec![l1, l1.conj(), l2, l2.conj()];
        let rep = check_resonances(&ev, &[0], 5, 0.02, true);
        assert_eq!(rep.quotients.absolute, Some(50_000_000));
        let r57 = rep.resonances.iter().find(|r| r.equation == 57).unwrap();
        let expected = (0.98f64 * 0.05 / 1e-9).ceil() as u32;
        assert!(
            (r57.a[0] as i64 - expected as i64).abs() <= 1,
            "{:?}",
            r57.a
        );
        // two master pairs: the order is capped by the budget, and said so
        let l3 = C64::new(-2e-9, 1.7);
        let ev = vec![l1, l1.conj(), l3, l3.conj(), l2, l2.conj()];
        let rep = check_resonances(&ev, &[0, 2], 5, 0.02, true);
        assert!(
            rep.warnings
                .iter()
                .any(|w| w.contains("eq. (57) was checked up to order")),
            "{:?}",
            rep.warnings
        );
    }
}
