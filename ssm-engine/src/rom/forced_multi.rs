//! Forced response of several master pairs (internal resonance):
//! continuation of the rotating-frame reduced dynamics
//! ([`crate::rom::continuation`]) with branch switching at branch points, and
//! the physical amplitudes of each point rebuilt from
//! `W(p(t)) + eps X0(Omega t)`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 4.2
//! (eq. 16, internal resonances), Fig. 15.

use crate::model::system::{OutputMap, System};
use crate::rom::accuracy::{self, percent};
use crate::rom::continuation::{
    Branch, BranchPoint, LocatedKind, PolarTerm, RotatingFrame, Settings,
};
use crate::rom::forced_response::{
    CurveDetails, ForcedResponse, FrcBifurcation, FrcCurve, FrcError, FrcRow,
};
use crate::scene::ForcingSection;
use crate::spectrum::MasterMode;
use crate::ssm::forced::ForcedSsm;
use crate::ssm::SsmExpansion;
use crate::C64;

/// Branch switches at most per curve (each branch point found is switched once).
const MAX_SWITCHES: usize = 6;

/// The rotating-frame terms of `R` truncated at `order`: those autonomous for
/// `p_{2j} = q_j e^{i r_j Omega t}` (all of a consistent normal form).
fn rotating_terms(ssm: &SsmExpansion, ratios: &[f64], order: usize) -> (Vec<PolarTerm>, usize) {
    let mut terms = Vec::new();
    let mut dropped = 0;
    for t in &ssm.r {
        if t.coord % 2 == 1 || ssm.set.order(t.index) > order {
            continue;
        }
        let e = ssm.set.exponents(t.index);
        let phase: f64 = e
            .iter()
            .enumerate()
            .map(|(v, &k)| {
                let r = ratios[v / 2];
                f64::from(k) * if v % 2 == 0 { r } else { -r }
            })
            .sum();
        if (phase - ratios[t.coord / 2]).abs() > 1e-9 {
            dropped += 1;
            continue;
        }
        terms.push(PolarTerm {
            pair: t.coord / 2,
            exponents: e.to_vec(),
            coeff: t.coeff,
        });
    }
    (terms, dropped)
}

/// Least common denominator of the ratios (at most 6), for the response period.
fn period_multiple(ratios: &[f64]) -> f64 {
    (1..=6)
        .find(|&d| {
            ratios
                .iter()
                .all(|r| ((r * f64::from(d)) - (r * f64::from(d)).round()).abs() < 1e-9)
        })
        .map_or(1.0, f64::from)
}

/// Estimated relative error of the response at the point `row` of a curve:
/// the eq. (60) residual (leading non-autonomous order) along its periodic
/// orbit `p_j = q_j e^{i r_j phi}`, `phi` over `periods` forcing periods,
/// projected on each master pair ([`accuracy::defect`]) and summed over the
/// pairs, relative to `|q|`, with `R` and `W` truncated at `order`.
#[allow(clippy::too_many_arguments)]
fn orbit_error(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    forced: &mut ForcedSsm,
    row: &FrcRow,
    ratios: &[f64],
    periods: f64,
    order: usize,
) -> Result<f64, FrcError> {
    let scale = row.rho;
    if scale == 0.0 {
        return Ok(0.0);
    }
    let na = forced.expansion(ssm, sys, row.omega, 0)?;
    let d = periods.round() as usize;
    let n = accuracy::PHASES * d;
    let mut modal = vec![Vec::with_capacity(n); masters.len()];
    for k in 0..n {
        let phi = 2.0 * std::f64::consts::PI * periods * k as f64 / n as f64;
        let p: Vec<C64> = row
            .q
            .iter()
            .zip(ratios)
            .flat_map(|(q, r)| {
                let z = q * C64::from_polar(1.0, r * phi);
                [z, z.conj()]
            })
            .collect();
        let r = na.residual(ssm, sys, row.epsilon, &p, phi, order);
        for (mj, m) in modal.iter_mut().zip(masters) {
            mj.push(m.left.iter().zip(&r).map(|(u, x)| u.conj() * x).sum());
        }
    }
    Ok(masters
        .iter()
        .zip(&modal)
        .zip(ratios.iter().zip(&row.q))
        .map(|((m, mj), (r, q))| {
            let co = (r * periods).round() as usize;
            accuracy::defect(mj, co, *q, scale, row.omega / periods).forced(m.lambda)
        })
        .sum())
}

