//! `[analysis.<name>]` tables resolved to the specs of the analyses of
//! [`crate::analyses::REGISTRY`].

use serde::{Deserialize, Serialize};

use crate::analyses::{self, AnalysisError, Needs};
use crate::scene::{SceneError, SceneFile};
use ssm_core::spec::{SpecError, SsmSpec};

/// An analysis of [`crate::analyses::REGISTRY`] with its spec, read and
/// checked (every default filled in): what a plan ships.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannedAnalysis {
    /// The analysis's name.
    pub name: String,
    /// Its spec as JSON.
    pub spec: serde_json::Value,
}

/// What the analyses of a plan with the SSM `ssm` are checked against.
pub fn needs(ssm: &SsmSpec) -> Needs {
    Needs {
        pairs: ssm.master_pairs.len(),
        max_order: ssm.max_order(),
    }
}

/// The `[analysis.<name>]` tables of `scene` (whose SSM is `ssm`), read and
/// checked; errors name the scene's file, line and key.
pub(super) fn analyses(
    scene: &SceneFile,
    ssm: &SsmSpec,
) -> Result<Vec<PlannedAnalysis>, SceneError> {
    let needs = needs(ssm);
    scene
        .scene
        .analysis
        .iter()
        .map(|(name, table)| {
            let at = table.span();
            let key = format!("analysis.{name}");
            let fail = |span: std::ops::Range<usize>, key: &str, e: AnalysisError| {
                scene.invalid(span, key, e.to_string())
            };
            let entry = analyses::find(name).map_err(|e| fail(at.clone(), &key, e))?;
            if entry.table() != key {
                return Err(scene.invalid(at.clone(), &key, own_table(&entry.table())));
            }
            let json = serde_json::to_value(table.get_ref())
                .map_err(|e| scene.invalid(at.clone(), &key, format!("cannot be read: {e}")))?;
            let spec = entry.spec(json, &needs).map_err(|e| match &e {
                AnalysisError::Spec { source, .. } => {
                    let at = source.at.as_ref().unwrap_or(&source.key);
                    scene.invalid(scene.locate(at), &source.key, source.problem.clone())
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

/// The analyses of a plan (built in code, their specs as JSON) read and
/// checked against the SSM `ssm`, as a scene's tables are.
pub(super) fn check(planned: &[PlannedAnalysis], ssm: &SsmSpec) -> Result<(), SpecError> {
    let needs = needs(ssm);
    for a in planned {
        let key = format!("analysis.{}", a.name);
        let entry = analyses::find(&a.name).map_err(|e| SpecError::new(&key, e.to_string()))?;
        if entry.table() != key {
            return Err(SpecError::new(&key, own_table(&entry.table())));
        }
        entry.spec(a.spec.clone(), &needs).map_err(|e| match e {
            AnalysisError::Spec { source, .. } => source,
            other => SpecError::new(&key, other.to_string()),
        })?;
    }
    Ok(())
}

/// Why an answer older than the registry is not asked for with
/// `[analysis.<name>]`.
fn own_table(table: &str) -> String {
    format!("is asked for with [{table}], not here")
}
