//! Running a scene: load the plugin, build and validate the model, compute the
//! spectrum and master modes, check resonances, compute the SSM and what is
//! read off it, assemble the outputs.

use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use toml::Spanned;

use crate::compare::ValidateError;
use crate::model::plugin::{Plugin, PluginLoadError, Registry};
use crate::model::system::{ModelError, OutputMap, System};
use crate::output::{spectrum_csv, OutputError, OutputSet};
use crate::reduce::{self, Reduction, SignalsError};
use crate::results::{self, ResultError};
use crate::results_frc::{self, FrcError};
use crate::results_report::{self, ReportError, ReportInputs};
use crate::results_validate;
use crate::scene::{ModelSection, SceneError, SceneFile, SpectrumMethod};
use crate::spectrum::{self, MasterMode, Method, Spectrum, SpectrumError, SpectrumOptions};
use crate::ssm::{self, Dynamics, SsmError, SsmExpansion, SsmOptions};

/// Anything that stops a run; each variant says where.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The scene is malformed or inconsistent with the model.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A plugin could not be loaded, or returned an error or panicked.
    #[error(transparent)]
    Plugin(#[from] PluginLoadError),
    /// A `[data]` file cannot be used.
    #[error("data: {0}")]
    Signals(#[from] SignalsError),
    /// The plugin's model is inconsistent.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The spectrum could not be computed.
    #[error("spectrum: {0}")]
    Spectrum(#[from] SpectrumError),
    /// Outputs could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The SSM could not be computed.
    #[error("SSM: {0}")]
    Ssm(#[from] SsmError),
    /// A result (backbone, transient, plot) could not be produced.
    #[error(transparent)]
    Result(#[from] ResultError),
    /// The forced response could not be produced.
    #[error(transparent)]
    Frc(#[from] FrcError),
    /// A full-system reference failed.
    #[error("validation: {0}")]
    Validate(#[from] ValidateError),
    /// The speed-against-error report failed.
    #[error(transparent)]
    Report(#[from] ReportError),
}

/// Stages reported to a progress display.
pub trait Progress {
    /// A new stage begins.
    fn stage(&self, name: &str);
}

/// No progress display.
pub struct Quiet;

impl Progress for Quiet {
    fn stage(&self, _name: &str) {}
}

/// Everything a run computed.
#[derive(Debug)]
pub struct JobResult {
    /// The validated system.
    pub system: System,
    /// Finite spectrum.
    pub spectrum: Spectrum,
    /// Master modes.
    pub masters: Vec<MasterMode>,
    /// The SSM.
    pub ssm: SsmExpansion,
    /// Warnings (resonances, ...).
    pub warnings: Vec<String>,
    /// Files to write.
    pub outputs: OutputSet,
}

/// Builds the model of `[model]` with its plugin (as the plugin gives it).
fn build_model(
    scene: &SceneFile,
    m: &ModelSection,
    registry: &mut Registry,
) -> Result<(String, ssm_api::Model), JobError> {
    let plugin = resolve(scene, registry, &m.plugin, "model.plugin")?;
    let name = m.name.as_ref().map_or("", |n| n.get_ref().as_str());
    let params = params_toml(scene, &m.params, "model.params")?;
    let model = plugin
        .build_model(name, &params)
        .map_err(|e| plugin_error(scene, e, "model.params"))?;
    Ok((plugin.name().to_owned(), model))
}

fn resolve(
    scene: &SceneFile,
    registry: &mut Registry,
    name: &Spanned<String>,
    key: &str,
) -> Result<Plugin, JobError> {
    registry.resolve(name.get_ref()).map_err(|e| match e {
        PluginLoadError::NotFound { .. } => {
            JobError::Scene(scene.invalid(name.span(), key, e.to_string()))
        }
        other => JobError::Plugin(other),
    })
}

fn params_toml(
    scene: &SceneFile,
    table: &Spanned<toml::Table>,
    key: &str,
) -> Result<String, JobError> {
    Ok(toml::to_string(table.get_ref()).map_err(|e| {
        scene.invalid(
            table.span(),
            key,
            format!("cannot pass the parameter table to the plugin: {e}"),
        )
    })?)
}

/// A plugin's [`ssm_api::ErrorKind::InvalidParameter`] becomes a scene error
/// at the parameter's line in the `[table]` it came from.
fn plugin_error(scene: &SceneFile, e: PluginLoadError, table: &str) -> JobError {
    match e {
        PluginLoadError::Plugin { plugin, error }
            if error.kind == ssm_api::ErrorKind::InvalidParameter =>
        {
            let line = param_line(&scene.text, table, error.context.as_str());
            JobError::Scene(SceneError::Invalid {
                path: scene.path.clone(),
                line,
                key: format!("{table}.{}", error.context),
                message: format!("plugin '{plugin}': {}", error.message),
            })
        }
        other => JobError::Plugin(other),
    }
}

/// The model the analyses run on: the plugin's model of `[model]`, or the
/// model the reducer of `[reduce]` makes from it and/or the `[data]` signals;
/// validated into a [`System`].
pub fn obtain_model(
    scene: &SceneFile,
    registry: &mut Registry,
) -> Result<(System, Option<Reduction>), JobError> {
    let sc = &scene.scene;
    let full = sc
        .model
        .as_ref()
        .map(|m| build_model(scene, m, registry))
        .transpose()?;
    let Some(red) = &sc.reduce else {
        let (plugin, model) = full.ok_or_else(|| {
            scene.invalid(0..0, "model", "the scene has no [model] section".into())
        })?;
        return Ok((System::from_model(&plugin, model)?, None));
    };
    let plugin = resolve(scene, registry, &red.plugin, "reduce.plugin")?;
    let listed = match plugin.reducers() {
        None => {
            return Err(scene
                .invalid(
                    red.plugin.span(),
                    "reduce.plugin",
                    PluginLoadError::NoReducers {
                        plugin: plugin.name().to_owned(),
                    }
                    .to_string(),
                )
                .into())
        }
        Some(list) => list?,
    };
    let wanted = red.reducer.get_ref();
    let info = listed
        .iter()
        .find(|r| r.name.as_str() == wanted)
        .ok_or_else(|| {
            let names: Vec<&str> = listed.iter().map(|r| r.name.as_str()).collect();
            scene.invalid(
                red.reducer.span(),
                "reduce.reducer",
                format!(
                    "plugin '{}' has no reducer '{wanted}'; it offers: {}",
                    plugin.name(),
                    if names.is_empty() {
                        "none".to_owned()
                    } else {
                        names.join(", ")
                    }
                ),
            )
        })?;
    if info.needs.model() && full.is_none() {
        return Err(scene
            .invalid(
                red.reducer.span(),
                "reduce.reducer",
                format!("reducer '{wanted}' needs a model: add a [model] section"),
            )
            .into());
    }
    if info.needs.signals() && sc.data.is_none() {
        return Err(scene
            .invalid(
                red.reducer.span(),
                "reduce.reducer",
                format!("reducer '{wanted}' needs sampled signals: add a [data] section"),
            )
            .into());
    }
    let signals = sc
        .data
        .as_ref()
        .map(|d| {
            let files: Vec<_> = d
                .files
                .get_ref()
                .iter()
                .map(|f| scene.relative(f))
                .collect();
            reduce::read_signals(&files, d.columns.as_ref().map(|c| c.get_ref().as_slice()))
        })
        .transpose()?;
    let n_trajectories = signals.as_ref().map_or(0, |s| s.trajectories.len());
    let (full_plugin, full_model) = full.unzip();
    let input = ssm_api::ReducerInput {
        model: full_model.into(),
        signals: signals.into(),
    };
    let params = params_toml(scene, &red.params, "reduce.params")?;
    let reduced = plugin
        .reduce(wanted, &params, &input)
        .map_err(|e| plugin_error(scene, e, "reduce.params"))?;
    let mut model = reduced.model;
    let lift = reduced.lift.into_option();
    let lifted_outputs = match (&lift, input.model.as_ref().into_option()) {
        (Some(l), Some(full)) => reduce::lift_outputs(&mut model, full, l),
        _ => Vec::new(),
    };
    let origin = match full_plugin {
        Some(p) => format!("{} via {}", p, plugin.name()),
        None => plugin.name().to_owned(),
    };
    let system = System::from_model(&origin, model)?;
    let reduction = Reduction {
        plugin: plugin.name().to_owned(),
        reducer: wanted.clone(),
        n_input_states: input.model.as_ref().into_option().map(|m| m.n_states()),
        n_trajectories,
        n_reduced_states: system.n_states(),
        lift,
        diagnostics: reduced.diagnostics.into_iter().collect(),
        lifted_outputs,
    };
    Ok((system, Some(reduction)))
}

/// Line of `key = ...` inside the `[table]` (the table header's line when the
/// key is not found there).
fn param_line(text: &str, table: &str, key: &str) -> usize {
    let header_text = format!("[{table}]");
    let mut in_params = false;
    let mut header = 0;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            in_params = t == header_text;
            if in_params {
                header = i + 1;
            }
            continue;
        }
        if in_params {
            if let Some((k, _)) = t.split_once('=') {
                if k.trim().trim_matches('"') == key {
                    return i + 1;
                }
            }
        }
    }
    header
}

/// Runs a scene and assembles its outputs (nothing is written here).
pub fn run(
    scene: &SceneFile,
    registry: &mut Registry,
    progress: &dyn Progress,
) -> Result<JobResult, JobError> {
    let t0 = Instant::now();
    progress.stage("building model");
    let (system, reduction) = obtain_model(scene, registry)?;
    let sc = &scene.scene;
    let mut warnings = Vec::new();
    for name in sc.outputs.coordinates.get_ref() {
        if system.output(name).is_none() {
            let known: Vec<&str> = system
                .outputs
                .iter()
                .map(|o| o.name.as_str())
                .take(40)
                .collect();
            return Err(scene
                .invalid(
                    sc.outputs.coordinates.span(),
                    "outputs.coordinates",
                    format!(
                        "model '{}' has no output '{name}'; it has: {}",
                        system.name,
                        known.join(", ")
                    ),
                )
                .into());
        }
    }
    progress.stage("spectrum");
    let t_spec = Instant::now();
    let pairs = sc.ssm.master_pairs.get_ref();
    let max_pair = pairs.iter().copied().max().unwrap_or(1);
    let opts = SpectrumOptions {
        method: match sc.spectrum.method {
            SpectrumMethod::Auto => None,
            SpectrumMethod::Dense => Some(Method::Dense),
            SpectrumMethod::Sparse => Some(Method::Sparse),
        },
        modes: sc
            .spectrum
            .modes
            .as_ref()
            .map_or(2 * max_pair + 10, |m| *m.get_ref())
            .max(2 * max_pair),
        shift: sc.spectrum.shift.unwrap_or(0.0),
        normalization: sc.ssm.normalization,
    };
    let dynamics = Dynamics::from(system.time);
    let (pencil_a, pencil_b) = system.spectral_pencil();
    let mut spectrum = match spectrum::compute(pencil_a, pencil_b, &opts) {
        // a stiff pencil (e.g. light pendulums on a heavy slider) can defeat the
        // dense path's rank decisions; the sparse path needs only the slow modes
        Err(e @ (SpectrumError::SingularPencil { .. } | SpectrumError::NoConvergence { .. }))
            if opts.method.is_none() =>
        {
            let sparse = SpectrumOptions {
                method: Some(Method::Sparse),
                ..opts.clone()
            };
            let sp = spectrum::compute(pencil_a, pencil_b, &sparse).map_err(|_| e.clone())?;
            warnings.push(format!(
                "dense spectrum failed ({e}); the sparse path was used instead (set [spectrum] method = \"sparse\" to skip the attempt)"
            ));
            sp
        }
        r => r?,
    };
    if let Dynamics::Map { .. } = dynamics {
        spectrum::sort_multipliers(&mut spectrum.eigenvalues);
    }
    let n_original = system.n_states() - system.n_auxiliary();
    let mechanical_layout = system
        .mechanical
        .as_ref()
        .filter(|m| n_original == 2 * m.n_dof + m.n_constraints);
    if let (true, Some(mech)) = (spectrum.complete, mechanical_layout) {
        let expected = 2 * (mech.n_dof - mech.n_constraints.min(mech.n_dof));
        if spectrum.eigenvalues.len() != expected {
            warnings.push(format!(
                "found {} finite eigenvalues where a mechanical system with {} dofs and {} constraints has {expected}: check that M is non-singular and G0 has full rank",
                spectrum.eigenvalues.len(),
                mech.n_dof,
                mech.n_constraints
            ));
        }
    }
    let masters = spectrum::master_modes(&system, &spectrum, pairs, opts.normalization).map_err(
        |e| match e {
            SpectrumError::PairOutOfRange { .. } => JobError::Scene(scene.invalid(
                sc.ssm.master_pairs.span(),
                "ssm.master_pairs",
                e.to_string(),
            )),
            other => JobError::Spectrum(other),
        },
    )?;
    let spectrum_s = t_spec.elapsed().as_secs_f64();
    let master_indices: Vec<usize> = masters.iter().map(|m| m.index).collect();
    let rates = match dynamics {
        Dynamics::Flow => spectrum.eigenvalues.clone(),
        Dynamics::Map { period } => spectrum::multipliers_to_rates(&spectrum.eigenvalues, period),
    };
    let t_res = Instant::now();
    let res = spectrum::check_resonances(
        &rates,
        &master_indices,
        *sc.ssm.order.get_ref(),
        *sc.ssm.resonance_tol.get_ref(),
        spectrum.complete,
    );
    let resonance_s = t_res.elapsed().as_secs_f64();
    warnings.extend(res.warnings.iter().cloned());
    if !spectrum.complete {
        warnings.push(format!(
            "sparse path: {} finite modes nearest sigma = {} were computed; resonance checks and spectral quotients cover only those",
            spectrum.eigenvalues.len(),
            opts.shift
        ));
    }

    progress.stage("SSM");
    let t_ssm = Instant::now();
    let others = ssm::non_master(&spectrum.eigenvalues, &masters);
    let expansion = ssm::compute(
        &system,
        &masters,
        &others,
        &SsmOptions {
            order: *sc.ssm.order.get_ref(),
            resonance_tol: *sc.ssm.resonance_tol.get_ref(),
        },
    )?;
    let ssm_s = t_ssm.elapsed().as_secs_f64();

    progress.stage("backbone, invariance error, transients");
    let t_out = Instant::now();
    let out_maps: Vec<&OutputMap> = sc
        .outputs
        .coordinates
        .get_ref()
        .iter()
        .filter_map(|n| system.output(n))
        .collect();
    let mut outputs = OutputSet::default();
    let invariance = sc
        .outputs
        .invariance_error
        .as_ref()
        .map(|sec| results::invariance_json(&expansion, &system, sec))
        .transpose()?;
    if let Some(sec) = &sc.outputs.backbone {
        let (csv, svg) = results::backbone(&expansion, sec, &out_maps)?;
        outputs.add("backbone.csv", csv);
        outputs.add("backbone.svg", svg);
    }
    let mut rom_steps = None;
    if let Some(sec) = &sc.outputs.transient {
        let (csv, steps) = results::transient(&expansion, sec, &out_maps)?;
        outputs.add("rom_trajectory.csv", csv);
        rom_steps = Some(steps);
    }
    let results_s = t_out.elapsed().as_secs_f64();
    let t_frc = std::time::Instant::now();
    let mut frc_report = None;
    if let Some(sec) = &sc.forcing {
        progress.stage("forced response curves");
        frc_report = Some(results_frc::frc(
            &expansion, &system, &masters, sec, &out_maps,
        )?);
    }
    let frc_s = t_frc.elapsed().as_secs_f64();
    let t_val = Instant::now();
    let mut validation = None;
    if let Some(vsec) = &sc.validate {
        progress.stage("full-system validation");
        if let ssm_api::TimeKind::Map { .. } = system.time {
            let at = scene.text.find("[validate").unwrap_or(0);
            return Err(scene
                .invalid(
                    at..at,
                    "validate",
                    format!(
                        "model '{}' is a map; the full-system integrator needs a flow",
                        system.name
                    ),
                )
                .into());
        }
        if let Some(ss) = &vsec.steady_state {
            if system.forcing.is_empty() {
                return Err(scene
                    .invalid(
                        ss.epsilon.span(),
                        "validate.steady_state",
                        format!(
                            "model '{}' has no forcing Fext to drive a steady state",
                            system.name
                        ),
                    )
                    .into());
            }
        }
        let compared = match &vsec.outputs {
            Some(names) => {
                let mut v = Vec::new();
                for n in names.get_ref() {
                    v.push(system.output(n).ok_or_else(|| {
                        scene.invalid(
                            names.span(),
                            "validate.outputs",
                            format!("model '{}' has no output '{n}'", system.name),
                        )
                    })?);
                }
                v
            }
            None => out_maps.clone(),
        };
        for (table, key, kind) in [
            (&vsec.x0, "validate.x0", ssm_api::StateKind::Displacement),
            (&vsec.v0, "validate.v0", ssm_api::StateKind::Velocity),
        ] {
            let Some(t) = table else { continue };
            for name in t.get_ref().keys() {
                if !system
                    .states
                    .iter()
                    .any(|s| s.name.as_str() == name && s.kind == kind)
                {
                    return Err(scene
                        .invalid(
                            t.span(),
                            key,
                            format!("model '{}' has no {kind:?} state '{name}'", system.name),
                        )
                        .into());
                }
            }
        }
        let vp = results_validate::validation(
            &expansion,
            &system,
            vsec,
            &compared,
            &out_maps,
            &masters,
            frc_report.as_mut(),
        )?;
        for (name, contents) in &vp.files {
            outputs.add(name, contents.clone());
        }
        validation = Some(vp);
    }
    let validation_s = t_val.elapsed().as_secs_f64();
    let frc_summary = frc_report.map(|rep| {
        outputs.add("frc.csv", rep.csv);
        outputs.add("frc.svg", rep.svg);
        rep.summary
    });
    let t_rep = Instant::now();
    let mut report_summary = None;
    if let Some(rsec) = &sc.report {
        progress.stage("speed-against-error report");
        let max = *sc.ssm.order.get_ref();
        let orders = rsec.orders.as_ref().map_or_else(
            || {
                let mut o: Vec<usize> = (1..=max).filter(|k| k % 2 == 1 && *k >= 3).collect();
                if o.last() != Some(&max) {
                    o.push(max);
                }
                o
            },
            |o| o.get_ref().clone(),
        );
        let p0 = validation
            .as_ref()
            .and_then(|v| v.transient.as_ref())
            .map(|t| t.p0.clone());
        let compared: Vec<&OutputMap> = match sc.validate.as_ref().and_then(|v| v.outputs.as_ref())
        {
            Some(names) => names
                .get_ref()
                .iter()
                .filter_map(|n| system.output(n))
                .collect(),
            None => out_maps.clone(),
        };
        let inputs = ReportInputs {
            orders: &orders,
            masters: &masters,
            others: &others,
            resonance_tol: *sc.ssm.resonance_tol.get_ref(),
            outputs: &compared,
            forcing: sc.forcing.as_ref(),
            validation: validation.as_ref(),
            p0,
            rtol: sc.validate.as_ref().map_or(1e-8, |v| *v.rtol.get_ref()),
        };
        let rows = results_report::rows(&system, &inputs)?;
        let full = results_report::full_costs(validation.as_ref());
        outputs.add("report.csv", results_report::csv(&rows, &full));
        outputs.add("report.md", results_report::markdown(&system, &rows, &full));
        outputs.add(
            "report.svg",
            results_report::svg(&rows, &full).map_err(ReportError::from)?,
        );
        report_summary = Some(results_report::json(&rows, &full));
    }
    let report_s = t_rep.elapsed().as_secs_f64();

    progress.stage("writing outputs");
    let n_finite = match (mechanical_layout, spectrum.complete) {
        (_, true) => spectrum.eigenvalues.len(),
        (Some(m), false) => 2 * (m.n_dof - m.n_constraints.min(m.n_dof)),
        _ => spectrum.eigenvalues.len(),
    };
    let pair_index: Vec<(usize, usize)> = masters.iter().map(|m| (m.pair, m.index)).collect();
    outputs.add("spectrum.csv", spectrum_csv(&spectrum, &pair_index));
    let summary = json!({
        "model": {
            "plugin": system.plugin,
            "name": system.name,
            "n_states": system.n_states(),
            "n_finite_modes": n_finite,
        },
        "reduction": reduction.as_ref().map(reduction_json),
        "recast": system.recast.as_ref().map(|r| json!({
            "n_original_states": r.n_original,
            "equilibrium_shifted": r.equilibrium.iter().any(|&v| v != 0.0),
            "auxiliaries": r.auxiliaries.iter().map(|a| json!({
                "name": a.name,
                "definition": a.definition,
                "equation": if a.kind.is_differential() { "differential" } else { "algebraic" },
            })).collect::<Vec<_>>(),
        })),
        "spectrum": spectrum.eigenvalues.iter().map(|l| json!({"re": l.re, "im": l.im})).collect::<Vec<_>>(),
        "spectrum_method": spectrum.method.as_str(),
        "spectrum_complete": spectrum.complete,
        "master_pairs": pairs,
        "master_modes": masters.iter().map(|m| json!({
            "pair": m.pair,
            "lambda": {"re": m.lambda.re, "im": m.lambda.im},
            "residual": m.residual,
        })).collect::<Vec<_>>(),
        "spectral_quotients": {
            "relative": res.quotients.relative,
            "absolute": res.quotients.absolute,
            "complete": res.quotients.complete,
        },
        "ssm": results::ssm_json(&expansion),
        "polar": results::polar_json(&expansion),
        "invariance_error": invariance,
        "rom_steps": rom_steps,
        "frc": frc_summary,
        "validation": validation.as_ref().map(|v| v.summary.clone()),
        "report": report_summary,
        "warnings": warnings,
        "timing_s": {
            "spectrum": spectrum_s,
            "resonance_check": resonance_s,
            "ssm": ssm_s,
            "ssm_composition": expansion.timing.compose_s,
            "ssm_factorization": expansion.timing.linear.factor_s,
            "ssm_solves": expansion.timing.linear.solve_s,
            "results": results_s,
            "frc": frc_s,
            "validation": validation_s,
            "report": report_s,
            "total": t0.elapsed().as_secs_f64(),
        },
        "linear_algebra": {
            "symbolic_factorizations": expansion.timing.linear.symbolic,
            "numeric_factorizations": expansion.timing.linear.factorizations,
            "solves": expansion.timing.linear.solves,
        },
    });
    outputs.add(
        "summary.json",
        serde_json::to_string_pretty(&summary).expect("JSON values are serializable"),
    );
    Ok(JobResult {
        system,
        spectrum,
        masters,
        ssm: expansion,
        warnings,
        outputs,
    })
}

fn reduction_json(r: &Reduction) -> serde_json::Value {
    let diagnostics: serde_json::Map<String, serde_json::Value> = r
        .diagnostics
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

/// Default output directory of a scene: `./out/<scene name>`.
pub fn default_out_dir(scene: &SceneFile) -> PathBuf {
    PathBuf::from("out").join(scene.name())
}
