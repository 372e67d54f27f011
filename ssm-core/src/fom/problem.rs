//! The right-hand side `f(t, z) = A z + F(z) + eps Fext(z, Omega t)`, its sparse
//! Jacobian on a fixed pattern, and the differentiation index of each state.

use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use ssm_api::{PolyVector, StateKind};

use super::lifted::{pow, LiftedPoly, PreparedLifted};
use crate::model::system::System;

/// One monomial derivative `d F_eq / d z_var`, accumulated into `slot`.
#[derive(Debug, Clone, Copy)]
struct JacEntry {
    term: u32,
    factor: u32,
    slot: u32,
}

/// A polynomial vector prepared for evaluation and differentiation on the
/// Jacobian pattern.
#[derive(Debug, Clone)]
struct PreparedPoly {
    poly: PolyVector,
    jac: Vec<JacEntry>,
}

/// One forcing harmonic `cos(k Omega t) P_c(z) + sin(k Omega t) P_s(z)`.
#[derive(Debug, Clone)]
struct PreparedHarmonic {
    multiple: f64,
    cos: PreparedPoly,
    sin: PreparedPoly,
}

/// The system to integrate, with forcing amplitude and frequency fixed.
///
/// The Jacobian pattern is the union of the patterns of `A`, `B`, `DF` and
/// `DFext`; `DaeProblem::jacobian` and `DaeProblem::b_values` fill values
/// in that pattern's order, so one symbolic LU serves the whole run.
#[derive(Debug, Clone)]
pub struct DaeProblem<'a> {
    /// The system.
    pub sys: &'a System,
    /// Forcing amplitude `eps`.
    pub epsilon: f64,
    /// Forcing frequency `Omega`.
    pub omega: f64,
    pattern: SymbolicSparseColMat<usize>,
    a_vals: Vec<f64>,
    b_vals: Vec<f64>,
    f: PreparedPoly,
    forcing: Vec<PreparedHarmonic>,
    steps: Vec<(f64, f64)>,
    index: Vec<u8>,
    /// The nonlinearity evaluated through a lift instead of `sys`'s, and
    /// the pattern slot of each reduced `(row, column)` (row-major).
    lifted: Option<(PreparedLifted<'a>, Vec<u32>)>,
}

impl<'a> DaeProblem<'a> {
    /// Prepares `sys` forced with `epsilon cos(Omega t)`-type harmonics
    /// (`epsilon = 0` for the autonomous system).
    pub fn new(sys: &'a System, epsilon: f64, omega: f64) -> Self {
        Self::build(sys, epsilon, omega, None)
    }

    /// Prepares `sys` with its nonlinearity `F` replaced by `lifted`, the
    /// same polynomial (or its hyper-reduction) evaluated through the lift
    /// to a full model ([`crate::reduce::hyper`]); `A`, `B` and the forcing
    /// stay `sys`'s.
    ///
    /// # Panics
    /// If `lifted` is not written in `sys`'s states.
    pub fn lifted(sys: &'a System, epsilon: f64, omega: f64, lifted: &'a LiftedPoly) -> Self {
        assert_eq!(
            lifted.n_reduced(),
            sys.n_states(),
            "a lifted nonlinearity in the system's states"
        );
        Self::build(sys, epsilon, omega, Some(lifted))
    }

