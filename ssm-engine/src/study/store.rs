//! A study's store: a directory holding `study.json` (which study it holds)
//! and one Parquet file per finished point under `points/`, each written
//! under a temporary name and renamed, so a reader sees a whole record or
//! none; `table.parquet` is the merged table.
//!
//! The layout is the one the Python package's studies write (pyarrow reads
//! and writes the same files): a record is one row whose columns are
//! nullable booleans, 64-bit integers, doubles or UTF-8 strings (lists as
//! JSON text), and a value without a type (a missing figure) a column of
//! the Parquet `Null` logical type, as pyarrow writes `None`.
//!
//! # References
//! Apache Parquet format specification (logical types `STRING`, `UNKNOWN`).

use std::collections::BTreeSet;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use parquet::basic::{LogicalType, Repetition, Type as PhysicalType};
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int32Type, Int64Type};
use parquet::file::properties::WriterProperties;
use parquet::file::reader::SerializedFileReader;
use parquet::file::writer::SerializedFileWriter;
use parquet::record::Field;
use parquet::schema::types::Type;

/// The layout version of `study.json`.
pub const STORE_VERSION: u64 = 1;

/// One value of a record.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// No value, of no type (a figure the run did not produce).
    Null,
    /// A boolean.
    Bool(bool),
    /// An integer.
    Int(i64),
    /// A double (NaN and infinities kept).
    Float(f64),
    /// A string.
    Text(String),
    /// A list of numbers (written as JSON text, a non-finite one as
    /// `null`).
    List(Vec<f64>),
}

impl Cell {
    /// A list as its JSON text.
    fn list_text(values: &[f64]) -> String {
        let items: Vec<String> = values
            .iter()
            .map(|v| {
                if v.is_finite() {
                    serde_json::Value::from(*v).to_string()
                } else {
                    "null".into()
                }
            })
            .collect();
        format!("[{}]", items.join(", "))
    }
}

/// A record: the columns of one point, in order.
pub type Record = Vec<(String, Cell)>;

/// What went wrong with a store.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// A file of the store cannot be read or written.
    #[error("store: {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A record file is not a Parquet file of the store's layout.
    #[error("store: {path}: {message}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The store holds another study, or something that is not a store.
    #[error("store: {0}")]
    Other(String),
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.to_owned(),
        source,
    }
}

fn format(path: &Path) -> impl FnOnce(parquet::errors::ParquetError) -> StoreError + '_ {
    move |e| StoreError::Format {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

/// The type of a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Null,
    Bool,
    Int,
    Float,
    Text,
}

impl Kind {
    fn of(cell: &Cell) -> Kind {
        match cell {
            Cell::Null => Kind::Null,
            Cell::Bool(_) => Kind::Bool,
            Cell::Int(_) => Kind::Int,
            Cell::Float(_) => Kind::Float,
            Cell::Text(_) | Cell::List(_) => Kind::Text,
        }
    }

    /// The type that holds both: a missing value takes the other's type,
    /// an integer column with a number becomes a number column, any other
    /// mix a text column.
    fn join(self, other: Kind) -> Kind {
        match (self, other) {
            (a, b) if a == b => a,
            (Kind::Null, b) => b,
            (a, Kind::Null) => a,
            (Kind::Int, Kind::Float) | (Kind::Float, Kind::Int) => Kind::Float,
            _ => Kind::Text,
        }
    }

    fn parquet(self, name: &str) -> parquet::errors::Result<Type> {
        let (physical, logical) = match self {
            Kind::Null => (PhysicalType::INT32, Some(LogicalType::Unknown)),
            Kind::Bool => (PhysicalType::BOOLEAN, None),
            Kind::Int => (PhysicalType::INT64, None),
            Kind::Float => (PhysicalType::DOUBLE, None),
            Kind::Text => (PhysicalType::BYTE_ARRAY, Some(LogicalType::String)),
        };
        Type::primitive_type_builder(name, physical)
            .with_repetition(Repetition::OPTIONAL)
            .with_logical_type(logical)
            .build()
    }
}

