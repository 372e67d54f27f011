//! Stable data types of a model: sparse matrices, sparse polynomials, forcing,
//! states, outputs and the first-order [`Model`] itself.

use abi_stable::std_types::{ROption, RString, RVec};
use abi_stable::StableAbi;

use crate::expr::ExprVector;

/// One stored entry `(row, col, value)` of a [`SparseMatrix`].
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct Triplet {
    /// 0-based row index.
    pub row: u32,
    /// 0-based column index.
    pub col: u32,
    /// Entry value; duplicates of the same `(row, col)` are summed.
    pub value: f64,
}

/// A sparse real matrix in coordinate (triplet) form.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    /// Number of rows.
    pub nrows: u32,
    /// Number of columns.
    pub ncols: u32,
    /// Stored entries; duplicates are summed, explicit zeros are allowed.
    pub entries: RVec<Triplet>,
}

impl SparseMatrix {
    /// An empty (all-zero) `nrows x ncols` matrix.
    pub fn zeros(nrows: usize, ncols: usize) -> Self {
        Self {
            nrows: nrows as u32,
            ncols: ncols as u32,
            entries: RVec::new(),
        }
    }

    /// A diagonal matrix with the given diagonal.
    pub fn diagonal(diag: &[f64]) -> Self {
        let mut m = Self::zeros(diag.len(), diag.len());
        for (i, &d) in diag.iter().enumerate() {
            m.push(i, i, d);
        }
        m
    }

    /// Rayleigh damping `C = alpha M + beta K`.
    pub fn rayleigh(mass: &Self, stiffness: &Self, alpha: f64, beta: f64) -> Self {
        let mut c = Self::zeros(mass.nrows as usize, mass.ncols as usize);
        for (r, col, v) in mass.iter() {
            c.push(r, col, alpha * v);
        }
        for (r, col, v) in stiffness.iter() {
            c.push(r, col, beta * v);
        }
        c
    }

    /// Adds `value` at `(row, col)` (summed with any earlier entry there).
    pub fn push(&mut self, row: usize, col: usize, value: f64) {
        if value != 0.0 {
            self.entries.push(Triplet {
                row: row as u32,
                col: col as u32,
                value,
            });
        }
    }

    /// Stores `value` at `(row, col)` even when it is zero: an explicit zero
    /// is part of the sparsity pattern the engine factorizes.
    pub fn push_entry(&mut self, row: usize, col: usize, value: f64) {
        self.entries.push(Triplet {
            row: row as u32,
            col: col as u32,
            value,
        });
    }

    /// Iterates over the stored entries as `(row, col, value)`.
    pub fn iter(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        self.entries
            .iter()
            .map(|t| (t.row as usize, t.col as usize, t.value))
    }

    /// The first entry pair, in column order, whose entries `m(i, j)` and
    /// `m(j, i)` (duplicates summed) differ by more than `rel_tol` times the
    /// largest entry, as `(i, j, m(i, j), m(j, i))` (0-based); `None` for a
    /// symmetric matrix. See [`SYMMETRY_TOLERANCE`].
    pub fn asymmetry(&self, rel_tol: f64) -> Option<(usize, usize, f64, f64)> {
        let mut at: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
        for (i, j, v) in self.iter() {
            *at.entry((j, i)).or_insert(0.0) += v;
        }
        let largest = at.values().fold(0.0_f64, |a, v| a.max(v.abs()));
        at.iter().find_map(|(&(j, i), &v)| {
            let w = at.get(&(i, j)).copied().unwrap_or(0.0);
            ((v - w).abs() > rel_tol * largest).then_some((i, j, v, w))
        })
    }
}

/// Largest difference between `M(i, j)` and `M(j, i)` accepted in a mass
/// matrix, relative to its largest entry: rounding of a matrix assembled in
/// double precision (some 1e-16 per operation, times the terms summed into
/// an entry) stays far below it, a modelling error far above. The kinetic
/// energy `x'^T M x' / 2` holds only the symmetric part of `M`.
pub const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// A variable raised to a power inside a monomial.
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct VarPower {
    /// 0-based variable index.
    pub var: u32,
    /// Exponent (at least 1).
    pub power: u32,
}

/// One term `coeff * prod_k z[var_k]^power_k` of equation `eq`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct PolyTerm {
    /// 0-based equation (component) index.
    pub eq: u32,
    /// Coefficient.
    pub coeff: f64,
    /// Sparse exponents: only variables with a non-zero power are listed.
    pub factors: RVec<VarPower>,
}

impl PolyTerm {
    /// Total degree of the monomial.
    pub fn degree(&self) -> u32 {
        self.factors.iter().map(|f| f.power).sum()
    }
}

/// A vector of sparse multivariate polynomials: component `eq` is the sum of the
/// terms with that `eq`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct PolyVector {
    /// Number of components (equations).
    pub n_eq: u32,
    /// Number of variables the monomials are written in.
    pub n_vars: u32,
    /// Terms, in any order; repeated monomials are summed.
    pub terms: RVec<PolyTerm>,
}

