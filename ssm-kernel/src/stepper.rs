//! One interface for the engine's time integrators: an integration in
//! progress advances by accepted steps and gives the state anywhere inside
//! its last step by its dense output. Radau IIA and HHT-alpha (the full
//! system, `ssm_core::fom`) and Dormand-Prince 5(4) (the reduced dynamics,
//! [`crate::dopri`]) implement [`Stepper`]; [`sample`] reads any of them
//! at given times, so a sampling, a comparison or a new integrator is
//! written once.

/// Work counters of an integration (zero where an integrator has no such
/// work: an explicit method factors nothing).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected step attempts.
    pub rejected: usize,
    /// Newton iterations (implicit methods).
    pub newton: usize,
    /// Matrix factorizations (implicit methods).
    pub factorizations: usize,
    /// Evaluations of the right-hand side.
    pub rhs: usize,
}

/// An integration in progress, advanced step by step.
pub trait Stepper {
    /// The scalar of the state: `f64` for the full system, complex for
    /// reduced coordinates.
    type Scalar: Copy;
    /// Why a step failed.
    type Error;

    /// The time reached.
    fn t(&self) -> f64;
    /// The state at [`Stepper::t`].
    fn state(&self) -> &[Self::Scalar];
    /// Advances by one accepted step, ending at `t_end` at the latest
    /// (rejected attempts are retried inside).
    fn step(&mut self, t_end: f64) -> Result<(), Self::Error>;
    /// Whether the last accepted step reaches the time `t` (round-off of
    /// the step end allowed): [`Stepper::dense`] is valid there.
    fn covers(&self, t: f64) -> bool {
        t <= self.t() * (1.0 + 1e-14)
    }
    /// The state at `t` inside the last accepted step, into `out`.
    fn dense(&self, t: f64, out: &mut [Self::Scalar]);
    /// The work so far.
    fn stats(&self) -> StepStats;
}

/// Steps `s` through the increasing `times` (all after its start), its
/// steps ending at `t_end` at the latest (the last time if that is later,
/// or if `t_end` is NaN),
/// and hands the state at each time to `at(t, state)`, in order, by the
/// dense output of the step that covers it.
///
/// # Errors
/// The first failed step's error.
pub fn sample<S: Stepper>(
    s: &mut S,
    times: &[f64],
    t_end: f64,
    mut at: impl FnMut(f64, &[S::Scalar]),
) -> Result<(), S::Error> {
    let Some(&last) = times.last() else {
        return Ok(());
    };
    // NaN-safe: `max` takes the number
    let t_end = t_end.max(last);
    let mut buf = s.state().to_vec();
    let mut next = 0;
    while next < times.len() {
        s.step(t_end)?;
        while next < times.len() && s.covers(times[next]) {
            s.dense(times[next], &mut buf);
            at(times[next], &buf);
            next += 1;
        }
    }
    Ok(())
}
