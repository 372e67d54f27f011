//! Finding and loading plugins.
//!
//! Plugins are found (in this order) from `--plugin PATH` arguments, from the
//! directories and files listed in `SSM_PLUGIN_PATH` (`:`-separated), and from
//! the directory of the running `ssm-engine` binary (so that after
//! `cargo build --release` every workspace plugin is found with no setup).
//!
//! Each library is loaded with `abi_stable::library::lib_header_from_path` and
//! `init_root_module`, not `RootModule::load_from_file`: the latter caches one
//! module per root-module type, so a second plugin would silently return the
//! first.

use std::path::{Path, PathBuf};

use abi_stable::library::{lib_header_from_path, LibraryError};
use ssm_api::{
    Model, ModelInfo, PluginError, Reduced, ReducerInfo, ReducerInput, SsmPluginRef, API_VERSION,
};
use ssm_model_files::input::{InputError, InputFile, Limit};

/// What went wrong while loading or calling a plugin.
#[derive(Debug, thiserror::Error)]
pub enum PluginLoadError {
    /// The file does not exist.
    #[error("plugin file {path} does not exist")]
    Missing {
        /// The path given.
        path: PathBuf,
    },
    /// The path is not a regular file (a FIFO, a device, a directory) or is
    /// larger than `LIBRARY`.
    #[error("plugin library: {0}")]
    Input(#[from] InputError),
    /// The library was built against an incompatible `ssm-api`.
    #[error("plugin {path} was built against ssm-api {found}, but this engine uses ssm-api {expected}: rebuild the plugin against ssm-api {expected}")]
    VersionMismatch {
        /// The library.
        path: PathBuf,
        /// Version the plugin was built against.
        found: String,
        /// Version of this engine's API.
        expected: String,
    },
    /// The library's API version is compatible but its root-module layout is
    /// not the engine's (a plugin built against a modified `ssm-api`).
    #[error("plugin {path} was built against an ssm-api {found} whose layout differs from this engine's ssm-api {expected} ({difference}): rebuild the plugin against ssm-api {expected}")]
    LayoutMismatch {
        /// The library.
        path: PathBuf,
        /// Version the plugin was built against.
        found: String,
        /// Version of this engine's API.
        expected: String,
        /// The last lines of abi_stable's layout report, where it names the
        /// first type that differs.
        difference: String,
    },
    /// The file is not a shared library exporting an ssm plugin.
    #[error("{path} is not an ssm plugin: {detail}")]
    NotAPlugin {
        /// The file.
        path: PathBuf,
        /// What is missing.
        detail: String,
    },
    /// The library could not be loaded for another reason.
    #[error("cannot load plugin {path}: {detail}")]
    Invalid {
        /// The library.
        path: PathBuf,
        /// abi_stable's explanation.
        detail: String,
    },
    /// No plugin with this name was found.
    #[error("no plugin named '{name}' was found (searched: {searched}); list them with `ssm-engine plugins`, or pass --plugin PATH")]
    NotFound {
        /// Name asked for.
        name: String,
        /// Where it looked.
        searched: String,
    },
    /// The plugin was built against API 1.0, before the reducer entry.
    #[error("plugin '{plugin}' was built against ssm-api 1.0, which has no reducers: rebuild it against ssm-api {} to offer reducers", API_VERSION)]
    NoReducers {
        /// Plugin name.
        plugin: String,
    },
    /// The plugin returned an error or panicked.
    #[error("plugin '{plugin}' failed: {error}")]
    Plugin {
        /// Plugin name.
        plugin: String,
        /// The plugin's error.
        error: PluginError,
    },
}

/// The root module of a loaded plugin, by the API layout it was built with.
#[derive(Clone, Copy)]
enum RootModule {
    /// The current layout (or a later 1.x, whose extra fields are ignored).
    Current(SsmPluginRef),
    /// API 1.0: no reducer entry.
    V1_0(ssm_api::v1_0::SsmPluginRef),
}

/// The largest plugin library loaded: 1 GiB.
pub(crate) const LIBRARY: Limit = Limit {
    bytes: 1 << 30,
    what: "a plugin library",
};

/// A loaded plugin.
#[derive(Clone, Copy)]
pub struct Plugin {
    module: RootModule,
}

impl std::fmt::Debug for Plugin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Plugin({})", self.name())
    }
}

