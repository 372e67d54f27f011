//! Where a model comes from: the plugin named by the scene, its parameter
//! table passed as TOML, and the plugin's errors mapped back to the scene's
//! lines.

use toml::Spanned;

use super::plugin::{Plugin, PluginLoadError, Registry};
use crate::scene::{ModelSection, SceneError, SceneFile};

/// Why a plugin's model could not be had.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// The scene names something the plugin does not have, or a bad parameter.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The plugin could not be loaded, or returned an error or panicked.
    #[error(transparent)]
    Plugin(#[from] PluginLoadError),
}

/// Builds the model of `[model]` with its plugin (as the plugin gives it).
pub fn build_model(
    scene: &SceneFile,
    m: &ModelSection,
    registry: &mut Registry,
) -> Result<(String, ssm_api::Model), SourceError> {
    let plugin = resolve(scene, registry, &m.plugin, "model.plugin")?;
    let name = m.name.as_ref().map_or("", |n| n.get_ref().as_str());
    let params = params_toml(scene, &m.params, "model.params")?;
    let model = plugin
        .build_model(name, &params)
        .map_err(|e| plugin_error(scene, e, "model.params"))?;
    Ok((plugin.name().to_owned(), model))
}

pub fn resolve(
    scene: &SceneFile,
    registry: &mut Registry,
    name: &Spanned<String>,
    key: &str,
) -> Result<Plugin, SourceError> {
    registry.resolve(name.get_ref()).map_err(|e| match e {
        PluginLoadError::NotFound { .. } => {
            SourceError::Scene(scene.invalid(name.span(), key, e.to_string()))
        }
        other => SourceError::Plugin(other),
    })
}

pub fn params_toml(
    scene: &SceneFile,
    table: &Spanned<toml::Table>,
    key: &str,
) -> Result<String, SourceError> {
    Ok(toml::to_string(table.get_ref()).map_err(|e| {
        scene.invalid(
            table.span(),
            key,
            format!("cannot pass the parameter table to the plugin: {e}"),
        )
    })?)
}

/// A plugin's [`ssm_api::ErrorKind::InvalidParameter`] becomes a scene error
/// at the parameter's line in the `[table]` it came from.
pub fn plugin_error(scene: &SceneFile, e: PluginLoadError, table: &str) -> SourceError {
    match e {
        PluginLoadError::Plugin { plugin, error }
            if error.kind == ssm_api::ErrorKind::InvalidParameter =>
        {
            let line = param_line(&scene.text, table, error.context.as_str());
            SourceError::Scene(SceneError::Invalid {
                path: scene.path.clone(),
                line,
                key: format!("{table}.{}", error.context),
                message: format!("plugin '{plugin}': {}", error.message),
            })
        }
        other => SourceError::Plugin(other),
    }
}

/// Line of `key = ...` inside the `[table]` (the table header's line when the
/// key is not found there).
fn param_line(text: &str, table: &str, key: &str) -> usize {
    let header_text = format!("[{table}]");
    let mut in_params = false;
    let mut header = 0;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            in_params = t == header_text;
            if in_params {
                header = i + 1;
            }
            continue;
        }
        if in_params {
            if let Some((k, _)) = t.split_once('=') {
                if k.trim().trim_matches('"') == key {
                    return i + 1;
                }
            }
        }
    }
    header
}
