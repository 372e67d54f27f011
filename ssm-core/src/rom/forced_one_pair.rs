//! Forced response curves of one master pair at primary resonance, from the
//! rotating-frame fixed points of the periodic SSM (eqs. 19-20, 60), with an
//! error estimate per curve and the non-autonomous order chosen to meet the
//! scene's accuracy target.
//!
//! The estimate of a curve is the larger of two figures: the modal residual
//! of eq. (60) along the peak's periodic orbit, converted into relative
//! changes of damping and frequency ([`accuracy::defect`]), and the change of
//! the curve from the previous non-autonomous order tried (of its peak, and
//! of the amplitude at every frequency where both curves are single-valued).
//! The first is reliable once the `O(eps |p|^k)` terms are in; the second
//! catches what the first misses at the leading order (the output map's
//! missing `eps p` terms) and the shift of the peak's frequency.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 4,
//! eqs. (16), (19)-(20), (41), (60), Figs. 5-6.

use std::collections::HashMap;

use crate::model::system::{OutputMap, System};
use crate::rom::accuracy::{self, percent};
use crate::rom::frc::{
    one_pair_frc, response_amplitudes, ForcedCoefficients, OnePair, NONAUTONOMOUS_NODES,
};
use crate::rom::frc_result::{
    CurveDetails, ForcedResponse, FrcBifurcation, FrcCurve, FrcError, FrcRow,
};
use crate::spec::FrcSpec;
use crate::spectrum::MasterMode;
use crate::ssm::analysis::{invariance_error, polar, Polar};
use crate::ssm::forced::{table_warning, ForcedSsm};
use crate::ssm::modal_residual::ModalResidual;
use crate::ssm::nonautonomous::NaSeries;
use crate::ssm::nonautonomous::NonAutonomous;
use crate::ssm::SsmExpansion;
use crate::C64;
use ssm_kernel::poly::MultiIndexSet;
use ssm_kernel::search::first_true_par;

/// Exact non-autonomous data at the Chebyshev nodes in `Omega`.
struct NaTable {
    /// `(sigma, tau)` per node.
    coeffs: Vec<(Vec<C64>, Vec<C64>)>,
    /// Per node: the outputs' `x_k`, output after output, over `set`.
    xs: Vec<Vec<C64>>,
    /// Multi-indices of the expansion.
    set: MultiIndexSet,
    /// The expansion as Taylor series over the nodes' band, where the model's
    /// factors are dear and the series converged (any frequency of the band
    /// is then an evaluation).
    series: Option<NaSeries>,
}

/// One non-autonomous order tried for a curve.
struct Attempt {
    k: usize,
    rows: Vec<FrcRow>,
    curve: FrcCurve,
    peak: f64,
    estimate: f64,
}

/// A segment `((omega, amplitude), (omega, amplitude))` of a curve, with
/// increasing frequency.
type Segment = ((f64, f64), (f64, f64));

/// The segments between consecutive points of one branch of `rows`.
fn segments(rows: &[FrcRow]) -> Vec<Segment> {
    rows.windows(2)
        .filter(|w| w[0].branch == w[1].branch)
        .map(|w| {
            let (a, b) = ((w[0].omega, w[0].plotted()), (w[1].omega, w[1].plotted()));
            if a.0 <= b.0 {
                (a, b)
            } else {
                (b, a)
            }
        })
        .collect()
}

/// The amplitude of the curve of `segs` at `omega`, if exactly one segment
/// spans it (the curve is single-valued there).
fn single_valued(segs: &[Segment], omega: f64) -> Option<f64> {
    let mut found = None;
    for &((w0, a0), (w1, a1)) in segs {
        if w0 <= omega && omega <= w1 && w1 > w0 {
            // a point shared by two consecutive segments is one crossing
            let a = a0 + (a1 - a0) * (omega - w0) / (w1 - w0);
            match found {
                None => found = Some(a),
                Some(b) if (a - b).abs() <= 1e-12 * a.abs().max(b.abs()) => {}
                Some(_) => return None,
            }
        }
    }
    found
}

