//! Forced response curves for the report: `frc.csv`, `frc.svg` and the `frc`
//! entry of `summary.json`, from the leading-order periodic SSM
//! ([`crate::ssm::forced`]) and the rotating-frame fixed points ([`crate::rom::frc`]).

use serde_json::{json, Value};

use crate::model::system::{OutputMap, System};
use crate::output::plot::{line_plot, Curve, PlotError, Scale};
use crate::poly::MultiIndexSet;
use crate::rom::frc::{
    chebyshev_interpolate, one_pair_frc, response_amplitudes, ForcedCoefficients, OnePair,
};
use crate::scene::ForcingSection;
use crate::spectrum::MasterMode;
use crate::ssm::analysis::{invariance_error, polar, PolarError};
use crate::ssm::forced::{ForcedError, ForcedSsm};
use crate::ssm::SsmExpansion;
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
    /// Plot failure.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// What the FRC path does not cover.
    #[error("FRC: {0}")]
    Unsupported(String),
    /// The continuation could not start.
    #[error("FRC: {0}")]
    Continuation(#[from] crate::rom::continuation::ContinuationError),
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

/// One point of an FRC as written to `frc.csv`.
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
    /// Largest `|output|` over the response period, per output.
    pub linf: Vec<f64>,
}

/// The products of the `[forcing]` section.
#[derive(Debug, Clone)]
pub struct FrcReport {
    /// `frc.csv`.
    pub csv: String,
    /// `frc.svg`.
    pub svg: String,
    /// `"frc"` of the summary.
    pub summary: Value,
    /// The rows of `frc.csv`.
    pub rows: Vec<FrcRow>,
    /// The curves of `frc.svg` (for overlays such as full-system references).
    pub curves: Vec<Curve>,
}