    fn build(sys: &'a System, epsilon: f64, omega: f64, lifted: Option<&'a LiftedPoly>) -> Self {
        let n = sys.n_states();
        let mut entries: Vec<(usize, usize)> = Vec::new();
        for m in [sys.a.as_ref(), sys.b.as_ref()] {
            for j in 0..n {
                entries.extend(m.row_idx_of_col(j).map(|i| (j, i)));
            }
        }
        let empty = PolyVector::zeros(n, n);
        let own = if lifted.is_some() {
            &empty
        } else {
            &sys.nonlinearity
        };
        let lifted = lifted.map(PreparedLifted::new);
        if let Some((_, cells)) = &lifted {
            entries.extend(cells.iter().copied());
        }
        let mut polys: Vec<&PolyVector> = vec![own];
        if epsilon != 0.0 {
            for h in &sys.forcing {
                polys.push(&h.cos);
                polys.push(&h.sin);
            }
        }
        for p in &polys {
            for t in p.terms.iter() {
                entries.extend(t.factors.iter().map(|v| (v.var as usize, t.eq as usize)));
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let pattern = square_pattern(n, &entries);
        let slot = |row: usize, col: usize| -> u32 {
            let p = pattern.as_ref();
            let start = p.col_ptr()[col];
            let rows = &p.row_idx()[start..p.col_ptr()[col + 1]];
            (start
                + rows
                    .binary_search(&row)
                    .expect("entry is in the union pattern")) as u32
        };
        let scatter = |m: SparseColMatRef<'_, usize, f64>| {
            let mut vals = vec![0.0; entries.len()];
            for j in 0..n {
                for (i, v) in m.row_idx_of_col(j).zip(m.val_of_col(j)) {
                    vals[slot(i, j) as usize] += v;
                }
            }
            vals
        };
        let a_vals = scatter(sys.a.as_ref());
        let b_vals = scatter(sys.b.as_ref());
        let prepare = |p: &PolyVector| PreparedPoly {
            poly: p.clone(),
            jac: p
                .terms
                .iter()
                .enumerate()
                .flat_map(|(k, t)| {
                    t.factors
                        .iter()
                        .enumerate()
                        .map(move |(q, v)| (k, q, t.eq as usize, v.var as usize))
                })
                .map(|(k, q, eq, var)| JacEntry {
                    term: k as u32,
                    factor: q as u32,
                    slot: slot(eq, var),
                })
                .collect(),
        };
        let f = prepare(own);
        let lifted = lifted.map(|(prep, _)| {
            let mut slots = vec![u32::MAX; n * n];
            for j in 0..n {
                let range = pattern.col_range(j);
                for (k, &i) in pattern.row_idx()[range.clone()].iter().enumerate() {
                    slots[i * n + j] = (range.start + k) as u32;
                }
            }
            (prep, slots)
        });
        let forcing = if epsilon != 0.0 {
            sys.forcing
                .iter()
                .map(|h| PreparedHarmonic {
                    multiple: h.multiple,
                    cos: prepare(&h.cos),
                    sin: prepare(&h.sin),
                })
                .collect()
        } else {
            Vec::new()
        };
        Self {
            sys,
            epsilon,
            omega,
            pattern,
            a_vals,
            b_vals,
            f,
            forcing,
            steps: Vec::new(),
            index: differentiation_index(sys),
            lifted,
        }
    }

    /// The same problem with its load switched in steps `(t_k, a_k)` (times
    /// rising): from `t_k` on the amplitude is `a_k eps`, before the first
    /// step zero. No steps: `eps` throughout.
    #[must_use]
    pub fn with_steps(mut self, steps: &[(f64, f64)]) -> Self {
        self.steps = steps.to_vec();
        self
    }

    /// The load factor at `t`: 1 without steps, else the factor of the last
    /// step at or before `t` (0 before the first).
    fn load_factor(&self, t: f64) -> f64 {
        if self.steps.is_empty() {
            return 1.0;
        }
        match self.steps.partition_point(|s| s.0 <= t) {
            0 => 0.0,
            k => self.steps[k - 1].1,
        }
    }

    /// Number of states `N`.
    pub fn n(&self) -> usize {
        self.index.len()
    }

    /// The Jacobian pattern (union of `A`, `B`, `DF`, `DFext`).
    pub fn pattern(&self) -> &SymbolicSparseColMat<usize> {
        &self.pattern
    }

    /// `B` in the pattern's order.
    pub(crate) fn b_values(&self) -> &[f64] {
        &self.b_vals
    }

    /// Differentiation index of each state's component (1, 2 or 3): used to
    /// scale the error estimate. Multipliers of configuration constraints are
    /// index 3 and the velocities index 2; all other states index 1.
    pub fn index(&self) -> &[u8] {
        &self.index
    }

    /// Name of state `i`.
    pub(crate) fn state_name(&self, i: usize) -> &str {
        self.sys.states[i].name.as_str()
    }

    /// `out = A z + F(z) + eps Fext(z, Omega t)`.
    pub fn rhs(&self, t: f64, z: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let a = self.sys.a.as_ref();
        for (j, zj) in z.iter().enumerate() {
            if *zj != 0.0 {
                for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                    out[i] += v * zj;
                }
            }
        }
        eval_into(&self.f.poly, z, 1.0, out);
        if let Some((l, _)) = &self.lifted {
            l.eval_into(z, 1.0, out);
        }
        let eps = self.epsilon * self.load_factor(t);
        for h in &self.forcing {
            let (s, c) = (h.multiple * self.omega * t).sin_cos();
            eval_into(&h.cos.poly, z, eps * c, out);
            eval_into(&h.sin.poly, z, eps * s, out);
        }
    }

