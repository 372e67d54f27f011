//! The Galerkin projection of a polynomial mechanical model onto a POD
//! subspace with reduced constraints: the reduced DAE of eq. (14) of
//! Stadlmayr, Witteveen & Steiner (2017), written as a model of its own.
//!
//! In the canonical first-order layout `z = (q, q', mu)` of the mechanical
//! builder (Li, Jain & Haller 2023, eqs. (4)-(5)), the ansatz
//! `q = U q_r`, `q' = U q_r'`, `mu = L mu_l` is `z = V y` with
//! `V = blkdiag(U, U, L)`, and premultiplying by `V^T` gives
//!
//! - momentum rows: `U^T C U q_r' + U^T M U v_r' = -U^T K U q_r - U^T f(U q_r, U v_r)
//!   - U^T C_q(U q_r)^T L mu_l + eps U^T fext` (eq. 14, with
//!   `C_{l q, r} = L^T C_q U`),
//! - kinematic rows: `U^T M U q_r' = U^T M U v_r`,
//! - constraint rows: `0 = L^T C(U q_r)` (eq. 13, `C_l = (L^i)^T C`),
//!
//! that is `B_r = V^T B V`, `A_r = V^T A V`, `F_r(y) = V^T F(V y)`,
//! `Fext_r(y) = V^T Fext(V y)`. Because the model is polynomial the
//! substitution is exact: the reduced model is again a sparse polynomial
//! model, whose evaluation costs nothing of the full model's size (the paper
//! instead lifts `q_r` to the full space at every evaluation, which it names
//! the bottleneck of the method). The mass matrix stays constant. The
//! model's origin (the reference configuration it is written about, at rest
//! when unforced) plays the role of `q_0` in the residual term
//! `R_q0 = q_0 - U U^T q_0` of eq. (8), which is therefore zero; what `U`
//! misses of a run's own initial values is reported by the reducer.
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint reduction
//! method for reduced order MBS models*, Multibody Syst. Dyn. (2017), eqs.
//! (7)-(14); M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), eqs. (4)-(5).

use std::collections::HashMap;

use faer::MatRef;
use ssm_api::{
    Harmonic, Lift, MechanicalInfo, Model, MotionKind, Output, PolyVector, SparseMatrix, StateInfo,
    StateKind, TimeKind, Weight,
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

/// The reduced model `V^T (B V y' - A V y - F(V y) - eps Fext(V y))` of a
/// mechanical `sys` in the canonical layout, with `U` (`n x r`) and `L`
/// (`n_c x l`), and the lift `z = V y` back to `sys`'s states.
///
/// The reduced states are `(q_r, q_r', mu_l)`; their outputs carry their
/// names (multipliers `mu_l1`, ...), and every output of `sys` can be added
/// through the lift ([`super::lift_outputs`]).
pub fn project_mechanical(
    sys: &System,
    u: MatRef<'_, f64>,
    l: MatRef<'_, f64>,
    coords: &ReducedCoordinates,
) -> Result<(Model, Lift), GalerkinError> {
    let mech = supported(sys)?;
    let (n, nc) = (mech.n_dof, mech.n_constraints);
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
    let nr = 2 * r + nl;
    // rows of V: full state -> [(reduced state, weight)]
    let mut v_rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); 2 * n + nc];
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
    let a = congruence(sys.a.as_ref(), &v_rows, nr);
    let b = congruence(sys.b.as_ref(), &v_rows, nr);
    let nonlinearity = substitute(&sys.nonlinearity, &v_rows, nr);
    let forcing = sys
        .forcing
        .iter()
        .map(|h| Harmonic {
            multiple: h.multiple,
            cos: substitute(&h.cos, &v_rows, nr),
            sin: substitute(&h.sin, &v_rows, nr),
        })
        .collect();
    let mass = congruence_block(mech.mass.as_ref(), u);
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
        name: format!("{} (POD, r = {r}, l = {nl})", sys.name)
            .as_str()
            .into(),
        a,
        b,
        nonlinearity,
        forcing,
        states: states.into_iter().collect(),
        outputs,
        time: TimeKind::Flow,
        mechanical: abi_stable::std_types::ROption::RSome(MechanicalInfo::canonical(r, nl, mass)),
        expressions: ssm_api::ExprVector::zeros(nr, nr),
        equilibrium: Default::default(),
    };
    let mut basis = SparseMatrix::zeros(2 * n + nc, nr);
    for (k, row) in v_rows.iter().enumerate() {
        for &(j, w) in row {
            basis.push(k, j, w);
        }
    }
    let lift = Lift {
        basis,
        offset: Default::default(),
        full_states: sys.states.iter().cloned().collect(),
    };
    Ok((model, lift))
}

