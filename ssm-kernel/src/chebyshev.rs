//! Chebyshev interpolation in one variable (the forcing frequency): Lobatto
//! nodes, barycentric evaluation, and an adaptive table that doubles its nodes
//! until the interpolant reproduces the function at the new nodes.
//!
//! Used for quantities of the forced response that are analytic in `Omega`
//! over the frequency range but cost a sparse solve of the full system per
//! frequency (the non-autonomous terms `X0`, `S0`): a few dozen solves then
//! serve every point of a curve, whatever its number of points. Written here
//! because the interpolation is a dozen lines and no crate of the workspace
//! offers it for complex vectors.
//!
//! # References
//! J.-P. Berrut, L. N. Trefethen, *Barycentric Lagrange interpolation*, SIAM
//! Review 46 (2004), eq. (5.2) (weights for Chebyshev points of the second
//! kind); L. N. Trefethen, *Approximation Theory and Approximation Practice*,
//! SIAM (2013), Ch. 8 (geometric convergence for analytic functions).

use crate::C64;

/// `count` Chebyshev points of the second kind (Lobatto) on `[a, b]`, from `b`
/// down to `a`. Nodes for `2 (count - 1) + 1` points contain these.
pub fn lobatto_nodes(a: f64, b: f64, count: usize) -> Vec<f64> {
    if count < 2 {
        return vec![0.5 * (a + b); count];
    }
    (0..count)
        .map(|k| {
            let t = (std::f64::consts::PI * k as f64 / (count - 1) as f64).cos();
            0.5 * (a + b) + 0.5 * (b - a) * t
        })
        .collect()
}

/// Barycentric interpolation at `x` of vectors given at the nodes of
/// [`lobatto_nodes`] (weights `(-1)^k`, halved at the ends; Berrut and
/// Trefethen eq. 5.2).
pub fn interpolate(nodes: &[f64], values: &[Vec<C64>], x: f64) -> Vec<C64> {
    let n = nodes.len();
    let len = values.first().map_or(0, Vec::len);
    let mut num = vec![C64::new(0.0, 0.0); len];
    let mut den = 0.0;
    for (k, (&xk, v)) in nodes.iter().zip(values).enumerate() {
        let mut w = if k == 0 || k == n - 1 { 0.5 } else { 1.0 };
        if k % 2 == 1 {
            w = -w;
        }
        let d = x - xk;
        if d == 0.0 {
            return v.clone();
        }
        den += w / d;
        for (o, c) in num.iter_mut().zip(v) {
            *o += c * (w / d);
        }
    }
    num.iter().map(|c| c / den).collect()
}

/// A vector function of one variable tabulated at Lobatto nodes.
#[derive(Debug, Clone)]
pub struct Table {
    /// The nodes.
    pub nodes: Vec<f64>,
    /// The function at each node.
    pub values: Vec<Vec<C64>>,
    /// The largest difference, relative to the largest value, between the
    /// interpolant of the previous (half as many) nodes and the function at
    /// the nodes added last: an upper estimate of the interpolation error.
    pub error: f64,
}

impl Table {
    /// The interpolant at `x`, held at the end values outside the nodes.
    pub fn at(&self, x: f64) -> Vec<C64> {
        interpolate_held(&self.nodes, &self.values, x)
    }

    /// `x` lies within the nodes.
    pub fn contains(&self, x: f64) -> bool {
        let (lo, hi) = span(&self.nodes);
        (lo..=hi).contains(&x)
    }
}

/// Smallest and largest node.
fn span(nodes: &[f64]) -> (f64, f64) {
    nodes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        })
}

/// [`interpolate`] at `x`, held at the end values outside the nodes (where
/// a polynomial interpolant would extrapolate).
pub fn interpolate_held(nodes: &[f64], values: &[Vec<C64>], x: f64) -> Vec<C64> {
    let (lo, hi) = span(nodes);
    interpolate(nodes, values, x.clamp(lo, hi))
}

