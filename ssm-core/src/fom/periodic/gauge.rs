//! The recast's gauge conditions for periodic orbits.
//!
//! A recast ([`crate::model::recast`]) defines some auxiliaries by a
//! differential equation, `u' = g'(a) a'` for `u = g(a)` (`sin`, `exp - 1`,
//! `ln`). Along any solution `u - g(a)` is then constant, and only the
//! initial value makes it zero. An initial-value problem inherits the zero
//! from a consistent start; a periodic boundary-value problem does not: the
//! mean (`k = 0`) row of the auxiliary's equation is implied by the other
//! rows, the harmonic-balance Jacobian is singular (the recast's spurious
//! zero eigenvalue), and orbits with `u - g(a) = const != 0` solve the
//! discretization too. So that row is replaced by the gauge condition
//!
//! `(1/M) sum_s [u(psi_s) - g(a(z(psi_s)))] = 0`,
//!
//! which selects the orbit on the recast manifold `u = g(a)`. In Hill's
//! method the row is algebraic (no `mu` term), which removes the spurious
//! exponent `mu = 0` and leaves the physical ones.
//!
//! # References
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), Sect. 4.2 (recast,
//! eq. (22), and its spurious zero eigenvalues).

use crate::model::recast::{AuxKind, SPoly};
use crate::model::system::System;

/// One gauge condition.
#[derive(Debug, Clone)]
pub(super) struct Gauge {
    /// The auxiliary's state.
    pub aux: usize,
    kind: AuxKind,
    a0: f64,
    argument: SPoly,
    /// `(state, d argument / d state)` of every state of the argument.
    grads: Vec<(usize, SPoly)>,
    /// Pattern positions of every entry of the row `aux K` (cleared before
    /// the gauge's derivatives are written).
    pub row_positions: Vec<usize>,
    /// `(state, positions of (aux K, state K + q) for every q)`.
    pub columns: Vec<(usize, Vec<usize>)>,
}

impl Gauge {
    /// The gauges of `sys`: one per differential auxiliary of its recast.
    pub fn of(sys: &System) -> Vec<Gauge> {
        let Some(info) = &sys.recast else {
            return Vec::new();
        };
        info.auxiliaries
            .iter()
            .filter(|a| a.kind.is_differential())
            .map(|a| Gauge {
                aux: a.state,
                kind: a.kind,
                a0: a.a0,
                argument: a.argument.clone(),
                grads: a
                    .argument
                    .vars()
                    .into_iter()
                    .map(|v| (v, a.argument.diff(v)))
                    .collect(),
                row_positions: Vec::new(),
                columns: Vec::new(),
            })
            .collect()
    }

    /// The states whose coefficients the condition involves.
    pub fn states(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.grads.iter().map(|(v, _)| *v).collect();
        s.push(self.aux);
        s.sort_unstable();
        s.dedup();
        s
    }

    /// `u - g(a)` at the state `z`.
    pub fn defect(&self, z: &[f64]) -> f64 {
        z[self.aux] - self.kind.value(self.a0, self.argument.eval(z))
    }

    /// `d (u - g(a)) / d z_j` at `z`, for each state of [`Gauge::states`]
    /// in order.
    pub fn gradient(&self, z: &[f64]) -> Vec<(usize, f64)> {
        let dg = self.kind.derivative(self.a0, self.argument.eval(z));
        self.states()
            .into_iter()
            .map(|j| {
                let own = if j == self.aux { 1.0 } else { 0.0 };
                let da = self
                    .grads
                    .iter()
                    .find(|(v, _)| *v == j)
                    .map_or(0.0, |(_, d)| d.eval(z));
                (j, own - dg * da)
            })
            .collect()
    }
}
