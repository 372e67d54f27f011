//! The invariance error of the SSM (`[outputs.invariance_error]`): eq. (41),
//! the relative residual of the invariance equation on tori of given radii
//! in the reduced coordinates, for each order asked for; how far the
//! truncated expansion is from an invariant manifold where the answers are
//! read.
//!
//! Its results keep the key `invariance_error` of `summary.json` (older than
//! the registry); files `invariance.csv` and `invariance.svg`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), eq. (41)
//! and Fig. 21.

mod write;

pub use write::InvarianceSummary;

use super::{Analysis, Answers, Beside, Context, Needs, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::rom::autonomous::{invariance_table, ResultError};
use ssm_core::spec::{InvarianceSpec, SpecError};

/// The invariance error as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Invariance;

impl Analysis for Invariance {
    const NAME: &'static str = "invariance";
    const OWN_TABLE: Option<&'static str> = Some("outputs.invariance_error");
    type Spec = InvarianceSpec;
    type Output = Vec<InvarianceSummary>;
    type Error = ResultError;

    fn check(spec: &InvarianceSpec, needs: &Needs) -> Result<(), SpecError> {
        spec.check(needs.max_order)
    }

    fn orders(spec: &InvarianceSpec) -> Vec<usize> {
        spec.orders.clone()
    }

    /// `n_alpha^(pairs - 1) n_theta^pairs` points per radius and order, each
    /// an evaluation of `W` and of the vector field.
    fn work(spec: &InvarianceSpec, sizes: &Sizes<'_>) -> Work {
        let pairs = sizes.pairs.max(1);
        let nvar = 2 * pairs;
        let points =
            (spec.n_alpha as f64).powi(pairs as i32 - 1) * (spec.n_theta as f64).powi(pairs as i32);
        let evaluations = points * (spec.radii.len() * spec.orders.len()) as f64;
        Work {
            ops: evaluations * (4.0 * sizes.multi_indices * sizes.states + 4.0 * sizes.factors),
            bytes: points * (16.0 * nvar as f64 + 64.0),
            key: "outputs.invariance_error.n_theta",
            what: format!("the invariance error on {points:.1e} points per radius and order (n_alpha^(pairs-1) n_theta^pairs with {pairs} pairs)"),
            advice: "lower n_alpha and n_theta",
        }
    }

    fn run(spec: &InvarianceSpec, cx: &Context<'_>) -> Result<Self::Output, ResultError> {
        Ok(InvarianceSummary::new(&invariance_table(
            cx.ssm, cx.system, spec,
        )?))
    }

    fn summarize(output: &Self::Output, answers: &mut Answers) {
        answers.invariance_error = Some(output.clone());
    }

    fn files(
        output: &Self::Output,
        _outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        if output.is_empty() {
            return Ok(Vec::new());
        }
        Ok(vec![
            (
                "invariance.csv".into(),
                write::invariance_csv(output).into(),
            ),
            (
                "invariance.svg".into(),
                write::invariance_svg(output)?.into(),
            ),
        ])
    }
}
