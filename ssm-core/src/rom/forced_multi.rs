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
use crate::rom::continuation::{Branch, BranchPoint, PolarTerm, RotatingFrame, Settings};
use crate::rom::frc_result::{
    CurveDetails, ForcedResponse, FrcBifurcation, FrcCurve, FrcError, FrcRow,
};
use crate::spec::FrcSpec;
use crate::spectrum::MasterMode;
use crate::ssm::forced::{table_warning, ForcedSsm};
use crate::ssm::SsmExpansion;
use crate::C64;
use ssm_kernel::continuation::BifurcationKind;

/// Branch switches at most per curve (each branch point found is switched once).
const MAX_SWITCHES: usize = 6;

/// Largest continuation step as a fraction of the width of the frequency
/// range (in the scaled amplitudes of [`RotatingFrame::scaled`]).
const H_MAX: f64 = 0.05;

/// The rate, in multiples of `Omega`, at which the monomial with exponents
/// `e` over `(p_1, conj p_1, p_2, ...)` turns on the orbit
/// `p_j = q_j e^{i r_j Omega t}`: `sum_v e_v r_v`, with `-r_j` for `conj p_j`.
fn turn_rate(e: &[u16], ratios: &[f64]) -> f64 {
    e.iter()
        .enumerate()
        .map(|(v, &k)| {
            let r = ratios[v / 2];
            f64::from(k) * if v % 2 == 0 { r } else { -r }
        })
        .sum()
}

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
        if (turn_rate(e, ratios) - ratios[t.coord / 2]).abs() > 1e-9 {
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

/// `(q_1, conj q_1, q_2, conj q_2, ...)`.
fn conjugate_pairs(q: &[C64]) -> Vec<C64> {
    q.iter().flat_map(|z| [*z, z.conj()]).collect()
}

/// The harmonic of `phi / periods` at which each monomial of the expansion
/// turns on the orbit `p_j = q_j e^{i r_j phi}`: `periods * sum_v e_v r_v`
/// (with `-r_j` for `conj p_j`), an integer for the ratios of
/// [`period_multiple`].
struct Harmonics {
    /// Slot of each monomial up to the order (harmonic `+ offset`).
    slot: Vec<usize>,
    /// Number of slots.
    span: usize,
    /// Harmonic of slot 0 is `-offset`.
    offset: i64,
    periods: f64,
}

impl Harmonics {
    fn new(ssm: &SsmExpansion, ratios: &[f64], periods: f64, order: usize) -> Self {
        let end = ssm.set.of_order(order.min(ssm.order)).end;
        let k: Vec<i64> = (0..end)
            .map(|i| (turn_rate(ssm.set.exponents(i), ratios) * periods).round() as i64)
            .collect();
        let lo = k.iter().copied().min().unwrap_or(0).min(0);
        let hi = k.iter().copied().max().unwrap_or(0).max(0);
        Self {
            slot: k.iter().map(|&h| (h - lo) as usize).collect(),
            span: (hi - lo + 1) as usize,
            offset: -lo,
            periods,
        }
    }

    /// Frequency in `phi` of slot `s`.
    fn frequency(&self, s: usize) -> f64 {
        (s as i64 - self.offset) as f64 / self.periods
    }
}

/// The phases `phi_k = 2 pi periods k / n` at which a response is sampled,
/// with every harmonic's turn there, computed once for all points.
struct Samples {
    phi: Vec<f64>,
    /// `turns[k][s] = e^{i f_s phi_k}` for the slots of [`Harmonics`].
    turns: Vec<Vec<C64>>,
    /// `e^{i phi_k}` (the forcing frequency's harmonic).
    first: Vec<C64>,
}

impl Samples {
    fn new(harmonics: &Harmonics, n: usize) -> Self {
        let phi: Vec<f64> = (0..n)
            .map(|k| 2.0 * std::f64::consts::PI * harmonics.periods * k as f64 / n as f64)
            .collect();
        let turns = phi
            .iter()
            .map(|&f| {
                (0..harmonics.span)
                    .map(|s| C64::from_polar(1.0, harmonics.frequency(s) * f))
                    .collect()
            })
            .collect();
        let first = phi.iter().map(|&f| C64::from_polar(1.0, f)).collect();
        Self { phi, turns, first }
    }

    /// `e^{i kappa_h phi_k}` per sample for the forcing harmonics `kappa`.
    fn forcing(&self, kappa: &[f64]) -> Vec<Vec<C64>> {
        self.phi
            .iter()
            .map(|&f| kappa.iter().map(|&x| C64::from_polar(1.0, x * f)).collect())
            .collect()
    }
}

/// Size of the harmonic table of `forced_response_multi` at `order` for
/// `ratios`, for the cost gate before any of it is allocated: the slots (at
/// most the harmonics `-h..=h`, `h = periods * order * max r`) and the
/// sampled phases (64 per response period).
pub fn harmonic_table(ratios: &[f64], order: usize) -> (f64, f64) {
    let periods = period_multiple(ratios);
    let top = ratios.iter().fold(0.0f64, |a, r| a.max(r.abs()));
    (
        2.0 * (periods * order as f64 * top).round() + 1.0,
        64.0 * periods,
    )
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

/// Distance of the point `row` of the curve of the frame `frame` (in
/// amplitudes `q / a`) from the branch of `lower`, the same reduced dynamics
/// truncated two orders lower: `|dq| / |q| + |dOmega| / Omega` between `row`
/// and the nearest point of `lower`'s branch
/// ([`RotatingFrame::nearest_point`]); infinite when `lower` has no branch
/// there. While the expansion converges this is the error of the lower
/// order's curve, an upper estimate of the error of `frame`'s.
fn order_change(frame: &RotatingFrame, lower: &RotatingFrame, a: f64, row: &FrcRow) -> f64 {
    let scale = row.rho / a;
    if scale == 0.0 {
        return 0.0;
    }
    let point = BranchPoint {
        q: row.q.iter().map(|q| q / a).collect(),
        omega: row.omega,
        stable: row.stable,
    };
    match lower.nearest_point(frame, &point) {
        Some(p) => {
            let dq =
                p.q.iter()
                    .zip(&point.q)
                    .map(|(x, y)| (x - y).norm_sqr())
                    .sum::<f64>()
                    .sqrt();
            dq / scale + (p.omega - row.omega).abs() / row.omega
        }
        None => f64::INFINITY,
    }
}

/// FRCs of several pairs for every `(order, epsilon)` of `sec`.
pub(crate) fn forced_response_multi(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    sec: &FrcSpec,
    outputs: &[&OutputMap],
    ratios: &[f64],
    tolerance: f64,
) -> Result<ForcedResponse, FrcError> {
    if sec.nonautonomous_order.is_some_and(|k| k > 0) {
        return Err(FrcError::Unsupported(
            "nonautonomous_order > 0 is implemented for one master pair only".into(),
        ));
    }
    let m = masters.len();
    let range = (sec.omega_range[0], sec.omega_range[1]);
    let mut forced = ForcedSsm::new(sys, masters, ratios)?;
    let center = forced.at(0.5 * (range.0 + range.1))?;
    let s: Vec<C64> = (0..m).map(|j| center.resonant_forcing(2 * j)).collect();
    if s.iter().all(|v| v.norm() == 0.0) {
        return Err(FrcError::Unsupported(
            "the forcing reaches no master pair at these resonance ratios (u^* F = 0)".into(),
        ));
    }
    let orders = sec.orders.clone().unwrap_or_else(|| vec![ssm.order]);
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let periods = period_multiple(ratios);
    let mut rows = Vec::new();
    let mut curves = Vec::new();
    let mut warnings = Vec::new();
    let weights: Vec<&[(usize, f64)]> = outputs.iter().map(|o| o.weights.as_slice()).collect();
    let table_error = forced.tabulate_outputs(range.0, range.1, &weights)?;
    if let Some(w) = table_warning(table_error, range) {
        warnings.push(w);
    }
    for (&order, &eps) in orders
        .iter()
        .flat_map(|o| sec.epsilon.iter().map(move |e| (o, e)))
    {
        let (terms, dropped) = rotating_terms(ssm, ratios, order);
        let harmonics = Harmonics::new(ssm, ratios, periods, order);
        let sampled = Samples::new(&harmonics, 64 * periods as usize);
        let kappa: Vec<f64> = sys.forcing.iter().map(|h| h.multiple).collect();
        let forcing_turns = sampled.forcing(&kappa);
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
        // continue in q / a, where a maps the largest linear resonant peak
        // |eps s_j / Re lambda_j| onto the width of the frequency range: the
        // steps then weigh frequency and amplitude alike, whatever the
        // amplitude unit
        let width = range.1 - range.0;
        let peak = masters
            .iter()
            .zip(&frame.force)
            .map(|(mm, f)| f.norm() / mm.lambda.re.abs().max(1e-300))
            .fold(0.0, f64::max);
        let a = if peak.is_finite() && peak > 0.0 {
            peak / width
        } else {
            1.0
        };
        let unscaled = frame;
        let frame = unscaled.scaled(a);
        let top = masters.iter().map(|mm| mm.lambda.im).fold(0.0, f64::max);
        let settings = Settings {
            omega_range: range,
            h_max: H_MAX * width,
            h_min: 1e-10 * top.max(width),
            max_steps: 20 * sec.points,
            max_amplitude: sec.rho_max.map(|r| r / a),
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
                .filter(|l| l.kind == BifurcationKind::BranchPoint)
                .cloned()
                .collect();
            for bp in bps {
                // skip branch points that another branch already runs through
                // (the secondary branch of a pitchfork ends at a second
                // branch point of the main branch)
                let seen = branches.iter().enumerate().any(|(i, b)| {
                    i != k
                        && b.located.iter().any(|l| {
                            l.kind == BifurcationKind::BranchPoint
                                && same_point(&l.at, &bp.at, settings.h_max)
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
        let branches: Vec<Branch> = branches.into_iter().map(|b| b.unscaled(a)).collect();
        let first = rows.len();
        for (bi, br) in branches.iter().enumerate() {
            if let (true, Some(last)) = (br.reached_max_amplitude, br.points.last()) {
                warnings.push(format!(
                    "O({order}), eps = {eps}: branch {} was stopped at Omega = {:.6}, where a pair amplitude passed [forcing] rho_max = {}; beyond it the expansion is not trusted",
                    bi + 1,
                    last.omega,
                    ssm_kernel::number::short(sec.rho_max.unwrap_or(f64::INFINITY)), eps = ssm_kernel::number::short(eps),
                ));
            }
            let first_of_branch = rows.len();
            for p in br
                .points
                .iter()
                .filter(|p| p.omega >= range.0 && p.omega <= range.1)
            {
                let x0 = forced.outputs_at(p.omega)?;
                // on the orbit p_j = q_j e^{i r_j phi} each monomial turns at
                // its own harmonic of phi / periods: sum the series per harmonic
                // once, then sample the harmonics
                let mono = ssm.set.monomials(&conjugate_pairs(&p.q), order);
                let end = ssm.set.of_order(order.min(ssm.order)).end;
                let amplitudes: Vec<Vec<C64>> = series
                    .iter()
                    .map(|ser| {
                        let mut h = vec![C64::new(0.0, 0.0); harmonics.span];
                        for i in 0..end {
                            h[harmonics.slot[i]] += ser[i] * mono[i];
                        }
                        h
                    })
                    .collect();
                let mut linf = vec![0.0f64; outputs.len()];
                let mut h1 = vec![C64::new(0.0, 0.0); outputs.len()];
                for (k, turns) in sampled.turns.iter().enumerate() {
                    for (oi, h) in amplitudes.iter().enumerate() {
                        let y = h.iter().zip(turns).map(|(a, b)| a * b).sum::<C64>().re
                            + eps * x0.value_turned(oi, &forcing_turns[k]);
                        linf[oi] = linf[oi].max(y.abs());
                        h1[oi] += y * sampled.first[k].conj();
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
                    h1: h1
                        .iter()
                        .map(|a| 2.0 * a.norm() / sampled.turns.len() as f64)
                        .collect(),
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
                let kind = l.kind.label();
                let rho: Vec<f64> = l.at.q.iter().map(|q| q.norm()).collect();
                // a closed secondary branch runs through its mirror image
                // (q_j -> -q_j for the pairs of odd resonance ratio, the same
                // orbit half a period later): list each bifurcation once
                if bifurcations.iter().any(|b: &FrcBifurcation| {
                    b.branch == bi + 1
                        && b.kind == kind
                        && (b.omega - l.at.omega).abs() <= 1e-6 * l.at.omega
                        && b.rho
                            .iter()
                            .zip(&rho)
                            .all(|(x, y)| (x - y).abs() <= 1e-3 * y.max(*x))
                }) {
                    continue;
                }
                bifurcations.push(FrcBifurcation {
                    kind,
                    omega: l.at.omega,
                    branch: bi + 1,
                    rho,
                    plotted: plotted
                        .iter()
                        .min_by(|a, b| dist(a.0).total_cmp(&dist(b.0)))
                        .map(|&(_, y)| y),
                });
            }
        }
        // the error figure of the curve: the largest over the peaks of its
        // branches (where the truncated terms weigh most) of the change from
        // two orders lower
        let lower = (order >= 3).then(|| {
            RotatingFrame {
                terms: rotating_terms(ssm, ratios, order - 2).0,
                ..unscaled.clone()
            }
            .scaled(a)
        });
        let mut error_estimate = 0.0f64;
        for bi in 0..branches.len() {
            let peak = rows[first..]
                .iter()
                .filter(|r| r.branch == bi + 1)
                .max_by(|a, b| a.rho.total_cmp(&b.rho));
            if let Some(pk) = peak {
                let e = lower
                    .as_ref()
                    .map_or(f64::NAN, |l| order_change(&frame, l, a, pk));
                error_estimate = if e.is_nan() || error_estimate.is_nan() {
                    f64::NAN
                } else {
                    error_estimate.max(e)
                };
            }
        }
        let untrusted = accuracy::exceeds(error_estimate, tolerance);
        if lower.is_none() {
            warnings.push(format!(
                "O({order}), eps = {eps}: no error estimate below O(3) (the estimate compares the curve with the one two orders lower); do not trust this curve: raise the expansion order", eps = ssm_kernel::number::short(eps)
            ));
        } else if untrusted {
            warnings.push(format!(
                "O({order}), eps = {eps}: the estimated error of the response, {}, exceeds the accuracy target {} ([ssm] tolerance); do not trust this curve: raise the expansion order, or lower the forcing (the response may lie beyond the SSM's convergence radius); non-autonomous terms beyond the leading order are implemented for one master pair only",
                percent(error_estimate),
                percent(tolerance), eps = ssm_kernel::number::short(eps),
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
        linear: forced.counts(),
        factor_bytes: forced.factor_bytes(),
    })
}

/// Two located points of the scaled frame coincide: closer than the largest
/// step (a branch point located on a secondary branch sits off `q_j = 0` by
/// a fraction of a step: near the crossing the corrector of the bisection
/// may land on either branch); this is the resolution of the continuation,
/// which does not tell apart two branch points closer than that.
fn same_point(a: &BranchPoint, b: &BranchPoint, h_max: f64) -> bool {
    let d2 = (a.omega - b.omega).powi(2)
        + a.q
            .iter()
            .zip(&b.q)
            .map(|(x, y)| (x - y).norm_sqr())
            .sum::<f64>();
    d2.sqrt() < h_max
}
