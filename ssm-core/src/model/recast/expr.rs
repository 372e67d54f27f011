//! Engine-side view of a plugin's [`ExprVector`]: validated once, then evaluated.

use ssm_api::{ExprNode, ExprOp, ExprVector};

use super::RecastError;

/// Largest integer exponent accepted in [`ExprOp::Powi`].
const MAX_POWER: f64 = 64.0;

/// A validated expression graph over `n` states with `n` components.
#[derive(Debug, Clone)]
pub struct ExprGraph {
    nodes: Vec<ExprNode>,
    terms: Vec<(usize, usize)>,
    n: usize,
}

impl ExprGraph {
    /// Checks shapes, child order, variable indices, exponents and constants.
    pub fn validate(v: &ExprVector, n: usize) -> Result<Self, RecastError> {
        let bad = |node: usize, detail: String| RecastError::Expression { node, detail };
        if v.n_eq as usize != n || v.n_vars as usize != n {
            return Err(bad(
                0,
                format!(
                    "the expressions have {} components in {} variables, the model {n} states",
                    v.n_eq, v.n_vars
                ),
            ));
        }
        for (k, node) in v.nodes.iter().enumerate() {
            let child = |c: u32| -> Result<(), RecastError> {
                if c as usize >= k {
                    Err(bad(
                        k,
                        format!(
                            "'{}' refers to node {c}, which does not come before it",
                            node.op.name()
                        ),
                    ))
                } else {
                    Ok(())
                }
            };
            match node.op {
                ExprOp::Const => {
                    if !node.value.is_finite() {
                        return Err(bad(k, format!("non-finite constant {}", node.value)));
                    }
                }
                ExprOp::Var => {
                    if node.a as usize >= n {
                        return Err(bad(k, format!("state {} of {n}", node.a)));
                    }
                }
                ExprOp::Add | ExprOp::Mul => {
                    child(node.a)?;
                    child(node.b)?;
                }
                ExprOp::Powi => {
                    child(node.a)?;
                    let p = node.value;
                    if p.fract() != 0.0 || p.abs() > MAX_POWER {
                        return Err(bad(
                            k,
                            format!("exponent {p} is not an integer of magnitude <= {MAX_POWER}"),
                        ));
                    }
                }
                ExprOp::Sin
                | ExprOp::Cos
                | ExprOp::Exp
                | ExprOp::Ln
                | ExprOp::Sqrt
                | ExprOp::Recip => child(node.a)?,
                op => {
                    return Err(bad(
                        k,
                        format!(
                            "unknown operation {op:?}: the plugin was built against a later ssm-api; update the engine"
                        ),
                    ))
                }
            }
        }
        let mut terms = Vec::with_capacity(v.terms.len());
        for t in v.terms.iter() {
            if t.eq as usize >= n || t.node as usize >= v.nodes.len() {
                return Err(bad(
                    t.node as usize,
                    format!(
                        "term of equation {} uses node {} of {}",
                        t.eq,
                        t.node,
                        v.nodes.len()
                    ),
                ));
            }
            terms.push((t.eq as usize, t.node as usize));
        }
        Ok(Self {
            nodes: v.nodes.to_vec(),
            terms,
            n,
        })
    }

    /// Nodes in topological order.
    pub fn nodes(&self) -> &[ExprNode] {
        &self.nodes
    }

    /// `(equation, root node)` of each term.
    pub fn terms(&self) -> &[(usize, usize)] {
        &self.terms
    }

    /// Value of every node at `z`.
    pub(crate) fn eval_nodes(&self, z: &[f64]) -> Vec<f64> {
        let mut val: Vec<f64> = Vec::with_capacity(self.nodes.len());
        for nd in &self.nodes {
            let a = || val[nd.a as usize];
            let x = match nd.op {
                ExprOp::Const => nd.value,
                ExprOp::Var => z[nd.a as usize],
                ExprOp::Add => a() + val[nd.b as usize],
                ExprOp::Mul => a() * val[nd.b as usize],
                ExprOp::Powi => a().powi(nd.value as i32),
                ExprOp::Sin => a().sin(),
                ExprOp::Cos => a().cos(),
                ExprOp::Exp => a().exp(),
                ExprOp::Ln => a().ln(),
                ExprOp::Sqrt => a().sqrt(),
                ExprOp::Recip => a().recip(),
                op => unreachable!("operation {op:?} is refused when the graph is built"),
            };
            val.push(x);
        }
        val
    }

    /// The `n` components at `z`.
    pub fn eval(&self, z: &[f64]) -> Vec<f64> {
        let val = self.eval_nodes(z);
        let mut out = vec![0.0; self.n];
        for &(eq, node) in &self.terms {
            out[eq] += val[node];
        }
        out
    }
}
