//! Checks of a scene against its model that the scene alone cannot make:
//! named outputs and states exist, `[validate]` has a flow and a forcing to
//! work with. Each failure is a scene error at the key's line.

use toml::Spanned;

use super::error::JobError;
use crate::scene::{SceneFile, ValidateSection};
use ssm_core::model::system::{OutputMap, System};

/// The outputs of `[outputs] coordinates`, each checked to exist.
pub fn coordinates<'a>(
    scene: &SceneFile,
    system: &'a System,
) -> Result<Vec<&'a OutputMap>, JobError> {
    named_outputs(
        scene,
        system,
        &scene.scene.outputs.coordinates,
        "outputs.coordinates",
    )
}

/// The outputs `names` (the scene key `key`), each checked to exist.
pub fn named_outputs<'a>(
    scene: &SceneFile,
    system: &'a System,
    names: &Spanned<Vec<String>>,
    key: &str,
) -> Result<Vec<&'a OutputMap>, JobError> {
    names
        .get_ref()
        .iter()
        .map(|name| {
            system.output(name).ok_or_else(|| {
                let known: Vec<&str> = system
                    .outputs
                    .iter()
                    .map(|o| o.name.as_str())
                    .take(40)
                    .collect();
                scene
                    .invalid(
                        names.span(),
                        key,
                        format!(
                            "model '{}' has no output '{name}'; it has: {}",
                            system.name,
                            known.join(", ")
                        ),
                    )
                    .into()
            })
        })
        .collect()
}

/// The outputs compared by `[validate]` (its `outputs`, else `coordinates`),
/// after checking that the model can be validated as the section asks.
pub fn validation_outputs<'a>(
    scene: &SceneFile,
    system: &'a System,
    vsec: &ValidateSection,
    coordinates: &[&'a OutputMap],
) -> Result<Vec<&'a OutputMap>, JobError> {
    if let ssm_api::TimeKind::Map { .. } = system.time {
        let at = scene.text.find("[validate").unwrap_or(0);
        return Err(scene
            .invalid(
                at..at,
                "validate",
                format!(
                    "model '{}' is a map; the full-system integrator needs a flow",
                    system.name
                ),
            )
            .into());
    }
    if let Some(ss) = &vsec.steady_state {
        if system.forcing.is_empty() {
            return Err(scene
                .invalid(
                    ss.epsilon.span(),
                    "validate.steady_state",
                    format!(
                        "model '{}' has no forcing Fext to drive a steady state",
                        system.name
                    ),
                )
                .into());
        }
    }
    for (table, key) in [(&vsec.x0, "validate.x0"), (&vsec.v0, "validate.v0")] {
        if let Some(t) = table {
            given_names(scene, system, t.get_ref(), t.span(), key)?;
        }
    }
    match &vsec.outputs {
        Some(names) => names
            .get_ref()
            .iter()
            .map(|n| {
                system.output(n).ok_or_else(|| {
                    scene
                        .invalid(
                            names.span(),
                            "validate.outputs",
                            format!("model '{}' has no output '{n}'", system.name),
                        )
                        .into()
                })
            })
            .collect(),
        None => Ok(coordinates.to_vec()),
    }
}

/// The keys of a given-start table name states of the model of the right
/// kind: displacements in `x0`, velocities in `v0` (the last part of `key`).
pub fn given_names(
    scene: &SceneFile,
    system: &System,
    table: &toml::Table,
    span: std::ops::Range<usize>,
    key: &str,
) -> Result<(), JobError> {
    let kind = if key.ends_with("v0") {
        ssm_api::StateKind::Velocity
    } else {
        ssm_api::StateKind::Displacement
    };
    for name in table.keys() {
        if !system
            .states
            .iter()
            .any(|s| s.name.as_str() == name && s.kind == kind)
        {
            return Err(scene
                .invalid(
                    span.clone(),
                    key,
                    format!("model '{}' has no {kind:?} state '{name}'", system.name),
                )
                .into());
        }
    }
    Ok(())
}
