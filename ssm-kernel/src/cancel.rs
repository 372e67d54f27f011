//! Cooperative cancellation of long computations.
//!
//! A caller that may want to stop a computation (a binding whose user pressed
//! Ctrl-C, a service with a deadline) runs it [`within`] a [`Flag`]; the long
//! loops of the kernel and the core (each continuation step, each integrator
//! step, each order of an SSM) ask [`requested`] and end early with their
//! own "interrupted" outcome (a [`crate::continuation::Stop::Interrupted`]
//! branch, an `Interrupted` error) once the flag is raised. An interrupted
//! computation's answer is incomplete: whoever raised the flag discards it.
//!
//! The flag belongs to the thread that runs the work: work handed to other
//! threads (a `rayon` parallel loop) carries it along with [`current`] and
//! [`within`]. A thread outside any [`within`] is never interrupted, so that
//! computations of other callers running at the same time are not affected.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A cancellation flag shared between the work and the one who stops it.
#[derive(Debug, Clone, Default)]
pub struct Flag(Arc<AtomicBool>);

impl Flag {
    /// A lowered flag.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the work running within this flag to stop.
    pub fn raise(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether the flag was raised.
    pub fn is_raised(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Flag>> = const { RefCell::new(None) };
}

/// Restores the thread's previous flag when the work ends, also by a panic.
struct Restore(Option<Flag>);

impl Drop for Restore {
    fn drop(&mut self) {
        let previous = self.0.take();
        CURRENT.with(|c| *c.borrow_mut() = previous);
    }
}

/// Runs `work` on this thread with `flag` as its cancellation flag (`None`:
/// not cancellable), then restores the thread's previous flag.
pub fn within<R>(flag: Option<&Flag>, work: impl FnOnce() -> R) -> R {
    let previous = CURRENT.with(|c| c.replace(flag.cloned()));
    let _restore = Restore(previous);
    work()
}

/// The flag of the work running on this thread, to hand to the threads it
/// spreads over.
pub fn current() -> Option<Flag> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Whether the work running on this thread was asked to stop.
pub fn requested() -> bool {
    CURRENT.with(|c| c.borrow().as_ref().is_some_and(Flag::is_raised))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_work_within_a_raised_flag_is_asked_to_stop() {
        let flag = Flag::new();
        assert!(!requested());
        within(Some(&flag), || {
            assert!(!requested());
            flag.raise();
            assert!(requested());
            // nested work without a flag is not cancellable
            within(None, || assert!(!requested()));
            assert!(requested());
            // another thread does not see it unless handed over
            let handed = current();
            std::thread::scope(|s| {
                s.spawn(|| assert!(!requested()));
                s.spawn(|| within(handed.as_ref(), || assert!(requested())));
            });
        });
        assert!(!requested());
    }

    #[test]
    fn the_previous_flag_returns_after_a_panic() {
        let flag = Flag::new();
        flag.raise();
        let r = std::panic::catch_unwind(|| within(Some(&flag), || panic!("in the work")));
        assert!(r.is_err());
        assert!(!requested());
    }
}