/// The mechanical structure of `sys` when it can be projected: a flow in
/// the canonical mechanical layout without auxiliary states.
pub fn supported(sys: &System) -> Result<&crate::model::system::Mechanical, GalerkinError> {
    let unsupported = |problem: &str| GalerkinError::Unsupported {
        model: sys.name.clone(),
        problem: problem.to_owned(),
    };
    let mech = sys
        .mechanical
        .as_ref()
        .ok_or_else(|| unsupported("not a mechanical model (no mass matrix and layout)"))?;
    if sys.time != TimeKind::Flow {
        return Err(unsupported("a map cannot be projected as a mechanical DAE"));
    }
    if sys.recast.is_some() || sys.states.len() != 2 * mech.n_dof + mech.n_constraints {
        return Err(unsupported(
            "it has auxiliary states (a recast of non-polynomial terms); POD projection needs a polynomial mechanical model",
        ));
    }
    Ok(mech)
}

fn state(name: &str, kind: StateKind, motion: MotionKind) -> StateInfo {
    StateInfo {
        name: name.into(),
        kind,
        motion,
    }
}

/// `V^T A V` of a sparse `A` with `V` given by its rows, as triplets.
fn congruence(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    v_rows: &[Vec<(usize, f64)>],
    nr: usize,
) -> SparseMatrix {
    let mut dense = vec![0.0; nr * nr];
    for k in 0..a.ncols() {
        let rows = a.row_idx_of_col(k);
        for (i, &val) in rows.zip(a.val_of_col(k)) {
            for &(p, vp) in &v_rows[i] {
                for &(q, vq) in &v_rows[k] {
                    dense[p * nr + q] += vp * val * vq;
                }
            }
        }
    }
    dense_to_sparse(&dense, nr, nr)
}

/// `U^T M U` of the mass matrix.
fn congruence_block(
    m: faer::sparse::SparseColMatRef<'_, usize, f64>,
    u: MatRef<'_, f64>,
) -> SparseMatrix {
    let r = u.ncols();
    let mut dense = vec![0.0; r * r];
    for k in 0..m.ncols() {
        for (i, &val) in m.row_idx_of_col(k).zip(m.val_of_col(k)) {
            for p in 0..r {
                let up = u[(i, p)] * val;
                if up != 0.0 {
                    for q in 0..r {
                        dense[p * r + q] += up * u[(k, q)];
                    }
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

/// `V^T P(V y)` of a polynomial vector `P` in the full states: every
/// monomial `c prod_k z_k^{p_k}` expanded with `z_k = sum_j V_kj y_j` and
/// sent to the reduced equations `V^T e_eq`.
fn substitute(poly: &PolyVector, v_rows: &[Vec<(usize, f64)>], nr: usize) -> PolyVector {
    // monomials as sorted lists of reduced variables with repetition
    let mut acc: Vec<HashMap<Vec<u32>, f64>> = vec![HashMap::new(); nr];
    for t in poly.terms.iter() {
        let rows = &v_rows[t.eq as usize];
        if rows.is_empty() {
            continue;
        }
        let mut expansion: HashMap<Vec<u32>, f64> = HashMap::from([(Vec::new(), t.coeff)]);
        for f in t.factors.iter() {
            for _ in 0..f.power {
                let mut next: HashMap<Vec<u32>, f64> = HashMap::with_capacity(expansion.len());
                for (mono, c) in &expansion {
                    for &(j, w) in &v_rows[f.var as usize] {
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
    let mut out = PolyVector::zeros(nr, nr);
    for (eq, terms) in acc.into_iter().enumerate() {
        let mut terms: Vec<(Vec<u32>, f64)> =
            terms.into_iter().filter(|(_, c)| *c != 0.0).collect();
        terms.sort_by(|x, y| x.0.cmp(&y.0));
        for (mono, c) in terms {
            let mut factors: Vec<(usize, u32)> = Vec::new();
            for &v in &mono {
                match factors.last_mut() {
                    Some((var, p)) if *var == v as usize => *p += 1,
                    _ => factors.push((v as usize, 1)),
                }
            }
            out.push(eq, c, &factors);
        }
    }
    out
}
