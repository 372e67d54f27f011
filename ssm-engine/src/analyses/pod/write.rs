//! Writers of the `[pod]` study: `pod_comparison.csv` and `pod_report.md`
//! (one row per reduced model and load), `pod_case_<k>.csv` (the outputs
//! of every model over time with their errors), `pod_errors.svg` (those
//! errors drawn), `pod_povs.csv` and `pod_povs.svg` (the POV decay),
//! `pod_constraints.csv` and the summary's
//! `pod`. They format a [`PodStudy`] and compute nothing.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use ssm_kernel::number::short;

use crate::plot::{line_plot, stacked_plot, Curve, Panel, PlotError, Scale};
use ssm_core::compare::pod::{CaseRun, PodStudy, RomRun};
use ssm_core::reduce::pod::Truncation;

/// One reduced model as the tables name it.
struct RomInfo<'a> {
    id: String,
    label: &'a str,
    kind: &'static str,
    /// Reduced coordinates (POD: `r`; SSM: `2m`).
    dimension: usize,
    /// States of the reduced model's DAE or ODE.
    states: usize,
    offline_s: f64,
}

fn roms(study: &PodStudy) -> Vec<RomInfo<'_>> {
    let pod = study.pod.iter().enumerate().map(|(k, r)| RomInfo {
        id: format!("pod{}", k + 1),
        label: &r.label,
        kind: "pod",
        dimension: r.reduction.u.ncols(),
        states: r.system.n_states(),
        offline_s: r.offline_s,
    });
    let ssm = study.ssm.iter().enumerate().map(|(k, r)| RomInfo {
        id: format!("ssm{}", k + 1),
        label: &r.label,
        kind: "ssm",
        dimension: r.expansion.dim(),
        states: r.expansion.dim(),
        offline_s: r.offline_s,
    });
    pod.chain(ssm).collect()
}

fn runs(case: &CaseRun) -> impl Iterator<Item = &RomRun> {
    case.pod.iter().chain(&case.ssm)
}

/// A figure, or an empty field where there is none (a failed run).
fn e(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map_or_else(String::new, |x| format!("{x:.6e}"))
}

/// A sample, or an empty field where it is not finite.
fn sample(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.17e}")
    } else {
        String::new()
    }
}

/// `pod_comparison.csv`: one row per reduced model and load case.
pub(crate) fn comparison_csv(study: &PodStudy) -> String {
    let mut s = String::from(
        "id,model,kind,case,trained,epsilon,omega,t_end,dimension,states,offline_s,online_s,full_s,speedup,max_error,late_error,reaction_gap,reaction_gap_subspace,start_distance,failure\n",
    );
    let infos = roms(study);
    for case in &study.cases {
        for (info, run) in infos.iter().zip(runs(case)) {
            let c = &case.case;
            s.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{},{},{},{}\n",
                info.id,
                info.label,
                info.kind,
                c.label,
                if info.kind == "pod" {
                    c.trained.to_string()
                } else {
                    String::new()
                },
                short(c.epsilon),
                short(c.omega),
                short(c.t_end),
                info.dimension,
                info.states,
                info.offline_s,
                run.online_s,
                case.full_s,
                case.full_s / run.online_s.max(1e-12),
                e(run.errors.as_ref().map(|x| x.max)),
                e(run.errors.as_ref().map(|x| x.late)),
                e(run.reactions.map(|r| r.full_space)),
                e(run.reactions.map(|r| r.in_subspace)),
                e(Some(run.start_distance)),
                run.failure
                    .as_deref()
                    .unwrap_or("")
                    .replace([',', '\n', '"'], ";"),
            ));
        }
    }
    s
}

/// `pod_case_<k>.csv` (1-based, the training run is 1): `t`, each output
/// of the full model (`<output>@full`) and of every reduced model
/// (`<output>@<id>`), then every model's error `e(t)` (`error@<id>`).
pub(crate) fn case_csv(study: &PodStudy, case: &CaseRun) -> String {
    let infos = roms(study);
    let mut head = vec!["t".to_owned()];
    for o in &study.outputs {
        head.push(format!("{o}@full"));
    }
    for info in &infos {
        for o in &study.outputs {
            head.push(format!("{o}@{}", info.id));
        }
    }
    for info in &infos {
        head.push(format!("error@{}", info.id));
    }
    let mut s = head.join(",");
    s.push('\n');
    let n_out = study.outputs.len();
    for (j, t) in case.times.iter().enumerate() {
        let mut row = vec![sample(*t)];
        row.extend(case.full_outputs[j].iter().map(|v| sample(*v)));
        for run in runs(case) {
            match run.outputs.get(j) {
                Some(vals) => row.extend(vals.iter().map(|v| sample(*v))),
                None => row.extend(std::iter::repeat_n(String::new(), n_out)),
            }
        }
        for run in runs(case) {
            row.push(e(run.errors.as_ref().map(|x| x.series[j])));
        }
        s.push_str(&row.join(","));
        s.push('\n');
    }
    s
}

