//! The scene format: a TOML file naming a model (plugin, model name,
//! parameters; or a reducer and its data) and what to compute. Unknown keys
//! are rejected; every error names the file, the line and the key.
//!
//! The format, annotated ([`FORMAT`]: the one source of this text, also shown
//! by `ssm-engine --help` and in `docs/scenes.md`; a test keeps them equal):
#![doc = concat!("```toml\n", include_str!("format.toml"), "```")]

use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use ssm_model_files::input::{self, InputError, InputFile};
use toml::Spanned;

use ssm_core::spec::{BackboneSpec, FrcSpec, InvarianceSpec, TransientSpec};

mod locate;
mod names;
mod pod;
mod reduce;
mod reference;
mod simulate;
mod validate;

pub use pod::{
    load_sampling, PodRun, PodSection, MAX_POD_ROMS, MAX_POD_TESTS, MIN_STEPS_PER_PERIOD,
};
pub use reduce::{DataSection, ReduceSection};
pub(crate) use reference::MAX_REFERENCE_COEFFICIENTS;
pub use reference::{ReferenceSection, MAX_HARMONICS, MAX_REFERENCE_CURVES, MAX_REFERENCE_STEPS};
pub use simulate::{SimulateRun, SimulateSection};
use ssm_core::spectrum::Normalization;
pub use validate::{ReportSection, SteadyStateSection, ValidateSection};

/// The annotated scene format, every section and key with its default: the
/// one source of the format's documentation (module docs, `--help`, `docs/scenes.md`).
pub const FORMAT: &str = include_str!("format.toml");

/// A number or a list of numbers in a scene.
enum NumberOrList {
    Number(f64),
    List(Vec<f64>),
}

