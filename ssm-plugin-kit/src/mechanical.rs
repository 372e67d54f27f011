//! Builder from mechanical form `(M, C, K, f(x, x'), g(x), fext)` to the
//! first-order DAE of eqs. (4)-(5) of Li, Jain & Haller (2023).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023) 8881-8911, eqs. (1)-(5).

use abi_stable::std_types::{RString, RVec};

use ssm_api::{
    ErrorKind, Harmonic, MechanicalInfo, Model, MotionKind, Output, PluginError, PolyVector,
    SparseMatrix, StateInfo, StateKind, TimeKind, Weight, SYMMETRY_TOLERANCE,
};

use crate::{expr_vector, Expr};

/// Configuration constraints `g(x) = 0` (eq. 2) in the `n` displacements: the
/// polynomial ones `G0 x + g_nl(x)` first, then those written as expressions
/// (e.g. `x2 - x1 - 0.5 l sin(phi2)`, eq. 33), which the engine recasts.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraints {
    /// Polynomial constraints, linear and nonlinear terms together (`n_p`
    /// equations in `n` variables, no constant term).
    pub g: PolyVector,
    /// Constraints `n_p + 1, ...` as expressions in the `n` displacements; they
    /// may have a constant part when the model gives an [`Equilibrium`] at which
    /// they vanish.
    pub expressions: Vec<Expr>,
}

impl Constraints {
    /// Polynomial constraints only.
    pub fn polynomial(g: PolyVector) -> Self {
        Self {
            g,
            expressions: Vec::new(),
        }
    }

    /// Constraints written as expressions in the `n` displacements.
    pub fn expressions(n_dof: usize, expressions: Vec<Expr>) -> Self {
        Self {
            g: PolyVector::zeros(0, n_dof),
            expressions,
        }
    }

    /// Number of constraints `n_c`.
    pub fn len(&self) -> usize {
        self.g.n_eq as usize + self.expressions.len()
    }

    /// True when there is no constraint.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A static equilibrium `(x_eq, mu_eq)` (velocities zero) that the engine shifts
/// to the origin (eqs. 34 and 107).
#[derive(Clone, Debug, PartialEq)]
pub struct Equilibrium {
    /// Displacements at the equilibrium (`n` values).
    pub x: Vec<f64>,
    /// Lagrange multipliers at the equilibrium (`n_c` values).
    pub mu: Vec<f64>,
}

/// What is wrong with a [`MechanicalSystem`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// A matrix has the wrong shape.
    #[error("{what} is {rows}x{cols}, expected {expected}x{expected}")]
    MatrixShape {
        /// Which matrix.
        what: &'static str,
        /// Rows found.
        rows: usize,
        /// Columns found.
        cols: usize,
        /// Expected size.
        expected: usize,
    },
    /// A matrix entry lies outside the matrix.
    #[error("{what} has an entry at ({row}, {col}) outside its {size}x{size} shape")]
    EntryOutOfRange {
        /// Which matrix.
        what: &'static str,
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
        /// Matrix size.
        size: usize,
    },
    /// A polynomial has the wrong number of equations or variables, or a term
    /// refers to a variable or equation outside it.
    #[error("{what}: {detail}")]
    PolyShape {
        /// Which polynomial.
        what: &'static str,
        /// What is wrong.
        detail: String,
    },
    /// A nonlinearity contains a constant or linear term (they belong in `K`, `C`, `G0`).
    #[error("{what}, equation {eq}: term of degree {degree}; only degree >= 2 belongs here (put linear terms in the matrices)")]
    LowDegreeTerm {
        /// Which polynomial.
        what: &'static str,
        /// 0-based equation.
        eq: usize,
        /// Degree found.
        degree: u32,
    },
    /// A constraint has a constant term, so the origin is not on the constraint surface.
    #[error("constraint {index} has a constant term {value}; g(0) must be 0 (shift the equilibrium to the origin)")]
    ConstraintConstant {
        /// 1-based constraint index.
        index: usize,
        /// The constant found.
        value: f64,
    },
    /// A constraint has no linear part, so `G0 = dg/dx(0)` is rank deficient.
    #[error("constraint {index} has no linear term, so G0 = dg/dx(0) is rank deficient (redundant or degenerate constraint)")]
    ConstraintNoLinearPart {
        /// 1-based constraint index.
        index: usize,
    },
    /// The mass matrix is not symmetric (beyond [`SYMMETRY_TOLERANCE`]).
    #[error("M({row}, {col}) = {value} but M({col}, {row}) = {mirror}: a mass matrix must be symmetric (the kinetic energy x'^T M x' / 2 holds only its symmetric part; tolerance {} of its largest entry)", SYMMETRY_TOLERANCE)]
    AsymmetricMass {
        /// 1-based row of the first entry.
        row: usize,
        /// 1-based column.
        col: usize,
        /// `M(row, col)`.
        value: f64,
        /// `M(col, row)`.
        mirror: f64,
    },
    /// Names do not match the number of degrees of freedom, or repeat.
    #[error("names: {0}")]
    Names(String),
    /// An expression uses a variable outside its range or enters a missing equation.
    #[error("{what}: {detail}")]
    ExprShape {
        /// Which expression.
        what: String,
        /// What is wrong.
        detail: String,
    },
    /// The equilibrium has the wrong length or a non-finite value.
    #[error("equilibrium: {0}")]
    Equilibrium(String),
}

