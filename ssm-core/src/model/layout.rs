//! The constraint layout a plugin declares ([`ssm_api::MechanicalInfo`]):
//! which states are the displacements `x`, velocities `x'` and multipliers
//! `mu`, and which rows are the configuration constraints `0 = g(x)`.
//!
//! The layout is checked against the state tags and the model (a constraint
//! row is algebraic: no entry of `B`), then the model is permuted into the
//! canonical order the engine works in: states `(x, x', mu, rest)`, the
//! constraint rows at `2n .. 2n + n_c`, the other rows in their own order. A
//! model already in that order (every model of the mechanical builder) is
//! returned unchanged.

use ssm_api::{
    ExprOp, ExprVector, Harmonic, MechanicalInfo, Model, PolyVector, SparseMatrix, StateKind,
};

/// Why a declared layout cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LayoutError {
    /// A list has the wrong length.
    #[error("{list} lists {found} states or rows, expected {expected} ({why})")]
    Length {
        /// Which list.
        list: &'static str,
        /// Entries found.
        found: usize,
        /// Entries expected.
        expected: usize,
        /// Where the expectation comes from.
        why: &'static str,
    },
    /// An index is outside the model or used twice.
    #[error("{list} entry {entry} is {index}: {problem}")]
    Index {
        /// Which list.
        list: &'static str,
        /// 0-based entry.
        entry: usize,
        /// The index.
        index: usize,
        /// What is wrong.
        problem: String,
    },
    /// A declared state does not carry the tag its role needs.
    #[error("{list} entry {entry} is state '{state}', tagged {found:?}, but a {role} must be tagged {expected:?}")]
    Tag {
        /// Which list.
        list: &'static str,
        /// 0-based entry.
        entry: usize,
        /// State name.
        state: String,
        /// Tag found.
        found: StateKind,
        /// Tag required.
        expected: StateKind,
        /// Role of the list.
        role: &'static str,
    },
    /// A declared constraint row has entries in `B` (it is differential).
    #[error("constraint row {row} has an entry in B at column {col}: a configuration constraint 0 = g(x) is algebraic")]
    DifferentialConstraint {
        /// The row.
        row: usize,
        /// A column of `B` with an entry in it.
        col: usize,
    },
}

/// Checks the layout of `model` and returns it in canonical order.
pub fn canonicalize(mut model: Model) -> Result<Model, LayoutError> {
    let Some(info) = model.mechanical.as_ref().into_option() else {
        return Ok(model);
    };
    let n_states = model.states.len();
    let (state_perm, row_perm) = check(info, &model, n_states)?;
    let identity = |p: &[usize]| p.iter().enumerate().all(|(i, &k)| i == k);
    if identity(&state_perm) && identity(&row_perm) {
        return Ok(model);
    }
    // new_of_state[old] = new index of an old state; likewise for rows
    let inverse = |p: &[usize]| {
        let mut inv = vec![0; p.len()];
        for (new, &old) in p.iter().enumerate() {
            inv[old] = new;
        }
        inv
    };
    let (col_new, row_new) = (inverse(&state_perm), inverse(&row_perm));
    let matrix = |m: &SparseMatrix| SparseMatrix {
        nrows: m.nrows,
        ncols: m.ncols,
        entries: m
            .entries
            .iter()
            .map(|t| ssm_api::Triplet {
                row: row_new[t.row as usize] as u32,
                col: col_new[t.col as usize] as u32,
                value: t.value,
            })
            .collect(),
    };
    let poly = |p: &PolyVector| {
        let mut p = p.clone();
        for t in p.terms.iter_mut() {
            t.eq = row_new[t.eq as usize] as u32;
            for f in t.factors.iter_mut() {
                f.var = col_new[f.var as usize] as u32;
            }
            t.factors.sort_by_key(|f| f.var);
        }
        p
    };
    let exprs = |e: &ExprVector| {
        let mut e = e.clone();
        for node in e.nodes.iter_mut().filter(|n| n.op == ExprOp::Var) {
            node.a = col_new[node.a as usize] as u32;
        }
        for t in e.terms.iter_mut() {
            t.eq = row_new[t.eq as usize] as u32;
        }
        e
    };
    model.a = matrix(&model.a);
    model.b = matrix(&model.b);
    model.nonlinearity = poly(&model.nonlinearity);
    model.expressions = exprs(&model.expressions);
    model.forcing = model
        .forcing
        .iter()
        .map(|h| Harmonic {
            multiple: h.multiple,
            cos: poly(&h.cos),
            sin: poly(&h.sin),
        })
        .collect();
    model.states = state_perm
        .iter()
        .map(|&k| model.states[k].clone())
        .collect();
    for o in model.outputs.iter_mut() {
        for w in o.weights.iter_mut() {
            if let Some(&k) = col_new.get(w.state as usize) {
                w.state = k as u32;
            }
        }
    }
    if model.equilibrium.len() == n_states {
        model.equilibrium = state_perm.iter().map(|&k| model.equilibrium[k]).collect();
    }
    let (nd, nc) = (info.n_dof as usize, info.n_constraints as usize);
    let mass = info.mass.clone();
    model.mechanical = Some(MechanicalInfo::canonical(nd, nc, mass)).into();
    Ok(model)
}

