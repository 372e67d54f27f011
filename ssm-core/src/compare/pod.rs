//! The `[pod]` study: POD reduced models (Stadlmayr, Witteveen & Steiner
//! 2017) made from a training run of the full model, run with the same HHT
//! integrator and the same fixed steps as the full model on the training
//! load and on loads not used for training; the outputs' errors against the
//! full runs over time, the time saved, and the paper's constraint-force
//! caveat measured (the reduced model's reactions against the full ones).
//! SSM reduced models of the same model can be run on the same loads
//! ([`super::ssm_run`]), so both reductions are compared on one table.
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint reduction
//! method for reduced order MBS models*, Multibody Syst. Dyn. (2017), Sects.
//! 3-4 (eqs. 7-14, the reaction forces of Sect. 3.4).

use std::time::Instant;

use faer::Mat;

use crate::fom::hht::{integrate, HhtOptions, HhtSolution};
use crate::fom::lifted::LiftedPoly;
use crate::fom::{given_start, DaeProblem, SimError};
use crate::model::system::{ModelError, OutputMap, System};
use crate::reduce::hyper::{deim, lifted_exact, HyperError, HyperInfo, Sample};
use crate::reduce::pod::Truncation;
use crate::reduce::pod_model::{reduce, PodReduceError, PodReduction, PodSettings, Reactions};
use crate::spectrum::MasterMode;
use crate::ssm::SsmExpansion;

/// Most instants at which the reaction forces are compared per run.
const REACTION_INSTANTS: usize = 400;

/// Why the study could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PodStudyError {
    /// A full-model run failed.
    #[error("{case}: full model: {source}")]
    FullRun {
        /// The run.
        case: String,
        /// Cause.
        source: Box<SimError>,
    },
    /// A truncation's reduction failed.
    #[error("{rom}: {source}")]
    Reduce {
        /// The reduced model.
        rom: String,
        /// Cause.
        source: Box<PodReduceError>,
    },
    /// A hyper-reduction could not be trained.
    #[error("{rom}: {source}")]
    Hyper {
        /// The reduced model.
        rom: String,
        /// Cause.
        source: HyperError,
    },
    /// A reduced model does not validate.
    #[error("{rom}: the reduced model is inconsistent: {source}")]
    ReducedModel {
        /// The reduced model.
        rom: String,
        /// Cause.
        source: Box<ModelError>,
    },
}

/// One load case: `eps Fext(Omega t)`, possibly switched in steps, from
/// rest or from a given start.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadCase {
    /// `train` or `test <k>`.
    pub label: String,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Forcing frequency.
    pub omega: f64,
    /// Length of the run.
    pub t_end: f64,
    /// Given displacements and velocities by state name (empty: from rest).
    pub start: Vec<(String, f64)>,
    /// Load steps `(t_k, a_k)` ([`DaeProblem::with_steps`]; empty: none).
    pub steps: Vec<(f64, f64)>,
    /// Whether the POD models were trained on it.
    pub trained: bool,
}

/// The HHT settings of every run and the reducer's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudySettings {
    /// Fixed step.
    pub step: f64,
    /// HHT `alpha`.
    pub alpha: f64,
    /// Constraint-reduction rank tolerance.
    pub rank_tol: f64,
    /// Snapshots of the stacked constraint Jacobian.
    pub jacobian_samples: usize,
}

/// A full-model run: its states, its outputs at the step ends, its time.
#[derive(Debug, Clone)]
pub struct FullRun {
    /// The HHT solution.
    pub solution: HhtSolution,
    /// Outputs at `solution.times` (time-major).
    pub outputs: Vec<Vec<f64>>,
    /// Seconds of integration.
    pub seconds: f64,
}

