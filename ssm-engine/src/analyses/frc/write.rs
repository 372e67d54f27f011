//! Writers of `[forcing]`: `frc.csv`, `frc.svg` (with the steady-state
//! reference of `[validate]` drawn in) and the summary's `frc`. They format a
//! [`ForcedResponse`] and compute nothing.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use ssm_kernel::number::short;

use crate::analyses::reference::write::reference_curves;
use crate::json::{Complex, LinearWork, PerPair};
use crate::plot::{line_plot, Curve, PlotError, Scale};
use ssm_core::compare::validation::SteadyReference;
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::rom::accuracy::percent;
use ssm_core::rom::forced_response::{CurveDetails, ForcedResponse, FrcCurve};

/// `frc.csv`: `order,epsilon,omega,stable,branch,<out>_linf...,rho_1..rho_m,<out>_h1...`.
pub(super) fn frc_csv(f: &ForcedResponse) -> String {
    let mut csv = String::from("order,epsilon,omega,stable,branch");
    for o in &f.outputs {
        csv.push_str(&format!(",{o}_linf"));
    }
    for j in 1..=f.forcing_on_master.len() {
        csv.push_str(&format!(",rho_{j}"));
    }
    for o in &f.outputs {
        csv.push_str(&format!(",{o}_h1"));
    }
    csv.push('\n');
    for r in &f.rows {
        csv.push_str(&format!(
            "{},{:e},{:.10e},{},{}",
            r.order,
            r.epsilon,
            r.omega,
            u8::from(r.stable),
            r.branch
        ));
        for v in r.linf.iter().chain(&r.pair_amplitudes).chain(&r.h1) {
            csv.push_str(&format!(",{v:.10e}"));
        }
        csv.push('\n');
    }
    csv
}

/// Drawn curves of `f`: per `(order, epsilon)` one segment per run of equal
/// stability on a branch (dashed when unstable; a segment shares its first
/// point with the previous one of its branch), and the bifurcations as circles.
fn curves(f: &ForcedResponse) -> Vec<Curve> {
    let mut drawn = Vec::new();
    let mut rows = f.rows.as_slice();
    for (ci, c) in f.curves.iter().enumerate() {
        let (mine, rest) = rows.split_at(c.points.min(rows.len()));
        rows = rest;
        let mut k = 0;
        let mut labelled = false;
        while k < mine.len() {
            let (st, br) = (mine[k].stable, mine[k].branch);
            let mut seg = Vec::new();
            if k > 0 && mine[k - 1].branch == br {
                seg.push((mine[k - 1].omega, mine[k - 1].plotted()));
            }
            while k < mine.len() && mine[k].stable == st && mine[k].branch == br {
                seg.push((mine[k].omega, mine[k].plotted()));
                k += 1;
            }
            drawn.push(Curve {
                label: if labelled {
                    String::new()
                } else {
                    format!(
                        "O({}), eps = {}, estimated error {}{}",
                        c.order,
                        short(c.epsilon),
                        percent(c.error_estimate()),
                        if c.untrusted {
                            "  UNTRUSTED: error estimate above [ssm] tolerance"
                        } else {
                            ""
                        }
                    )
                },
                points: seg,
                dashed: !st,
                markers: Vec::new(),
                color: Some(ci),
                full: false,
            });
            labelled = true;
        }
        drawn.push(Curve {
            label: String::new(),
            points: Vec::new(),
            dashed: false,
            markers: c
                .bifurcations
                .iter()
                .filter_map(|b| b.plotted.map(|y| (b.omega, y)))
                .collect(),
            color: Some(ci),
            full: false,
        });
    }
    drawn
}

/// `frc.svg`: amplitude of the first output (or `rho_1`) against `Omega`, with
/// the full-system steady states of `reference` as circles and the
/// full-system curves of `[reference]` in black.
pub(super) fn frc_svg(
    f: &ForcedResponse,
    reference: Option<&SteadyReference>,
    full: Option<&ReferenceFrc>,
) -> Result<String, PlotError> {
    let mut drawn = curves(f);
    if let Some(r) = full {
        // the full system beneath the reduced curves
        drawn.extend(
            reference_curves(r)
                .into_iter()
                .map(|c| Curve { full: true, ..c }),
        );
    }
    if let Some(r) = reference {
        drawn.push(Curve {
            label: format!("full system, eps = {} (steady state)", short(r.epsilon)),
            points: Vec::new(),
            markers: r
                .points
                .iter()
                .filter_map(|p| p.amplitudes.first().map(|&a| (p.omega, a)))
                .collect(),
            ..Curve::default()
        });
    }
    let y_label = f
        .outputs
        .first()
        .map_or("rho_1".to_owned(), |o| format!("max |{o}|"));
    line_plot(
        "forced response (dashed: unstable, circles: bifurcations)",
        "Omega",
        &y_label,
        &drawn,
        Scale::Linear,
    )
}

