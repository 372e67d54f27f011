//! What a continuation run leaves behind as it goes: its [`Trace`] (all the
//! next step depends on), each accepted [`Step`] as an observer sees it, and
//! the [`Ledger`] that keeps the runs of a computation so that a stopped one
//! resumes where it stopped.

use super::{Event, Point, Stop};

/// A branch as far as it was traced, with the step size and the count of
/// steps (tried, accepted or not) at which it goes on: everything the next
/// step depends on, so that [`super::resume_branch`] from a stored trace computes
/// what the uninterrupted continuation would have.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trace<I> {
    /// Accepted points in order (at least the start).
    pub points: Vec<Point<I>>,
    /// Located events in order.
    pub events: Vec<Event<I>>,
    /// The next step's size.
    pub h: f64,
    /// Steps tried so far.
    pub steps: usize,
}

/// An accepted point as the observer of a continuation sees it: the point,
/// the events located on the step to it, and the state the next step starts
/// from (what a checkpoint stores).
#[derive(Debug, Clone, Copy)]
pub struct Step<'a, I> {
    /// The accepted point.
    pub point: &'a Point<I>,
    /// The events located between the previous point and this one.
    pub events: &'a [Event<I>],
    /// The next step's size.
    pub h: f64,
    /// Steps tried so far.
    pub steps: usize,
}

/// Where continuation runs are kept as they go, so that a stopped
/// computation resumes where it stopped: a computation opens its runs in a
/// fixed order, and a resumed one gets back what was kept of each.
/// Implementations keep their own state (methods take `&self`, as a
/// progress display's do).
pub trait Ledger<I> {
    /// Opens the next run, and returns what is kept of it: its trace so far
    /// and, when it ended, why.
    fn open(&self) -> Option<(Trace<I>, Option<Stop>)>;
    /// Records an accepted step of the open run.
    fn step(&self, step: &Step<'_, I>);
    /// Records the end of the open run.
    fn close(&self, stop: &Stop);
    /// Withdraws the run just opened, fresh and without a step recorded
    /// (its start failed): the next run opened takes its number.
    fn withdraw(&self);
}

/// A ledger that keeps nothing.
pub struct NoLedger;

impl<I> Ledger<I> for NoLedger {
    fn open(&self) -> Option<(Trace<I>, Option<Stop>)> {
        None
    }
    fn step(&self, _step: &Step<'_, I>) {}
    fn close(&self, _stop: &Stop) {}
    fn withdraw(&self) {}
}
