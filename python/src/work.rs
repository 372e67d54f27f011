//! Long work as Python users expect it: the computation runs on a thread of
//! its own without the GIL (other Python threads run meanwhile), the calling
//! thread wakes every [`POLL`] to let Python handle its signals (Ctrl-C
//! raises `KeyboardInterrupt` after the work has stopped at its next
//! cancellation point, [`ssm_kernel::cancel`]) and to pass the work's
//! progress to a Python callback, at most once per [`THROTTLE`].

use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use pyo3::prelude::*;
use ssm_engine::progress::Progress;
use ssm_kernel::cancel::{self, Flag};

use crate::errors::{raise, Family};

/// How often the waiting thread lets Python handle its signals.
const POLL: Duration = Duration::from_millis(50);

/// The shortest time between two calls of the progress callback.
const THROTTLE: Duration = Duration::from_millis(100);

/// The longest time without a call of the progress callback while the
/// work runs (the last news is repeated).
const HEARTBEAT: Duration = Duration::from_millis(250);

/// The stack of the thread that computes: the engine's command line runs its
/// work on the main thread's (8 MiB on Linux), a spawned thread gets 2 MiB.
const STACK: usize = 16 << 20;

/// What the work tells the waiting thread.
enum Message<T> {
    /// A stage began (its name) or moved on (the stage and where it is).
    Progress(String, String),
    /// The work's result.
    Done(T),
}

/// The work's progress, sent to the waiting thread (the engine's progress
/// display for a whole run; a core call reports its stage).
pub(crate) struct Reporter<'a, T> {
    to: &'a Sender<Message<T>>,
    stage: std::sync::Mutex<String>,
}

impl<T: Send> Reporter<'_, T> {
    /// A stage begins.
    pub(crate) fn begin(&self, name: &str) {
        if let Ok(mut s) = self.stage.lock() {
            *s = name.to_owned();
        }
        let _ = self
            .to
            .send(Message::Progress(name.to_owned(), String::new()));
    }
}

impl<T: Send> Progress for Reporter<'_, T> {
    fn stage(&self, name: &str) {
        self.begin(name);
    }

    fn detail(&self, what: &str) {
        let stage = self.stage.lock().map(|s| s.clone()).unwrap_or_default();
        let _ = self.to.send(Message::Progress(stage, what.to_owned()));
    }
}

/// Calls `progress` with the pending news, if any (remembered as the last
/// news); the callback's exception, if it raised one.
fn tell(
    progress: Option<&Bound<'_, PyAny>>,
    pending: &mut Option<(String, String)>,
    last: &mut Option<(String, String)>,
    last_call: &mut Option<Instant>,
) -> Option<PyErr> {
    let callback = progress?;
    let news = pending.take()?;
    *last_call = Some(Instant::now());
    *last = Some(news.clone());
    callback.call1(news).err()
}

/// Runs `work` on its own thread without the GIL, within a cancellation
/// flag that Ctrl-C raises, and returns its result; `progress` (a Python
/// callable taking the stage and the detail, both strings) hears the work's
/// progress: at most once per [`THROTTLE`], at least once per
/// [`HEARTBEAT`], and the last news once the work is done.
///
/// # Errors
/// `KeyboardInterrupt` (or whatever Python's signal handler raised) once the
/// interrupted work has stopped; the progress callback's exception, after
/// stopping the work the same way; `ssm.errors.SsmError` if the work
/// panicked (its message).
pub(crate) fn interruptible<T, F>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: F,
) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Reporter<'_, T>) -> T + Send,
{
    let flag = Flag::new();
    let (tx, rx) = mpsc::channel::<Message<T>>();
    std::thread::scope(|scope| {
        let worker_flag = flag.clone();
        let spawned = std::thread::Builder::new()
            .name("ssm-work".into())
            .stack_size(STACK)
            .spawn_scoped(scope, move || {
                let reporter = Reporter {
                    to: &tx,
                    stage: std::sync::Mutex::new(String::new()),
                };
                let result = cancel::within(Some(&worker_flag), || work(&reporter));
                let _ = tx.send(Message::Done(result));
            });
        let handle = match spawned {
            Ok(h) => h,
            Err(e) => {
                return Err(raise(
                    py,
                    Family::Analysis,
                    format!("cannot start the computation: {e}"),
                ))
            }
        };
        let mut rx = rx;
        let mut result = None;
        let mut stopped: Option<PyErr> = None;
        let mut last_call: Option<Instant> = None;
        let mut pending: Option<(String, String)> = None;
        let mut last: Option<(String, String)> = None;
        loop {
            let (back, got) = py.detach(move || {
                let got = rx.recv_timeout(POLL);
                (rx, got)
            });
            rx = back;
            match got {
                Ok(Message::Done(r)) => result = Some(r),
                Ok(Message::Progress(stage, detail)) => pending = Some((stage, detail)),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            if stopped.is_some() {
                continue;
            }
            if let Err(e) = py.check_signals() {
                flag.raise();
                stopped = Some(e);
                continue;
            }
            // the latest news at most once per THROTTLE, the last news again
            // after a HEARTBEAT without any (a display's clock moves on)
            let since = last_call.map(|t: Instant| t.elapsed());
            if pending.is_none() && since.is_some_and(|t| t >= HEARTBEAT) {
                pending = last.clone();
            }
            if since.is_none_or(|t| t >= THROTTLE) {
                if let Some(e) = tell(progress, &mut pending, &mut last, &mut last_call) {
                    flag.raise();
                    stopped = Some(e);
                }
            }
        }
        let joined = py.detach(move || handle.join());
        if stopped.is_none() {
            // the news that came after the last call
            stopped = tell(progress, &mut pending, &mut last, &mut last_call);
        }
        if let Some(e) = stopped {
            return Err(e);
        }
        match (joined, result) {
            (Ok(()), Some(r)) => Ok(r),
            (Err(panic), _) => {
                let message = panic
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_owned())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic without a message".into());
                Err(raise(
                    py,
                    Family::Analysis,
                    format!("internal error (a panic in the engine; please report it): {message}"),
                ))
            }
            (Ok(()), None) => Err(raise(
                py,
                Family::Analysis,
                "the computation ended without a result",
            )),
        }
    })
}
