//! Studies without Python: a study file names a base scene (its model and
//! its analyses) and a set of points (a grid, given points, or a seeded
//! sample over parameter ranges), and `ssm-engine study` runs one slice of
//! them (`--shard I/N`, for one task of a job array), each finished point
//! written at once to a store, then gathers the store into one table
//! (`--merge`).
//!
//! A point sets model parameters (`model.<name>`, passed to the plugin
//! over the scene's `[model.params]`) and plan values (`<section>.<key>`
//! of the engine's [`Plan`], e.g. `frc.epsilon`, `ssm.order`,
//! `frc.omega_range`), exactly as a point of the Python package's
//! `ssm.study` does; both doors write the same store (see [`store`]) and
//! the same figures ([`figures::figures`]).
//!
//! ```toml
//! scene = "../spatial_oscillator_frc.toml"   # relative to this file
//! backbone_at = [0.1]                         # optional figures
//!
//! [[grid]]
//! parameter = "frc.epsilon"
//! values = [0.005, 0.01]
//!
//! [[grid]]
//! parameter = "model.zeta1"
//! values = [0.01, 0.02]
//! ```
//! or `[[point]]` tables (`frc.epsilon = 0.01`, `model.zeta1 = 0.02`), or
//! `[sample]` with `n`, `seed` and `ranges` (`"model.zeta1" = [0.01,
//! 0.03]`).

pub mod figures;
pub mod points;
pub mod store;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Deserialize;
use serde_json::Value;
use sha2::{Digest, Sha256};

use crate::pipeline::{self, JobError, Model, Progress};
use crate::plan::{self, budget::Limits, Plan};
use crate::scene::{SceneError, SceneFile};
use points::{Points, PointsError};
use ssm_core::model::plugin::Registry;
use ssm_model_files::input::{self, InputFile};
use store::{Cell, Meta, Record, Store, StoreError, STORE_VERSION};

/// Why a study cannot run.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The study file cannot be read or is malformed.
    #[error("{path}: {message}")]
    File {
        /// The study file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Its base scene cannot be read or is malformed.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Its points are not valid.
    #[error("{path}: {source}")]
    Points {
        /// The study file.
        path: PathBuf,
        /// What is wrong.
        source: PointsError,
    },
    /// The store cannot be used.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// `--shard I/N` is not a slice.
    #[error("shard: {0}")]
    Shard(String),
    /// The store lacks points a merge needs.
    #[error("store: {missing} of {points} points have no record yet ({first}); run their shards again (the store keeps the others)")]
    Missing {
        /// How many.
        missing: usize,
        /// Of how many.
        points: usize,
        /// The first few, 0-based.
        first: String,
    },
}