/// A POD reduced model.
#[derive(Debug, Clone)]
pub struct PodRom {
    /// Its label (`pod energy 1e-4`).
    pub label: String,
    /// The truncation.
    pub truncation: Truncation,
    /// POVs, POMs, `U`, the constraint reduction, the reduced model.
    pub reduction: PodReduction,
    /// The reduced model, validated (recast where it has `sin`, ...).
    pub system: System,
    /// Its nonlinearity evaluated through the lift (the full model's
    /// polynomial rows, exactly or hyper-reduced); `None` where the full
    /// model is recast (auxiliaries): the expanded polynomial is run.
    pub lifted: Option<LiftedPoly>,
    /// The hyper-reduction's training, for a hyper-reduced model.
    pub hyper: Option<HyperInfo>,
    /// Seconds of POD, constraint reduction, projection (and DEIM training).
    pub offline_s: f64,
}

/// The reaction forces of a reduced run against the full run's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReactionGap {
    /// Largest `|C_q^T mu|` of the full run.
    pub peak: f64,
    /// Largest difference in the full coordinates, relative to `peak`: the
    /// reactions of the removed constraints.
    pub full_space: f64,
    /// Largest difference of `U^T C_q^T mu`, relative to `peak`: what the
    /// reduced equations feel.
    pub in_subspace: f64,
}

/// The errors of a reduced run's outputs against the full run's.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorFigures {
    /// `e(t) = max_o |y_o - y_o,full| / max_t |y_o,full|` at the step ends.
    pub series: Vec<f64>,
    /// Its largest value over the run.
    pub max: f64,
    /// Its largest value over the second half of the run (steady part).
    pub late: f64,
}

/// A reduced model's run on one load case.
#[derive(Debug, Clone)]
pub struct RomRun {
    /// Outputs at the full run's step ends (time-major); empty on failure.
    pub outputs: Vec<Vec<f64>>,
    /// Seconds of the reduced run (integration and lift to the outputs).
    pub online_s: f64,
    /// The errors (`None` on failure).
    pub errors: Option<ErrorFigures>,
    /// Reactions against the full model's (POD models).
    pub reactions: Option<ReactionGap>,
    /// Distance of the start from the reduced model's manifold or subspace,
    /// relative to the start's size.
    pub start_distance: f64,
    /// Why the run failed.
    pub failure: Option<String>,
}

/// Errors of `rom` against `full` (time-major outputs at the same `times`).
pub(crate) fn error_figures(times: &[f64], full: &[Vec<f64>], rom: &[Vec<f64>]) -> ErrorFigures {
    let n_out = full.first().map_or(0, Vec::len);
    let peaks: Vec<f64> = (0..n_out)
        .map(|o| full.iter().map(|y| y[o].abs()).fold(0.0, f64::max))
        .collect();
    let series: Vec<f64> = full
        .iter()
        .zip(rom)
        .map(|(f, r)| {
            (0..n_out)
                .filter(|&o| peaks[o] > 0.0)
                .map(|o| (r[o] - f[o]).abs() / peaks[o])
                .fold(
                    0.0,
                    |a: f64, b| if b.is_nan() { f64::NAN } else { a.max(b) },
                )
        })
        .collect();
    let half = times.last().copied().unwrap_or(0.0) * 0.5;
    let worst = |it: &mut dyn Iterator<Item = f64>| {
        it.fold(
            0.0,
            |a: f64, b| if b.is_nan() { f64::NAN } else { a.max(b) },
        )
    };
    ErrorFigures {
        max: worst(&mut series.iter().copied()),
        late: worst(
            &mut times
                .iter()
                .zip(&series)
                .filter(|(t, _)| **t >= half)
                .map(|(_, e)| *e),
        ),
        series,
    }
}

/// The values of `outputs` at the state `z`.
pub(crate) fn output_values(outputs: &[&OutputMap], z: &[f64]) -> Vec<f64> {
    outputs
        .iter()
        .map(|o| o.weights.iter().map(|&(s, w)| w * z[s]).sum())
        .collect()
}