/// A mechanical system `M x'' + C x' + K x + f(x, x') + G(x)^T mu = eps fext, g(x) = 0`
/// (eq. 1), to be turned into first-order form by [`MechanicalSystem::into_model`].
#[derive(Clone, Debug, PartialEq)]
pub struct MechanicalSystem {
    /// Model name.
    pub name: String,
    /// Names of the `n` displacements (outputs get these names; velocities get `<name>_dot`).
    pub dof_names: Vec<String>,
    /// Physical nature of each displacement.
    pub dof_motion: Vec<MotionKind>,
    /// Mass matrix `M` (`n x n`, non-singular).
    pub mass: SparseMatrix,
    /// Damping matrix `C` (`n x n`).
    pub damping: SparseMatrix,
    /// Stiffness matrix `K` (`n x n`).
    pub stiffness: SparseMatrix,
    /// Internal force `f(x, x')`: `n` equations in `2n` variables (`x` first,
    /// then `x'`), degree >= 2 only.
    pub internal_force: PolyVector,
    /// Configuration constraints, if any.
    pub constraints: Option<Constraints>,
    /// Non-polynomial (or constant, or linear) parts of `f(x, x')` as
    /// `(dof, expression in the 2n variables (x, x'))`, e.g. `(0, sin(phi))` for
    /// the pendulum (eq. 21) or `(1, -m1 g)` for gravity; recast by the engine.
    pub force_expressions: Vec<(usize, Expr)>,
    /// External forcing `fext(x, x', Omega t)` as harmonics, each `n` equations in `2n` variables.
    pub forcing: Vec<Harmonic>,
    /// Extra named outputs as `(name, [(displacement index, weight)])`.
    pub extra_outputs: Vec<(String, Vec<(usize, f64)>)>,
    /// Equilibrium to expand about, when it is not the origin.
    pub equilibrium: Option<Equilibrium>,
}

impl MechanicalSystem {
    /// An unconstrained, unforced, linear system with `n` displacements named
    /// `dof_names` and zero matrices; fill in the fields afterwards.
    pub fn new(name: &str, dof_names: &[&str]) -> Self {
        let n = dof_names.len();
        Self {
            name: name.to_owned(),
            dof_names: dof_names.iter().map(|s| (*s).to_owned()).collect(),
            dof_motion: vec![MotionKind::Unspecified; n],
            mass: SparseMatrix::zeros(n, n),
            damping: SparseMatrix::zeros(n, n),
            stiffness: SparseMatrix::zeros(n, n),
            internal_force: PolyVector::zeros(n, 2 * n),
            constraints: None,
            force_expressions: Vec::new(),
            forcing: Vec::new(),
            extra_outputs: Vec::new(),
            equilibrium: None,
        }
    }

    /// Number of displacements `n`.
    pub fn n_dof(&self) -> usize {
        self.dof_names.len()
    }

