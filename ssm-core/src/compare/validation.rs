//! The comparisons of `[validate]`: a full-system transient against the
//! reduced one, and steady-state references against the forced response
//! curves, with the error figures of both.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sects.
//! 5.1.1, 5.2.3, Appendix G.1, eq. (47), Figs. 4, 10, 14, 15.

use std::time::Instant;

use ssm_api::StateKind;

use super::{
    nearest_on_ssm, steady_state_reference, transient, TransientSettings, TransientValidation,
    ValidateError,
};
use crate::fom::periodic::frc::ReferenceFrc;
use crate::fom::{
    consistent_initial_keeping, DaeProblem, RadauOptions, SteadyOptions, SteadyState,
};
use crate::model::system::{OutputMap, System};
use crate::rom::autonomous::polar_point;
use crate::rom::forced_response::FrcRow;
use crate::spec::{SteadyStart, ValidationSpec, ValidationStart, ValidationTransientSpec};
use crate::spectrum::MasterMode;
use crate::ssm::SsmExpansion;
use crate::C64;

/// Multipliers added to the transient comparison without being listed (the first ones).
const MAX_AUTO_MULTIPLIERS: usize = 8;

/// Where the transient comparison started.
#[derive(Debug, Clone, PartialEq)]
pub enum TransientStart {
    /// On the SSM at `W(p0)`, `p0` given in polar form.
    Ssm {
        /// Polar amplitudes.
        rho0: Vec<f64>,
        /// Polar angles.
        theta0: Vec<f64>,
    },
    /// From given states; the reduced model starts at the nearest point of the SSM.
    Given {
        /// The given state values, by name.
        values: Vec<(String, f64)>,
        /// Distance of the (projected) start to the SSM.
        distance: f64,
        /// Polar amplitudes of the nearest point.
        rho0: Vec<f64>,
        /// Polar angles of the nearest point.
        theta0: Vec<f64>,
    },
}

/// The transient comparison and its error figures.
#[derive(Debug, Clone)]
pub struct TransientComparison {
    /// Expansion order of the reduced model.
    pub order: usize,
    /// The start.
    pub start: TransientStart,
    /// End time.
    pub t_end: f64,
    /// Compared outputs, then the multipliers added for Appendix G.1.
    pub outputs: Vec<String>,
    /// How many of `outputs` were asked for (the rest are multipliers).
    pub n_compared: usize,
    /// The trajectories.
    pub result: TransientValidation,
    /// Relative error of each output over the run.
    pub relative_errors: Vec<f64>,
    /// Root-mean-square relative error of each output over the run
    /// ([`TransientValidation::rms_relative_error`]).
    pub rms_relative_errors: Vec<f64>,
    /// Relative error over all outputs at each sample.
    pub relative_error_series: Vec<f64>,
    /// Largest relative error of the compared outputs.
    pub max_relative_error: f64,
    /// Largest distance of the full trajectory to the SSM.
    pub max_manifold_distance: f64,
    /// Largest algebraic residual of the full trajectory.
    pub max_algebraic_residual: f64,
    /// Accepted full-system steps per second.
    pub steps_per_s: f64,
}

/// The FRC's error against a steady-state reference, for one order.
#[derive(Debug, Clone, PartialEq)]
pub struct FrcErrorEntry {
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Largest relative amplitude error (`None`: no reference point covered).
    pub max_relative_error: Option<f64>,
    /// Reference points the FRC covers.
    pub points_compared: usize,
    /// The output compared.
    pub output: Option<String>,
}

/// Steady-state reference points of one forcing amplitude.
#[derive(Debug, Clone)]
pub struct SteadyReference {
    /// Forcing amplitude.
    pub epsilon: f64,
    /// One converged response per frequency.
    pub points: Vec<SteadyState>,
    /// Names of the outputs whose amplitudes are in `points`.
    pub outputs: Vec<String>,
    /// Wall time of all points (run in parallel).
    pub wall_s: f64,
    /// Accepted steps of all points.
    pub steps: usize,
    /// Convergence threshold of eq. (47).
    pub delta: f64,
    /// Per frequency, whether it started from the SSM prediction (`None`: all from rest).
    pub from_ssm: Option<Vec<bool>>,
    /// The FRCs' errors against the reference, if there were FRCs.
    pub frc_errors: Option<Vec<FrcErrorEntry>>,
}

