//! The engine's own reducers, named in `[reduce]` without a plugin: `pod`,
//! the POD reduction with generalized constraint reduction
//! ([`ssm_core::reduce::pod_model`]) of the `[model]` from an HHT training run, whose
//! reduced model the analyses then run on (e.g. its SSM).

use serde::Deserialize;
use ssm_api::Diagnostic;

use super::ReduceError;
use crate::plan::budget::{check_pod_reducer, Limits};
use crate::scene::{load_sampling, ReduceSection, SceneFile};
use ssm_core::fom::hht::{integrate, HhtOptions};
use ssm_core::fom::{given_start, DaeProblem};
use ssm_core::model::system::System;
use ssm_core::reduce::pod::Truncation;
use ssm_core::reduce::pod_model::{pod_reduce, PodSettings};
use ssm_core::reduce::{lift_outputs, Reduction};
use ssm_kernel::number::short;

/// The reducers the engine offers itself.
pub(crate) const ENGINE_REDUCERS: [&str; 1] = ["pod"];

/// `[reduce.params]` of the engine's `pod`: the training run and the
/// reducer's settings.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct PodParams {
    /// Fixed HHT step of the training run.
    step: f64,
    /// Length of the training run.
    t_end: f64,
    #[serde(default)]
    epsilon: f64,
    #[serde(default)]
    omega: f64,
    #[serde(default = "default_alpha")]
    hht_alpha: f64,
    #[serde(default)]
    energy: Option<f64>,
    #[serde(default)]
    drop: Option<f64>,
    #[serde(default = "default_rank_tol")]
    rank_tol: f64,
    #[serde(default = "default_samples")]
    jacobian_samples: usize,
    #[serde(default)]
    x0: Option<toml::Table>,
    #[serde(default)]
    v0: Option<toml::Table>,
}

fn default_alpha() -> f64 {
    -0.1
}
fn default_rank_tol() -> f64 {
    1e-8
}
fn default_samples() -> usize {
    64
}

impl PodParams {
    /// The first problem with the parameters, if any.
    fn problem(&self) -> Option<String> {
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(self.step) || !positive(self.t_end) {
            return Some(format!(
                "step and t_end must be positive, found {} and {}",
                short(self.step),
                short(self.t_end)
            ));
        }
        if !(self.epsilon.is_finite() && self.omega.is_finite() && self.omega >= 0.0) {
            return Some(format!(
                "epsilon must be finite and omega a non-negative frequency, found {} and {}",
                short(self.epsilon),
                short(self.omega)
            ));
        }
        if let Err(m) = load_sampling(self.step, self.omega) {
            return Some(m);
        }
        if !(-1.0 / 3.0..=0.0).contains(&self.hht_alpha) {
            return Some(format!(
                "hht_alpha must lie in [-1/3, 0], found {}",
                short(self.hht_alpha)
            ));
        }
        match (self.energy, self.drop) {
            (Some(_), Some(_)) => return Some("give energy or drop, not both".into()),
            (Some(e), None) if !(e.is_finite() && e > 0.0 && e < 1.0) => {
                return Some(format!("energy must lie in (0, 1), found {}", short(e)))
            }
            (None, Some(d)) if !(d.is_finite() && d > 0.0 && d <= 16.0) => {
                return Some(format!(
                    "drop must lie in (0, 16] decades, found {}",
                    short(d)
                ))
            }
            _ => {}
        }
        if !(self.rank_tol.is_finite() && self.rank_tol > 0.0 && self.rank_tol < 1.0) {
            return Some(format!(
                "rank_tol must lie in (0, 1), found {}",
                short(self.rank_tol)
            ));
        }
        if !(1..=10_000).contains(&self.jacobian_samples) {
            return Some(format!(
                "jacobian_samples must be 1 to 10000, found {}",
                self.jacobian_samples
            ));
        }
        None
    }
}

