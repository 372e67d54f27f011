//! The checkpoint of a run's full-system reference: each continuation step
//! appended, as it is accepted, to a JSON-lines file beside the output
//! directory (`<out>.reference-checkpoint.jsonl`), so that a stopped run
//! (killed, out of time, a machine that went down) resumes where it stopped
//! and ends with what the uninterrupted run would have written.
//!
//! The file is a header line (format, engine version, the scene's name and
//! fingerprint), then one line per record: an accepted step of a
//! continuation run (its point with tangent and Floquet data, the events
//! located on the step, the next step size and the steps tried) or the end
//! of a run. Numbers are written in the shortest form that reads back to the
//! same bits. A fresh run creates its file with its first step, never over
//! an existing file (a stopped run's checkpoint stays for `--resume`: the new
//! one gets the process id in its name) and never through a link. A resumed
//! run reads the whole file first (a last line cut short by the stop is
//! dropped; any other line that does not read, or records out of order, are
//! an error naming the line), locks it against a second resume, and appends
//! its own steps to it, so that it can be stopped and resumed again.
//! Records only: the reading and writing of the file compute nothing.

use std::cell::{Cell, RefCell};
use std::collections::VecDeque;
use std::fs::{File, OpenOptions};
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use ssm_model_files::input::{escaped, excerpt, InputError, InputFile, Limit};

use ssm_core::fom::periodic::OrbitInfo;
use ssm_kernel::continuation::{crossed, Event, Ledger, Point, Step, Stop, Trace};

/// Version of the file's layout.
const FORMAT: u32 = 1;

/// The largest checkpoint read (it is read whole): 1 GiB.
pub(crate) const LIMIT: Limit = Limit {
    bytes: 1 << 30,
    what: "a reference checkpoint",
};

/// Why a checkpoint cannot be resumed from.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// There is no checkpoint to resume.
    #[error("no checkpoint to resume at {path} (a run writes it while it computes a [reference]; run without --resume)")]
    Missing {
        /// Where it was looked for.
        path: PathBuf,
    },
    /// The file cannot be read or written.
    #[error("checkpoint {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The failure.
        source: std::io::Error,
    },
    /// Another run holds the file.
    #[error(
        "checkpoint {path} is being resumed by another run (it is locked); wait for it or stop it"
    )]
    Busy {
        /// The file.
        path: PathBuf,
    },
    /// The path is not a regular file of its own (a symbolic or hard link,
    /// a FIFO, a directory), or it is too large (`LIMIT`).
    #[error("cannot resume from the checkpoint: {0}")]
    Input(InputError),
    /// A line does not read, or records are out of order.
    #[error("checkpoint {path}, line {line}: {cause} (the file is damaged: run without --resume)")]
    Damaged {
        /// The file.
        path: PathBuf,
        /// Line number (1 = the header).
        line: usize,
        /// What is wrong.
        cause: String,
    },
    /// The file was written for another scene or engine.
    #[error("checkpoint {path} was written {what}: run without --resume to start over, or restore what changed")]
    Foreign {
        /// The file.
        path: PathBuf,
        /// What differs.
        what: String,
    },
}

/// The first line of the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Header {
    checkpoint: u32,
    engine: String,
    scene: String,
    fingerprint: String,
}

/// A record as written (borrowing the step).
#[derive(Serialize)]
enum RecordOut<'a> {
    Step {
        run: usize,
        point: &'a Point<OrbitInfo>,
        events: &'a [Event<OrbitInfo>],
        h: f64,
        steps: usize,
    },
    Stop {
        run: usize,
        stop: &'a Stop,
    },
}

/// A record as read.
#[derive(Deserialize)]
enum RecordIn {
    Step {
        run: usize,
        point: Point<OrbitInfo>,
        events: Vec<Event<OrbitInfo>>,
        h: f64,
        steps: usize,
    },
    Stop {
        run: usize,
        stop: Stop,
    },
}

/// A run as kept: its trace and, when it ended, why.
type Kept = (Trace<OrbitInfo>, Option<Stop>);