impl<'de> Deserialize<'de> for NumberOrList {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = NumberOrList;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a list of numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(NumberOrList::Number(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(NumberOrList::Number(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(NumberOrList::Number(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<Self::Value, A::Error> {
                let mut v = Vec::new();
                while let Some(x) = a.next_element::<f64>()? {
                    v.push(x);
                }
                Ok(NumberOrList::List(v))
            }
        }
        d.deserialize_any(Visitor)
    }
}

impl NumberOrList {
    fn into_vec(self) -> Vec<f64> {
        match self {
            Self::Number(x) => vec![x],
            Self::List(v) => v,
        }
    }
}

/// A key that takes a list and also accepts a single number (`epsilon = 0.6`
/// for `epsilon = [0.6]`).
fn number_or_list<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Spanned<Vec<f64>>, D::Error> {
    let s = Spanned::<NumberOrList>::deserialize(d)?;
    let span = s.span();
    Ok(Spanned::new(span, s.into_inner().into_vec()))
}

/// A key that takes one number and also accepts a list of one (`epsilon =
/// [0.6]` for `epsilon = 0.6`).
fn number_or_single<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Spanned<f64>, D::Error> {
    let s = Spanned::<NumberOrList>::deserialize(d)?;
    let span = s.span();
    match s.into_inner().into_vec()[..] {
        [x] => Ok(Spanned::new(span, x)),
        ref v => Err(serde::de::Error::custom(format!(
            "expected one number (or a list of one), found a list of {}; one steady-state epsilon per scene",
            v.len()
        ))),
    }
}

/// A scene that cannot be used, with the place and the problem.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read (not a regular file, too large, not
    /// text: [`ssm_model_files::input`]).
    #[error("cannot read the scene: {0}")]
    Read(#[from] InputError),
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
    /// Which model (also the input of a reducer that needs one).
    #[serde(default)]
    pub model: Option<ModelSection>,
    /// A reducer producing the model the analyses run on.
    #[serde(default)]
    pub reduce: Option<ReduceSection>,
    /// Sampled signals for a reducer.
    #[serde(default)]
    pub data: Option<DataSection>,
    /// SSM settings.
    #[serde(default)]
    pub ssm: SsmSection,
    /// Eigen-solver settings.
    #[serde(default)]
    pub spectrum: SpectrumSection,
    /// Requested outputs.
    #[serde(default)]
    pub outputs: OutputsSection,
    /// Harmonic forcing and forced response curves.
    #[serde(default)]
    pub forcing: Option<ForcingSection>,
    /// Full-system references.
    #[serde(default)]
    pub validate: Option<ValidateSection>,
    /// Speed-against-error report.
    #[serde(default)]
    pub report: Option<ReportSection>,
    /// Sampled full-system runs written as `[data]` CSV files.
    #[serde(default)]
    pub simulate: Option<SimulateSection>,
    /// POD reduction with constraint reduction, compared with the full model.
    #[serde(default)]
    pub pod: Option<PodSection>,
    /// The full system's forced response by harmonic balance.
    #[serde(default)]
    pub reference: Option<ReferenceSection>,
    /// Analyses added as slices, `[analysis.<name>]` (see
    /// [`crate::analyses`]); read and checked by [`crate::plan`].
    #[serde(default)]
    pub analysis: std::collections::BTreeMap<String, Spanned<toml::Table>>,
}

/// `[forcing]`: forced response curves of the periodic SSM. The load's shape is
/// the model's `Fext` (e.g. the plugin parameter `f1`); `epsilon` scales it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForcingSection {
    /// Forcing amplitudes, one FRC each (a number or a list).
    #[serde(deserialize_with = "number_or_list")]
    pub epsilon: Spanned<Vec<f64>>,
    /// `[Omega_min, Omega_max]`.
    pub omega_range: Spanned<Vec<f64>>,
    /// Expansion orders of the reduced dynamics, one FRC each (default: `[ssm] order`).
    #[serde(default)]
    pub orders: Option<Spanned<Vec<usize>>>,
    /// External resonance ratios `r` of eq. (16), one per master pair
    /// (default: 1 for a single pair).
    #[serde(default)]
    pub resonance: Option<Spanned<Vec<f64>>>,
    /// Points per side of each FRC branch.
    #[serde(default = "default_frc_points")]
    pub points: Spanned<usize>,
    /// Largest polar amplitude searched for branches (default: three times the
    /// linear peak amplitude at the largest epsilon).
    #[serde(default)]
    pub rho_max: Option<Spanned<f64>>,
    /// Order in `p` of the non-autonomous terms `O(eps |p|^k)` (0: the leading
    /// order `X0`, `S0` of the paper).
    #[serde(default)]
    pub nonautonomous_order: Option<Spanned<usize>>,
}

fn default_frc_points() -> Spanned<usize> {
    Spanned::new(0..0, FrcSpec::DEFAULT_POINTS)
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

/// `[ssm]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SsmSection {
    /// 1-based master mode pairs, slowest first.
    #[serde(default = "default_master_pairs")]
    pub master_pairs: Spanned<Vec<usize>>,
    /// Expansion order; without it the engine chooses the lowest odd order
    /// from 3 up to `SsmSpec::AUTO_MAX_ORDER` (and the machine's limits) whose
    /// answers meet `tolerance`.
    #[serde(default)]
    pub order: Option<Spanned<usize>>,
    /// Eigenvector scaling.
    #[serde(default)]
    pub normalization: Normalization,
    /// Relative distance `|a.lambda + b.conj(lambda) - lambda_k| / |lambda_k|`
    /// below which a combination counts as a (near) resonance.
    #[serde(default = "default_resonance_tol")]
    pub resonance_tol: Spanned<f64>,
    /// Accuracy target: the relative error an answer may have before it is
    /// flagged (and up to which the non-autonomous order is raised).
    #[serde(default = "default_tolerance")]
    pub tolerance: Spanned<f64>,
}

fn default_master_pairs() -> Spanned<Vec<usize>> {
    Spanned::new(0..0, vec![1])
}
fn default_resonance_tol() -> Spanned<f64> {
    Spanned::new(0..0, ssm_core::spec::SsmSpec::DEFAULT_RESONANCE_TOL)
}
fn default_tolerance() -> Spanned<f64> {
    Spanned::new(0..0, ssm_core::spec::SsmSpec::DEFAULT_TOLERANCE)
}

impl Default for SsmSection {
    fn default() -> Self {
        Self {
            master_pairs: default_master_pairs(),
            order: None,
            normalization: Normalization::Unit,
            resonance_tol: default_resonance_tol(),
            tolerance: default_tolerance(),
        }
    }
}

/// Eigen-solver choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SpectrumMethod {
    /// Dense path up to [`ssm_core::spectrum::DENSE_LIMIT`] states, sparse above.
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
    /// `[outputs.invariance_error]`: eq. (41) at given radii and orders.
    #[serde(default)]
    pub invariance_error: Option<InvarianceErrorSection>,
    /// `[outputs.backbone]`: backbone curves (one master pair).
    #[serde(default)]
    pub backbone: Option<BackboneSection>,
    /// `[outputs.transient]`: reduced-model trajectory lifted to the outputs.
    #[serde(default)]
    pub transient: Option<TransientSection>,
}

impl Default for OutputsSection {
    fn default() -> Self {
        Self {
            coordinates: empty_list(),
            invariance_error: None,
            backbone: None,
            transient: None,
        }
    }
}

/// `[outputs.invariance_error]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InvarianceErrorSection {
    /// Radii `varrho` of the sampling spheres.
    pub radii: Spanned<Vec<f64>>,
    /// Expansion orders to evaluate (each at most `[ssm] order`).
    pub orders: Spanned<Vec<usize>>,
    /// Amplitude angles per pair after the first (eq. 40).
    #[serde(default = "default_n_alpha")]
    pub n_alpha: Spanned<usize>,
    /// Phases per pair (eq. 40).
    #[serde(default = "default_n_theta")]
    pub n_theta: Spanned<usize>,
}

/// `[outputs.backbone]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BackboneSection {
    /// Largest polar amplitude `rho`.
    pub rho_max: Spanned<f64>,
    /// Number of amplitudes in `[0, rho_max]`.
    #[serde(default = "default_points")]
    pub points: Spanned<usize>,
    /// Expansion orders, one curve each (default: `[ssm] order`).
    #[serde(default)]
    pub orders: Option<Spanned<Vec<usize>>>,
}

