//! The scene format: a TOML file naming a model (plugin, model name, parameters)
//! and what to compute. Unknown keys are rejected; every error names the file,
//! the line and the key.
//!
//! ```toml
//! [model]
//! plugin = "spatial-oscillator"   # a name listed by `ssm-engine plugins`, or a path
//! # name = "chain"                # which model, when a plugin offers several
//! [model.params]                  # passed to the plugin (the paper's symbols)
//! constraint = "cubic"
//! [ssm]
//! master_pairs = [1]              # 1-based mode pairs, slowest first
//! order = 13                      # expansion order (non-resonance checks go up to it)
//! normalization = "unit"          # or "mass"
//! resonance_tol = 0.02            # relative distance counted as a (near) resonance
//! [spectrum]
//! method = "auto"                 # "dense" | "sparse" | "auto" (dense up to 2000 states)
//! modes = 12                      # finite modes computed on the sparse path
//! [outputs]
//! coordinates = ["x1"]            # named outputs of the model
//! ```

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

/// A scene that cannot be used, with the place and the problem.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene {path}: {source}")]
    Io {
        /// The scene file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// TOML syntax, an unknown key, a missing key or a value of the wrong type.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The scene file.
        path: PathBuf,
        /// 1-based line (0 when unknown).
        line: usize,
        /// The parser's message (names the key).
        message: String,
    },
    /// A well-typed value that does not make sense for this model.
    #[error("{path}:{line}: `{key}`: {message}")]
    Invalid {
        /// The scene file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The key concerned.
        key: String,
        /// What is wrong and what is allowed.
        message: String,
    },
}

/// A parsed scene.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Which model.
    pub model: ModelSection,
    /// SSM settings.
    #[serde(default)]
    pub ssm: SsmSection,
    /// Eigen-solver settings.
    #[serde(default)]
    pub spectrum: SpectrumSection,
    /// Requested outputs.
    #[serde(default)]
    pub outputs: OutputsSection,
}

/// `[model]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelSection {
    /// Plugin name or path to a plugin library.
    pub plugin: Spanned<String>,
    /// Model name, when the plugin offers several.
    #[serde(default)]
    pub name: Option<Spanned<String>>,
    /// Parameters passed to the plugin.
    #[serde(default = "empty_table")]
    pub params: Spanned<toml::Table>,
}

/// How master eigenvectors are scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Normalization {
    /// Unit 2-norm of the whole state vector.
    #[default]
    Unit,
    /// Displacement part mass-normalized, `x^H M x = 1` (needs a mechanical model).
    Mass,
}

/// `[ssm]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SsmSection {
    /// 1-based master mode pairs, slowest first.
    #[serde(default = "default_master_pairs")]
    pub master_pairs: Spanned<Vec<usize>>,
    /// Expansion order.
    #[serde(default = "default_order")]
    pub order: Spanned<usize>,
    /// Eigenvector scaling.
    #[serde(default)]
    pub normalization: Normalization,
    /// Relative distance `|a.lambda + b.conj(lambda) - lambda_k| / |lambda_k|`
    /// below which a combination counts as a (near) resonance.
    #[serde(default = "default_resonance_tol")]
    pub resonance_tol: Spanned<f64>,
}

fn default_master_pairs() -> Spanned<Vec<usize>> {
    Spanned::new(0..0, vec![1])
}
fn default_order() -> Spanned<usize> {
    Spanned::new(0..0, 3)
}
fn default_resonance_tol() -> Spanned<f64> {
    Spanned::new(0..0, 0.02)
}

impl Default for SsmSection {
    fn default() -> Self {
        Self {
            master_pairs: default_master_pairs(),
            order: default_order(),
            normalization: Normalization::Unit,
            resonance_tol: default_resonance_tol(),
        }
    }
}

/// Eigen-solver choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SpectrumMethod {
    /// Dense path up to [`crate::spectrum::DENSE_LIMIT`] states, sparse above.
    #[default]
    Auto,
    /// Dense eigensolver of the whole shift-inverted pencil.
    Dense,
    /// Shift-invert Krylov-Schur with a sparse LU, only the requested modes.
    Sparse,
}