/// The study file's layout.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyToml {
    scene: String,
    #[serde(default)]
    backbone_at: Vec<f64>,
    #[serde(default)]
    grid: Vec<AxisToml>,
    #[serde(default)]
    point: Vec<toml::Table>,
    #[serde(default)]
    sample: Option<SampleToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisToml {
    parameter: String,
    values: Vec<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SampleToml {
    n: usize,
    seed: u64,
    ranges: toml::Table,
}

/// A study read from its file: the base scene, its plan, the points.
#[derive(Debug)]
pub struct StudyFile {
    /// The study file.
    pub path: PathBuf,
    /// The base scene.
    pub scene: SceneFile,
    /// The base scene's plan (checked against the model when each point
    /// runs).
    pub plan: Plan,
    /// The points.
    pub points: Points,
    /// The backbone amplitudes of the figures.
    pub backbone_at: Vec<f64>,
    /// What identifies the study in a store.
    pub fingerprint: String,
}

/// `value` (a study file's) as JSON; NaN, infinities and dates refused.
fn json_of(name: &str, value: &toml::Value) -> Result<Value, PointsError> {
    Ok(match value {
        toml::Value::String(s) => Value::from(s.clone()),
        toml::Value::Integer(i) => Value::from(*i),
        toml::Value::Float(x) if x.is_finite() => Value::from(*x),
        toml::Value::Float(x) => {
            return Err(PointsError(format!("'{name}' = {x}: give a finite number")))
        }
        toml::Value::Boolean(b) => Value::from(*b),
        toml::Value::Array(items) => Value::Array(
            items
                .iter()
                .map(|v| json_of(name, v))
                .collect::<Result<_, _>>()?,
        ),
        toml::Value::Datetime(_) => {
            return Err(PointsError(format!("'{name}' is a date; give a number")))
        }
        toml::Value::Table(_) => {
            return Err(PointsError(format!(
                "'{name}' is a table; give a number, a string, a boolean or a list"
            )))
        }
    })
}

/// A table of parameters as `name = value` pairs: `frc.epsilon = 0.01`
/// (a dotted key: a table `frc` holding `epsilon`) and `"frc.epsilon" =
/// 0.01` alike.
fn flatten(table: &toml::Table) -> Vec<(String, &toml::Value)> {
    let mut out = Vec::new();
    for (head, value) in table {
        match value {
            toml::Value::Table(inner) if !head.contains('.') => {
                out.extend(inner.iter().map(|(k, v)| (format!("{head}.{k}"), v)));
            }
            _ => out.push((head.clone(), value)),
        }
    }
    out
}

impl StudyFile {
    /// Reads the study file at `path` and its base scene; checks its
    /// points (names, values, and each plan value against the plan).
    ///
    /// # Errors
    /// The file or its scene cannot be read or is malformed, a point is
    /// not valid.
    pub fn load(path: &Path) -> Result<StudyFile, StudyError> {
        let text = InputFile::open(path, input::SCENE)
            .and_then(|mut f| f.read_text())
            .map_err(SceneError::from)?;
        let file_error = |message: String| StudyError::File {
            path: path.to_owned(),
            message,
        };
        let points_error = |source: PointsError| StudyError::Points {
            path: path.to_owned(),
            source,
        };
        let raw: toml::Table =
            toml::from_str(&text).map_err(|e| file_error(e.message().to_owned()))?;
        let study: StudyToml =
            toml::from_str(&text).map_err(|e| file_error(e.message().to_owned()))?;
        let scene_path = path.parent().unwrap_or(Path::new(".")).join(&study.scene);
        let scene = SceneFile::load(&scene_path)?;
        let plan = plan::of_scene(&scene)?;
        let limits = Limits::of_machine();
        if let Some(bad) = study
            .backbone_at
            .iter()
            .find(|a| !a.is_finite() || **a < 0.0)
        {
            return Err(file_error(format!(
                "backbone_at: {bad} is not a polar amplitude (give finite values >= 0)"
            )));
        }
        let given = [
            !study.grid.is_empty(),
            !study.point.is_empty(),
            study.sample.is_some(),
        ];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(file_error(
                "give the points one way: [[grid]] tables, [[point]] tables, or [sample]".into(),
            ));
        }
        let points = if !study.grid.is_empty() {
            let axes = study
                .grid
                .iter()
                .map(|a| {
                    let values = a
                        .values
                        .iter()
                        .map(|v| json_of(&a.parameter, v))
                        .collect::<Result<Vec<_>, _>>()?;
                    Ok((a.parameter.clone(), values))
                })
                .collect::<Result<Vec<_>, PointsError>>()
                .map_err(points_error)?;
            points::grid(axes, &limits).map_err(points_error)?
        } else if let Some(s) = &study.sample {
            let ranges = flatten(&s.ranges)
                .into_iter()
                .map(|(name, v)| match json_of(&name, v)? {
                    Value::Array(b) if b.len() == 2 && b.iter().all(Value::is_number) => Ok((
                        name,
                        b[0].as_f64().unwrap_or(f64::NAN),
                        b[1].as_f64().unwrap_or(f64::NAN),
                    )),
                    _ => Err(PointsError(format!(
                        "the range of '{name}': give [low, high]"
                    ))),
                })
                .collect::<Result<Vec<_>, _>>()
                .map_err(points_error)?;
            points::sample(ranges, s.n, s.seed, &limits).map_err(points_error)?
        } else {
            let values = study
                .point
                .iter()
                .map(|t| {
                    flatten(t)
                        .into_iter()
                        .map(|(n, v)| Ok((n.clone(), json_of(&n, v)?)))
                        .collect::<Result<Vec<_>, _>>()
                })
                .collect::<Result<Vec<_>, PointsError>>()
                .map_err(points_error)?;
            points::given(values).map_err(points_error)?
        };
        check_plan_values(&plan, &points).map_err(points_error)?;
        if !points
            .values
            .iter()
            .flatten()
            .all(|(n, _)| !n.starts_with("model."))
            && scene.scene.model.is_none()
        {
            return Err(file_error(format!(
                "model.<parameter>: the scene {} has no [model] whose parameters a point could set",
                scene_path.display()
            )));
        }
        let description = serde_json::json!({
            "version": STORE_VERSION,
            "scene": scene.text,
            "study": raw,
        });
        let fingerprint = Sha256::digest(description.to_string().as_bytes())
            .iter()
            .take(8)
            .map(|b| format!("{b:02x}"))
            .collect();
        Ok(StudyFile {
            path: path.to_owned(),
            scene,
            plan,
            points,
            backbone_at: study.backbone_at,
            fingerprint,
        })
    }

    /// What the store's `study.json` says of this study.
    pub fn meta(&self) -> Meta {
        Meta {
            version: STORE_VERSION,
            fingerprint: self.fingerprint.clone(),
            points: self.points.values.len(),
            dims: self
                .points
                .dims
                .as_ref()
                .map(|d| d.iter().map(|(n, _)| n.clone()).collect()),
        }
    }
}

