//! Forced response curves of `[forcing]`: for one master pair from the
//! rotating-frame fixed points of the leading-order (or higher non-autonomous
//! order) periodic SSM ([`crate::rom::frc`]); for several pairs by
//! continuation ([`crate::rom::forced_multi`]). Each point carries the
//! physical amplitudes of the outputs, each curve its error figures
//! (invariance error eq. (41) and residual eq. (60) at the peak).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 4,
//! eqs. (16), (41), (60), Figs. 5-6.

pub use crate::rom::frc_result::{
    CurveDetails, ForcedResponse, FrcBifurcation, FrcCurve, FrcError, FrcRow,
};

use crate::model::system::{OutputMap, System};
use crate::spec::FrcSpec;
use crate::spectrum::MasterMode;
use crate::ssm::{Dynamics, SsmExpansion};

/// External resonance ratios chosen from the forcing frequency (eq. 16): the
/// pair whose frequency is nearest `omega` gets `r = 1`; the others the
/// nearest fraction `k/d`, `d <= 3`, of their frequency ratio to it.
pub(crate) fn auto_ratios(masters: &[MasterMode], omega: f64) -> Vec<f64> {
    let main = masters
        .iter()
        .min_by(|a, b| {
            (a.lambda.im - omega)
                .abs()
                .total_cmp(&(b.lambda.im - omega).abs())
        })
        .map_or(1.0, |m| m.lambda.im);
    masters
        .iter()
        .map(|m| {
            let x = m.lambda.im / main;
            (1..=3)
                .map(|d| (x * f64::from(d)).round().max(1.0) / f64::from(d))
                .min_by(|a, b| (a - x).abs().total_cmp(&(b - x).abs()))
                .unwrap_or(1.0)
        })
        .collect()
}

/// The external resonance ratios of `sec`: its `resonance`, else
/// `auto_ratios` at the middle of its frequency range.
pub fn resonance_ratios(sec: &FrcSpec, masters: &[MasterMode]) -> Vec<f64> {
    let range = sec.omega_range;
    match &sec.resonance {
        Some(r) => r.clone(),
        None => auto_ratios(masters, 0.5 * (range[0] + range[1])),
    }
}

/// FRCs for every `(order, epsilon)` of `sec`, with the amplitudes of
/// `outputs`; each curve's error estimate is checked against the relative
/// `tolerance`.
pub fn forced_response(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    sec: &FrcSpec,
    outputs: &[&OutputMap],
    tolerance: f64,
) -> Result<ForcedResponse, FrcError> {
    if let Dynamics::Map { .. } = ssm.dynamics {
        return Err(FrcError::Unsupported(
            "the model is a map; [forcing] needs a flow".into(),
        ));
    }
    sec.check(masters.len(), ssm.order)?;
    let ratios = resonance_ratios(sec, masters);
    if masters.len() > 1 {
        return crate::rom::forced_multi::forced_response_multi(
            ssm, sys, masters, sec, outputs, &ratios, tolerance,
        );
    }
    if ratios[0] != 1.0 {
        return Err(FrcError::Unsupported(format!(
            "resonance ratio {} for a single pair: only primary resonance (r = 1) is implemented",
            ratios[0]
        )));
    }
    crate::rom::forced_one_pair::forced_response_one_pair(
        ssm, sys, masters, sec, outputs, ratios, tolerance,
    )
}