/// `pod_povs.csv`: every proper orthogonal value per coordinate kind, with
/// its value relative to the kind's largest and the POD models keeping it.
pub(crate) fn povs_csv(study: &PodStudy) -> String {
    let mut s = String::from("kind,index,pov,relative,kept_by\n");
    let Some(first) = study.pod.first() else {
        return s;
    };
    for (g, kind) in first.reduction.kinds.iter().enumerate() {
        let v = &kind.basis.values;
        let largest = v.first().copied().unwrap_or(0.0);
        for (i, x) in v.iter().enumerate() {
            let kept: Vec<String> = study
                .pod
                .iter()
                .enumerate()
                .filter(|(_, r)| r.reduction.kinds.get(g).is_some_and(|k| i < k.basis.kept()))
                .map(|(k, _)| format!("pod{}", k + 1))
                .collect();
            s.push_str(&format!(
                "{:?},{},{x:.6e},{:.6e},{}\n",
                kind.motion,
                i + 1,
                if largest > 0.0 { x / largest } else { 0.0 },
                kept.join(" ")
            ));
        }
    }
    s
}

/// `pod_povs.svg`: the POV decay of each coordinate kind (relative to its
/// largest), the basis of the truncation.
pub(crate) fn povs_svg(study: &PodStudy) -> Result<String, PlotError> {
    let curves: Vec<Curve> = study
        .pod
        .first()
        .map(|r| {
            r.reduction
                .kinds
                .iter()
                .map(|k| {
                    let largest = k.basis.values.first().copied().unwrap_or(1.0);
                    Curve {
                        label: format!("{:?} ({} kept by {})", k.motion, k.basis.kept(), r.label),
                        points: k
                            .basis
                            .values
                            .iter()
                            .enumerate()
                            .map(|(i, v)| ((i + 1) as f64, v / largest))
                            .collect(),
                        ..Curve::default()
                    }
                })
                .collect()
        })
        .unwrap_or_default();
    line_plot(
        "Proper orthogonal values (velocity snapshots of the training run)",
        "index",
        "POV / largest",
        &curves,
        Scale::LogLog,
    )
}

/// `pod_errors.svg`: every reduced model's output error `e(t)` over each
/// load case (a panel per case, log scale; a failed run's curve ends where it
/// failed, an exact model's zero errors are not drawn). The figures are
/// those of `pod_case_<k>.csv`'s `error@<id>` columns.
pub(crate) fn errors_svg(study: &PodStudy) -> Result<String, PlotError> {
    let infos = roms(study);
    let titles: Vec<String> = study
        .cases
        .iter()
        .map(|c| {
            format!(
                "{}: output error relative to the full model's peak",
                c.case.label
            )
        })
        .collect();
    let curves: Vec<Vec<Curve>> = study
        .cases
        .iter()
        .map(|case| {
            infos
                .iter()
                .zip(runs(case))
                .map(|(info, run)| Curve {
                    label: format!("{} ({})", info.id, info.label),
                    points: run.errors.as_ref().map_or_else(Vec::new, |x| {
                        case.times
                            .iter()
                            .copied()
                            .zip(x.series.iter().copied())
                            .collect()
                    }),
                    ..Curve::default()
                })
                .collect()
        })
        .collect();
    let panels: Vec<Panel<'_>> = titles
        .iter()
        .zip(&curves)
        .map(|(title, curves)| Panel {
            title,
            x_label: "t",
            y_label: "error",
            curves,
            scale: Scale::LogY,
        })
        .collect();
    stacked_plot(&panels, 480)
}

/// `pod_constraints.csv`: the singular values of the stacked projected
/// constraint Jacobian of each POD model, and which combinations it keeps.
pub(crate) fn constraints_csv(study: &PodStudy) -> String {
    let mut s = String::from("id,index,singular_value,relative,kept\n");
    for (k, r) in study.pod.iter().enumerate() {
        let c = &r.reduction.constraints;
        let largest = c.singular_values.first().copied().unwrap_or(0.0);
        for (i, v) in c.singular_values.iter().enumerate() {
            s.push_str(&format!(
                "pod{},{},{v:.6e},{:.6e},{}\n",
                k + 1,
                i + 1,
                if largest > 0.0 { v / largest } else { 0.0 },
                i < c.basis.ncols()
            ));
        }
    }
    s
}