/// The full model's HHT run on `case`.
pub fn full_run(
    sys: &System,
    case: &LoadCase,
    settings: &StudySettings,
    outputs: &[&OutputMap],
) -> Result<FullRun, PodStudyError> {
    let fail = |source| PodStudyError::FullRun {
        case: case.label.clone(),
        source: Box::new(source),
    };
    let p = DaeProblem::new(sys, case.epsilon, case.omega).with_steps(&case.steps);
    let z0 = given_start(&p, &case.start).map_err(fail)?;
    let t = Instant::now();
    let solution = integrate(
        &p,
        &z0,
        0.0,
        case.t_end,
        &HhtOptions::new(settings.alpha, settings.step),
    )
    .map_err(fail)?;
    let seconds = t.elapsed().as_secs_f64();
    let outputs = solution
        .states
        .iter()
        .map(|z| output_values(outputs, z))
        .collect();
    Ok(FullRun {
        solution,
        outputs,
        seconds,
    })
}

/// The POD reduced models of the training run `train`: per truncation, the
/// POD model, then one hyper-reduced model per entry of `hyper` (labelled
/// `<truncation> deim <tol>`). Where the full model is polynomial in its
/// own states (no recast auxiliaries), every model evaluates its
/// nonlinearity through the lift ([`crate::reduce::hyper`]).
pub fn pod_roms(
    full_model: &ssm_api::Model,
    sys: &System,
    train: &HhtSolution,
    truncations: &[(String, Truncation)],
    hyper: &[Sample],
    settings: &StudySettings,
) -> Result<Vec<PodRom>, PodStudyError> {
    let mut roms = Vec::new();
    for (label, truncation) in truncations {
        let t = Instant::now();
        let pod_settings = PodSettings {
            truncation: *truncation,
            rank_tol: settings.rank_tol,
            jacobian_samples: settings.jacobian_samples,
        };
        let liftable_full = sys
            .recast
            .as_ref()
            .is_none_or(|r| r.n_original == sys.n_states());
        let reduction = reduce(
            full_model,
            sys,
            &train.states,
            &pod_settings,
            !liftable_full,
        )
        .map_err(|source| PodStudyError::Reduce {
            rom: label.clone(),
            source: Box::new(source),
        })?;
        let system =
            System::from_model(&format!("{} via pod", sys.plugin), reduction.model.clone())
                .map_err(|source| PodStudyError::ReducedModel {
                    rom: label.clone(),
                    source: Box::new(source),
                })?;
        let liftable = liftable_full
            && system
                .recast
                .as_ref()
                .is_none_or(|r| r.n_original == system.n_states());
        let nr = system.n_states();
        let v_rows = basis_rows(&reduction.lift.basis, sys.n_states());
        let lifted = liftable.then(|| lifted_exact(&sys.nonlinearity, &v_rows, nr));
        let offline_s = t.elapsed().as_secs_f64();
        let n = reduction.u.nrows();
        let mut extra = Vec::new();
        for &sample in hyper.iter().filter(|_| liftable) {
            let h = deim(
                &sys.nonlinearity,
                &full_model.a,
                &v_rows,
                nr,
                n,
                &train.states,
                sample,
            )
            .map_err(|source| PodStudyError::Hyper {
                rom: label.clone(),
                source,
            })?;
            // the sampled rows' linear part, where DEIM carries it, out of A_r
            let system = if h.linear_removed.is_empty() {
                system.clone()
            } else {
                let mut model = reduction.model.clone();
                for &(p, q, value) in &h.linear_removed {
                    model.a.push(p, q, -value);
                }
                System::from_model(&format!("{} via pod", sys.plugin), model).map_err(|source| {
                    PodStudyError::ReducedModel {
                        rom: label.clone(),
                        source: Box::new(source),
                    }
                })?
            };
            let what = match sample {
                Sample::Tolerance(tol) => format!("deim {tol:e}"),
                Sample::Points(m) => format!("deim {m} rows"),
            };
            extra.push(PodRom {
                label: format!("{label} {what}"),
                truncation: *truncation,
                reduction: reduction.clone(),
                system,
                offline_s: offline_s + h.info.seconds,
                lifted: Some(h.lifted),
                hyper: Some(h.info),
            });
        }
        roms.push(PodRom {
            label: label.clone(),
            truncation: *truncation,
            reduction,
            system,
            lifted,
            hyper: None,
            offline_s,
        });
        roms.extend(extra);
    }
    Ok(roms)
}

