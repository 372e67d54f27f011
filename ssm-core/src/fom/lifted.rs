//! A polynomial in reduced states evaluated through a lift: `F_r(y) = P
//! F_S(V_S y)`, the rows `S` of a full polynomial at the lifted states,
//! projected by `P` (the data of [`crate::reduce::hyper`], evaluated and
//! differentiated by [`super::DaeProblem`]).

use std::collections::HashMap;

use ssm_api::PolyVector;

/// A polynomial in the reduced states evaluated through the lift:
/// `F_r(y) = P F_S(V_S y)`.
#[derive(Debug, Clone)]
pub struct LiftedPoly {
    n_reduced: usize,
    /// The row of `V` of each local variable: `(reduced state, weight)`.
    lift: Vec<Vec<(u32, f64)>>,
    /// The full state of each local variable.
    vars: Vec<u32>,
    /// The terms, in local rows and local variables.
    poly: PolyVector,
    /// The projection of each local row: `(reduced equation, weight)`.
    proj: Vec<Vec<(u32, f64)>>,
    /// The full row of each local row.
    rows: Vec<u32>,
}

impl LiftedPoly {
    /// Number of reduced states (and equations).
    pub fn n_reduced(&self) -> usize {
        self.n_reduced
    }

    /// Number of full rows evaluated.
    pub fn n_rows(&self) -> usize {
        self.rows.len()
    }

    /// Number of full states lifted.
    pub fn n_lifted(&self) -> usize {
        self.vars.len()
    }

    /// Number of full terms evaluated.
    pub fn n_terms(&self) -> usize {
        self.poly.terms.len()
    }

    /// `z_S = V_S y`: the local variables at the reduced state `y`.
    pub(crate) fn lift_into(&self, y: &[f64], z: &mut [f64]) {
        for (zk, row) in z.iter_mut().zip(&self.lift) {
            *zk = row.iter().map(|&(j, w)| w * y[j as usize]).sum();
        }
    }

    /// `out += scale P f` of the local row values `f`.
    pub(crate) fn project_into(&self, f: &[f64], scale: f64, out: &mut [f64]) {
        for (fk, row) in f.iter().zip(&self.proj) {
            let s = scale * fk;
            if s != 0.0 {
                for &(p, w) in row {
                    out[p as usize] += w * s;
                }
            }
        }
    }
}

/// One term of a full polynomial placed into a lifted one: the term's index
/// and its local row.
pub(crate) struct Placed {
    /// Index into the full polynomial's terms.
    pub term: usize,
    /// Local row.
    pub row: usize,
}

impl LiftedPoly {
    /// The lifted polynomial of the `placed` terms of `full`, with the local
    /// rows `rows` (full row, projection) and `V` by its rows `v_rows`.
    pub(crate) fn assemble(
        full: &PolyVector,
        placed: &[Placed],
        rows: Vec<(u32, Vec<(u32, f64)>)>,
        v_rows: &[Vec<(u32, f64)>],
        n_reduced: usize,
    ) -> LiftedPoly {
        let mut local_var: HashMap<u32, u32> = HashMap::new();
        let mut vars = Vec::new();
        let mut poly = PolyVector::zeros(rows.len(), 0);
        for p in placed {
            let t = &full.terms[p.term];
            let factors: Vec<(usize, u32)> = t
                .factors
                .iter()
                .map(|f| {
                    let k = *local_var.entry(f.var).or_insert_with(|| {
                        vars.push(f.var);
                        (vars.len() - 1) as u32
                    });
                    (k as usize, f.power)
                })
                .collect();
            poly.push(p.row, t.coeff, &factors);
        }
        poly.n_vars = vars.len() as u32;
        let lift = vars.iter().map(|&v| v_rows[v as usize].clone()).collect();
        let (rows, proj) = rows.into_iter().unzip();
        LiftedPoly {
            n_reduced,
            lift,
            vars,
            poly,
            proj,
            rows,
        }
    }
}

/// `x^p` with the common small powers as plain products (`powi` is a call).
#[inline]
pub(super) fn pow(x: f64, p: u32) -> f64 {
    match p {
        0 => 1.0,
        1 => x,
        2 => x * x,
        3 => x * x * x,
        _ => x.powi(p as i32),
    }
}

/// A [`LiftedPoly`] prepared for evaluation and differentiation on a
/// reduced Jacobian pattern.
#[derive(Debug, Clone)]
pub(crate) struct PreparedLifted<'a> {
    poly: &'a LiftedPoly,
    /// `(term, factor, slot)` of each derivative: it adds into `slot` of
    /// the sparse `dF_S`.
    jac: Vec<(u32, u32, u32)>,
    /// `(local row, local variable)` of each slot of `dF_S`, by rows.
    slots: Vec<(u32, u32)>,
    /// The reduced states each local row depends on.
    row_cols: Vec<Vec<u32>>,
}