/// The model the engine's reducer `red.reducer` makes from `full` (plugin
/// name and model of `[model]`).
pub(crate) fn engine_reduce(
    scene: &SceneFile,
    red: &ReduceSection,
    full: Option<(String, ssm_api::Model)>,
) -> Result<(System, Reduction), ReduceError> {
    let wanted = red.reducer.get_ref();
    let bad = |key: &str, span: std::ops::Range<usize>, m: String| -> ReduceError {
        scene.invalid(span, key, m).into()
    };
    if !ENGINE_REDUCERS.contains(&wanted.as_str()) {
        return Err(bad(
            "reduce.reducer",
            red.reducer.span(),
            format!(
                "the engine has no reducer '{wanted}' (it offers: {}); a plugin's reducer needs reduce.plugin",
                ENGINE_REDUCERS.join(", ")
            ),
        ));
    }
    let Some((plugin, model)) = full else {
        return Err(bad(
            "reduce.reducer",
            red.reducer.span(),
            "reducer 'pod' needs a model: add a [model] section".into(),
        ));
    };
    let params: PodParams =
        red.params
            .get_ref()
            .clone()
            .try_into()
            .map_err(|e: toml::de::Error| {
                bad("reduce.params", red.params.span(), e.message().to_owned())
            })?;
    if let Some(m) = params.problem() {
        return Err(bad("reduce.params", red.params.span(), m));
    }
    let sys = System::from_model(&plugin, model.clone())?;
    check_pod_reducer(
        &sys,
        (params.step, params.t_end, params.jacobian_samples),
        &Limits::of_machine(),
    )
    .map_err(|e| e.in_scene(scene))?;
    let start = crate::scene::given_values([&params.x0, &params.v0].into_iter().flatten());
    if let Some((name, _)) = start
        .iter()
        .find(|(n, v)| !v.is_finite() || !sys.states.iter().any(|s| s.name.as_str() == n))
    {
        return Err(bad(
            "reduce.params",
            red.params.span(),
            format!(
                "x0/v0: '{name}' is not a state of '{}' with a finite value",
                sys.name
            ),
        ));
    }
    let training = |e: String| {
        bad(
            "reduce.params",
            red.params.span(),
            format!("training run: {e}"),
        )
    };
    let p = DaeProblem::new(&sys, params.epsilon, params.omega);
    let z0 = given_start(&p, &start).map_err(|e| training(e.to_string()))?;
    let run = integrate(
        &p,
        &z0,
        0.0,
        params.t_end,
        &HhtOptions::new(params.hht_alpha, params.step),
    )
    .map_err(|e| training(e.to_string()))?;
    let settings = PodSettings {
        truncation: match (params.energy, params.drop) {
            (Some(fraction), _) => Truncation::Energy { fraction },
            (None, d) => Truncation::Drop {
                decades: d.unwrap_or(6.0),
            },
        },
        rank_tol: params.rank_tol,
        jacobian_samples: params.jacobian_samples,
    };
    let reduced = pod_reduce(&model, &sys, &run.states, &settings)
        .map_err(|e| bad("reduce.params", red.params.span(), e.to_string()))?;
    let mut reduced_model = reduced.model;
    let lifted_outputs = lift_outputs(&mut reduced_model, &model, &reduced.lift);
    let system = System::from_model(&format!("{plugin} via pod"), reduced_model)?;
    let c = &reduced.constraints;
    let mut diagnostics: Vec<Diagnostic> = reduced
        .kinds
        .iter()
        .map(|k| {
            Diagnostic::values(
                &format!("povs_{:?}", k.motion).to_lowercase(),
                &k.basis.values,
            )
        })
        .collect();
    if let Ok(Some(w)) = load_sampling(params.step, params.omega) {
        diagnostics.push(Diagnostic::text(
            "warning_sampling",
            &format!("training run: {w}"),
        ));
    }
    diagnostics.extend([
        Diagnostic::values("reduced_coordinates", &[reduced.u.ncols() as f64]),
        Diagnostic::values("constraints_removed", &[c.removed() as f64]),
        Diagnostic::values("constraint_singular_values", &c.singular_values),
        Diagnostic::values("initial_residual", &reduced.initial_residual),
    ]);
    let reduction = Reduction {
        plugin: "engine".into(),
        reducer: wanted.clone(),
        n_input_states: Some(model.n_states()),
        n_trajectories: 0,
        n_reduced_states: system.n_states(),
        lift: Some(reduced.lift),
        diagnostics,
        lifted_outputs,
        signals: None,
    };
    Ok((system, reduction))
}
