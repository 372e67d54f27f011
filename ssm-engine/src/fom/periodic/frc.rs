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

use crate::continuation::{
    self, solve_at_parameter, ContinuationError, EventKind, NoLedger, Point, Problem, Settings,
    Stop,
};
use crate::model::system::{OutputMap, System};
use crate::C64;

use super::floquet::{FloquetError, MultiplierCheck};
use super::monodromy::check_multipliers;
use super::runs::Runs;
use super::seed::{seeded_branch, Path, Seed, Seeded};
use super::{HarmonicBalance, HarmonicBalanceError, OrbitInfo, Parameter};

/// Settings of a reference forced response.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceSettings {
    /// Forcing amplitude `eps`.
    pub epsilon: f64,
    /// `[Omega_min, Omega_max]`; the branch starts at `Omega_min`.
    pub omega_range: (f64, f64),
    /// Harmonics `H`.
    pub harmonics: usize,
    /// Largest arclength step in scaled unknowns (amplitude by the start's,
    /// frequency by the range width).
    pub step: f64,
    /// Newton tolerance (relative update).
    pub tol: f64,
    /// Largest number of continuation steps.
    pub max_steps: usize,
    /// Outputs whose amplitudes are reported.
    pub outputs: Vec<OutputMap>,
    /// Switch to the branch of period `2T` at each period doubling.
    pub period_doubling: bool,
    /// Floquet multipliers at each orbit: stability and the bifurcations
    /// they locate (folds are found from the tangent either way).
    pub stability: bool,
    /// Frequencies at which the orbits of the branch are also solved exactly
    /// (every crossing of the branch), e.g. those of steady states to
    /// compare with.
    pub points_at: Vec<f64>,
    /// Predicted orbits to start further branches from (`start = "ssm"`):
    /// each one not on a branch already traced starts a branch of its own.
    pub seeds: Vec<Seed>,
}

/// What was located on the reference branch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReferenceEventKind {
    /// A fold (saddle-node of orbits): a multiplier passes `+1` where the
    /// branch turns in `Omega`.
    Fold,
    /// A multiplier passes `+1` without a fold: a branch point.
    BranchPoint,
    /// A multiplier passes `-1`: period doubling.
    PeriodDoubling,
    /// A complex pair of multipliers leaves the unit circle.
    NeimarkSacker,
}

impl ReferenceEventKind {
    /// `SN`, `BP`, `PD` or `NS`.
    pub fn label(self) -> &'static str {
        match self {
            Self::Fold => "SN",
            Self::BranchPoint => "BP",
            Self::PeriodDoubling => "PD",
            Self::NeimarkSacker => "NS",
        }
    }
}

/// One orbit of the reference forced response.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceOrbit {
    /// Forcing frequency.
    pub omega: f64,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// No Floquet multiplier outside the unit circle; `None` where the
    /// multipliers were not computed.
    pub stable: Option<bool>,
    /// Branch number (1 = main branch).
    pub branch: usize,
    /// Period as a multiple of the forcing period.
    pub period_multiple: usize,
    /// `max_t |y(t)|` per output of the settings.
    pub linf: Vec<f64>,
    /// Largest multiplier modulus.
    pub max_multiplier: Option<f64>,
    /// Truncation estimate (relative amplitude of harmonic `H`).
    pub tail: f64,
}

/// A located bifurcation of the reference.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceEvent {
    /// What it is.
    pub kind: ReferenceEventKind,
    /// The orbit there.
    pub orbit: ReferenceOrbit,
    /// The critical multiplier.
    pub multiplier: Option<C64>,
}

/// A traced reference branch.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceBranch {
    /// Orbits in order.
    pub orbits: Vec<ReferenceOrbit>,
    /// Located bifurcations in order.
    pub events: Vec<ReferenceEvent>,
    /// Why the branch ended.
    pub stop: Stop,
    /// Numeric sparse factorizations used.
    pub factorizations: usize,
    /// Fourier coefficients per orbit.
    pub coefficients: usize,
    /// Time samples per period of the AFT.
    pub samples: usize,
    /// The orbits at [`ReferenceSettings::points_at`], each with its state
    /// at `t = 0` (a multiple of the period).
    pub at: Vec<(ReferenceOrbit, Vec<f64>)>,
    /// The branches of period `2T` switched to at this branch's period
    /// doublings.
    pub doubled: Vec<ReferenceBranch>,
    /// Branches traced from [`ReferenceSettings::seeds`] (not connected to
    /// the main branch inside the range), each with its own doubled
    /// branches.
    pub seeded: Vec<ReferenceBranch>,
    /// What became of the seeds that started no branch.
    pub notes: Vec<String>,
    /// The branches that could not be traced from this one (a switch at a
    /// period doubling, a start from the reduced model), each named with
    /// its start and why; the branches that worked are kept beside them.
    pub failed: Vec<String>,
    /// The branch's multipliers checked at its most critical orbit (`None`
    /// without multipliers).
    pub multiplier_check: Option<Result<MultiplierCheck, FloquetError>>,
}

