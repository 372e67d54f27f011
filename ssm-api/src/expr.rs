//! Non-polynomial terms of a model as expressions over its states.
//!
//! A plugin writes terms such as `sin(phi)`, `0.5 l cos(phi) mu` or
//! `1 / (1 + x^2)` (with the `Expr` builder of `ssm-plugin-kit`) and hands
//! them over as an [`ExprVector`], a graph of [`ExprNode`]s; the engine *recasts* them into polynomials by adding auxiliary
//! states (`u1 = sin phi`, `u2 = 1 - cos phi`, eqs. (22) and (35) of Li, Jain &
//! Haller 2023) with their differential equations and algebraic constraints.
//!
//! Supported operations: constants, states, sums, products, integer powers
//! (negative ones too), `sin`, `cos`, `exp`, `ln`, `sqrt` and `recip` (`1/x`).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 4.2;
//! L. Guillot, B. Cochelin, C. Vergez, *A generic and efficient Taylor series-based
//! continuation method using a quadratic recast of smooth nonlinear systems*,
//! Int. J. Numer. Methods Eng. 119 (2019) 261-280.

use abi_stable::std_types::RVec;
use abi_stable::StableAbi;

growable_tag! {
    /// Operation of one [`ExprNode`] (a transparent `u8`: later versions may
    /// add functions; an engine refuses one it does not know with a typed error).
    ExprOp {
        /// The constant `value`.
        Const = 0,
        /// State number `a`.
        Var = 1,
        /// `node a + node b`.
        Add = 2,
        /// `node a * node b`.
        Mul = 3,
        /// `(node a)^value`, `value` an integer (negative allowed).
        Powi = 4,
        /// `sin(node a)`.
        Sin = 5,
        /// `cos(node a)`.
        Cos = 6,
        /// `exp(node a)`.
        Exp = 7,
        /// `ln(node a)` (natural logarithm).
        Ln = 8,
        /// `sqrt(node a)`.
        Sqrt = 9,
        /// `1 / node a`.
        Recip = 10,
    }
}

impl ExprOp {
    /// Name as written in messages (`sin`, `recip`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Self::Const => "const",
            Self::Var => "var",
            Self::Add => "+",
            Self::Mul => "*",
            Self::Powi => "powi",
            Self::Sin => "sin",
            Self::Cos => "cos",
            Self::Exp => "exp",
            Self::Ln => "ln",
            Self::Sqrt => "sqrt",
            Self::Recip => "recip",
            _ => "unknown",
        }
    }
}

/// One node of an expression graph; children always come earlier in
/// [`ExprVector::nodes`] (topological order).
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct ExprNode {
    /// Operation.
    pub op: ExprOp,
    /// First child node, or the state index for [`ExprOp::Var`].
    pub a: u32,
    /// Second child node (binary operations only).
    pub b: u32,
    /// Constant value ([`ExprOp::Const`]) or integer exponent ([`ExprOp::Powi`]).
    pub value: f64,
}

/// `node` is added to component `eq`.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct ExprTerm {
    /// 0-based equation.
    pub eq: u32,
    /// Root node of the term.
    pub node: u32,
}

/// A vector of expressions over `n_vars` states, stored as one shared graph:
/// component `eq` is the sum of the terms with that `eq`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct ExprVector {
    /// Number of components.
    pub n_eq: u32,
    /// Number of variables (states).
    pub n_vars: u32,
    /// Nodes in topological order (shared sub-expressions appear once).
    pub nodes: RVec<ExprNode>,
    /// Terms.
    pub terms: RVec<ExprTerm>,
}

impl ExprVector {
    /// No terms: `n_eq` zero components in `n_vars` variables.
    pub fn zeros(n_eq: usize, n_vars: usize) -> Self {
        Self {
            n_eq: n_eq as u32,
            n_vars: n_vars as u32,
            nodes: RVec::new(),
            terms: RVec::new(),
        }
    }

    /// True when there is no term.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }
}