/// Checks every plan value of `points` against `plan` before anything
/// runs: each value of a grid's axis alone, each given point, a sample's
/// first point.
fn check_plan_values(plan: &Plan, points: &Points) -> Result<(), PointsError> {
    let mut trials: Vec<Vec<(String, Value)>> = match &points.dims {
        Some(axes) => axes
            .iter()
            .flat_map(|(n, vals)| vals.iter().map(move |v| vec![(n.clone(), v.clone())]))
            .collect(),
        None if points.values.len() <= 10_000 => points.values.clone(),
        None => points.values[..1].to_vec(),
    };
    trials.retain(|p| p.iter().any(|(n, _)| !n.starts_with("model.")));
    for trial in trials {
        let at = points::plan_at(plan, &trial)?;
        at.validate().map_err(|e| {
            let names: Vec<&str> = trial.iter().map(|(n, _)| n.as_str()).collect();
            PointsError(format!("{}: {}: {}", names.join(", "), e.key, e.problem))
        })?;
    }
    Ok(())
}

/// The `I/N` of `--shard` (1-based: `1/4` to `4/4`).
///
/// # Errors
/// Not two integers with `1 <= I <= N`.
pub fn parse_shard(text: &str) -> Result<(usize, usize), StudyError> {
    let bad = || {
        StudyError::Shard(format!(
            "'{text}' is not a slice: give I/N with 1 <= I <= N (e.g. $SLURM_ARRAY_TASK_ID/4 with --array=1-4)"
        ))
    };
    let (i, n) = text.split_once('/').ok_or_else(bad)?;
    let (i, n): (usize, usize) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if i == 0 || i > n {
        return Err(bad());
    }
    Ok((i, n))
}

/// What a shard did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShardReport {
    /// Points of the shard.
    pub points: usize,
    /// Of which the store held a record already.
    pub skipped: usize,
    /// Of which were computed now.
    pub computed: usize,
    /// Of the computed, those that failed (their error is their record).
    pub failed: usize,
}