impl Plugin {
    /// Loads the plugin library at `path`, checking the API version and layout.
    pub fn load(path: &Path) -> Result<Self, PluginLoadError> {
        if !path.exists() {
            return Err(PluginLoadError::Missing {
                path: path.to_owned(),
            });
        }
        // a FIFO or a device would block or feed dlopen: regular files only
        InputFile::open(path, LIBRARY)?;
        // dlopen searches the library path for a name without a slash: always
        // hand it the file itself
        let file = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
        let header = lib_header_from_path(&file).map_err(|e| load_error(path, e))?;
        // every layout is checked in full by abi_stable; an older 1.x plugin
        // fails the current layout (its root module has fewer fields) and
        // passes its own
        let module = match header.init_root_module::<SsmPluginRef>() {
            Ok(m) => RootModule::Current(m),
            Err(LibraryError::AbiInstability(current)) => {
                match header.init_root_module::<ssm_api::v1_0::SsmPluginRef>() {
                    Ok(m) => RootModule::V1_0(m),
                    Err(_) => {
                        return Err(PluginLoadError::LayoutMismatch {
                            path: path.to_owned(),
                            found: header.version_strings().version.to_string(),
                            expected: API_VERSION.to_owned(),
                            difference: last_lines(&current.to_string(), 3),
                        })
                    }
                }
            }
            Err(e) => return Err(load_error(path, e)),
        };
        Ok(Self { module })
    }

    /// Plugin name.
    pub fn name(&self) -> &'static str {
        match self.module {
            RootModule::Current(m) => m.name().as_str(),
            RootModule::V1_0(m) => m.name().as_str(),
        }
    }

    /// Plugin version.
    pub fn version(&self) -> &'static str {
        match self.module {
            RootModule::Current(m) => m.version().as_str(),
            RootModule::V1_0(m) => m.version().as_str(),
        }
    }

    /// One-line description.
    pub fn description(&self) -> &'static str {
        match self.module {
            RootModule::Current(m) => m.description().as_str(),
            RootModule::V1_0(m) => m.description().as_str(),
        }
    }

    /// The models offered, with parameters and defaults.
    pub fn models(&self) -> Result<Vec<ModelInfo>, PluginLoadError> {
        let models = match self.module {
            RootModule::Current(m) => m.models(),
            RootModule::V1_0(m) => m.models(),
        };
        models()
            .into_result()
            .map(|v| v.into_iter().collect())
            .map_err(|error| self.failed(error))
    }

    /// Builds model `name` (empty: the plugin's only/default model) from the TOML
    /// text of the scene's `[model.params]`.
    pub fn build_model(&self, name: &str, params_toml: &str) -> Result<Model, PluginLoadError> {
        let build = match self.module {
            RootModule::Current(m) => m.build_model(),
            RootModule::V1_0(m) => m.build_model(),
        };
        build(name.into(), params_toml.into())
            .into_result()
            .map_err(|error| self.failed(error))
    }

    /// The reducers offered: `None` for a plugin built against API 1.0 (its
    /// root module ends before the reducer entry), else the listing.
    pub fn reducers(&self) -> Option<Result<Vec<ReducerInfo>, PluginLoadError>> {
        let RootModule::Current(m) = self.module else {
            return None;
        };
        let list = m.reducers()?;
        Some(
            list()
                .into_result()
                .map(|v| v.into_iter().collect())
                .map_err(|error| self.failed(error)),
        )
    }

    /// Runs reducer `name` with the TOML text of `[reduce.params]` on `input`.
    pub fn reduce(
        &self,
        name: &str,
        params_toml: &str,
        input: &ReducerInput,
    ) -> Result<Reduced, PluginLoadError> {
        let no_reducers = || PluginLoadError::NoReducers {
            plugin: self.name().to_owned(),
        };
        let RootModule::Current(m) = self.module else {
            return Err(no_reducers());
        };
        let reduce = m.reduce().ok_or_else(no_reducers)?;
        reduce(name.into(), params_toml.into(), input)
            .into_result()
            .map_err(|error| self.failed(error))
    }

    fn failed(&self, error: PluginError) -> PluginLoadError {
        PluginLoadError::Plugin {
            plugin: self.name().to_owned(),
            error,
        }
    }
}

/// Which plugin library a run used: recorded in `summary.json` so that a
/// result names the code that produced it.
#[derive(Debug, Clone, PartialEq)]
pub struct PluginOrigin {
    /// Plugin name.
    pub name: String,
    /// Plugin version.
    pub version: String,
    /// The library file, absolute.
    pub file: PathBuf,
}

/// Where plugins are searched for, and what was found there.
#[derive(Debug, Default)]
pub struct Registry {
    /// Loaded plugins with the file each came from.
    pub plugins: Vec<(PathBuf, Plugin)>,
    /// Libraries found by directory search that could not be loaded.
    pub rejected: Vec<PluginLoadError>,
    searched: Vec<String>,
    used: Vec<PluginOrigin>,
}