/// The rows of a sparse `V` (`n_full x nr`) as `(reduced state, weight)`.
fn basis_rows(v: &ssm_api::SparseMatrix, n_full: usize) -> Vec<Vec<(u32, f64)>> {
    let mut rows = vec![Vec::new(); n_full];
    for (i, j, w) in v.iter() {
        if w != 0.0 && i < n_full {
            rows[i].push((j as u32, w));
        }
    }
    rows
}

/// `(U^T q, U^T q', L^T mu)` of the shifted full state `z`, and the part of
/// `(q, q')` the subspace misses relative to their size (eqs. 8-9).
fn reduced_coordinates(rom: &PodRom, z: &[f64]) -> (Vec<f64>, f64) {
    let u = rom.reduction.u.as_ref();
    let l = rom.reduction.constraints.basis.as_ref();
    let (n, r) = (u.nrows(), u.ncols());
    let project = |off: usize| -> Vec<f64> {
        (0..r)
            .map(|j| (0..n).map(|i| u[(i, j)] * z[off + i]).sum())
            .collect()
    };
    let (q, v) = (project(0), project(n));
    let mu: Vec<f64> = (0..l.ncols())
        .map(|j| (0..l.nrows()).map(|i| l[(i, j)] * z[2 * n + i]).sum())
        .collect();
    let mut missed = 0.0;
    for (off, coords) in [(0, &q), (n, &v)] {
        for i in 0..n {
            let back: f64 = (0..r).map(|j| u[(i, j)] * coords[j]).sum();
            missed += (z[off + i] - back).powi(2);
        }
    }
    let size: f64 = z[..2 * n].iter().map(|x| x * x).sum();
    let y = q.into_iter().chain(v).chain(mu).collect();
    (y, (missed / size.max(f64::MIN_POSITIVE)).sqrt())
}

/// The shifted full state `V y` of the reduced state `y`, with the full
/// model's auxiliaries where it is recast.
fn lifted_state(rom: &PodRom, full: &System, y: &[f64]) -> Vec<f64> {
    let u = rom.reduction.u.as_ref();
    let l = rom.reduction.constraints.basis.as_ref();
    let (n, r, nl) = (u.nrows(), u.ncols(), l.ncols());
    let mut z = vec![0.0; 2 * n + l.nrows()];
    for i in 0..n {
        z[i] = (0..r).map(|j| u[(i, j)] * y[j]).sum();
        z[n + i] = (0..r).map(|j| u[(i, j)] * y[r + j]).sum();
    }
    for i in 0..l.nrows() {
        z[2 * n + i] = (0..nl).map(|j| l[(i, j)] * y[2 * r + j]).sum();
    }
    match &full.recast {
        Some(rc) => rc.lift(&z),
        None => z,
    }
}

/// The POD model `rom` on `case`, against the full run `full` at its step
/// ends: the reduced model starts from the projection of the full start
/// (made consistent), runs with the same fixed steps, and is lifted by `V`.
pub fn pod_case_run(
    rom: &PodRom,
    sys: &System,
    case: &LoadCase,
    full: &FullRun,
    settings: &StudySettings,
    outputs: &[&OutputMap],
) -> RomRun {
    let z0 = &full.solution.states[0];
    let (y0, start_distance) = reduced_coordinates(rom, z0);
    let rsys = &rom.system;
    let y0 = match &rsys.recast {
        Some(rc) => rc.lift(&y0),
        None => y0,
    };
    let p = match &rom.lifted {
        Some(l) => DaeProblem::lifted(rsys, case.epsilon, case.omega, l),
        None => DaeProblem::new(rsys, case.epsilon, case.omega),
    }
    .with_steps(&case.steps);
    let t = Instant::now();
    let run = integrate(
        &p,
        &y0,
        0.0,
        case.t_end,
        &HhtOptions::new(settings.alpha, settings.step),
    );
    let reduced = match run {
        Ok(r) => r,
        Err(e) => {
            return RomRun {
                outputs: Vec::new(),
                online_s: t.elapsed().as_secs_f64(),
                errors: None,
                reactions: None,
                start_distance,
                failure: Some(e.to_string()),
            }
        }
    };
    let n_red = rom.reduction.u.ncols();
    let lifted: Vec<Vec<f64>> = full
        .solution
        .times
        .iter()
        .map(|&t| lifted_state(rom, sys, &reduced.at(t, n_red)))
        .collect();
    let values: Vec<Vec<f64>> = lifted.iter().map(|z| output_values(outputs, z)).collect();
    let online_s = t.elapsed().as_secs_f64();
    let reactions = sys
        .mechanical
        .as_ref()
        .filter(|m| m.n_constraints > 0)
        .map(|_| reaction_gap(rom, sys, &full.solution.states, &lifted));
    RomRun {
        errors: Some(error_figures(&full.solution.times, &full.outputs, &values)),
        outputs: values,
        online_s,
        reactions,
        start_distance,
        failure: None,
    }
}

