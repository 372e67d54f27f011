//! `[reference]`: the full system's forced response by harmonic balance and
//! continuation ([`ssm_core::fom::periodic`]), the reference for the reduced
//! model's forced response curves.

use serde::Deserialize;
use toml::Spanned;

use super::{number_or_list, SceneError, SceneFile};
use ssm_core::spec::ReferenceSpec;

pub use ssm_core::spec::{MAX_HARMONICS, MAX_REFERENCE_CURVES, MAX_REFERENCE_STEPS};

/// Most Fourier coefficients `N (2H + 1)` of one orbit.
pub(crate) const MAX_REFERENCE_COEFFICIENTS: usize = 400_000;

/// `[reference]`: forced responses of the full system.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSection {
    /// Forcing amplitudes, one branch each (a number or a list).
    #[serde(deserialize_with = "number_or_list")]
    pub epsilon: Spanned<Vec<f64>>,
    /// `[Omega_min, Omega_max]` (default: `[forcing] omega_range`).
    #[serde(default)]
    pub omega_range: Option<Spanned<Vec<f64>>>,
    /// Harmonics `H` of the orbits.
    #[serde(default = "default_harmonics")]
    pub harmonics: Spanned<usize>,
    /// Largest arclength step (amplitudes scaled by the first orbit's,
    /// frequency by the range width).
    #[serde(default = "default_step")]
    pub step: Spanned<f64>,
    /// Newton tolerance (relative update).
    #[serde(default = "default_tol")]
    pub tol: Spanned<f64>,
    /// Most continuation steps per branch.
    #[serde(default = "default_max_steps")]
    pub max_steps: Spanned<usize>,
    /// Switch to the branch of period `2T` at each period doubling.
    #[serde(default = "default_period_doubling")]
    pub period_doubling: Spanned<bool>,
    /// Floquet multipliers of every orbit (stability, period doublings,
    /// Neimark-Sacker, branch points); `false` traces the curves alone.
    #[serde(default = "default_stability")]
    pub stability: Spanned<bool>,
    /// Outputs whose amplitudes are written (default: `[outputs] coordinates`).
    #[serde(default)]
    pub outputs: Option<Spanned<Vec<String>>>,
    /// `"rest"`: one branch from rest at `Omega_min`; `"ssm"` (the default
    /// with `[forcing]`): also a branch from the peak of each branch of the
    /// reduced model's FRC, lifted by `W`, that is not on one traced already.
    #[serde(default)]
    pub start: Option<Spanned<String>>,
    /// Frequencies at which the amplitude response (continuation in `eps`
    /// at fixed `Omega`) is also traced, one branch each.
    #[serde(default)]
    pub amplitude_at: Option<Spanned<Vec<f64>>>,
    /// `[eps_min, eps_max]` of the amplitude responses (default `[0, the
    /// largest epsilon]`).
    #[serde(default)]
    pub amplitude_range: Option<Spanned<Vec<f64>>>,
}

fn default_harmonics() -> Spanned<usize> {
    Spanned::new(0..0, ReferenceSpec::DEFAULT_HARMONICS)
}
fn default_step() -> Spanned<f64> {
    Spanned::new(0..0, ReferenceSpec::DEFAULT_STEP)
}
fn default_tol() -> Spanned<f64> {
    Spanned::new(0..0, ReferenceSpec::DEFAULT_TOL)
}
fn default_period_doubling() -> Spanned<bool> {
    Spanned::new(0..0, true)
}
fn default_stability() -> Spanned<bool> {
    Spanned::new(0..0, true)
}
fn default_max_steps() -> Spanned<usize> {
    Spanned::new(0..0, ReferenceSpec::DEFAULT_MAX_STEPS)
}

impl SceneFile {
    /// `[reference]`'s shape: ranges of two numbers, a non-empty
    /// `amplitude_at` when given, a known start.
    pub(super) fn check_reference(&self) -> Result<(), SceneError> {
        let Some(r) = &self.scene.reference else {
            return Ok(());
        };
        if let Some(o) = r.omega_range.as_ref().filter(|o| o.get_ref().len() != 2) {
            return Err(self.invalid(
                o.span(),
                "reference.omega_range",
                format!(
                    "give [Omega_min, Omega_max], found {} numbers",
                    o.get_ref().len()
                ),
            ));
        }
        if let Some(at) = r.amplitude_at.as_ref().filter(|a| a.get_ref().is_empty()) {
            return Err(self.invalid(
                at.span(),
                "reference.amplitude_at",
                format!(
                    "give 1 to {MAX_REFERENCE_CURVES} positive, finite forcing frequencies, found []"
                ),
            ));
        }
        if let Some(range) = r
            .amplitude_range
            .as_ref()
            .filter(|a| a.get_ref().len() != 2)
        {
            return Err(self.invalid(
                range.span(),
                "reference.amplitude_range",
                format!(
                    "give [eps_min, eps_max], found {} numbers",
                    range.get_ref().len()
                ),
            ));
        }
        self.check_start(r.start.as_ref(), "reference.start")
    }
}