/// FRCs of several pairs for every `(order, epsilon)` of `sec`.
pub fn forced_response_multi(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    sec: &ForcingSection,
    outputs: &[&OutputMap],
    ratios: &[f64],
    tolerance: f64,
) -> Result<ForcedResponse, FrcError> {
    if sec
        .nonautonomous_order
        .as_ref()
        .is_some_and(|k| *k.get_ref() > 0)
    {
        return Err(FrcError::Unsupported(
            "nonautonomous_order > 0 is implemented for one master pair only".into(),
        ));
    }
    let m = masters.len();
    let range = (sec.omega_range.get_ref()[0], sec.omega_range.get_ref()[1]);
    let mut forced = ForcedSsm::new(sys, masters, ratios)?;
    let center = forced.at(0.5 * (range.0 + range.1))?;
    let s: Vec<C64> = (0..m).map(|j| center.resonant_forcing(2 * j)).collect();
    if s.iter().all(|v| v.norm() == 0.0) {
        return Err(FrcError::Unsupported(
            "the forcing reaches no master pair at these resonance ratios (u^* F = 0)".into(),
        ));
    }
    let orders = sec
        .orders
        .as_ref()
        .map_or(vec![ssm.order], |o| o.get_ref().clone());
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let periods = period_multiple(ratios);
    let mut rows = Vec::new();
    let mut curves = Vec::new();
    let mut warnings = Vec::new();
    for (&order, &eps) in orders
        .iter()
        .flat_map(|o| sec.epsilon.get_ref().iter().map(move |e| (o, e)))
    {
        let (terms, dropped) = rotating_terms(ssm, ratios, order);
        if dropped > 0 {
            warnings.push(format!(
                "O({order}): {dropped} near-resonant terms of R are not autonomous for the resonance ratios {ratios:?} and were left out of the forced response"
            ));
        }
        let frame = RotatingFrame {
            terms,
            ratios: ratios.to_vec(),
            force: s.iter().map(|v| v * eps).collect(),
        };
        let scale = masters.iter().map(|mm| mm.lambda.im).fold(0.0, f64::max);
        let settings = Settings {
            omega_range: range,
            h_max: 2e-2 * scale.max(range.1 - range.0),
            h_min: 1e-10 * scale,
            max_steps: 20 * *sec.points.get_ref(),
            max_amplitude: sec.rho_max.as_ref().map(|r| *r.get_ref()),
        };
        let guess: Vec<f64> = (0..m)
            .flat_map(|j| {
                let q = -frame.force[j] / (masters[j].lambda - C64::new(0.0, ratios[j] * range.0));
                [q.re, q.im]
            })
            .collect();
        let main = frame.start(range.0, guess, &settings)?;
        let mut branches: Vec<Branch> = vec![main];
        let mut bifurcations = Vec::new();
        let mut switched = 0;
        let mut k = 0;
        while k < branches.len() && switched < MAX_SWITCHES {
            let bps: Vec<_> = branches[k]
                .located
                .iter()
                .filter(|l| l.kind == LocatedKind::BranchPoint)
                .cloned()
                .collect();
            for bp in bps {
                // skip branch points that another branch already runs through
                // (the secondary branch of a pitchfork ends at a second
                // branch point of the main branch)
                let seen = branches.iter().enumerate().any(|(i, b)| {
                    i != k
                        && b.located.iter().any(|l| {
                            l.kind == LocatedKind::BranchPoint && same_point(&l.at, &bp.at)
                        })
                });
                if seen || switched >= MAX_SWITCHES {
                    continue;
                }
                branches.extend(frame.switch(&bp, &settings));
                switched += 1;
            }
            k += 1;
        }
        let first = rows.len();
        for (bi, br) in branches.iter().enumerate() {
            if let (true, Some(last)) = (br.reached_max_amplitude, br.points.last()) {
                warnings.push(format!(
                    "O({order}), eps = {eps}: branch {} was stopped at Omega = {:.6}, where a pair amplitude passed [forcing] rho_max = {}; beyond it the expansion is not trusted",
                    bi + 1,
                    last.omega,
                    sec.rho_max.as_ref().map_or(f64::INFINITY, |r| *r.get_ref()),
                ));
            }
            let first_of_branch = rows.len();
            for p in br
                .points
                .iter()
                .filter(|p| p.omega >= range.0 && p.omega <= range.1)
            {
                let x0 = forced.at(p.omega)?;
                let mut linf = vec![0.0f64; outputs.len()];
                let mut h1 = vec![C64::new(0.0, 0.0); outputs.len()];
                let samples = 64 * periods as usize;
                for k in 0..samples {
                    let phi = 2.0 * std::f64::consts::PI * periods * k as f64 / samples as f64;
                    let pz: Vec<C64> = (0..m)
                        .flat_map(|j| {
                            let q = p.q[j] * C64::from_polar(1.0, ratios[j] * phi);
                            [q, q.conj()]
                        })
                        .collect();
                    let mono = ssm.set.monomials(&pz, order);
                    let end = ssm.set.of_order(order.min(ssm.order)).end;
                    for (oi, (o, ser)) in outputs.iter().zip(&series).enumerate() {
                        let y = (0..end).map(|i| ser[i] * mono[i]).sum::<C64>().re
                            + eps * x0.output_at(&o.weights, phi);
                        linf[oi] = linf[oi].max(y.abs());
                        h1[oi] += y * C64::from_polar(1.0, -phi);
                    }
                }
                rows.push(FrcRow {
                    order,
                    epsilon: eps,
                    omega: p.omega,
                    branch: bi + 1,
                    stable: p.stable,
                    rho: p.q.iter().map(|q| q.norm_sqr()).sum::<f64>().sqrt(),
                    q: p.q.clone(),
                    pair_amplitudes: p.q.iter().map(|q| q.norm()).collect(),
                    linf,
                    h1: h1.iter().map(|a| 2.0 * a.norm() / samples as f64).collect(),
                });
            }
            let plotted: Vec<(&BranchPoint, f64)> = br
                .points
                .iter()
                .filter(|p| p.omega >= range.0 && p.omega <= range.1)
                .zip(&rows[first_of_branch..])
                .map(|(p, r)| (p, r.plotted()))
                .collect();
            for l in &br.located {
                if l.at.omega < range.0 || l.at.omega > range.1 {
                    continue;
                }
                let dist = |p: &BranchPoint| {
                    (p.omega - l.at.omega).abs()
                        + p.q
                            .iter()
                            .zip(&l.at.q)
                            .map(|(a, b)| (a - b).norm())
                            .sum::<f64>()
                };
                bifurcations.push(FrcBifurcation {
                    kind: match l.kind {
                        LocatedKind::BranchPoint => "BP",
                        LocatedKind::Bifurcation(b) => b.label(),
                    },
                    omega: l.at.omega,
                    branch: bi + 1,
                    rho: l.at.q.iter().map(|q| q.norm()).collect(),
                    plotted: plotted
                        .iter()
                        .min_by(|a, b| dist(a.0).total_cmp(&dist(b.0)))
                        .map(|&(_, y)| y),
                });
            }
        }
        // the error figure of the curve: the largest over the peaks of its
        // branches (where the truncated terms weigh most)
        let mut error_estimate = 0.0f64;
        for bi in 0..branches.len() {
            let peak = rows[first..]
                .iter()
                .filter(|r| r.branch == bi + 1)
                .max_by(|a, b| a.rho.total_cmp(&b.rho));
            if let Some(pk) = peak {
                let figures = accuracy::tail_orders(order)
                    .into_iter()
                    .map(|o| orbit_error(ssm, sys, masters, &mut forced, pk, ratios, periods, o))
                    .collect::<Result<Vec<f64>, FrcError>>()?;
                let e = accuracy::tail(&figures);
                error_estimate = if e.is_nan() { e } else { error_estimate.max(e) };
            }
        }
        let untrusted = accuracy::exceeds(error_estimate, tolerance);
        if untrusted {
            warnings.push(format!(
                "O({order}), eps = {eps}: the estimated error of the response, {}, exceeds the accuracy target {} ([ssm] tolerance); do not trust this curve: raise the expansion order, or lower the forcing (the response may lie beyond the SSM's convergence radius); non-autonomous terms beyond the leading order are implemented for one master pair only",
                percent(error_estimate),
                percent(tolerance),
            ));
        }
        curves.push(FrcCurve {
            order,
            epsilon: eps,
            points: rows.len() - first,
            branches: branches.len(),
            bifurcations,
            untrusted,
            details: CurveDetails::Continuation {
                branch_switches: switched,
                continuation_steps: branches.iter().map(|b| b.points.len()).sum::<usize>(),
                error_estimate,
            },
        });
    }
    Ok(ForcedResponse {
        outputs: outputs.iter().map(|o| o.name.clone()).collect(),
        rows,
        curves,
        resonance: ratios.to_vec(),
        rho_max: None,
        forcing_on_master: s,
        warnings,
    })
}

/// Two located points coincide: `1e-5` relative in `Omega`, `5e-2` relative
/// in the amplitudes (a branch point located on a secondary branch sits off
/// `q_j = 0` by up to a few percent of the amplitude, the corrector's error
/// where two branches cross).
fn same_point(a: &BranchPoint, b: &BranchPoint) -> bool {
    let scale = b.q.iter().map(|q| q.norm()).fold(0.0, f64::max).max(1e-300);
    (a.omega - b.omega).abs() < 1e-5 * b.omega
        && a.q
            .iter()
            .zip(&b.q)
            .all(|(x, y)| (x - y).norm() <= 5e-2 * scale)
}
