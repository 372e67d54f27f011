//! `[reference]`: the full system's forced response by harmonic balance and
//! continuation ([`ssm_core::fom::periodic`]), the reference for the reduced
//! model's forced response curves.

use serde::Deserialize;
use ssm_kernel::number::{list, short};
use toml::Spanned;

use super::{number_or_list, SceneError, SceneFile};
use ssm_core::spec::ReferenceSpec;

/// Most forcing amplitudes (one branch each).
pub const MAX_REFERENCE_CURVES: usize = 8;
/// Most harmonics.
pub const MAX_HARMONICS: usize = 64;
/// Most Fourier coefficients `N (2H + 1)` of one orbit.
pub const MAX_REFERENCE_COEFFICIENTS: usize = 400_000;
/// Most continuation steps of one branch.
pub const MAX_REFERENCE_STEPS: usize = 100_000;

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

impl ReferenceSection {
    /// The frequency range: this section's, else `[forcing]`'s.
    pub fn omega_range(&self, scene: &SceneFile) -> Option<(f64, f64)> {
        self.omega_range
            .as_ref()
            .map(|r| r.get_ref())
            .or(scene
                .scene
                .forcing
                .as_ref()
                .map(|f| f.omega_range.get_ref()))
            .and_then(|r| (r.len() == 2).then(|| (r[0], r[1])))
    }
}

impl SceneFile {
    pub(super) fn check_reference(&self) -> Result<(), SceneError> {
        let Some(r) = &self.scene.reference else {
            return Ok(());
        };
        let eps = r.epsilon.get_ref();
        if eps.is_empty()
            || eps.len() > MAX_REFERENCE_CURVES
            || eps.iter().any(|e| !(e.is_finite() && *e > 0.0))
        {
            return Err(self.invalid(
                r.epsilon.span(),
                "reference.epsilon",
                format!(
                    "give 1 to {MAX_REFERENCE_CURVES} positive, finite forcing amplitudes, found {eps:?}"
                ),
            ));
        }
        let span = r
            .omega_range
            .as_ref()
            .map_or(r.epsilon.span(), |o| o.span());
        match (
            r.omega_range.as_ref().map(|o| o.get_ref()),
            r.omega_range(self),
        ) {
            (Some(v), _) if v.len() != 2 => {
                return Err(self.invalid(
                    span,
                    "reference.omega_range",
                    format!("give [Omega_min, Omega_max], found {} numbers", v.len()),
                ))
            }
            (_, None) => {
                return Err(self.invalid(
                    span,
                    "reference.omega_range",
                    "give omega_range here or in [forcing]".into(),
                ))
            }
            (_, Some((lo, hi))) if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) => {
                return Err(self.invalid(
                    span,
                    "reference.omega_range",
                    format!(
                        "must be positive, finite and increasing, found {}",
                        list(&[lo, hi])
                    ),
                ))
            }
            _ => {}
        }
        let h = *r.harmonics.get_ref();
        if !(1..=MAX_HARMONICS).contains(&h) {
            return Err(self.invalid(
                r.harmonics.span(),
                "reference.harmonics",
                format!("must lie in 1..={MAX_HARMONICS}, found {h}"),
            ));
        }
        let step = *r.step.get_ref();
        if !(step.is_finite() && (1e-4..=10.0).contains(&step)) {
            return Err(self.invalid(
                r.step.span(),
                "reference.step",
                format!("must lie in [1e-4, 10] (scaled arclength; 0.5 crosses a resonance peak in about 100 steps), found {}", short(step)),
            ));
        }
        let tol = *r.tol.get_ref();
        if !(tol.is_finite() && (1e-14..=1e-3).contains(&tol)) {
            return Err(self.invalid(
                r.tol.span(),
                "reference.tol",
                format!("must lie in [1e-14, 1e-3], found {}", short(tol)),
            ));
        }
        if let Some(st) = &r.start {
            match st.get_ref().as_str() {
                "rest" => {}
                "ssm" if self.scene.forcing.is_some() => {}
                "ssm" => {
                    return Err(self.invalid(
                        st.span(),
                        "reference.start",
                        "start = \"ssm\" starts from the reduced model's forced response: add [forcing]".into(),
                    ))
                }
                other => {
                    return Err(self.invalid(
                        st.span(),
                        "reference.start",
                        format!("unknown start \"{other}\"; expected \"rest\" or \"ssm\""),
                    ))
                }
            }
        }
        self.check_amplitude_responses(r)?;
        let steps = *r.max_steps.get_ref();
        if !(1..=MAX_REFERENCE_STEPS).contains(&steps) {
            return Err(self.invalid(
                r.max_steps.span(),
                "reference.max_steps",
                format!("must lie in 1..={MAX_REFERENCE_STEPS}, found {steps}"),
            ));
        }
        Ok(())
    }

    /// `amplitude_at` and `amplitude_range`.
    fn check_amplitude_responses(&self, r: &ReferenceSection) -> Result<(), SceneError> {
        if let Some(at) = &r.amplitude_at {
            let w = at.get_ref();
            if w.is_empty()
                || w.len() > MAX_REFERENCE_CURVES
                || w.iter().any(|v| !(v.is_finite() && *v > 0.0))
            {
                return Err(self.invalid(
                    at.span(),
                    "reference.amplitude_at",
                    format!(
                        "give 1 to {MAX_REFERENCE_CURVES} positive, finite forcing frequencies, found {w:?}"
                    ),
                ));
            }
        }
        if let Some(range) = &r.amplitude_range {
            let v = range.get_ref();
            let message = if r.amplitude_at.is_none() {
                Some("traces the amplitude responses of amplitude_at: give the frequencies in amplitude_at".to_owned())
            } else if v.len() != 2 {
                Some(format!(
                    "give [eps_min, eps_max], found {} numbers",
                    v.len()
                ))
            } else if !(v[0].is_finite() && v[1].is_finite() && v[0] >= 0.0 && v[1] > v[0]) {
                Some(format!(
                    "must be finite, non-negative and increasing, found {}",
                    list(&v[..2])
                ))
            } else {
                None
            };
            if let Some(m) = message {
                return Err(self.invalid(range.span(), "reference.amplitude_range", m));
            }
        }
        Ok(())
    }
}
