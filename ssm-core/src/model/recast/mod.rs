//! Recast of non-polynomial models into polynomial DAEs (Sect. 4.2).
//!
//! A plugin's model is `B z' = A z + F(z) + E(z)` with `E` given as expressions
//! ([`ssm_api::ExprVector`]) and possibly an equilibrium `z_eq`. The recast
//! 1. substitutes `z = z_eq + z_hat` (eqs. 34, 107) and checks that the right-hand
//!    side vanishes at `z_hat = 0`;
//! 2. turns every expression into a polynomial in `z_hat` and auxiliary states
//!    `u`, one family per distinct function argument `a = a0 + a_hat`
//!    (`a0 = a(z_eq)`), each chosen to vanish at the equilibrium so that the origin
//!    stays a fixed point:
//!
//!    | term      | auxiliary                          | its equation                              |
//!    |-----------|------------------------------------|-------------------------------------------|
//!    | sin, cos  | `u_s = sin a_hat`, `u_c = 1 - cos a_hat` | `u_s' = (1 - u_c) a_hat'`, `0 = u_s^2 - 2 u_c + u_c^2` (eqs. 22, 35) |
//!    | exp       | `u_e = exp(a_hat) - 1`            | `u_e' = (1 + u_e) a_hat'`                 |
//!    | 1/a       | `u_r = 1/a - 1/a0`                | `0 = u_r + a_hat/a0^2 + u_r a_hat/a0`       |
//!    | sqrt      | `u_q = sqrt(a) - sqrt(a0)`        | `0 = u_q + (u_q^2 - a_hat)/(2 sqrt(a0))`   |
//!    | ln        | `u_l = ln(a/a0)`                  | `u_l' = (1/a) a_hat'` (with the `1/a` auxiliary) |
//!
//!    with `sin a = sin a0 (1 - u_c) + cos a0 u_s`, `exp a = e^{a0} (1 + u_e)`, and
//!    so on. The time derivative `a_hat'` is formed symbolically: a displacement's
//!    derivative is its velocity state, an auxiliary's derivative is the rule above
//!    (so nested functions work);
//! 3. splits every equation into linear part (into `A`) and the rest (into `F`).
//!
//! Each differential auxiliary adds a zero eigenvalue to the pencil and each
//! algebraic one an infinite eigenvalue; both are artifacts (Sect. 4.2). The
//! recast therefore also returns the *physical pencil*: the linearization of the
//! original model at the equilibrium, obtained by eliminating the auxiliaries
//! through their linearized definitions `u = L z_hat`. Its finite spectrum is
//! exactly that of the model, so master modes and resonance checks never see the
//! spurious modes — by construction, not by a threshold.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 4.2, eqs. (21)-(22),
//! (34)-(35), (107)-(115); L. Guillot, B. Cochelin, C. Vergez, *A generic and
//! efficient Taylor series-based continuation method using a quadratic recast of
//! smooth nonlinear systems*, Int. J. Numer. Methods Eng. 119 (2019) 261-280.

mod derivative;
mod expr;
mod spoly;

use std::collections::HashMap;

use faer::sparse::{SparseColMat, Triplet};
use ssm_api::{ExprOp, Harmonic, PolyVector, StateInfo};

pub use expr::ExprGraph;
pub use spoly::{Mono, SPoly};

/// Relative size of the right-hand side at the given equilibrium above which it
/// is refused as not being an equilibrium.
const EQUILIBRIUM_TOL: f64 = 1e-10;

