//! What each analysis is asked to compute, free of the scene's TOML: the
//! types code builds directly (a binding, a study, a test) and that the
//! scene's sections resolve to (`crate::plan`). Every spec
//! serializes to and from JSON; a field left out of the JSON takes the
//! default documented on it, the same default a scene gets.

use serde::{Deserialize, Serialize};

mod check;
mod runs;

pub use check::{
    MAX_HARMONICS, MAX_POD_ROMS, MAX_POD_TESTS, MAX_REFERENCE_CURVES, MAX_REFERENCE_STEPS,
    MAX_SIMULATE_SAMPLES, MAX_STEADY_STATES,
};
pub use runs::{
    PodRunSpec, PodSpec, PodTruncations, ReferenceSpec, ReferenceStart, ReportSpec, SimulateSpec,
    SpectrumSpec, SsmSpec,
};

/// A spec that cannot be computed: the key (as the scene spells it), where a
/// scene's message points when not at the key itself, and what is wrong
/// with its value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}: {problem}")]
pub struct SpecError {
    /// The key, e.g. `forcing.omega_range`.
    pub key: String,
    /// The key path whose place a scene's message points at, when it is not
    /// `key` (e.g. `ssm.master_pairs` for a backbone asked of two pairs).
    pub at: Option<String>,
    /// What is wrong.
    pub problem: String,
}

impl SpecError {
    /// A problem of `key`.
    pub fn new(key: impl Into<String>, problem: String) -> Self {
        Self {
            key: key.into(),
            at: None,
            problem,
        }
    }

    /// A problem of `key`, pointed at `at`.
    pub fn at(key: impl Into<String>, at: impl Into<String>, problem: String) -> Self {
        Self {
            key: key.into(),
            at: Some(at.into()),
            problem,
        }
    }
}

fn spec_error(key: &str, problem: String) -> SpecError {
    SpecError::new(key, problem)
}

/// Backbone curves `omega(rho)` of the master pair, one per expansion order
/// (`[outputs.backbone]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BackboneSpec {
    /// Largest polar amplitude `rho` of the curve.
    pub rho_max: f64,
    /// Amplitudes on each curve, uniformly in `[0, rho_max]` (default 101).
    #[serde(default = "BackboneSpec::default_points")]
    pub points: usize,
    /// Expansion orders, one curve each (`None`: the SSM's order).
    #[serde(default)]
    pub orders: Option<Vec<usize>>,
}

impl BackboneSpec {
    /// Amplitudes on a curve when none are asked for.
    pub const DEFAULT_POINTS: usize = 101;

    fn default_points() -> usize {
        Self::DEFAULT_POINTS
    }

    /// Curves up to `rho_max` with the default number of points, at the
    /// SSM's order.
    pub fn up_to(rho_max: f64) -> Self {
        Self {
            rho_max,
            points: Self::DEFAULT_POINTS,
            orders: None,
        }
    }
}

/// The invariance error of eq. (41) on tori of the SSM
/// (`[outputs.invariance_error]`), one value per order and radius.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InvarianceSpec {
    /// Radii of the sampled tori.
    pub radii: Vec<f64>,
    /// Expansion orders.
    pub orders: Vec<usize>,
    /// Samples of the torus angle `alpha` (default 10).
    #[serde(default = "InvarianceSpec::default_n_alpha")]
    pub n_alpha: usize,
    /// Samples of each phase `theta` (default 30).
    #[serde(default = "InvarianceSpec::default_n_theta")]
    pub n_theta: usize,
}

impl InvarianceSpec {
    /// Samples of `alpha` when none are asked for.
    pub const DEFAULT_N_ALPHA: usize = 10;
    /// Samples of each `theta` when none are asked for.
    pub const DEFAULT_N_THETA: usize = 30;

    fn default_n_alpha() -> usize {
        Self::DEFAULT_N_ALPHA
    }
    fn default_n_theta() -> usize {
        Self::DEFAULT_N_THETA
    }
}

/// A transient of the reduced model lifted by `W` (`[outputs.transient]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransientSpec {
    /// Initial polar amplitude of each master pair.
    pub rho0: Vec<f64>,
    /// Initial phase of each master pair (`None`: zeros).
    #[serde(default)]
    pub theta0: Option<Vec<f64>>,
    /// Final time.
    pub t_end: f64,
    /// Output samples (default 1001).
    #[serde(default = "TransientSpec::default_samples")]
    pub samples: usize,
    /// Expansion order of the reduced model (`None`: the SSM's order).
    #[serde(default)]
    pub order: Option<usize>,
    /// Relative tolerance of the integrator (default 1e-9).
    #[serde(default = "TransientSpec::default_rtol")]
    pub rtol: f64,
}

impl TransientSpec {
    /// Output samples when none are asked for.
    pub const DEFAULT_SAMPLES: usize = 1001;
    /// Relative tolerance when none is asked for.
    pub const DEFAULT_RTOL: f64 = 1e-9;