/// A run's reference checkpoint (a [`Ledger`] of its continuation runs).
pub struct Checkpoint {
    /// Where a fresh run writes (the default name; the process id is added
    /// when it exists).
    base: PathBuf,
    header: Header,
    /// The open file and its path (from the first step of a fresh run; at
    /// once when resuming).
    file: RefCell<Option<(PathBuf, File)>>,
    /// The runs kept by the stopped run, in the order they were opened.
    kept: RefCell<VecDeque<Kept>>,
    /// Runs opened so far (the open run's number).
    run: Cell<usize>,
    /// Runs handed back from the file.
    restored: Cell<usize>,
    /// A write failed: the warning was given, nothing more is written.
    failed: Cell<bool>,
}

impl Checkpoint {
    /// The default checkpoint of the output directory `out`:
    /// `<out>.reference-checkpoint.jsonl` beside it.
    pub fn default_path(out: &Path) -> PathBuf {
        let name = out
            .file_name()
            .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        out.with_file_name(format!("{name}.reference-checkpoint.jsonl"))
    }

    /// A fresh checkpoint for the output directory `out` of the scene
    /// `scene_name` with text `scene_text`; nothing is written before the
    /// first step.
    pub fn fresh(out: &Path, scene_name: &str, scene_text: &str) -> Self {
        Checkpoint {
            base: Self::default_path(out),
            header: header(scene_name, scene_text),
            file: RefCell::new(None),
            kept: RefCell::new(VecDeque::new()),
            run: Cell::new(0),
            restored: Cell::new(0),
            failed: Cell::new(false),
        }
    }

    /// Resumes from the checkpoint at `path`, written by a stopped run of
    /// the same scene (name and text) and engine version: its runs are
    /// restored in order, and the new steps appended to it.
    pub fn resume(
        path: &Path,
        scene_name: &str,
        scene_text: &str,
    ) -> Result<Self, CheckpointError> {
        let io = |source| CheckpointError::Io {
            path: path.to_owned(),
            source,
        };
        // a file of its own: never written through a link to another name
        let mut input = match InputFile::open_own(path, LIMIT) {
            Ok(f) => f,
            Err(InputError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
                return Err(CheckpointError::Missing {
                    path: path.to_owned(),
                })
            }
            Err(e) => return Err(CheckpointError::Input(e)),
        };
        match input.file().try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                return Err(CheckpointError::Busy {
                    path: path.to_owned(),
                })
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io(e)),
        }
        let text = input.read_text().map_err(CheckpointError::Input)?;
        let mut file = input.into_file();
        // a byte-order mark the reading skipped stays in front
        let skipped = (file.metadata().map_err(io)?.len()).saturating_sub(text.len() as u64);
        let expected = header(scene_name, scene_text);
        let (kept, complete) = parse(path, &text, &expected)?;
        // a line cut short by the stop is dropped; the new records follow
        // the last whole one
        file.set_len(skipped + complete as u64).map_err(io)?;
        file.seek(SeekFrom::End(0)).map_err(io)?;
        if complete == 0 {
            // stopped before its header was whole: nothing kept
            let line = serde_json::to_string(&expected).map_err(|e| io(e.into()))? + "\n";
            file.write_all(line.as_bytes()).map_err(io)?;
        }
        Ok(Checkpoint {
            base: path.to_owned(),
            header: expected,
            file: RefCell::new(Some((path.to_owned(), file))),
            kept: RefCell::new(kept),
            run: Cell::new(0),
            restored: Cell::new(0),
            failed: Cell::new(false),
        })
    }

    /// Runs restored from the file so far.
    pub fn restored(&self) -> usize {
        self.restored.get()
    }

    /// The file written (or resumed from), if any.
    pub fn written(&self) -> Option<PathBuf> {
        self.file.borrow().as_ref().map(|(p, _)| p.clone())
    }

    /// Creates the file and writes the header: the default name, else with
    /// the process id; never over an existing file.
    fn create(&self) -> Option<(PathBuf, File)> {
        let pid = std::process::id();
        let header = serde_json::to_string(&self.header).ok()? + "\n";
        let candidates = [
            self.base.clone(),
            self.base.with_extension(format!("{pid}.jsonl")),
        ];
        create_first(&candidates, &header)
            .map_err(|(path, e)| {
                eprintln!(
                    "warning: cannot write the reference's checkpoint to {}: {e}; a stopped run will not resume",
                    path.display()
                );
            })
            .ok()
    }

    /// Appends one record.
    fn append(&self, record: &RecordOut<'_>) {
        if self.failed.get() {
            return;
        }
        let mut slot = self.file.borrow_mut();
        if slot.is_none() {
            *slot = self.create();
        }
        let written = match (slot.as_mut(), serde_json::to_string(record)) {
            (Some((_, f)), Ok(line)) => f.write_all((line + "\n").as_bytes()).is_ok(),
            _ => false,
        };
        if !written {
            if let Some((path, _)) = slot.as_ref() {
                eprintln!(
                    "warning: writing the reference's checkpoint {} failed; a stopped run will not resume from here",
                    path.display()
                );
            }
            self.failed.set(true);
        }
    }
}

