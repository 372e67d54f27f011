//! Derivatives of a recast's auxiliaries with respect to the original
//! states: the chain rule through the auxiliaries' definitions, for users
//! of a recast model that need the total Jacobian of an original equation
//! (e.g. the constraint Jacobian `dC/dq` of a position constraint written
//! in `sin phi`, whose recast rows depend on `phi` only through `u = sin phi`).

use super::{AuxKind, RecastInfo};

impl AuxKind {
    /// Derivative of [`AuxKind::value`] with respect to the argument
    /// deviation `x`.
    pub fn derivative(self, a0: f64, x: f64) -> f64 {
        match self {
            Self::Sin => x.cos(),
            Self::OneMinusCos => x.sin(),
            Self::ExpMinusOne => x.exp(),
            Self::Ln => (a0 + x).recip(),
            Self::Recip => -(a0 + x).powi(2).recip(),
            Self::Sqrt => 0.5 / (a0 + x).sqrt(),
        }
    }
}

impl RecastInfo {
    /// `du_k / dz_j` of every auxiliary `u_k` with respect to the original
    /// (shifted) states `z_j`, at the recast state `z` (original states
    /// followed by the auxiliaries), as sparse rows `(j, value)` in
    /// auxiliary order: `du_k/dz = u_k'(x) (da/dz + sum_b da/du_b du_b/dz)`
    /// over the earlier auxiliaries `u_b` the argument `a` contains.
    pub(crate) fn aux_jacobian(&self, z: &[f64]) -> Vec<Vec<(usize, f64)>> {
        let n = self.n_original;
        let mut rows: Vec<Vec<f64>> = Vec::with_capacity(self.auxiliaries.len());
        for a in &self.auxiliaries {
            let slope = a.kind.derivative(a.a0, a.argument.eval(z));
            let mut row = vec![0.0; n];
            for v in a.argument.vars() {
                let d = a.argument.diff(v).eval(z);
                if d == 0.0 {
                    continue;
                }
                if v < n {
                    row[v] += d;
                } else if let Some(earlier) = rows.get(v - n) {
                    for (r, e) in row.iter_mut().zip(earlier) {
                        *r += d * e;
                    }
                }
            }
            for r in &mut row {
                *r *= slope;
            }
            rows.push(row);
        }
        rows.into_iter()
            .map(|row| {
                row.into_iter()
                    .enumerate()
                    .filter(|(_, v)| *v != 0.0)
                    .collect()
            })
            .collect()
    }
}
