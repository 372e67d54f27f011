//! `[pod]`: POD with generalized constraint reduction of the `[model]`
//! (Stadlmayr, Witteveen & Steiner 2017) from a training run, one reduced
//! model per truncation, every reduced model run against the full one with
//! HHT on the training load and on the `[[pod.test]]` loads, optionally
//! beside SSM reduced models of the same model.

use serde::Deserialize;
use ssm_kernel::number::short;
use toml::Spanned;

use super::{SceneError, SceneFile, AUTO_MAX_ORDER};
use ssm_core::spec::PodSpec;

/// Most reduced models (truncations plus SSM pair sets).
pub const MAX_POD_ROMS: usize = 16;
/// Most test runs.
pub const MAX_POD_TESTS: usize = 32;

pub use ssm_core::fom::hht::{load_sampling, MIN_STEPS_PER_PERIOD};

/// `[pod]`: the reducer's settings, the runs, the models compared.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PodSection {
    /// Energy fractions left out by the truncation, one reduced model each.
    #[serde(default)]
    pub energy: Option<Spanned<Vec<f64>>>,
    /// Drops of the normalized POVs in decades, one reduced model each
    /// (default: one model at 6 decades when `energy` is not given).
    #[serde(default)]
    pub drop: Option<Spanned<Vec<f64>>>,
    /// Singular values of the stacked projected constraint Jacobian below
    /// this fraction of the largest are removed.
    #[serde(default = "default_rank_tol")]
    pub rank_tol: Spanned<f64>,
    /// Snapshots at which `C_q(q) U` is stacked.
    #[serde(default = "default_jacobian_samples")]
    pub jacobian_samples: Spanned<usize>,
    /// Fixed HHT step of every run.
    pub step: Spanned<f64>,
    /// HHT `alpha` in `[-1/3, 0]`.
    #[serde(default = "default_alpha")]
    pub hht_alpha: Spanned<f64>,
    /// Outputs compared (default: `[outputs] coordinates`).
    #[serde(default)]
    pub outputs: Option<Spanned<Vec<String>>>,
    /// Master pair sets of SSM reduced models run on the same loads.
    #[serde(default)]
    pub ssm_pairs: Option<Spanned<Vec<Vec<usize>>>>,
    /// Expansion order of the SSM reduced models (default: `[ssm] order`, else 5).
    #[serde(default)]
    pub ssm_order: Option<Spanned<usize>>,
    /// The training run of the full model.
    pub train: Spanned<PodRun>,
    /// Loads the reduced models were not trained on.
    #[serde(default = "no_tests")]
    pub test: Spanned<Vec<PodRun>>,
}

/// One run: a harmonic load `eps Fext(Omega t)` (or none) from rest or
/// from given displacements and velocities.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PodRun {
    /// Forcing amplitude (0: a free run).
    #[serde(default)]
    pub epsilon: f64,
    /// Forcing frequency.
    #[serde(default = "no_frequency")]
    pub omega: Spanned<f64>,
    /// Length of the run.
    pub t_end: f64,
    /// Given displacements (the others zero), projected onto the constraints.
    #[serde(default)]
    pub x0: Option<toml::Table>,
    /// Given velocities.
    #[serde(default)]
    pub v0: Option<toml::Table>,
}

impl PodRun {
    /// Given initial values `(state name, value)` of `x0` and `v0`.
    pub fn given_start(&self) -> Vec<(String, f64)> {
        super::given_values([&self.x0, &self.v0].into_iter().flatten())
    }
}

fn default_rank_tol() -> Spanned<f64> {
    Spanned::new(0..0, PodSpec::DEFAULT_RANK_TOL)
}
fn default_jacobian_samples() -> Spanned<usize> {
    Spanned::new(0..0, PodSpec::DEFAULT_JACOBIAN_SAMPLES)
}
fn default_alpha() -> Spanned<f64> {
    Spanned::new(0..0, PodSpec::DEFAULT_HHT_ALPHA)
}
fn no_frequency() -> Spanned<f64> {
    Spanned::new(0..0, 0.0)
}
fn no_tests() -> Spanned<Vec<PodRun>> {
    Spanned::new(0..0, Vec::new())
}

