//! The full system against the reduced answers (`[validate]`): a transient
//! of the full model from a start on (or near) the SSM, integrated by Radau
//! IIA and compared sample by sample with the reduced model's lifted
//! trajectory (with its distance to the SSM and its algebraic residual),
//! and steady states of the forced full model at given frequencies,
//! compared with the forced response curves. It runs once, on the SSM of
//! the order chosen, after the reduced answers ([`super::Phase::FullSystem`]);
//! the errors it measures join `accuracy.measured` (the transient's against
//! `full_transient`, each curve's against `steady_state`).
//!
//! Its results keep the key `validation` of `summary.json` (older than the
//! registry); files `validation.csv`/`.svg` and `steady_state.csv` (the
//! steady states are also drawn on `frc.svg`).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5
//! (the full-system transients and steady states of Figs. 6, 9-15, 21-22).

pub mod write;

use super::frc::Frc;
use super::{output_of, outputs_named, Analysis, Answers, Beside, Context, Phase, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::compare::validation::{validation, Validation};
use ssm_core::compare::ValidateError;
use ssm_core::rom::accuracy::MeasuredError;
use ssm_core::spec::ValidationSpec;
use ssm_core::ssm::Dynamics;
use write::ValidationSummary;

/// The full-system comparisons as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Validate;

/// The comparisons; as JSON, their summary ([`ValidationSummary`]).
#[derive(Debug, Clone)]
pub struct Comparisons(pub Validation);

super::serialized_as!(Comparisons, ValidationSummary, |c| ValidationSummary::new(
    &c.0
));

/// Why the comparisons failed.
#[derive(Debug, thiserror::Error)]
pub enum ValidationError {
    /// An output the spec names is not the model's.
    #[error("[validate] the model has no output named '{0}'")]
    Output(String),
    /// A full-system run failed.
    #[error(transparent)]
    Run(#[from] ValidateError),
}

impl Analysis for Validate {
    const NAME: &'static str = "validation";
    const OWN_TABLE: Option<&'static str> = Some("validate");
    const PHASE: Phase = Phase::FullSystem;
    const STAGE: Option<&'static str> = Some("full-system validation");
    type Spec = ValidationSpec;
    type Output = Comparisons;
    type Error = ValidationError;

    fn orders(spec: &ValidationSpec) -> Vec<usize> {
        spec.transient.iter().filter_map(|t| t.order).collect()
    }

    /// The transient: one implicit step per step of the integrator over
    /// `t_end` (at least one per sample), and per sample the lift through
    /// `W` and a Newton projection onto the SSM (about ten evaluations of
    /// `W` and its Jacobian). The steady states: up to `max_periods` periods
    /// (of the longest period multiple) per frequency, the frequencies
    /// spread over the machine's cores. The two run one after the other:
    /// their times add, their memory does not.
    fn work(v: &ValidationSpec, sizes: &Sizes<'_>) -> Work {
        let step = sizes.sparse_solve;
        let coords = v.outputs.as_ref().map_or(sizes.outputs, Vec::len) as f64;
        let nvar = 2.0 * sizes.pairs as f64;
        let periods = |t_end: f64| t_end * sizes.periods_per_time;
        let steps = |t_end: f64| match sizes.dynamics {
            Dynamics::Map { .. } => periods(t_end),
            Dynamics::Flow => periods(t_end) * sizes.steps_per_period,
        };
        let mut parts: Vec<(Work, f64)> = Vec::new();
        if let Some(tr) = &v.transient {
            let n = steps(tr.t_end);
            let samples = tr.samples as f64;
            let per_sample = 10.0 * sizes.multi_indices * sizes.states * (nvar + 1.0);
            let key = if n * step > samples * per_sample {
                "validate.t_end"
            } else {
                "validate.samples"
            };
            let ops = n.max(samples) * step + samples * per_sample;
            parts.push((
                Work {
                    ops,
                    bytes: samples * 8.0 * (3.0 * sizes.states + 4.0 * coords),
                    key,
                    what: format!(
                        "the full-system transient over {:.1e} periods with {samples:.1e} samples",
                        periods(tr.t_end)
                    ),
                    advice: "shorten [validate] t_end or take fewer samples",
                },
                ops,
            ));
        }
        if let Some(ss) = &v.steady_state {
            let freqs = ss.omegas.len() as f64;
            let periods = ss.max_periods as f64 * ss.max_period_multiple as f64;
            let per_period = sizes.steps_per_period.max(ss.samples_per_period as f64);
            // frequencies run in parallel on the machine's cores
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
            let ops = freqs * periods * per_period * step / cores;
            parts.push((
                Work {
                    ops,
                    bytes: freqs * (8.0 * sizes.states * per_period + 1e3),
                    key: "validate.steady_state.max_periods",
                    what: format!(
                        "steady states at {freqs:.0} frequencies over up to {periods:.1e} periods each"
                    ),
                    advice: "lower max_periods (or the number of frequencies)",
                },
                ops,
            ));
        }
        let ops: f64 = parts.iter().map(|p| p.1).sum();
        let bytes = parts.iter().map(|p| p.0.bytes).fold(0.0, f64::max);
        let what = parts
            .iter()
            .map(|p| p.0.what.clone())
            .collect::<Vec<_>>()
            .join(" and ");
        // the part that costs most names the key and the advice
        let main = parts
            .into_iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|p| p.0);
        match main {
            Some(m) => Work {
                ops,
                bytes,
                what,
                ..m
            },
            None => Work {
                ops: 0.0,
                bytes: 0.0,
                key: "validate",
                what: "no full-system comparison".into(),
                advice: "",
            },
        }
    }

    fn run(spec: &ValidationSpec, cx: &Context<'_>) -> Result<Comparisons, ValidationError> {
        let compared = outputs_named(
            cx.system,
            spec.outputs.as_deref(),
            cx.outputs,
            ValidationError::Output,
        )?;
        let frc = output_of::<Frc>(cx.earlier).map(|f| f.0.rows.as_slice());
        Ok(Comparisons(validation(
            cx.ssm, cx.system, spec, &compared, cx.outputs, cx.masters, frc,
        )?))
    }

    fn measured(output: &Comparisons) -> Vec<MeasuredError> {
        measured_errors(&output.0)
    }

    fn summarize(output: &Comparisons, answers: &mut Answers) {
        answers.validation = Some(ValidationSummary::new(&output.0));
    }

    fn files(
        output: &Comparisons,
        _outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        let v = &output.0;
        let mut files = Vec::new();
        if let Some(t) = &v.transient {
            files.push((
                "validation.csv".to_owned(),
                write::transient_csv(t).into_bytes(),
            ));
            files.push((
                "validation.svg".to_owned(),
                write::transient_svg(t)?.into_bytes(),
            ));
        }
        if let Some(r) = &v.steady {
            files.push((
                "steady_state.csv".to_owned(),
                write::steady_csv(r).into_bytes(),
            ));
        }
        Ok(files)
    }
}

/// The errors `[validate]` measured against the full system: the
/// transient's and each forced response curve's against the steady states.
fn measured_errors(v: &Validation) -> Vec<MeasuredError> {
    let mut list: Vec<MeasuredError> = v
        .transient
        .iter()
        .map(|t| MeasuredError {
            answer: "transient",
            order: t.order,
            epsilon: None,
            relative_error: Some(t.max_relative_error),
            output: t.relative_errors[..t.n_compared]
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map(|(k, _)| t.outputs[k].clone()),
            against: "full_transient",
        })
        .collect();
    for e in v.steady.iter().flat_map(|s| s.frc_errors.iter().flatten()) {
        list.push(MeasuredError {
            answer: "frc",
            order: e.order,
            epsilon: Some(e.epsilon),
            relative_error: e.max_relative_error,
            output: e.output.clone(),
            against: "steady_state",
        });
    }
    list
}