fn fmt_s(x: f64) -> String {
    if x < 1e-3 {
        format!("{:.1} µs", x * 1e6)
    } else if x < 1.0 {
        format!("{:.2} ms", x * 1e3)
    } else {
        format!("{x:.2} s")
    }
}

fn rel(v: Option<f64>) -> String {
    v.map_or_else(|| "failed".into(), |x| format!("{x:.2e}"))
}

/// `pod_report.md`: the comparison a person reads.
pub(crate) fn report_md(model: &str, study: &PodStudy) -> String {
    let infos = roms(study);
    let mut s = format!(
        "# POD and SSM reduced models against the full model: {model} ({} states)\n\n\
         Every run uses HHT (alpha = {}, fixed step {}) for the full and the POD models; \
         the SSM models integrate their reduced dynamics (Dormand-Prince) and lift \
         through W (+ eps X0). Error: the largest deviation of the outputs ({}) over the \
         run, each relative to its full-model peak; late: over the second half. Reaction gap: \
         the largest difference of the reactions C_q^T mu, relative to the full model's peak, in \
         the full coordinates (the removed constraints' reactions are missing) and projected on \
         the POD subspace (U^T C_q^T mu: what the reduced equations feel).\n\n",
        study.n_full_states,
        study.settings.alpha,
        study.settings.step,
        study.outputs.join(", ")
    );
    s.push_str("| Model | Coordinates | States | Offline |\n|---|---|---|---|\n");
    for i in &infos {
        s.push_str(&format!(
            "| {} ({}) | {} | {} | {} |\n",
            i.label,
            i.id,
            i.dimension,
            i.states,
            fmt_s(i.offline_s)
        ));
    }
    for (k, r) in study.pod.iter().enumerate() {
        let c = &r.reduction.constraints;
        if c.basis.nrows() > 0 {
            s.push_str(&format!(
                "{}pod{}: of {} constraints the generalized reduction keeps {} combinations \
                 (removes {}); {} vanish on the subspace along the whole run, all that a \
                 reduction along fixed axes (the paper's reference [27]) would remove.\n",
                if k == 0 { "\n" } else { "" },
                k + 1,
                c.basis.nrows(),
                c.basis.ncols(),
                c.removed(),
                r.reduction.vanishing.len()
            ));
        }
    }
    for (k, r) in study.pod.iter().enumerate() {
        if let Some(h) = &r.hyper {
            s.push_str(&format!(
                "pod{}: DEIM hyper-reduction (Chaturantabut & Sorensen 2010) of the {}: \
                 {} of {} force rows sampled{}, training error {:.2e} over {} snapshots, \
                 trained in {}; constraints and reactions lifted exactly.\n",
                k + 1,
                if h.total {
                    "whole internal forces (linear part included: fewer rows than the nonlinear part alone)"
                } else {
                    "nonlinear internal forces"
                },
                h.sampled.len(),
                h.force_rows,
                if h.all_rows { " (all: exact)" } else { "" },
                h.training_error,
                h.snapshots,
                fmt_s(h.seconds)
            ));
        }
    }
    for case in &study.cases {
        let c = &case.case;
        s.push_str(&format!(
            "\n## {}: eps = {}, Omega = {}, {} s{}{}{}\n\nFull model: {} ({} steps).\n\n\
             | Model | Online | Speed-up | Error | Late error | Reaction gap | In the subspace |\n|---|---|---|---|---|---|---|\n",
            c.label,
            short(c.epsilon),
            short(c.omega),
            short(c.t_end),
            if c.start.is_empty() { ", from rest" } else { ", from a given start" },
            load_steps(&c.steps),
            if c.trained { " (POD trained on it)" } else { "" },
            fmt_s(case.full_s),
            case.full_steps,
        ));
        for (i, run) in infos.iter().zip(runs(case)) {
            s.push_str(&format!(
                "| {} | {} | {:.2} | {} | {} | {} | {} |\n",
                i.id,
                fmt_s(run.online_s),
                case.full_s / run.online_s.max(1e-12),
                rel(run.errors.as_ref().map(|x| x.max)),
                rel(run.errors.as_ref().map(|x| x.late)),
                run.reactions
                    .map_or_else(|| "-".into(), |r| format!("{:.2e}", r.full_space)),
                run.reactions
                    .map_or_else(|| "-".into(), |r| format!("{:.2e}", r.in_subspace)),
            ));
        }
    }
    s
}