impl SceneFile {
    pub(super) fn check_pod(&self) -> Result<(), SceneError> {
        let Some(p) = &self.scene.pod else {
            return Ok(());
        };
        if self.scene.model.is_none() || self.scene.reduce.is_some() {
            return Err(self.invalid(
                p.step.span(),
                "pod",
                "[pod] reduces the plugin model of [model]: give a [model] section and no [reduce]"
                    .into(),
            ));
        }
        if p.energy.is_some() && p.drop.is_some() {
            return Err(self.invalid(
                p.step.span(),
                "pod",
                "give either energy (fractions left out) or drop (decades), not both".into(),
            ));
        }
        let n_pod = if let Some(e) = &p.energy {
            let v = e.get_ref();
            if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x > 0.0 && *x < 1.0)) {
                return Err(self.invalid(
                    e.span(),
                    "pod.energy",
                    format!("give fractions in (0, 1) (1e-4: the POMs keep all but 0.01 % of the POVs' sum), found {v:?}"),
                ));
            }
            v.len()
        } else if let Some(d) = &p.drop {
            let v = d.get_ref();
            if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x > 0.0 && *x <= 16.0)) {
                return Err(self.invalid(
                    d.span(),
                    "pod.drop",
                    format!("give drops in decades in (0, 16], found {v:?}"),
                ));
            }
            v.len()
        } else {
            1
        };
        let tol = *p.rank_tol.get_ref();
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(self.invalid(
                p.rank_tol.span(),
                "pod.rank_tol",
                format!(
                    "must lie in (0, 1) (relative to the largest singular value), found {}",
                    short(tol)
                ),
            ));
        }
        let js = *p.jacobian_samples.get_ref();
        if !(1..=10_000).contains(&js) {
            return Err(self.invalid(
                p.jacobian_samples.span(),
                "pod.jacobian_samples",
                format!("must be 1 to 10000, found {js}"),
            ));
        }
        self.check_positive(&p.step, "pod.step")?;
        let a = *p.hht_alpha.get_ref();
        if !(-1.0 / 3.0..=0.0).contains(&a) {
            return Err(self.invalid(
                p.hht_alpha.span(),
                "pod.hht_alpha",
                format!(
                    "must lie in [-1/3, 0] (0: no numerical damping), found {}",
                    short(a)
                ),
            ));
        }
        if let Some(o) = &p.outputs {
            if o.get_ref().is_empty() {
                return Err(self.invalid(
                    o.span(),
                    "pod.outputs",
                    "name at least one output, or leave the key out for [outputs] coordinates"
                        .into(),
                ));
            }
        }
        let n_ssm = if let Some(sets) = &p.ssm_pairs {
            for set in sets.get_ref() {
                let mut s = set.clone();
                s.sort_unstable();
                s.dedup();
                if s.is_empty() || s.len() != set.len() || s[0] == 0 {
                    return Err(self.invalid(
                        sets.span(),
                        "pod.ssm_pairs",
                        format!(
                            "each set lists 1-based master pairs without repeats, found {set:?}"
                        ),
                    ));
                }
            }
            sets.get_ref().len()
        } else {
            0
        };
        if n_pod + n_ssm > MAX_POD_ROMS {
            return Err(self.invalid(
                p.step.span(),
                "pod",
                format!(
                    "{} reduced models asked for; at most {MAX_POD_ROMS}",
                    n_pod + n_ssm
                ),
            ));
        }
        if let Some(o) = &p.ssm_order {
            let k = *o.get_ref();
            if !(1..=AUTO_MAX_ORDER).contains(&k) {
                return Err(self.invalid(
                    o.span(),
                    "pod.ssm_order",
                    format!("must be 1 to {AUTO_MAX_ORDER}, found {k}"),
                ));
            }
        }
        if p.test.get_ref().len() > MAX_POD_TESTS {
            return Err(self.invalid(
                p.test.span(),
                "pod.test",
                format!("at most {MAX_POD_TESTS} test runs"),
            ));
        }
        let step = *p.step.get_ref();
        let runs = std::iter::once(("pod.train".to_owned(), p.train.span(), p.train.get_ref()))
            .chain(
                p.test
                    .get_ref()
                    .iter()
                    .enumerate()
                    .map(|(k, r)| (format!("pod.test[{}]", k + 1), p.test.span(), r)),
            );
        for (key, span, r) in runs {
            let bad = |m: String| self.invalid(span.clone(), &key, m);
            if !(r.t_end.is_finite() && r.t_end > 0.0) {
                return Err(bad(format!(
                    "t_end must be positive, found {}",
                    short(r.t_end)
                )));
            }
            if !r.epsilon.is_finite() {
                return Err(bad(format!(
                    "epsilon must be a finite number, found {}",
                    short(r.epsilon)
                )));
            }
            let omega = *r.omega.get_ref();
            if !(omega.is_finite() && omega >= 0.0) {
                return Err(bad(format!(
                    "omega must be a non-negative frequency, found {}",
                    short(omega)
                )));
            }
            if let Err(m) = load_sampling(step, omega) {
                return Err(self.invalid(r.omega.span(), &format!("{key}.omega"), m));
            }
            if let Some((name, _)) = r.given_start().into_iter().find(|(_, v)| !v.is_finite()) {
                return Err(bad(format!("'{name}' must be a finite number")));
            }
        }
        Ok(())
    }
}