/// Why a model could not be recast.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecastError {
    /// The expression graph is malformed.
    #[error("expression node {node}: {detail}")]
    Expression {
        /// Node index.
        node: usize,
        /// What is wrong.
        detail: String,
    },
    /// The equilibrium has the wrong length or a non-finite entry.
    #[error("the equilibrium has {found} values for a model with {expected} states (or a non-finite value)")]
    EquilibriumShape {
        /// Values given.
        found: usize,
        /// States of the model.
        expected: usize,
    },
    /// The right-hand side does not vanish at the given equilibrium.
    #[error("the model is not at equilibrium at the given state: equation {equation} (the row of state '{state}') has residual {residual:e}; give the equilibrium positions and multipliers (eqs. 34, 107), or remove constant forces")]
    NotAnEquilibrium {
        /// 0-based equation.
        equation: usize,
        /// Name of the state of that row.
        state: String,
        /// Residual found.
        residual: f64,
    },
    /// A function is singular (or undefined) at the equilibrium.
    #[error("{function}({argument}) is not defined at the equilibrium (argument {value}); shift the model so the argument stays in the function's domain")]
    Singular {
        /// Function.
        function: &'static str,
        /// Its argument, written out.
        argument: String,
        /// Argument value at the equilibrium.
        value: f64,
    },
    /// A function whose auxiliary needs a differential equation has an argument
    /// whose time derivative is not a state.
    #[error("the argument of {function}({argument}) depends on state '{state}', whose time derivative is not a state of the model; inside sin, cos, exp and ln only displacements (and functions of them) may appear")]
    NoTimeDerivative {
        /// Function.
        function: &'static str,
        /// Its argument, written out.
        argument: String,
        /// The state.
        state: String,
    },
}

/// What an auxiliary state stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum AuxKind {
    /// `sin a_hat`.
    Sin,
    /// `1 - cos a_hat`.
    OneMinusCos,
    /// `exp(a_hat) - 1`.
    ExpMinusOne,
    /// `ln(a / a0)`.
    Ln,
    /// `1/a - 1/a0`.
    Recip,
    /// `sqrt(a) - sqrt(a0)`.
    Sqrt,
}

impl AuxKind {
    /// Value of the auxiliary for the argument deviation `x = a_hat` and `a0`.
    pub fn value(self, a0: f64, x: f64) -> f64 {
        match self {
            Self::Sin => x.sin(),
            Self::OneMinusCos => 1.0 - x.cos(),
            Self::ExpMinusOne => x.exp_m1(),
            Self::Ln => (x / a0).ln_1p(),
            Self::Recip => (a0 + x).recip() - a0.recip(),
            Self::Sqrt => (a0 + x).sqrt() - a0.sqrt(),
        }
    }

    /// Derivative of [`AuxKind::value`] with respect to `x` at `x = 0`: the
    /// auxiliary's linearization `u = slope * a_hat`.
    fn slope(self, a0: f64) -> f64 {
        match self {
            Self::Sin | Self::ExpMinusOne => 1.0,
            Self::OneMinusCos => 0.0,
            Self::Ln => 1.0 / a0,
            Self::Recip => -1.0 / (a0 * a0),
            Self::Sqrt => 0.5 / a0.sqrt(),
        }
    }

    /// True when the auxiliary is defined by a differential equation.
    pub fn is_differential(self) -> bool {
        matches!(self, Self::Sin | Self::ExpMinusOne | Self::Ln)
    }
}

/// One auxiliary state of a recast.
#[derive(Debug, Clone)]
pub struct Auxiliary {
    /// Its state index in the recast system.
    pub state: usize,
    /// Its name (`u1`, `u2`, ...).
    pub name: String,
    /// What it stands for, e.g. `u1 = sin(phi2)`.
    pub definition: String,
    /// Kind.
    pub kind: AuxKind,
    /// Argument deviation `a_hat` (polynomial in the shifted states and earlier auxiliaries).
    pub argument: SPoly,
    /// Argument at the equilibrium `a0`.
    pub a0: f64,
}

/// The original (unrecast) model, kept for evaluation and for the physical pencil.
#[derive(Debug, Clone)]
pub struct RecastInfo {
    /// States of the original model (the recast appends the auxiliaries after them).
    pub n_original: usize,
    /// The auxiliaries, in state order.
    pub auxiliaries: Vec<Auxiliary>,
    /// Equilibrium `z_eq` of the original states (zeros: the origin).
    pub equilibrium: Vec<f64>,
    /// Linearization of the original model at `z_eq` (`N x N`, auxiliaries eliminated).
    pub physical_a: SparseColMat<usize, f64>,
    /// `B` of the original model.
    pub physical_b: SparseColMat<usize, f64>,
    original_a: SparseColMat<usize, f64>,
    original_f: PolyVector,
    original_e: ExprGraph,
}