/// A record's value of a point's parameter.
fn cell_of(value: &Value) -> Cell {
    match value {
        Value::Bool(b) => Cell::Bool(*b),
        Value::Number(n) => n
            .as_i64()
            .map_or_else(|| Cell::Float(n.as_f64().unwrap_or(f64::NAN)), Cell::Int),
        Value::String(s) => Cell::Text(s.clone()),
        Value::Null => Cell::Null,
        other => Cell::Text(other.to_string()),
    }
}

/// A plugin's parameter value as TOML.
fn toml_of(value: &Value) -> toml::Value {
    match value {
        Value::Bool(b) => toml::Value::Boolean(*b),
        Value::Number(n) => n.as_i64().map_or_else(
            || toml::Value::Float(n.as_f64().unwrap_or(f64::NAN)),
            toml::Value::Integer,
        ),
        Value::String(s) => toml::Value::String(s.clone()),
        Value::Array(a) => toml::Value::Array(a.iter().map(toml_of).collect()),
        Value::Null | Value::Object(_) => toml::Value::String(value.to_string()),
    }
}

/// The class of `ssm.errors` a run's error belongs to (what a record's
/// `error_type` says, in both doors).
pub fn error_type(e: &JobError) -> &'static str {
    match e {
        JobError::Plan(_) | JobError::Scene(_) => "InputError",
        JobError::Model(_) | JobError::Plugin(_) => "ModelError",
        JobError::Spectrum(_) => "SpectrumError",
        JobError::Ssm(_) => "ExpansionError",
        _ => "AnalysisError",
    }
}

