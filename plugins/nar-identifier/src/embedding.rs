//! The delay embedding (3.1) and the monomial basis `psi` of the NAR model
//! (7.1): every exponent vector `m` in `N^{2 nu}` with `1 <= |m| <= r`.

use ssm_api::Signals;

/// The monomials `xi^m`, `1 <= |m| <= r`, graded (by degree, then
/// lexicographically from the first delay coordinate), each of degree two
/// or more stored as its parent monomial times one variable so that a row
/// of `psi` costs one multiplication per monomial.
#[derive(Debug, Clone)]
pub struct MonomialBasis {
    /// Number of variables `2 nu`.
    pub n_vars: usize,
    /// Exponent vectors, in evaluation order.
    pub exponents: Vec<Vec<u32>>,
    /// `(parent, variable)` of each monomial; `None` for the linear ones.
    parents: Vec<Option<(usize, usize)>>,
}

impl MonomialBasis {
    /// All monomials of degree `1..=order` in `n_vars` variables.
    pub fn new(n_vars: usize, order: usize) -> Self {
        let mut exponents: Vec<Vec<u32>> = (0..n_vars)
            .map(|v| {
                let mut e = vec![0; n_vars];
                e[v] = 1;
                e
            })
            .collect();
        let mut parents: Vec<Option<(usize, usize)>> = vec![None; n_vars];
        let mut level = 0..n_vars;
        for _ in 2..=order {
            let start = exponents.len();
            for p in level.clone() {
                // extend by variables at or after the first nonzero one, so
                // each monomial is made once: m = e_v * parent, v <= first(parent)
                let first = exponents[p].iter().position(|&x| x > 0).unwrap_or(0);
                for v in 0..=first {
                    let mut e = exponents[p].clone();
                    e[v] += 1;
                    exponents.push(e);
                    parents.push(Some((p, v)));
                }
            }
            level = start..exponents.len();
        }
        Self {
            n_vars,
            exponents,
            parents,
        }
    }

    /// Number of monomials (unknowns per equation of the NAR model).
    pub fn len(&self) -> usize {
        self.exponents.len()
    }

    /// Whether the basis is empty (never, for `n_vars, order >= 1`).
    pub fn is_empty(&self) -> bool {
        self.exponents.is_empty()
    }

    /// Degree `|m|` of monomial `k`.
    pub fn degree(&self, k: usize) -> u32 {
        self.exponents[k].iter().sum()
    }

    /// `psi(xi)` into `out` (`len()` values).
    pub fn eval(&self, xi: &[f64], out: &mut [f64]) {
        for (k, p) in self.parents.iter().enumerate() {
            out[k] = match *p {
                None => xi[k],
                Some((parent, v)) => out[parent] * xi[v],
            };
        }
    }
}

/// The samples of one observable, decimated and trimmed: trajectory `p` keeps
/// samples `skip, skip + d, skip + 2d, ...` (`d = decimate`).
#[derive(Debug, Clone)]
pub struct Series {
    /// Where each came from (file names, for error messages).
    pub sources: Vec<String>,
    /// The kept samples of each trajectory.
    pub values: Vec<Vec<f64>>,
    /// Sampling period of the kept samples, `d T`.
    pub period: f64,
}

impl Series {
    /// Observable `j` of `signals`, every `decimate`-th sample from `skip` on.
    pub fn new(signals: &Signals, j: usize, skip: usize, decimate: usize) -> Self {
        let values = (0..signals.trajectories.len())
            .map(|p| {
                (skip..signals.n_samples(p))
                    .step_by(decimate)
                    .map(|i| signals.sample(p, i)[j])
                    .collect()
            })
            .collect();
        Self {
            sources: signals
                .trajectories
                .iter()
                .map(|t| t.source.to_string())
                .collect(),
            values,
            period: signals.period * decimate as f64,
        }
    }

    /// Largest `|y|` over all trajectories (the scale of the data).
    pub fn scale(&self) -> f64 {
        self.values
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// Rows of the regression of trajectory `p` with embedding dimension
    /// `dim`: the pairs `(xi_k, y_{k + dim})`, `k = 0 .. M_p - dim - 1`.
    pub fn rows(&self, p: usize, dim: usize) -> usize {
        self.values[p].len().saturating_sub(dim)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count of monomials of degree 1..=r in n variables is
    /// `C(n + r, r) - 1`, each made once.
    #[test]
    fn basis_has_every_monomial_once() {
        for (n, r) in [(1, 4), (2, 3), (4, 5), (6, 3), (6, 7)] {
            let b = MonomialBasis::new(n, r);
            let binom = (1..=r).fold(1usize, |acc, k| acc * (n + k) / k);
            assert_eq!(b.len(), binom - 1, "n = {n}, r = {r}");
            let mut sorted = b.exponents.clone();
            sorted.sort();
            sorted.dedup();
            assert_eq!(sorted.len(), b.len());
            assert!(b.exponents.iter().all(|e| {
                let d: u32 = e.iter().sum();
                (1..=r as u32).contains(&d)
            }));
        }
    }

    /// `eval` equals the product of powers.
    #[test]
    fn eval_is_the_product_of_powers() {
        let b = MonomialBasis::new(3, 4);
        let xi = [0.7, -1.3, 2.1];
        let mut out = vec![0.0; b.len()];
        b.eval(&xi, &mut out);
        for (k, e) in b.exponents.iter().enumerate() {
            let direct: f64 = e.iter().zip(&xi).map(|(&p, x)| x.powi(p as i32)).product();
            assert!((out[k] - direct).abs() <= 1e-14 * direct.abs().max(1.0));
        }
    }
}