impl RecastInfo {
    /// The recast state `(z_hat, u(z_hat))` whose auxiliaries satisfy their
    /// definitions exactly: the lift of a shifted original state.
    pub fn lift(&self, z_hat: &[f64]) -> Vec<f64> {
        let mut z = z_hat[..self.n_original].to_vec();
        for a in &self.auxiliaries {
            let x = a.argument.eval(&z);
            z.push(a.kind.value(a.a0, x));
        }
        z
    }

    /// The original right-hand side `A z + F(z) + E(z)` at `z = z_eq + z_hat`.
    pub fn original_rhs(&self, z_hat: &[f64]) -> Vec<f64> {
        let z: Vec<f64> = (0..self.n_original)
            .map(|i| self.equilibrium[i] + z_hat[i])
            .collect();
        let mut out = self.original_e.eval(&z);
        let a = self.original_a.as_ref();
        for (c, zc) in z.iter().enumerate() {
            for (r, v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
                out[r] += v * zc;
            }
        }
        for t in self.original_f.terms.iter() {
            out[t.eq as usize] += t.factors.iter().fold(t.coeff, |acc, f| {
                acc * z[f.var as usize].powi(f.power as i32)
            });
        }
        out
    }
}

/// The model a recast starts from.
#[derive(Debug, Clone, Copy)]
pub struct Source<'a> {
    /// `A` (`N x N`).
    pub a: &'a SparseColMat<usize, f64>,
    /// `B` (`N x N`).
    pub b: &'a SparseColMat<usize, f64>,
    /// Polynomial part `F`.
    pub f: &'a PolyVector,
    /// Non-polynomial part `E`.
    pub e: &'a ssm_api::ExprVector,
    /// Equilibrium (empty: the origin).
    pub equilibrium: &'a [f64],
    /// Forcing harmonics (polynomials in `z`).
    pub forcing: &'a [Harmonic],
    /// States.
    pub states: &'a [StateInfo],
    /// Number of displacements when `z = (x, x', mu)`: the derivative of state
    /// `i < n_dof` is state `n_dof + i`.
    pub n_dof: Option<usize>,
}

/// A recast model: polynomial, with the auxiliaries appended to the states.
#[derive(Debug, Clone)]
pub struct Recast {
    /// `A` of the recast system.
    pub a: SparseColMat<usize, f64>,
    /// `B` of the recast system.
    pub b: SparseColMat<usize, f64>,
    /// `F` of the recast system (degree >= 2).
    pub nonlinearity: PolyVector,
    /// Forcing in the shifted, recast states.
    pub forcing: Vec<Harmonic>,
    /// What was added and what the original was.
    pub info: RecastInfo,
}

struct Aux {
    kind: AuxKind,
    arg: SPoly,
    a0: f64,
    /// Trig: the other member of the pair; Ln: its `1/a` auxiliary.
    partner: Option<usize>,
}

/// Identifies an auxiliary: kind, `a0` bits where the definition depends on
/// it, and the exact argument polynomial.
type AuxKey = (AuxKind, u64, Vec<(Mono, u64)>);

struct Builder<'a> {
    n: usize,
    prefix: &'static str,
    n_dof: Option<usize>,
    states: &'a [StateInfo],
    aux: Vec<Aux>,
    index: HashMap<AuxKey, usize>,
    derivs: HashMap<usize, SPoly>,
}

