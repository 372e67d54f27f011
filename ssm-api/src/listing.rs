//! What a plugin lists: its models and their parameters (and, from API 1.1,
//! its reducers, see [`crate::ReducerInfo`]).

use abi_stable::std_types::{RString, RVec};
use abi_stable::StableAbi;

use crate::error::{ErrorKind, PluginError};

/// The listed kind ([`ParamInfo::kind`]) of a path parameter: the engine
/// resolves relative values of such parameters against the scene's folder
/// before it passes the table to the plugin.
pub const PATH_KIND: &str = "path";

/// Listing of one parameter of a model.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name (the paper's symbol).
    pub name: RString,
    /// Type, or the allowed values separated by `|`.
    pub kind: RString,
    /// Default value, written as TOML.
    pub default: RString,
    /// What it is.
    pub description: RString,
}

/// Listing of one model a plugin offers (built from parameter specs by
/// `ssm_plugin_kit::model_info`).
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct ModelInfo {
    /// Model name (`[model] name = ...`).
    pub name: RString,
    /// One line on what it is and which paper/equations it implements.
    pub description: RString,
    /// Parameters with defaults.
    pub params: RVec<ParamInfo>,
}

/// The model a `build` call asks for: `requested`, or the first of `offered`
/// when `requested` is empty; an [`ErrorKind::UnknownModel`] error naming the
/// offered ones otherwise.
pub fn select_model<'a>(requested: &str, offered: &[&'a str]) -> Result<&'a str, PluginError> {
    if requested.is_empty() {
        if let Some(first) = offered.first() {
            return Ok(first);
        }
    }
    offered
        .iter()
        .find(|o| **o == requested)
        .copied()
        .ok_or_else(|| {
            PluginError::new(
                ErrorKind::UnknownModel,
                requested,
                &format!("this plugin offers: {}", offered.join(", ")),
            )
        })
}
