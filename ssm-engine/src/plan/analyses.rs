//! `[analysis.<name>]` tables resolved to the specs of the analyses of
//! [`crate::analyses::REGISTRY`].

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::analyses::{self, AnalysisError, Needs};
use crate::scene::{SceneError, SceneFile};

/// An analysis of [`crate::analyses::REGISTRY`] with its spec, read and
/// checked (every default filled in): what a plan ships.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedAnalysis {
    /// The analysis's name.
    pub name: String,
    /// Its spec as JSON.
    pub spec: serde_json::Value,
}

/// What the analyses of `scene` are checked against.
pub fn needs(scene: &SceneFile) -> Needs {
    let ssm = &scene.scene.ssm;
    Needs {
        pairs: ssm.master_pairs.get_ref().len(),
        max_order: ssm.max_order(),
    }
}

/// The `[analysis.<name>]` tables of `scene`, read and checked; errors name
/// the scene's file, line and key.
pub fn analyses(scene: &SceneFile) -> Result<Vec<PlannedAnalysis>, SceneError> {
    let needs = needs(scene);
    scene
        .scene
        .analysis
        .iter()
        .map(|(name, table)| {
            let at = table.span();
            let key = format!("analysis.{name}");
            let fail = |span: Range<usize>, key: &str, e: AnalysisError| {
                scene.invalid(span, key, e.to_string())
            };
            let entry = analyses::find(name).map_err(|e| fail(at.clone(), &key, e))?;
            let json = serde_json::to_value(table.get_ref())
                .map_err(|e| scene.invalid(at.clone(), &key, format!("cannot be read: {e}")))?;
            let spec = entry.spec(json, &needs).map_err(|e| match &e {
                AnalysisError::Spec { source, .. } => {
                    let span = key_span(scene, at.clone(), source.key);
                    scene.invalid(span, source.key, source.problem.clone())
                }
                _ => fail(at.clone(), &key, e),
            })?;
            Ok(PlannedAnalysis {
                name: name.clone(),
                spec,
            })
        })
        .collect()
}

/// Where the last part of `key` (`analysis.damping.rho_max`: `rho_max`) is
/// written in the table that starts at `table` (up to the next table
/// header) of the scene's text, else `table`.
pub fn key_span(scene: &SceneFile, table: Range<usize>, key: &str) -> Range<usize> {
    let last = key.rsplit('.').next().unwrap_or(key);
    let text = scene.text.get(table.start..).unwrap_or("");
    let mut offset = table.start;
    for (k, line) in text.split_inclusive('\n').enumerate() {
        let trimmed = line.trim_start();
        if k > 0 && trimmed.starts_with('[') {
            break;
        }
        if let Some(rest) = trimmed.strip_prefix(last) {
            if rest.trim_start().starts_with('=') {
                let start = offset + (line.len() - trimmed.len());
                return start..start + last.len();
            }
        }
        offset += line.len();
    }
    table
}
