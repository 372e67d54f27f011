//! The model as HHT sees it: the layout of the mechanical builder's rows,
//! the sparse iteration matrix on the unknowns `(a, mu, w_hat)` with its
//! reusable symbolic LU, and the momentum force.

use faer::linalg::solvers::PartialPivLu;
use faer::prelude::Solve;
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, Par};
use ssm_kernel::sparse_lu::SparseLu;

use super::HhtOptions;
use crate::fom::problem::square_pattern;
use crate::fom::{DaeProblem, SimError};

/// The momentum, constraint and auxiliary rows of a mechanical model as HHT
/// sees them.
pub(super) struct Layout {
    pub(super) n: usize,
    pub(super) n_c: usize,
    /// Per auxiliary row (rows `2n + n_c ..`): differential (`B` has entries
    /// in it) or algebraic.
    pub(super) differential: Vec<bool>,
}

/// Checks that `p` is the first-order form of the mechanical builder (Li,
/// Jain & Haller 2023, eqs. (4)-(5)) in canonical order: momentum rows
/// `0..n`, `C_B x' + M v' = A_m z + F_m(z)`; kinematic rows `n..2n`,
/// `E x' = E v`; constraint rows `2n .. 2n + n_c`, `0 = g(x, w)` (no `B`);
/// and the rows of a recast's auxiliaries `w` after them, differential
/// (`B_w w' = f_w(z)`, `B` only in auxiliary columns) or algebraic.
pub(super) fn layout(p: &DaeProblem) -> Result<Layout, SimError> {
    let sys = p.sys;
    let not = |why: String| {
        Err(SimError::Settings(format!(
            "HHT integrates second-order mechanical models (M x'' = f(x, x', mu, t), 0 = g(x)); {why}"
        )))
    };
    let Some(mech) = sys.mechanical.as_ref() else {
        return not("this model declares no mechanical structure".into());
    };
    let (n, n_c) = (mech.n_dof, mech.n_constraints);
    let big_n = sys.n_states();
    let first_aux = 2 * n + n_c;
    if big_n < first_aux {
        return not(format!(
            "{big_n} states, fewer than 2 n + n_c = {first_aux}"
        ));
    }
    let entries = |m: faer::sparse::SparseColMatRef<'_, usize, f64>| {
        let mut e: Vec<(usize, usize, f64)> = (0..m.ncols())
            .flat_map(|j| {
                m.row_idx_of_col(j)
                    .zip(m.val_of_col(j))
                    .map(move |(i, v)| (i, j, *v))
            })
            .collect();
        e.sort_by_key(|x| (x.0, x.1));
        e
    };
    let (b, a) = (entries(sys.b.as_ref()), entries(sys.a.as_ref()));
    let misplaced = |&&(i, j, _): &&(usize, usize, f64)| {
        if i >= first_aux || j >= first_aux {
            // an auxiliary's own rate, and nothing else, in its rows
            i < first_aux || j < first_aux
        } else {
            j >= 2 * n || i >= 2 * n || (i >= n && j >= n)
        }
    };
    if let Some(&(i, j, _)) = b.iter().find(misplaced) {
        return not(format!(
            "B has an entry at ({i}, {j}) outside [[C, M, 0], [E, 0, 0], [0, 0, 0], [0, 0, B_w]]"
        ));
    }
    // kinematic rows: E x' = E v, the same E on both sides
    let kin_b: Vec<(usize, usize, f64)> = b
        .iter()
        .filter(|e| (n..2 * n).contains(&e.0))
        .copied()
        .collect();
    let kin_a: Vec<(usize, usize, f64)> = a
        .iter()
        .filter(|e| (n..2 * n).contains(&e.0))
        .map(|&(i, j, v)| (i, j.wrapping_sub(n), v))
        .collect();
    if kin_b != kin_a {
        return not("rows n..2n are not E x' = E v".into());
    }
    if let Some(t) = sys
        .nonlinearity
        .terms
        .iter()
        .find(|t| (n..2 * n).contains(&(t.eq as usize)))
    {
        return not(format!("the kinematic row {} has a nonlinear term", t.eq));
    }
    let mut differential = vec![false; big_n - first_aux];
    for &(i, _, _) in &b {
        if i >= first_aux {
            differential[i - first_aux] = true;
        }
    }
    Ok(Layout {
        n,
        n_c,
        differential,
    })
}

