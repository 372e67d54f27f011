//! The full system against the reduced answers: the forced response of
//! `[reference]`, the transient and steady states of `[validate]` and the
//! speed-against-error report of `[report]`; the errors they measure join
//! the run's accuracy table. (The sampled runs of `[simulate]` are an
//! analysis of the full-system phase: `crate::analyses::simulate`.)

use std::time::Instant;

use super::{reference, JobError, Stage};
use crate::output::summary::Timing;
use crate::plan::named_outputs;
use ssm_core::compare::report::{report, Report, ReportInputs};
use ssm_core::compare::validation::{validation, Validation};
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::rom::accuracy::{Accuracy, MeasuredError};
use ssm_core::rom::forced_response::ForcedResponse;
use ssm_core::spec::ValidationSpec;
use ssm_core::ssm::SsmExpansion;

/// What the full system answered.
pub(super) struct FullSystem {
    /// The forced response of `[reference]`.
    pub reference: Option<ReferenceFrc>,
    /// The comparisons of `[validate]`.
    pub validation: Option<Validation>,
    /// The speed-against-error report.
    pub report: Option<Report>,
}

/// The full-system stages the plan of `stage` asks for, on the reduced
/// answers at `expansion` (its forced response `frc`); their measured errors
/// go into `accuracy`, their seconds into `timing`.
pub(super) fn full_system(
    stage: &Stage<'_>,
    expansion: &SsmExpansion,
    frc: Option<&ForcedResponse>,
    accuracy: &mut Accuracy,
    timing: &mut Timing,
    warnings: &mut Vec<String>,
) -> Result<FullSystem, JobError> {
    let (plan, system, sp) = (stage.plan, stage.system, stage.sp);
    let (coordinates, progress) = (stage.coordinates, stage.progress);
    let tolerance = accuracy.tolerance;
    let full_frc = match &plan.reference {
        Some(sec) => {
            let (r, w) = reference::reference_stage(
                plan,
                sec,
                system,
                coordinates,
                frc.map(|f| (expansion, f)),
                tolerance,
                progress,
            )?;
            warnings.extend(w);
            timing.reference = r.seconds;
            Some(r)
        }
        None => None,
    };

    let t = Instant::now();
    let mut compared = coordinates.to_vec();
    let checked = match &plan.validation {
        Some(vspec) => {
            progress.stage("full-system validation");
            if let Some(names) = &vspec.outputs {
                compared = named_outputs(system, names, "validate.outputs")?;
            }
            Some(validation(
                expansion,
                system,
                vspec,
                &compared,
                coordinates,
                &sp.masters,
                frc.map(|f| f.rows.as_slice()),
            )?)
        }
        None => None,
    };
    accuracy.measured = checked.as_ref().map_or_else(Vec::new, measured_errors);
    if let (Some(f), Some(r)) = (frc, &full_frc) {
        accuracy.measured.extend(reference::reference_errors(f, r));
    }
    timing.validation = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let speed = match &plan.report {
        Some(r) => {
            progress.stage("speed-against-error report");
            let orders = r.orders_up_to(expansion.order);
            let inputs = ReportInputs {
                orders: &orders,
                masters: &sp.masters,
                others: stage.others,
                resonance_tol: plan.ssm.resonance_tol,
                outputs: &compared,
                forcing: plan.frc.as_ref(),
                validation: checked.as_ref(),
                p0: checked
                    .as_ref()
                    .and_then(|v| v.transient.as_ref())
                    .map(|t| t.result.p0.clone()),
                rtol: plan
                    .validation
                    .as_ref()
                    .map_or(ValidationSpec::DEFAULT_RTOL, |v| v.rtol),
                tolerance: plan.ssm.tolerance,
                reference: full_frc.as_ref(),
            };
            Some(report(system, &inputs)?)
        }
        None => None,
    };
    timing.report = t.elapsed().as_secs_f64();

    Ok(FullSystem {
        reference: full_frc,
        validation: checked,
        report: speed,
    })
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
