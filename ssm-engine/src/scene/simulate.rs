//! `[simulate]`: sampled full-system runs written as `[data]` CSV files, the
//! input of data-driven reducers (e.g. the NAR identifier).

use serde::Deserialize;
use ssm_kernel::number::short;
use toml::Spanned;

use super::{SceneError, SceneFile};
use ssm_core::spec::SimulateSpec;

/// Most samples per run (a CSV of this many rows is already ~100 MB per output).
pub const MAX_SAMPLES: usize = 2_000_000;

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
    pub fn given_start(&self) -> Vec<(String, f64)> {
        super::given_values([&self.x0, &self.v0].into_iter().flatten())
    }
}

impl SceneFile {
    pub(super) fn check_simulate(&self) -> Result<(), SceneError> {
        let Some(s) = &self.scene.simulate else {
            return Ok(());
        };
        self.check_positive(&s.period, "simulate.period")?;
        let n = *s.samples.get_ref();
        if !(2..=MAX_SAMPLES).contains(&n) {
            return Err(self.invalid(
                s.samples.span(),
                "simulate.samples",
                format!("must be 2 to {MAX_SAMPLES}, found {n}"),
            ));
        }
        let span = *s.period.get_ref() * (n - 1) as f64;
        if !span.is_finite() {
            return Err(self.invalid(
                s.period.span(),
                "simulate.period",
                format!("the runs would last {span} (period times samples - 1): not a time"),
            ));
        }
        let noise = *s.noise.get_ref();
        if !(noise.is_finite() && (0.0..=1.0).contains(&noise)) {
            return Err(self.invalid(
                s.noise.span(),
                "simulate.noise",
                format!("must lie in [0, 1] (relative to each output's largest value; 0.01 = 1 %), found {}", short(noise)),
            ));
        }
        for (tol, key) in [(&s.rtol, "simulate.rtol"), (&s.atol, "simulate.atol")] {
            self.check_positive(tol, key)?;
        }
        if let Some(alpha) = &s.hht_alpha {
            let a = *alpha.get_ref();
            if !(-1.0 / 3.0..=0.0).contains(&a) {
                return Err(self.invalid(
                    alpha.span(),
                    "simulate.hht_alpha",
                    format!(
                        "must lie in [-1/3, 0] (0: no numerical damping), found {}",
                        short(a)
                    ),
                ));
            }
        }
        if let Some(o) = &s.outputs {
            if o.get_ref().is_empty() {
                return Err(self.invalid(
                    o.span(),
                    "simulate.outputs",
                    "name at least one output, or leave the key out for [outputs] coordinates"
                        .into(),
                ));
            }
        }
        let runs = s.run.get_ref();
        if runs.is_empty() {
            return Err(self.invalid(
                s.run.span(),
                "simulate.run",
                "give at least one [[simulate.run]] with x0/v0 or rho0".into(),
            ));
        }
        let pairs = self.scene.ssm.master_pairs.get_ref().len();
        for (k, r) in runs.iter().enumerate() {
            let key = format!("simulate.run[{}]", k + 1);
            let given = r.x0.is_some() || r.v0.is_some();
            let bad = |m: String| self.invalid(s.run.span(), &key, m);
            match (&r.rho0, given) {
                (Some(_), true) => {
                    return Err(bad(
                        "give either rho0 (a start on the SSM) or x0/v0, not both".into(),
                    ))
                }
                (None, false) => {
                    return Err(bad(
                        "give x0/v0 (displacements, velocities) or rho0 (a start on the SSM)"
                            .into(),
                    ))
                }
                (Some(rho), false) => {
                    if rho.len() != pairs || rho.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                        return Err(bad(format!(
                            "rho0: give {pairs} non-negative amplitude(s), one per master pair"
                        )));
                    }
                    if let Some(th) = &r.theta0 {
                        if th.len() != pairs || th.iter().any(|t| !t.is_finite()) {
                            return Err(bad(format!("theta0: give {pairs} finite phase(s)")));
                        }
                    }
                }
                (None, true) => {
                    if r.theta0.is_some() {
                        return Err(bad("theta0 goes with rho0, not with x0/v0".into()));
                    }
                    if let Some((name, _)) =
                        r.given_start().into_iter().find(|(_, v)| !v.is_finite())
                    {
                        return Err(bad(format!("'{name}' must be a finite number")));
                    }
                }
            }
        }
        Ok(())
    }
}
