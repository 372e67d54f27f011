//! The engine-side first-order system `B z' = A z + F(z) + eps Fext(z, Omega t)`,
//! validated and converted from a plugin's [`ssm_api::Model`].

use faer::sparse::{SparseColMat, Triplet};
use ssm_api::{Harmonic, MotionKind, PolyVector, StateInfo, StateKind, TimeKind};

use crate::model::recast::{self, RecastError, RecastInfo};

/// A plugin's model that the engine cannot use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A matrix or polynomial has the wrong dimensions.
    #[error("model '{model}': {what} is {found}, expected {expected}")]
    Shape {
        /// Model name.
        model: String,
        /// Which part.
        what: String,
        /// Dimensions found.
        found: String,
        /// Dimensions expected.
        expected: String,
    },
    /// An index points outside the system.
    #[error("model '{model}': {what} refers to index {index}, but the system has {size}")]
    Index {
        /// Model name.
        model: String,
        /// Which part.
        what: String,
        /// Offending index.
        index: usize,
        /// Valid size.
        size: usize,
    },
    /// A NaN or infinite coefficient.
    #[error("model '{model}': {what} has a non-finite value {value}")]
    NonFinite {
        /// Model name.
        model: String,
        /// Where.
        what: String,
        /// The value.
        value: f64,
    },
    /// Two outputs or states share a name.
    #[error("model '{model}': the name '{name}' is used twice")]
    DuplicateName {
        /// Model name.
        model: String,
        /// The repeated name.
        name: String,
    },
    /// A state or output name that cannot stand as a CSV column or plot label.
    #[error("model '{model}': {what} name {name:?} {problem}: use letters, digits and punctuation other than commas and quotes")]
    BadName {
        /// Model name.
        model: String,
        /// "state" or "output".
        what: &'static str,
        /// The name.
        name: String,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// The non-polynomial part could not be recast.
    #[error("model '{model}': recast: {source}")]
    Recast {
        /// Model name.
        model: String,
        /// What went wrong.
        source: RecastError,
    },
    /// The declared constraint layout contradicts the states or the model.
    #[error("model '{model}': constraint layout: {source}")]
    Layout {
        /// Model name.
        model: String,
        /// What is wrong.
        source: crate::model::layout::LayoutError,
    },
    /// A monomial lists a variable with exponent 0.
    #[error("model '{model}': {what}, equation {eq}, lists variable {var} with power 0; list only variables with a power of at least 1")]
    ZeroPower {
        /// Model name.
        model: String,
        /// Which part.
        what: String,
        /// 0-based equation.
        eq: usize,
        /// 0-based variable.
        var: usize,
    },
    /// A monomial's total degree is beyond [`MAX_DEGREE`].
    #[error("model '{model}': {what}, equation {eq}, has a monomial of degree {degree}; the engine accepts degrees up to {MAX_DEGREE}")]
    HighDegree {
        /// Model name.
        model: String,
        /// Which part.
        what: String,
        /// 0-based equation.
        eq: usize,
        /// The total degree.
        degree: u64,
    },
    /// The nonlinearity has a constant or linear term.
    #[error("model '{model}': F, equation {eq}, has a term of degree {degree}; F must start at degree 2 (linear terms belong in A)")]
    LowDegree {
        /// Model name.
        model: String,
        /// 0-based equation.
        eq: usize,
        /// Degree found.
        degree: u32,
    },
}

/// Largest total degree of a monomial of `F` or of the forcing. Mechanical
/// nonlinearities are of low degree (the recast yields at most 3); the limit
/// keeps a corrupt exponent from asking for gigabytes of series storage.
pub const MAX_DEGREE: u64 = 64;

/// A named output `sum_k w_k z[s_k]`.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputMap {
    /// Output name.
    pub name: String,
    /// `(state, weight)` pairs.
    pub weights: Vec<(usize, f64)>,
}

/// Mechanical structure `z = (x, x', mu)`.
#[derive(Debug, Clone)]
pub struct Mechanical {
    /// Number of displacements `n`.
    pub n_dof: usize,
    /// Number of constraints `n_c`.
    pub n_constraints: usize,
    /// Mass matrix.
    pub mass: SparseColMat<usize, f64>,
}