/// `"pod"` of `summary.json`: the reduced models of the `[pod]` study and
/// their runs against the full system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PodSummary {
    /// The compared outputs.
    pub outputs: Vec<String>,
    /// States of the full model.
    pub n_full_states: usize,
    /// The HHT integrator every model runs with.
    pub hht: HhtSummary,
    /// Relative rank tolerance of the constraint reduction.
    pub rank_tol: f64,
    /// The POD models.
    pub pod_models: Vec<PodModelSummary>,
    /// The SSM models.
    pub ssm_models: Vec<SsmModelSummary>,
    /// The load cases and every model's run.
    pub cases: Vec<PodCaseSummary>,
}

/// The HHT-alpha integrator of the study.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HhtSummary {
    /// Numerical damping `alpha` (in `[-1/3, 0]`).
    pub alpha: f64,
    /// Time step.
    pub step: f64,
}

/// How the POD basis was truncated.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TruncationSummary {
    /// `{"drop_decades": d}`: proper orthogonal values more than `d` decades
    /// below the largest are dropped.
    DropDecades(f64),
    /// `{"energy_left_out": f}`: the fraction `f` of the energy left out.
    EnergyLeftOut(f64),
}

/// The kept POD basis of one kind of motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct KeptSummary {
    /// The kind of motion.
    pub kind: String,
    /// Coordinates of that kind.
    pub coordinates: usize,
    /// POD vectors kept.
    pub kept: usize,
}

/// One POD model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PodModelSummary {
    /// `pod1`, `pod2`, ...
    pub id: String,
    /// Its truncation.
    pub truncation: TruncationSummary,
    /// The basis kept per kind of motion.
    pub kept: Vec<KeptSummary>,
    /// Reduced coordinates.
    pub reduced_coordinates: usize,
    /// Constraints of the full model.
    pub constraints: usize,
    /// Constraints kept by the generalized constraint reduction.
    pub constraints_kept: usize,
    /// Constraints removed.
    pub constraints_removed: usize,
    /// Constraints whose projected Jacobian rows vanish along the training
    /// run: all that the earlier reduction along fixed axes (the paper's
    /// reference \[27\]) would remove.
    pub constraints_vanishing: usize,
    /// Singular values of the projected constraint Jacobians.
    pub singular_values: Vec<f64>,
    /// Residuals of the reduced model's initial state (position, velocity).
    pub initial_residual: [f64; 2],
    /// States of the reduced DAE.
    pub states: usize,
    /// Seconds to build it (its hyper-reduction's training included).
    pub offline_s: f64,
    /// Its hyper-reduction of the internal forces (null: the plain
    /// Galerkin projection).
    pub hyper: Option<HyperSummary>,
}

/// The DEIM hyper-reduction of a POD model's internal forces
/// (Chaturantabut & Sorensen 2010): the full model's force rows evaluated
/// at the sampled rows only, the constraints and reactions exactly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct HyperSummary {
    /// Full rows carrying internal forces (the candidates).
    pub force_rows: usize,
    /// The sampled rows (0-based full coordinates), in DEIM's order.
    pub sampled_rows: Vec<usize>,
    /// Every force row is sampled: the plain projection, exactly.
    pub all_rows: bool,
    /// Relative error of the reduced internal force over the training
    /// snapshots.
    pub training_error: f64,
    /// Force snapshots of the training run used.
    pub snapshots: usize,
    /// Seconds of the training.
    pub training_s: f64,
    /// The sampled rows carry the whole internal force, its linear part
    /// included (chosen where it needs fewer rows than the nonlinear part
    /// alone, as where that part cancels the linear one in absolute nodal
    /// coordinates); otherwise the nonlinear part only.
    pub whole_force: bool,
}

/// One SSM model of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SsmModelSummary {
    /// `ssm1`, `ssm2`, ...
    pub id: String,
    /// Its master pairs.
    pub master_pairs: Vec<usize>,
    /// Expansion order.
    pub order: usize,
    /// Dimension of the SSM.
    pub dimension: usize,
    /// Seconds to compute it.
    pub offline_s: f64,
}

/// One load case: the full run and every model's run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PodCaseSummary {
    /// Its label.
    pub case: String,
    /// The POD models were trained on it.
    pub trained: bool,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Forcing frequency.
    pub omega: f64,
    /// End time.
    pub t_end: f64,
    /// Load steps `[t_k, a_k]`: from `t_k` on the amplitude is `a_k
    /// epsilon`, before the first step zero (empty: `epsilon` throughout).
    pub steps: Vec<(f64, f64)>,
    /// Seconds of the full run.
    pub full_s: f64,
    /// Steps of the full run.
    pub full_steps: usize,
    /// Every model's run (POD models first, then SSM models).
    pub runs: Vec<PodRunSummary>,
}