/// Everything `[validate]` produced.
#[derive(Debug, Clone)]
pub struct Validation {
    /// The transient comparison, if requested.
    pub transient: Option<TransientComparison>,
    /// The steady-state reference, if requested.
    pub steady: Option<SteadyReference>,
}

/// Multiplier outputs (`mu1`, ...) of the model, for the Appendix G.1 comparison.
fn multiplier_outputs(sys: &System) -> Vec<&OutputMap> {
    sys.states
        .iter()
        .enumerate()
        .filter(|(_, s)| s.kind == StateKind::Multiplier)
        .filter_map(|(i, s)| {
            sys.output(s.name.as_str())
                .filter(|o| o.weights.len() == 1 && o.weights[0].0 == i)
        })
        .collect()
}

/// Runs the comparisons of `sec`: `compared` are the outputs of the transient
/// (the multipliers are added), `coordinates` those of the steady state (the
/// FRC's outputs, in its order), `frc` the FRC points to start from and to
/// measure against the reference.
pub fn validation(
    ssm: &SsmExpansion,
    sys: &System,
    sec: &ValidationSpec,
    compared: &[&OutputMap],
    coordinates: &[&OutputMap],
    masters: &[MasterMode],
    frc: Option<&[FrcRow]>,
) -> Result<Validation, ValidateError> {
    let opts = RadauOptions {
        rtol: sec.rtol,
        atol: sec.atol,
        ..RadauOptions::default()
    };
    let transient = sec
        .transient
        .as_ref()
        .map(|tr| transient_comparison(ssm, sys, tr, compared, masters, opts))
        .transpose()?;
    let mut steady = None;
    if let Some(ss) = &sec.steady_state {
        let eps = ss.epsilon;
        let omegas = &ss.omegas;
        let sopts = SteadyOptions {
            delta: ss.delta,
            max_periods: ss.max_periods,
            samples_per_period: ss.samples_per_period,
            max_multiple: ss.max_period_multiple,
            radau: opts,
        };
        let starts = match (ss.start, frc) {
            (SteadyStart::Ssm, Some(rows)) => Some(ssm_starts(ssm, rows, eps, omegas)),
            _ => None,
        };
        let t0 = Instant::now();
        let points =
            steady_state_reference(sys, eps, omegas, coordinates, &sopts, starts.as_deref())?;
        let mut reference = SteadyReference {
            epsilon: eps,
            steps: points.iter().map(|p| p.stats.accepted).sum(),
            points,
            outputs: coordinates.iter().map(|o| o.name.clone()).collect(),
            wall_s: t0.elapsed().as_secs_f64(),
            delta: ss.delta,
            from_ssm: starts.map(|st| st.iter().map(Option::is_some).collect()),
            frc_errors: None,
        };
        reference.frc_errors = frc.map(|rows| frc_errors(rows, &reference));
        steady = Some(reference);
    }
    Ok(Validation { transient, steady })
}