/// The kind of a row of the iteration matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Row {
    /// `M a - (1 + alpha) f(z_{n+1}) + alpha f(z_n)`.
    Momentum,
    /// `g(z_{n+1}) / (beta h^2)`: a constraint or an algebraic auxiliary.
    Algebraic,
    /// `(B_w (w_{n+1} - w_n) - h/2 (f_w(z_{n+1}) + f_w(z_n))) / (beta h^2)`.
    Differential,
}

/// One contribution to the iteration matrix: `coef(row, col) * J[src]`
/// (and `coef_b(row, col) * B[src]`) into slot `dst`.
#[derive(Debug, Clone, Copy)]
struct Scatter {
    src: usize,
    dst: usize,
    /// 0: a position column, 1: a velocity column, 2: a multiplier column,
    /// 3: an auxiliary column.
    col: u8,
    row: Row,
}

/// Largest iteration matrix factorized densely.
const DENSE_MAX: usize = 2000;

/// The LU of the iteration matrix: sparse, or dense where the pattern is
/// at least a quarter full (a reduced model with modes that mix every
/// coordinate: there the sparse LU's symbolic work per column is wasted).
enum Factor {
    /// On one thread (see [`SparseLu`]): the steps are sequential, and
    /// independent integrations share the cores.
    Sparse(Box<SparseLu<f64>>),
    /// Partial pivoting, once factorized.
    Dense(Option<PartialPivLu<f64>>),
}

/// The sparse iteration matrix on the unknowns `(a, mu)` and its LU.
pub(super) struct Iteration {
    pattern: SymbolicSparseColMat<usize>,
    scatter: Vec<Scatter>,
    lu: Factor,
}

impl Iteration {
    pub(super) fn new(p: &DaeProblem, l: &Layout) -> Result<Self, SimError> {
        let (n, n_c) = (l.n, l.n_c);
        let size = p.n() - n;
        let src = p.pattern().as_ref();
        let mut entries: Vec<(usize, usize, usize, u8, Row)> = Vec::new();
        for c in 0..src.ncols() {
            let (col, kind) = if c < n {
                (c, 0)
            } else if c < 2 * n {
                (c - n, 1)
            } else if c < 2 * n + n_c {
                (c - n, 2)
            } else {
                (c - n, 3)
            };
            for k in src.col_ptr()[c]..src.col_ptr()[c + 1] {
                // momentum rows keep their index, constraint and auxiliary
                // rows follow them, the kinematic rows are the Newmark formulas
                let r = src.row_idx()[k];
                let row = if r < n {
                    Row::Momentum
                } else if r < 2 * n {
                    continue;
                } else if r < 2 * n + n_c || !l.differential[r - 2 * n - n_c] {
                    Row::Algebraic
                } else {
                    Row::Differential
                };
                entries.push((col, if r < n { r } else { r - n }, k, kind, row));
            }
        }
        let mut cells: Vec<(usize, usize)> = entries.iter().map(|e| (e.0, e.1)).collect();
        // the diagonal, so that a row the Jacobian leaves empty is reported
        // as singular rather than as a bad pattern
        cells.extend((0..size).map(|i| (i, i)));
        cells.sort_unstable();
        cells.dedup();
        let pattern = square_pattern(size, &cells);
        let scatter = entries
            .iter()
            .map(|&(c, r, k, col, row)| Scatter {
                src: k,
                dst: cells.binary_search(&(c, r)).expect("cell listed"),
                col,
                row,
            })
            .collect();
        let lu = if size <= DENSE_MAX && 4 * cells.len() >= size * size {
            Factor::Dense(None)
        } else {
            Factor::Sparse(Box::new(
                SparseLu::analyze(pattern.as_ref(), Par::Seq).map_err(|e| {
                    SimError::SingularIteration {
                        t: 0.0,
                        h: 0.0,
                        detail: format!("symbolic LU of the HHT iteration matrix failed: {e:?}"),
                    }
                })?,
            ))
        };
        Ok(Self {
            pattern,
            scatter,
            lu,
        })
    }

