//! The Galerkin projection of a mechanical model onto a POD subspace with
//! reduced constraints: the reduced DAE of eq. (14) of Stadlmayr, Witteveen
//! & Steiner (2017), written as a model of its own.
//!
//! In the canonical first-order layout `z = (q, q', mu)` of the mechanical
//! builder (Li, Jain & Haller 2023, eqs. (4)-(5)), the ansatz
//! `q = U q_r`, `q' = U q_r'`, `mu = mu_eq + L mu_l` about the equilibrium
//! is `z = z_eq + V y` with `V = blkdiag(U, U, L)`, and premultiplying by
//! `V^T` gives
//!
//! - momentum rows: `U^T C U q_r' + U^T M U v_r' = -U^T K U q_r - U^T f(U q_r, U v_r)
//!   - U^T C_q(U q_r)^T (mu_eq + L mu_l) + eps U^T fext` (eq. 14, with
//!   `C_{l q, r} = L^T C_q U`),
//! - kinematic rows: `U^T M U q_r' = U^T M U v_r`,
//! - constraint rows: `0 = L^T C(U q_r)` (eq. 13, `C_l = (L^i)^T C`),
//!
//! that is `B_r = V^T B V` and `V^T` of every right-hand-side part at
//! `z_eq + V y`. Polynomial parts are substituted exactly and stay sparse
//! polynomials; non-polynomial parts (`sin phi`, `cos(phi) mu`) stay
//! expressions, their states replaced by the affine combinations, and the
//! engine recasts the reduced model like any plugin model. Its evaluation
//! costs nothing of the full model's size (the paper instead lifts `q_r` to
//! the full space at every evaluation, which it names the bottleneck of the
//! method). The mass matrix stays constant. The equilibrium (the reference
//! configuration, at rest when unforced) plays the role of `q_0` in the
//! residual term `R_q0 = q_0 - U U^T q_0` of eq. (8), which is therefore
//! zero; what `U` misses of a run's own initial values is reported by the
//! reducer.
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint reduction
//! method for reduced order MBS models*, Multibody Syst. Dyn. (2017), eqs.
//! (7)-(14); M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), eqs. (4)-(5).

use std::collections::HashMap;

use faer::MatRef;
use ssm_api::{
    ExprNode, ExprOp, ExprTerm, ExprVector, Harmonic, Lift, MechanicalInfo, Model, MotionKind,
    Output, PolyVector, SparseMatrix, StateInfo, StateKind, TimeKind, Weight,
};

use crate::model::system::System;

/// Why a model cannot be projected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GalerkinError {
    /// The model is not mechanical, is a map, or has auxiliary states.
    #[error("model '{model}': {problem}")]
    Unsupported {
        /// Model name.
        model: String,
        /// What is missing or extra.
        problem: String,
    },
    /// The model itself is invalid (an index out of range, a NaN, ...).
    #[error("model '{model}' is invalid: {problem}")]
    Invalid {
        /// Model name.
        model: String,
        /// What the validation found.
        problem: String,
    },
    /// A basis has the wrong number of rows, or a name list the wrong length.
    #[error("{what} has {found} rows or entries, expected {expected}")]
    Shape {
        /// Which input.
        what: &'static str,
        /// Found.
        found: usize,
        /// Expected.
        expected: usize,
    },
    /// A basis entry is NaN or infinite.
    #[error("{what} has a non-finite entry at ({row}, {col})")]
    NotFinite {
        /// Which basis.
        what: &'static str,
        /// Row.
        row: usize,
        /// Column.
        col: usize,
    },
}

/// The reduced coordinates: a name and a motion kind for each column of `U`.
#[derive(Debug, Clone, PartialEq)]
pub struct ReducedCoordinates {
    /// Names of the `r` reduced coordinates (velocities get `<name>_dot`).
    pub names: Vec<String>,
    /// Motion kind of each (the kind of the POD block it came from).
    pub motion: Vec<MotionKind>,
}

