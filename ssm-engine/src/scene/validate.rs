//! `[validate]`, `[validate.steady_state]` and `[report]`: full-system
//! references and the speed-against-error report.

use serde::Deserialize;
use toml::Spanned;

use super::{SceneError, SceneFile};
use ssm_core::spec::{SteadyStateSpec, ValidationSpec, ValidationTransientSpec};

/// `[validate]`: the full system against the reduced model.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValidateSection {
    /// Initial polar amplitude of each master pair of the transient started
    /// on the SSM (no transient without it).
    #[serde(default)]
    pub rho0: Option<Spanned<Vec<f64>>>,
    /// Initial phase of each master pair (default 0).
    #[serde(default)]
    pub theta0: Option<Spanned<Vec<f64>>>,
    /// Instead of `rho0`: given displacements `{ name = value }` (the others
    /// zero), projected onto the constraints; the reduced model starts from
    /// the nearest point of the SSM.
    #[serde(default)]
    pub x0: Option<Spanned<toml::Table>>,
    /// Given velocities `{ name_dot = value }`, with `x0`.
    #[serde(default)]
    pub v0: Option<Spanned<toml::Table>>,
    /// Final time of the transient.
    #[serde(default)]
    pub t_end: Option<Spanned<f64>>,
    /// Samples of the transient.
    #[serde(default = "default_samples")]
    pub samples: Spanned<usize>,
    /// Expansion order of the reduced model compared (default: `[ssm] order`).
    #[serde(default)]
    pub order: Option<Spanned<usize>>,
    /// Outputs compared (default: `[outputs] coordinates`); the first eight
    /// multipliers are added to `validation.csv`.
    #[serde(default)]
    pub outputs: Option<Spanned<Vec<String>>>,
    /// Relative tolerance of the full-system integrator.
    #[serde(default = "default_rtol")]
    pub rtol: Spanned<f64>,
    /// Absolute tolerance of the full-system integrator.
    #[serde(default = "default_atol")]
    pub atol: Spanned<f64>,
    /// Steady-state forced responses of the full system.
    #[serde(default)]
    pub steady_state: Option<SteadyStateSection>,
}

/// `[validate.steady_state]`: integration from rest until criterion (47) holds.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SteadyStateSection {
    /// Forcing amplitude (a number, or a list of one).
    #[serde(deserialize_with = "super::number_or_single")]
    pub epsilon: Spanned<f64>,
    /// Forcing frequencies (or `omega_range` and `points`).
    #[serde(default)]
    pub omega: Option<Spanned<Vec<f64>>>,
    /// `[Omega_min, Omega_max]`, sampled uniformly at `points` frequencies.
    #[serde(default)]
    pub omega_range: Option<Spanned<Vec<f64>>>,
    /// Number of frequencies in `omega_range`.
    #[serde(default = "default_points")]
    pub points: Spanned<usize>,
    /// Relative tolerance `delta` of criterion (47).
    #[serde(default = "default_delta")]
    pub delta: Spanned<f64>,
    /// Forcing periods at most.
    #[serde(default = "default_max_periods")]
    pub max_periods: Spanned<usize>,
    /// Output samples per period for the amplitudes.
    #[serde(default = "default_period_samples")]
    pub samples_per_period: Spanned<usize>,
    /// Largest multiple of the forcing period accepted as the response period
    /// (1: criterion (47) as published; 2 or more for subharmonic responses).
    #[serde(default = "default_multiple")]
    pub max_period_multiple: Spanned<usize>,
    /// Where each integration starts: `"rest"` (the unforced equilibrium,
    /// default) or `"ssm"` (the point `W(p0)` of the largest stable response
    /// the FRC predicts at that frequency, which reaches upper branches where
    /// the response is bistable).
    #[serde(default)]
    pub start: Option<Spanned<String>>,
}

impl ValidateSection {
    /// Given initial values `(state name, value)` of `x0` and `v0`.
    pub(crate) fn given_start(&self) -> Vec<(String, f64)> {
        super::given_values(
            [&self.x0, &self.v0]
                .into_iter()
                .flatten()
                .map(|t| t.get_ref()),
        )
    }
}

/// `[report]`: speed against error, one row per expansion order.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSection {
    /// Expansion orders (default: the odd orders up to `[ssm] order`).
    #[serde(default)]
    pub orders: Option<Spanned<Vec<usize>>>,
}

