//! The speed-against-error report (`[report]`): for each expansion order,
//! the SSM rebuilt and the reduced answers recomputed on it, each with its
//! seconds and its error against the full system (the invariance error,
//! the transient against `[validate]`'s, the forced response against the
//! curves of `[reference]` or else the steady states of `[validate]`),
//! beside the seconds of the full-system runs. It runs once, after the
//! full-system comparisons it reads ([`super::Phase::FullSystem`]).
//!
//! Its results keep the key `report` of `summary.json` (older than the
//! registry); files `report.csv`, `report.md` and `report.svg`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5
//! (the run times of the reduced and full models compared there).

pub mod write;

use serde::{Deserialize, Serialize};
use ssm_kernel::number::short;

use super::reference::Reference;
use super::validation::Validate;
use super::{output_of, outputs_named, Analysis, Answers, Beside, Context, Phase, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::compare::report::{report, Report, ReportError, ReportInputs};
use ssm_core::spec::FrcSpec;
use write::ReportSummary;

/// The report as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct SpeedReport;

/// `[report]` with what it takes from the rest of the plan resolved (what
/// [`crate::plan::Plan::requested`] hands the registry).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportRequest {
    /// Expansion orders, one row each (`None`: the odd orders from 3 up to
    /// the SSM's order, which is always included).
    pub orders: Option<Vec<usize>>,
    /// The forced response recomputed at each order (`[forcing]`), if any.
    pub forcing: Option<FrcSpec>,
    /// The outputs compared (`[validate] outputs`; `None`: the plan's
    /// coordinates); the first is the amplitude of the backbone and the
    /// forced response.
    pub outputs: Option<Vec<String>>,
    /// Relative tolerance of the reduced transients (the full system's, of
    /// `[validate]`).
    pub rtol: f64,
    /// Resonance tolerance of the SSMs rebuilt (`[ssm] resonance_tol`).
    pub resonance_tol: f64,
}

impl ReportRequest {
    /// The orders of the report on an SSM of order `max`.
    fn orders_up_to(&self, max: usize) -> Vec<usize> {
        ssm_core::spec::ReportSpec {
            orders: self.orders.clone(),
        }
        .orders_up_to(max)
    }
}

/// The report, with the model it was made of; as JSON, its summary
/// ([`ReportSummary`]).
#[derive(Debug, Clone)]
pub struct ReportOfModel {
    /// The report.
    pub report: Report,
    /// The model's name.
    pub model: String,
    /// The model's states.
    pub states: usize,
}

super::serialized_as!(ReportOfModel, ReportSummary, |r| ReportSummary::new(
    &r.report
));

/// Why the report failed.
#[derive(Debug, thiserror::Error)]
pub enum SpeedReportError {
    /// An output the request names is not the model's.
    #[error("[report] the model has no output named '{0}'")]
    Output(String),
    /// A reduced model of one order failed.
    #[error(transparent)]
    Report(#[from] ReportError),
}

impl Analysis for SpeedReport {
    const NAME: &'static str = "report";
    const OWN_TABLE: Option<&'static str> = Some("report");
    const PHASE: Phase = Phase::FullSystem;
    const STAGE: Option<&'static str> = Some("speed-against-error report");
    type Spec = ReportRequest;
    type Output = ReportOfModel;
    type Error = SpeedReportError;

    fn orders(spec: &ReportRequest) -> Vec<usize> {
        spec.orders.clone().unwrap_or_default()
    }

    /// The SSMs rebuilt at its orders are costed with the SSM's order
    /// (`ssm.order`); here the forced responses recomputed on them: per
    /// order and curve, the points of `[forcing]` on the polar form (`4`
    /// evaluations of `64` samples each over the expansion's multi-indices).
    fn work(spec: &ReportRequest, sizes: &Sizes<'_>) -> Work {
        // without orders: the odd orders up to the SSM's (3 when the run
        // chooses it)
        let top = sizes.fixed_order.unwrap_or(3).max(3);
        let rows = spec.orders.as_ref().map_or(top.div_ceil(2), Vec::len) as f64;
        let (curves, points) = spec
            .forcing
            .as_ref()
            .map_or((0.0, 0.0), |f| (f.epsilon.len() as f64, f.points as f64));
        let ops = rows * curves * points * 4.0 * sizes.multi_indices * 64.0;
        Work {
            ops,
            bytes: rows * curves * points * 8.0 * (16.0 + sizes.outputs as f64),
            key: if spec.orders.is_some() {
                "report.orders"
            } else {
                "report"
            },
            what: format!(
                "a speed-against-error report of {} order(s) with {} forced response curve(s) each",
                short(rows),
                short(curves)
            ),
            advice: "give fewer orders",
        }
    }

    fn run(spec: &ReportRequest, cx: &Context<'_>) -> Result<ReportOfModel, SpeedReportError> {
        let compared = outputs_named(
            cx.system,
            spec.outputs.as_deref(),
            cx.outputs,
            SpeedReportError::Output,
        )?;
        let validation = output_of::<Validate>(cx.earlier).map(|c| &c.0);
        let orders = spec.orders_up_to(cx.ssm.order);
        let inputs = ReportInputs {
            orders: &orders,
            masters: cx.masters,
            others: cx.others,
            resonance_tol: spec.resonance_tol,
            outputs: &compared,
            forcing: spec.forcing.as_ref(),
            validation,
            p0: validation
                .and_then(|v| v.transient.as_ref())
                .map(|t| t.result.p0.clone()),
            rtol: spec.rtol,
            tolerance: cx.tolerance,
            reference: output_of::<Reference>(cx.earlier).map(|r| &r.frc),
        };
        Ok(ReportOfModel {
            report: report(cx.system, &inputs)?,
            model: cx.system.name.clone(),
            states: cx.system.n_states(),
        })
    }

    fn summarize(output: &ReportOfModel, answers: &mut Answers) {
        answers.report = Some(ReportSummary::new(&output.report));
    }

    fn files(
        output: &ReportOfModel,
        _outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        let r = &output.report;
        Ok(vec![
            ("report.csv".to_owned(), write::csv(r).into_bytes()),
            (
                "report.md".to_owned(),
                write::markdown(&output.model, output.states, r).into_bytes(),
            ),
            ("report.svg".to_owned(), write::svg(r)?.into_bytes()),
        ])
    }
}