/// Writes `rows` (each the same columns `names`, of the types `kinds`) as
/// one Parquet row group to `file`.
fn write_rows(
    file: File,
    names: &[String],
    kinds: &[Kind],
    rows: &[Vec<Cell>],
) -> parquet::errors::Result<()> {
    let fields = names
        .iter()
        .zip(kinds)
        .map(|(n, k)| k.parquet(n).map(Arc::new))
        .collect::<parquet::errors::Result<Vec<_>>>()?;
    let schema = Arc::new(
        Type::group_type_builder("schema")
            .with_fields(fields)
            .build()?,
    );
    let props = Arc::new(WriterProperties::builder().build());
    let mut writer = SerializedFileWriter::new(file, schema, props)?;
    let mut group = writer.next_row_group()?;
    for (j, kind) in kinds.iter().enumerate() {
        let Some(mut column) = group.next_column()? else {
            break;
        };
        let cells = rows.iter().map(|r| &r[j]);
        let levels: Vec<i16> = cells.clone().map(|c| i16::from(*c != Cell::Null)).collect();
        // the values of a column of `T` (missing ones only in `levels`)
        fn values<'c, T>(
            cells: impl Iterator<Item = &'c Cell>,
            of: impl Fn(&Cell) -> Option<T>,
        ) -> Vec<T> {
            cells.filter_map(of).collect()
        }
        match kind {
            Kind::Null => {
                let none: [i32; 0] = [];
                column
                    .typed::<Int32Type>()
                    .write_batch(&none, Some(&levels), None)?;
            }
            Kind::Bool => {
                let v = values(cells, |c| match c {
                    Cell::Bool(b) => Some(*b),
                    _ => None,
                });
                column
                    .typed::<BoolType>()
                    .write_batch(&v, Some(&levels), None)?;
            }
            Kind::Int => {
                let v = values(cells, |c| match c {
                    Cell::Int(i) => Some(*i),
                    _ => None,
                });
                column
                    .typed::<Int64Type>()
                    .write_batch(&v, Some(&levels), None)?;
            }
            // an integer column joined with numbers holds numbers
            Kind::Float => {
                let v = values(cells, |c| match c {
                    Cell::Float(x) => Some(*x),
                    Cell::Int(i) => Some(*i as f64),
                    _ => None,
                });
                column
                    .typed::<DoubleType>()
                    .write_batch(&v, Some(&levels), None)?;
            }
            // text, lists as JSON, and the values of a column of mixed ones
            Kind::Text => {
                let v = values(cells, |c| {
                    let text = match c {
                        Cell::Null => return None,
                        Cell::Text(s) => s.clone(),
                        Cell::List(v) => Cell::list_text(v),
                        Cell::Bool(b) => b.to_string(),
                        Cell::Int(i) => i.to_string(),
                        Cell::Float(x) => {
                            Cell::list_text(&[*x]).trim_matches(['[', ']']).to_owned()
                        }
                    };
                    Some(ByteArray::from(text.as_str()))
                });
                column
                    .typed::<ByteArrayType>()
                    .write_batch(&v, Some(&levels), None)?;
            }
        }
        column.close()?;
    }
    group.close()?;
    writer.close()?;
    Ok(())
}

