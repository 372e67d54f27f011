//! Sparse multivariate polynomials with exact symbolic arithmetic, the working
//! representation of the recast (sums, products, powers, partial derivatives).
//!
//! `poly::MultiIndexSet` indexes *all* monomials of a few reduced coordinates; the
//! recast instead works with a handful of monomials in thousands of states, so
//! it keeps a sorted map from sparse monomials to coefficients.

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;

/// A monomial: `(variable, power)` pairs sorted by variable, powers >= 1.
pub type Mono = Vec<(u32, u32)>;

/// A sparse polynomial `sum_m c_m z^m`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SPoly {
    terms: BTreeMap<Mono, f64>,
}

impl SPoly {
    /// The zero polynomial.
    pub fn zero() -> Self {
        Self::default()
    }

    /// The constant `c`.
    pub fn constant(c: f64) -> Self {
        let mut p = Self::zero();
        p.add_term(Vec::new(), c);
        p
    }

    /// The variable `z_i`.
    pub fn var(i: usize) -> Self {
        let mut p = Self::zero();
        p.add_term(vec![(i as u32, 1)], 1.0);
        p
    }

    /// `c z^m` added to the polynomial (a term that cancels exactly is removed).
    pub(crate) fn add_term(&mut self, m: Mono, c: f64) {
        if c == 0.0 {
            return;
        }
        match self.terms.entry(m) {
            Entry::Vacant(v) => {
                v.insert(c);
            }
            Entry::Occupied(mut o) => {
                *o.get_mut() += c;
                if *o.get() == 0.0 {
                    o.remove();
                }
            }
        }
    }

    /// `self += s * other`.
    pub(crate) fn add_scaled(&mut self, other: &SPoly, s: f64) {
        for (m, c) in &other.terms {
            self.add_term(m.clone(), s * c);
        }
    }

    /// `s * self`.
    pub fn scaled(&self, s: f64) -> SPoly {
        let mut p = SPoly::zero();
        p.add_scaled(self, s);
        p
    }

    /// `self + other`.
    pub fn plus(&self, other: &SPoly) -> SPoly {
        let mut p = self.clone();
        p.add_scaled(other, 1.0);
        p
    }

    /// `self * other`.
    pub fn times(&self, other: &SPoly) -> SPoly {
        let mut p = SPoly::zero();
        for (ma, ca) in &self.terms {
            for (mb, cb) in &other.terms {
                p.add_term(mono_mul(ma, mb), ca * cb);
            }
        }
        p
    }

    /// `self^n`, by repeated squaring.
    pub(crate) fn pow(&self, mut n: u32) -> SPoly {
        let mut base = self.clone();
        let mut acc = SPoly::constant(1.0);
        while n > 0 {
            if n & 1 == 1 {
                acc = acc.times(&base);
            }
            n >>= 1;
            if n > 0 {
                base = base.times(&base);
            }
        }
        acc
    }

    /// Partial derivative with respect to `z_i`.
    pub fn diff(&self, i: usize) -> SPoly {
        let mut p = SPoly::zero();
        for (m, c) in &self.terms {
            if let Some(k) = m.iter().position(|&(v, _)| v as usize == i) {
                let pw = m[k].1;
                let mut d = m.clone();
                if pw == 1 {
                    d.remove(k);
                } else {
                    d[k].1 -= 1;
                }
                p.add_term(d, c * f64::from(pw));
            }
        }
        p
    }

    /// The constant term (the value at the origin).
    pub(crate) fn constant_term(&self) -> f64 {
        self.terms.get(&Vec::new()).copied().unwrap_or(0.0)
    }

    /// The polynomial without its constant term.
    pub(crate) fn without_constant(&self) -> SPoly {
        let mut p = self.clone();
        p.terms.remove(&Vec::new());
        p
    }

    /// True when the polynomial is identically zero.
    pub(crate) fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// Terms `(monomial, coefficient)` in monomial order.
    pub fn terms(&self) -> impl Iterator<Item = (&Mono, f64)> {
        self.terms.iter().map(|(m, c)| (m, *c))
    }

    /// The variables that occur, sorted.
    pub fn vars(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self
            .terms
            .keys()
            .flat_map(|m| m.iter().map(|&(i, _)| i as usize))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Value at `z`.
    pub fn eval(&self, z: &[f64]) -> f64 {
        self.terms
            .iter()
            .map(|(m, c)| {
                m.iter()
                    .fold(*c, |acc, &(v, p)| acc * z[v as usize].powi(p as i32))
            })
            .sum()
    }

    /// A hashable key identifying the polynomial exactly.
    pub fn key(&self) -> Vec<(Mono, u64)> {
        self.terms
            .iter()
            .map(|(m, c)| (m.clone(), c.to_bits()))
            .collect()
    }

    /// Readable form with the variable names `names` (e.g. `0.5*x1 + phi2^2`).
    pub fn display(&self, names: &dyn Fn(usize) -> String) -> String {
        if self.terms.is_empty() {
            return "0".into();
        }
        let mut out = String::new();
        for (k, (m, c)) in self.terms.iter().enumerate() {
            let sign = if *c < 0.0 { "-" } else { "+" };
            if k > 0 {
                out.push_str(&format!(" {sign} "));
            } else if *c < 0.0 {
                out.push('-');
            }
            let a = c.abs();
            let mut parts: Vec<String> = Vec::new();
            if a != 1.0 || m.is_empty() {
                parts.push(format!("{a}"));
            }
            for &(v, p) in m {
                parts.push(if p == 1 {
                    names(v as usize)
                } else {
                    format!("{}^{p}", names(v as usize))
                });
            }
            out.push_str(&parts.join("*"));
        }
        out
    }
}

fn mono_mul(a: &Mono, b: &Mono) -> Mono {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].0.cmp(&b[j].0) {
            std::cmp::Ordering::Less => {
                out.push(a[i]);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(b[j]);
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                out.push((a[i].0, a[i].1 + b[j].1));
                i += 1;
                j += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomial_expansion_and_derivative() {
        // (1 + x)^5 = sum C(5,k) x^k; d/dx at x = 0.3 equals 5 (1.3)^4
        let p = SPoly::constant(1.0).plus(&SPoly::var(0)).pow(5);
        let binom = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
        for (k, (m, c)) in p.terms().enumerate() {
            let deg = m.first().map_or(0, |t| t.1) as usize;
            assert_eq!(c, binom[deg], "term {k}");
        }
        let d = p.diff(0).eval(&[0.3]);
        assert!((d - 5.0 * 1.3f64.powi(4)).abs() < 1e-13);
    }

    #[test]
    fn cancellation_removes_terms() {
        let x = SPoly::var(0);
        let y = SPoly::var(1);
        let p = x.plus(&y).times(&x.plus(&y.scaled(-1.0))); // x^2 - y^2
        assert_eq!(p.terms().count(), 2);
        assert_eq!(p.vars(), vec![0, 1]);
        assert_eq!(p.eval(&[2.0, 1.0]), 3.0);
    }
}
