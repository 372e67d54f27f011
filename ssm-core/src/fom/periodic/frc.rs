//! The full system's forced response curve: harmonic-balance orbits traced
//! in `Omega` by the shared continuation core, with Floquet stability and
//! the located folds, period doublings, Neimark-Sacker and branch points.
//!
//! The branch starts at the low end of the frequency range from rest: one
//! Newton step from `c = 0` is the linear response, and Newton converges from
//! there to the orbit. The amplitude scale of the unknowns is that start's
//! largest coefficient. Each accepted orbit is handed to an observer (which
//! writes it and drives a progress bar), so a stopped run keeps what it
//! computed.
//!
//! Each orbit carries its truncation estimate: the largest amplitude of the
//! highest harmonic `H` relative to the largest amplitude of the orbit. For
//! the analytic orbits of polynomial systems the Fourier coefficients decay
//! geometrically, so the error of the orbit is of the order of this tail.
//!
//! # References
//! M. Krack, J. Gross, *Harmonic Balance for Nonlinear Vibration Problems*,
//! Springer (2019), Chs. 4-5 (continuation, stability, bifurcations);
//! Y. A. Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed.,
//! Springer (2004), Sect. 9.5 (bifurcations of periodic orbits by their
//! critical multipliers).

pub use super::branch::{
    ReferenceBranch, ReferenceError, ReferenceEvent, ReferenceFrc, ReferenceOrbit,
    ReferenceSettings,
};

use crate::model::system::System;
use ssm_kernel::continuation::{solve_at_parameter, NoLedger, Point, Settings};

use super::branch::{classify, orbits_at, Reader};
use super::runs::Runs;
use super::seed::{seeded_branch, Path, Seeded};
use super::{HarmonicBalance, OrbitInfo};

/// The reference forced response of `sys`; `observe` sees each orbit as it
/// is accepted and returns `false` to stop.
pub fn reference_frc<O>(
    sys: &System,
    settings: &ReferenceSettings,
    observe: O,
) -> Result<ReferenceBranch, ReferenceError>
where
    O: FnMut(&ReferenceOrbit) -> bool,
{
    reference_frc_resumable(sys, settings, &mut Runs::new(&NoLedger, observe))
}

/// [`reference_frc`] with its continuation runs kept in (and, resuming a
/// stopped computation, restored from) the ledger of `runs`.
pub fn reference_frc_resumable(
    sys: &System,
    settings: &ReferenceSettings,
    runs: &mut Runs<'_>,
) -> Result<ReferenceBranch, ReferenceError> {
    let (lo, hi) = settings.omega_range;
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return Err(ReferenceError::Settings(format!(
            "omega_range [{lo}, {hi}] must be finite, positive and increasing"
        )));
    }
    check_flow(sys, settings.harmonics)?;
    let mut hb = HarmonicBalance::new(sys, settings.epsilon, settings.harmonics, 1)?;
    hb.frequency_scale = hi - lo;
    hb.stability = settings.stability;
    let nu = hb.n_coefficients();
    let cs = Settings {
        tol: settings.tol,
        max_steps: settings.max_steps,
        ..Settings::new((lo / (hi - lo), hi / (hi - lo)), settings.step)
    };
    // one Newton step from rest is the linear response; it sets the scale
    let mut u0 = hb.scale(&vec![0.0; nu], lo);
    let lin = Settings {
        max_newton: 1,
        tol: f64::INFINITY,
        ..cs
    };
    u0 = solve_at_parameter(&mut hb, u0, &lin)?;
    let (c_lin, _) = hb.unscale(&u0);
    let scale = c_lin.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return Err(ReferenceError::Settings(format!(
            "the linear response at Omega = {lo} is {scale}: no forcing reaches the model (epsilon = {})",
            settings.epsilon
        )));
    }
    // the arclength weighs amplitude by the largest linear response in the
    // range, so that the steps along the resonance peak are not counted in
    // units of the small response at its foot
    hb.amplitude_scale = scale.max(linear_peak(sys, settings.epsilon, (lo, hi)));
    let guess = hb.scale(&c_lin, lo);
    let u0 = solve_at_parameter(&mut hb, guess, &cs)?;
    let mut t0 = vec![0.0; nu + 1];
    t0[nu] = 1.0;
    let reader = Reader::of(&hb, settings.epsilon, &settings.outputs);
    let branch = runs.trace(&mut hb, u0, &t0, &cs, &reader, 1, true)?;
    let at = orbits_at(
        &mut hb,
        &branch.points,
        &settings.points_at,
        &cs,
        &reader,
        1,
    );
    let (orbits, events, doublings) = classify(&branch, &reader, 1);
    let mut paths = vec![Path::of(1, &branch.points)];
    let mut next = 2;
    let mut failed = Vec::new();
    let doubled = switch_all(
        sys,
        settings,
        &hb,
        &doublings,
        &cs,
        (&mut next, &mut paths, &mut failed),
        runs,
    )?;
    let mut seeded = Vec::new();
    let mut notes = Vec::new();
    for seed in &settings.seeds {
        let outcome = seeded_branch(sys, settings, &hb, seed, &cs, next, &paths, runs);
        match survivable(outcome)? {
            Err(why) => failed.push(format!(
                "the branch from the reduced model's orbit at Omega = {:.6} ({}, period {}T) could not be traced: {why}",
                seed.omega, seed.origin, seed.period_multiple
            )),
            Ok(Seeded::Branch(mut b, path, pds)) => {
                next += 1;
                paths.push(path);
                b.doubled = switch_all(
                    sys,
                    settings,
                    &hb,
                    &pds,
                    &cs,
                    (&mut next, &mut paths, &mut failed),
                    runs,
                )?;
                seeded.push(*b);
            }
            Ok(Seeded::Known) => {}
            Ok(Seeded::Dropped(note)) => notes.push(note),
        }
    }
    Ok(ReferenceBranch {
        doubled,
        seeded,
        notes,
        failed,
        ..ReferenceBranch::traced(&mut hb, &branch.points, orbits, events, branch.stop, at)
    })
}

