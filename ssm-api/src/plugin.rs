//! The plugin root module and the boundary helpers.

use abi_stable::library::RootModule;
use abi_stable::sabi_types::VersionStrings;
use abi_stable::std_types::{RResult, RStr, RVec};
use abi_stable::{declare_root_module_statics, package_version_strings, StableAbi};

use crate::error::PluginError;
use crate::listing::ModelInfo;
use crate::model::Model;
use crate::reducer::{Reduced, ReducerInfo, ReducerInput};

/// Version of this API (the `ssm-api` package version) that plugins are built against.
pub const API_VERSION: &str = env!("CARGO_PKG_VERSION");

/// The root module every plugin exports (via [`crate::declare_plugin!`]).
///
/// A prefix type: the fields up to `build_model` are API 1.0 and never change;
/// later minor versions only *append* fields, each optional
/// (`missing_field(option)`): the engine reads a field a plugin's older layout
/// lacks as `None`, an absent capability. API 1.1 appended the reducer entry.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = SsmPluginRef)))]
#[sabi(missing_field(option))]
pub struct SsmPlugin {
    /// Plugin name, as used in scenes (`[model] plugin = ...`).
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
    /// API 1.1: lists the reducers with their parameters and inputs (empty
    /// when the plugin offers none).
    pub reducers: extern "C" fn() -> RResult<RVec<ReducerInfo>, PluginError>,
    /// API 1.1: runs reducer `name` with the TOML text of `[reduce.params]` on
    /// `input`.
    pub reduce: extern "C" fn(
        name: RStr<'_>,
        params: RStr<'_>,
        input: &ReducerInput,
    ) -> RResult<Reduced, PluginError>,
}

impl RootModule for SsmPluginRef {
    declare_root_module_statics! {SsmPluginRef}
    const BASE_NAME: &'static str = "ssm_plugin";
    const NAME: &'static str = "ssm-api";
    const VERSION_STRINGS: VersionStrings = package_version_strings!();
}

/// Declares a plugin's root module.
///
/// ```ignore
/// ssm_api::declare_plugin! {
///     name: "spatial-oscillator",
///     description: "Spatial oscillator of Li, Jain & Haller (2023), eq. (23)",
///     models: models,   // fn() -> Vec<ssm_api::ModelInfo>
///     build: build,     // fn(&str, &str) -> Result<ssm_api::Model, ssm_api::PluginError>
///     // optional (API 1.1), for plugins that offer reducers:
///     reducers: reducers, // fn() -> Vec<ssm_api::ReducerInfo>
///     reduce: reduce,     // fn(&str, &str, &ssm_api::ReducerInput) -> Result<ssm_api::Reduced, ssm_api::PluginError>
/// }
/// ```
///
/// The generated entry points catch panics ([`crate::guard`]), so a plugin bug is
/// reported by the engine instead of unwinding across the boundary. Plugins need
/// only `ssm-api` as a dependency. A plugin without reducers lists none.
#[macro_export]
macro_rules! declare_plugin {
    (name: $name:expr, description: $desc:expr, models: $models:path, build: $build:path $(,)?) => {
        fn __ssm_no_reducers() -> ::std::vec::Vec<$crate::ReducerInfo> {
            ::std::vec::Vec::new()
        }
        fn __ssm_no_reduce(
            name: &str,
            _params: &str,
            _input: &$crate::ReducerInput,
        ) -> ::std::result::Result<$crate::Reduced, $crate::PluginError> {
            ::std::result::Result::Err($crate::PluginError::new(
                $crate::ErrorKind::UnknownModel,
                name,
                "this plugin offers no reducers",
            ))
        }
        $crate::declare_plugin! {
            name: $name,
            description: $desc,
            models: $models,
            build: $build,
            reducers: __ssm_no_reducers,
            reduce: __ssm_no_reduce,
        }
    };
    (name: $name:expr, description: $desc:expr, models: $models:path, build: $build:path,
     reducers: $reducers:path, reduce: $reduce:path $(,)?) => {
        extern "C" fn __ssm_models() -> $crate::reexports::abi_stable::std_types::RResult<
            $crate::reexports::abi_stable::std_types::RVec<$crate::ModelInfo>,
            $crate::PluginError,
        > {
            $crate::guard("listing models", || Ok($models().into_iter().collect()))
        }

        extern "C" fn __ssm_build_model(
            name: $crate::reexports::abi_stable::std_types::RStr<'_>,
            params: $crate::reexports::abi_stable::std_types::RStr<'_>,
        ) -> $crate::reexports::abi_stable::std_types::RResult<$crate::Model, $crate::PluginError> {
            $crate::guard(&format!("building model '{}'", name.as_str()), || {
                $build(name.as_str(), params.as_str())
            })
        }

        extern "C" fn __ssm_reducers() -> $crate::reexports::abi_stable::std_types::RResult<
            $crate::reexports::abi_stable::std_types::RVec<$crate::ReducerInfo>,
            $crate::PluginError,
        > {
            $crate::guard("listing reducers", || Ok($reducers().into_iter().collect()))
        }

        extern "C" fn __ssm_reduce(
            name: $crate::reexports::abi_stable::std_types::RStr<'_>,
            params: $crate::reexports::abi_stable::std_types::RStr<'_>,
            input: &$crate::ReducerInput,
        ) -> $crate::reexports::abi_stable::std_types::RResult<$crate::Reduced, $crate::PluginError>
        {
            $crate::guard(&format!("reducer '{}'", name.as_str()), || {
                $reduce(name.as_str(), params.as_str(), input)
            })
        }

        fn __ssm_root_module() -> $crate::SsmPluginRef {
            use $crate::reexports::abi_stable::prefix_type::PrefixTypeTrait;
            $crate::SsmPlugin {
                name: $crate::reexports::abi_stable::std_types::RStr::from_str($name),
                version: $crate::reexports::abi_stable::std_types::RStr::from_str(env!(
                    "CARGO_PKG_VERSION"
                )),
                description: $crate::reexports::abi_stable::std_types::RStr::from_str($desc),
                models: __ssm_models,
                build_model: __ssm_build_model,
                reducers: __ssm_reducers,
                reduce: __ssm_reduce,
            }
            .leak_into_prefix()
        }

        /// The abi_stable library header (what `#[export_root_module]` generates;
        /// written out so that plugins need not depend on abi_stable directly).
        #[no_mangle]
        pub static _1as_0lib_1header_0root_bmodule_bloader:
            $crate::reexports::abi_stable::library::LibHeader = {
            extern "C" fn erased() -> $crate::reexports::abi_stable::library::RootModuleResult {
                $crate::reexports::abi_stable::library::__call_root_module_loader(__ssm_root_module)
            }
            unsafe {
                $crate::reexports::abi_stable::library::LibHeader::from_constructor::<
                    $crate::SsmPluginRef,
                >(
                    erased,
                    $crate::reexports::abi_stable::library::CheckTypeLayout::Yes,
                )
            }
        };
    };
}

#[cfg(test)]
mod tests {
    /// The static written by `declare_plugin!` must carry the symbol name that
    /// abi_stable's loader looks for.
    #[test]
    fn loader_symbol_name_matches_abi_stable() {
        assert_eq!(
            abi_stable::library::ROOT_MODULE_LOADER_NAME,
            "_1as_0lib_1header_0root_bmodule_bloader"
        );
    }
}