/// `"frc"` of `summary.json`: the forced response curves of `[forcing]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrcSummary {
    /// Bifurcations and branch points inside the frequency range.
    pub bifurcations: Vec<FrcBifurcationSummary>,
    /// Points of all curves (the rows of `frc.csv`).
    pub points: usize,
    /// One entry per expansion order and forcing amplitude.
    pub curves: Vec<FrcCurveSummary>,
    /// External resonance ratios `r_j` (eq. 16).
    pub resonance: Vec<f64>,
    /// Resonant forcing `u_j^* Fext` on the master pair (one per pair for
    /// several).
    pub forcing_on_master: PerPair<Complex>,
    /// Terms left out or other caveats.
    pub warnings: Vec<String>,
    /// Largest polar amplitude searched (one pair).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rho_max: Option<f64>,
    /// Its sparse linear algebra with the full system's matrices (also in
    /// the run's `linear_algebra`).
    pub linear_algebra: LinearWork,
    /// The most heap its sparse factors held at once (bytes; a run fact,
    /// reported in the run's `memory`, not here).
    #[serde(skip)]
    #[schemars(skip)]
    pub factor_bytes: Option<usize>,
}

/// A bifurcation located on a reduced forced response curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrcBifurcationSummary {
    /// `SN` (fold), `HB` (Hopf), `BP` (branch point), `PD`, `NS`.
    pub kind: String,
    /// Forcing frequency.
    pub omega: f64,
    /// Forcing amplitude of its curve.
    pub epsilon: f64,
    /// Expansion order of its curve.
    pub order: usize,
    /// `|q_j|` there (one number for one master pair).
    pub rho: PerPair<f64>,
    /// Branch it lies on.
    pub branch: usize,
}

/// One reduced forced response curve: an order and a forcing amplitude.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FrcCurveSummary {
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Points written (inside the frequency range).
    pub points: usize,
    /// Branches.
    pub branches: usize,
    /// The error estimate exceeds `[ssm] tolerance`.
    pub untrusted: bool,
    /// Estimated relative error of the response amplitude (null when the
    /// expansion diverged or there is none).
    pub error_estimate: Option<f64>,
    /// One pair: largest polar amplitude on the curve.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rho_peak: Option<f64>,
    /// One pair: eq. (41) at `rho_peak` (null when not computed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub invariance_error_at_peak: Option<Option<f64>>,
    /// One pair: largest eq. (60) residual along the peak's orbit (null when
    /// not computed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub residual_eq60_at_peak: Option<Option<f64>>,
    /// One pair: order of the non-autonomous terms used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonautonomous_order: Option<usize>,
    /// Several pairs: branches switched to at branch points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branch_switches: Option<usize>,
    /// Several pairs: continuation steps over all branches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub continuation_steps: Option<usize>,
}

impl FrcCurveSummary {
    fn new(c: &FrcCurve) -> Self {
        let finite = |e: f64| e.is_finite().then_some(e);
        let mut v = FrcCurveSummary {
            order: c.order,
            epsilon: c.epsilon,
            points: c.points,
            branches: c.branches,
            untrusted: c.untrusted,
            error_estimate: finite(c.error_estimate()),
            rho_peak: None,
            invariance_error_at_peak: None,
            residual_eq60_at_peak: None,
            nonautonomous_order: None,
            branch_switches: None,
            continuation_steps: None,
        };
        match &c.details {
            CurveDetails::OnePair {
                rho_peak,
                invariance_error_at_peak,
                residual_eq60_at_peak,
                nonautonomous_order,
                ..
            } => {
                v.rho_peak = Some(*rho_peak);
                v.invariance_error_at_peak = Some(*invariance_error_at_peak);
                v.residual_eq60_at_peak = Some(*residual_eq60_at_peak);
                v.nonautonomous_order = Some(*nonautonomous_order);
            }
            CurveDetails::Continuation {
                branch_switches,
                continuation_steps,
                ..
            } => {
                v.branch_switches = Some(*branch_switches);
                v.continuation_steps = Some(*continuation_steps);
            }
        }
        v
    }
}

impl FrcSummary {
    /// The summary of `f`.
    pub fn new(f: &ForcedResponse) -> Self {
        let one_pair = f.forcing_on_master.len() == 1;
        let forcing: Vec<Complex> = f.forcing_on_master.iter().map(|&z| z.into()).collect();
        FrcSummary {
            bifurcations: f
                .curves
                .iter()
                .flat_map(|c| {
                    c.bifurcations.iter().map(move |b| FrcBifurcationSummary {
                        kind: b.kind.to_owned(),
                        omega: b.omega,
                        epsilon: c.epsilon,
                        order: c.order,
                        rho: PerPair::of(&b.rho, one_pair),
                        branch: b.branch,
                    })
                })
                .collect(),
            points: f.rows.len(),
            curves: f.curves.iter().map(FrcCurveSummary::new).collect(),
            resonance: f.resonance.clone(),
            forcing_on_master: PerPair::of(&forcing, one_pair),
            warnings: f.warnings.clone(),
            rho_max: f.rho_max,
            linear_algebra: LinearWork::of(f.linear),
            factor_bytes: f.factor_bytes,
        }
    }
}
