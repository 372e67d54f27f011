//! `[simulate]`: sampled full-system runs written as `[data]` CSV files, the
//! input of data-driven reducers (e.g. the NAR identifier).

use serde::Deserialize;
use toml::Spanned;

use super::{SceneError, SceneFile};
use ssm_core::spec::SimulateSpec;

/// `[simulate]`: the full model integrated from given starts and sampled
/// uniformly; each run becomes `simulation_<k>.csv` (header `t,<outputs>`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulateSection {
    /// Sampling period `T`.
    pub period: Spanned<f64>,
    /// Samples per run, at `t = 0, T, ..., (samples - 1) T`.
    pub samples: Spanned<usize>,
    /// Outputs sampled (default: `[outputs] coordinates`).
    #[serde(default)]
    pub outputs: Option<Spanned<Vec<String>>>,
    /// Additive Gaussian noise: standard deviation `noise * max |y|` of each
    /// output over its run (0: none).
    #[serde(default = "zero")]
    pub noise: Spanned<f64>,
    /// Seed of the noise (runs and outputs draw from one stream in order).
    #[serde(default = "one")]
    pub seed: Spanned<u64>,
    /// Relative tolerance of the integrator.
    #[serde(default = "default_rtol")]
    pub rtol: Spanned<f64>,
    /// Absolute tolerance of the integrator.
    #[serde(default = "default_atol")]
    pub atol: Spanned<f64>,
    /// Integrate with HHT-alpha at this `alpha` (in `[-1/3, 0]`; `rtol` and
    /// `atol` then control its positions' local error) instead of Radau.
    #[serde(default)]
    pub hht_alpha: Option<Spanned<f64>>,
    /// The runs, one file each.
    pub run: Spanned<Vec<SimulateRun>>,
}

/// One run's start: given displacements/velocities, or a point on the SSM.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulateRun {
    /// Given displacements `{ name = value }` (the others zero), projected
    /// onto the constraints.
    #[serde(default)]
    pub x0: Option<toml::Table>,
    /// Given velocities `{ name_dot = value }`.
    #[serde(default)]
    pub v0: Option<toml::Table>,
    /// Instead of `x0`/`v0`: the start `W(p0)` on the SSM, one amplitude per master pair.
    #[serde(default)]
    pub rho0: Option<Vec<f64>>,
    /// Phases with `rho0` (default 0).
    #[serde(default)]
    pub theta0: Option<Vec<f64>>,
}

fn zero() -> Spanned<f64> {
    Spanned::new(0..0, 0.0)
}
fn one() -> Spanned<u64> {
    Spanned::new(0..0, 1)
}
fn default_rtol() -> Spanned<f64> {
    Spanned::new(0..0, SimulateSpec::DEFAULT_RTOL)
}
fn default_atol() -> Spanned<f64> {
    Spanned::new(0..0, SimulateSpec::DEFAULT_ATOL)
}

impl SimulateRun {
    /// Given initial values `(state name, value)` of `x0` and `v0`.
    pub(crate) fn given_start(&self) -> Vec<(String, f64)> {
        super::given_values([&self.x0, &self.v0].into_iter().flatten())
    }
}

impl SceneFile {
    /// `[[simulate.run]]`'s shape: each run starts on the SSM (`rho0`,
    /// `theta0`) or at given values (`x0`, `v0`), not both, with `theta0`
    /// only beside `rho0`.
    pub(super) fn check_simulate(&self) -> Result<(), SceneError> {
        let Some(s) = &self.scene.simulate else {
            return Ok(());
        };
        for (k, r) in s.run.get_ref().iter().enumerate() {
            let key = format!("simulate.run[{}]", k + 1);
            let given = r.x0.is_some() || r.v0.is_some();
            let problem = match (&r.rho0, given) {
                (Some(_), true) => Some("give either rho0 (a start on the SSM) or x0/v0, not both"),
                (None, false) => {
                    Some("give x0/v0 (displacements, velocities) or rho0 (a start on the SSM)")
                }
                (None, true) if r.theta0.is_some() => Some("theta0 goes with rho0, not with x0/v0"),
                _ => None,
            };
            if let Some(m) = problem {
                return Err(self.invalid(self.locate(&key), &key, m.into()));
            }
        }
        Ok(())
    }
}
