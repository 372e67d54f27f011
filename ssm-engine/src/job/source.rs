//! Where a model comes from: the plugin named by the scene, its parameter
//! table passed as TOML, and the plugin's errors mapped back to the scene's
//! lines.

use std::path::{Path, PathBuf};

use toml::Spanned;

use crate::scene::{line_of, ModelSection, SceneError, SceneFile};
use ssm_core::model::plugin::{is_path, Plugin, PluginLoadError, Registry};

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
    let params = model_params_toml(scene, &plugin, name, &m.params)?;
    let model = plugin
        .build_model(name, &params)
        .map_err(|e| plugin_error(scene, e, "model.params"))?;
    Ok((plugin.name().to_owned(), model))
}

/// The files and folders a run of `scene` reads, as far as they can be
/// named before it runs: the scene itself, its `[data]` files, the path
/// parameters of its `[model]` (a model folder, read from the scene's
/// folder) and every plugin library loaded. A plugin that cannot be had
/// adds nothing here (the run reports it).
pub fn scene_inputs(scene: &SceneFile, registry: &mut Registry) -> Vec<PathBuf> {
    let sc = &scene.scene;
    let mut inputs = vec![scene.path.clone()];
    if let Some(data) = &sc.data {
        inputs.extend(data.files.get_ref().iter().map(|f| scene.relative(f)));
    }
    if let Some(m) = &sc.model {
        if let Ok(plugin) = resolve(scene, registry, &m.plugin, "model.plugin") {
            let name = m.name.as_ref().map_or("", |n| n.get_ref().as_str());
            if let Ok(keys) = path_keys(&plugin, name) {
                inputs.extend(keys.iter().filter_map(|k| match m.params.get_ref().get(k) {
                    Some(toml::Value::String(s)) if !s.is_empty() => Some(scene.relative(s)),
                    _ => None,
                }));
            }
        }
    }
    if let Some(p) = sc.reduce.as_ref().and_then(|r| r.plugin.as_ref()) {
        let _ = resolve(scene, registry, p, "reduce.plugin");
    }
    inputs.extend(registry.plugins.iter().map(|(p, _)| p.clone()));
    inputs
}

/// The parameters of the model `name` of `plugin` (its first when empty)
/// that are paths ([`ssm_api::PATH_KIND`]).
fn path_keys(plugin: &Plugin, name: &str) -> Result<Vec<String>, SourceError> {
    let models = plugin.models()?;
    let listed = if name.is_empty() {
        models.first()
    } else {
        models.iter().find(|m| m.name.as_str() == name)
    };
    Ok(listed.map_or_else(Vec::new, |m| {
        m.params
            .iter()
            .filter(|p| p.kind.as_str() == ssm_api::PATH_KIND)
            .map(|p| p.name.to_string())
            .collect()
    }))
}

/// The plugin a scene key names: a plugin name, or a library path, which when
/// relative is read from the scene's folder (as every other path of a scene).
pub fn resolve(
    scene: &SceneFile,
    registry: &mut Registry,
    name: &Spanned<String>,
    key: &str,
) -> Result<Plugin, SourceError> {
    let raw = name.get_ref();
    let target = match scene.path.parent() {
        Some(dir) if is_path(raw) && Path::new(raw).is_relative() => {
            dir.join(raw).to_string_lossy().into_owned()
        }
        _ => raw.clone(),
    };
    registry.resolve(&target).map_err(|e| match e {
        PluginLoadError::NotFound { .. } => {
            SourceError::Scene(scene.invalid(name.span(), key, e.to_string()))
        }
        PluginLoadError::Missing { path } => SourceError::Scene(scene.invalid(
            name.span(),
            key,
            format!(
                "plugin file {} does not exist (a relative path is read from the scene's folder)",
                path.display()
            ),
        )),
        other => SourceError::Plugin(other),
    })
}

/// The TOML text of `[model.params]` with every parameter the model lists as a
/// path ([`ssm_api::PATH_KIND`]) read from the scene's folder when relative, so
/// a scene and its model files move together.
fn model_params_toml(
    scene: &SceneFile,
    plugin: &Plugin,
    name: &str,
    table: &Spanned<toml::Table>,
) -> Result<String, SourceError> {
    let paths = path_keys(plugin, name)?;
    let dir = scene.path.parent().unwrap_or(Path::new(""));
    let mut resolved = table.clone();
    for key in &paths {
        if let Some(toml::Value::String(s)) = resolved.get_mut().get_mut(key) {
            if !s.is_empty() && Path::new(s.as_str()).is_relative() {
                *s = dir.join(s.as_str()).to_string_lossy().into_owned();
            }
        }
    }
    params_toml(scene, &resolved, "model.params")
}

/// The TOML text of a scene's parameter table, as passed to a plugin.
pub(crate) fn params_toml(
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
pub(crate) fn plugin_error(scene: &SceneFile, e: PluginLoadError, table: &str) -> SourceError {
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

/// Line of `key` inside the dotted `table` (e.g. `model.params`), found on
/// the parsed document so that inline tables, nested tables and quoted keys
/// all count; the table's line when the key is not there (the plugin may name
/// a parameter the scene left out).
fn param_line(text: &str, table: &str, key: &str) -> usize {
    use toml::de::{DeTable, DeValue};
    let Ok(doc) = DeTable::parse(text) else {
        return 1;
    };
    let mut current: &DeTable = doc.get_ref();
    let mut pos = 0;
    for part in table.split('.') {
        let Some((k, v)) = current.iter().find(|(k, _)| k.get_ref() == part) else {
            return line_of(text, pos);
        };
        pos = k.span().start;
        match v.get_ref() {
            DeValue::Table(t) => current = t,
            _ => return line_of(text, pos),
        }
    }
    match current.iter().find(|(k, _)| k.get_ref() == key) {
        Some((k, _)) => line_of(text, k.span().start),
        None => line_of(text, pos),
    }
}
