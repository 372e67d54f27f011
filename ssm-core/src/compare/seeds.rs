//! Starting orbits of the full-system reference from the reduced model's
//! forced response (`[reference] start = "ssm"`): on each branch of the
//! highest-order curve at a forcing amplitude, the orbit of largest
//! amplitude and the orbits where the branch enters or leaves the frequency
//! range (except where a subharmonic branch ends on one of period `T`),
//! lifted to the full state by the SSM parametrization. The peak
//! reaches isolas and upper branches; the range's ends reach the sheets of a
//! bistable band that the range cuts (a start from rest finds one of them).
//!
//! The reduced orbit is `p_j(t) = q_j e^{i r_j Omega t}` (the rotating-frame
//! fixed point `q` and the external resonance ratios `r_j` of eq. (16)); its
//! period is `m T`, `m` the smallest multiple that makes `m r_j` an integer
//! for every excited pair (`m = 2` on the divider's secondary branch, where
//! the pair at `r = 1/2` is excited). The full state is `z(t) = W(p(t))`; the
//! leading-order non-autonomous part `eps X_0(Omega t)` is left out: it is
//! small where the seeds lie (the peaks, dominated by the master modes), and
//! Newton on the full system corrects it.
//!
//! # References
//! G. Haller, S. Ponsioen, Nonlinear normal modes and spectral submanifolds,
//! Nonlinear Dyn. 86 (2016) 1493-1534; S. Jain, G. Haller, How to compute
//! invariant manifolds and their reduced dynamics in high-dimensional
//! finite element models, Nonlinear Dyn. 107 (2022) 1417-1450, Sect. 5
//! (forced response in the rotating frame).

use crate::fom::periodic::seed::Seed;
use crate::rom::forced_response::{ForcedResponse, FrcRow};
use crate::ssm::SsmExpansion;
use crate::C64;

/// Largest period multiple a seed may have.
const MAX_MULTIPLE: usize = 4;

/// The seeds of the curve of `frc` at forcing amplitude `epsilon` (its
/// highest order) in the frequency `range`: on each branch its peak and the
/// ends of its stretches inside the range, each sampled finely enough for
/// `harmonics` harmonics of its own period; empty where there is no such
/// curve or the SSM does not describe the model's states.
pub fn ssm_seeds(
    ssm: &SsmExpansion,
    frc: &ForcedResponse,
    n_states: usize,
    epsilon: f64,
    range: (f64, f64),
    harmonics: usize,
) -> Vec<Seed> {
    if ssm.n_states() != n_states {
        return Vec::new();
    }
    let same = |r: &FrcRow| (r.epsilon - epsilon).abs() <= 1e-12 * epsilon.abs();
    let Some(order) = frc.rows.iter().filter(|r| same(r)).map(|r| r.order).max() else {
        return Vec::new();
    };
    let order = order.min(ssm.order);
    let curve: Vec<&FrcRow> = frc
        .rows
        .iter()
        .filter(|r| same(r) && r.order == order)
        .collect();
    let mut branches: Vec<usize> = curve.iter().map(|r| r.branch).collect();
    branches.sort_unstable();
    branches.dedup();
    let inside = |r: &FrcRow| r.omega >= range.0 && r.omega <= range.1;
    let mut seeds = Vec::new();
    for b in branches {
        let points: Vec<&FrcRow> = curve
            .iter()
            .copied()
            .filter(|r| r.branch == b && r.plotted().is_finite())
            .collect();
        // the peak, and the ends of every stretch of the branch inside the
        // range (where a branch cut by the range enters or leaves it)
        let mut picks: Vec<usize> = Vec::new();
        if let Some((k, _)) = points
            .iter()
            .enumerate()
            .filter(|(_, r)| inside(r))
            .max_by(|x, y| x.1.plotted().total_cmp(&y.1.plotted()))
        {
            picks.push(k);
        }
        // the subharmonic pairs' amplitude (those at a fractional resonance
        // ratio): an end where it is below a tenth of the branch's largest is
        // next to a branch point where the branch meets one of period T
        // (traced from rest already; the first step off such a pitchfork
        // carries a few percent, 2.8 % on the divider), and its prediction is
        // a near-singular start for the period-mT problem
        let sub = |r: &FrcRow| {
            r.q.iter()
                .zip(&frc.resonance)
                .filter(|(_, ratio)| (*ratio - ratio.round()).abs() > 1e-9)
                .map(|(q, _)| q.norm())
                .fold(0.0, f64::max)
        };
        let sub_max = points.iter().map(|r| sub(r)).fold(0.0, f64::max);
        for k in 0..points.len() {
            let before = k > 0 && inside(points[k - 1]);
            let after = k + 1 < points.len() && inside(points[k + 1]);
            let merging = sub_max > 0.0 && sub(points[k]) < 0.1 * sub_max;
            if inside(points[k]) && (!before || !after) && !merging {
                picks.push(k);
            }
        }
        picks.sort_unstable();
        picks.dedup();
        seeds.extend(
            picks
                .into_iter()
                .filter_map(|k| lifted(ssm, points[k], &frc.resonance, order, harmonics, b)),
        );
    }
    seeds
}

/// The orbit of `row` lifted by `W` (truncated at `order`), or `None` where
/// its period is not a small multiple of the forcing period.
fn lifted(
    ssm: &SsmExpansion,
    row: &FrcRow,
    ratios: &[f64],
    order: usize,
    harmonics: usize,
    branch: usize,
) -> Option<Seed> {
    if row.q.len() != ratios.len() || row.omega.is_nan() || row.omega <= 0.0 {
        return None;
    }
    let big = row.q.iter().map(|q| q.norm()).fold(0.0, f64::max);
    let excited: Vec<f64> = row
        .q
        .iter()
        .zip(ratios)
        .filter(|(q, _)| q.norm() > 1e-12 * big)
        .map(|(_, r)| *r)
        .collect();
    let m = (1..=MAX_MULTIPLE).find(|&m| {
        excited
            .iter()
            .all(|r| (r * m as f64 - (r * m as f64).round()).abs() < 1e-9)
    })?;
    let samples = 4 * m * harmonics + 4;
    let states = (0..samples)
        .map(|s| {
            // Omega t over one period m T
            let phase = 2.0 * std::f64::consts::PI * (m * s) as f64 / samples as f64;
            let p: Vec<C64> = row
                .q
                .iter()
                .zip(ratios)
                .flat_map(|(q, r)| {
                    let pj = q * C64::from_polar(1.0, r * phase);
                    [pj, pj.conj()]
                })
                .collect();
            ssm.w_at(&ssm.set.monomials(&p, order), order)
                .iter()
                .map(|c| c.re)
                .collect()
        })
        .collect();
    Some(Seed {
        omega: row.omega,
        period_multiple: m,
        states,
        origin: format!("O({order}) FRC branch {branch} (eps = {:e})", row.epsilon),
    })
}
