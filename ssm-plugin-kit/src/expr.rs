//! Non-polynomial terms of a model as expressions over its states: the
//! [`Expr`] builder and its lowering into the [`ExprVector`] graph that
//! crosses the plugin boundary ([`expr_vector`]).
//!
//! A plugin writes terms such as `sin(phi)`, `0.5 l cos(phi) mu` or
//! `1 / (1 + x^2)`; the engine *recasts* them into polynomials by adding
//! auxiliary states (`u1 = sin phi`, `u2 = 1 - cos phi`, eqs. (22) and (35) of
//! Li, Jain & Haller 2023) with their differential equations and algebraic
//! constraints. [`Expr::diff`] differentiates symbolically (the constraint
//! Jacobian of expression constraints).
//!
//! Supported operations: constants, states, sums, products, integer powers
//! (negative ones too), `sin`, `cos`, `exp`, `ln`, `sqrt` and `recip` (`1/x`).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 4.2.

use std::collections::HashMap;
use std::ops::{Add, Mul, Neg, Sub};
use std::rc::Rc;

use abi_stable::std_types::RVec;
use ssm_api::{ExprNode, ExprOp, ExprTerm, ExprVector};

/// The [`ExprVector`] of `(eq, expression)` pairs: `n_eq` components in
/// `n_vars` states, lowered into one graph; sub-expressions shared between
/// terms (the same [`Expr`] value cloned) are stored once, zero constants
/// are left out.
pub fn expr_vector(n_eq: usize, n_vars: usize, terms: &[(usize, Expr)]) -> ExprVector {
    let mut v = ExprVector::zeros(n_eq, n_vars);
    let mut seen: HashMap<*const Node, u32> = HashMap::new();
    for (eq, e) in terms {
        if let Node::Const(c) = *e.0 {
            if c == 0.0 {
                continue;
            }
        }
        let node = lower(e, &mut v.nodes, &mut seen);
        v.terms.push(ExprTerm {
            eq: *eq as u32,
            node,
        });
    }
    v
}

fn lower(e: &Expr, nodes: &mut RVec<ExprNode>, seen: &mut HashMap<*const Node, u32>) -> u32 {
    let key = Rc::as_ptr(&e.0);
    if let Some(&i) = seen.get(&key) {
        return i;
    }
    let node = match &*e.0 {
        Node::Const(c) => leaf(ExprOp::Const, 0, *c),
        Node::Var(i) => leaf(ExprOp::Var, *i, 0.0),
        Node::Binary(op, x, y) => {
            let a = lower(x, nodes, seen);
            let b = lower(y, nodes, seen);
            ExprNode {
                op: *op,
                a,
                b,
                value: 0.0,
            }
        }
        Node::Unary(op, x) => {
            let a = lower(x, nodes, seen);
            leaf(*op, a, 0.0)
        }
        Node::Powi(x, n) => {
            let a = lower(x, nodes, seen);
            leaf(ExprOp::Powi, a, f64::from(*n))
        }
    };
    nodes.push(node);
    let i = (nodes.len() - 1) as u32;
    seen.insert(key, i);
    i
}

fn leaf(op: ExprOp, a: u32, value: f64) -> ExprNode {
    ExprNode { op, a, b: 0, value }
}

#[derive(Debug, PartialEq)]
enum Node {
    Const(f64),
    Var(u32),
    Binary(ExprOp, Expr, Expr),
    Unary(ExprOp, Expr),
    Powi(Expr, i32),
}

/// A scalar expression over the states, built with operators and the
/// functions below; constants are folded as the expression is built.
///
/// ```
/// use ssm_plugin_kit::Expr;
/// let phi = Expr::var(0);
/// let mu = Expr::var(2);
/// // 0.5 l cos(phi) mu with l = 1
/// let e = 0.5 * phi.cos() * mu;
/// assert!((e.eval(&[0.3, 0.0, 2.0]) - 0.3f64.cos()).abs() < 1e-15);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Expr(Rc<Node>);