/// A validated first-order system.
#[derive(Debug, Clone)]
pub struct System {
    /// Plugin that built it.
    pub plugin: String,
    /// Model name.
    pub name: String,
    /// `A` (`N x N`).
    pub a: SparseColMat<usize, f64>,
    /// `B` (`N x N`).
    pub b: SparseColMat<usize, f64>,
    /// `F(z)`.
    pub nonlinearity: PolyVector,
    /// `Fext` harmonics.
    pub forcing: Vec<Harmonic>,
    /// States.
    pub states: Vec<StateInfo>,
    /// Outputs.
    pub outputs: Vec<OutputMap>,
    /// Flow or map.
    pub time: TimeKind,
    /// Mechanical structure, if any.
    pub mechanical: Option<Mechanical>,
    /// The recast of a non-polynomial model (auxiliary states appended after
    /// the model's own), if it needed one.
    pub recast: Option<RecastInfo>,
}

impl System {
    /// Validates a plugin's model and converts its matrices to compressed form.
    pub fn from_model(plugin: &str, m: ssm_api::Model) -> Result<Self, ModelError> {
        let model = m.name.to_string();
        let n = m.states.len();
        // Indices, exponents and values are checked before the layout permutes
        // them, so that no part of the conversion ever sees a bad index.
        check_matrix(&model, "A", &m.a, n, n)?;
        check_matrix(&model, "B", &m.b, n, n)?;
        check_poly(&model, "F", &m.nonlinearity, n)?;
        if let Some(t) = m.nonlinearity.terms.iter().find(|t| t.degree() < 2) {
            return Err(ModelError::LowDegree {
                model,
                eq: t.eq as usize,
                degree: t.degree(),
            });
        }
        for (k, h) in m.forcing.iter().enumerate() {
            check_poly(
                &model,
                &format!("forcing harmonic {} (cos)", k + 1),
                &h.cos,
                n,
            )?;
            check_poly(
                &model,
                &format!("forcing harmonic {} (sin)", k + 1),
                &h.sin,
                n,
            )?;
            if !h.multiple.is_finite() {
                return Err(ModelError::NonFinite {
                    model,
                    what: format!("forcing harmonic {} multiple", k + 1),
                    value: h.multiple,
                });
            }
        }
        if !m.expressions.is_empty() {
            recast::ExprGraph::validate(&m.expressions, n).map_err(|source| {
                ModelError::Recast {
                    model: model.clone(),
                    source,
                }
            })?;
        }
        let m = crate::model::layout::canonicalize(m).map_err(|source| ModelError::Layout {
            model: model.clone(),
            source,
        })?;
        let a = to_csc(&model, "A", &m.a, n, n)?;
        let b = to_csc(&model, "B", &m.b, n, n)?;
        let mut names = std::collections::HashSet::new();
        for s in m.states.iter() {
            check_name(&model, "state", s.name.as_str())?;
            if !names.insert(s.name.as_str()) {
                return Err(ModelError::DuplicateName {
                    model,
                    name: s.name.to_string(),
                });
            }
        }
        let mut outputs = Vec::with_capacity(m.outputs.len());
        let mut out_names = std::collections::HashSet::new();
        for o in m.outputs.iter() {
            check_name(&model, "output", o.name.as_str())?;
            if !out_names.insert(o.name.as_str()) {
                return Err(ModelError::DuplicateName {
                    model,
                    name: o.name.to_string(),
                });
            }
            let mut weights = Vec::with_capacity(o.weights.len());
            for w in o.weights.iter() {
                let what = format!("output '{}'", o.name);
                if w.state as usize >= n {
                    return Err(ModelError::Index {
                        model,
                        what,
                        index: w.state as usize,
                        size: n,
                    });
                }
                if !w.value.is_finite() {
                    return Err(ModelError::NonFinite {
                        model,
                        what,
                        value: w.value,
                    });
                }
                weights.push((w.state as usize, w.value));
            }
            outputs.push(OutputMap {
                name: o.name.to_string(),
                weights,
            });
        }
        let mechanical = match m.mechanical.into_option() {
            Some(info) => {
                let nd = info.n_dof as usize;
                let nc = info.n_constraints as usize;
                if 2 * nd + nc > n {
                    return Err(ModelError::Shape {
                        model,
                        what: "mechanical structure (2 n_dof + n_constraints)".into(),
                        found: format!("{}", 2 * nd + nc),
                        expected: format!("at most {n}"),
                    });
                }
                Some(Mechanical {
                    n_dof: nd,
                    n_constraints: nc,
                    mass: to_csc(&model, "M", &info.mass, nd, nd)?,
                })
            }
            None => None,
        };
        let needs_recast = !m.expressions.is_empty() || !m.equilibrium.is_empty();
        if needs_recast && m.time != TimeKind::Flow {
            return Err(ModelError::Shape {
                model,
                what: "expressions or equilibrium".into(),
                found: "a map".into(),
                expected: "a flow (the recast of maps is not supported)".into(),
            });
        }
        if let TimeKind::Map { period } = m.time {
            if !(period.is_finite() && period > 0.0) {
                return Err(ModelError::NonFinite {
                    model,
                    what: "map period".into(),
                    value: period,
                });
            }
        }
        let forcing: Vec<Harmonic> = m.forcing.into_iter().collect();
        let mut states: Vec<StateInfo> = m.states.into_iter().collect();
        if !needs_recast {
            return Ok(Self {
                plugin: plugin.to_owned(),
                name: model,
                a,
                b,
                nonlinearity: m.nonlinearity.canonical(),
                forcing,
                states,
                outputs,
                time: m.time,
                mechanical,
                recast: None,
            });
        }
        let rc = recast::recast(recast::Source {
            a: &a,
            b: &b,
            f: &m.nonlinearity,
            e: &m.expressions,
            equilibrium: &m.equilibrium,
            forcing: &forcing,
            states: &states,
            n_dof: mechanical.as_ref().map(|mc| mc.n_dof),
        })
        .map_err(|source| ModelError::Recast {
            model: model.clone(),
            source,
        })?;
        for aux in &rc.info.auxiliaries {
            states.push(StateInfo {
                name: aux.name.as_str().into(),
                kind: StateKind::Auxiliary,
                motion: MotionKind::Unspecified,
            });
            if out_names.insert(aux.name.as_str()) {
                outputs.push(OutputMap {
                    name: aux.name.clone(),
                    weights: vec![(aux.state, 1.0)],
                });
            }
        }
        Ok(Self {
            plugin: plugin.to_owned(),
            name: model,
            a: rc.a,
            b: rc.b,
            nonlinearity: rc.nonlinearity.canonical(),
            forcing: rc.forcing,
            states,
            outputs,
            time: m.time,
            mechanical,
            recast: Some(rc.info),
        })
    }