/// `[outputs.transient]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransientSection {
    /// Initial polar amplitude of each master pair.
    pub rho0: Spanned<Vec<f64>>,
    /// Initial phase of each master pair (default 0).
    #[serde(default)]
    pub theta0: Option<Spanned<Vec<f64>>>,
    /// Final time.
    pub t_end: Spanned<f64>,
    /// Number of output samples.
    #[serde(default = "default_samples")]
    pub samples: Spanned<usize>,
    /// Expansion order of the reduced model (default: `[ssm] order`).
    #[serde(default)]
    pub order: Option<Spanned<usize>>,
    /// Relative tolerance of the integrator.
    #[serde(default = "default_rtol")]
    pub rtol: Spanned<f64>,
}

fn default_n_alpha() -> Spanned<usize> {
    Spanned::new(0..0, InvarianceSpec::DEFAULT_N_ALPHA)
}
fn default_n_theta() -> Spanned<usize> {
    Spanned::new(0..0, InvarianceSpec::DEFAULT_N_THETA)
}
fn default_points() -> Spanned<usize> {
    Spanned::new(0..0, BackboneSpec::DEFAULT_POINTS)
}
fn default_samples() -> Spanned<usize> {
    Spanned::new(0..0, TransientSpec::DEFAULT_SAMPLES)
}
fn default_rtol() -> Spanned<f64> {
    Spanned::new(0..0, TransientSpec::DEFAULT_RTOL)
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
        let text = InputFile::open(path, input::SCENE)?.read_text()?;
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

    /// A periodic orbit's `start` (of `key`) names `"rest"` or `"ssm"`.
    pub(crate) fn check_start(
        &self,
        start: Option<&Spanned<String>>,
        key: &str,
    ) -> Result<(), SceneError> {
        match start.map(|st| (st, st.get_ref().as_str())) {
            Some((st, other)) if other != "rest" && other != "ssm" => Err(self.invalid(
                st.span(),
                key,
                format!("unknown start \"{other}\"; expected \"rest\" or \"ssm\""),
            )),
            _ => Ok(()),
        }
    }

    /// The checks of the scene's shape that its specs cannot make (which
    /// keys go together, lists of two numbers, names of starts); the
    /// values are checked by the specs' own checks when the scene is
    /// resolved (`ssm_engine::plan::of_scene`), at the same keys and lines.
    fn check_generic(&self) -> Result<(), SceneError> {
        self.check_model_source()?;
        self.check_unique_names()?;
        if let Some(f) = &self.scene.forcing {
            let r = f.omega_range.get_ref();
            if r.len() != 2 {
                return Err(self.invalid(
                    f.omega_range.span(),
                    "forcing.omega_range",
                    format!(
                        "must be [Omega_min, Omega_max] with 0 < Omega_min < Omega_max, found {r:?}"
                    ),
                ));
            }
        }
        self.check_validate()?;
        self.check_simulate()?;
        self.check_pod()?;
        self.check_reference()
    }
}

/// The `(state name, value)` pairs of given-start tables (`x0`, `v0`);
/// a value that is not a number comes out as NaN (the section checks refuse it).
pub(crate) fn given_values<'a>(
    tables: impl IntoIterator<Item = &'a toml::Table>,
) -> Vec<(String, f64)> {
    tables
        .into_iter()
        .flat_map(|t| {
            t.iter().map(|(k, v)| {
                (
                    k.clone(),
                    v.as_float()
                        .or(v.as_integer().map(|i| i as f64))
                        .unwrap_or(f64::NAN),
                )
            })
        })
        .collect()
}

/// 1-based line of byte offset `pos` in `text`.
pub fn line_of(text: &str, pos: usize) -> usize {
    text[..pos.min(text.len())]
        .bytes()
        .filter(|&b| b == b'\n')
        .count()
        + 1
}