/// The transient comparison of `sec`.
fn transient_comparison(
    ssm: &SsmExpansion,
    sys: &System,
    sec: &ValidationTransientSpec,
    compared: &[&OutputMap],
    masters: &[MasterMode],
    radau: RadauOptions,
) -> Result<TransientComparison, ValidateError> {
    let order = sec.order.unwrap_or(ssm.order);
    let t_end = sec.t_end;
    let (p0, full_start, start) = match &sec.start {
        ValidationStart::Ssm { rho0, theta0 } => {
            let theta0 = theta0.clone().unwrap_or_else(|| vec![0.0; rho0.len()]);
            let p0 = polar_point(rho0, &theta0);
            let start = TransientStart::Ssm {
                rho0: rho0.clone(),
                theta0,
            };
            (p0, None, start)
        }
        ValidationStart::Given { values } => {
            let (z, keep) = sys.given_state(values);
            let problem = DaeProblem::new(sys, 0.0, 0.0);
            let c = consistent_initial_keeping(&problem, 0.0, &z, &keep)?;
            let (p0, distance) = nearest_on_ssm(ssm, sys, order, masters, &c.z);
            let start = TransientStart::Given {
                values: values.clone(),
                distance,
                rho0: p0.iter().step_by(2).map(|q| q.norm()).collect(),
                theta0: p0.iter().step_by(2).map(|q| q.arg()).collect(),
            };
            // the raw values go to the full system, whose projection is reported
            (p0, Some((z, keep)), start)
        }
    };
    let mut outs: Vec<&OutputMap> = compared.to_vec();
    // a few multipliers are added (Appendix G.1); large models list the ones they want
    for m in multiplier_outputs(sys)
        .into_iter()
        .take(MAX_AUTO_MULTIPLIERS)
    {
        if !outs.iter().any(|o| o.name == m.name) {
            outs.push(m);
        }
    }
    let tv = transient(
        ssm,
        sys,
        &TransientSettings {
            order,
            p0: &p0,
            t_end,
            samples: sec.samples,
            outputs: &outs,
            radau,
            full_start: full_start
                .as_ref()
                .map(|(z, k)| (z.as_slice(), k.as_slice())),
        },
    )?;
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let relative_errors: Vec<f64> = (0..outs.len()).map(|k| tv.relative_error(k)).collect();
    Ok(TransientComparison {
        order,
        start,
        t_end,
        outputs: outs.iter().map(|o| o.name.clone()).collect(),
        n_compared: compared.len(),
        relative_error_series: (0..tv.times.len())
            .map(|j| tv.relative_error_at(j))
            .collect(),
        max_relative_error: max(&relative_errors[..compared.len()]),
        max_manifold_distance: max(&tv.distance),
        max_algebraic_residual: max(&tv.algebraic_residual),
        steps_per_s: tv.stats.accepted as f64 / tv.full_s.max(1e-12),
        relative_errors,
        rms_relative_errors: (0..outs.len()).map(|k| tv.rms_relative_error(k)).collect(),
        result: tv,
    })
}

/// Starting states from the FRC: at each `omega`, the point `W(p0)` of the
/// largest stable response (first output) of the highest-order curve at
/// `epsilon`, `p0` the rotating-frame fixed point interpolated along the
/// branch; `None` where no stable branch crosses `omega`.
fn ssm_starts(
    ssm: &SsmExpansion,
    rows: &[FrcRow],
    epsilon: f64,
    omegas: &[f64],
) -> Vec<Option<Vec<f64>>> {
    let same_eps = |r: &FrcRow| (r.epsilon - epsilon).abs() <= 1e-12 * epsilon;
    let Some(order) = rows.iter().filter(|r| same_eps(r)).map(|r| r.order).max() else {
        return vec![None; omegas.len()];
    };
    let curve: Vec<&FrcRow> = rows
        .iter()
        .filter(|r| same_eps(r) && r.order == order)
        .collect();
    omegas
        .iter()
        .map(|&w| {
            let best = curve
                .windows(2)
                .filter(|c| c[0].branch == c[1].branch && c[0].stable && c[1].stable)
                .filter(|c| (c[0].omega - w) * (c[1].omega - w) <= 0.0 && c[0].omega != c[1].omega)
                .map(|c| {
                    let s = (w - c[0].omega) / (c[1].omega - c[0].omega);
                    let amp = c[0]
                        .linf
                        .first()
                        .map_or(c[0].rho, |a| a + s * (c[1].linf[0] - a));
                    let q: Vec<C64> = c[0]
                        .q
                        .iter()
                        .zip(&c[1].q)
                        .map(|(a, b)| a + (b - a) * s)
                        .collect();
                    (amp, q)
                })
                .max_by(|a, b| a.0.total_cmp(&b.0))?;
            let p0: Vec<C64> = best.1.iter().flat_map(|q| [*q, q.conj()]).collect();
            Some(
                ssm.w_at(&ssm.set.monomials(&p0, order), order)
                    .iter()
                    .map(|c| c.re)
                    .collect(),
            )
        })
        .collect()
}

