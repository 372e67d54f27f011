//! Writers of `[reference]`: `reference_frc.csv`, the reference curves drawn
//! on `frc.svg` (or `reference_frc.svg` without `[forcing]`), the amplitude
//! responses' `reference_amplitude.csv`/`.svg`, and the summary's
//! `reference`. They format a [`ReferenceFrc`] and compute nothing.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::json::Complex;
use crate::plot::{line_plot, Curve, PlotError, Scale};
use ssm_core::fom::periodic::frc::{ReferenceBranch, ReferenceFrc, ReferenceOrbit};
use ssm_kernel::continuation::Stop;

/// `reference_frc.csv`: `omega,epsilon,stable,branch,period_multiple,
/// <out>_linf...,max_multiplier,tail`, one row per orbit (`stable` and
/// `max_multiplier` empty where the multipliers were not computed).
pub(crate) fn reference_csv(r: &ReferenceFrc) -> String {
    orbits_csv(&r.outputs, &r.branches)
}

/// `reference_amplitude.csv`: the amplitude responses, with the columns of
/// [`reference_csv`] (`branch` numbers the frequencies of `amplitude_at`).
pub(crate) fn amplitude_csv(r: &ReferenceFrc) -> String {
    orbits_csv(&r.outputs, &r.amplitude)
}

fn orbits_csv(outputs: &[String], branches: &[ReferenceBranch]) -> String {
    let mut csv = orbit_header(outputs);
    for o in branches.iter().flat_map(|b| &b.orbits) {
        csv.push_str(&orbit_row(o));
    }
    csv
}

/// The header line of `reference_csv` for the output names `outputs`.
pub fn orbit_header(outputs: &[String]) -> String {
    let mut csv = String::from("omega,epsilon,stable,branch,period_multiple");
    for o in outputs {
        csv.push_str(&format!(",{o}_linf"));
    }
    csv.push_str(",max_multiplier,tail\n");
    csv
}

/// One line of `reference_csv`.
pub fn orbit_row(o: &ReferenceOrbit) -> String {
    let mut row = format!(
        "{:.12e},{:e},{},{},{}",
        o.omega,
        o.epsilon,
        o.stable.map_or(String::new(), |s| u8::from(s).to_string()),
        o.branch,
        o.period_multiple
    );
    for v in &o.linf {
        row.push_str(&format!(",{v:.12e}"));
    }
    row.push_str(&format!(
        ",{},{:.3e}\n",
        o.max_multiplier
            .map_or(String::new(), |m| format!("{m:.10e}")),
        o.tail
    ));
    row
}

/// The reference curves to draw: per branch one segment per run of equal
/// stability (dashed when unstable), and its bifurcations as markers; the
/// first output's amplitude (nothing when the scene names no output).
pub(crate) fn reference_curves(r: &ReferenceFrc) -> Vec<Curve> {
    let label = |o: &ReferenceOrbit| {
        format!(
            "full system (harmonic balance, H = {}), eps = {}",
            r.harmonics,
            ssm_kernel::number::short(o.epsilon)
        )
    };
    curves(r, &r.branches, |o| o.omega, label)
}

/// The curves of `branches` over `x` (the frequency, or the forcing
/// amplitude), each labelled once by `label` of its first orbit.
fn curves(
    r: &ReferenceFrc,
    branches: &[ReferenceBranch],
    x: impl Fn(&ReferenceOrbit) -> f64,
    label: impl Fn(&ReferenceOrbit) -> String,
) -> Vec<Curve> {
    let mut drawn = Vec::new();
    if r.outputs.is_empty() {
        return drawn;
    }
    let y = |o: &ReferenceOrbit| (x(o), o.linf[0]);
    for b in branches {
        let mut labelled = false;
        let mut k = 0;
        let orbits = &b.orbits;
        while k < orbits.len() {
            let st = orbits[k].stable;
            let mut seg = Vec::new();
            if k > 0 {
                seg.push(y(&orbits[k - 1]));
            }
            while k < orbits.len() && orbits[k].stable == st {
                seg.push(y(&orbits[k]));
                k += 1;
            }
            drawn.push(Curve {
                label: if labelled {
                    String::new()
                } else {
                    label(&orbits[0])
                },
                points: seg,
                dashed: st == Some(false),
                markers: Vec::new(),
                color: None,
                full: false,
            });
            labelled = true;
        }
        drawn.push(Curve {
            markers: b.events.iter().map(|e| y(&e.orbit)).collect(),
            ..Curve::default()
        });
    }
    drawn
}

