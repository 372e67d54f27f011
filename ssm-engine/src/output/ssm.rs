//! Writers of what is read off an SSM: the `ssm` and `polar` entries of
//! `summary.json` (the backbone, the invariance error and the transient are
//! analyses, with their writers: `crate::analyses`). They format typed
//! results and compute nothing.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use ssm_core::ssm::analysis::Polar;
use ssm_core::ssm::{Dynamics, RTerm, SsmExpansion};

/// `"ssm"` of `summary.json`: order, dimension, resonant terms and reduced
/// dynamics (coordinates `p1, conj p1, ...`, 1-based equation numbers).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SsmSummary {
    /// Expansion order.
    pub order: usize,
    /// Dimension of the SSM (twice its master pairs).
    pub dim: usize,
    /// The reduced dynamics is a flow or a map.
    pub time: TimeSummary,
    /// The nonlinear terms kept in the reduced dynamics (the resonant ones).
    pub resonant_terms: Vec<ResonantTerm>,
    /// Every term of the reduced dynamics `R(p)`.
    pub reduced_dynamics: Vec<DynamicsTerm>,
}

/// Continuous or discrete time.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TimeSummary {
    /// `"flow"`: `p' = R(p)`.
    Flow,
    /// `{"map_period": T}`: `p_{k+1} = R(p_k)`, sampled every `T`.
    MapPeriod(f64),
}

/// A nonlinear term kept in the reduced dynamics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ResonantTerm {
    /// Equation (1-based: `p1, conj p1, p2, ...`).
    pub eq: usize,
    /// Exponents of the monomial in `p1, conj p1, ...`.
    pub exponents: Vec<u16>,
}

/// A term of the reduced dynamics with its coefficient.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DynamicsTerm {
    /// Equation (1-based: `p1, conj p1, p2, ...`).
    pub eq: usize,
    /// Exponents of the monomial in `p1, conj p1, ...`.
    pub exponents: Vec<u16>,
    /// Real part of the coefficient.
    pub re: f64,
    /// Imaginary part of the coefficient.
    pub im: f64,
}

impl SsmSummary {
    /// The summary of `ssm`.
    pub fn new(ssm: &SsmExpansion) -> Self {
        SsmSummary {
            order: ssm.order,
            dim: ssm.dim(),
            time: match ssm.dynamics {
                Dynamics::Flow => TimeSummary::Flow,
                Dynamics::Map { period } => TimeSummary::MapPeriod(period),
            },
            resonant_terms: ssm
                .nonlinear_terms()
                .map(|t| ResonantTerm {
                    eq: t.coord + 1,
                    exponents: ssm.set.exponents(t.index).to_vec(),
                })
                .collect(),
            reduced_dynamics: ssm
                .r
                .iter()
                .map(|t: &RTerm| DynamicsTerm {
                    eq: t.coord + 1,
                    exponents: ssm.set.exponents(t.index).to_vec(),
                    re: t.coeff.re,
                    im: t.coeff.im,
                })
                .collect(),
        }
    }
}

/// `"polar"` of `summary.json` (a two-dimensional SSM of a flow): the
/// coefficients of `rho' = a1 rho + a3 rho^3 + ...` and
/// `theta' = b0 + b2 rho^2 + ...`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PolarSummary {
    /// Master pair (1).
    pub pair: usize,
    /// `a1, a3, a5, ...`: the real parts of the coefficients of
    /// `p^(j+1) conj(p)^j` in the equation of `p`.
    pub rho_dot: Vec<f64>,
    /// `b0, b2, b4, ...`: their imaginary parts.
    pub omega: Vec<f64>,
}

impl PolarSummary {
    /// The summary of `p` (one entry: the master pair).
    pub fn new(p: &Polar) -> Vec<Self> {
        vec![PolarSummary {
            pair: 1,
            rho_dot: p.rho_dot(),
            omega: p.omega(),
        }]
    }
}