    /// Factorizes the matrix for step `h` from the Jacobian values `jac`.
    pub(super) fn factorize(
        &mut self,
        p: &DaeProblem,
        jac: &[f64],
        h: f64,
        o: &HhtOptions,
        t: f64,
    ) -> Result<(), SimError> {
        let (gamma, beta) = o.newmark();
        let w = 1.0 + o.alpha;
        // unknowns (a, mu, w_hat) with dq/da = beta h^2, dv/da = gamma h
        // and w = w_pred + beta h^2 w_hat (auxiliaries move with the
        // positions). Momentum rows: d/d(unknown) of
        // M a - (1 + alpha) (A z + F(z) - C_B v); B's mass and damping blocks
        // share the Jacobian's slots
        let bh2 = beta * h * h;
        let momentum_j = [-w * bh2, -w * gamma * h, -w, -w * bh2];
        let momentum_b = [w * gamma * h, 1.0, 0.0, 0.0];
        let algebraic = [1.0, gamma / (beta * h), 1.0 / bh2, 1.0];
        let differential_j = [-0.5 * h, -0.5 * gamma / beta, -0.5 / (beta * h), -0.5 * h];
        let differential_b = [0.0, 0.0, 0.0, 1.0];
        let b = p.b_values();
        let mut vals = vec![0.0; self.pattern.row_idx().len()];
        for s in &self.scatter {
            let k = s.col as usize;
            vals[s.dst] += match s.row {
                Row::Momentum => momentum_j[k] * jac[s.src] + momentum_b[k] * b[s.src],
                Row::Algebraic => algebraic[k] * jac[s.src],
                Row::Differential => differential_j[k] * jac[s.src] + differential_b[k] * b[s.src],
            };
        }
        let m = SparseColMat::new(self.pattern.clone(), vals);
        match &mut self.lu {
            Factor::Sparse(lu) => lu
                .factor(m.as_ref())
                .map_err(|e| SimError::SingularIteration {
                    t,
                    h,
                    detail: format!("LU of the HHT iteration matrix failed: {e:?}"),
                }),
            Factor::Dense(lu) => {
                let f = m.to_dense().partial_piv_lu();
                let u = f.U();
                if let Some(k) =
                    (0..u.nrows()).find(|&k| !(u[(k, k)] != 0.0 && u[(k, k)].is_finite()))
                {
                    *lu = None;
                    return Err(SimError::SingularIteration {
                        t,
                        h,
                        detail: format!(
                            "LU of the HHT iteration matrix failed: pivot {k} is {}",
                            u[(k, k)]
                        ),
                    });
                }
                *lu = Some(f);
                Ok(())
            }
        }
    }

    pub(super) fn solve(&mut self, rhs: &mut [f64]) {
        let mut x = Mat::<f64>::from_fn(rhs.len(), 1, |i, _| rhs[i]);
        match &mut self.lu {
            Factor::Sparse(lu) => lu.solve_in_place(x.as_mut()),
            Factor::Dense(Some(lu)) => lu.solve_in_place(x.as_mut()),
            Factor::Dense(None) => x.fill(f64::NAN),
        }
        for (i, r) in rhs.iter_mut().enumerate() {
            *r = x[(i, 0)];
        }
    }
}

/// Turns `f = A z + F(z) + eps Fext` (already in `f`) into the force of
/// `M q'' = f` on the momentum rows `0..n`: subtracts the damping `C_B q'`
/// that the first-order form keeps in `B` (`bz`, `acc`: scratch).
pub(super) fn momentum_force(
    p: &DaeProblem,
    z: &[f64],
    f: &mut [f64],
    bz: &mut [f64],
    acc: &mut [f64],
    n: usize,
) {
    acc.iter_mut().for_each(|v| *v = 0.0);
    acc[..n].copy_from_slice(&z[n..2 * n]);
    p.b_mul(acc, bz);
    for i in 0..n {
        f[i] -= bz[i];
    }
}

/// `a_0` from `M a_0 = f(z_0, t_0)` (the momentum rows of `f`, from
/// [`momentum_force`]).
pub(super) fn initial_accelerations(
    p: &DaeProblem,
    l: &Layout,
    f: &[f64],
    t: f64,
) -> Result<Vec<f64>, SimError> {
    let n = l.n;
    let b = p.sys.b.as_ref();
    let mut triplets = Vec::new();
    for j in n..2 * n {
        for (i, v) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
            if i < n {
                triplets.push(faer::sparse::Triplet::new(i, j - n, *v));
            }
        }
    }
    let singular = |detail: String| SimError::SingularIteration { t, h: 0.0, detail };
    let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| singular(format!("mass matrix: {e:?}")))?;
    let lu = m
        .sp_lu()
        .map_err(|e| singular(format!("LU of the mass matrix failed: {e:?}")))?;
    let mut x = Mat::<f64>::from_fn(n, 1, |i, _| f[i]);
    lu.solve_in_place(x.as_mut());
    let a: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
    if a.iter().all(|v| v.is_finite()) {
        Ok(a)
    } else {
        Err(singular("the mass matrix is singular".into()))
    }
}
