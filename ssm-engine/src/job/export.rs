//! `ssm-engine export`: the mechanical model of a scene's `[model]` written as
//! a model folder (see `ssm_model_files`), so that a plugin's model can be
//! handed to another tool, or files checked against a plugin.

use ssm_model_files::ExportError;

use super::source::{build_model, SourceError};
use crate::output::OutputSet;
use crate::scene::SceneFile;
use ssm_core::model::plugin::Registry;
use ssm_core::model::system::{ModelError, System};

/// Why a scene's model could not be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportFailure {
    /// The scene has no `[model]` section.
    #[error("{path}: the scene has no [model] section to export")]
    NoModel {
        /// The scene file.
        path: String,
    },
    /// The plugin could not build the model.
    #[error(transparent)]
    Source(#[from] SourceError),
    /// The plugin's model fails the engine's checks (sizes, indices, values).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The model is not in the form the files hold.
    #[error(transparent)]
    Export(#[from] ExportError),
    /// Encoding the files failed.
    #[error("cannot encode the model files: {0}")]
    Encode(#[from] std::io::Error),
}

/// The files of the scene's model (as its plugin builds it), with notes on
/// what was left out.
pub fn export(
    scene: &SceneFile,
    registry: &mut Registry,
) -> Result<(OutputSet, Vec<String>), ExportFailure> {
    let section = scene
        .scene
        .model
        .as_ref()
        .ok_or_else(|| ExportFailure::NoModel {
            path: scene.path.display().to_string(),
        })?;
    let (plugin, model) = build_model(scene, section, registry)?;
    // the engine's checks first: nothing is written that the engine (or the
    // reader) would refuse
    System::from_model(&plugin, model.clone())?;
    let (files, notes) = ssm_plugin_kit::files_from_model(&model)?;
    let source = format!(
        "plugin '{plugin}', model '{}' of {}",
        model.name,
        scene.path.display()
    );
    let mut set = OutputSet::default();
    for (name, contents) in files.encode(&source)? {
        set.add(name, contents);
    }
    Ok((set, notes))
}