/// Refuses what has no forced periodic orbits to compute: a map, or no
/// harmonics.
pub(super) fn check_flow(sys: &System, harmonics: usize) -> Result<(), ReferenceError> {
    if let ssm_api::TimeKind::Map { .. } = sys.time {
        return Err(ReferenceError::Settings(format!(
            "model '{}' is a map (discrete time): periodic orbits of a forced flow do not apply",
            sys.name
        )));
    }
    if harmonics == 0 {
        return Err(ReferenceError::Settings(
            "harmonics must be at least 1".into(),
        ));
    }
    Ok(())
}

/// A branch's failure that the computation survives, as its cause: every
/// one but a checkpoint that is not this computation's (which would mix
/// another computation's runs into the later ones).
fn survivable<T>(outcome: Result<T, ReferenceError>) -> Result<Result<T, String>, ReferenceError> {
    match outcome {
        Ok(v) => Ok(Ok(v)),
        Err(e @ ReferenceError::Checkpoint { .. }) => Err(e),
        Err(e) => Ok(Err(e.to_string())),
    }
}

/// The branches of period `2T` at the period doublings `pds` of a
/// period-`T` branch of `hb` (when [`ReferenceSettings::period_doubling`]),
/// numbered from `next`; a doubling where a branch traced earlier ended
/// (it rejoined the period-`T` branch there) starts none, and one whose
/// switch or trace fails is named in `failed` (the others go on).
fn switch_all(
    sys: &System,
    settings: &ReferenceSettings,
    hb: &HarmonicBalance<'_>,
    pds: &[Point<OrbitInfo>],
    cs: &Settings,
    (next, paths, failed): (&mut usize, &mut Vec<Path>, &mut Vec<String>),
    runs: &mut Runs<'_>,
) -> Result<Vec<ReferenceBranch>, ReferenceError> {
    let mut doubled: Vec<ReferenceBranch> = Vec::new();
    if !settings.period_doubling {
        return Ok(doubled);
    }
    for pd in pds {
        // a branch of period 2T that ends here (within 2 % of the range)
        // rejoined the period-T branch here: it was traced already
        let w = pd.parameter();
        let near = |u: &Vec<f64>| (u[u.len() - 1] - w).abs() < 0.02;
        let reached = paths.iter().any(|p| {
            p.multiple == 2
                && (p.points.last().is_some_and(near) || p.points.first().is_some_and(near))
        });
        if reached {
            continue;
        }
        let outcome = super::doubling::doubled_branch(sys, settings, hb, pd, cs, *next, runs);
        match survivable(outcome)? {
            Ok((b, path)) => {
                *next += 1;
                paths.push(path);
                doubled.push(b);
            }
            Err(why) => failed.push(format!(
                "the period-2T branch from the period doubling at Omega = {:.6} could not be traced: {why}",
                w * hb.frequency_scale
            )),
        }
    }
    Ok(doubled)
}

/// The largest first-harmonic linear response (largest coefficient) at 97
/// frequencies across `range`: one Newton step from rest of the one-harmonic
/// balance at each. A resonance narrower than the sampling is missed, which
/// only makes the amplitude scale smaller (more steps, not fewer).
fn linear_peak(sys: &System, epsilon: f64, range: (f64, f64)) -> f64 {
    let Ok(mut hb) = HarmonicBalance::new(sys, epsilon, 1, 1) else {
        return 0.0;
    };
    hb.frequency_scale = range.1 - range.0;
    let nu = hb.n_coefficients();
    let lin = Settings {
        max_newton: 1,
        tol: f64::INFINITY,
        ..Settings::new((0.0, f64::INFINITY), 1.0)
    };
    (0..=96)
        .filter_map(|k| {
            let omega = range.0 + (range.1 - range.0) * k as f64 / 96.0;
            let rest = hb.scale(&vec![0.0; nu], omega);
            let u = solve_at_parameter(&mut hb, rest, &lin).ok()?;
            Some(u[..nu].iter().fold(0.0_f64, |m, v| m.max(v.abs())))
        })
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}