/// The largest relative change of the plotted amplitude between two curves
/// of the same response, at the points of `rows` whose frequency both curves
/// cross once: away from the peak, a shift of the peak's frequency changes
/// the amplitude on a steep flank by far more than the peak's own change
/// (the spatial oscillator's O(13) curve at non-autonomous order 8: 0.55 %
/// at the peak, 3.1 % on the flank). Near folds, where the frequency meets
/// several branches, the peak's change speaks alone.
fn curve_change(prev: &[FrcRow], rows: &[FrcRow]) -> f64 {
    let (old, new) = (segments(prev), segments(rows));
    rows.iter()
        .filter_map(|row| {
            let a = single_valued(&new, row.omega)?;
            let b = single_valued(&old, row.omega)?;
            Some((a - b).abs() / a.abs().max(f64::MIN_POSITIVE))
        })
        .filter(|c| c.is_finite())
        .fold(0.0, f64::max)
}

/// What every curve of one pair shares.
struct Context<'a> {
    ssm: &'a SsmExpansion,
    sys: &'a System,
    masters: &'a [MasterMode],
    outputs: &'a [&'a OutputMap],
    forced: ForcedSsm<'a>,
    pol: Polar,
    s: C64,
    rho_max: f64,
    points: usize,
    range: (f64, f64),
    series: Vec<Vec<C64>>,
    nodes: Vec<f64>,
    /// Non-autonomous tables by order, made when first needed.
    tables: HashMap<usize, NaTable>,
}