/// The FRC amplitude of output `k` at `omega` on the curve `(order, epsilon)`:
/// linear interpolation on every branch segment that crosses `omega`, the
/// crossing nearest `near` (the reference from rest sits on one branch).
pub(crate) fn frc_amplitude_at(
    rows: &[FrcRow],
    order: usize,
    epsilon: f64,
    k: usize,
    omega: f64,
    near: f64,
) -> Option<f64> {
    let same = |r: &FrcRow| r.order == order && (r.epsilon - epsilon).abs() <= 1e-12 * epsilon;
    let curve: Vec<&FrcRow> = rows.iter().filter(|r| same(r)).collect();
    curve
        .windows(2)
        .filter(|w| w[0].branch == w[1].branch)
        .filter(|w| (w[0].omega - omega) * (w[1].omega - omega) <= 0.0 && w[0].omega != w[1].omega)
        .map(|w| {
            let s = (omega - w[0].omega) / (w[1].omega - w[0].omega);
            w[0].linf[k] + s * (w[1].linf[k] - w[0].linf[k])
        })
        .min_by(|a, b| (a - near).abs().total_cmp(&(b - near).abs()))
}

/// Per FRC order at the reference's epsilon: the largest relative amplitude
/// error against the reference over the frequencies the FRC covers.
pub fn frc_errors(rows: &[FrcRow], r: &SteadyReference) -> Vec<FrcErrorEntry> {
    let mut orders: Vec<usize> = rows
        .iter()
        .filter(|w| (w.epsilon - r.epsilon).abs() <= 1e-12 * r.epsilon)
        .map(|w| w.order)
        .collect();
    orders.sort_unstable();
    orders.dedup();
    let outputs = r.outputs.len().max(1);
    orders
        .into_iter()
        .flat_map(|order| {
            (0..outputs).map(move |k| {
                let (err, compared) = frc_error(rows, r, order, k);
                FrcErrorEntry {
                    order,
                    epsilon: r.epsilon,
                    max_relative_error: err,
                    points_compared: compared,
                    output: r.outputs.get(k).cloned(),
                }
            })
        })
        .collect()
}

/// Largest `|A_frc - A_ref| / max A_ref` of output `k` over the reference
/// points covered by the FRC of `order`, and how many were covered.
pub fn frc_error(
    rows: &[FrcRow],
    r: &SteadyReference,
    order: usize,
    k: usize,
) -> (Option<f64>, usize) {
    let points: Vec<(f64, Vec<f64>)> = r
        .points
        .iter()
        .map(|p| (p.omega, p.amplitudes.clone()))
        .collect();
    frc_error_at(rows, &points, r.epsilon, order, k)
}

/// [`frc_error`] against reference points `(Omega, amplitudes)` at forcing
/// amplitude `epsilon` (steady states, or the orbits of `[reference]`): at
/// each point the FRC's amplitude nearest the reference's among its
/// branches there.
pub fn frc_error_at(
    rows: &[FrcRow],
    points: &[(f64, Vec<f64>)],
    epsilon: f64,
    order: usize,
    k: usize,
) -> (Option<f64>, usize) {
    let scale = points
        .iter()
        .map(|p| p.1.get(k).copied().unwrap_or(0.0))
        .fold(0.0, f64::max);
    let errs: Vec<f64> = points
        .iter()
        .filter_map(|(omega, amps)| {
            let a = *amps.get(k)?;
            frc_amplitude_at(rows, order, epsilon, k, *omega, a).map(|f| (f - a).abs() / scale)
        })
        .collect();
    let n = errs.len();
    ((n > 0).then(|| errs.into_iter().fold(0.0, f64::max)), n)
}

/// The main-branch orbits of a `[reference]` curve at `epsilon` as
/// reference points `(Omega, amplitudes)` (`None`: no curve at `epsilon`).
pub fn reference_points(r: &ReferenceFrc, epsilon: f64) -> Option<Vec<(f64, Vec<f64>)>> {
    r.branches
        .iter()
        .find(|b| {
            b.orbits.first().is_some_and(|o| {
                o.period_multiple == 1 && (o.epsilon - epsilon).abs() <= 1e-12 * epsilon.abs()
            })
        })
        .map(|b| b.orbits.iter().map(|o| (o.omega, o.linf.clone())).collect())
}
