//! Forced response curves (`[forcing]`): the periodic responses of the
//! reduced model on the SSM to `epsilon Fext cos(Omega t)`, continued in the
//! forcing frequency for each forcing amplitude and expansion order, with
//! their stability, folds, branch points and torus bifurcations (one master
//! pair: the polar form's closed-form curves; several: the reduced
//! harmonic-balance continuation), each curve with the estimate of its
//! error.
//!
//! Its results keep the key `frc` of `summary.json` (older than the
//! registry) and its estimates the `frc` entries of `accuracy.answers`;
//! files `frc.csv` and `frc.svg` (with the full system's steady states of
//! `[validate]` and forced responses of `[reference]` drawn in).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 3.4
//! (eqs. 16-21) and Figs. 11, 15 and 23.

mod write;

pub use write::{FrcBifurcationSummary, FrcCurveSummary, FrcSummary};

use ssm_kernel::number::short;

use super::{Analysis, Answers, Beside, Context, Needs, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::rom::accuracy::AnswerEstimate;
use ssm_core::rom::forced_response::{forced_response, ForcedResponse, FrcError};
use ssm_core::spec::{FrcSpec, SpecError};

/// The forced response as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Frc;

/// The forced response curves; as JSON, their summary ([`FrcSummary`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ForcedResponses(pub ForcedResponse);

super::serialized_as!(ForcedResponses, FrcSummary, |f| FrcSummary::new(&f.0));

impl Analysis for Frc {
    const NAME: &'static str = "frc";
    const OWN_TABLE: Option<&'static str> = Some("forcing");
    const STAGE: Option<&'static str> = Some("forced response curves");
    type Spec = FrcSpec;
    type Output = ForcedResponses;
    type Error = FrcError;

    fn check(spec: &FrcSpec, needs: &Needs) -> Result<(), SpecError> {
        spec.check(needs.pairs, needs.max_order)
    }

    fn orders(spec: &FrcSpec) -> Vec<usize> {
        spec.orders.clone().unwrap_or_default()
    }

    /// Per point of each curve: the polar form (one pair) or `20` Newton
    /// iterations of the reduced harmonic balance with `8` samples each
    /// (several pairs), and the outputs' harmonics from the table of the
    /// resonant harmonics (several pairs).
    fn work(spec: &FrcSpec, sizes: &Sizes<'_>) -> Work {
        let pairs = sizes.masters.len().max(1);
        let (n_idx, coords) = (sizes.multi_indices, sizes.outputs as f64);
        let nvar = 2.0 * pairs as f64;
        let points = spec.points as f64;
        let orders = spec.orders.as_deref().unwrap_or(&[]);
        let curves = (spec.epsilon.len() * orders.len().max(1)) as f64;
        let top = orders
            .iter()
            .copied()
            .max()
            .unwrap_or(0)
            .max(sizes.fixed_order.unwrap_or(0));
        let (slots, samples) = if pairs > 1 {
            let ratios = ssm_core::rom::forced_response::resonance_ratios(spec, sizes.masters);
            ssm_core::rom::forced_multi::harmonic_table(&ratios, top.max(1))
        } else {
            (0.0, 0.0)
        };
        let per_point = if pairs == 1 {
            4.0 * n_idx * 64.0
        } else {
            20.0 * 8.0 * (4.0 * n_idx * nvar + nvar.powi(3))
                + coords * (4.0 * n_idx + 4.0 * samples * slots)
        };
        let (table_ops, table_bytes) = (
            curves * 20.0 * samples * slots,
            16.0 * samples * slots + 16.0 * coords * slots,
        );
        let ops = curves * points * per_point + table_ops;
        let bytes = curves * points * 8.0 * (16.0 + 4.0 * nvar + coords) + table_bytes;
        match &spec.resonance {
            Some(r) if table_bytes * 2.0 > bytes || table_ops * 2.0 > ops => Work {
                ops,
                bytes,
                key: "forcing.resonance",
                what: format!(
                    "forced response curves at resonance ratios {} ({} harmonics sampled at {} phases)",
                    ssm_kernel::number::list(r),
                    short(slots),
                    short(samples)
                ),
                advice: "use ratios near the master pairs' frequencies over Omega (small integers or fractions)",
            },
            _ => Work {
                ops,
                bytes,
                key: "forcing.points",
                what: format!(
                    "{} forced response curve(s) of {} points",
                    short(curves),
                    short(points)
                ),
                advice: "lower the number of points, epsilon values or orders",
            },
        }
    }

    fn run(spec: &FrcSpec, cx: &Context<'_>) -> Result<ForcedResponses, FrcError> {
        forced_response(
            cx.ssm,
            cx.system,
            cx.masters,
            spec,
            cx.outputs,
            cx.tolerance,
        )
        .map(ForcedResponses)
    }

    fn estimates(output: &ForcedResponses) -> Vec<AnswerEstimate> {
        output
            .0
            .curves
            .iter()
            .map(|c| AnswerEstimate {
                answer: "frc",
                order: c.order,
                epsilon: Some(c.epsilon),
                estimate: Some(c.error_estimate()),
                untrusted: c.untrusted,
                trusted_up_to: None,
            })
            .collect()
    }

    fn warnings(output: &ForcedResponses) -> Vec<String> {
        output.0.warnings.clone()
    }

    fn summarize(output: &ForcedResponses, answers: &mut Answers) {
        answers.frc = Some(FrcSummary::new(&output.0));
    }

    fn files(
        output: &ForcedResponses,
        _outputs: &[String],
        beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        Ok(vec![
            ("frc.csv".into(), write::frc_csv(&output.0).into_bytes()),
            (
                "frc.svg".into(),
                write::frc_svg(&output.0, beside.steady, beside.reference)?.into_bytes(),
            ),
        ])
    }
}