/// FRCs of one master pair for every `(order, epsilon)` of `sec`, each with
/// the non-autonomous order of the scene or, without one, the lowest that
/// meets `tolerance`.
pub(crate) fn forced_response_one_pair(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    sec: &FrcSpec,
    outputs: &[&OutputMap],
    ratios: Vec<f64>,
    tolerance: f64,
) -> Result<ForcedResponse, FrcError> {
    let range = (sec.omega_range[0], sec.omega_range[1]);
    let mut forced = ForcedSsm::new(sys, masters, &ratios)?;
    // one factorization at the band's middle serves the leading order's
    // solves across the band
    let center = 0.5 * (range.0 + range.1);
    forced.anchor_at(center);
    let s = forced.at(center)?.resonant_forcing(0);
    if s.norm() == 0.0 {
        return Err(FrcError::Unsupported(
            "the forcing does not reach the master mode (u^* F = 0): no resonant response".into(),
        ));
    }
    let pol = polar(ssm)?;
    let eps_list = &sec.epsilon;
    let orders = sec.orders.clone().unwrap_or_else(|| vec![ssm.order]);
    let eps_max = eps_list.iter().copied().fold(0.0, f64::max);
    let mut warnings = Vec::new();
    let mut cut_short = false;
    let points = sec.points;
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let single_harmonic = sys.forcing.len() == 1 && sys.forcing[0].multiple == 1.0;
    let k_na = sec.nonautonomous_order;
    if k_na.is_some_and(|k| k > 0) && !single_harmonic {
        return Err(FrcError::Unsupported(
            "nonautonomous_order > 0 needs a single forcing harmonic at Omega".into(),
        ));
    }
    let width = range.1 - range.0;
    let nodes = ForcedCoefficients::nodes(
        range.0 - 0.1 * width,
        range.1 + 0.1 * width,
        NONAUTONOMOUS_NODES,
    );
    let weights: Vec<&[(usize, f64)]> = outputs.iter().map(|o| o.weights.as_slice()).collect();
    // the output table's series over the non-autonomous nodes' band, which
    // the table's multi-index 0 then reuses
    let band = nodes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &w| {
            (lo.min(w), hi.max(w))
        });
    // the amplitude scan and the output table read different things: side
    // by side (the table's series runs on one core)
    let (scan, table_error) = rayon::join(
        || {
            sec.rho_max
                .is_none()
                .then(|| default_rho_max(ssm, sys, &masters[0], &pol, &orders, eps_max * s, range))
        },
        || forced.tabulate_outputs_within(range.0, range.1, band, &weights),
    );
    let rho_max = match (sec.rho_max, scan) {
        (Some(r), _) => r,
        (None, scan) => {
            let (rho_max, cut) = scan.expect("scanned without [forcing] rho_max");
            cut_short = cut.is_some();
            warnings.extend(cut);
            rho_max
        }
    };
    let table_error = table_error?;
    if let Some(w) = table_warning(table_error, range) {
        warnings.push(w);
    }
    let mut ctx = Context {
        ssm,
        sys,
        masters,
        outputs,
        forced,
        pol,
        s,
        rho_max,
        points,
        range,
        series,
        nodes,
        tables: HashMap::new(),
    };
    let mut rows = Vec::new();
    let mut curves = Vec::new();
    for (&order, &eps) in orders
        .iter()
        .flat_map(|o| eps_list.iter().map(move |e| (o, e)))
    {
        let top = order.saturating_sub(1);
        // the non-autonomous orders tried: the scene's (and the next, for the
        // change), or 0, 2, 4, .. up to order - 1 until the estimate meets
        // the tolerance (a force with several harmonics has the leading
        // order only)
        let ladder: Vec<usize> = match k_na {
            Some(k) => vec![k.min(top), (k + 2).min(top)],
            None if single_harmonic => (0..=top).step_by(2).chain([top]).collect(),
            None => vec![0],
        };
        let mut tried: Vec<Attempt> = Vec::new();
        let mut chosen = None;
        for &k in &ladder {
            if tried.last().is_some_and(|a| a.k == k) {
                continue;
            }
            let (r, c, modal) = match ctx.curve(order, eps, k) {
                // the whole response lies beyond the convergence limit (warned)
                Err(FrcError::Empty { .. }) if cut_short => break,
                other => other?,
            };
            let peak = r.iter().map(FrcRow::plotted).fold(0.0, f64::max);
            let mut estimate = modal;
            if let Some(prev) = tried.last_mut() {
                // the change of the peak, and of the amplitude at every
                // frequency where both curves are single-valued, bounds the
                // previous rung's error, and conservatively this one's
                let change = ((prev.peak - peak).abs() / peak.max(f64::MIN_POSITIVE))
                    .max(curve_change(&prev.rows, &r));
                prev.estimate = prev.estimate.max(change);
                estimate = estimate.max(change);
            }
            tried.push(Attempt {
                k,
                rows: r,
                curve: c,
                peak,
                estimate,
            });
            if k_na.is_none() && tried.len() > 1 && estimate <= tolerance {
                chosen = Some(tried.len() - 1);
                break;
            }
        }
        if tried.is_empty() {
            continue;
        }
        let pick = match (k_na, chosen) {
            (Some(_), _) => 0,
            (None, Some(i)) => i,
            (None, None) => tried
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.estimate.total_cmp(&b.1.estimate))
                .map_or(0, |(i, _)| i),
        };
        let best = tried.swap_remove(pick);
        let untrusted = accuracy::exceeds(best.estimate, tolerance);
        if untrusted {
            warnings.push(format!(
                "O({order}), eps = {eps}: the estimated error of the response, {}, exceeds the accuracy target {} ([ssm] tolerance) with non-autonomous order {}; do not trust this curve: {}",
                percent(best.estimate),
                percent(tolerance),
                best.k,
                if k_na.is_some_and(|k| k < top) {
                    "raise [forcing] nonautonomous_order (or leave it out to let the engine choose)"
                } else {
                    "raise the expansion order, or lower the forcing (the response may lie beyond the SSM's convergence radius)"
                }, eps = ssm_kernel::number::short(eps)
            ));
        }
        let mut curve = best.curve;
        curve.untrusted = untrusted;
        if let CurveDetails::OnePair { error_estimate, .. } = &mut curve.details {
            *error_estimate = best.estimate;
        }
        rows.extend(best.rows);
        curves.push(curve);
    }
    Ok(ForcedResponse {
        outputs: outputs.iter().map(|o| o.name.clone()).collect(),
        rows,
        curves,
        resonance: ratios,
        rho_max: Some(rho_max),
        forcing_on_master: vec![s],
        warnings,
        linear: ctx.forced.counts(),
        factor_bytes: ctx.forced.factor_bytes(),
    })
}