    /// The forcing `Fext(z, Omega t)` alone (per unit amplitude, times the
    /// load factor of any steps): the derivative of [`DaeProblem::rhs`] in
    /// `eps`. Empty (zero) for a problem prepared with `epsilon = 0`.
    pub(crate) fn forcing_rhs(&self, t: f64, z: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let a = self.load_factor(t);
        for h in &self.forcing {
            let (s, c) = (h.multiple * self.omega * t).sin_cos();
            eval_into(&h.cos.poly, z, a * c, out);
            eval_into(&h.sin.poly, z, a * s, out);
        }
    }

    /// The autonomous part `A z + F(z)` (no forcing).
    pub(crate) fn autonomous_rhs(&self, z: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let a = self.sys.a.as_ref();
        for (j, zj) in z.iter().enumerate() {
            for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                out[i] += v * zj;
            }
        }
        eval_into(&self.f.poly, z, 1.0, out);
        if let Some((l, _)) = &self.lifted {
            l.eval_into(z, 1.0, out);
        }
    }

    /// `J = A + DF(z) + eps DFext(z, Omega t)` in the pattern's order.
    pub(crate) fn jacobian(&self, t: f64, z: &[f64], vals: &mut [f64]) {
        vals.copy_from_slice(&self.a_vals);
        jac_into(&self.f, z, 1.0, vals);
        if let Some((l, slots)) = &self.lifted {
            let n = self.n();
            l.jac_into(z, 1.0, vals, |p, q| slots[p * n + q] as usize);
        }
        let eps = self.epsilon * self.load_factor(t);
        for h in &self.forcing {
            let (s, c) = (h.multiple * self.omega * t).sin_cos();
            jac_into(&h.cos, z, eps * c, vals);
            jac_into(&h.sin, z, eps * s, vals);
        }
    }

    /// `out = B v`.
    pub fn b_mul(&self, v: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        let b = self.sys.b.as_ref();
        for (j, vj) in v.iter().enumerate() {
            for (i, bv) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
                out[i] += bv * vj;
            }
        }
    }
}

/// The `n x n` sparse pattern of the cells `(col, row)`, sorted and without
/// repeats.
pub(crate) fn square_pattern(n: usize, cells: &[(usize, usize)]) -> SymbolicSparseColMat<usize> {
    let mut col_ptr = vec![0usize; n + 1];
    for &(c, _) in cells {
        col_ptr[c + 1] += 1;
    }
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    let row_idx: Vec<usize> = cells.iter().map(|&(_, r)| r).collect();
    SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
}

fn eval_into(p: &PolyVector, z: &[f64], scale: f64, out: &mut [f64]) {
    if scale == 0.0 {
        return;
    }
    for t in p.terms.iter() {
        let v = t.factors.iter().fold(t.coeff * scale, |acc, f| {
            acc * pow(z[f.var as usize], f.power)
        });
        out[t.eq as usize] += v;
    }
}

fn jac_into(p: &PreparedPoly, z: &[f64], scale: f64, vals: &mut [f64]) {
    if scale == 0.0 {
        return;
    }
    let terms = &p.poly.terms;
    for e in &p.jac {
        let t = &terms[e.term as usize];
        let mut d = t.coeff * scale;
        for (q, f) in t.factors.iter().enumerate() {
            let zv = z[f.var as usize];
            if q == e.factor as usize {
                d *= f.power as f64 * pow(zv, f.power - 1);
            } else {
                d *= pow(zv, f.power);
            }
        }
        vals[e.slot as usize] += d;
    }
}

/// Index of each state: with configuration constraints, velocities are index 2
/// and multipliers index 3 (Hairer & Wanner II, Sect. VII.1); everything else,
/// including a recast's algebraic auxiliaries, is index 1.
fn differentiation_index(sys: &System) -> Vec<u8> {
    let constrained = sys.states.iter().any(|s| s.kind == StateKind::Multiplier);
    sys.states
        .iter()
        .map(|s| match s.kind {
            StateKind::Multiplier => 3,
            StateKind::Velocity if constrained => 2,
            _ => 1,
        })
        .collect()
}