    /// The pencil whose finite spectrum is the model's: `(A, B)`, or for a
    /// recast model the physical pencil with the auxiliaries eliminated
    /// ([`RecastInfo::physical_a`]), free of the recast's spurious modes.
    pub fn spectral_pencil(
        &self,
    ) -> (
        faer::sparse::SparseColMatRef<'_, usize, f64>,
        faer::sparse::SparseColMatRef<'_, usize, f64>,
    ) {
        match &self.recast {
            Some(r) => (r.physical_a.as_ref(), r.physical_b.as_ref()),
            None => (self.a.as_ref(), self.b.as_ref()),
        }
    }

    /// Number of auxiliary states added by a recast.
    pub fn n_auxiliary(&self) -> usize {
        self.recast.as_ref().map_or(0, |r| r.auxiliaries.len())
    }

    /// Number of states `N`.
    pub fn n_states(&self) -> usize {
        self.states.len()
    }

    /// The velocities `n .. 2n` of a mechanical model (canonical layout `z =
    /// (x, x', mu, rest)`), `None` for any other model.
    pub fn velocities(&self) -> Option<std::ops::Range<usize>> {
        self.mechanical
            .as_ref()
            .filter(|m| m.n_dof > 0 && 2 * m.n_dof <= self.n_states())
            .map(|m| m.n_dof..2 * m.n_dof)
    }

    /// The state with the given `(state name, value)` pairs set (the others
    /// zero), and the displacements among them (to be kept where the
    /// constraints allow). Names the model lacks are skipped: the scene
    /// checks refuse them first.
    pub fn given_state(&self, values: &[(String, f64)]) -> (Vec<f64>, Vec<usize>) {
        let mut z = vec![0.0; self.n_states()];
        let mut keep = Vec::new();
        for (name, value) in values {
            if let Some(i) = self.states.iter().position(|s| s.name.as_str() == name) {
                z[i] = *value;
                if self.states[i].kind == StateKind::Displacement {
                    keep.push(i);
                }
            }
        }
        (z, keep)
    }