/// The reactions `C_q^T mu` of the lifted reduced run against the full
/// run's at up to [`REACTION_INSTANTS`] step ends.
fn reaction_gap(rom: &PodRom, sys: &System, full: &[Vec<f64>], lifted: &[Vec<f64>]) -> ReactionGap {
    let mut reactions = Reactions::new(sys);
    let u = &rom.reduction.u;
    let stride = full.len().div_ceil(REACTION_INSTANTS).max(1);
    let (mut peak, mut full_space, mut in_subspace) = (0.0f64, 0.0f64, 0.0f64);
    for (zf, zr) in full.iter().zip(lifted).step_by(stride) {
        let rf = reactions.at(zf);
        let rr = reactions.at(zr);
        let diff = Mat::from_fn(rf.len(), 1, |i, _| rf[i] - rr[i]);
        peak = rf.iter().fold(peak, |a, x| a.max(x.abs()));
        full_space = full_space.max(diff.norm_max());
        in_subspace = in_subspace.max((u.transpose() * &diff).norm_max());
    }
    let scale = peak.max(f64::MIN_POSITIVE);
    ReactionGap {
        peak,
        full_space: full_space / scale,
        in_subspace: in_subspace / scale,
    }
}

/// An SSM reduced model.
#[derive(Debug, Clone)]
pub struct SsmRom {
    /// Its label (`ssm pairs [1, 2] O(5)`).
    pub label: String,
    /// The master pairs.
    pub pairs: Vec<usize>,
    /// The master modes.
    pub masters: Vec<MasterMode>,
    /// The expansion.
    pub expansion: SsmExpansion,
    /// Seconds of spectrum and SSM.
    pub offline_s: f64,
}

/// Every model's run on one load case.
#[derive(Debug, Clone)]
pub struct CaseRun {
    /// The load.
    pub case: LoadCase,
    /// The full run's step ends.
    pub times: Vec<f64>,
    /// The full run's outputs there (time-major).
    pub full_outputs: Vec<Vec<f64>>,
    /// Seconds of the full run.
    pub full_s: f64,
    /// HHT steps of the full run.
    pub full_steps: usize,
    /// One run per POD model, in the order of [`PodStudy::pod`].
    pub pod: Vec<RomRun>,
    /// One run per SSM model, in the order of [`PodStudy::ssm`].
    pub ssm: Vec<RomRun>,
}

/// The whole `[pod]` study.
#[derive(Debug, Clone)]
pub struct PodStudy {
    /// Names of the outputs compared.
    pub outputs: Vec<String>,
    /// States of the full (validated) model.
    pub n_full_states: usize,
    /// The settings.
    pub settings: StudySettings,
    /// The POD models.
    pub pod: Vec<PodRom>,
    /// The SSM models.
    pub ssm: Vec<SsmRom>,
    /// The training run first, then the tests.
    pub cases: Vec<CaseRun>,
}

impl CaseRun {
    /// The case's full run with no reduced runs yet.
    pub fn new(case: LoadCase, full: &FullRun) -> Self {
        Self {
            case,
            times: full.solution.times.clone(),
            full_outputs: full.outputs.clone(),
            full_s: full.seconds,
            full_steps: full.solution.stats.steps,
            pod: Vec::new(),
            ssm: Vec::new(),
        }
    }
}