/// Tabulates `f` on `[a, b]` from 17 nodes, doubling the intervals until the
/// interpolant of the previous nodes meets `tol` (relative) at the new ones,
/// until a doubling gains less than a factor 10 (geometric convergence has
/// reached the rounding error of `f`, or `f` is not analytic on the
/// interval), or until `max_nodes` would be passed. Returns the last table with its
/// error estimate either way; the caller decides whether it is good enough.
///
/// # Errors
/// The first error of `f`.
pub fn adaptive<E>(
    a: f64,
    b: f64,
    tol: f64,
    max_nodes: usize,
    mut f: impl FnMut(f64) -> Result<Vec<C64>, E>,
) -> Result<Table, E> {
    let mut count = 17;
    let nodes = lobatto_nodes(a, b, count);
    let values = nodes.iter().map(|&x| f(x)).collect::<Result<Vec<_>, E>>()?;
    let mut table = Table {
        nodes,
        values,
        error: f64::INFINITY,
    };
    while 2 * (count - 1) < max_nodes {
        let finer = lobatto_nodes(a, b, 2 * (count - 1) + 1);
        let mut values = Vec::with_capacity(finer.len());
        let mut diff = 0.0f64;
        let mut size = 0.0f64;
        let mut finite = true;
        for (k, &x) in finer.iter().enumerate() {
            let v = if k % 2 == 0 {
                table.values[k / 2].clone()
            } else {
                let v = f(x)?;
                let old = interpolate(&table.nodes, &table.values, x);
                for (p, q) in v.iter().zip(&old) {
                    diff = diff.max((p - q).norm());
                }
                v
            };
            for p in &v {
                size = size.max(p.norm());
            }
            finite &= v.iter().all(|p| p.re.is_finite() && p.im.is_finite());
            values.push(v);
        }
        count = finer.len();
        let error = if !finite {
            f64::INFINITY
        } else if size > 0.0 {
            diff / size
        } else {
            0.0
        };
        let previous = table.error;
        table = Table {
            nodes: finer,
            values,
            error: if error.is_nan() { f64::INFINITY } else { error },
        };
        // done, or no longer converging: the rounding error of `f` itself
        // (or a singularity in the interval) sets the floor
        if table.error <= tol || table.error > 0.1 * previous {
            break;
        }
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: the closed form of `1 / (x - z)` with a pole `z` off the
    /// interval; the interpolation error falls geometrically with the nodes
    /// (Trefethen, Thm. 8.2), so the table meets 1e-12 well before 257 nodes
    /// and its error estimate bounds the true error at points between nodes.
    #[test]
    fn resolvent_is_tabulated_to_its_estimate() {
        let z = C64::new(1.5, 0.2);
        let f = |x: f64| -> Result<Vec<C64>, ()> { Ok(vec![1.0 / (C64::new(x, 0.0) - z)]) };
        let t = adaptive(-1.0, 1.0, 1e-12, 257, f).unwrap();
        assert!(t.error <= 1e-12, "estimate {}", t.error);
        assert!(t.nodes.len() <= 129, "{} nodes", t.nodes.len());
        let worst = (0..1000)
            .map(|i| -1.0 + 2.0 * (i as f64 + 0.37) / 1000.0)
            .map(|x| (t.at(x)[0] - f(x).unwrap()[0]).norm())
            .fold(0.0, f64::max);
        assert!(worst < 1e-11, "true error {worst:e}");
    }

    /// A function with a non-finite value is never taken for converged.
    #[test]
    fn non_finite_values_are_not_converged() {
        let f = |x: f64| -> Result<Vec<C64>, ()> {
            Ok(vec![if x > 0.5 {
                C64::new(f64::NAN, 0.0)
            } else {
                C64::new(1.0, 0.0)
            }])
        };
        let t = adaptive(-1.0, 1.0, 1e-10, 129, f).unwrap();
        assert!(t.error.is_infinite(), "estimate {}", t.error);
    }

    /// A pole inside the interval cannot be tabulated: the estimate says so.
    #[test]
    fn pole_in_range_is_reported() {
        let z = C64::new(0.3, 1e-6);
        let f = |x: f64| -> Result<Vec<C64>, ()> { Ok(vec![1.0 / (C64::new(x, 0.0) - z)]) };
        let t = adaptive(-1.0, 1.0, 1e-10, 129, f).unwrap();
        assert!(t.error > 1e-3, "estimate {}", t.error);
    }
}
