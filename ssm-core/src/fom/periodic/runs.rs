//! The continuation runs of a reference computation, shown and kept as they
//! go: each accepted orbit is handed to the caller's observer (a progress
//! display, a journal), each step to a [`Ledger`] (a checkpoint), and a run
//! the ledger holds already (a resumed computation) is restored from it
//! rather than traced again, then continued where it stopped.
//!
//! A computation opens its runs in a fixed order (main branch, period
//! doublings, seeds, per forcing amplitude; then the amplitude responses),
//! and what decides the later runs (the events and points of the earlier
//! ones) is restored bit for bit, so a resumed computation opens the same
//! runs and ends with what the uninterrupted one would have computed. The
//! start of a restored run is checked against the start computed again: a
//! ledger written for another model or other settings is refused, not
//! mixed in.

use ssm_kernel::continuation::{self, Branch, Ledger, Point, Settings, Stop};

use super::branch::{Reader, ReferenceError, ReferenceOrbit};
use super::{HarmonicBalance, OrbitInfo};

/// A restored run's start may differ from the start computed again by this
/// much (relative): rounding of a different thread schedule, not another
/// model (whose orbits differ in the leading digits).
const SAME_START: f64 = 1e-6;

/// The observer of a reference computation's orbits and the ledger of its
/// continuation runs.
pub struct Runs<'a> {
    /// Sees each orbit as it is accepted (or restored); `false` stops.
    /// (Boxed: the continuation behind it is compiled once, in this crate,
    /// not again for every caller's closure.)
    observe: Box<dyn FnMut(&ReferenceOrbit) -> bool + 'a>,
    /// Keeps the runs' steps, and holds those of a stopped computation.
    pub ledger: &'a dyn Ledger<OrbitInfo>,
    /// Runs opened so far.
    opened: usize,
}

impl<'a> Runs<'a> {
    /// Runs shown to `observe` and kept in `ledger`.
    pub fn new(
        ledger: &'a dyn Ledger<OrbitInfo>,
        observe: impl FnMut(&ReferenceOrbit) -> bool + 'a,
    ) -> Self {
        Runs {
            observe: Box::new(observe),
            ledger,
            opened: 0,
        }
    }

    /// The branch of `hb` through its solution `u0` in the direction `t0`,
    /// its orbits numbered `number` (read by `reader`): restored from the
    /// ledger where it holds this run, traced otherwise; `show_start`:
    /// whether the observer sees the start (the backward half of a branch
    /// shares its start with the forward half). Every step is recorded and
    /// the end too, unless the observer stopped the run.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn trace(
        &mut self,
        hb: &mut HarmonicBalance<'_>,
        u0: Vec<f64>,
        t0: &[f64],
        cs: &Settings,
        reader: &Reader,
        number: usize,
        show_start: bool,
    ) -> Result<Branch<OrbitInfo>, ReferenceError> {
        let Runs {
            observe,
            ledger,
            opened,
        } = self;
        // the observer sees every orbit but an unshown start
        let mut shown = show_start;
        let mut show = |p: &Point<OrbitInfo>| {
            !std::mem::replace(&mut shown, true) || observe(&reader.orbit(p, number))
        };
        *opened += 1;
        let run = *opened;
        // (the branch, whether its end is new: not kept already)
        let (branch, ended_here) = match ledger.open() {
            None => {
                // the start, the only step that can fail: a run that cannot
                // start is withdrawn, so that the ledger holds no trace of
                // it and a resumed computation fails at the same place
                let first = match continuation::start_point(hb, u0, t0) {
                    Ok(first) => first,
                    Err(e) => {
                        ledger.withdraw();
                        *opened -= 1;
                        return Err(e.into());
                    }
                };
                let b = continuation::continue_from(hb, first, cs, |s| {
                    ledger.step(s);
                    show(s.point)
                });
                (b, true)
            }
            Some((trace, stop)) => {
                check_start(run, trace.points.first(), &u0)?;
                let going = trace.points.iter().all(&mut show);
                match stop {
                    Some(stop) if going => {
                        let b = Branch {
                            points: trace.points,
                            events: trace.events,
                            stop,
                        };
                        (b, false)
                    }
                    None if going => {
                        let b = continuation::resume_branch(hb, trace, cs, |s| {
                            ledger.step(s);
                            show(s.point)
                        });
                        (b, true)
                    }
                    _ => {
                        let b = Branch {
                            points: trace.points,
                            events: trace.events,
                            stop: Stop::Interrupted,
                        };
                        (b, false)
                    }
                }
            }
        };
        if ended_here && branch.stop != Stop::Interrupted {
            ledger.close(&branch.stop);
        }
        Ok(branch)
    }
}

/// Refuses a restored run `run` whose start `kept` is not `u0`.
fn check_start(
    run: usize,
    kept: Option<&Point<OrbitInfo>>,
    u0: &[f64],
) -> Result<(), ReferenceError> {
    let Some(kept) = kept.map(|p| p.u.as_slice()) else {
        return Err(ReferenceError::Checkpoint {
            run,
            cause: "it holds no start point".into(),
        });
    };
    if kept.len() != u0.len() {
        return Err(ReferenceError::Checkpoint {
            run,
            cause: format!(
                "its orbits have {} unknowns, this computation's {}",
                kept.len(),
                u0.len()
            ),
        });
    }
    let norm = continuation::dot(u0, u0).sqrt();
    let gap = continuation::distance(kept, u0);
    if gap.is_nan() || gap > SAME_START * (1.0 + norm) {
        return Err(ReferenceError::Checkpoint {
            run,
            cause: format!(
                "it starts {gap:.3e} away from this computation's start (relative to {:.3e})",
                1.0 + norm
            ),
        });
    }
    Ok(())
}
