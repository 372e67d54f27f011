//! `[reduce]` and `[data]`: a model produced by a reducer from the `[model]`
//! and/or sampled signals.

use std::path::PathBuf;

use serde::Deserialize;
use toml::Spanned;

use super::{SceneError, SceneFile};

/// `[reduce]`: which reducer makes the model the analyses run on.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReduceSection {
    /// Plugin name or path to a plugin library (relative paths: from the
    /// scene's directory); without it, one of the engine's own reducers (`pod`).
    #[serde(default)]
    pub plugin: Option<Spanned<String>>,
    /// Reducer name, as listed by `ssm-engine plugins`.
    pub reducer: Spanned<String>,
    /// Parameters passed to the reducer.
    #[serde(default = "super::empty_table")]
    pub params: Spanned<toml::Table>,
}

/// `[data]`: uniformly sampled signals, one CSV file per trajectory (first
/// column `t`, then one column per observable, a header line naming them).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DataSection {
    /// CSV files, relative to the scene's directory.
    pub files: Spanned<Vec<String>>,
    /// Observables to pass (default: every column after `t`).
    #[serde(default)]
    pub columns: Option<Spanned<Vec<String>>>,
}

impl SceneFile {
    /// `path` relative to the scene's directory (absolute paths unchanged).
    pub fn relative(&self, path: &str) -> PathBuf {
        let p = PathBuf::from(path);
        if p.is_absolute() {
            return p;
        }
        self.path
            .parent()
            .map_or_else(|| p.clone(), |dir| dir.join(&p))
    }

    /// The model comes from `[model]`, from `[reduce]`, or both; `[data]`
    /// only feeds a reducer.
    pub(super) fn check_model_source(&self) -> Result<(), SceneError> {
        let sc = &self.scene;
        if sc.model.is_none() && sc.reduce.is_none() {
            return Err(self.invalid(
                0..0,
                "model",
                "the scene needs a [model] section (a plugin's model), or a [reduce] section (a reducer's model)".into(),
            ));
        }
        if let (Some(data), None) = (&sc.data, &sc.reduce) {
            return Err(self.invalid(
                data.files.span(),
                "data",
                "[data] feeds a reducer: add a [reduce] section".into(),
            ));
        }
        if let Some(data) = &sc.data {
            if data.files.get_ref().is_empty() {
                return Err(self.invalid(
                    data.files.span(),
                    "data.files",
                    "at least one file is needed".into(),
                ));
            }
            if let Some(cols) = &data.columns {
                if cols.get_ref().is_empty() {
                    return Err(self.invalid(
                        cols.span(),
                        "data.columns",
                        "name at least one column, or leave the key out for all".into(),
                    ));
                }
            }
        }
        Ok(())
    }
}