/// Writes `file` through a temporary file beside it, renamed over it at
/// the end: a reader sees the old file, the whole new one, or none.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(File) -> parquet::errors::Result<()>,
) -> Result<(), StoreError> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.{}.{}.tmp", std::process::id(), unique()));
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(io(&tmp))?;
    let written = write(file).map_err(format(path));
    let result = written.and_then(|()| std::fs::rename(&tmp, path).map_err(io(path)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// A number no other call of this process gets.
fn unique() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// Writes `record` as a one-row Parquet file at `path`, atomically.
///
/// # Errors
/// The file cannot be written ([`StoreError::Io`], [`StoreError::Format`]).
pub fn write_record(path: &Path, record: &Record) -> Result<(), StoreError> {
    let names: Vec<String> = record.iter().map(|(n, _)| n.clone()).collect();
    let kinds: Vec<Kind> = record.iter().map(|(_, c)| Kind::of(c)).collect();
    let row = vec![record.iter().map(|(_, c)| c.clone()).collect()];
    write_atomically(path, |file| write_rows(file, &names, &kinds, &row))
}

/// The rows of the Parquet file at `path`, each as a record.
///
/// # Errors
/// The file cannot be read, is not a regular file, or holds a column of a type the store does not
/// write (nested, binary, dates).
pub fn read_records(path: &Path) -> Result<Vec<Record>, StoreError> {
    // a store's records are regular files: a link planted among them is not
    // followed
    let meta = std::fs::symlink_metadata(path).map_err(io(path))?;
    if !meta.is_file() {
        return Err(StoreError::Format {
            path: path.to_owned(),
            message: "not a regular file (a link, a directory or a device)".into(),
        });
    }
    let file = File::open(path).map_err(io(path))?;
    let reader = SerializedFileReader::new(file).map_err(format(path))?;
    let mut rows = Vec::new();
    for row in reader {
        let row = row.map_err(format(path))?;
        let mut record = Record::new();
        for (name, field) in row.get_column_iter() {
            let cell = match field {
                Field::Null => Cell::Null,
                Field::Bool(b) => Cell::Bool(*b),
                Field::Byte(i) => Cell::Int(i64::from(*i)),
                Field::Short(i) => Cell::Int(i64::from(*i)),
                Field::Int(i) => Cell::Int(i64::from(*i)),
                Field::Long(i) => Cell::Int(*i),
                Field::UByte(i) => Cell::Int(i64::from(*i)),
                Field::UShort(i) => Cell::Int(i64::from(*i)),
                Field::UInt(i) => Cell::Int(i64::from(*i)),
                Field::Float(x) => Cell::Float(f64::from(*x)),
                Field::Double(x) => Cell::Float(*x),
                Field::Str(s) => Cell::Text(s.clone()),
                other => {
                    return Err(StoreError::Format {
                        path: path.to_owned(),
                        message: format!(
                            "column '{name}' holds {other:?}, not a value a study writes"
                        ),
                    })
                }
            };
            record.push((name.clone(), cell));
        }
        rows.push(record);
    }
    Ok(rows)
}

/// Writes `records` as one table at `path`, atomically: the union of
/// their columns in the order first seen, a column missing from a record
/// empty there; a column's type is the one its values share (an integer
/// column with a number in it becomes a number column, a column of text
/// and numbers a text column).
///
/// # Errors
/// The file cannot be written.
pub fn write_table(path: &Path, records: &[Record]) -> Result<(), StoreError> {
    let mut names: Vec<String> = Vec::new();
    let mut kinds: Vec<Kind> = Vec::new();
    for r in records {
        for (name, cell) in r {
            let kind = Kind::of(cell);
            match names.iter().position(|n| n == name) {
                None => {
                    names.push(name.clone());
                    kinds.push(kind);
                }
                Some(j) => kinds[j] = kinds[j].join(kind),
            }
        }
    }
    let rows: Vec<Vec<Cell>> = records
        .iter()
        .map(|r| {
            names
                .iter()
                .map(|n| {
                    r.iter()
                        .find(|(m, _)| m == n)
                        .map_or(Cell::Null, |(_, c)| c.clone())
                })
                .collect()
        })
        .collect();
    write_atomically(path, |file| write_rows(file, &names, &kinds, &rows))
}

/// What `study.json` says: the layout version, the study's fingerprint,
/// its number of points and, for a grid, its parameters.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Meta {
    /// [`STORE_VERSION`].
    pub version: u64,
    /// What identifies the study.
    pub fingerprint: String,
    /// Its number of points.
    pub points: usize,
    /// A grid's parameters, in order (`None` for other points).
    pub dims: Option<Vec<String>>,
}

/// A store directory.
#[derive(Debug, Clone)]
pub struct Store {
    dir: PathBuf,
}

impl Store {
    /// Creates the store `dir` for the study `meta`, or checks that it
    /// holds that study. Several processes may open one store at once (the
    /// shards of a job array): `study.json` is written once, through a
    /// link that fails when another got there first.
    ///
    /// # Errors
    /// `dir` is a file, holds something else than a study, or holds
    /// another study.
    pub fn open(dir: &Path, meta: &Meta) -> Result<Store, StoreError> {
        let store = Store {
            dir: dir.to_owned(),
        };
        if let Some(held) = store.meta_if_any()? {
            return store.same(&held, meta);
        }
        if std::fs::symlink_metadata(dir).is_ok_and(|m| !m.is_dir()) {
            return Err(StoreError::Other(format!(
                "{} is not a directory",
                dir.display()
            )));
        }
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let foreign = std::fs::read_dir(dir)
            .map_err(io(dir))?
            .filter_map(Result::ok)
            .any(|e| !e.file_name().to_string_lossy().starts_with(".study.json."));
        if foreign {
            // another shard may have created it since
            return match store.meta_if_any()? {
                Some(held) => store.same(&held, meta),
                None => Err(StoreError::Other(format!(
                    "{} is not empty and holds no study; give an empty or new directory",
                    dir.display()
                ))),
            };
        }
        let text = serde_json::to_string(meta).map_err(|e| StoreError::Other(e.to_string()))?;
        let path = store.meta_path();
        let tmp = dir.join(format!(
            ".study.json.{}.{}.tmp",
            std::process::id(),
            unique()
        ));
        std::fs::write(&tmp, text).map_err(io(&tmp))?;
        let linked = std::fs::hard_link(&tmp, &path);
        let _ = std::fs::remove_file(&tmp);
        match linked {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let held = store.meta_if_any()?.ok_or_else(|| {
                    StoreError::Other(format!("{} vanished while opening", path.display()))
                })?;
                store.same(&held, meta)?;
            }
            Err(e) => return Err(io(&path)(e)),
        }
        let points = store.points_dir();
        std::fs::create_dir_all(&points).map_err(io(&points))?;
        Ok(store)
    }

    /// The store at `dir` as it is, with what its `study.json` says.
    ///
    /// # Errors
    /// `dir` holds no study.
    pub fn existing(dir: &Path) -> Result<(Store, Meta), StoreError> {
        let store = Store {
            dir: dir.to_owned(),
        };
        let meta = store.meta_if_any()?.ok_or_else(|| {
            StoreError::Other(format!("{} holds no study (no study.json)", dir.display()))
        })?;
        Ok((store, meta))
    }

    fn same(&self, held: &Meta, meta: &Meta) -> Result<Store, StoreError> {
        if held.version != meta.version || held.fingerprint != meta.fingerprint {
            return Err(StoreError::Other(format!(
                "{} holds another study (fingerprint {}, this one {}); give another store",
                self.dir.display(),
                held.fingerprint,
                meta.fingerprint
            )));
        }
        let points = self.points_dir();
        std::fs::create_dir_all(&points).map_err(io(&points))?;
        Ok(self.clone())
    }

    fn meta_path(&self) -> PathBuf {
        self.dir.join("study.json")
    }

    fn points_dir(&self) -> PathBuf {
        self.dir.join("points")
    }

    fn meta_if_any(&self) -> Result<Option<Meta>, StoreError> {
        let path = self.meta_path();
        match std::fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) if e.kind() == std::io::ErrorKind::NotADirectory => {
                return Err(StoreError::Other(format!(
                    "{} is not a directory",
                    self.dir.display()
                )))
            }
            Err(e) => return Err(io(&path)(e)),
            Ok(m) if !m.is_file() => {
                return Err(StoreError::Other(format!(
                    "{} is not a study's file (a link, a directory or a device)",
                    path.display()
                )))
            }
            Ok(_) => {}
        }
        let text = std::fs::read_to_string(&path).map_err(io(&path))?;
        serde_json::from_str(&text)
            .map(Some)
            .map_err(|e| StoreError::Format {
                path,
                message: format!("not a study's description: {e}"),
            })
    }

    /// The record file of point `index`.
    pub fn record_path(&self, index: usize) -> PathBuf {
        self.points_dir().join(format!("{index:08}.parquet"))
    }

    /// The merged table.
    pub fn table_path(&self) -> PathBuf {
        self.dir.join("table.parquet")
    }

    /// The points the store holds a record of.
    ///
    /// # Errors
    /// `points/` cannot be listed.
    pub fn done(&self) -> Result<BTreeSet<usize>, StoreError> {
        let dir = self.points_dir();
        let entries = match std::fs::read_dir(&dir) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(BTreeSet::new()),
            other => other.map_err(io(&dir))?,
        };
        Ok(entries
            .filter_map(Result::ok)
            // a link planted under a record's name is no record
            .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                let stem = name.strip_suffix(".parquet")?;
                stem.bytes()
                    .all(|b| b.is_ascii_digit())
                    .then(|| stem.parse().ok())?
            })
            .collect())
    }
}
