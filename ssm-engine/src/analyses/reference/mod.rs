//! The full system's forced responses (`[reference]`): periodic orbits of
//! the full model by harmonic balance, continued in the forcing frequency
//! for each forcing amplitude (and in the amplitude at each frequency of
//! `amplitude_at`), with Floquet multipliers, folds, branch points, period
//! doublings and Neimark-Sacker points. Branches start from rest and, where
//! the plan has a forced response, from each of its branches lifted by the
//! SSM. It runs once, on the SSM of the order chosen, after the reduced
//! answers it is seeded from ([`super::Phase::FullSystem`]), and measures
//! each forced response curve's error against the reference curve of its
//! amplitude (`accuracy.measured`, against `harmonic_balance`).
//!
//! Its results keep the key `reference` of `summary.json` (older than the
//! registry); files `reference_frc.csv` (drawn on `frc.svg`, or on
//! `reference_frc.svg` without a forced response) and, with `amplitude_at`,
//! `reference_amplitude.csv`/`.svg`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5.1.2
//! (Fig. 5, validated there by collocation of the full system).

mod run;
pub mod write;

use super::frc::Frc;
use super::{output_of, Analysis, Answers, Beside, Context, Phase, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::fom::periodic::{floquet, monodromy};
use ssm_core::rom::accuracy::MeasuredError;
use ssm_core::spec::ReferenceSpec;
use write::ReferenceSummary;

/// The full system's forced responses as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Reference;

/// The reference curves, the warnings of their continuation and the
/// forced response's errors against them; as JSON, their summary
/// ([`ReferenceSummary`]).
#[derive(Debug, Clone)]
pub struct ReferenceCurves {
    /// The curves.
    pub frc: ReferenceFrc,
    /// What a user must see of them (a truncated series, a branch that
    /// stopped short, a start dropped, multipliers not computed).
    pub warnings: Vec<String>,
    /// The forced response's errors against them.
    pub measured: Vec<MeasuredError>,
    /// Whether a forced response of the reduced model draws them
    /// (`frc.svg`), so that they need no plot of their own.
    pub drawn_with_frc: bool,
}

super::serialized_as!(
    ReferenceCurves,
    ReferenceSummary,
    |r| ReferenceSummary::new(&r.frc)
);

/// Why the reference failed.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceRunError {
    /// An output the spec names is not the model's.
    #[error("[reference] the model has no output named '{0}'")]
    Output(String),
    /// Neither the spec nor a forced response gives the frequency range.
    #[error("[reference] give omega_range here or in [forcing]")]
    NoRange,
    /// The continuation of the full system failed.
    #[error(transparent)]
    Frc(#[from] ssm_core::fom::periodic::ReferenceError),
}

/// Continuation steps assumed per reference branch when `max_steps` allows
/// more (measured: 143 orbits a branch on the spatial oscillator's zoo
/// scene, 377 on the divider's, below).
const REFERENCE_STEPS: f64 = 400.0;

/// Factor of the reference's per-orbit operation count, fitted to two
/// measured runs (release build, 2 shared cores; CPU time of the reference,
/// since the machine was loaded):
/// - `zoo/spatial_oscillator_cubic_reference.toml` (7 states, H = 9, three
///   branches in `Omega` and one amplitude response, 643 orbits): 11.2 s
///   wall, under 6 s of CPU; the uncalibrated count said 83 s (at 500 steps
///   a branch);
/// - the divider of `benches/benches/reference.rs` (146 states, H = 5,
///   1606 Fourier coefficients, multipliers by the monodromy map; one
///   branch from rest at eps = 0.1 over [43.07, 49.87], 377 orbits): 651 s
///   wall, 329 s of CPU; the uncalibrated count said 14 min.
///
/// With 400 steps a branch and this factor the divider is estimated at
/// 5.6 min (its CPU time) and the oscillator at 33 s, an overestimate of
/// about 6 for small models, where the Hill eigenproblem's `(N (2H+1))^3`
/// bound is loose; the old count refused sound requests at 7-15 times their
/// run time.
const REFERENCE_CALIBRATION: f64 = 0.5;

impl Analysis for Reference {
    const NAME: &'static str = "reference";
    const OWN_TABLE: Option<&'static str> = Some("reference");
    const PHASE: Phase = Phase::FullSystem;
    type Spec = ReferenceSpec;
    type Output = ReferenceCurves;
    type Error = ReferenceRunError;

    /// Per step five sparse factorizations of the harmonic-balance Jacobian
    /// (a dense `(2H+1)^2` block per nonzero of the pencil, eliminated at
    /// `(2H+1)^3` each) and one Floquet analysis: up to the dense Hill limit
    /// one Hill eigenproblem (`(N (2H+1))^3`), above it the monodromy
    /// matrix.
    fn work(r: &ReferenceSpec, sizes: &Sizes<'_>) -> Work {
        let k = 2.0 * r.harmonics as f64 + 1.0;
        let n = sizes.states;
        let nu = n * k;
        let pattern = sizes.nnz + sizes.factors;
        let factor = 2.0 * pattern * k.powi(3);
        // multipliers: the dense Hill eigenproblem, or the monodromy matrix
        // (16 H steps, each a sparse LU of the 3N stages and N solves, then
        // a dense N x N eigenproblem; measured 0.23 s per orbit on the
        // divider, N = 146, H = 5, which this estimate puts at 0.3 s); above
        // 200 states the dominant multipliers by subspace iteration (the
        // 16 H LUs kept, about three passes of a block of 16: some 64 solves
        // per step)
        let stage_steps = 8.0 * (k - 1.0);
        let hill_limit = floquet::MAX_HILL_COEFFICIENTS as f64;
        let hill = if !r.stability {
            0.0
        } else if nu <= hill_limit {
            nu.powi(3)
        } else if n <= monodromy::MAX_MONODROMY_STATES as f64 {
            stage_steps * 2.0 * n * pattern + 10.0 * n.powi(3)
        } else {
            stage_steps * 2.0 * 64.0 * pattern
        };
        // the kept LUs of the period's steps (9 blocks of the pencil's
        // pattern and fill each)
        let kept_lus = if r.stability && nu > hill_limit {
            stage_steps * 9.0 * pattern * 16.0
        } else {
            0.0
        };
        let branches = (r.epsilon.len() + r.amplitude_at.len()) as f64;
        // a branch's scaled arclength is of order ten: small steps take more
        let max_steps = r.max_steps as f64;
        let by_step = REFERENCE_STEPS.max(10.0 / r.step);
        let steps = max_steps.min(by_step);
        // each orbit's amplitudes of every output (a sum over the harmonics)
        let outputs = r.outputs.as_ref().map_or(sizes.outputs, Vec::len) as f64;
        let ops = REFERENCE_CALIBRATION * branches * steps * (5.0 * factor + hill)
            + branches * steps * outputs * 8.0 * nu;
        let bytes = 8.0 * pattern * k * k * 4.0
            + 8.0 * nu * nu.min(1500.0)
            + kept_lus
            + branches * steps * 8.0 * (outputs + 8.0);
        // the key that drives the cost: the number of steps when it exceeds
        // a typical branch's (max_steps when it caps the steps a small step
        // asks for, unless only step was changed from its default), else
        // the harmonics
        let caps = max_steps <= by_step
            && (r.max_steps != ReferenceSpec::DEFAULT_MAX_STEPS
                || r.step == ReferenceSpec::DEFAULT_STEP);
        let (key, advice) = if steps > REFERENCE_STEPS && caps {
            ("reference.max_steps", "lower max_steps")
        } else if steps > REFERENCE_STEPS {
            ("reference.step", "raise step (fewer, longer steps)")
        } else {
            (
                "reference.harmonics",
                "lower harmonics, or give fewer epsilon or amplitude_at",
            )
        };
        Work {
            ops,
            bytes,
            key,
            what: format!(
                "the full-system reference ({branches:.0} branches of up to {steps:.0} orbits with {nu:.0} Fourier coefficients)"
            ),
            advice,
        }
    }

    fn run(spec: &ReferenceSpec, cx: &Context<'_>) -> Result<ReferenceCurves, ReferenceRunError> {
        let reduced = output_of::<Frc>(cx.earlier).map(|f| &f.0);
        let (frc, warnings) = run::reference_stage(
            spec,
            cx.system,
            cx.outputs,
            reduced.map(|f| (cx.ssm, f)),
            cx.tolerance,
            cx.progress,
        )?;
        let measured = reduced.map_or_else(Vec::new, |f| run::reference_errors(f, &frc));
        Ok(ReferenceCurves {
            frc,
            warnings,
            measured,
            drawn_with_frc: reduced.is_some(),
        })
    }

    fn warnings(output: &ReferenceCurves) -> Vec<String> {
        output.warnings.clone()
    }

    fn measured(output: &ReferenceCurves) -> Vec<MeasuredError> {
        output.measured.clone()
    }

    fn summarize(output: &ReferenceCurves, answers: &mut Answers) {
        answers.reference = Some(ReferenceSummary::new(&output.frc));
    }

    fn files(
        output: &ReferenceCurves,
        _outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        let r = &output.frc;
        let mut files = vec![(
            "reference_frc.csv".to_owned(),
            write::reference_csv(r).into_bytes(),
        )];
        if !output.drawn_with_frc {
            files.push((
                "reference_frc.svg".into(),
                write::reference_svg(r)?.into_bytes(),
            ));
        }
        if !r.amplitude.is_empty() {
            files.push((
                "reference_amplitude.csv".into(),
                write::amplitude_csv(r).into_bytes(),
            ));
            files.push((
                "reference_amplitude.svg".into(),
                write::amplitude_svg(r)?.into_bytes(),
            ));
        }
        Ok(files)
    }
}
