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

use std::collections::HashMap;

use crate::model::system::{OutputMap, System};
use crate::poly::MultiIndexSet;
use crate::rom::frc::{
    chebyshev_interpolate, one_pair_frc, response_amplitudes, ForcedCoefficients, OnePair,
};
use crate::scene::ForcingSection;
use crate::spectrum::MasterMode;
use crate::ssm::analysis::{invariance_error, polar, PolarError};
use crate::ssm::forced::{ForcedError, ForcedSsm};
use crate::ssm::{Dynamics, SsmExpansion};
use crate::C64;

/// Why an FRC could not be produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrcError {
    /// The periodic SSM failed.
    #[error("forced SSM: {0}")]
    Forced(#[from] ForcedError),
    /// No polar form.
    #[error("FRC: {0}")]
    Polar(#[from] PolarError),
    /// What the FRC path does not cover.
    #[error("FRC: {0}")]
    Unsupported(String),
    /// A curve has no point in the frequency range.
    #[error("FRC O({order}), eps = {epsilon}: no response found in the frequency range with amplitudes up to rho_max = {rho_max:e}; every forcing frequency has one, so the amplitude grid missed them: set [forcing] rho_max near the expected peak amplitude (or raise points)")]
    Empty {
        /// Expansion order.
        order: usize,
        /// Forcing amplitude.
        epsilon: f64,
        /// Largest amplitude searched.
        rho_max: f64,
    },
    /// The continuation could not start.
    #[error("FRC: {0}")]
    Continuation(#[from] crate::rom::continuation::ContinuationError),
}

/// One point of a forced response curve.
#[derive(Debug, Clone, PartialEq)]
pub struct FrcRow {
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Forcing frequency.
    pub omega: f64,
    /// Branch number (points of one branch are consecutive, in arc order).
    pub branch: usize,
    /// Stability.
    pub stable: bool,
    /// Polar amplitude `|p|` of the fixed point (all pairs).
    pub rho: f64,
    /// The fixed point `q_j` of each pair in the rotating frame, `p_j(t) =
    /// q_j e^{i r_j Omega t}`: the reduced coordinates at `t = 0`.
    pub q: Vec<C64>,
    /// `|q_j|` of each pair.
    pub pair_amplitudes: Vec<f64>,
    /// Largest `|output|` over the response period, per output.
    pub linf: Vec<f64>,
    /// Amplitude of the first harmonic of each output.
    pub h1: Vec<f64>,
}

impl FrcRow {
    /// The amplitude an FRC is drawn with: the first output's, or `|q_1|`.
    pub fn plotted(&self) -> f64 {
        self.linf
            .first()
            .copied()
            .unwrap_or_else(|| self.pair_amplitudes.first().copied().unwrap_or(self.rho))
    }
}

/// A bifurcation (or branch point) located on a forced response curve.
#[derive(Debug, Clone, PartialEq)]
pub struct FrcBifurcation {
    /// `"SN"`, `"HB"`, `"BP"`, ...
    pub kind: &'static str,
    /// Forcing frequency.
    pub omega: f64,
    /// Branch it lies on.
    pub branch: usize,
    /// `|q_j|` of each pair there.
    pub rho: Vec<f64>,
    /// Drawn amplitude of the nearest computed point of its branch.
    pub plotted: Option<f64>,
}

/// What is known of one curve beyond its points.
#[derive(Debug, Clone, PartialEq)]
pub enum CurveDetails {
    /// One pair: fixed points on an amplitude grid, with error figures.
    OnePair {
        /// Largest polar amplitude on the curve.
        rho_peak: f64,
        /// Eq. (41) at `rho_peak`.
        invariance_error_at_peak: Option<f64>,
        /// Largest eq. (60) residual along the peak's periodic orbit.
        residual_eq60_at_peak: Option<f64>,
        /// Order of the non-autonomous terms used.
        nonautonomous_order: usize,
    },
    /// Several pairs: pseudo-arclength continuation with branch switching.
    Continuation {
        /// Branches switched to at branch points.
        branch_switches: usize,
        /// Continuation steps over all branches.
        continuation_steps: usize,
    },
}

/// One forced response curve: an expansion order and a forcing amplitude.
#[derive(Debug, Clone, PartialEq)]
pub struct FrcCurve {
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Points written (inside the frequency range).
    pub points: usize,
    /// Branches.
    pub branches: usize,
    /// Bifurcations inside the frequency range.
    pub bifurcations: Vec<FrcBifurcation>,
    /// Method-specific figures.
    pub details: CurveDetails,
}

/// Everything `[forcing]` produced.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcedResponse {
    /// Names of the outputs of `linf` and `h1`.
    pub outputs: Vec<String>,
    /// All points, curve after curve.
    pub rows: Vec<FrcRow>,
    /// The curves, in the order of `rows`.
    pub curves: Vec<FrcCurve>,
    /// External resonance ratios `r_j` (eq. 16).
    pub resonance: Vec<f64>,
    /// Largest polar amplitude searched (one pair).
    pub rho_max: Option<f64>,
    /// Resonant forcing `u_j^* Fext` on each master pair.
    pub forcing_on_master: Vec<C64>,
    /// Terms left out or other caveats.
    pub warnings: Vec<String>,
}

/// External resonance ratios chosen from the forcing frequency (eq. 16): the
/// pair whose frequency is nearest `omega` gets `r = 1`; the others the
/// nearest fraction `k/d`, `d <= 3`, of their frequency ratio to it.
pub fn auto_ratios(masters: &[MasterMode], omega: f64) -> Vec<f64> {
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

/// Exact non-autonomous data at the Chebyshev nodes in `Omega`.
struct NaTable {
    /// `(sigma, tau)` per node.
    coeffs: Vec<(Vec<C64>, Vec<C64>)>,
    /// Per node: the outputs' `x_k`, output after output, over `set`.
    xs: Vec<Vec<C64>>,
    /// Multi-indices of the expansion.
    set: MultiIndexSet,
}

/// FRCs for every `(order, epsilon)` of `sec`, with the amplitudes of `outputs`.
pub fn forced_response(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    sec: &ForcingSection,
    outputs: &[&OutputMap],
) -> Result<ForcedResponse, FrcError> {
    if let Dynamics::Map { .. } = ssm.dynamics {
        return Err(FrcError::Unsupported(
            "the model is a map; [forcing] needs a flow".into(),
        ));
    }
    let range = (sec.omega_range.get_ref()[0], sec.omega_range.get_ref()[1]);
    let ratios = match &sec.resonance {
        Some(r) => r.get_ref().clone(),
        None => auto_ratios(masters, 0.5 * (range.0 + range.1)),
    };
    if masters.len() > 1 {
        return crate::rom::forced_multi::forced_response_multi(
            ssm, sys, masters, sec, outputs, &ratios,
        );
    }
    if ratios[0] != 1.0 {
        return Err(FrcError::Unsupported(format!(
            "resonance ratio {} for a single pair: only primary resonance (r = 1) is implemented",
            ratios[0]
        )));
    }
    let mut forced = ForcedSsm::new(sys, masters, &ratios)?;
    let s = forced.at(0.5 * (range.0 + range.1))?.resonant_forcing(0);
    if s.norm() == 0.0 {
        return Err(FrcError::Unsupported(
            "the forcing does not reach the master mode (u^* F = 0): no resonant response".into(),
        ));
    }
    let pol = polar(ssm)?;
    let eps_list = sec.epsilon.get_ref();
    let orders = sec
        .orders
        .as_ref()
        .map_or(vec![ssm.order], |o| o.get_ref().clone());
    let eps_max = eps_list.iter().copied().fold(0.0, f64::max);
    let rho_max = sec.rho_max.as_ref().map_or_else(
        || 3.0 * eps_max * s.norm() / masters[0].lambda.re.abs().max(1e-300),
        |r| *r.get_ref(),
    );
    let points = *sec.points.get_ref();
    let series: Vec<Vec<C64>> = outputs
        .iter()
        .map(|o| ssm.output_series(&o.weights))
        .collect();
    let k_na = sec.nonautonomous_order.as_ref().map_or(0, |k| *k.get_ref());
    if k_na > 0 && (sys.forcing.len() != 1 || sys.forcing[0].multiple != 1.0) {
        return Err(FrcError::Unsupported(
            "nonautonomous_order > 0 needs a single forcing harmonic at Omega".into(),
        ));
    }
    let width = range.1 - range.0;
    let nodes = ForcedCoefficients::nodes(range.0 - 0.1 * width, range.1 + 0.1 * width, 17);
    let tables = nonautonomous_tables(&mut forced, ssm, sys, outputs, &orders, k_na, &nodes)?;
    let mut rows = Vec::new();
    let mut curves = Vec::new();
    for (&order, &eps) in orders
        .iter()
        .flat_map(|o| eps_list.iter().map(move |e| (o, e)))
    {
        let k_eff = k_na.min(order.saturating_sub(1));
        let table = tables.get(&k_eff);
        let mut pb = OnePair::new(&pol, order, eps * s);
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
        let first = rows.len();
        for p in &f.points {
            let mut linf = Vec::with_capacity(outputs.len());
            let mut h1 = Vec::with_capacity(outputs.len());
            match table {
                Some(t) => {
                    let x = chebyshev_interpolate(&nodes, &t.xs, p.omega);
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
                    let x0 = forced.at(p.omega)?;
                    for (o, ser) in outputs.iter().zip(&series) {
                        let part = |_: C64, phi: f64| eps * x0.output_at(&o.weights, phi);
                        let (l, a) = response_amplitudes(ssm, ser, order, p, &part);
                        linf.push(l);
                        h1.push(a);
                    }
                }
            }
            if linf.iter().chain(&h1).any(|v| !v.is_finite()) {
                return Err(FrcError::Unsupported(format!(
                    "O({order}), eps = {eps}: non-finite response amplitude at rho = {}: the expansion diverges there; lower [forcing] rho_max",
                    p.rho
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
        let curve_rows = &rows[first..];
        // the error figure beside the answer: eq. (41) at the largest amplitude
        let rho_peak = f.points.iter().map(|p| p.rho).fold(0.0, f64::max);
        let err = (rho_peak > 0.0).then(|| invariance_error(ssm, sys, order, rho_peak, 2, 30));
        // and the residual of eq. (60) along the peak's periodic orbit (Fig. 6)
        let peak = f.points.iter().max_by(|a, b| a.rho.total_cmp(&b.rho));
        let res60 = match peak {
            Some(pk) => {
                let na = forced.expansion(ssm, sys, pk.omega, k_eff)?;
                (0..64)
                    .map(|k| {
                        let phi = 2.0 * std::f64::consts::PI * f64::from(k) / 64.0;
                        let q = C64::from_polar(pk.rho, pk.theta + phi);
                        let r = na.residual(ssm, sys, eps, &[q, q.conj()], phi, order);
                        r.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt()
                    })
                    .fold(0.0, f64::max)
            }
            None => 0.0,
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
        curves.push(FrcCurve {
            order,
            epsilon: eps,
            points: f.points.len(),
            branches: f.points.iter().map(|p| p.branch).max().unwrap_or(0),
            bifurcations,
            details: CurveDetails::OnePair {
                rho_peak,
                invariance_error_at_peak: err.filter(|e| e.is_finite()),
                residual_eq60_at_peak: res60.is_finite().then_some(res60),
                nonautonomous_order: k_eff,
            },
        });
    }
    Ok(ForcedResponse {
        outputs: outputs.iter().map(|o| o.name.clone()).collect(),
        rows,
        curves,
        resonance: ratios,
        rho_max: Some(rho_max),
        forcing_on_master: vec![s],
        warnings: Vec::new(),
    })
}

/// Higher-order non-autonomous terms: exact expansions at the Chebyshev nodes
/// in `Omega`, interpolated in between (sigma, tau and the outputs' X), one
/// table per effective order `min(K, order - 1)`.
fn nonautonomous_tables(
    forced: &mut ForcedSsm,
    ssm: &SsmExpansion,
    sys: &System,
    outputs: &[&OutputMap],
    orders: &[usize],
    k_na: usize,
    nodes: &[f64],
) -> Result<HashMap<usize, NaTable>, FrcError> {
    let mut tables = HashMap::new();
    for &order in orders {
        let k_eff = k_na.min(order.saturating_sub(1));
        if k_eff == 0 || tables.contains_key(&k_eff) {
            continue;
        }
        let mut coeffs = Vec::with_capacity(nodes.len());
        let mut xs = Vec::with_capacity(nodes.len());
        let mut set = None;
        for &w in nodes {
            let na = forced.expansion(ssm, sys, w, k_eff)?;
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
            set = Some(na.set);
        }
        tables.insert(
            k_eff,
            NaTable {
                coeffs,
                xs,
                set: set.expect("at least one node"),
            },
        );
    }
    Ok(tables)
}
