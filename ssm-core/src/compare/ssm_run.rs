//! An SSM reduced model run on a full-system load case, for side-by-side
//! comparisons with other reductions ([`super::pod`]): the reduced dynamics
//! `p' = R(p) + eps S0(Omega t)` of the (leading-order periodic) SSM from
//! the point nearest the full model's start, lifted to the outputs through
//! `W(p) + eps X0(Omega t)` at the full run's times.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), eqs.
//! (19)-(20) (the periodic SSM and its reduced dynamics at leading order).

use std::time::Instant;

use super::nearest_on_ssm;
use super::pod::{error_figures, FullRun, LoadCase, RomRun, SsmRom};
use crate::model::system::{OutputMap, System};
use crate::rom::forced_response::auto_ratios;
use crate::ssm::forced::{ForcedSsm, ForcedTerms};
use crate::ssm::rom::integrate_forced;
use crate::C64;

/// Relative tolerance of the reduced integration.
const RTOL: f64 = 1e-9;

/// The run of `rom` on `case` against the full run `full` (at its step
/// ends). A load makes the SSM periodic: the forced terms `X0`, `S0` are
/// computed at `Omega` (external resonance with the master pair nearest
/// `Omega`) and counted in the online time.
pub fn ssm_case_run(
    rom: &SsmRom,
    sys: &System,
    case: &LoadCase,
    full: &FullRun,
    outputs: &[&OutputMap],
) -> RomRun {
    let t = Instant::now();
    let fail = |e: String, distance: f64| RomRun {
        outputs: Vec::new(),
        online_s: t.elapsed().as_secs_f64(),
        errors: None,
        reactions: None,
        start_distance: distance,
        failure: Some(e),
    };
    if !case.steps.is_empty() {
        return fail(
            "the SSM's forced terms hold for one constant load amplitude; this load is switched in steps".into(),
            f64::NAN,
        );
    }
    let eps = case.epsilon;
    let forced = if eps != 0.0 && !sys.forcing.is_empty() {
        let ratios = auto_ratios(&rom.masters, case.omega);
        match ForcedSsm::new(sys, &rom.masters, &ratios).and_then(|mut f| f.at(case.omega)) {
            Ok(terms) => Some(terms),
            Err(e) => return fail(e.to_string(), f64::NAN),
        }
    } else {
        None
    };
    // the start on the SSM: nearest to the full start minus eps X0(0)
    let mut target = full.solution.states[0].clone();
    if let Some(terms) = &forced {
        for h in &terms.harmonics {
            for (z, x) in target.iter_mut().zip(&h.x) {
                *z -= eps * 2.0 * x.re;
            }
        }
    }
    let order = rom.expansion.order;
    let (p0, distance) = nearest_on_ssm(&rom.expansion, sys, order, &rom.masters, &target);
    let distance = if distance.is_finite() { distance } else { 0.0 };
    let omega = case.omega;
    let g = |time: f64| -> Vec<C64> {
        let mut v = vec![C64::new(0.0, 0.0); p0.len()];
        if let Some(terms) = &forced {
            for h in &terms.harmonics {
                let turn = C64::from_polar(1.0, h.multiple * omega * time);
                for j in (0..v.len()).step_by(2) {
                    let s = h.s[j] * turn * eps;
                    v[j] += s;
                    v[j + 1] += s.conj();
                }
            }
        }
        v
    };
    let scale = p0
        .iter()
        .map(|c| c.norm())
        .fold(0.0, f64::max)
        .max(forced_scale(forced.as_ref(), eps, &rom.expansion.lambda));
    let times = &full.solution.times;
    let traj = match integrate_forced(&rom.expansion, order, &p0, times, RTOL, scale, g) {
        Ok(tr) => tr,
        Err(e) => return fail(e.to_string(), distance),
    };
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| rom.expansion.output_series(&o.weights))
        .collect();
    let x0: Vec<Vec<(f64, C64)>> = outputs
        .iter()
        .map(|o| {
            forced.as_ref().map_or_else(Vec::new, |terms| {
                terms
                    .harmonics
                    .iter()
                    .map(|h| (h.multiple, o.weights.iter().map(|&(s, w)| h.x[s] * w).sum()))
                    .collect()
            })
        })
        .collect();
    let end = rom.expansion.set.of_order(order).end;
    let values: Vec<Vec<f64>> = traj
        .times
        .iter()
        .zip(&traj.states)
        .map(|(&time, p)| {
            let mono = rom.expansion.set.monomials(p, order);
            series
                .iter()
                .zip(&x0)
                .map(|(c, xs)| {
                    let w: C64 = c[1..end]
                        .iter()
                        .zip(&mono[1..end])
                        .map(|(a, b)| a * b)
                        .sum();
                    let x: f64 = xs
                        .iter()
                        .map(|(k, x)| 2.0 * (x * C64::from_polar(1.0, k * omega * time)).re)
                        .sum();
                    w.re + eps * x
                })
                .collect()
        })
        .collect();
    let online_s = t.elapsed().as_secs_f64();
    RomRun {
        errors: Some(error_figures(times, &full.outputs, &values)),
        outputs: values,
        online_s,
        reactions: None,
        start_distance: distance,
        failure: None,
    }
}

/// The size of the forced response of the reduced coordinates, `eps |S0| /
/// |Re lambda|`, the scale of the absolute tolerance from a start at rest.
fn forced_scale(forced: Option<&ForcedTerms>, eps: f64, lambda: &[C64]) -> f64 {
    let Some(terms) = forced else {
        return 0.0;
    };
    let s = terms
        .harmonics
        .iter()
        .flat_map(|h| h.s.iter().map(|c| c.norm()))
        .fold(0.0, f64::max);
    let damping = lambda
        .iter()
        .map(|l| l.re.abs())
        .fold(f64::INFINITY, f64::min)
        .max(1e-12);
    (eps.abs() * s / damping).min(1e12)
}