impl Builder<'_> {
    fn name(&self, v: usize) -> String {
        if v < self.n {
            self.states[v].name.to_string()
        } else {
            format!("{}{}", self.prefix, v - self.n + 1)
        }
    }

    fn show(&self, p: &SPoly) -> String {
        p.display(&|v| self.name(v))
    }

    fn var(&self, k: usize) -> SPoly {
        SPoly::var(self.n + k)
    }

    /// The auxiliary of `kind` for argument `a0 + arg`, created on first use.
    fn aux(&mut self, kind: AuxKind, a0: f64, arg: &SPoly) -> usize {
        // a0 matters only where the auxiliary's definition depends on it
        let a0_key = match kind {
            AuxKind::Sin | AuxKind::OneMinusCos | AuxKind::ExpMinusOne => 0,
            _ => a0.to_bits(),
        };
        let key = (kind, a0_key, arg.key());
        if let Some(&k) = self.index.get(&key) {
            return k;
        }
        let k = self.aux.len();
        self.aux.push(Aux {
            kind,
            arg: arg.clone(),
            a0,
            partner: None,
        });
        self.index.insert(key, k);
        match kind {
            AuxKind::Sin => {
                let c = self.aux(AuxKind::OneMinusCos, 0.0, arg);
                self.aux[k].partner = Some(c);
                self.aux[c].partner = Some(k);
            }
            AuxKind::Ln => {
                let r = self.aux(AuxKind::Recip, a0, arg);
                self.aux[k].partner = Some(r);
            }
            _ => {}
        }
        k
    }

    /// `(u_s, u_c)` for `sin`/`cos` of `a_hat`.
    fn trig(&mut self, arg: &SPoly) -> (usize, usize) {
        let s = self.aux(AuxKind::Sin, 0.0, arg);
        let c = self.aux[s]
            .partner
            .expect("a sine auxiliary has its cosine partner");
        (s, c)
    }

    /// Polynomial of `op(a)` for a polynomial argument `a`.
    fn apply(&mut self, op: ExprOp, a: &SPoly) -> Result<SPoly, RecastError> {
        let a0 = a.constant_term();
        let ah = a.without_constant();
        let singular = |b: &Self, function: &'static str| RecastError::Singular {
            function,
            argument: b.show(a),
            value: a0,
        };
        if ah.is_zero() {
            let v = match op {
                ExprOp::Sin => a0.sin(),
                ExprOp::Cos => a0.cos(),
                ExprOp::Exp => a0.exp(),
                ExprOp::Ln => a0.ln(),
                ExprOp::Sqrt => a0.sqrt(),
                _ => a0.recip(),
            };
            return if v.is_finite() {
                Ok(SPoly::constant(v))
            } else {
                Err(singular(self, op.name()))
            };
        }
        let mut p = SPoly::zero();
        match op {
            ExprOp::Sin | ExprOp::Cos => {
                let (s, c) = self.trig(&ah);
                let (sa, ca) = a0.sin_cos();
                let (k0, ks, kc) = if op == ExprOp::Sin {
                    (sa, ca, -sa)
                } else {
                    (ca, -sa, -ca)
                };
                p.add_term(Vec::new(), k0);
                p.add_scaled(&self.var(s), ks);
                p.add_scaled(&self.var(c), kc);
            }
            ExprOp::Exp => {
                let e = self.aux(AuxKind::ExpMinusOne, 0.0, &ah);
                let ea = a0.exp();
                p.add_term(Vec::new(), ea);
                p.add_scaled(&self.var(e), ea);
            }
            ExprOp::Ln => {
                if a0.is_nan() || a0 <= 0.0 {
                    return Err(singular(self, "ln"));
                }
                let l = self.aux(AuxKind::Ln, a0, &ah);
                p.add_term(Vec::new(), a0.ln());
                p.add_scaled(&self.var(l), 1.0);
            }
            ExprOp::Sqrt => {
                if a0.is_nan() || a0 <= 0.0 {
                    return Err(singular(self, "sqrt"));
                }
                let q = self.aux(AuxKind::Sqrt, a0, &ah);
                p.add_term(Vec::new(), a0.sqrt());
                p.add_scaled(&self.var(q), 1.0);
            }
            _ => {
                if a0 == 0.0 || !a0.recip().is_finite() {
                    return Err(singular(self, "recip"));
                }
                let r = self.aux(AuxKind::Recip, a0, &ah);
                p.add_term(Vec::new(), a0.recip());
                p.add_scaled(&self.var(r), 1.0);
            }
        }
        Ok(p)
    }

    /// Time derivative of state `v` as a polynomial; `ctx` names the function
    /// whose argument needs it (for the error message).
    fn deriv_var(&mut self, v: usize, ctx: (&'static str, &SPoly)) -> Result<SPoly, RecastError> {
        if v < self.n {
            return match self.n_dof {
                Some(nd) if v < nd => Ok(SPoly::var(nd + v)),
                _ => Err(RecastError::NoTimeDerivative {
                    function: ctx.0,
                    argument: self.show(ctx.1),
                    state: self.name(v),
                }),
            };
        }
        let k = v - self.n;
        if let Some(d) = self.derivs.get(&k) {
            return Ok(d.clone());
        }
        let arg = self.aux[k].arg.clone();
        let a0 = self.aux[k].a0;
        let kind = self.aux[k].kind;
        let da = self.deriv(&arg, (fn_name(kind), &arg))?;
        let one = SPoly::constant(1.0);
        let factor = match kind {
            AuxKind::Sin => {
                let c = self.aux[k].partner.expect("pair");
                one.plus(&self.var(c).scaled(-1.0))
            }
            AuxKind::OneMinusCos => self.var(self.aux[k].partner.expect("pair")),
            AuxKind::ExpMinusOne => one.plus(&self.var(k)),
            AuxKind::Ln => {
                let r = self.aux[k].partner.expect("recip partner");
                self.var(r).plus(&SPoly::constant(a0.recip()))
            }
            AuxKind::Recip => self
                .var(k)
                .plus(&SPoly::constant(a0.recip()))
                .pow(2)
                .scaled(-1.0),
            AuxKind::Sqrt => {
                // d sqrt(a) = a' / (2 sqrt(a)), with 1/sqrt(a) an auxiliary of its own
                let s0 = a0.sqrt();
                let vk = self.var(k);
                let r = self.aux(AuxKind::Recip, s0, &vk);
                self.var(r).plus(&SPoly::constant(s0.recip())).scaled(0.5)
            }
        };
        let d = factor.times(&da);
        self.derivs.insert(k, d.clone());
        Ok(d)
    }

    /// Time derivative of a polynomial, `sum_v (d p / d z_v) z_v'`.
    fn deriv(&mut self, p: &SPoly, ctx: (&'static str, &SPoly)) -> Result<SPoly, RecastError> {
        let mut out = SPoly::zero();
        for v in p.vars() {
            let dv = self.deriv_var(v, ctx)?;
            out.add_scaled(&p.diff(v).times(&dv), 1.0);
        }
        Ok(out)
    }

    /// Right-hand side of auxiliary `k`'s own equation.
    fn equation(&mut self, k: usize) -> Result<SPoly, RecastError> {
        let a = &self.aux[k];
        let (kind, a0, arg) = (a.kind, a.a0, a.arg.clone());
        if kind.is_differential() {
            return self.deriv_var(self.n + k, (fn_name(kind), &arg));
        }
        let u = self.var(k);
        Ok(match kind {
            AuxKind::OneMinusCos => {
                // u_s^2 - 2 u_c + u_c^2 = 0  (u_s^2 + (1 - u_c)^2 = 1)
                let s = self.var(self.aux[k].partner.expect("pair"));
                let mut p = s.pow(2);
                p.add_scaled(&u, -2.0);
                p.add_scaled(&u.pow(2), 1.0);
                p
            }
            AuxKind::Recip => {
                // (u + 1/a0)(a0 + a_hat) = 1, divided by a0
                let mut p = u.clone();
                p.add_scaled(&arg, 1.0 / (a0 * a0));
                p.add_scaled(&u.times(&arg), 1.0 / a0);
                p
            }
            _ => {
                // (u + s0)^2 = a0 + a_hat, divided by 2 s0
                let s0 = a0.sqrt();
                let mut p = u.clone();
                p.add_scaled(&u.pow(2), 0.5 / s0);
                p.add_scaled(&arg, -0.5 / s0);
                p
            }
        })
    }
}

fn fn_name(kind: AuxKind) -> &'static str {
    match kind {
        AuxKind::Sin | AuxKind::OneMinusCos => "sin/cos",
        AuxKind::ExpMinusOne => "exp",
        AuxKind::Ln => "ln",
        AuxKind::Recip => "recip",
        AuxKind::Sqrt => "sqrt",
    }
}