/// The reduced model `V^T (B V y' - A z - F(z) - E(z) - eps Fext(z))`,
/// `z = z_eq + V y`, of the mechanical plugin model `full` in the canonical
/// layout, with `U` (`n x r`) and `L` (`n_c x l`), and the lift
/// `z = z_eq + V y` back to `full`'s states.
///
/// The polynomial parts are expanded exactly. Non-polynomial terms `E`
/// (`sin phi`, `l cos(phi) mu`, ...) stay expressions, their states replaced
/// by `z_eq + V y`: the engine recasts the reduced model like any other, its
/// auxiliaries then stand for `sin` of the lifted angles. The reduced model
/// is written about `y = 0`, where its right-hand side is `V^T` of the full
/// one at the equilibrium `z_eq`, zero.
///
/// The reduced states are `(q_r, q_r', mu_l)`; their outputs carry their
/// names (multipliers `mu_l1`, ...), and every output of `full` can be
/// added through the lift ([`super::lift_outputs`]).
pub fn project_mechanical(
    full: &Model,
    u: MatRef<'_, f64>,
    l: MatRef<'_, f64>,
    coords: &ReducedCoordinates,
) -> Result<(Model, Lift), GalerkinError> {
    project(full, u, l, coords, true)
}

/// [`project_mechanical`], or with `expand` false and a full model that is
/// polynomial about `z = 0` (no expressions, no equilibrium offset), the
/// reduced model without its nonlinearity: the terms of degree two and more
/// are left out, for a run that evaluates them through the lift
/// ([`super::hyper::lifted_exact`]); its name says so.
pub(crate) fn project(
    full: &Model,
    u: MatRef<'_, f64>,
    l: MatRef<'_, f64>,
    coords: &ReducedCoordinates,
    expand: bool,
) -> Result<(Model, Lift), GalerkinError> {
    let (n, nc) = supported(full)?;
    // every index of the model in range, every value finite: the
    // substitution below indexes by them
    System::from_model("projection", full.clone()).map_err(|e| GalerkinError::Invalid {
        model: full.name.to_string(),
        problem: e.to_string(),
    })?;
    let (r, nl) = (u.ncols(), l.ncols());
    for (what, m, rows) in [("U", u, n), ("L", l, nc)] {
        if m.nrows() != rows {
            return Err(GalerkinError::Shape {
                what,
                found: m.nrows(),
                expected: rows,
            });
        }
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                if !m[(i, j)].is_finite() {
                    return Err(GalerkinError::NotFinite {
                        what,
                        row: i,
                        col: j,
                    });
                }
            }
        }
    }
    if coords.names.len() != r || coords.motion.len() != r {
        return Err(GalerkinError::Shape {
            what: "reduced coordinate names and kinds",
            found: coords.names.len().min(coords.motion.len()),
            expected: r,
        });
    }
    let big_n = 2 * n + nc;
    let z_eq: Vec<f64> = if full.equilibrium.is_empty() {
        vec![0.0; big_n]
    } else {
        full.equilibrium.to_vec()
    };
    let nr = 2 * r + nl;
    // rows of V: full state -> [(reduced state, weight)]
    let mut v_rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); big_n];
    for i in 0..n {
        for j in 0..r {
            let w = u[(i, j)];
            if w != 0.0 {
                v_rows[i].push((j, w));
                v_rows[n + i].push((r + j, w));
            }
        }
    }
    for c in 0..nc {
        for j in 0..nl {
            let w = l[(c, j)];
            if w != 0.0 {
                v_rows[2 * n + c].push((2 * r + j, w));
            }
        }
    }
    let affine = Affine {
        rows: &v_rows,
        offset: &z_eq,
        nr,
    };
    // V^T A (z_eq + V y) + V^T F(z_eq + V y): constants, linear part, the rest
    let mut a = congruence(&full.a, &v_rows, nr);
    let mut constant = vec![0.0; nr];
    for (i, k, val) in full.a.iter() {
        for &(p, wp) in &v_rows[i] {
            constant[p] += wp * val * z_eq[k];
        }
    }
    let mut nonlinearity = PolyVector::zeros(nr, nr);
    let skip = !expand && full.expressions.terms.is_empty() && z_eq.iter().all(|&v| v == 0.0);
    let kept;
    let expanded = if skip {
        let mut low = PolyVector::zeros(full.nonlinearity.n_eq as usize, big_n);
        for t in full.nonlinearity.terms.iter() {
            if t.factors.iter().map(|f| f.power).sum::<u32>() < 2 {
                let f: Vec<(usize, u32)> = t
                    .factors
                    .iter()
                    .map(|f| (f.var as usize, f.power))
                    .collect();
                low.push(t.eq as usize, t.coeff, &f);
            }
        }
        kept = low;
        &kept
    } else {
        &full.nonlinearity
    };
    for (eq, mono, c) in affine.substitute(expanded) {
        match mono.len() {
            0 => constant[eq] += c,
            1 => a[eq * nr + mono[0] as usize] += c,
            _ => nonlinearity.push(eq, c, &factors(&mono)),
        }
    }
    let forcing = full
        .forcing
        .iter()
        .map(|h| {
            let poly = |p: &PolyVector| {
                let mut out = PolyVector::zeros(nr, nr);
                for (eq, mono, c) in affine.substitute(p) {
                    out.push(eq, c, &factors(&mono));
                }
                out
            };
            Harmonic {
                multiple: h.multiple,
                cos: poly(&h.cos),
                sin: poly(&h.sin),
            }
        })
        .collect();
    let expressions = substitute_expressions(&full.expressions, &affine, &constant);
    let mech = full.mechanical.as_ref().into_option().expect("checked");
    let mass = congruence_block(&mech.mass, u);
    let mut states = Vec::with_capacity(nr);
    for (name, &motion) in coords.names.iter().zip(&coords.motion) {
        states.push(state(name, StateKind::Displacement, motion));
    }
    for (name, &motion) in coords.names.iter().zip(&coords.motion) {
        states.push(state(&format!("{name}_dot"), StateKind::Velocity, motion));
    }
    for j in 0..nl {
        states.push(state(
            &format!("mu_l{}", j + 1),
            StateKind::Multiplier,
            MotionKind::Unspecified,
        ));
    }
    let outputs = states
        .iter()
        .enumerate()
        .map(|(k, s)| Output {
            name: s.name.clone(),
            weights: vec![Weight {
                state: k as u32,
                value: 1.0,
            }]
            .into(),
        })
        .collect();
    let model = Model {
        name: format!(
            "{} (POD, r = {r}, l = {nl}{})",
            full.name,
            if skip { ", nonlinearity lifted" } else { "" }
        )
        .as_str()
        .into(),
        a: dense_to_sparse(&a, nr, nr),
        b: dense_to_sparse(&congruence(&full.b, &v_rows, nr), nr, nr),
        nonlinearity: nonlinearity.canonical(),
        forcing,
        states: states.into_iter().collect(),
        outputs,
        time: TimeKind::Flow,
        mechanical: abi_stable::std_types::ROption::RSome(MechanicalInfo::canonical(r, nl, mass)),
        expressions,
        equilibrium: Default::default(),
    };
    let mut basis = SparseMatrix::zeros(big_n, nr);
    for (k, row) in v_rows.iter().enumerate() {
        for &(j, w) in row {
            basis.push(k, j, w);
        }
    }
    let lift = Lift {
        basis,
        offset: full.equilibrium.clone(),
        full_states: full.states.clone(),
    };
    Ok((model, lift))
}