impl PolyVector {
    /// The zero polynomial vector with `n_eq` components in `n_vars` variables.
    pub fn zeros(n_eq: usize, n_vars: usize) -> Self {
        Self {
            n_eq: n_eq as u32,
            n_vars: n_vars as u32,
            terms: RVec::new(),
        }
    }

    /// Adds `coeff * prod z[var]^power` to component `eq`; `factors` lists
    /// `(var, power)` pairs (a variable may appear more than once; powers add).
    pub fn push(&mut self, eq: usize, coeff: f64, factors: &[(usize, u32)]) {
        if coeff == 0.0 {
            return;
        }
        let mut merged: Vec<VarPower> = Vec::with_capacity(factors.len());
        for &(var, power) in factors {
            if power == 0 {
                continue;
            }
            match merged.iter_mut().find(|f| f.var as usize == var) {
                Some(f) => f.power += power,
                None => merged.push(VarPower {
                    var: var as u32,
                    power,
                }),
            }
        }
        merged.sort_by_key(|f| f.var);
        self.terms.push(PolyTerm {
            eq: eq as u32,
            coeff,
            factors: merged.into_iter().collect(),
        });
    }

    /// The same polynomials with the terms sorted by equation and monomial,
    /// repeated monomials summed in the order given and zero sums dropped:
    /// every sum over the terms then runs in one order, so equal models give
    /// equal digits however their terms were ordered.
    pub fn canonical(mut self) -> Self {
        let mut terms: Vec<PolyTerm> = std::mem::take(&mut self.terms).into_iter().collect();
        terms.sort_by(|x, y| (x.eq, x.factors.as_slice()).cmp(&(y.eq, y.factors.as_slice())));
        let mut merged: Vec<PolyTerm> = Vec::with_capacity(terms.len());
        for t in terms {
            match merged.last_mut() {
                Some(last) if last.eq == t.eq && last.factors == t.factors => {
                    last.coeff += t.coeff;
                }
                _ => merged.push(t),
            }
        }
        merged.retain(|t| t.coeff != 0.0);
        self.terms = merged.into_iter().collect();
        self
    }

    /// Highest total degree of any term (0 when empty).
    pub fn degree(&self) -> u32 {
        self.terms.iter().map(PolyTerm::degree).max().unwrap_or(0)
    }
}

/// One harmonic of the external forcing: `cos * cos(multiple * Omega t) + sin * sin(multiple * Omega t)`,
/// each a polynomial vector in the states (usually constant).
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Harmonic {
    /// Frequency of this harmonic as a multiple of the forcing frequency `Omega`.
    pub multiple: f64,
    /// Coefficient of `cos(multiple * Omega t)`.
    pub cos: PolyVector,
    /// Coefficient of `sin(multiple * Omega t)`.
    pub sin: PolyVector,
}

growable_tag! {
    /// What a state variable is, for reducers and reports that need it.
    StateKind {
        /// A generalized displacement `x_i`.
        Displacement = 0,
        /// A generalized velocity `x_i'`.
        Velocity = 1,
        /// A Lagrange multiplier of a configuration constraint.
        Multiplier = 2,
        /// An auxiliary variable introduced by a recast of non-polynomial terms.
        Auxiliary = 3,
        /// Anything else (e.g. a state of a map).
        Other = 4,
    }
}

growable_tag! {
    /// Physical nature of a displacement (or of its velocity).
    MotionKind {
        /// A translation.
        Translational = 0,
        /// A rotation (angle).
        Rotational = 1,
        /// A flexible (elastic) coordinate.
        Flexible = 2,
        /// Not specified.
        Unspecified = 3,
    }
}

/// Name and tags of one state variable.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct StateInfo {
    /// Name, unique within the model (e.g. `x1`, `x1_dot`, `mu1`).
    pub name: RString,
    /// What the state is.
    pub kind: StateKind,
    /// Physical nature (for displacements and velocities).
    pub motion: MotionKind,
}

/// One weight `value * z[state]` of an [`Output`].
#[repr(C)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub struct Weight {
    /// 0-based state index.
    pub state: u32,
    /// Weight.
    pub value: f64,
}

/// A named output: the linear functional `sum_k weights[k].value * z[weights[k].state]`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Output {
    /// Name used in scenes (`[outputs] coordinates = [...]`).
    pub name: RString,
    /// Sparse weights.
    pub weights: RVec<Weight>,
}

/// Continuous (flow) or discrete (map) time.
#[repr(u8)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq)]
pub enum TimeKind {
    /// `B z' = A z + F(z) + eps Fext(z, Omega t)`.
    Flow,
    /// `z_{k+1} = A z_k + F(z_k)` with sampling period `period`.
    Map {
        /// Sampling period `T` of the map.
        period: f64,
    },
}