    fn check(&self) -> Result<usize, BuildError> {
        let n = self.n_dof();
        if self.dof_motion.len() != n {
            return Err(BuildError::Names(format!(
                "{} motion kinds for {n} degrees of freedom",
                self.dof_motion.len()
            )));
        }
        let mut seen = std::collections::HashSet::new();
        for name in &self.dof_names {
            if name.is_empty() || !seen.insert(name.as_str()) {
                return Err(BuildError::Names(format!(
                    "degree-of-freedom name '{name}' is empty or repeated"
                )));
            }
        }
        for (what, m) in [
            ("M", &self.mass),
            ("C", &self.damping),
            ("K", &self.stiffness),
        ] {
            check_matrix(what, m, n)?;
        }
        if let Some((row, col, value, mirror)) = self.mass.asymmetry(SYMMETRY_TOLERANCE) {
            return Err(BuildError::AsymmetricMass {
                row: row + 1,
                col: col + 1,
                value,
                mirror,
            });
        }
        check_poly("f(x, x')", &self.internal_force, n, 2 * n)?;
        check_degree("f(x, x')", &self.internal_force, 2)?;
        for h in &self.forcing {
            check_poly("fext (cos part)", &h.cos, n, 2 * n)?;
            check_poly("fext (sin part)", &h.sin, n, 2 * n)?;
        }
        for (k, (i, e)) in self.force_expressions.iter().enumerate() {
            let what = format!("force expression {}", k + 1);
            if *i >= n {
                return Err(BuildError::ExprShape {
                    what,
                    detail: format!("enters dof {i} of {n}"),
                });
            }
            check_expr(what, e, 2 * n)?;
        }
        if let Some(c) = &self.constraints {
            for (k, e) in c.expressions.iter().enumerate() {
                check_expr(format!("constraint {}", c.g.n_eq as usize + k + 1), e, n)?;
            }
        }
        if let Some(eq) = &self.equilibrium {
            let nc = self.constraints.as_ref().map_or(0, Constraints::len);
            if eq.x.len() != n || eq.mu.len() != nc {
                return Err(BuildError::Equilibrium(format!(
                    "{} displacements and {} multipliers given, expected {n} and {nc}",
                    eq.x.len(),
                    eq.mu.len()
                )));
            }
            if let Some(v) = eq.x.iter().chain(&eq.mu).find(|v| !v.is_finite()) {
                return Err(BuildError::Equilibrium(format!("non-finite value {v}")));
            }
        }
        if let Some(c) = &self.constraints {
            check_poly("g(x)", &c.g, c.g.n_eq as usize, n)?;
            let nc = c.g.n_eq as usize;
            let mut has_linear = vec![false; nc];
            for t in c.g.terms.iter() {
                match t.degree() {
                    0 => {
                        return Err(BuildError::ConstraintConstant {
                            index: t.eq as usize + 1,
                            value: t.coeff,
                        })
                    }
                    1 => has_linear[t.eq as usize] = true,
                    _ => {}
                }
            }
            if let Some(j) = has_linear.iter().position(|&h| !h) {
                return Err(BuildError::ConstraintNoLinearPart { index: j + 1 });
            }
        }
        for (name, w) in &self.extra_outputs {
            if let Some(&(i, _)) = w.iter().find(|(i, _)| *i >= n) {
                return Err(BuildError::Names(format!(
                    "output '{name}' refers to displacement {i} of {n}"
                )));
            }
        }
        Ok(n)
    }