impl Ledger<OrbitInfo> for Checkpoint {
    fn open(&self) -> Option<Kept> {
        self.run.set(self.run.get() + 1);
        let kept = self.kept.borrow_mut().pop_front();
        if kept.is_some() {
            self.restored.set(self.restored.get() + 1);
        }
        kept
    }

    fn step(&self, step: &Step<'_, OrbitInfo>) {
        self.append(&RecordOut::Step {
            run: self.run.get(),
            point: step.point,
            events: step.events,
            h: step.h,
            steps: step.steps,
        });
    }

    fn close(&self, stop: &Stop) {
        self.append(&RecordOut::Stop {
            run: self.run.get(),
            stop,
        });
    }

    fn withdraw(&self) {
        self.run.set(self.run.get().saturating_sub(1));
    }
}

/// The first of `candidates` that does not exist, created (never over an
/// existing file, never through a link) with `head` written; else the last
/// candidate and why it failed.
pub fn create_first(
    candidates: &[PathBuf],
    head: &str,
) -> Result<(PathBuf, File), (PathBuf, std::io::Error)> {
    let mut last = (PathBuf::new(), std::io::Error::other("no candidate path"));
    for path in candidates {
        match OpenOptions::new().write(true).create_new(true).open(path) {
            Ok(mut f) => {
                return match f.write_all(head.as_bytes()) {
                    Ok(()) => Ok((path.clone(), f)),
                    Err(e) => Err((path.clone(), e)),
                }
            }
            Err(e) => last = (path.clone(), e),
        }
    }
    Err(last)
}

/// The JSON reader's message, which may quote the file, escaped and cut.
fn quoted(e: &serde_json::Error) -> String {
    escaped(&e.to_string(), 200)
}

/// The header of a scene's checkpoint.
fn header(scene_name: &str, scene_text: &str) -> Header {
    Header {
        checkpoint: FORMAT,
        engine: env!("CARGO_PKG_VERSION").into(),
        scene: scene_name.into(),
        fingerprint: format!("{:016x}", fnv1a(scene_text.as_bytes())),
    }
}

/// The 64-bit FNV-1a hash: a fingerprint of the scene's text that is the
/// same in every build (std's hasher may change between releases), written
/// here since no cryptographic strength is needed.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `Ok` when `events` are what a continuation locates on the step from the
/// end of `trace` to `point`: each a change on that step ([`crossed`]), once,
/// after the trace's last point.
fn check_events(
    trace: &Trace<OrbitInfo>,
    point: &Point<OrbitInfo>,
    events: &[Event<OrbitInfo>],
) -> Result<(), String> {
    let Some(last) = trace.points.last() else {
        return Err("a step of a run without a start".into());
    };
    let found = crossed(last, point);
    let after = trace.points.len() - 1;
    for (j, e) in events.iter().enumerate() {
        if !found.contains(&e.kind) {
            return Err(format!(
                "event {:?}, which is not a change on this step (its changes: {found:?})",
                e.kind
            ));
        }
        if events[..j].iter().any(|f| f.kind == e.kind) || e.after != after {
            return Err(format!(
                "event {:?} repeated, or not after point {after}",
                e.kind
            ));
        }
    }
    Ok(())
}