impl Expr {
    /// The constant `c`.
    pub fn constant(c: f64) -> Self {
        Self(Rc::new(Node::Const(c)))
    }

    /// State number `i` (0-based, in the numbering of the polynomial it enters).
    pub fn var(i: usize) -> Self {
        Self(Rc::new(Node::Var(i as u32)))
    }

    fn as_const(&self) -> Option<f64> {
        match *self.0 {
            Node::Const(c) => Some(c),
            _ => None,
        }
    }

    /// True when the expression is a constant.
    pub fn is_constant(&self) -> bool {
        self.as_const().is_some()
    }

    fn unary(self, op: ExprOp, f: fn(f64) -> f64) -> Self {
        match self.as_const() {
            Some(c) => Self::constant(f(c)),
            None => Self(Rc::new(Node::Unary(op, self))),
        }
    }

    /// `sin(self)`.
    pub fn sin(self) -> Self {
        self.unary(ExprOp::Sin, f64::sin)
    }

    /// `cos(self)`.
    pub fn cos(self) -> Self {
        self.unary(ExprOp::Cos, f64::cos)
    }

    /// `exp(self)`.
    pub fn exp(self) -> Self {
        self.unary(ExprOp::Exp, f64::exp)
    }

    /// `ln(self)`, natural logarithm.
    pub fn ln(self) -> Self {
        self.unary(ExprOp::Ln, f64::ln)
    }

    /// `sqrt(self)`.
    pub fn sqrt(self) -> Self {
        self.unary(ExprOp::Sqrt, f64::sqrt)
    }

    /// `1 / self`.
    pub fn recip(self) -> Self {
        self.unary(ExprOp::Recip, f64::recip)
    }

    /// `self^n` for an integer `n` (negative: a power of `1 / self`).
    pub fn powi(self, n: i32) -> Self {
        match (n, self.as_const()) {
            (0, _) => Self::constant(1.0),
            (1, _) => self,
            (_, Some(c)) => Self::constant(c.powi(n)),
            _ => Self(Rc::new(Node::Powi(self, n))),
        }
    }

    /// The states the expression depends on, sorted and without repeats.
    pub fn vars(&self) -> Vec<usize> {
        fn walk(e: &Expr, out: &mut Vec<usize>) {
            match &*e.0 {
                Node::Const(_) => {}
                Node::Var(i) => out.push(*i as usize),
                Node::Binary(_, a, b) => {
                    walk(a, out);
                    walk(b, out);
                }
                Node::Unary(_, a) | Node::Powi(a, _) => walk(a, out),
            }
        }
        let mut out = Vec::new();
        walk(self, &mut out);
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Value at the states `z`.
    ///
    /// # Panics
    /// If the expression uses a state index outside `z`.
    pub fn eval(&self, z: &[f64]) -> f64 {
        match &*self.0 {
            Node::Const(c) => *c,
            Node::Var(i) => z[*i as usize],
            Node::Binary(ExprOp::Add, a, b) => a.eval(z) + b.eval(z),
            Node::Binary(_, a, b) => a.eval(z) * b.eval(z),
            Node::Powi(a, n) => a.eval(z).powi(*n),
            Node::Unary(op, a) => {
                let x = a.eval(z);
                match *op {
                    ExprOp::Sin => x.sin(),
                    ExprOp::Cos => x.cos(),
                    ExprOp::Exp => x.exp(),
                    ExprOp::Ln => x.ln(),
                    ExprOp::Sqrt => x.sqrt(),
                    _ => x.recip(),
                }
            }
        }
    }

    /// Partial derivative with respect to state `i`, by the chain rule.
    pub fn diff(&self, i: usize) -> Self {
        match &*self.0 {
            Node::Const(_) => Self::constant(0.0),
            Node::Var(j) => Self::constant(if *j as usize == i { 1.0 } else { 0.0 }),
            Node::Binary(ExprOp::Add, a, b) => a.diff(i) + b.diff(i),
            Node::Binary(_, a, b) => a.diff(i) * b.clone() + a.clone() * b.diff(i),
            Node::Powi(a, n) => f64::from(*n) * a.clone().powi(n - 1) * a.diff(i),
            Node::Unary(op, a) => {
                let da = a.diff(i);
                if da.as_const() == Some(0.0) {
                    return da;
                }
                let outer = match *op {
                    ExprOp::Sin => a.clone().cos(),
                    ExprOp::Cos => -a.clone().sin(),
                    ExprOp::Exp => self.clone(),
                    ExprOp::Ln => a.clone().recip(),
                    ExprOp::Sqrt => 0.5 * self.clone().recip(),
                    _ => -self.clone().powi(2),
                };
                outer * da
            }
        }
    }
}

impl From<f64> for Expr {
    fn from(c: f64) -> Self {
        Self::constant(c)
    }
}

impl Add for Expr {
    type Output = Expr;
    fn add(self, rhs: Expr) -> Expr {
        match (self.as_const(), rhs.as_const()) {
            (Some(a), Some(b)) => Expr::constant(a + b),
            (Some(0.0), _) => rhs,
            (_, Some(0.0)) => self,
            _ => Expr(Rc::new(Node::Binary(ExprOp::Add, self, rhs))),
        }
    }
}

impl Mul for Expr {
    type Output = Expr;
    fn mul(self, rhs: Expr) -> Expr {
        match (self.as_const(), rhs.as_const()) {
            (Some(a), Some(b)) => Expr::constant(a * b),
            (Some(z), _) | (_, Some(z)) if z == 0.0 => Expr::constant(0.0),
            (Some(1.0), _) => rhs,
            (_, Some(1.0)) => self,
            _ => Expr(Rc::new(Node::Binary(ExprOp::Mul, self, rhs))),
        }
    }
}

impl Neg for Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        -1.0 * self
    }
}