fn default_samples() -> Spanned<usize> {
    Spanned::new(0..0, ValidationTransientSpec::DEFAULT_SAMPLES)
}
fn default_rtol() -> Spanned<f64> {
    Spanned::new(0..0, ValidationSpec::DEFAULT_RTOL)
}
fn default_atol() -> Spanned<f64> {
    Spanned::new(0..0, ValidationSpec::DEFAULT_ATOL)
}
fn default_points() -> Spanned<usize> {
    Spanned::new(0..0, SteadyStateSpec::DEFAULT_POINTS)
}
fn default_delta() -> Spanned<f64> {
    Spanned::new(0..0, SteadyStateSpec::DEFAULT_DELTA)
}
fn default_max_periods() -> Spanned<usize> {
    Spanned::new(0..0, SteadyStateSpec::DEFAULT_MAX_PERIODS)
}
fn default_multiple() -> Spanned<usize> {
    Spanned::new(0..0, SteadyStateSpec::DEFAULT_MAX_PERIOD_MULTIPLE)
}
fn default_period_samples() -> Spanned<usize> {
    Spanned::new(0..0, SteadyStateSpec::DEFAULT_SAMPLES_PER_PERIOD)
}

impl SceneFile {
    /// `[validate]`'s shape: a start on the SSM or given values, not both,
    /// with `t_end`; given values that are numbers; the steady states'
    /// frequencies as `omega` or as `omega_range` and `points`; a known
    /// start.
    pub(super) fn check_validate(&self) -> Result<(), SceneError> {
        let Some(v) = &self.scene.validate else {
            return Ok(());
        };
        let given = v.x0.as_ref().or(v.v0.as_ref());
        if let (Some(r), Some(_)) = (&v.rho0, given) {
            return Err(self.invalid(
                r.span(),
                "validate.rho0",
                "give either rho0 (a start on the SSM) or x0/v0 (given displacements and velocities), not both".into(),
            ));
        }
        for (table, key) in [(&v.x0, "validate.x0"), (&v.v0, "validate.v0")] {
            if let Some(t) = table {
                if let Some((name, _)) = t.get_ref().iter().find(|(_, val)| {
                    !val.as_float()
                        .or(val.as_integer().map(|i| i as f64))
                        .is_some_and(f64::is_finite)
                }) {
                    return Err(self.invalid(
                        t.span(),
                        key,
                        format!("'{name}' must be a finite number"),
                    ));
                }
            }
        }
        match (v.rho0.as_ref().map(|r| r.span()).or(given.map(|g| g.span())), &v.t_end) {
            (Some(span), None) => {
                return Err(self.invalid(
                    span,
                    "validate.t_end",
                    "a transient validation needs t_end with rho0 or x0/v0".into(),
                ))
            }
            (None, Some(t)) => {
                return Err(self.invalid(
                    t.span(),
                    "validate.rho0",
                    "a transient validation needs rho0 (the start W(p0) on the SSM) or x0/v0 with t_end"
                        .into(),
                ))
            }
            _ => {}
        }
        match &v.steady_state {
            Some(s) => self.check_steady(s),
            None => Ok(()),
        }
    }

    fn check_steady(&self, s: &SteadyStateSection) -> Result<(), SceneError> {
        match (&s.omega, &s.omega_range) {
            (Some(_), None) => {}
            (None, Some(r)) => {
                let ok = r.get_ref().len() == 2
                    && r.get_ref().iter().all(|w| w.is_finite() && *w > 0.0)
                    && r.get_ref()[0] < r.get_ref()[1];
                if !ok {
                    return Err(self.invalid(
                        r.span(),
                        "validate.steady_state.omega_range",
                        "give [Omega_min, Omega_max] with 0 < Omega_min < Omega_max".into(),
                    ));
                }
                let points = *s.points.get_ref();
                if !(1..=ssm_core::spec::MAX_STEADY_STATES).contains(&points) {
                    return Err(self.invalid(
                        s.points.span(),
                        "validate.steady_state.points",
                        format!(
                            "must lie in 1..={}, found {points}",
                            ssm_core::spec::MAX_STEADY_STATES
                        ),
                    ));
                }
            }
            (Some(o), Some(_)) => {
                return Err(self.invalid(
                    o.span(),
                    "validate.steady_state.omega",
                    "give either omega or omega_range, not both".into(),
                ))
            }
            (None, None) => {
                return Err(self.invalid(
                    s.epsilon.span(),
                    "validate.steady_state",
                    "give the frequencies: omega = [...] or omega_range = [min, max] with points"
                        .into(),
                ))
            }
        }
        self.check_start(s.start.as_ref(), "validate.steady_state.start")
    }
}