    /// Assembles the first-order DAE of eqs. (4)-(5):
    /// `z = (x, x', mu)`,
    /// `A = [[-K, 0, -G0^T], [0, M, 0], [G0, 0, 0]]`,
    /// `B = [[C, M, 0], [M, 0, 0], [0, 0, 0]]`,
    /// `F = (-f(x, x') - G_nl(x)^T mu, 0, g_nl(x))`, `Fext = (fext, 0, 0)`.
    ///
    /// Force expressions enter `E(z)` as `-f_i`; each expression constraint
    /// `g_j` enters as `E_{2n+j} = g_j(x)` and `E_i = -(d g_j / d x_i) mu_j`,
    /// differentiated symbolically ([`Expr::diff`]).
    pub fn into_model(self) -> Result<Model, BuildError> {
        let n = self.check()?;
        let nc = self.constraints.as_ref().map_or(0, Constraints::len);
        let big_n = 2 * n + nc;
        let mut a = SparseMatrix::zeros(big_n, big_n);
        let mut b = SparseMatrix::zeros(big_n, big_n);
        // entries copied as given, explicit zeros included: they are part of
        // the sparsity pattern the engine factorizes
        for (i, k, v) in self.stiffness.iter() {
            a.push_entry(i, k, -v);
        }
        for (i, k, v) in self.mass.iter() {
            a.push_entry(n + i, n + k, v);
            b.push_entry(i, n + k, v);
            b.push_entry(n + i, k, v);
        }
        for (i, k, v) in self.damping.iter() {
            b.push_entry(i, k, v);
        }
        let mut f = PolyVector::zeros(big_n, big_n);
        for t in self.internal_force.terms.iter() {
            let factors: Vec<(usize, u32)> = t
                .factors
                .iter()
                .map(|p| (p.var as usize, p.power))
                .collect();
            f.push(t.eq as usize, -t.coeff, &factors);
        }
        if let Some(c) = &self.constraints {
            for t in c.g.terms.iter() {
                let j = t.eq as usize;
                let mu = 2 * n + j;
                if t.degree() == 1 {
                    let x = t.factors[0].var as usize;
                    a.push(mu, x, t.coeff);
                    a.push(x, mu, -t.coeff);
                    continue;
                }
                let factors: Vec<(usize, u32)> = t
                    .factors
                    .iter()
                    .map(|p| (p.var as usize, p.power))
                    .collect();
                f.push(mu, t.coeff, &factors);
                // -(d g_nl_j / d x_i) mu_j in row i, for every variable of the monomial
                for (k, p) in t.factors.iter().enumerate() {
                    let mut d: Vec<(usize, u32)> = factors.clone();
                    d[k].1 -= 1;
                    d.push((mu, 1));
                    f.push(p.var as usize, -t.coeff * p.power as f64, &d);
                }
            }
        }
        let mut expr_terms: Vec<(usize, Expr)> = self
            .force_expressions
            .iter()
            .map(|(i, e)| (*i, -e.clone()))
            .collect();
        if let Some(c) = &self.constraints {
            let np = c.g.n_eq as usize;
            for (k, g) in c.expressions.iter().enumerate() {
                let mu = Expr::var(2 * n + np + k);
                expr_terms.push((2 * n + np + k, g.clone()));
                for i in g.vars() {
                    expr_terms.push((i, -(g.diff(i) * mu.clone())));
                }
            }
        }
        let expressions = expr_vector(big_n, big_n, &expr_terms);
        let equilibrium: RVec<f64> = match &self.equilibrium {
            Some(eq) => {
                eq.x.iter()
                    .copied()
                    .chain(std::iter::repeat_n(0.0, n))
                    .chain(eq.mu.iter().copied())
                    .collect()
            }
            None => RVec::new(),
        };
        let forcing = self
            .forcing
            .iter()
            .map(|h| Harmonic {
                multiple: h.multiple,
                cos: embed(&h.cos, big_n),
                sin: embed(&h.sin, big_n),
            })
            .collect();
        let mut states = RVec::with_capacity(big_n);
        let mut outputs = RVec::with_capacity(big_n + self.extra_outputs.len());
        for (i, name) in self.dof_names.iter().enumerate() {
            states.push(state(name, StateKind::Displacement, self.dof_motion[i]));
        }
        for (i, name) in self.dof_names.iter().enumerate() {
            states.push(state(
                &format!("{name}_dot"),
                StateKind::Velocity,
                self.dof_motion[i],
            ));
        }
        for j in 0..nc {
            states.push(state(
                &format!("mu{}", j + 1),
                StateKind::Multiplier,
                MotionKind::Unspecified,
            ));
        }
        for (k, s) in states.iter().enumerate() {
            outputs.push(Output {
                name: s.name.clone(),
                weights: vec![Weight {
                    state: k as u32,
                    value: 1.0,
                }]
                .into(),
            });
        }
        for (name, w) in &self.extra_outputs {
            outputs.push(Output {
                name: name.as_str().into(),
                weights: w
                    .iter()
                    .map(|&(i, value)| Weight {
                        state: i as u32,
                        value,
                    })
                    .collect(),
            });
        }
        Ok(Model {
            name: self.name.as_str().into(),
            a,
            b,
            nonlinearity: f,
            forcing,
            states,
            outputs,
            time: TimeKind::Flow,
            mechanical: abi_stable::std_types::ROption::RSome(MechanicalInfo::canonical(
                n, nc, self.mass,
            )),
            expressions,
            equilibrium,
        })
    }
}