impl Context<'_> {
    /// The curve at `order`, `eps` with non-autonomous order `k_eff`, and the
    /// modal-residual estimate of its relative error.
    fn curve(
        &mut self,
        order: usize,
        eps: f64,
        k_eff: usize,
    ) -> Result<(Vec<FrcRow>, FrcCurve, f64), FrcError> {
        if k_eff > 0 && !self.tables.contains_key(&k_eff) {
            let t = nonautonomous_table(
                &mut self.forced,
                self.ssm,
                self.sys,
                self.outputs,
                k_eff,
                &self.nodes,
                0.5 * (self.range.0 + self.range.1),
            )?;
            self.tables.insert(k_eff, t);
        }
        let (ssm, sys, masters, outputs) = (self.ssm, self.sys, self.masters, self.outputs);
        let (s, rho_max, points, range) = (self.s, self.rho_max, self.points, self.range);
        let (series, nodes, pol) = (&self.series, &self.nodes, &self.pol);
        let forced = &mut self.forced;
        let tables = &self.tables;
        let mut rows = Vec::new();
        let table = tables.get(&k_eff);
        let mut pb = OnePair::new(pol, order, eps * s);
        if let Some(t) = table {
            pb = pb.with_forced(ForcedCoefficients::new(
                nodes.clone(),
                t.coeffs.clone(),
                eps,
            ));
        }
        let f = one_pair_frc(&pb, rho_max, points, range);
        if f.points.is_empty() {
            return Err(FrcError::Empty {
                order,
                epsilon: eps,
                rho_max,
            });
        }
        for p in &f.points {
            let mut linf = Vec::with_capacity(outputs.len());
            let mut h1 = Vec::with_capacity(outputs.len());
            match table {
                Some(t) => {
                    let x = ssm_kernel::chebyshev::interpolate(nodes, &t.xs, p.omega);
                    let len = t.set.len();
                    for (oi, ser) in series.iter().enumerate() {
                        let xo = &x[oi * len..(oi + 1) * len];
                        let part = |q: C64, phi: f64| {
                            let mono = t.set.monomials(&[q, q.conj()], t.set.max_order());
                            let v: C64 = xo.iter().zip(&mono).map(|(a, b)| a * b).sum();
                            2.0 * eps * (v * C64::from_polar(1.0, phi)).re
                        };
                        let (l, a) = response_amplitudes(ssm, ser, order, p, &part);
                        linf.push(l);
                        h1.push(a);
                    }
                }
                None => {
                    let x0 = forced.outputs_at(p.omega)?;
                    for (oi, ser) in series.iter().enumerate() {
                        let part = |_: C64, phi: f64| eps * x0.value(oi, phi);
                        let (l, a) = response_amplitudes(ssm, ser, order, p, &part);
                        linf.push(l);
                        h1.push(a);
                    }
                }
            }
            if linf.iter().chain(&h1).any(|v| !v.is_finite()) {
                return Err(FrcError::Unsupported(format!(
                "O({order}), eps = {eps}: non-finite response amplitude at rho = {}: the expansion diverges there; lower [forcing] rho_max",
                p.rho, eps = ssm_kernel::number::short(eps)
            )));
            }
            rows.push(FrcRow {
                order,
                epsilon: eps,
                omega: p.omega,
                branch: p.branch,
                stable: p.stable,
                rho: p.rho,
                q: vec![C64::from_polar(p.rho, p.theta)],
                pair_amplitudes: vec![p.rho],
                linf,
                h1,
            });
        }
        let curve_rows = &rows[..];
        // the error figure beside the answer: eq. (41) at the largest amplitude
        let rho_peak = f.points.iter().map(|p| p.rho).fold(0.0, f64::max);
        let err = (rho_peak > 0.0).then(|| invariance_error(ssm, sys, order, rho_peak, 2, 30));
        // and the residual of eq. (60) along the peak's periodic orbit (Fig. 6)
        let peak = f.points.iter().max_by(|a, b| a.rho.total_cmp(&b.rho));
        let (res60, error_estimate) = match peak {
            Some(pk) => {
                let mid = 0.5 * (range.0 + range.1);
                let band = table
                    .and_then(|t| t.series.as_ref())
                    .filter(|s| s.contains(pk.omega));
                // the leading order's: the output table's series where it
                // holds the peak's frequency (it solves the system there)
                let leading = (k_eff == 0)
                    .then(|| forced.at_series(pk.omega))
                    .flatten()
                    .map(|x0| NonAutonomous::leading(x0, ssm.dim()));
                let mut one = match (band, leading) {
                    (Some(s), _) => vec![s.at(pk.omega)],
                    (None, Some(x0)) => vec![x0],
                    (None, None) => forced.expansions(ssm, sys, &[pk.omega], k_eff, Some(mid))?,
                };
                let na = one.pop().expect("one frequency, one expansion");
                // the orbit's samples, in groups one per core
                let orbit: Vec<(Vec<C64>, f64)> = (0..ORBIT_SAMPLES)
                    .map(|k| {
                        let phi = 2.0 * std::f64::consts::PI * k as f64 / ORBIT_SAMPLES as f64;
                        let q = C64::from_polar(pk.rho, pk.theta + phi);
                        (vec![q, q.conj()], phi)
                    })
                    .collect();
                let samples: Vec<(f64, C64)> = na
                    .residuals(ssm, sys, eps, &orbit, order)
                    .into_iter()
                    .map(|r| {
                        let norm = r.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
                        let modal = masters[0]
                            .left
                            .iter()
                            .zip(&r)
                            .map(|(u, x)| u.conj() * x)
                            .sum();
                        (norm, modal)
                    })
                    .collect();
                let res60 = samples.iter().map(|s| s.0).fold(0.0f64, f64::max);
                let modal: Vec<C64> = samples.iter().map(|s| s.1).collect();
                let lambda = masters[0].lambda;
                let q0 = C64::from_polar(pk.rho, pk.theta);
                let d = accuracy::defect(&modal, 1, q0, pk.rho, lambda.norm());
                (res60, d.forced(lambda))
            }
            None => (0.0, 0.0),
        };
        let bifurcations = f
            .bifurcations
            .iter()
            .map(|b| FrcBifurcation {
                kind: b.kind.label(),
                omega: b.omega,
                branch: b.branch,
                rho: vec![b.rho],
                plotted: curve_rows
                    .iter()
                    .filter(|r| r.branch == b.branch)
                    .min_by(|x, y| (x.rho - b.rho).abs().total_cmp(&(y.rho - b.rho).abs()))
                    .map(FrcRow::plotted),
            })
            .collect();
        let curve = FrcCurve {
            order,
            epsilon: eps,
            points: f.points.len(),
            branches: f.points.iter().map(|p| p.branch).max().unwrap_or(0),
            bifurcations,
            untrusted: false,
            details: CurveDetails::OnePair {
                rho_peak,
                invariance_error_at_peak: err.filter(|e| e.is_finite()),
                residual_eq60_at_peak: res60.is_finite().then_some(res60),
                error_estimate,
                nonautonomous_order: k_eff,
            },
        };
        Ok((rows, curve, error_estimate))
    }
}

