//! Errors crossing the plugin boundary, and the guard that keeps panics on the
//! plugin's side of it. Shared by every 1.x version of the API.

use std::panic::{catch_unwind, AssertUnwindSafe};

use abi_stable::std_types::{RResult, RString};
use abi_stable::StableAbi;

/// Category of a [`PluginError`].
///
/// A transparent `u8` rather than an enum, so that later API versions can add
/// categories without changing the layout: an engine meets a category it does
/// not know as a value it prints by number, never as undefined behaviour.
#[repr(transparent)]
#[derive(StableAbi, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ErrorKind(pub u8);

#[allow(non_upper_case_globals)]
impl ErrorKind {
    /// A parameter is unknown, of the wrong type, or out of range.
    pub const InvalidParameter: Self = Self(0);
    /// The requested model (or reducer) name is not offered by the plugin.
    pub const UnknownModel: Self = Self(1);
    /// The model could not be built (e.g. inconsistent dimensions).
    pub const BuildFailed: Self = Self(2);
    /// The plugin panicked; the panic was caught at the boundary.
    pub const Panicked: Self = Self(3);
    /// The input of a reducer (signals, model) cannot be reduced.
    pub const InvalidInput: Self = Self(4);
    /// A reducer failed (e.g. a singular regression).
    pub const ReductionFailed: Self = Self(5);

    /// A short description (`"category 9"` for one added after this version).
    pub fn describe(self) -> std::borrow::Cow<'static, str> {
        match self {
            Self::InvalidParameter => "invalid parameter".into(),
            Self::UnknownModel => "unknown model".into(),
            Self::BuildFailed => "model build failed".into(),
            Self::Panicked => "panicked".into(),
            Self::InvalidInput => "invalid reducer input".into(),
            Self::ReductionFailed => "reduction failed".into(),
            Self(k) => format!("error category {k}").into(),
        }
    }
}

impl std::fmt::Debug for ErrorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe())
    }
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
        write!(
            f,
            "{} ({}): {}",
            self.kind.describe(),
            self.context,
            self.message
        )
    }
}

impl std::error::Error for PluginError {}

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

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn unknown_error_kinds_of_later_versions_are_printed_by_number() {
        let e = PluginError::new(ErrorKind(42), "here", "what");
        assert_eq!(e.to_string(), "error category 42 (here): what");
    }
}