/// Why no reference was computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReferenceError {
    /// The discretization cannot be set up.
    #[error("reference: {0}")]
    Setup(#[from] HarmonicBalanceError),
    /// The continuation could not start.
    #[error("reference: {0}")]
    Start(#[from] ContinuationError),
    /// Settings that cannot work.
    #[error("reference: {0}")]
    Settings(String),
    /// A run kept by the ledger of a stopped computation is not this
    /// computation's.
    #[error("reference: the checkpoint's run {run} is not this computation's: {cause}; it was written for another model or other settings (run without resuming)")]
    Checkpoint {
        /// The run (1 = the first opened).
        run: usize,
        /// What differs.
        cause: String,
    },
}

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
pub fn reference_frc_resumable<O>(
    sys: &System,
    settings: &ReferenceSettings,
    runs: &mut Runs<'_, O>,
) -> Result<ReferenceBranch, ReferenceError>
where
    O: FnMut(&ReferenceOrbit) -> bool,
{
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

impl ReferenceBranch {
    /// A branch traced with `hb` through `points`: its orbits (one per
    /// point), events, stop and orbits at given parameter values, the costs
    /// of `hb`, the check of its multipliers, and no further branches.
    pub(super) fn traced(
        hb: &mut HarmonicBalance<'_>,
        points: &[Point<OrbitInfo>],
        orbits: Vec<ReferenceOrbit>,
        events: Vec<ReferenceEvent>,
        stop: Stop,
        at: Vec<(ReferenceOrbit, Vec<f64>)>,
    ) -> Self {
        let multiplier_check = check_branch(hb, points, &orbits);
        ReferenceBranch {
            orbits,
            events,
            stop,
            factorizations: hb.factorizations(),
            coefficients: hb.n_coefficients(),
            samples: hb.samples(),
            at,
            doubled: Vec::new(),
            seeded: Vec::new(),
            notes: Vec::new(),
            failed: Vec::new(),
            multiplier_check,
        }
    }
}

/// The [`MultiplierCheck`] of the branch `points` (with their `orbits`) at
/// the point whose largest multiplier is nearest the unit circle; `None`
/// where no point has multipliers.
fn check_branch(
    hb: &mut HarmonicBalance<'_>,
    points: &[Point<OrbitInfo>],
    orbits: &[ReferenceOrbit],
) -> Option<Result<MultiplierCheck, FloquetError>> {
    let (i, floquet) = points
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.monitor.info.floquet.as_ref().map(|f| (i, f)))
        .min_by(|a, b| {
            (a.1.max_modulus() - 1.0)
                .abs()
                .total_cmp(&(b.1.max_modulus() - 1.0).abs())
        })?;
    let (c, omega) = hb.load(&points[i].u);
    Some(
        check_multipliers(hb, &c, omega, floquet).map(|(steps, difference)| MultiplierCheck {
            omega: orbits[i].omega,
            epsilon: orbits[i].epsilon,
            steps,
            difference,
            uncertain_orbits: points
                .iter()
                .filter_map(|p| p.monitor.info.floquet.as_ref())
                .filter(|f| (f.max_modulus() - 1.0).abs() < difference)
                .count(),
        }),
    )
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
fn switch_all<O>(
    sys: &System,
    settings: &ReferenceSettings,
    hb: &HarmonicBalance<'_>,
    pds: &[Point<OrbitInfo>],
    cs: &Settings,
    (next, paths, failed): (&mut usize, &mut Vec<Path>, &mut Vec<String>),
    runs: &mut Runs<'_, O>,
) -> Result<Vec<ReferenceBranch>, ReferenceError>
where
    O: FnMut(&ReferenceOrbit) -> bool,
{
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

/// Drops what a branch of period `m T` that ended at its bound ([`Stop::Bound`]:
/// it rejoined the period-`T` branch) located on its last step: that step
/// crossed the period-`T` branch at the period doubling reported there, onto
/// the same orbits shifted by `T`, and its tangent's turn and multipliers
/// are that crossing, not a fold or a bifurcation of the branch.
pub(super) fn drop_rejoining_step(branch: &mut continuation::Branch<OrbitInfo>) {
    if branch.stop == Stop::Bound {
        let last = branch.points.len().saturating_sub(2);
        branch.events.retain(|e| e.after < last);
    }
}

/// The orbits of a traced branch, its located bifurcations (a multiplier
/// through `+1` in the step of a fold is that fold), and the points of its
/// period doublings.
pub(super) fn classify(
    branch: &continuation::Branch<OrbitInfo>,
    reader: &Reader,
    number: usize,
) -> (
    Vec<ReferenceOrbit>,
    Vec<ReferenceEvent>,
    Vec<Point<OrbitInfo>>,
) {
    let orbits: Vec<ReferenceOrbit> = branch
        .points
        .iter()
        .map(|p| reader.orbit(p, number))
        .collect();
    let mut events = Vec::new();
    let mut doublings = Vec::new();
    for e in &branch.events {
        let critical =
            e.at.monitor
                .info
                .floquet
                .as_ref()
                .and_then(|f| f.critical(e.kind != EventKind::Test(1)));
        let kind = match e.kind {
            EventKind::Fold => ReferenceEventKind::Fold,
            EventKind::Test(1) => ReferenceEventKind::NeimarkSacker,
            EventKind::Test(_) => {
                let Some(rho) = critical else { continue };
                if rho.re > 0.0 {
                    let fold_same_step = branch
                        .events
                        .iter()
                        .any(|f| f.kind == EventKind::Fold && f.after == e.after);
                    if fold_same_step {
                        continue;
                    }
                    ReferenceEventKind::BranchPoint
                } else {
                    doublings.push(e.at.clone());
                    ReferenceEventKind::PeriodDoubling
                }
            }
        };
        events.push(ReferenceEvent {
            kind,
            orbit: reader.orbit(&e.at, number),
            multiplier: critical,
        });
    }
    (orbits, events, doublings)
}

/// The orbits at the parameter's values `values` (frequencies, or forcing
/// amplitudes when the amplitude is the parameter): at each crossing of the
/// branch, Newton at the fixed parameter from the chord between the two
/// points around it.
pub(super) fn orbits_at(
    hb: &mut HarmonicBalance<'_>,
    points: &[Point<OrbitInfo>],
    values: &[f64],
    cs: &Settings,
    reader: &Reader,
    number: usize,
) -> Vec<(ReferenceOrbit, Vec<f64>)> {
    let nu = hb.n_coefficients();
    let w = match hb.parameter {
        Parameter::Frequency => hb.frequency_scale,
        Parameter::Amplitude { .. } => hb.epsilon_scale,
    };
    let mut out = Vec::new();
    for &value in values {
        let target = value / w;
        for pair in points.windows(2) {
            let (a, b) = (pair[0].u[nu], pair[1].u[nu]);
            if (a - target) * (b - target) > 0.0 || a == b {
                continue;
            }
            let s = (target - a) / (b - a);
            let mut guess: Vec<f64> = pair[0]
                .u
                .iter()
                .zip(&pair[1].u)
                .map(|(x, y)| x + s * (y - x))
                .collect();
            guess[nu] = target;
            let Ok(u) = solve_at_parameter(hb, guess, cs) else {
                continue;
            };
            let t = pair[0].tangent.clone();
            let monitor = hb.monitor(&u, &t).ok();
            let Some(monitor) = monitor else { continue };
            let pt = Point {
                u,
                tangent: t,
                monitor,
            };
            let (c, _) = hb.unscale(&pt.u);
            out.push((reader.orbit(&pt, number), hb.state_at(&c, 0.0)));
        }
    }
    out
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

/// What turns a continuation point into a [`ReferenceOrbit`] (the scales and
/// sizes of the discretization, copied so that the observer can run while
/// the continuation holds the discretization).
pub(super) struct Reader {
    pub amplitude_scale: f64,
    pub frequency_scale: f64,
    pub epsilon_scale: f64,
    pub parameter: Parameter,
    pub n: usize,
    pub harmonics: usize,
    pub multiple: usize,
    pub epsilon: f64,
    pub outputs: Vec<Vec<(usize, f64)>>,
}

impl Reader {
    /// The reader of `hb`'s orbits at forcing amplitude `epsilon` (unused
    /// when the amplitude is the parameter) with the `outputs`.
    pub fn of(hb: &HarmonicBalance<'_>, epsilon: f64, outputs: &[OutputMap]) -> Self {
        Reader {
            amplitude_scale: hb.amplitude_scale,
            frequency_scale: hb.frequency_scale,
            epsilon_scale: hb.epsilon_scale,
            parameter: hb.parameter,
            n: hb.n_states(),
            harmonics: hb.harmonics(),
            multiple: hb.period_multiple(),
            epsilon,
            outputs: outputs.iter().map(|o| o.weights.clone()).collect(),
        }
    }

    pub fn orbit(&self, p: &Point<OrbitInfo>, branch: usize) -> ReferenceOrbit {
        let kk = 2 * self.harmonics + 1;
        let nu = self.n * kk;
        let c: Vec<f64> = p.u[..nu].iter().map(|v| v * self.amplitude_scale).collect();
        let (omega, epsilon) = match self.parameter {
            Parameter::Frequency => (p.u[nu] * self.frequency_scale, self.epsilon),
            Parameter::Amplitude { omega } => (omega, p.u[nu] * self.epsilon_scale),
        };
        let linf = self
            .outputs
            .iter()
            .map(|w| {
                // the output's own Fourier coefficients
                let mut y = vec![0.0; kk];
                for (i, wi) in w {
                    for (yq, cq) in y.iter_mut().zip(&c[i * kk..(i + 1) * kk]) {
                        *yq += wi * cq;
                    }
                }
                series_linf(&y, self.harmonics)
            })
            .collect();
        let h = self.harmonics;
        let (mut top, mut all) = (0.0_f64, 0.0_f64);
        for i in 0..self.n {
            let ci = &c[i * kk..(i + 1) * kk];
            top = top.max(ci[2 * h - 1].hypot(ci[2 * h]));
            all = all.max(ci.iter().map(|v| v.abs()).sum::<f64>());
        }
        let floquet = p.monitor.info.floquet.as_ref();
        ReferenceOrbit {
            omega,
            epsilon,
            stable: floquet.map(|f| f.stable()),
            branch,
            period_multiple: self.multiple,
            linf,
            max_multiplier: floquet.map(|f| f.max_modulus()),
            tail: if all > 0.0 { top / all } else { 0.0 },
        }
    }
}

/// `max_psi |y(psi)|` of the series `y = (y_0, y_1^c, y_1^s, ...)` with `h`
/// harmonics: the largest of `16 h` samples (at least 64), refined by Newton
/// on `y'(psi) = 0` (a sampled maximum alone is low by up to `1 - cos(pi /
/// samples)` relative).
pub fn series_linf(y: &[f64], h: usize) -> f64 {
    let eval = |psi: f64| -> (f64, f64, f64) {
        let (mut v, mut d1, mut d2) = (y[0], 0.0, 0.0);
        for k in 1..=h {
            let kf = k as f64;
            let (s, c) = (kf * psi).sin_cos();
            let (a, b) = (y[2 * k - 1], y[2 * k]);
            v += a * c + b * s;
            d1 += kf * (b * c - a * s);
            d2 -= kf * kf * (a * c + b * s);
        }
        (v, d1, d2)
    };
    let samples = (16 * h).max(64);
    let step = 2.0 * std::f64::consts::PI / samples as f64;
    let (best, _) = (0..samples)
        .map(|s| (s, eval(s as f64 * step).0.abs()))
        .fold((0, -1.0), |acc, x| if x.1 > acc.1 { x } else { acc });
    let mut psi = best as f64 * step;
    let mut top = eval(psi).0.abs();
    for _ in 0..20 {
        let (_, d1, d2) = eval(psi);
        if d2 == 0.0 {
            break;
        }
        let next = psi - (d1 / d2).clamp(-step, step);
        let v = eval(next).0.abs();
        if v < top {
            break;
        }
        top = v;
        if (next - psi).abs() < 1e-15 {
            break;
        }
        psi = next;
    }
    top
}

/// The reference forced responses of a scene: one branch per forcing
/// amplitude.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceFrc {
    /// Output names, in the order of [`ReferenceOrbit::linf`].
    pub outputs: Vec<String>,
    /// Harmonics `H`.
    pub harmonics: usize,
    /// Time samples per period of the AFT.
    pub samples: usize,
    /// One branch per forcing amplitude, then the branches of period `2T`
    /// and those started from the reduced model.
    pub branches: Vec<ReferenceBranch>,
    /// The amplitude responses (continuation in `eps`), one per frequency.
    pub amplitude: Vec<ReferenceBranch>,
    /// Wall-clock seconds.
    pub seconds: f64,
}
