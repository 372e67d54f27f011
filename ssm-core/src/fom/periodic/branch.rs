//! What the full system's reference computes and reads: its settings, the
//! orbits, events and branches it returns with their errors, the predicted
//! orbits (seeds) it may start from, and what turns a continuation point
//! into an orbit (shared by the traced branches of [`super::frc`],
//! [`super::seed`], [`super::doubling`] and [`super::runs`]).

use crate::model::system::OutputMap;
use crate::C64;
use ssm_kernel::continuation::{
    self, solve_at_parameter, BifurcationKind, ContinuationError, EventKind, Point, Problem,
    Settings, Stop,
};

use super::floquet::{FloquetError, MultiplierCheck, CHECK_WARNING};
use super::monodromy::check_multipliers;
use super::{HarmonicBalance, HarmonicBalanceError, OrbitInfo, Parameter};

/// A predicted orbit to start a reference branch from.
#[derive(Debug, Clone, PartialEq)]
pub struct Seed {
    /// Forcing frequency.
    pub omega: f64,
    /// The orbit's period as a multiple `m` of the forcing period.
    pub period_multiple: usize,
    /// The full state at `S` equally spaced times `t_s = s m T / S` over one
    /// period, from `t = 0` (the forcing's phase origin); `S` must exceed
    /// twice the harmonics of the orbit.
    pub states: Vec<Vec<f64>>,
    /// Where the prediction comes from (for notes), e.g. `"O(7) branch 2"`.
    pub origin: String,
}

impl Seed {
    /// Fourier coefficients `(c_0, c_1^c, c_1^s, ...)` per state (state-major,
    /// `2h + 1` each) of the sampled orbit: the discrete projection, exact for
    /// a trigonometric polynomial of degree below `S / 2`.
    pub fn coefficients(&self, n: usize, h: usize) -> Result<Vec<f64>, String> {
        let s = self.states.len();
        if s <= 2 * h {
            return Err(format!(
                "{} samples cannot resolve {h} harmonics (need more than {})",
                s,
                2 * h
            ));
        }
        if let Some(bad) = self.states.iter().position(|z| z.len() != n) {
            return Err(format!(
                "sample {bad} has {} states, the model {n}",
                self.states[bad].len()
            ));
        }
        if self.states.iter().flatten().any(|v| !v.is_finite()) {
            return Err("the predicted orbit is not finite".into());
        }
        let kk = 2 * h + 1;
        let mut c = vec![0.0; n * kk];
        let inv = 1.0 / s as f64;
        for (j, z) in self.states.iter().enumerate() {
            let psi = 2.0 * std::f64::consts::PI * j as f64 * inv;
            for (i, zi) in z.iter().enumerate() {
                let ci = &mut c[i * kk..(i + 1) * kk];
                ci[0] += inv * zi;
                for k in 1..=h {
                    let (sn, cs) = (k as f64 * psi).sin_cos();
                    ci[2 * k - 1] += 2.0 * inv * zi * cs;
                    ci[2 * k] += 2.0 * inv * zi * sn;
                }
            }
        }
        Ok(c)
    }
}

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
    pub kind: BifurcationKind,
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

impl ReferenceBranch {
    /// The warning a branch calls for when its multipliers' check differs
    /// by more than `CHECK_WARNING` or failed, led by `at` (where it was
    /// traced, e.g. `[reference]`); every traced branch gets it.
    pub fn multiplier_warning(&self, at: &str) -> Option<String> {
        match self.multiplier_check.as_ref()? {
            Ok(c) if c.difference > CHECK_WARNING => Some(format!(
                "{at}: the Floquet multipliers of the orbit at Omega = {:.6}, eps = {:e} differ by {:.2e} from a check by the monodromy map with {} steps: stability and bifurcations are uncertain to that much ({} orbits of the branch have their largest multiplier within it of the unit circle); raise harmonics",
                c.omega, c.epsilon, c.difference, c.steps, c.uncertain_orbits
            )),
            Ok(_) => None,
            Err(e) => Some(format!(
                "{at}: the check of the Floquet multipliers failed ({e}); the stable column is unchecked"
            )),
        }
    }

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
            EventKind::Fold => BifurcationKind::Fold,
            EventKind::Test(1) => BifurcationKind::NeimarkSacker,
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
                    BifurcationKind::BranchPoint
                } else {
                    doublings.push(e.at.clone());
                    BifurcationKind::PeriodDoubling
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
pub(crate) fn series_linf(y: &[f64], h: usize) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn branch(check: Option<Result<MultiplierCheck, FloquetError>>) -> ReferenceBranch {
        ReferenceBranch {
            orbits: Vec::new(),
            events: Vec::new(),
            stop: Stop::Range,
            factorizations: 0,
            coefficients: 0,
            samples: 0,
            at: Vec::new(),
            doubled: Vec::new(),
            seeded: Vec::new(),
            notes: Vec::new(),
            failed: Vec::new(),
            multiplier_check: check,
        }
    }

    /// A check differing by 1e-4 is no warning, one differing by 2e-3
    /// (above [`CHECK_WARNING`]) is a warning naming the orbit, the figure
    /// and the uncertain orbits; a failed check is a warning too.
    #[test]
    fn a_multiplier_check_above_its_tolerance_is_a_warning() {
        let check = |difference: f64| MultiplierCheck {
            omega: 1.95,
            epsilon: 0.02,
            steps: 288,
            difference,
            uncertain_orbits: 3,
        };
        let warn = |b: &ReferenceBranch| b.multiplier_warning("[reference]");
        assert_eq!(warn(&branch(Some(Ok(check(1e-4))))), None);
        assert_eq!(warn(&branch(None)), None);
        let w = warn(&branch(Some(Ok(check(2e-3))))).expect("warning");
        assert!(
            w.contains("Omega = 1.950000") && w.contains("2.00e-3") && w.contains("3 orbits"),
            "{w}"
        );
        let failed = Some(Err(FloquetError::Spectrum("did not converge".into())));
        let w = warn(&branch(failed)).expect("warning");
        assert!(w.contains("did not converge"), "{w}");
    }
}