    fn default_samples() -> usize {
        Self::DEFAULT_SAMPLES
    }
    fn default_rtol() -> f64 {
        Self::DEFAULT_RTOL
    }
}

/// Forced response curves of the periodic SSM (`[forcing]`), one per
/// `(order, epsilon)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrcSpec {
    /// Forcing amplitudes, one curve each.
    pub epsilon: Vec<f64>,
    /// `[Omega_min, Omega_max]`.
    pub omega_range: [f64; 2],
    /// Expansion orders of the reduced dynamics (`None`: the SSM's order).
    #[serde(default)]
    pub orders: Option<Vec<usize>>,
    /// External resonance ratios `r` of eq. (16), one per master pair
    /// (`None`: the nearest small rational of each pair's frequency to the
    /// middle of the range; 1 for a single pair).
    #[serde(default)]
    pub resonance: Option<Vec<f64>>,
    /// Points per side of each branch (default 200).
    #[serde(default = "FrcSpec::default_points")]
    pub points: usize,
    /// Largest polar amplitude searched for branches (`None`: from the
    /// forcing, the damping and the backbone, see
    /// `rom::frc::default_rho_max`).
    #[serde(default)]
    pub rho_max: Option<f64>,
    /// Order in `p` of the non-autonomous terms `O(eps |p|^k)` (`None` or 0:
    /// the leading order `X0`, `S0` of the paper).
    #[serde(default)]
    pub nonautonomous_order: Option<usize>,
}

impl FrcSpec {
    /// Points per branch side when none are asked for.
    pub const DEFAULT_POINTS: usize = 200;

    fn default_points() -> usize {
        Self::DEFAULT_POINTS
    }

    /// Curves at the amplitudes `epsilon` over `omega_range`, everything
    /// else at its default.
    pub fn new(epsilon: Vec<f64>, omega_range: [f64; 2]) -> Self {
        Self {
            epsilon,
            omega_range,
            orders: None,
            resonance: None,
            points: Self::DEFAULT_POINTS,
            rho_max: None,
            nonautonomous_order: None,
        }
    }

    /// Checks the spec against an SSM of `pairs` master pairs computed to
    /// `ssm_order` (what a scene's `[forcing]` is checked for, with the
    /// same messages; a spec built in code meets these checks at
    /// [`crate::rom::forced_response::forced_response`]).
    pub fn check(&self, pairs: usize, ssm_order: usize) -> Result<(), SpecError> {
        if self.epsilon.is_empty() || self.epsilon.iter().any(|e| !(e.is_finite() && *e > 0.0)) {
            return Err(spec_error(
                "forcing.epsilon",
                format!(
                    "needs at least one forcing amplitude, each positive, found {:?}",
                    self.epsilon
                ),
            ));
        }
        let [a, b] = self.omega_range;
        if !(a.is_finite() && b.is_finite() && 0.0 < a && a < b) {
            return Err(spec_error(
                "forcing.omega_range",
                format!(
                    "must be [Omega_min, Omega_max] with 0 < Omega_min < Omega_max, found {:?}",
                    self.omega_range
                ),
            ));
        }
        if let Some(orders) = &self.orders {
            check::orders(orders, ssm_order, "forcing.orders")?;
        }
        if let Some(r) = &self.resonance {
            if r.len() != pairs || r.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(spec_error(
                    "forcing.resonance",
                    format!("needs one positive ratio per master pair ({pairs}), found {r:?}"),
                ));
            }
        }
        if self.points < 2 {
            return Err(spec_error(
                "forcing.points",
                format!("must be at least 2, found {}", self.points),
            ));
        }
        if let Some(r) = self.rho_max {
            if !(r.is_finite() && r > 0.0) {
                return Err(spec_error(
                    "forcing.rho_max",
                    format!("must be a positive number, found {r}"),
                ));
            }
        }
        if let Some(k) = self.nonautonomous_order {
            let max = ssm_order.saturating_sub(1);
            if k > max {
                return Err(spec_error(
                    "forcing.nonautonomous_order",
                    format!("must be at most the SSM's order - 1 = {max}, found {k}"),
                ));
            }
        }
        Ok(())
    }

    /// The same curves at the single order `order`.
    pub(crate) fn at_order(&self, order: usize) -> Self {
        Self {
            orders: Some(vec![order]),
            ..self.clone()
        }
    }
}

/// Where a full-system transient of `[validate]` starts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ValidationStart {
    /// On the SSM at `W(p0)`, `p0` in polar form.
    Ssm {
        /// Polar amplitude of each master pair.
        rho0: Vec<f64>,
        /// Phase of each master pair (`None`: zeros).
        #[serde(default)]
        theta0: Option<Vec<f64>>,
    },
    /// Given displacements and velocities by state name (the others zero),
    /// projected onto the constraints; the reduced model starts from the
    /// nearest point of the SSM.
    Given {
        /// `(state name, value)` pairs.
        values: Vec<(String, f64)>,
    },
}