/// `reference_frc.svg`: the reference alone (a scene without `[forcing]`).
pub(crate) fn reference_svg(r: &ReferenceFrc) -> Result<String, PlotError> {
    let y_label = r
        .outputs
        .first()
        .map_or("amplitude".to_owned(), |o| format!("max |{o}|"));
    line_plot(
        "full-system forced response (dashed: unstable, circles: bifurcations)",
        "Omega",
        &y_label,
        &reference_curves(r),
        Scale::Linear,
    )
}

/// `reference_amplitude.svg`: the amplitude responses over `eps`.
pub(crate) fn amplitude_svg(r: &ReferenceFrc) -> Result<String, PlotError> {
    let y_label = r
        .outputs
        .first()
        .map_or("amplitude".to_owned(), |o| format!("max |{o}|"));
    let label = |o: &ReferenceOrbit| {
        format!(
            "full system (harmonic balance, H = {}), Omega = {}",
            r.harmonics, o.omega
        )
    };
    line_plot(
        "full-system amplitude response (dashed: unstable, circles: bifurcations)",
        "eps",
        &y_label,
        &curves(r, &r.amplitude, |o| o.epsilon, label),
        Scale::Linear,
    )
}

fn stop_text(s: &Stop) -> String {
    match s {
        Stop::Range => "range".into(),
        Stop::Bound => "bound".into(),
        Stop::Closed => "closed".into(),
        Stop::MaxSteps => "max_steps".into(),
        Stop::StepTooSmall { cause, .. } => format!("step too small: {cause}"),
        Stop::Interrupted => "interrupted".into(),
    }
}

/// What `"reference.method"` of `summary.json` says.
pub(crate) const REFERENCE_METHOD: &str = "harmonic balance (AFT) continued in Omega (and in eps at the frequencies of amplitude_at) by local parametrization; Floquet multipliers by Hill's method up to 1500 Fourier coefficients, above by the monodromy map (Radau IIA on the variational DAE: the whole matrix up to 200 states, the multipliers above 1e-3 by subspace iteration above)";

/// `"reference"` of `summary.json`: the full-system forced responses of
/// `[reference]`; per branch its parameter's fixed value, the orbit count,
/// why it stopped, its costs and bifurcations.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSummary {
    /// How the curves were computed (`REFERENCE_METHOD`).
    pub method: String,
    /// Harmonics of the Fourier series.
    pub harmonics: usize,
    /// Time samples per period (AFT).
    pub samples_per_period: usize,
    /// The outputs whose amplitudes are reported.
    pub outputs: Vec<String>,
    /// The branches continued in `Omega` (each at fixed `epsilon`).
    pub branches: Vec<BranchSummary>,
    /// The branches continued in `epsilon` (each at fixed `Omega`).
    pub amplitude_responses: Vec<BranchSummary>,
    /// Wall time in seconds.
    pub seconds: f64,
}

/// One continued branch of periodic orbits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BranchSummary {
    /// Forcing amplitude (branches continued in `Omega`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
    /// Forcing frequency (branches continued in `epsilon`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub omega: Option<f64>,
    /// Orbits computed.
    pub orbits: usize,
    /// Why the continuation stopped (`range`, `bound`, `closed`,
    /// `max_steps`, `interrupted`, or `step too small: ...`).
    pub stop: String,
    /// LU factorizations.
    pub factorizations: usize,
    /// Fourier coefficients of an orbit.
    pub coefficients: usize,
    /// Largest relative size of the highest harmonics over the orbits.
    pub largest_tail: f64,
    /// Every orbit has its stability.
    pub stability_computed: bool,
    /// The multipliers checked at the most critical orbit by the monodromy
    /// map (null without multipliers).
    pub multiplier_check: Option<MultiplierCheckSummary>,
    /// Bifurcations located on the branch.
    pub bifurcations: Vec<ReferenceBifurcationSummary>,
}