fn state(name: &str, kind: StateKind, motion: MotionKind) -> StateInfo {
    StateInfo {
        name: RString::from(name),
        kind,
        motion,
    }
}

/// Re-indexes a polynomial in `(x, x')` (the first `2n` states) as one in all
/// `big_n` states, keeping its `n` equations in the first block.
fn embed(p: &PolyVector, big_n: usize) -> PolyVector {
    PolyVector {
        n_eq: big_n as u32,
        n_vars: big_n as u32,
        terms: p.terms.clone(),
    }
}

fn check_expr(what: String, e: &Expr, n_vars: usize) -> Result<(), BuildError> {
    if let Some(&v) = e.vars().iter().find(|&&v| v >= n_vars) {
        return Err(BuildError::ExprShape {
            what,
            detail: format!("uses variable {v} of {n_vars}"),
        });
    }
    Ok(())
}

fn check_matrix(what: &'static str, m: &SparseMatrix, n: usize) -> Result<(), BuildError> {
    if m.nrows as usize != n || m.ncols as usize != n {
        return Err(BuildError::MatrixShape {
            what,
            rows: m.nrows as usize,
            cols: m.ncols as usize,
            expected: n,
        });
    }
    for (row, col, _) in m.iter() {
        if row >= n || col >= n {
            return Err(BuildError::EntryOutOfRange {
                what,
                row,
                col,
                size: n,
            });
        }
    }
    Ok(())
}

fn check_poly(
    what: &'static str,
    p: &PolyVector,
    n_eq: usize,
    n_vars: usize,
) -> Result<(), BuildError> {
    if p.n_eq as usize != n_eq || p.n_vars as usize != n_vars {
        return Err(BuildError::PolyShape {
            what,
            detail: format!(
                "has {} equations in {} variables, expected {n_eq} in {n_vars}",
                p.n_eq, p.n_vars
            ),
        });
    }
    for t in p.terms.iter() {
        if t.eq as usize >= n_eq {
            return Err(BuildError::PolyShape {
                what,
                detail: format!("term in equation {} of {n_eq}", t.eq),
            });
        }
        if let Some(v) = t.factors.iter().find(|v| v.var as usize >= n_vars) {
            return Err(BuildError::PolyShape {
                what,
                detail: format!("term uses variable {} of {n_vars}", v.var),
            });
        }
        if !t.coeff.is_finite() {
            return Err(BuildError::PolyShape {
                what,
                detail: format!("non-finite coefficient in equation {}", t.eq),
            });
        }
    }
    Ok(())
}

fn check_degree(what: &'static str, p: &PolyVector, min: u32) -> Result<(), BuildError> {
    match p.terms.iter().find(|t| t.degree() < min) {
        Some(t) => Err(BuildError::LowDegreeTerm {
            what,
            eq: t.eq as usize,
            degree: t.degree(),
        }),
        None => Ok(()),
    }
}

