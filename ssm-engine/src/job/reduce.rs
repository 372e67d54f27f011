//! A scene's `[reduce]`: the reducer found in its plugin, its needs checked
//! against the scene, its input assembled from `[model]` and `[data]`, and
//! the reduced model validated with its outputs lifted.

use super::source::{params_toml, plugin_error, resolve, SourceError};
use super::ReduceError;
use crate::scene::{ReduceSection, SceneFile};
use ssm_core::model::plugin::{PluginLoadError, Registry};
use ssm_core::model::system::System;
use ssm_core::reduce::{lift_outputs, read_signals, Reduction};

/// The model the reducer of `[reduce]` makes from the full model `full`
/// (plugin name and model of `[model]`, if any) and/or the `[data]` signals,
/// validated into a [`System`].
pub(crate) fn reduce_scene(
    scene: &SceneFile,
    red: &ReduceSection,
    full: Option<(String, ssm_api::Model)>,
    registry: &mut Registry,
) -> Result<(System, Reduction), ReduceError> {
    let sc = &scene.scene;
    let Some(plugin_key) = &red.plugin else {
        return super::pod_reducer::engine_reduce(scene, red, full);
    };
    let plugin = resolve(scene, registry, plugin_key, "reduce.plugin")?;
    let listed = match plugin.reducers() {
        None => {
            return Err(scene
                .invalid(
                    plugin_key.span(),
                    "reduce.plugin",
                    PluginLoadError::NoReducers {
                        plugin: plugin.name().to_owned(),
                    }
                    .to_string(),
                )
                .into());
        }
        Some(list) => list.map_err(SourceError::Plugin)?,
    };
    let wanted = red.reducer.get_ref();
    let info = listed
        .iter()
        .find(|r| r.name.as_str() == wanted)
        .ok_or_else(|| {
            let names: Vec<&str> = listed.iter().map(|r| r.name.as_str()).collect();
            scene.invalid(
                red.reducer.span(),
                "reduce.reducer",
                format!(
                    "plugin '{}' has no reducer '{wanted}'; it offers: {}",
                    plugin.name(),
                    if names.is_empty() {
                        "none".to_owned()
                    } else {
                        names.join(", ")
                    }
                ),
            )
        })?;
    if info.needs.model() && full.is_none() {
        return Err(scene
            .invalid(
                red.reducer.span(),
                "reduce.reducer",
                format!("reducer '{wanted}' needs a model: add a [model] section"),
            )
            .into());
    }
    if info.needs.signals() && sc.data.is_none() {
        return Err(scene
            .invalid(
                red.reducer.span(),
                "reduce.reducer",
                format!("reducer '{wanted}' needs sampled signals: add a [data] section"),
            )
            .into());
    }
    let signals = sc
        .data
        .as_ref()
        .map(|d| {
            let files: Vec<_> = d
                .files
                .get_ref()
                .iter()
                .map(|f| scene.relative(f))
                .collect();
            read_signals(&files, d.columns.as_ref().map(|c| c.get_ref().as_slice()))
        })
        .transpose()?;
    let n_trajectories = signals.as_ref().map_or(0, |s| s.trajectories.len());
    let (full_plugin, full_model) = full.unzip();
    let input = ssm_api::ReducerInput {
        model: full_model.into(),
        signals: signals.into(),
    };
    let params = params_toml(scene, &red.params, "reduce.params")?;
    let reduced = plugin
        .reduce(wanted, &params, &input)
        .map_err(|e| plugin_error(scene, e, "reduce.params"))?;
    let mut model = reduced.model;
    let lift = reduced.lift.into_option();
    let lifted_outputs = match (&lift, input.model.as_ref().into_option()) {
        (Some(l), Some(full)) => lift_outputs(&mut model, full, l),
        _ => Vec::new(),
    };
    let origin = match full_plugin {
        Some(p) => format!("{} via {}", p, plugin.name()),
        None => plugin.name().to_owned(),
    };
    let system = System::from_model(&origin, model)?;
    let reduction = Reduction {
        plugin: plugin.name().to_owned(),
        reducer: wanted.clone(),
        n_input_states: input.model.as_ref().into_option().map(|m| m.n_states()),
        n_trajectories,
        n_reduced_states: system.n_states(),
        lift,
        diagnostics: reduced.diagnostics.into_iter().collect(),
        lifted_outputs,
        signals: input.signals.into_option(),
    };
    Ok((system, reduction))
}
