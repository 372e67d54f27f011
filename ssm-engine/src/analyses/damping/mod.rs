//! The amplitude-dependent damping of a master pair (`[analysis.damping]`):
//! `zeta(rho) = -rho' / (rho omega)` from the polar form of the reduced
//! dynamics on its two-dimensional SSM, beside the backbone `omega(rho)`.
//! This is the curve experimentalists compare with decay measurements: the
//! envelope of a free decay read by the Hilbert transform gives the same
//! ratio, `zeta = -A' / (A omega)` (see
//! [`ssm_core::compare::instantaneous::hilbert_cycles`]).
//!
//! For a flow, `rho' = rho Re f(rho)` and `theta' = Im f(rho)` with
//! `f(rho) = lambda + c_1 rho^2 + c_2 rho^4 + ...` (the coefficients of the
//! polar form), so `zeta = -Re f / Im f`; at `rho = 0` that is
//! `-Re lambda / Im lambda`, `zeta_0 / sqrt(1 - zeta_0^2)` for a viscously
//! damped mode of damping ratio `zeta_0` (the per-period convention of a
//! logarithmic decrement `delta`, `zeta = delta / (2 pi)`). For a map of
//! period `T` the polar form gives the multiplier `f(rho)` of one step, and
//! `-rho'/rho` and `omega` are `-ln|f| / T` and `arg f / T`.
//!
//! Files: `damping.csv` and `damping.svg` (the backbone above, the damping
//! below, against the amplitude of the first output; the part beyond the
//! amplitude up to which the error estimate meets the tolerance dashed).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 3.3
//! (the polar form); G. Haller, S. Ponsioen, *Nonlinear normal modes and
//! spectral submanifolds*, Nonlinear Dyn. 86 (2016), Sect. 6 (backbone and
//! damping curves of a two-dimensional SSM); M. Feldman, J. Sound Vib. 208
//! (1997) 475-489 (damping from a free decay by the Hilbert transform).

mod curve;
mod write;

pub use curve::{damping_curves, DampingCurve, DampingCurves, DampingError, DampingPoint};

use super::backbone::Backbone;
use super::{untrusted_warning, Analysis, Beside, Context, Needs, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::rom::accuracy::AnswerEstimate;
use ssm_core::spec::{BackboneSpec, SpecError};

/// `[analysis.damping]`: damping curves `zeta(rho)` of the master pair, one
/// per expansion order, on the amplitudes of a backbone (`rho_max`,
/// `points`, `orders`, with the backbone's defaults).
pub type DampingSpec = BackboneSpec;

/// Checks `spec` against `needs` (one master pair, orders the run can
/// compute).
pub fn check(spec: &DampingSpec, needs: &Needs) -> Result<(), SpecError> {
    let fail = |key: &str, problem: String| Err(SpecError::new(key, problem));
    if needs.pairs != 1 {
        return fail(
            "analysis.damping",
            format!(
                "the damping curve of a master pair needs exactly one master pair, found {}",
                needs.pairs
            ),
        );
    }
    if !(spec.rho_max.is_finite() && spec.rho_max > 0.0) {
        return fail(
            "analysis.damping.rho_max",
            format!("must be positive and finite, found {}", spec.rho_max),
        );
    }
    if spec.points < 2 {
        return fail(
            "analysis.damping.points",
            format!("must be at least 2, found {}", spec.points),
        );
    }
    if let Some(orders) = &spec.orders {
        if orders.is_empty() {
            return fail(
                "analysis.damping.orders",
                "at least one order is needed".into(),
            );
        }
        if let Some(bad) = orders.iter().find(|&&o| o < 1 || o > needs.max_order) {
            return fail(
                "analysis.damping.orders",
                format!(
                    "order {bad} is outside 1..={} ([ssm] order)",
                    needs.max_order
                ),
            );
        }
    }
    Ok(())
}

/// The damping analysis (see the module's documentation).
#[derive(Debug, Clone, Copy)]
pub struct Damping;

impl Analysis for Damping {
    const NAME: &'static str = "damping";
    type Spec = DampingSpec;
    type Output = DampingCurves;
    type Error = DampingError;

    fn check(spec: &DampingSpec, needs: &Needs) -> Result<(), SpecError> {
        check(spec, needs)
    }

    fn orders(spec: &DampingSpec) -> Vec<usize> {
        Backbone::orders(spec)
    }

    /// A backbone's: the same amplitudes at the same orders.
    fn work(spec: &DampingSpec, sizes: &Sizes<'_>) -> Work {
        Work {
            key: "analysis.damping.points",
            what: format!("a damping curve of {:.1e} points", spec.points as f64),
            ..Backbone::work(spec, sizes)
        }
    }

    fn run(spec: &DampingSpec, cx: &Context<'_>) -> Result<DampingCurves, DampingError> {
        damping_curves(spec, cx)
    }

    fn estimates(out: &DampingCurves) -> Vec<AnswerEstimate> {
        out.curves
            .iter()
            .map(|c| AnswerEstimate {
                answer: Self::NAME,
                order: c.order,
                epsilon: None,
                estimate: c.error_estimate,
                untrusted: c.untrusted,
                trusted_up_to: c.trusted_up_to,
            })
            .collect()
    }

    fn warnings(out: &DampingCurves) -> Vec<String> {
        out.curves
            .iter()
            .filter(|c| c.untrusted)
            .map(|c| {
                untrusted_warning(
                    &format!("damping O({})", c.order),
                    c.error_estimate,
                    out.tolerance,
                    c.trusted_up_to,
                    "lower [analysis.damping] rho_max or raise the expansion order",
                )
            })
            .collect()
    }

    fn files(
        out: &DampingCurves,
        outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        Ok(vec![
            ("damping.csv".into(), write::csv(out, outputs).into_bytes()),
            ("damping.svg".into(), write::svg(out, outputs)?.into_bytes()),
        ])
    }
}