/// Structure kept from a mechanical model: which states are the
/// displacements `x`, velocities `x'` and multipliers `mu`, and which rows of
/// the model are the configuration constraints `0 = g(x)`.
///
/// The layout is explicit, so a model assembled by hand in any order is read
/// correctly; the engine checks it against the state tags ([`StateKind`]).
/// The mechanical builder (`ssm_plugin_kit::MechanicalSystem`) writes the
/// canonical layout `z = (x, x', mu)` with the constraints in rows
/// `2n .. 2n + n_c`.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct MechanicalInfo {
    /// Number of generalized displacements `n`.
    pub n_dof: u32,
    /// Number of configuration constraints `n_c`.
    pub n_constraints: u32,
    /// Mass matrix `M` (`n x n`), for mass normalization of modes.
    pub mass: SparseMatrix,
    /// State index of each displacement `x_i` (`n` entries).
    pub displacements: RVec<u32>,
    /// State index of each velocity `x_i'` (`n` entries, in the order of `displacements`).
    pub velocities: RVec<u32>,
    /// State index of each multiplier `mu_j` (`n_c` entries).
    pub multipliers: RVec<u32>,
    /// Row of the model holding constraint `g_j(x) = 0` (`n_c` entries, in the
    /// order of `multipliers`).
    pub constraint_rows: RVec<u32>,
}

impl MechanicalInfo {
    /// The canonical layout `z = (x, x', mu)`, constraints in rows `2n .. 2n + n_c`.
    pub fn canonical(n_dof: usize, n_constraints: usize, mass: SparseMatrix) -> Self {
        let range = |lo: usize, len: usize| (lo..lo + len).map(|k| k as u32).collect();
        Self {
            n_dof: n_dof as u32,
            n_constraints: n_constraints as u32,
            mass,
            displacements: range(0, n_dof),
            velocities: range(n_dof, n_dof),
            multipliers: range(2 * n_dof, n_constraints),
            constraint_rows: range(2 * n_dof, n_constraints),
        }
    }
}

/// A model in first-order form, as it crosses the plugin boundary.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct Model {
    /// Model name (as listed in [`crate::ModelInfo`]).
    pub name: RString,
    /// Linear part `A` (`N x N`).
    pub a: SparseMatrix,
    /// Left-hand-side matrix `B` (`N x N`), possibly singular; identity for maps.
    pub b: SparseMatrix,
    /// Nonlinearity `F(z)`: `N` components in `N` variables, no constant or linear terms.
    pub nonlinearity: PolyVector,
    /// External forcing `Fext(z, Omega t)` as harmonics (empty when unforced).
    pub forcing: RVec<Harmonic>,
    /// Names and tags of the `N` states.
    pub states: RVec<StateInfo>,
    /// Named outputs (linear functionals of `z`).
    pub outputs: RVec<Output>,
    /// Flow or map.
    pub time: TimeKind,
    /// Mechanical structure, when the model came from the mechanical builder
    /// (`ssm_plugin_kit::MechanicalSystem`) or declares its layout.
    pub mechanical: ROption<MechanicalInfo>,
    /// Non-polynomial right-hand-side terms `E(z)` (`N` components in the `N`
    /// states), added to `A z + F(z)`; they may have constant and linear parts.
    /// The engine recasts them into polynomials with auxiliary states (Sect. 4.2
    /// of Li, Jain & Haller 2023). Empty for purely polynomial models.
    pub expressions: ExprVector,
    /// Equilibrium `z_eq` to expand about (eqs. 34, 107): the engine substitutes
    /// `z = z_eq + z_hat`, so `A z_eq + F(z_eq) + E(z_eq)` must vanish. Empty:
    /// the origin.
    pub equilibrium: RVec<f64>,
}

impl Model {
    /// Number of states `N`.
    pub fn n_states(&self) -> usize {
        self.states.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(equation, coefficient, factors)` of one pushed term.
    type Term = (usize, f64, &'static [(usize, u32)]);

    /// The same polynomial pushed in two orders is equal once canonical;
    /// repeated monomials are summed and zero sums dropped.
    #[test]
    fn canonical_terms_do_not_depend_on_their_order() {
        let terms: [Term; 4] = [
            (1, 2.0, &[(0, 1), (1, 2)]),
            (0, 1.5, &[(1, 3)]),
            (1, -0.5, &[(1, 2), (0, 1)]),
            (0, 4.0, &[(0, 2)]),
        ];
        let mut forward = PolyVector::zeros(2, 2);
        let mut backward = PolyVector::zeros(2, 2);
        for &(eq, c, f) in &terms {
            forward.push(eq, c, f);
        }
        for &(eq, c, f) in terms.iter().rev() {
            backward.push(eq, c, f);
        }
        backward.push(0, 1.0, &[(1, 1), (0, 1)]);
        backward.push(0, -1.0, &[(0, 1), (1, 1)]);
        let (f, b) = (forward.canonical(), backward.canonical());
        assert_eq!(f, b);
        assert_eq!(f.terms.len(), 3);
        assert_eq!(f.terms[2].coeff, 1.5);
    }
}