/// One declared list: name, indices, expected length, why, required tag, role.
type RoleList<'a> = (
    &'static str,
    &'a [u32],
    usize,
    &'static str,
    StateKind,
    &'static str,
);

/// The state order `(x, x', mu, rest)` and the row order (non-constraint rows
/// filling `0 .. 2n`, the constraints, then the remaining rows), after
/// checking every declared index and tag.
fn check(
    info: &MechanicalInfo,
    model: &Model,
    n_states: usize,
) -> Result<(Vec<usize>, Vec<usize>), LayoutError> {
    let (nd, nc) = (info.n_dof as usize, info.n_constraints as usize);
    let lists: [RoleList; 3] = [
        (
            "displacements",
            &info.displacements,
            nd,
            "n_dof",
            StateKind::Displacement,
            "displacement",
        ),
        (
            "velocities",
            &info.velocities,
            nd,
            "n_dof",
            StateKind::Velocity,
            "velocity",
        ),
        (
            "multipliers",
            &info.multipliers,
            nc,
            "n_constraints",
            StateKind::Multiplier,
            "multiplier",
        ),
    ];
    let mut used = vec![false; n_states];
    let mut order = Vec::with_capacity(n_states);
    for (list, idx, expected, why, tag, role) in lists {
        if idx.len() != expected {
            return Err(LayoutError::Length {
                list,
                found: idx.len(),
                expected,
                why,
            });
        }
        for (entry, &k) in idx.iter().enumerate() {
            let k = k as usize;
            if k >= n_states || used[k] {
                return Err(LayoutError::Index {
                    list,
                    entry,
                    index: k,
                    problem: if k >= n_states {
                        format!("the model has {n_states} states")
                    } else {
                        "the state is declared twice".into()
                    },
                });
            }
            let found = model.states[k].kind;
            if found != tag {
                return Err(LayoutError::Tag {
                    list,
                    entry,
                    state: model.states[k].name.to_string(),
                    found,
                    expected: tag,
                    role,
                });
            }
            used[k] = true;
            order.push(k);
        }
    }
    order.extend((0..n_states).filter(|&k| !used[k]));
    if info.constraint_rows.len() != nc {
        return Err(LayoutError::Length {
            list: "constraint_rows",
            found: info.constraint_rows.len(),
            expected: nc,
            why: "n_constraints",
        });
    }
    let mut is_constraint = vec![false; n_states];
    for (entry, &r) in info.constraint_rows.iter().enumerate() {
        let r = r as usize;
        if r >= n_states || is_constraint[r] {
            return Err(LayoutError::Index {
                list: "constraint_rows",
                entry,
                index: r,
                problem: if r >= n_states {
                    format!("the model has {n_states} rows")
                } else {
                    "the row is declared twice".into()
                },
            });
        }
        is_constraint[r] = true;
    }
    if let Some(t) = model
        .b
        .entries
        .iter()
        .find(|t| t.value != 0.0 && is_constraint.get(t.row as usize).copied().unwrap_or(false))
    {
        return Err(LayoutError::DifferentialConstraint {
            row: t.row as usize,
            col: t.col as usize,
        });
    }
    let mut others = (0..n_states).filter(|&r| !is_constraint[r]);
    let mut rows: Vec<usize> = others.by_ref().take(2 * nd).collect();
    rows.extend(info.constraint_rows.iter().map(|&r| r as usize));
    rows.extend(others);
    Ok((order, rows))
}
