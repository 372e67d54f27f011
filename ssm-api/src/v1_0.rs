//! The frozen root module of API 1.0 (the model layout, before the reducer
//! entry). abi_stable checks a root module as "the engine's fields are a
//! prefix of the plugin's", so an engine loads an older plugin through the
//! older layout: it tries [`crate::SsmPlugin`] first and this one when the
//! plugin's root module is shorter. Never change this type; a later minor
//! version that appends fields adds its own frozen module beside it.

use abi_stable::library::RootModule;
use abi_stable::sabi_types::VersionStrings;
use abi_stable::std_types::{RResult, RStr, RVec};
use abi_stable::{declare_root_module_statics, StableAbi};

use crate::error::PluginError;
use crate::listing::ModelInfo;
use crate::model::Model;

/// The API 1.0 root module: ends at `build_model`.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = SsmPluginRef)))]
#[sabi(missing_field(option))]
pub struct SsmPlugin {
    /// Plugin name.
    pub name: RStr<'static>,
    /// Plugin's own version.
    pub version: RStr<'static>,
    /// One line on what the plugin offers.
    pub description: RStr<'static>,
    /// Lists the models with their parameters.
    pub models: extern "C" fn() -> RResult<RVec<ModelInfo>, PluginError>,
    /// Builds model `name` from the TOML text of `[model.params]`.
    #[sabi(last_prefix_field)]
    pub build_model: extern "C" fn(name: RStr<'_>, params: RStr<'_>) -> RResult<Model, PluginError>,
}

impl RootModule for SsmPluginRef {
    declare_root_module_statics! {SsmPluginRef}
    const BASE_NAME: &'static str = "ssm_plugin";
    const NAME: &'static str = "ssm-api";
    // the engine's version: the major version decides compatibility
    const VERSION_STRINGS: VersionStrings = abi_stable::package_version_strings!();
}