/// Where the steady-state integrations of `[validate.steady_state]` start.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SteadyStart {
    /// The unforced equilibrium.
    #[default]
    Rest,
    /// The largest stable response the FRC predicts at that frequency.
    Ssm,
}

/// Steady states of the full system by integration until criterion (47)
/// holds (`[validate.steady_state]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteadyStateSpec {
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Forcing frequencies.
    pub omegas: Vec<f64>,
    /// Relative tolerance `delta` of criterion (47) (default 1e-3).
    #[serde(default = "SteadyStateSpec::default_delta")]
    pub delta: f64,
    /// Forcing periods at most (default 2000).
    #[serde(default = "SteadyStateSpec::default_max_periods")]
    pub max_periods: usize,
    /// Output samples per period (default 128).
    #[serde(default = "SteadyStateSpec::default_samples_per_period")]
    pub samples_per_period: usize,
    /// Largest multiple of the forcing period accepted as the response
    /// period (default 1: criterion (47) as published).
    #[serde(default = "SteadyStateSpec::default_max_period_multiple")]
    pub max_period_multiple: usize,
    /// Where each integration starts (default: rest).
    #[serde(default)]
    pub start: SteadyStart,
}

impl SteadyStateSpec {
    /// `delta` when none is asked for.
    pub const DEFAULT_DELTA: f64 = 1e-3;
    /// Periods at most when none are asked for.
    pub const DEFAULT_MAX_PERIODS: usize = 2000;
    /// Samples per period when none are asked for.
    pub const DEFAULT_SAMPLES_PER_PERIOD: usize = 128;
    /// Frequencies of an `omega_range` when no `points` are asked for.
    pub const DEFAULT_POINTS: usize = 21;
    /// Period multiple when none is asked for.
    pub const DEFAULT_MAX_PERIOD_MULTIPLE: usize = 1;

    fn default_delta() -> f64 {
        Self::DEFAULT_DELTA
    }
    fn default_max_periods() -> usize {
        Self::DEFAULT_MAX_PERIODS
    }
    fn default_samples_per_period() -> usize {
        Self::DEFAULT_SAMPLES_PER_PERIOD
    }
    fn default_max_period_multiple() -> usize {
        Self::DEFAULT_MAX_PERIOD_MULTIPLE
    }

    /// `points` frequencies uniformly over `[range[0], range[1]]` (its
    /// middle for one point).
    pub fn uniform(range: [f64; 2], points: usize) -> Vec<f64> {
        match points {
            0 => Vec::new(),
            1 => vec![0.5 * (range[0] + range[1])],
            n => (0..n)
                .map(|i| range[0] + (range[1] - range[0]) * i as f64 / (n - 1) as f64)
                .collect(),
        }
    }
}

/// The full-system transient of `[validate]` against the reduced one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValidationTransientSpec {
    /// Where both start.
    pub start: ValidationStart,
    /// Final time.
    pub t_end: f64,
    /// Samples (default 1001).
    #[serde(default = "ValidationTransientSpec::default_samples")]
    pub samples: usize,
    /// Expansion order of the reduced model compared (`None`: the SSM's).
    #[serde(default)]
    pub order: Option<usize>,
}

impl ValidationTransientSpec {
    /// Samples when none are asked for.
    pub const DEFAULT_SAMPLES: usize = 1001;

    fn default_samples() -> usize {
        Self::DEFAULT_SAMPLES
    }
}

/// Full-system comparisons (`[validate]`): a transient against the reduced
/// one and steady states against the forced response curves, both
/// integrated by Radau IIA with the tolerances given here.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValidationSpec {
    /// The transient comparison.
    #[serde(default)]
    pub transient: Option<ValidationTransientSpec>,
    /// Steady-state references.
    #[serde(default)]
    pub steady_state: Option<SteadyStateSpec>,
    /// Relative tolerance of the full-system integrator (default 1e-8).
    #[serde(default = "ValidationSpec::default_rtol")]
    pub rtol: f64,
    /// Absolute tolerance of the full-system integrator (default 1e-10).
    #[serde(default = "ValidationSpec::default_atol")]
    pub atol: f64,
    /// Outputs compared (`None`: the plan's coordinates).
    #[serde(default)]
    pub outputs: Option<Vec<String>>,
}

impl ValidationSpec {
    /// Relative tolerance when none is asked for.
    pub const DEFAULT_RTOL: f64 = 1e-8;
    /// Absolute tolerance when none is asked for.
    pub const DEFAULT_ATOL: f64 = 1e-10;

    fn default_rtol() -> f64 {
        Self::DEFAULT_RTOL
    }
    fn default_atol() -> f64 {
        Self::DEFAULT_ATOL
    }
}