impl From<BuildError> for PluginError {
    fn from(e: BuildError) -> Self {
        Self::new(ErrorKind::BuildFailed, "mechanical builder", &e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every plugin's mass matrix goes through the builder: `M(1, 2) = 0.5`,
    /// `M(2, 1) = -0.5` is refused naming both entries, a stiffness that is
    /// not symmetric (follower forces) is accepted.
    #[test]
    fn an_asymmetric_mass_matrix_is_refused() {
        let mut s = MechanicalSystem::new("t", &["x1", "x2"]);
        s.mass = SparseMatrix::diagonal(&[1.0, 1.0]);
        s.stiffness = SparseMatrix::diagonal(&[4.0, 9.0]);
        s.stiffness.push(0, 1, 0.3);
        assert!(s.clone().into_model().is_ok());
        s.mass.push(0, 1, 0.5);
        s.mass.push(1, 0, -0.5);
        let e = s.into_model().unwrap_err();
        assert!(
            e.to_string()
                .contains("M(2, 1) = -0.5 but M(1, 2) = 0.5: a mass matrix must be symmetric"),
            "{e}"
        );
    }

    /// One pendulum-like dof with a spherical-type constraint: checks the block
    /// layout of eq. (5) entry by entry, and that `G_nl^T mu` is the exact
    /// derivative of `g_nl`.
    #[test]
    fn block_layout_matches_eq5() {
        let mut s = MechanicalSystem::new("t", &["x1", "x2"]);
        s.mass = SparseMatrix::diagonal(&[2.0, 3.0]);
        s.damping = SparseMatrix::diagonal(&[0.1, 0.2]);
        s.stiffness = SparseMatrix::diagonal(&[5.0, 7.0]);
        let mut g = PolyVector::zeros(1, 2);
        g.push(0, 1.0, &[(1, 1)]); // x2
        g.push(0, -1.0, &[(0, 3)]); // -x1^3
        s.constraints = Some(Constraints::polynomial(g));
        let m = s.into_model().unwrap();
        assert_eq!(m.n_states(), 5);
        let dense = |sm: &SparseMatrix| {
            let mut d = vec![vec![0.0; 5]; 5];
            for (i, k, v) in sm.iter() {
                d[i][k] += v;
            }
            d
        };
        let a = dense(&m.a);
        let b = dense(&m.b);
        assert_eq!(a[0][0], -5.0);
        assert_eq!(a[1][1], -7.0);
        assert_eq!(a[2][2], 2.0);
        assert_eq!(a[3][3], 3.0);
        assert_eq!(a[1][4], -1.0); // -G0^T
        assert_eq!(a[4][1], 1.0); // G0
        assert_eq!(b[0][0], 0.1);
        assert_eq!(b[0][2], 2.0);
        assert_eq!(b[2][0], 2.0);
        assert_eq!(b[4].iter().filter(|v| **v != 0.0).count(), 0);
        // F: row 4 has g_nl = -x1^3; row 0 has -(d g_nl/d x1) mu = +3 x1^2 mu
        let row4: Vec<_> = m.nonlinearity.terms.iter().filter(|t| t.eq == 4).collect();
        assert_eq!(row4.len(), 1);
        assert_eq!(row4[0].coeff, -1.0);
        let row0: Vec<_> = m.nonlinearity.terms.iter().filter(|t| t.eq == 0).collect();
        assert_eq!(row0.len(), 1);
        assert_eq!(row0[0].coeff, 3.0);
        assert_eq!(
            row0[0].factors.as_slice(),
            &[
                ssm_api::VarPower { var: 0, power: 2 },
                ssm_api::VarPower { var: 4, power: 1 }
            ]
        );
    }

    #[test]
    fn constraint_without_linear_part_is_refused() {
        let mut s = MechanicalSystem::new("t", &["x1"]);
        s.mass = SparseMatrix::diagonal(&[1.0]);
        let mut g = PolyVector::zeros(1, 1);
        g.push(0, 1.0, &[(0, 2)]);
        s.constraints = Some(Constraints::polynomial(g));
        assert_eq!(
            s.into_model(),
            Err(BuildError::ConstraintNoLinearPart { index: 1 })
        );
    }

    #[test]
    fn linear_term_in_f_is_refused() {
        let mut s = MechanicalSystem::new("t", &["x1"]);
        s.internal_force.push(0, 1.0, &[(0, 1)]);
        assert!(matches!(
            s.into_model(),
            Err(BuildError::LowDegreeTerm { degree: 1, .. })
        ));
    }
}