/// One reduced model's run of a load case (null: the run failed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PodRunSummary {
    /// The model's id.
    pub id: String,
    /// Seconds of the run.
    pub online_s: f64,
    /// The full run's seconds over these.
    pub speedup: f64,
    /// Largest relative output error over the run.
    pub max_error: Option<f64>,
    /// Largest relative output error over the last part of the run.
    pub late_error: Option<f64>,
    /// Relative gap of the constraint reactions to the full run's.
    pub reaction_gap: Option<f64>,
    /// The same gap within the reduced subspace.
    pub reaction_gap_subspace: Option<f64>,
    /// Distance of its start to the full model's start.
    pub start_distance: f64,
    /// Why the run failed.
    pub failure: Option<String>,
}

impl PodSummary {
    /// The summary of `study`.
    pub fn new(study: &PodStudy) -> Self {
        let infos = roms(study);
        PodSummary {
            outputs: study.outputs.clone(),
            n_full_states: study.n_full_states,
            hht: HhtSummary {
                alpha: study.settings.alpha,
                step: study.settings.step,
            },
            rank_tol: study.settings.rank_tol,
            pod_models: study
                .pod
                .iter()
                .enumerate()
                .map(|(k, r)| PodModelSummary {
                    id: format!("pod{}", k + 1),
                    truncation: match r.truncation {
                        Truncation::Drop { decades } => TruncationSummary::DropDecades(decades),
                        Truncation::Energy { fraction } => {
                            TruncationSummary::EnergyLeftOut(fraction)
                        }
                    },
                    kept: r
                        .reduction
                        .kinds
                        .iter()
                        .map(|g| KeptSummary {
                            kind: format!("{:?}", g.motion),
                            coordinates: g.coordinates.len(),
                            kept: g.basis.kept(),
                        })
                        .collect(),
                    reduced_coordinates: r.reduction.u.ncols(),
                    constraints: r.reduction.constraints.basis.nrows(),
                    constraints_kept: r.reduction.constraints.basis.ncols(),
                    constraints_removed: r.reduction.constraints.removed(),
                    constraints_vanishing: r.reduction.vanishing.len(),
                    singular_values: r.reduction.constraints.singular_values.clone(),
                    initial_residual: r.reduction.initial_residual,
                    states: r.system.n_states(),
                    offline_s: r.offline_s,
                    hyper: r.hyper.as_ref().map(|h| HyperSummary {
                        force_rows: h.force_rows,
                        sampled_rows: h.sampled.clone(),
                        all_rows: h.all_rows,
                        training_error: h.training_error,
                        snapshots: h.snapshots,
                        training_s: h.seconds,
                        whole_force: h.total,
                    }),
                })
                .collect(),
            ssm_models: study
                .ssm
                .iter()
                .enumerate()
                .map(|(k, r)| SsmModelSummary {
                    id: format!("ssm{}", k + 1),
                    master_pairs: r.pairs.clone(),
                    order: r.expansion.order,
                    dimension: r.expansion.dim(),
                    offline_s: r.offline_s,
                })
                .collect(),
            cases: study
                .cases
                .iter()
                .map(|c| PodCaseSummary {
                    case: c.case.label.clone(),
                    trained: c.case.trained,
                    epsilon: c.case.epsilon,
                    omega: c.case.omega,
                    t_end: c.case.t_end,
                    steps: c.case.steps.clone(),
                    full_s: c.full_s,
                    full_steps: c.full_steps,
                    runs: infos
                        .iter()
                        .zip(runs(c))
                        .map(|(i, r)| PodRunSummary {
                            id: i.id.clone(),
                            online_s: r.online_s,
                            speedup: c.full_s / r.online_s.max(1e-12),
                            max_error: r.errors.as_ref().map(|x| x.max),
                            late_error: r.errors.as_ref().map(|x| x.late),
                            reaction_gap: r.reactions.map(|g| g.full_space),
                            reaction_gap_subspace: r.reactions.map(|g| g.in_subspace),
                            start_distance: r.start_distance,
                            failure: r.failure.clone(),
                        })
                        .collect(),
                })
                .collect(),
        }
    }
}

/// `, load steps 0 -> 1 eps at t = 0.2, -> 5 eps at t = 1.5` (empty without steps).
fn load_steps(steps: &[(f64, f64)]) -> String {
    if steps.is_empty() {
        return String::new();
    }
    let parts: Vec<String> = steps
        .iter()
        .map(|&(t, a)| format!("{} eps at t = {}", short(a), short(t)))
        .collect();
    format!(", load steps to {}", parts.join(", then "))
}