/// The independent check of a branch's Floquet multipliers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum MultiplierCheckSummary {
    /// The check ran.
    Done {
        /// Forcing frequency of the orbit checked.
        omega: f64,
        /// Forcing amplitude of the orbit checked.
        epsilon: f64,
        /// Integration steps of the monodromy map.
        steps: usize,
        /// Largest difference between the two sets of multipliers.
        difference: f64,
        /// Orbits whose stability is uncertain by that difference.
        uncertain_orbits: usize,
    },
    /// It failed.
    Failed {
        /// Why.
        error: String,
    },
}

/// A bifurcation of the full system located on a branch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ReferenceBifurcationSummary {
    /// `SN` (fold), `BP` (branch point), `PD` (period doubling), `NS`
    /// (Neimark-Sacker).
    pub kind: String,
    /// Forcing frequency.
    pub omega: f64,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Branch it lies on.
    pub branch: usize,
    /// Period of the orbit in forcing periods.
    pub period_multiple: usize,
    /// The multiplier that crossed the unit circle (null at a fold or
    /// branch point located by other means).
    pub multiplier: Option<Complex>,
    /// `<output>_linf`: largest `|output|` over the orbit, per output.
    #[serde(flatten)]
    pub linf: BTreeMap<String, f64>,
}

impl ReferenceSummary {
    /// The summary of `r`.
    pub fn new(r: &ReferenceFrc) -> Self {
        ReferenceSummary {
            method: REFERENCE_METHOD.to_owned(),
            harmonics: r.harmonics,
            samples_per_period: r.samples,
            outputs: r.outputs.clone(),
            branches: r
                .branches
                .iter()
                .map(|b| BranchSummary {
                    epsilon: Some(b.orbits.first().map_or(0.0, |o| o.epsilon)),
                    ..BranchSummary::new(r, b)
                })
                .collect(),
            amplitude_responses: r
                .amplitude
                .iter()
                .map(|b| BranchSummary {
                    omega: Some(b.orbits.first().map_or(0.0, |o| o.omega)),
                    ..BranchSummary::new(r, b)
                })
                .collect(),
            seconds: r.seconds,
        }
    }
}

impl BranchSummary {
    fn new(r: &ReferenceFrc, b: &ReferenceBranch) -> Self {
        BranchSummary {
            epsilon: None,
            omega: None,
            orbits: b.orbits.len(),
            stop: stop_text(&b.stop),
            factorizations: b.factorizations,
            coefficients: b.coefficients,
            largest_tail: b.orbits.iter().map(|o| o.tail).fold(0.0, f64::max),
            stability_computed: b.orbits.iter().all(|o| o.stable.is_some()),
            multiplier_check: b.multiplier_check.as_ref().map(|c| match c {
                Ok(c) => MultiplierCheckSummary::Done {
                    omega: c.omega,
                    epsilon: c.epsilon,
                    steps: c.steps,
                    difference: c.difference,
                    uncertain_orbits: c.uncertain_orbits,
                },
                Err(e) => MultiplierCheckSummary::Failed {
                    error: e.to_string(),
                },
            }),
            bifurcations: b
                .events
                .iter()
                .map(|e| ReferenceBifurcationSummary {
                    kind: e.kind.label().to_owned(),
                    omega: e.orbit.omega,
                    epsilon: e.orbit.epsilon,
                    branch: e.orbit.branch,
                    period_multiple: e.orbit.period_multiple,
                    multiplier: e.multiplier.map(Complex::from),
                    linf: r
                        .outputs
                        .iter()
                        .zip(&e.orbit.linf)
                        .map(|(name, &a)| (format!("{name}_linf"), a))
                        .collect(),
                })
                .collect(),
        }
    }
}