/// Runs point `index` of `study` on `model` and returns its record: the
/// point, its parameters (`param:<name>`), its figures or its error
/// (`error`, `error_type`), `seconds` and `warnings` (JSON text).
fn run_point(
    study: &StudyFile,
    index: usize,
    model: Result<&Model, &(String, &'static str)>,
    limits: &Limits,
    progress: &dyn Progress,
) -> Record {
    let point = &study.points.values[index];
    let started = Instant::now();
    let mut record: Record = vec![(
        "point".into(),
        Cell::Int(i64::try_from(index).unwrap_or(i64::MAX)),
    )];
    record.extend(
        point
            .iter()
            .map(|(n, v)| (format!("param:{n}"), cell_of(v))),
    );
    let outcome = model.map_err(Clone::clone).and_then(|model| {
        let plan =
            points::plan_at(&study.plan, point).map_err(|e| (e.to_string(), "InputError"))?;
        let job = pipeline::execute(&plan, model.clone(), limits, progress, started)
            .map_err(|e| (e.to_string(), error_type(&e)))?;
        let files = &job.outputs.files;
        let figures = figures::figures(files, &study.backbone_at)
            .map_err(|e| (e.to_string(), "AnalysisError"))?;
        Ok((figures, figures::warnings(files)))
    });
    let warnings = match outcome {
        Ok((figures, warnings)) => {
            record.extend(figures);
            record.push(("error".into(), Cell::Null));
            record.push(("error_type".into(), Cell::Null));
            warnings
        }
        Err((message, kind)) => {
            record.push(("error".into(), Cell::Text(message)));
            record.push(("error_type".into(), Cell::Text(kind.into())));
            Vec::new()
        }
    };
    record.push((
        "seconds".into(),
        Cell::Float(started.elapsed().as_secs_f64()),
    ));
    // JSON with the separators of Python's json.dumps, as the Python door writes it
    let warnings: Vec<String> = warnings
        .iter()
        .map(|w| Value::from(w.as_str()).to_string())
        .collect();
    record.push((
        "warnings".into(),
        Cell::Text(format!("[{}]", warnings.join(", "))),
    ));
    record
}

/// Runs the points of shard `shard` = `(I, N)` of `study` (those whose
/// 0-based index is `I - 1` modulo `N`) that `store` holds no record of,
/// each written to the store as it finishes; `note(index, record)` is
/// called after each. Points sharing model parameters run one after the
/// other on one model, built once.
///
/// # Errors
/// The store cannot be opened or written (a failing point is a record,
/// not an error).
pub fn run_shard(
    study: &StudyFile,
    store_dir: &Path,
    shard: (usize, usize),
    registry: &mut Registry,
    progress: &dyn Progress,
    note: &mut dyn FnMut(usize, &Record),
) -> Result<ShardReport, StudyError> {
    let store = Store::open(store_dir, &study.meta())?;
    let done = store.done()?;
    let (i, n) = shard;
    let mine: Vec<usize> = (0..study.points.values.len())
        .filter(|k| k % n == i - 1)
        .collect();
    // grouped by model: each model built once
    let mut todo: BTreeMap<String, Vec<usize>> = BTreeMap::new();
    for &k in mine.iter().filter(|k| !done.contains(k)) {
        let params = points::model_params(&study.points.values[k]);
        todo.entry(
            Value::from(
                params
                    .iter()
                    .map(|(n, v)| Value::from(vec![Value::from(n.clone()), v.clone()]))
                    .collect::<Vec<_>>(),
            )
            .to_string(),
        )
        .or_default()
        .push(k);
    }
    let limits = Limits::of_machine();
    let mut report = ShardReport {
        points: mine.len(),
        skipped: mine.iter().filter(|k| done.contains(k)).count(),
        computed: 0,
        failed: 0,
    };
    for indices in todo.values() {
        let params = points::model_params(&study.points.values[indices[0]]);
        let mut scene = study.scene.clone();
        if let Some(m) = scene.scene.model.as_mut() {
            for (name, value) in &params {
                m.params.get_mut().insert(name.clone(), toml_of(value));
            }
        }
        progress.stage("building model");
        let model =
            crate::job::scene_model(&scene, registry).map_err(|e| (e.to_string(), error_type(&e)));
        for &k in indices {
            let record = run_point(study, k, model.as_ref(), &limits, progress);
            store::write_record(&store.record_path(k), &record)?;
            report.computed += 1;
            report.failed +=
                usize::from(record.iter().any(|(n, c)| n == "error" && *c != Cell::Null));
            note(k, &record);
        }
    }
    Ok(report)
}

/// Gathers the records of `study`'s store into `table.parquet` (one row
/// per point, in the points' order) and returns its path and the number
/// of failed points.
///
/// # Errors
/// The store holds another study or lacks points, a record cannot be read,
/// a column holds text in one record and numbers in another.
pub fn merge(study: &StudyFile, store_dir: &Path) -> Result<(PathBuf, usize), StudyError> {
    let (store, meta) = Store::existing(store_dir)?;
    if meta.fingerprint != study.fingerprint || meta.version != STORE_VERSION {
        return Err(StoreError::Other(format!(
            "{} holds another study (fingerprint {}, this one {})",
            store_dir.display(),
            meta.fingerprint,
            study.fingerprint
        ))
        .into());
    }
    let done = store.done()?;
    let all: BTreeSet<usize> = (0..meta.points).collect();
    let missing: Vec<usize> = all.difference(&done).copied().collect();
    if !missing.is_empty() {
        let first: Vec<String> = missing.iter().take(8).map(usize::to_string).collect();
        return Err(StudyError::Missing {
            missing: missing.len(),
            points: meta.points,
            first: format!(
                "{}{}",
                first.join(", "),
                if missing.len() > 8 { ", ..." } else { "" }
            ),
        });
    }
    let mut records = Vec::with_capacity(meta.points);
    for k in 0..meta.points {
        let read = store::read_records(&store.record_path(k)).map_err(|e| match e {
            StoreError::Format { path, message } => StoreError::Format {
                path,
                message: format!("{message}; remove it and run its shard again"),
            },
            other => other,
        })?;
        records.extend(read);
    }
    let failed = records
        .iter()
        .filter(|r| r.iter().any(|(n, c)| n == "error" && *c != Cell::Null))
        .count();
    let path = store.table_path();
    store::write_table(&path, &records)?;
    Ok((path, failed))
}