/// `[spectrum]`.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SpectrumSection {
    /// Solver.
    #[serde(default)]
    pub method: SpectrumMethod,
    /// Number of finite eigenvalues to compute on the sparse path (default: the
    /// master modes plus 10).
    #[serde(default)]
    pub modes: Option<Spanned<usize>>,
    /// Real shift `sigma` of the sparse path (default 0: modes nearest the origin).
    #[serde(default)]
    pub shift: Option<f64>,
}

/// `[outputs]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputsSection {
    /// Named outputs of the model to report.
    #[serde(default = "empty_list")]
    pub coordinates: Spanned<Vec<String>>,
}

impl Default for OutputsSection {
    fn default() -> Self {
        Self {
            coordinates: empty_list(),
        }
    }
}

fn empty_list() -> Spanned<Vec<String>> {
    Spanned::new(0..0, Vec::new())
}

fn empty_table() -> Spanned<toml::Table> {
    Spanned::new(0..0, toml::Table::new())
}

/// A scene with the file it came from (for error messages).
#[derive(Debug, Clone)]
pub struct SceneFile {
    /// Path of the scene.
    pub path: PathBuf,
    /// Its text.
    pub text: String,
    /// Parsed content.
    pub scene: Scene,
}

impl SceneFile {
    /// Reads and parses a scene file.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(path, text)
    }

    /// Parses scene text (`path` is used in messages only).
    pub fn parse(path: &Path, text: String) -> Result<Self, SceneError> {
        let scene: Scene = toml::from_str(&text).map_err(|e| SceneError::Parse {
            path: path.to_owned(),
            line: e.span().map_or(0, |s| line_of(&text, s.start)),
            message: e.message().to_owned(),
        })?;
        let file = Self {
            path: path.to_owned(),
            text,
            scene,
        };
        file.check_generic()?;
        Ok(file)
    }

    /// Scene name: the file stem.
    pub fn name(&self) -> String {
        self.path
            .file_stem()
            .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned())
    }

    /// An [`SceneError::Invalid`] at `span`.
    pub fn invalid(&self, span: Range<usize>, key: &str, message: String) -> SceneError {
        SceneError::Invalid {
            path: self.path.clone(),
            line: line_of(&self.text, span.start),
            key: key.to_owned(),
            message,
        }
    }

    /// Checks that need no model.
    fn check_generic(&self) -> Result<(), SceneError> {
        let ssm = &self.scene.ssm;
        if ssm.master_pairs.get_ref().is_empty() {
            return Err(self.invalid(
                ssm.master_pairs.span(),
                "ssm.master_pairs",
                "at least one master pair is needed".into(),
            ));
        }
        let mut sorted = ssm.master_pairs.get_ref().clone();
        sorted.sort_unstable();
        sorted.dedup();
        if sorted.len() != ssm.master_pairs.get_ref().len() || sorted[0] == 0 {
            return Err(self.invalid(
                ssm.master_pairs.span(),
                "ssm.master_pairs",
                "pairs are 1-based and must not repeat".into(),
            ));
        }
        if *ssm.order.get_ref() < 1 {
            return Err(self.invalid(ssm.order.span(), "ssm.order", "must be at least 1".into()));
        }
        let tol = *ssm.resonance_tol.get_ref();
        if !(tol.is_finite() && tol > 0.0 && tol < 1.0) {
            return Err(self.invalid(
                ssm.resonance_tol.span(),
                "ssm.resonance_tol",
                format!("must lie in (0, 1), found {tol}"),
            ));
        }
        if let Some(m) = &self.scene.spectrum.modes {
            if *m.get_ref() == 0 {
                return Err(self.invalid(m.span(), "spectrum.modes", "must be at least 1".into()));
            }
        }
        Ok(())
    }
}

/// 1-based line of byte offset `pos` in `text`.
pub fn line_of(text: &str, pos: usize) -> usize {
    text[..pos.min(text.len())]
        .bytes()
        .filter(|&b| b == b'\n')
        .count()
        + 1
}