impl Registry {
    /// Loads every explicitly given plugin (an error if any fails) and every
    /// library found in `SSM_PLUGIN_PATH` and next to the running binary (those
    /// that fail are kept in [`Registry::rejected`]).
    pub fn discover(explicit: &[PathBuf]) -> Result<Self, PluginLoadError> {
        let mut reg = Self::default();
        for path in explicit {
            let plugin = Plugin::load(path)?;
            reg.add(path.clone(), plugin);
            reg.searched.push(path.display().to_string());
        }
        let mut dirs: Vec<PathBuf> = Vec::new();
        if let Some(var) = std::env::var_os("SSM_PLUGIN_PATH") {
            dirs.extend(std::env::split_paths(&var).filter(|p| !p.as_os_str().is_empty()));
        }
        if let Some(dir) = std::env::current_exe()
            .ok()
            .and_then(|p| p.parent().map(Path::to_owned))
        {
            dirs.push(dir);
        }
        for dir in dirs {
            reg.searched.push(dir.display().to_string());
            for lib in libraries_in(&dir) {
                if reg.plugins.iter().any(|(p, _)| same_file(p, &lib)) {
                    continue;
                }
                match Plugin::load(&lib) {
                    Ok(plugin) => reg.add(lib, plugin),
                    Err(e) => reg.rejected.push(e),
                }
            }
        }
        Ok(reg)
    }

    fn add(&mut self, path: PathBuf, plugin: Plugin) {
        // the first one found under a name wins (explicit paths come first)
        if !self.plugins.iter().any(|(_, p)| p.name() == plugin.name()) {
            self.plugins.push((path, plugin));
        }
    }

    /// The plugin named `name`, or loaded from `name` if it is a path to a
    /// file; the plugin is recorded as used (see [`Registry::take_used`]).
    pub fn resolve(&mut self, name: &str) -> Result<Plugin, PluginLoadError> {
        let found = match self.plugins.iter().find(|(_, p)| p.name() == name) {
            Some((path, p)) => (path.clone(), *p),
            None if is_path(name) => {
                let path = PathBuf::from(name);
                let plugin = Plugin::load(&path)?;
                self.add(path.clone(), plugin);
                (path, plugin)
            }
            None => {
                return Err(PluginLoadError::NotFound {
                    name: name.to_owned(),
                    searched: self.searched.join(", "),
                })
            }
        };
        let (path, plugin) = found;
        let origin = PluginOrigin {
            name: plugin.name().to_owned(),
            version: plugin.version().to_owned(),
            file: std::path::absolute(&path).unwrap_or(path),
        };
        if !self.used.contains(&origin) {
            self.used.push(origin);
        }
        Ok(plugin)
    }

    /// The plugins [`Registry::resolve`] has handed out since the last call,
    /// in order.
    pub fn take_used(&mut self) -> Vec<PluginOrigin> {
        std::mem::take(&mut self.used)
    }
}

/// True when a plugin reference names a file rather than a plugin.
pub fn is_path(name: &str) -> bool {
    name.contains(std::path::MAIN_SEPARATOR)
        || Path::new(name)
            .extension()
            .is_some_and(|e| matches!(e.to_str(), Some("so" | "dylib" | "dll")))
}

/// A short, typed account of a loader error: abi_stable's own texts run to
/// thousands of lines for a layout report and say "Could load symbol" for a
/// symbol it could not load.
fn load_error(path: &Path, e: LibraryError) -> PluginLoadError {
    let path = path.to_owned();
    match e {
        LibraryError::IncompatibleVersionNumber { actual_version, .. } => {
            PluginLoadError::VersionMismatch {
                path,
                found: actual_version.to_string(),
                expected: API_VERSION.to_owned(),
            }
        }
        LibraryError::OpenError { err, .. } => PluginLoadError::NotAPlugin {
            path,
            detail: format!("it cannot be opened as a shared library ({err})"),
        },
        LibraryError::GetSymbolError { symbol, .. } => PluginLoadError::NotAPlugin {
            path,
            detail: format!(
                "it exports no `{}` (a plugin declares itself with ssm_api::declare_plugin!)",
                String::from_utf8_lossy(&symbol).trim_end_matches('\0')
            ),
        },
        LibraryError::InvalidAbiHeader(_) | LibraryError::InvalidCAbi { .. } => {
            PluginLoadError::Invalid {
                path,
                detail: format!(
                    "it was built with an incompatible abi_stable or Rust C ABI: rebuild it against ssm-api {API_VERSION}"
                ),
            }
        }
        other => PluginLoadError::Invalid {
            path,
            detail: last_lines(&other.to_string(), 6),
        },
    }
}

/// The last `n` non-empty lines of `text`, joined by "; ".
fn last_lines(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    let start = lines.len().saturating_sub(n);
    let mut out = lines[start..].join("; ");
    if start > 0 {
        out.insert_str(0, "...; ");
    }
    out
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// Shared libraries (`*.so`, `*.dylib`, `*.dll`) directly inside `path` (or
/// `path` itself when it is a file), sorted by name.
fn libraries_in(path: &Path) -> Vec<PathBuf> {
    if path.is_file() {
        return vec![path.to_owned()];
    }
    let Ok(entries) = std::fs::read_dir(path) else {
        return Vec::new();
    };
    let mut libs: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file()
                && matches!(
                    p.extension().and_then(|e| e.to_str()),
                    Some("so" | "dylib" | "dll")
                )
        })
        .collect();
    libs.sort();
    libs
}
