//! `summary.json`: every typed result of a run, formatted; nothing is
//! computed here.

use serde_json::{json, Value};

use super::{frc, pod, reference, report, simulation, ssm, validation};
use ssm_core::compare::pod::PodStudy;
use ssm_core::compare::report::Report;
use ssm_core::compare::validation::Validation;
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::fom::Simulation;
use ssm_core::model::plugin::PluginOrigin;
use ssm_core::model::system::System;
use ssm_core::reduce::Reduction;
use ssm_core::rom::accuracy::Accuracy;
use ssm_core::rom::autonomous::InvarianceEntry;
use ssm_core::rom::forced_response::ForcedResponse;
use ssm_core::spectrum::{MasterMode, SpectralQuotients, Spectrum};
use ssm_core::ssm::analysis::Polar;
use ssm_core::ssm::SsmExpansion;

/// Seconds spent per stage.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Timing {
    /// Spectrum and master modes.
    pub spectrum: f64,
    /// Non-resonance checks (eqs. 53, 57).
    pub resonance_check: f64,
    /// The SSM.
    pub ssm: f64,
    /// Backbone, invariance error, reduced transient.
    pub results: f64,
    /// Forced response curves.
    pub frc: f64,
    /// Full-system references.
    pub validation: f64,
    /// Speed-against-error report.
    pub report: f64,
    /// The `[pod]` study.
    pub pod: f64,
    /// The `[reference]` forced responses.
    pub reference: f64,
    /// The whole run.
    pub total: f64,
}

/// The results a run hands to `summary.json`.
pub struct Summary<'a> {
    /// The model analysed.
    pub system: &'a System,
    /// The plugin libraries that ran (model, reducer).
    pub plugins: &'a [PluginOrigin],
    /// Finite modes of the model (counted, or known from its structure).
    pub n_finite_modes: usize,
    /// The reduction that made the model, if any.
    pub reduction: Option<&'a Reduction>,
    /// The finite spectrum.
    pub spectrum: &'a Spectrum,
    /// Requested master pairs.
    pub master_pairs: &'a [usize],
    /// The master modes.
    pub masters: &'a [MasterMode],
    /// Spectral quotients (eqs. 54, 58).
    pub quotients: &'a SpectralQuotients,
    /// The SSM.
    pub ssm: &'a SsmExpansion,
    /// Polar form of a two-dimensional SSM of a flow.
    pub polar: Option<&'a Polar>,
    /// Invariance-error table.
    pub invariance: Option<&'a [InvarianceEntry]>,
    /// Steps of the reduced transient.
    pub rom_steps: Option<usize>,
    /// Forced response curves.
    pub frc: Option<&'a ForcedResponse>,
    /// Full-system comparisons.
    pub validation: Option<&'a Validation>,
    /// Speed-against-error report.
    pub report: Option<&'a Report>,
    /// Sampled full-system runs of `[simulate]`.
    pub simulation: Option<&'a Simulation>,
    /// The `[pod]` study.
    pub pod: Option<&'a PodStudy>,
    /// The `[reference]` forced responses of the full system.
    pub reference: Option<&'a ReferenceFrc>,
    /// The results of the analyses of `[analysis]`, by name.
    pub analyses: &'a [(&'a str, Value)],
    /// The accuracy target, the order and every answer's estimate.
    pub accuracy: &'a Accuracy,
    /// Warnings of the run.
    pub warnings: &'a [String],
    /// Stage timings.
    pub timing: Timing,
}

/// `summary.json`, pretty-printed.
pub fn summary_json(s: &Summary<'_>) -> String {
    let sys = s.system;
    let t = &s.timing;
    let lin = &s.ssm.timing.linear;
    let mut value = json!({
        "plugins": plugins_json(s.plugins),
        "model": {
            "plugin": sys.plugin,
            "name": sys.name,
            "n_states": sys.n_states(),
            "n_finite_modes": s.n_finite_modes,
        },
        "reduction": s.reduction.map(reduction_json),
        "recast": sys.recast.as_ref().map(|r| json!({
            "n_original_states": r.n_original,
            "equilibrium_shifted": r.equilibrium.iter().any(|&v| v != 0.0),
            "auxiliaries": r.auxiliaries.iter().map(|a| json!({
                "name": a.name,
                "definition": a.definition,
                "equation": if a.kind.is_differential() { "differential" } else { "algebraic" },
            })).collect::<Vec<_>>(),
        })),
        "spectrum": s.spectrum.eigenvalues.iter().map(|l| json!({"re": l.re, "im": l.im})).collect::<Vec<_>>(),
        "spectrum_method": s.spectrum.method.as_str(),
        "spectrum_complete": s.spectrum.complete,
        "master_pairs": s.master_pairs,
        "master_modes": s.masters.iter().map(|m| json!({
            "pair": m.pair,
            "lambda": {"re": m.lambda.re, "im": m.lambda.im},
            "residual": m.residual,
        })).collect::<Vec<_>>(),
        "spectral_quotients": {
            "relative": s.quotients.relative,
            "absolute": s.quotients.absolute,
            "complete": s.quotients.complete,
        },
        "ssm": ssm::ssm_json(s.ssm),
        "polar": s.polar.map(ssm::polar_json),
        "invariance_error": s.invariance.map(ssm::invariance_json),
        "rom_steps": s.rom_steps,
        "frc": s.frc.map(frc::frc_json),
        "validation": s.validation.map(validation::validation_json),
        "report": s.report.map(report::json),
        "simulation": s.simulation.map(simulation::simulation_json),
        "pod": s.pod.map(pod::pod_json),
        "reference": s.reference.map(reference::reference_json),
        "accuracy": accuracy_json(s.accuracy),
        "warnings": s.warnings,
        "timing_s": {
            "spectrum": t.spectrum,
            "resonance_check": t.resonance_check,
            "ssm": t.ssm,
            "ssm_composition": s.ssm.timing.compose_s,
            "ssm_factorization": lin.factor_s,
            "ssm_solves": lin.solve_s,
            "results": t.results,
            "frc": t.frc,
            "validation": t.validation,
            "report": t.report,
            "pod": t.pod,
            "reference": t.reference,
            "total": t.total,
        },
        "linear_algebra": {
            "symbolic_factorizations": lin.symbolic,
            "numeric_factorizations": lin.factorizations,
            "solves": lin.solves,
        },
    });
    if !s.analyses.is_empty() {
        value["analyses"] = s
            .analyses
            .iter()
            .map(|(name, v)| ((*name).to_owned(), v.clone()))
            .collect::<serde_json::Map<_, _>>()
            .into();
    }
    serde_json::to_string_pretty(&value).expect("JSON values are serializable")
}