/// The canonical mechanical layout `(q, q', mu)` of `full`, `(n, n_c)`, when
/// it can be projected: a mechanical flow whose states are exactly that.
pub fn supported(full: &Model) -> Result<(usize, usize), GalerkinError> {
    let unsupported = |problem: &str| GalerkinError::Unsupported {
        model: full.name.to_string(),
        problem: problem.to_owned(),
    };
    let mech = full
        .mechanical
        .as_ref()
        .into_option()
        .ok_or_else(|| unsupported("not a mechanical model (no mass matrix and layout)"))?;
    if full.time != TimeKind::Flow {
        return Err(unsupported("a map cannot be projected as a mechanical DAE"));
    }
    let (n, nc) = (mech.n_dof as usize, mech.n_constraints as usize);
    if *mech != MechanicalInfo::canonical(n, nc, mech.mass.clone())
        || full.states.len() != 2 * n + nc
    {
        return Err(unsupported(
            "its states are not the canonical mechanical layout (q, q', mu) with constraint rows after the momentum rows",
        ));
    }
    Ok((n, nc))
}

fn state(name: &str, kind: StateKind, motion: MotionKind) -> StateInfo {
    StateInfo {
        name: name.into(),
        kind,
        motion,
    }
}

/// `V^T A V` of a sparse `A` with `V` given by its rows, row-major dense.
fn congruence(a: &SparseMatrix, v_rows: &[Vec<(usize, f64)>], nr: usize) -> Vec<f64> {
    let mut dense = vec![0.0; nr * nr];
    for (i, k, val) in a.iter() {
        for &(p, vp) in &v_rows[i] {
            for &(q, vq) in &v_rows[k] {
                dense[p * nr + q] += vp * val * vq;
            }
        }
    }
    dense
}