    /// The output named `name`.
    pub fn output(&self, name: &str) -> Option<&OutputMap> {
        self.outputs.iter().find(|o| o.name == name)
    }
}

/// A name becomes a CSV column header and a plot label: it must be non-empty
/// and free of the CSV field separators (comma, double quote, line breaks and
/// other control characters).
fn check_name(model: &str, what: &'static str, name: &str) -> Result<(), ModelError> {
    let problem = if name.trim().is_empty() {
        Some("is empty")
    } else if name.contains(',') {
        Some("contains a comma")
    } else if name.contains('"') {
        Some("contains a double quote")
    } else if name.chars().any(char::is_control) {
        Some("contains a control character")
    } else {
        None
    };
    match problem {
        Some(problem) => Err(ModelError::BadName {
            model: model.to_owned(),
            what,
            name: name.to_owned(),
            problem,
        }),
        None => Ok(()),
    }
}

fn to_csc(
    model: &str,
    what: &str,
    m: &ssm_api::SparseMatrix,
    nrows: usize,
    ncols: usize,
) -> Result<SparseColMat<usize, f64>, ModelError> {
    check_matrix(model, what, m, nrows, ncols)?;
    let trip: Vec<_> = m.iter().map(|(r, c, v)| Triplet::new(r, c, v)).collect();
    SparseColMat::try_new_from_triplets(nrows, ncols, &trip).map_err(|e| ModelError::Shape {
        model: model.to_owned(),
        what: format!("matrix {what}"),
        found: format!("{e:?}"),
        expected: "a valid sparse matrix".into(),
    })
}

fn check_matrix(
    model: &str,
    what: &str,
    m: &ssm_api::SparseMatrix,
    nrows: usize,
    ncols: usize,
) -> Result<(), ModelError> {
    if m.nrows as usize != nrows || m.ncols as usize != ncols {
        return Err(ModelError::Shape {
            model: model.to_owned(),
            what: format!("matrix {what}"),
            found: format!("{}x{}", m.nrows, m.ncols),
            expected: format!("{nrows}x{ncols}"),
        });
    }
    for t in m.entries.iter() {
        let (r, c) = (t.row as usize, t.col as usize);
        if r >= nrows || c >= ncols {
            return Err(ModelError::Index {
                model: model.to_owned(),
                what: format!("matrix {what} entry ({r}, {c})"),
                index: r.max(c),
                size: nrows.max(ncols),
            });
        }
        if !t.value.is_finite() {
            return Err(ModelError::NonFinite {
                model: model.to_owned(),
                what: format!("matrix {what} entry ({r}, {c})"),
                value: t.value,
            });
        }
    }
    Ok(())
}

fn check_poly(model: &str, what: &str, p: &PolyVector, n: usize) -> Result<(), ModelError> {
    if p.n_eq as usize != n || p.n_vars as usize != n {
        return Err(ModelError::Shape {
            model: model.to_owned(),
            what: what.to_owned(),
            found: format!("{} equations in {} variables", p.n_eq, p.n_vars),
            expected: format!("{n} in {n}"),
        });
    }
    for t in p.terms.iter() {
        if t.eq as usize >= n {
            return Err(ModelError::Index {
                model: model.to_owned(),
                what: format!("{what} term equation"),
                index: t.eq as usize,
                size: n,
            });
        }
        if let Some(v) = t.factors.iter().find(|v| v.var as usize >= n) {
            return Err(ModelError::Index {
                model: model.to_owned(),
                what: format!("{what} term variable"),
                index: v.var as usize,
                size: n,
            });
        }
        if !t.coeff.is_finite() {
            return Err(ModelError::NonFinite {
                model: model.to_owned(),
                what: format!("{what}, equation {}", t.eq),
                value: t.coeff,
            });
        }
        if let Some(v) = t.factors.iter().find(|v| v.power == 0) {
            return Err(ModelError::ZeroPower {
                model: model.to_owned(),
                what: what.to_owned(),
                eq: t.eq as usize,
                var: v.var as usize,
            });
        }
        // summed in u64: u32 powers cannot wrap around there
        let degree: u64 = t.factors.iter().map(|v| u64::from(v.power)).sum();
        if degree > MAX_DEGREE {
            return Err(ModelError::HighDegree {
                model: model.to_owned(),
                what: what.to_owned(),
                eq: t.eq as usize,
                degree,
            });
        }
    }
    Ok(())
}