/// Ratio of consecutive amplitudes of the scan of [`default_rho_max`]: fine
/// enough to place the grid's end within 2 % of the response's largest
/// amplitude, while 2000 amplitudes cover 17 decades.
const SCAN_RATIO: f64 = 1.02;

/// Amplitudes of the scan of [`default_rho_max`] between two evaluations
/// of the backbone estimate before the first diverged one is bisected
/// (ratio `1.02^32 = 1.88`): the estimate grows like a power of the
/// amplitude, so it crosses the limit once within such a step, and the
/// scan costs about 67 estimates an order instead of 2000, each `O(N)` (a
/// modal residual on a circle): on large models this scan was most of the
/// forced response's time. [`first_true_par`] finds what the full scan finds
/// when the estimate crosses the limit once within a stride.
const SCAN_STRIDE: usize = 32;

/// The grid's end over the largest amplitude the leading-order response
/// reaches in the range: the scan's step (2 %) and the shift of the peak by
/// the non-autonomous terms of higher order (a few percent where the curve
/// is trusted) stay inside it; spurious roots of the truncated amplitude
/// equation, which come from its highest terms at amplitudes where they
/// rival the lowest, lie well beyond (Duffing at O(13): 0.75 against a
/// response up to 0.41).
const REACH_MARGIN: f64 = 1.25;