impl<'a> PreparedLifted<'a> {
    /// Prepares `poly`; its Jacobian cells `(reduced column, reduced row)`.
    pub(crate) fn new(poly: &'a LiftedPoly) -> (Self, Vec<(usize, usize)>) {
        let nr = poly.n_reduced;
        let mut reach: Vec<Vec<bool>> = vec![vec![false; nr]; poly.rows.len()];
        let mut cell: HashMap<(u32, u32), u32> = HashMap::new();
        let mut pairs = Vec::new();
        for (k, t) in poly.poly.terms.iter().enumerate() {
            for (q, f) in t.factors.iter().enumerate() {
                pairs.push((k as u32, q as u32, t.eq, f.var));
                cell.insert((t.eq, f.var), 0);
                for &(j, _) in &poly.lift[f.var as usize] {
                    reach[t.eq as usize][j as usize] = true;
                }
            }
        }
        let mut slots: Vec<(u32, u32)> = cell.keys().copied().collect();
        slots.sort_unstable();
        for (k, key) in slots.iter().enumerate() {
            cell.insert(*key, k as u32);
        }
        let jac = pairs
            .iter()
            .map(|&(k, q, row, var)| (k, q, cell[&(row, var)]))
            .collect();
        let row_cols: Vec<Vec<u32>> = reach
            .iter()
            .map(|r| (0..nr as u32).filter(|&j| r[j as usize]).collect())
            .collect();
        let mut cells = Vec::new();
        let mut seen = vec![false; nr * nr];
        for (proj, cols) in poly.proj.iter().zip(&row_cols) {
            for &(p, _) in proj {
                for &q in cols {
                    let c = q as usize * nr + p as usize;
                    if !seen[c] {
                        seen[c] = true;
                        cells.push((q as usize, p as usize));
                    }
                }
            }
        }
        (
            Self {
                poly,
                jac,
                slots,
                row_cols,
            },
            cells,
        )
    }

    /// `out += scale F_r(y)`.
    pub(crate) fn eval_into(&self, y: &[f64], scale: f64, out: &mut [f64]) {
        if scale == 0.0 {
            return;
        }
        let lp = self.poly;
        let mut z = vec![0.0; lp.vars.len()];
        lp.lift_into(y, &mut z);
        let mut f = vec![0.0; lp.rows.len()];
        for t in lp.poly.terms.iter() {
            f[t.eq as usize] += t
                .factors
                .iter()
                .fold(t.coeff, |acc, v| acc * pow(z[v.var as usize], v.power));
        }
        lp.project_into(&f, scale, out);
    }

    /// `vals[slot(p, q)] += scale dF_r,p / dy_q`: the sparse `dF_S` (each
    /// distinct row and variable once), `W = dF_S V_S` row by row, then
    /// `P W`; `slot` maps a reduced `(row, column)` to the pattern.
    pub(crate) fn jac_into(
        &self,
        y: &[f64],
        scale: f64,
        vals: &mut [f64],
        slot: impl Fn(usize, usize) -> usize,
    ) {
        if scale == 0.0 {
            return;
        }
        let lp = self.poly;
        let nr = lp.n_reduced;
        let mut z = vec![0.0; lp.vars.len()];
        lp.lift_into(y, &mut z);
        let mut w = vec![0.0; lp.rows.len() * nr];
        let mut df = vec![0.0; self.slots.len()];
        let terms = &lp.poly.terms;
        for &(term, factor, cell) in &self.jac {
            let t = &terms[term as usize];
            let mut d = t.coeff;
            for (q, f) in t.factors.iter().enumerate() {
                let zv = z[f.var as usize];
                if q == factor as usize {
                    d *= f.power as f64 * pow(zv, f.power - 1);
                } else {
                    d *= pow(zv, f.power);
                }
            }
            df[cell as usize] += d;
        }
        for (&(row, var), &d) in self.slots.iter().zip(&df) {
            if d != 0.0 {
                let wr = &mut w[row as usize * nr..(row as usize + 1) * nr];
                for &(j, v) in &lp.lift[var as usize] {
                    wr[j as usize] += d * v;
                }
            }
        }
        for (k, (proj, cols)) in lp.proj.iter().zip(&self.row_cols).enumerate() {
            let wr = &w[k * nr..(k + 1) * nr];
            for &(p, wp) in proj {
                let s = scale * wp;
                for &q in cols {
                    vals[slot(p as usize, q as usize)] += s * wr[q as usize];
                }
            }
        }
    }
}