/// `coeff * prod_k (z_eq + z_hat)_{v_k}^{p_k}` as a polynomial in `z_hat`.
fn shifted_monomial(coeff: f64, factors: &[ssm_api::VarPower], eq: &[f64]) -> SPoly {
    let mut p = SPoly::constant(coeff);
    for f in factors {
        let v = f.var as usize;
        let base = if eq[v] == 0.0 {
            SPoly::var(v)
        } else {
            SPoly::var(v).plus(&SPoly::constant(eq[v]))
        };
        p = p.times(&base.pow(f.power));
    }
    p
}

/// Recasts `src` (see the module documentation).
pub fn recast(src: Source<'_>) -> Result<Recast, RecastError> {
    let n = src.states.len();
    let eq: Vec<f64> = if src.equilibrium.is_empty() {
        vec![0.0; n]
    } else if src.equilibrium.len() == n && src.equilibrium.iter().all(|v| v.is_finite()) {
        src.equilibrium.to_vec()
    } else {
        return Err(RecastError::EquilibriumShape {
            found: src.equilibrium.len(),
            expected: n,
        });
    };
    let graph = ExprGraph::validate(src.e, n)?;
    // auxiliaries are u1, u2, ... as in the paper unless the model has such names
    let clash = src.states.iter().any(|s| {
        s.name
            .strip_prefix('u')
            .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
    });
    let mut bld = Builder {
        n,
        prefix: if clash { "aux_u" } else { "u" },
        n_dof: src.n_dof,
        states: src.states,
        aux: Vec::new(),
        index: HashMap::new(),
        derivs: HashMap::new(),
    };

    // right-hand side rows in z_hat and auxiliaries, with the size of what
    // cancels at the equilibrium
    let mut rows = vec![SPoly::zero(); n];
    let mut scale = vec![0.0f64; n];
    let a = src.a.as_ref();
    for (c, &ec) in eq.iter().enumerate() {
        for (r, &v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
            rows[r].add_term(vec![(c as u32, 1)], v);
            rows[r].add_term(Vec::new(), v * ec);
            scale[r] += (v * ec).abs();
        }
    }
    for t in src.f.terms.iter() {
        let r = t.eq as usize;
        let p = shifted_monomial(t.coeff, &t.factors, &eq);
        scale[r] += p.constant_term().abs();
        rows[r].add_scaled(&p, 1.0);
    }
    let mut node_poly: Vec<SPoly> = Vec::with_capacity(graph.nodes().len());
    for nd in graph.nodes() {
        let p = match nd.op {
            ExprOp::Const => SPoly::constant(nd.value),
            ExprOp::Var => {
                let v = nd.a as usize;
                SPoly::var(v).plus(&SPoly::constant(eq[v]))
            }
            ExprOp::Add => node_poly[nd.a as usize].plus(&node_poly[nd.b as usize]),
            ExprOp::Mul => node_poly[nd.a as usize].times(&node_poly[nd.b as usize]),
            ExprOp::Powi => {
                let e = nd.value as i32;
                let base = if e < 0 {
                    bld.apply(ExprOp::Recip, &node_poly[nd.a as usize])?
                } else {
                    node_poly[nd.a as usize].clone()
                };
                base.pow(e.unsigned_abs())
            }
            op => bld.apply(op, &node_poly[nd.a as usize])?,
        };
        node_poly.push(p);
    }
    for &(r, node) in graph.terms() {
        scale[r] += node_poly[node].constant_term().abs();
        rows[r].add_scaled(&node_poly[node], 1.0);
    }
    for (r, row) in rows.iter().enumerate() {
        let c = row.constant_term();
        if c.abs() > EQUILIBRIUM_TOL * scale[r].max(1.0) {
            return Err(RecastError::NotAnEquilibrium {
                equation: r,
                state: src.states[r].name.to_string(),
                residual: c,
            });
        }
    }
    // the auxiliaries' own equations (they may create further auxiliaries)
    let mut aux_rows = Vec::new();
    let mut k = 0;
    while k < bld.aux.len() {
        aux_rows.push(bld.equation(k)?);
        k += 1;
    }
    let n_aux = bld.aux.len();
    let big_n = n + n_aux;

    // assemble A, B, F of the recast system
    let mut a_trip = Vec::new();
    let mut f = PolyVector::zeros(big_n, big_n);
    for (r, row) in rows.iter().chain(aux_rows.iter()).enumerate() {
        for (m, c) in row.terms() {
            match m.iter().map(|t| t.1).sum::<u32>() {
                0 => {}
                1 => a_trip.push(Triplet::new(r, m[0].0 as usize, c)),
                _ => {
                    let factors: Vec<(usize, u32)> =
                        m.iter().map(|&(v, p)| (v as usize, p)).collect();
                    f.push(r, c, &factors);
                }
            }
        }
    }
    let mut b_trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
    let b = src.b.as_ref();
    for c in 0..n {
        for (r, &v) in b.row_idx_of_col(c).zip(b.val_of_col(c)) {
            b_trip.push(Triplet::new(r, c, v));
        }
    }
    for (k, x) in bld.aux.iter().enumerate() {
        if x.kind.is_differential() {
            b_trip.push(Triplet::new(n + k, n + k, 1.0));
        }
    }
    let new_a = SparseColMat::try_new_from_triplets(big_n, big_n, &a_trip)
        .expect("recast A indices are in range");
    let new_b = SparseColMat::try_new_from_triplets(big_n, big_n, &b_trip)
        .expect("recast B indices are in range");

    // physical pencil: auxiliaries eliminated through u = L z_hat
    let mut lin: Vec<Vec<(usize, f64)>> = Vec::with_capacity(n_aux);
    for x in &bld.aux {
        let s = x.kind.slope(x.a0);
        let mut l: HashMap<usize, f64> = HashMap::new();
        if s != 0.0 {
            for (m, c) in x.arg.terms() {
                if m.len() == 1 && m[0].1 == 1 {
                    let v = m[0].0 as usize;
                    if v < n {
                        *l.entry(v).or_insert(0.0) += s * c;
                    } else {
                        for &(j, w) in &lin[v - n] {
                            *l.entry(j).or_insert(0.0) += s * c * w;
                        }
                    }
                }
            }
        }
        let mut l: Vec<(usize, f64)> = l.into_iter().filter(|e| e.1 != 0.0).collect();
        l.sort_by_key(|e| e.0);
        lin.push(l);
    }
    let mut p_trip = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        for (m, c) in row.terms() {
            if m.len() == 1 && m[0].1 == 1 {
                let v = m[0].0 as usize;
                if v < n {
                    p_trip.push(Triplet::new(r, v, c));
                } else {
                    for &(j, w) in &lin[v - n] {
                        p_trip.push(Triplet::new(r, j, c * w));
                    }
                }
            }
        }
    }
    let physical_a = SparseColMat::try_new_from_triplets(n, n, &p_trip)
        .expect("physical A indices are in range");

    let forcing = src
        .forcing
        .iter()
        .map(|h| Harmonic {
            multiple: h.multiple,
            cos: shift_poly(&h.cos, &eq, big_n),
            sin: shift_poly(&h.sin, &eq, big_n),
        })
        .collect();
    let auxiliaries = bld
        .aux
        .iter()
        .enumerate()
        .map(|(k, x)| {
            let arg = bld.show(&x.arg.plus(&SPoly::constant(x.a0)));
            let name = bld.name(n + k);
            let definition = match x.kind {
                AuxKind::Sin => format!("{name} = sin({})", bld.show(&x.arg)),
                AuxKind::OneMinusCos => format!("{name} = 1 - cos({})", bld.show(&x.arg)),
                AuxKind::ExpMinusOne => format!("{name} = exp({}) - 1", bld.show(&x.arg)),
                AuxKind::Ln => format!("{name} = ln(({arg}) / {})", x.a0),
                AuxKind::Recip => format!("{name} = 1/({arg}) - 1/{}", x.a0),
                AuxKind::Sqrt => format!("{name} = sqrt({arg}) - sqrt({})", x.a0),
            };
            Auxiliary {
                state: n + k,
                name,
                definition,
                kind: x.kind,
                argument: x.arg.clone(),
                a0: x.a0,
            }
        })
        .collect();
    Ok(Recast {
        a: new_a,
        b: new_b,
        nonlinearity: f,
        forcing,
        info: RecastInfo {
            n_original: n,
            auxiliaries,
            equilibrium: eq,
            physical_a,
            physical_b: src.b.clone(),
            original_a: src.a.clone(),
            original_f: src.f.clone(),
            original_e: graph,
        },
    })
}

/// A polynomial vector in `z` rewritten in `z_hat` (with `big_n` variables).
fn shift_poly(p: &PolyVector, eq: &[f64], big_n: usize) -> PolyVector {
    let mut out = PolyVector::zeros(big_n, big_n);
    for t in p.terms.iter() {
        for (m, c) in shifted_monomial(t.coeff, &t.factors, eq).terms() {
            let factors: Vec<(usize, u32)> = m.iter().map(|&(v, p)| (v as usize, p)).collect();
            out.push(t.eq as usize, c, &factors);
        }
    }
    out
}