/// `U^T M U` of the mass matrix.
fn congruence_block(m: &SparseMatrix, u: MatRef<'_, f64>) -> SparseMatrix {
    let r = u.ncols();
    let mut dense = vec![0.0; r * r];
    for (i, k, val) in m.iter() {
        for p in 0..r {
            let up = u[(i, p)] * val;
            if up != 0.0 {
                for q in 0..r {
                    dense[p * r + q] += up * u[(k, q)];
                }
            }
        }
    }
    dense_to_sparse(&dense, r, r)
}

/// Triplets of a row-major dense matrix, exact zeros left out. Nothing is
/// dropped by size: the round-off of products that cancel costs a few
/// entries (8 of 278 polynomial terms on the crank drive), while a size
/// threshold would cut a tiny damping or a weak coupling.
fn dense_to_sparse(dense: &[f64], rows: usize, cols: usize) -> SparseMatrix {
    let mut s = SparseMatrix::zeros(rows, cols);
    for i in 0..rows {
        for j in 0..cols {
            let v = dense[i * cols + j];
            if v != 0.0 {
                s.push(i, j, v);
            }
        }
    }
    s
}

/// The affine substitution `z = z_eq + V y`: `V` by its rows.
struct Affine<'a> {
    rows: &'a [Vec<(usize, f64)>],
    offset: &'a [f64],
    nr: usize,
}

impl Affine<'_> {
    /// `V^T P(z_eq + V y)` of a polynomial vector `P` in the full states,
    /// as `(reduced equation, monomial, coefficient)`; a monomial is the
    /// sorted list of its reduced variables with repetition (empty: a
    /// constant). Every monomial `c prod_k z_k^{p_k}` is expanded with
    /// `z_k = z_eq,k + sum_j V_kj y_j` and sent to `V^T e_eq`.
    fn substitute(&self, poly: &PolyVector) -> Vec<(usize, Vec<u32>, f64)> {
        let mut acc: Vec<HashMap<Vec<u32>, f64>> = vec![HashMap::new(); self.nr];
        for t in poly.terms.iter() {
            let rows = &self.rows[t.eq as usize];
            if rows.is_empty() {
                continue;
            }
            let mut expansion: HashMap<Vec<u32>, f64> = HashMap::from([(Vec::new(), t.coeff)]);
            for f in t.factors.iter() {
                let var = f.var as usize;
                for _ in 0..f.power {
                    let mut next: HashMap<Vec<u32>, f64> = HashMap::with_capacity(expansion.len());
                    for (mono, c) in &expansion {
                        if self.offset[var] != 0.0 {
                            *next.entry(mono.clone()).or_insert(0.0) += c * self.offset[var];
                        }
                        for &(j, w) in &self.rows[var] {
                            let mut m = mono.clone();
                            let at = m.partition_point(|&x| x <= j as u32);
                            m.insert(at, j as u32);
                            *next.entry(m).or_insert(0.0) += c * w;
                        }
                    }
                    expansion = next;
                }
            }
            for &(p, wp) in rows {
                for (mono, c) in &expansion {
                    *acc[p].entry(mono.clone()).or_insert(0.0) += wp * c;
                }
            }
        }
        let mut out = Vec::new();
        for (eq, terms) in acc.into_iter().enumerate() {
            let mut terms: Vec<(Vec<u32>, f64)> =
                terms.into_iter().filter(|(_, c)| *c != 0.0).collect();
            terms.sort_by(|x, y| x.0.cmp(&y.0));
            out.extend(terms.into_iter().map(|(m, c)| (eq, m, c)));
        }
        out
    }
}