/// FRCs for every `(order, epsilon)` of `sec`; columns
/// `order,epsilon,omega,stable,branch,<output>_linf...,rho_1,<output>_h1...`.
pub fn frc(
    ssm: &SsmExpansion,
    sys: &System,
    masters: &[MasterMode],
    sec: &ForcingSection,
    outputs: &[&OutputMap],
) -> Result<FrcReport, FrcError> {
    if let crate::ssm::Dynamics::Map { .. } = ssm.dynamics {
        return Err(FrcError::Unsupported(
            "the model is a map; [forcing] needs a flow".into(),
        ));
    }
    let range0 = (sec.omega_range.get_ref()[0], sec.omega_range.get_ref()[1]);
    let ratios = match &sec.resonance {
        Some(r) => r.get_ref().clone(),
        None => auto_ratios(masters, 0.5 * (range0.0 + range0.1)),
    };
    if masters.len() > 1 {
        return crate::results_frc_multi::frc_multi(ssm, sys, masters, sec, outputs, &ratios);
    }
    if ratios[0] != 1.0 {
        return Err(FrcError::Unsupported(format!(
            "resonance ratio {} for a single pair: only primary resonance (r = 1) is implemented",
            ratios[0]
        )));
    }
    let range = (sec.omega_range.get_ref()[0], sec.omega_range.get_ref()[1]);
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
    let mut csv = csv_header(outputs, 1);
    let mut rows = Vec::new();
    // higher-order non-autonomous terms: exact expansions at Chebyshev nodes in
    // Omega, interpolated in between (sigma, tau and the outputs' X), one table
    // per effective order min(K, order - 1)
    let k_na = sec.nonautonomous_order.as_ref().map_or(0, |k| *k.get_ref());
    if k_na > 0 && (sys.forcing.len() != 1 || sys.forcing[0].multiple != 1.0) {
        return Err(FrcError::Unsupported(
            "nonautonomous_order > 0 needs a single forcing harmonic at Omega".into(),
        ));
    }
    let width = range.1 - range.0;
    let nodes = ForcedCoefficients::nodes(range.0 - 0.1 * width, range.1 + 0.1 * width, 17);
    let mut tables: std::collections::HashMap<usize, NaTable> = std::collections::HashMap::new();
    for &order in &orders {
        let k_eff = k_na.min(order.saturating_sub(1));
        if k_eff == 0 || tables.contains_key(&k_eff) {
            continue;
        }
        let mut coeffs = Vec::with_capacity(nodes.len());
        let mut xs = Vec::with_capacity(nodes.len());
        let mut set = None;
        for &w in &nodes {
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
    let mut curves: Vec<Curve> = Vec::new();
    let mut bifurcations = Vec::new();
    let mut summaries = Vec::new();
    let mut n_points = 0;
    for (ci, (&order, &eps)) in orders
        .iter()
        .flat_map(|o| eps_list.iter().map(move |e| (o, e)))
        .enumerate()
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
        let mut first_amp = Vec::with_capacity(f.points.len());
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
            csv.push_str(&format!(
                "{order},{eps:e},{:.10e},{},{}",
                p.omega,
                u8::from(p.stable),
                p.branch
            ));
            for l in &linf {
                csv.push_str(&format!(",{l:.10e}"));
            }
            csv.push_str(&format!(",{:.10e}", p.rho));
            for a in &h1 {
                csv.push_str(&format!(",{a:.10e}"));
            }
            csv.push('\n');
            first_amp.push(linf.first().copied().unwrap_or(p.rho));
            rows.push(FrcRow {
                order,
                epsilon: eps,
                omega: p.omega,
                branch: p.branch,
                stable: p.stable,
                rho: p.rho,
                q: vec![C64::from_polar(p.rho, p.theta)],
                linf: linf.clone(),
            });
        }
        n_points += f.points.len();
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
        summaries.push(json!({
            "order": order,
            "epsilon": eps,
            "points": f.points.len(),
            "branches": f.points.iter().map(|p| p.branch).max().unwrap_or(0),
            "rho_peak": rho_peak,
            "invariance_error_at_peak": err.filter(|e| e.is_finite()),
            "residual_eq60_at_peak": res60.is_finite().then_some(res60),
            "nonautonomous_order": k_eff,
        }));
        // one segment per run of equal stability on a branch; dashed when unstable
        let mut k = 0;
        let mut labelled = false;
        while k < f.points.len() {
            let (st, br) = (f.points[k].stable, f.points[k].branch);
            let mut seg = Vec::new();
            // the segment shares its first point with the previous one
            if k > 0 && f.points[k - 1].branch == br {
                seg.push((f.points[k - 1].omega, first_amp[k - 1]));
            }
            while k < f.points.len() && f.points[k].stable == st && f.points[k].branch == br {
                seg.push((f.points[k].omega, first_amp[k]));
                k += 1;
            }
            curves.push(Curve {
                label: if labelled {
                    String::new()
                } else {
                    format!("O({order}), eps = {eps}")
                },
                points: seg,
                dashed: !st,
                markers: Vec::new(),
                color: Some(ci),
            });
            labelled = true;
        }
        for b in &f.bifurcations {
            let nearest = f
                .points
                .iter()
                .enumerate()
                .filter(|(_, p)| p.branch == b.branch)
                .min_by(|x, y| (x.1.rho - b.rho).abs().total_cmp(&(y.1.rho - b.rho).abs()));
            if let (Some((i, _)), Some(c)) = (nearest, curves.last_mut()) {
                c.markers.push((b.omega, first_amp[i]));
            }
            bifurcations.push(json!({
                "kind": b.kind.label(),
                "omega": b.omega,
                "epsilon": eps,
                "order": order,
                "rho": b.rho,
                "branch": b.branch,
            }));
        }
    }
    assemble(
        csv,
        rows,
        curves,
        outputs,
        json!({
            "bifurcations": bifurcations,
            "points": n_points,
            "curves": summaries,
            "resonance": ratios,
            "rho_max": rho_max,
            "forcing_on_master": {"re": s.re, "im": s.im},
        }),
    )
}

/// Header of `frc.csv` for `m` pairs:
/// `order,epsilon,omega,stable,branch,<out>_linf...,rho_1..rho_m,<out>_h1...`.
pub(crate) fn csv_header(outputs: &[&OutputMap], m: usize) -> String {
    let mut csv = String::from("order,epsilon,omega,stable,branch");
    for o in outputs {
        csv.push_str(&format!(",{}_linf", o.name));
    }
    for j in 1..=m {
        csv.push_str(&format!(",rho_{j}"));
    }
    for o in outputs {
        csv.push_str(&format!(",{}_h1", o.name));
    }
    csv.push('\n');
    csv
}

/// `frc.svg` (amplitude of the first output, or `rho_1`, against `Omega`) and
/// the report around `csv` and `summary`.
pub(crate) fn assemble(
    csv: String,
    rows: Vec<FrcRow>,
    curves: Vec<Curve>,
    outputs: &[&OutputMap],
    summary: Value,
) -> Result<FrcReport, FrcError> {
    let svg = frc_svg(&curves, outputs)?;
    Ok(FrcReport {
        csv,
        svg,
        summary,
        rows,
        curves,
    })
}

/// `frc.svg` of `curves`: amplitude of the first output (or `rho_1`) against `Omega`.
pub fn frc_svg(curves: &[Curve], outputs: &[&OutputMap]) -> Result<String, PlotError> {
    let y_label = outputs
        .first()
        .map_or("rho_1".to_owned(), |o| format!("max |{}|", o.name));
    line_plot(
        "forced response (dashed: unstable, circles: bifurcations)",
        "Omega",
        &y_label,
        curves,
        Scale::Linear,
    )
}