/// Where the scan of [`default_rho_max`] stops: the estimated relative error
/// of the backbone frequency ([`accuracy::backbone_error`]) at 100 %: beyond
/// it the truncated expansion no longer describes the motion (the amplitude
/// is outside its convergence estimate), so its fixed points there are no
/// response of the model.
const CONVERGENCE_LIMIT: f64 = 1.0;

/// The amplitude grid's end `rho_max` when `[forcing] rho_max` is not given,
/// for the forcing `eps_s = eps s` on the master pair of `master`, and the
/// warning when the expansion's convergence estimate cut the response short.
///
/// The response reaches amplitude `rho` inside `range` where
/// [`OnePair::reaches`]: its damping lets it (`rho |Re g| <= eps |s|`, which
/// for linear damping bounds it by the linear peak `eps |s| / |Re lambda|`)
/// and its backbone `Im g(rho^2)` is within `eps |s| / rho` of the range.
/// Amplitudes are scanned geometrically ([`SCAN_RATIO`]) from far below the
/// linear peak up to three times it, at every order of `orders`, and the
/// scan stops where the backbone's error estimate passes
/// [`CONVERGENCE_LIMIT`]; the grid ends [`REACH_MARGIN`] above the largest
/// amplitude reached (so that the fixed-point scan of [`one_pair_frc`]
/// resolves the response, and neither the empty amplitudes beyond a lightly
/// damped linear peak nor the spurious roots of a truncated expansion far
/// above the response), at three times the linear peak at most, and at the
/// convergence limit where the response still reached there (the warning).
fn default_rho_max(
    ssm: &SsmExpansion,
    sys: &System,
    master: &MasterMode,
    pol: &Polar,
    orders: &[usize],
    eps_s: C64,
    range: (f64, f64),
) -> (f64, Option<String>) {
    let linear = eps_s.norm() / master.lambda.re.abs().max(f64::MIN_POSITIVE);
    let top = 3.0 * linear;
    let modal = ModalResidual::new(ssm, sys, &master.left);
    // the scan's amplitudes, each the previous one times SCAN_RATIO
    let mut grid = Vec::new();
    let mut rho = top * 1e-17_f64.max(f64::MIN_POSITIVE / top);
    while rho <= top {
        grid.push(rho);
        rho *= SCAN_RATIO;
    }
    let (mut reach, mut cut) = (0.0_f64, None::<(usize, f64)>);
    for &order in orders {
        let pb = OnePair::new(pol, order, eps_s);
        // the backbone estimate costs O(N) (a modal residual on a circle),
        // the reduced model's reach O(1): the first diverged amplitude is
        // found on every SCAN_STRIDE-th one and bisected in between
        let first = first_true_par(grid.len(), SCAN_STRIDE, |k| {
            accuracy::backbone_error(ssm, &modal, master.lambda, grid[k], order)
                .is_some_and(|e| e.is_nan() || e > CONVERGENCE_LIMIT)
        });
        let below = first.unwrap_or(grid.len());
        if let Some(&r) = grid[..below].iter().rev().find(|&&r| pb.reaches(r, range)) {
            reach = reach.max(r);
        }
        if let Some(k) = first {
            let rho = grid[k];
            if pb.reaches(rho, range) && cut.is_none_or(|(_, r)| rho < r) {
                cut = Some((order, rho));
            }
        }
    }
    match cut {
        Some((order, at)) => (
            at,
            Some(format!(
                "the forced response at eps |s| = {:.3e} reaches beyond amplitude rho = {at:.4e}, where the O({order}) expansion's backbone error estimate passes {}: the curves end there (their part beyond is not a response of the model); lower the forcing or raise the order, or set [forcing] rho_max to see the expansion beyond",
                eps_s.norm(),
                percent(CONVERGENCE_LIMIT)
            )),
        ),
        None if reach > 0.0 => ((REACH_MARGIN * reach).min(top), None),
        None => (top, None),
    }
}

/// Samples of the peak's periodic orbit for the eq. (60) residual.
const ORBIT_SAMPLES: usize = 64;