/// `(variable, power)` factors of a sorted monomial with repetition.
fn factors(mono: &[u32]) -> Vec<(usize, u32)> {
    let mut out: Vec<(usize, u32)> = Vec::new();
    for &v in mono {
        match out.last_mut() {
            Some((var, p)) if *var == v as usize => *p += 1,
            _ => out.push((v as usize, 1)),
        }
    }
    out
}

/// `V^T E(z_eq + V y) + constant` of the expressions `E` in the full states:
/// the graph copied node by node (shared sub-expressions stay shared), each
/// state replaced by its affine combination of the reduced states, each
/// term sent to `V^T e_eq`; `constant` (the polynomial parts' value at
/// `y = 0`) joins as constant terms, so the reduced right-hand side
/// vanishes at `y = 0` as a whole.
fn substitute_expressions(e: &ExprVector, affine: &Affine<'_>, constant: &[f64]) -> ExprVector {
    let nr = affine.nr;
    let mut out = ExprVector::zeros(nr, nr);
    let push = |nodes: &mut Vec<ExprNode>, op, a: u32, b: u32, value: f64| {
        nodes.push(ExprNode { op, a, b, value });
        (nodes.len() - 1) as u32
    };
    let mut nodes: Vec<ExprNode> = Vec::new();
    let mut var_node: HashMap<u32, u32> = HashMap::new();
    let mut map: Vec<u32> = Vec::with_capacity(e.nodes.len());
    for node in e.nodes.iter() {
        let new = if node.op == ExprOp::Var {
            if let Some(&k) = var_node.get(&node.a) {
                k
            } else {
                let i = node.a as usize;
                let mut acc = push(&mut nodes, ExprOp::Const, 0, 0, affine.offset[i]);
                for &(j, w) in &affine.rows[i] {
                    let c = push(&mut nodes, ExprOp::Const, 0, 0, w);
                    let y = push(&mut nodes, ExprOp::Var, j as u32, 0, 0.0);
                    let cy = push(&mut nodes, ExprOp::Mul, c, y, 0.0);
                    acc = push(&mut nodes, ExprOp::Add, acc, cy, 0.0);
                }
                var_node.insert(node.a, acc);
                acc
            }
        } else if node.op == ExprOp::Const {
            push(&mut nodes, ExprOp::Const, 0, 0, node.value)
        } else {
            let a = map[node.a as usize];
            let b = if node.op == ExprOp::Add || node.op == ExprOp::Mul {
                map[node.b as usize]
            } else {
                0
            };
            push(&mut nodes, node.op, a, b, node.value)
        };
        map.push(new);
    }
    let mut terms = Vec::new();
    for t in e.terms.iter() {
        for &(p, w) in &affine.rows[t.eq as usize] {
            let c = push(&mut nodes, ExprOp::Const, 0, 0, w);
            let node = push(&mut nodes, ExprOp::Mul, c, map[t.node as usize], 0.0);
            terms.push(ExprTerm { eq: p as u32, node });
        }
    }
    for (p, &c) in constant.iter().enumerate() {
        if c != 0.0 {
            let node = push(&mut nodes, ExprOp::Const, 0, 0, c);
            terms.push(ExprTerm { eq: p as u32, node });
        }
    }
    out.nodes = nodes.into_iter().collect();
    out.terms = terms.into_iter().collect();
    out
}