/// `"accuracy"`: the target, the order (and how it was set), and the error
/// estimate of each answer.
fn accuracy_json(a: &Accuracy) -> Value {
    let finite = |e: Option<f64>| e.filter(|x| x.is_finite());
    json!({
        "tolerance": a.tolerance,
        "order": a.order,
        "order_from": if a.chosen { "tolerance" } else { "scene" },
        "orders_tried": a.tried.iter().map(|(o, e)| json!({
            "order": o,
            "largest_estimate": finite(*e),
        })).collect::<Vec<_>>(),
        "answers": a.answers.iter().map(|x| json!({
            "answer": x.answer,
            "order": x.order,
            "epsilon": x.epsilon,
            "error_estimate": finite(x.estimate),
            "diverged": x.estimate.is_some_and(|e| !e.is_finite()),
            "untrusted": x.untrusted,
            "trusted_up_to_rho": x.trusted_up_to,
        })).collect::<Vec<_>>(),
        "measured": a.measured.iter().map(|m| json!({
            "answer": m.answer,
            "order": m.order,
            "epsilon": m.epsilon,
            "relative_error": m.relative_error,
            "output": m.output,
            "against": m.against,
        })).collect::<Vec<_>>(),
    })
}

/// A reducer's diagnostics as a JSON object: a number, a list, or text each.
pub fn diagnostics_json(list: &[ssm_api::Diagnostic]) -> Value {
    let map: serde_json::Map<String, Value> = list
        .iter()
        .map(|d| {
            let v = match (d.values.len(), d.text.is_empty()) {
                (_, false) if d.values.is_empty() => json!(d.text.as_str()),
                (1, true) => json!(d.values[0]),
                (_, true) => json!(d.values.as_slice()),
                _ => json!({"values": d.values.as_slice(), "text": d.text.as_str()}),
            };
            (d.name.to_string(), v)
        })
        .collect();
    Value::Object(map)
}

fn reduction_json(r: &Reduction) -> Value {
    let diagnostics = diagnostics_json(&r.diagnostics);
    json!({
        "plugin": r.plugin,
        "reducer": r.reducer,
        "n_input_states": r.n_input_states,
        "n_trajectories": r.n_trajectories,
        "n_reduced_states": r.n_reduced_states,
        "lift": r.lift.as_ref().map(|l| json!({
            "n_full_states": l.basis.nrows,
            "n_reduced_states": l.basis.ncols,
            "offset": !l.offset.is_empty(),
        })),
        "lifted_outputs": r.lifted_outputs,
        "diagnostics": diagnostics,
    })
}

/// `summary.json` of a `[pod]` scene that asks for no SSM answer: the
/// model, the plugins, the study, the warnings and the times.
pub fn pod_only_summary_json(
    system: &System,
    plugins: &[PluginOrigin],
    study: Option<&PodStudy>,
    warnings: &[String],
    timing: Timing,
) -> String {
    let value = json!({
        "plugins": plugins_json(plugins),
        "model": {
            "plugin": system.plugin,
            "name": system.name,
            "n_states": system.n_states(),
        },
        "pod": study.map(pod::pod_json),
        "warnings": warnings,
        "timing_s": {"pod": timing.pod, "total": timing.total},
    });
    serde_json::to_string_pretty(&value).expect("JSON values are serializable")
}

/// The plugin libraries that ran, by name, version and file.
fn plugins_json(plugins: &[PluginOrigin]) -> Value {
    plugins
        .iter()
        .map(|p| {
            json!({
                "name": p.name,
                "version": p.version,
                "file": p.file.display().to_string(),
            })
        })
        .collect()
}