/// The runs kept in `text` and the length of its whole lines; the header
/// must be `expected`.
fn parse(
    path: &Path,
    text: &str,
    expected: &Header,
) -> Result<(VecDeque<Kept>, usize), CheckpointError> {
    let damaged = |line: usize, cause: String| CheckpointError::Damaged {
        path: path.to_owned(),
        line,
        cause,
    };
    // whole lines only: the last one may have been cut by the stop
    let complete = text.rfind('\n').map_or(0, |i| i + 1);
    let mut lines = text[..complete].lines().enumerate();
    let Some((_, first)) = lines.next() else {
        return Ok((VecDeque::new(), complete));
    };
    let found: Header = serde_json::from_str(first)
        .map_err(|e| damaged(1, format!("not a checkpoint header: {}", quoted(&e))))?;
    if found != *expected {
        let what = if found.checkpoint != expected.checkpoint || found.engine != expected.engine {
            format!(
                "by engine {} (layout {}), this is {} (layout {})",
                excerpt(&found.engine),
                found.checkpoint,
                expected.engine,
                expected.checkpoint
            )
        } else if found.scene != expected.scene {
            format!(
                "for scene '{}', not '{}'",
                excerpt(&found.scene),
                expected.scene
            )
        } else {
            format!("for scene '{}' before it was edited", excerpt(&found.scene))
        };
        return Err(CheckpointError::Foreign {
            path: path.to_owned(),
            what,
        });
    }
    let mut kept: VecDeque<Kept> = VecDeque::new();
    for (i, line) in lines {
        let number = i + 1;
        let record: RecordIn =
            serde_json::from_str(line).map_err(|e| damaged(number, quoted(&e)))?;
        let open = kept.len();
        match record {
            RecordIn::Step {
                run,
                point,
                events,
                h,
                steps,
            } => {
                // what a continuation would index or step with: the same
                // number of unknowns in every point and tangent of a run, a
                // positive step
                let size = kept
                    .back()
                    .filter(|_| run == open)
                    .map_or(point.u.len(), |(t, _)| t.points[0].u.len());
                let points = std::iter::once(&point).chain(events.iter().map(|e| &e.at));
                if point.u.is_empty()
                    || !(h.is_finite() && h > 0.0)
                    || points
                        .clone()
                        .any(|p| p.u.len() != size || p.tangent.len() != size)
                {
                    return Err(damaged(
                        number,
                        format!("a step of run {run} whose sizes or step size do not fit its run"),
                    ));
                }
                // what is cheap to recompute is recomputed: the unstable
                // count and test functions from the multipliers
                for p in points {
                    if let Some(why) = p.monitor.info.restored_inconsistency(&p.monitor.tests) {
                        return Err(damaged(number, format!("a point of run {run}: {why}")));
                    }
                }
                if run == open + 1 && steps == 0 && events.is_empty() {
                    kept.push_back((
                        Trace {
                            points: vec![point],
                            events,
                            h,
                            steps,
                        },
                        None,
                    ));
                    continue;
                }
                let Some((trace, None)) = kept.back_mut().filter(|_| run == open) else {
                    return Err(damaged(
                        number,
                        format!("a step of run {run} where run {open} is open"),
                    ));
                };
                if steps <= trace.steps {
                    return Err(damaged(
                        number,
                        format!(
                            "step {steps} of run {run} does not follow step {}",
                            trace.steps
                        ),
                    ));
                }
                check_events(trace, &point, &events)
                    .map_err(|why| damaged(number, format!("step {steps} of run {run}: {why}")))?;
                trace.points.push(point);
                trace.events.extend(events);
                trace.h = h;
                trace.steps = steps;
            }
            RecordIn::Stop { run, stop } => match kept.back_mut() {
                Some((_, end @ None)) if run == open => *end = Some(stop),
                _ => {
                    return Err(damaged(
                        number,
                        format!("the end of run {run}, which is not open"),
                    ))
                }
            },
        }
    }
    Ok((kept, complete))
}
