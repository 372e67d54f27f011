//! The plugin root module and the boundary helpers.

use std::panic::{catch_unwind, AssertUnwindSafe};

use abi_stable::library::RootModule;
use abi_stable::sabi_types::VersionStrings;
use abi_stable::std_types::{RResult, RStr, RString, RVec};
use abi_stable::{declare_root_module_statics, package_version_strings, StableAbi};

use crate::model::Model;

/// Version of this API (the `ssm-api` package version) that plugins are built against.
pub const API_VERSION: &str = env!("CARGO_PKG_VERSION");

/// Category of a [`PluginError`].
#[repr(u8)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// A parameter is unknown, of the wrong type, or out of range.
    InvalidParameter,
    /// The requested model name is not offered by the plugin.
    UnknownModel,
    /// The model could not be built (e.g. inconsistent dimensions).
    BuildFailed,
    /// The plugin panicked; the panic was caught at the boundary.
    Panicked,
}

/// An error returned by a plugin: a category, where (parameter name, model name,
/// stage) and what.
#[repr(C)]
#[derive(StableAbi, Clone, Debug, PartialEq)]
pub struct PluginError {
    /// Category.
    pub kind: ErrorKind,
    /// Where: the parameter, model or stage concerned.
    pub context: RString,
    /// What is wrong, and what to do about it when known.
    pub message: RString,
}

impl PluginError {
    /// A new error.
    pub fn new(kind: ErrorKind, context: &str, message: &str) -> Self {
        Self {
            kind,
            context: context.into(),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for PluginError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kind = match self.kind {
            ErrorKind::InvalidParameter => "invalid parameter",
            ErrorKind::UnknownModel => "unknown model",
            ErrorKind::BuildFailed => "model build failed",
            ErrorKind::Panicked => "panicked",
        };
        write!(f, "{kind} ({}): {}", self.context, self.message)
    }
}

impl std::error::Error for PluginError {}

impl From<crate::mechanical::BuildError> for PluginError {
    fn from(e: crate::mechanical::BuildError) -> Self {
        Self::new(ErrorKind::BuildFailed, "mechanical builder", &e.to_string())
    }
}

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

/// Listing of one model a plugin offers.
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

/// The root module every plugin exports (via [`crate::declare_plugin!`]).
///
/// This is a prefix type: later API versions only *append* fields (after the
/// one marked `last_prefix_field`), so older plugins keep loading and the engine
/// sees the missing trailing fields as absent capabilities.
#[repr(C)]
#[derive(StableAbi)]
#[sabi(kind(Prefix(prefix_ref = SsmPluginRef)))]
#[sabi(missing_field(panic))]
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
}

impl RootModule for SsmPluginRef {
    declare_root_module_statics! {SsmPluginRef}
    const BASE_NAME: &'static str = "ssm_plugin";
    const NAME: &'static str = "ssm-api";
    const VERSION_STRINGS: VersionStrings = package_version_strings!();
}

/// Runs `f`, turning a panic into a [`PluginError`] of kind
/// [`ErrorKind::Panicked`] naming `stage` and the panic message, so that no
/// panic unwinds through the plugin boundary.
pub fn guard<T, F>(stage: &str, f: F) -> RResult<T, PluginError>
where
    F: FnOnce() -> Result<T, PluginError>,
{
    // The panic is reported through the returned error; the plugin's own copy of
    // std would otherwise also print it (with a backtrace) to stderr.
    static QUIET_HOOK: std::sync::Once = std::sync::Once::new();
    QUIET_HOOK.call_once(|| std::panic::set_hook(Box::new(|_| {})));
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(v)) => RResult::ROk(v),
        Ok(Err(e)) => RResult::RErr(e),
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "non-string panic payload".to_owned());
            RResult::RErr(PluginError::new(ErrorKind::Panicked, stage, &msg))
        }
    }
}

/// Declares a plugin's root module.
///
/// ```ignore
/// ssm_api::declare_plugin! {
///     name: "spatial-oscillator",
///     description: "Spatial oscillator of Li, Jain & Haller (2023), eq. (23)",
///     models: models,   // fn() -> Vec<ssm_api::ModelInfo>
///     build: build,     // fn(&str, &str) -> Result<ssm_api::Model, ssm_api::PluginError>
/// }
/// ```
///
/// The generated entry points catch panics ([`guard`]), so a plugin bug is
/// reported by the engine instead of unwinding across the boundary. Plugins need
/// only `ssm-api` as a dependency.
#[macro_export]
macro_rules! declare_plugin {
    (name: $name:expr, description: $desc:expr, models: $models:path, build: $build:path $(,)?) => {
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
    use super::*;

    /// The static written by `declare_plugin!` must carry the symbol name that
    /// abi_stable's loader looks for.
    #[test]
    fn loader_symbol_name_matches_abi_stable() {
        assert_eq!(
            abi_stable::library::ROOT_MODULE_LOADER_NAME,
            "_1as_0lib_1header_0root_bmodule_bloader"
        );
    }

    #[test]
    fn guard_turns_panic_into_error() {
        let r: RResult<(), PluginError> = guard("stage x", || panic!("boom {}", 7));
        match r {
            RResult::RErr(e) => {
                assert_eq!(e.kind, ErrorKind::Panicked);
                assert_eq!(e.context.as_str(), "stage x");
                assert_eq!(e.message.as_str(), "boom 7");
            }
            RResult::ROk(()) => panic!("guard did not catch the panic"),
        }
    }
}
