//! `[pod]`: POD with generalized constraint reduction of the `[model]`
//! (Stadlmayr, Witteveen & Steiner 2017) from a training run, one reduced
//! model per truncation, every reduced model run against the full one with
//! HHT on the training load and on the `[[pod.test]]` loads, optionally
//! beside SSM reduced models of the same model.

use serde::Deserialize;
use toml::Spanned;

use super::{SceneError, SceneFile};
use ssm_core::spec::PodSpec;

pub use ssm_core::spec::{MAX_POD_ROMS, MAX_POD_TESTS};

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
    /// Training tolerances of DEIM hyper-reductions of each POD model.
    #[serde(default)]
    pub hyper: Option<Spanned<Vec<f64>>>,
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

/// One run: a harmonic load `eps Fext(Omega t)` (or none), possibly
/// switched in steps, from rest or from given displacements and velocities.
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
    /// Load steps `[[t_k, a_k], ...]`: from `t_k` on the load is
    /// `a_k eps Fext`, before the first step none.
    #[serde(default)]
    pub steps: Vec<(f64, f64)>,
}

impl PodRun {
    /// Given initial values `(state name, value)` of `x0` and `v0`.
    pub(crate) fn given_start(&self) -> Vec<(String, f64)> {
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
    /// `[pod]`'s shape: it reduces the plugin model of `[model]` (no
    /// `[reduce]`), truncated by `energy` or by `drop`, not both.
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
        Ok(())
    }
}