impl Sub for Expr {
    type Output = Expr;
    fn sub(self, rhs: Expr) -> Expr {
        self + (-rhs)
    }
}

macro_rules! scalar_ops {
    ($($tr:ident $f:ident),*) => {$(
        impl $tr<f64> for Expr {
            type Output = Expr;
            fn $f(self, rhs: f64) -> Expr {
                $tr::$f(self, Expr::constant(rhs))
            }
        }
        impl $tr<Expr> for f64 {
            type Output = Expr;
            fn $f(self, rhs: Expr) -> Expr {
                $tr::$f(Expr::constant(self), rhs)
            }
        }
    )*};
}
scalar_ops!(Add add, Sub sub, Mul mul);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_central_difference() {
        let x = Expr::var(0);
        let y = Expr::var(1);
        let e = x.clone().sin() * y.clone().powi(-2)
            + (1.0 + x.clone() * y.clone()).sqrt().ln()
            + (0.5 * x.clone()).exp() * y.clone().cos()
            + (2.0 + x.clone()).recip();
        let z = [0.37, 1.21];
        for i in 0..2 {
            let h = 1e-6;
            let mut zp = z;
            let mut zm = z;
            zp[i] += h;
            zm[i] -= h;
            let fd = (e.eval(&zp) - e.eval(&zm)) / (2.0 * h);
            let d = e.diff(i).eval(&z);
            assert!(
                (d - fd).abs() < 1e-8 * (1.0 + d.abs()),
                "d/dz{i}: {d} vs {fd}"
            );
        }
    }

    #[test]
    fn constants_fold_and_shared_nodes_are_stored_once() {
        let phi = Expr::var(0);
        let s = phi.clone().sin();
        assert!((Expr::constant(2.0) * 3.0 - 6.0).is_constant());
        let v = expr_vector(2, 1, &[(0, s.clone()), (1, 2.0 * s)]);
        // var, sin, const 2, mul: the sine is not duplicated
        assert_eq!(v.nodes.len(), 4);
        assert_eq!(v.terms.len(), 2);
        assert_eq!(v.terms[0].node, 1);
    }
}