/// Higher-order non-autonomous terms of order `k`: exact expansions at the
/// Chebyshev nodes in `Omega`, interpolated in between (sigma, tau and the
/// outputs' X); each multi-index's solves at the nodes go through one
/// factorization at `mid`, the middle of the nodes' band and of the forced
/// response's range (where the X0 table's factorization is).
fn nonautonomous_table(
    forced: &mut ForcedSsm,
    ssm: &SsmExpansion,
    sys: &System,
    outputs: &[&OutputMap],
    k: usize,
    nodes: &[f64],
    mid: f64,
) -> Result<NaTable, FrcError> {
    let series = if forced.iterative() {
        // the output table's factorization is not needed beside these
        forced.drop_anchor_factors();
        forced.expansion_series(ssm, sys, nodes, k, mid)?
    } else {
        None
    };
    if let Some(s) = series {
        // the reduced coefficients and outputs from their series alone
        return Ok(NaTable {
            coeffs: nodes
                .iter()
                .map(|&w| s.rotating_frame_coefficients_at(w))
                .collect(),
            xs: nodes
                .iter()
                .map(|&w| {
                    outputs
                        .iter()
                        .flat_map(|o| s.outputs_at(w, &o.weights))
                        .collect()
                })
                .collect(),
            set: s.set.clone(),
            series: Some(s),
        });
    }
    let expansions = forced.expansions_solved(ssm, sys, nodes, k, Some(mid))?;
    let mut coeffs = Vec::with_capacity(nodes.len());
    let mut xs = Vec::with_capacity(nodes.len());
    for na in &expansions {
        coeffs.push(na.rotating_frame_coefficients());
        let h = &na.harmonics[0];
        xs.push(
            outputs
                .iter()
                .flat_map(|o| {
                    h.x.iter()
                        .map(|xk| o.weights.iter().map(|&(s, wt)| xk[s] * wt).sum::<C64>())
                        .collect::<Vec<_>>()
                })
                .collect::<Vec<C64>>(),
        );
    }
    Ok(NaTable {
        coeffs,
        xs,
        set: expansions[0].set.clone(),
        series: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(branch: usize, omega: f64, amplitude: f64) -> FrcRow {
        FrcRow {
            order: 3,
            epsilon: 0.1,
            omega,
            branch,
            stable: true,
            rho: amplitude,
            q: Vec::new(),
            pair_amplitudes: vec![amplitude],
            linf: vec![amplitude],
            h1: vec![amplitude],
        }
    }

    /// Two single-valued curves: the change is the largest relative gap at
    /// the new curve's frequencies, interpolated linearly on the old one.
    #[test]
    fn the_change_of_single_valued_curves_is_their_largest_gap() {
        let old: Vec<FrcRow> = (0..=10).map(|i| row(1, i as f64, 1.0)).collect();
        let new: Vec<FrcRow> = (0..=20)
            .map(|i| row(1, 0.5 * i as f64, 1.0 + 0.01 * (0.5 * i as f64 - 5.0).abs()))
            .collect();
        let c = curve_change(&old, &new);
        // largest at omega = 0 and 10: 0.05 / 1.05
        assert!((c - 0.05 / 1.05).abs() < 1e-15, "{c}");
        assert_eq!(curve_change(&old, &old), 0.0);
    }

    /// Where a curve folds over (three branches of one frequency), or where
    /// the other curve does not reach, nothing is compared.
    #[test]
    fn folds_and_frequencies_outside_either_curve_are_not_compared() {
        // a fold: forward to 2, back to 1, forward to 3, with amplitudes far
        // from the old curve's only on the folded part 1 < omega < 2
        let new = vec![
            row(1, 0.0, 1.0),
            row(1, 1.0, 1.0),
            row(1, 2.0, 9.0),
            row(1, 1.0, 9.0),
            row(1, 2.0, 1.0),
            row(1, 3.0, 1.0),
        ];
        let old: Vec<FrcRow> = (0..=4).map(|i| row(1, 0.5 * i as f64, 1.0)).collect();
        // only omega = 0 is single-valued on both curves (1 and 2 meet the
        // fold's ends, 3 lies beyond the old curve)
        assert_eq!(curve_change(&old, &new), 0.0);
        // two branches over the same frequencies
        let two = vec![
            row(1, 0.0, 1.0),
            row(1, 2.0, 1.0),
            row(2, 0.0, 5.0),
            row(2, 2.0, 5.0),
        ];
        assert_eq!(curve_change(&old, &two), 0.0);
    }
}
