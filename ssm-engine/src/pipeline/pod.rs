//! The `[pod]` stage: the training run, the POD models of each truncation,
//! the SSM models of `ssm_pairs`, and every model run on every load
//! ([`ssm_core::compare::pod`]).

use std::time::Instant;

use toml::Spanned;

use super::checks::named_outputs;
use super::error::JobError;
use super::spectral::spectral;
use super::Progress;
use crate::scene::{load_sampling, PodRun, PodSection, SceneFile};
use ssm_core::compare::pod::SsmRom;
use ssm_core::compare::pod::{
    full_run, pod_case_run, pod_roms, CaseRun, LoadCase, PodStudy, StudySettings,
};
use ssm_core::compare::ssm_run::ssm_case_run;
use ssm_core::model::system::{OutputMap, System};
use ssm_core::reduce::pod::Truncation;
use ssm_core::ssm::{self, SsmOptions};

/// The outputs `[pod]` compares (its `outputs`, else `[outputs]
/// coordinates`), each checked to exist.
fn pod_outputs<'a>(
    scene: &SceneFile,
    sys: &'a System,
    sec: &PodSection,
) -> Result<Vec<&'a OutputMap>, JobError> {
    let (names, key) = match &sec.outputs {
        Some(o) => (o, "pod.outputs"),
        None => (&scene.scene.outputs.coordinates, "outputs.coordinates"),
    };
    if names.get_ref().is_empty() {
        return Err(scene
            .invalid(
                sec.step.span(),
                "pod.outputs",
                "name the outputs to compare: [pod] outputs or [outputs] coordinates".into(),
            )
            .into());
    }
    named_outputs(scene, sys, names, key)
}

/// The load case of a `[pod]` run, its start states checked to exist.
fn load_case(
    scene: &SceneFile,
    sys: &System,
    run: &PodRun,
    label: String,
    span: std::ops::Range<usize>,
    trained: bool,
) -> Result<LoadCase, JobError> {
    let start = run.given_start();
    if let Some((name, _)) = start
        .iter()
        .find(|(n, _)| !sys.states.iter().any(|s| s.name.as_str() == n))
    {
        return Err(scene
            .invalid(
                span,
                &format!("pod.{}", label.replace(' ', "")),
                format!("model '{}' has no state '{name}'", sys.name),
            )
            .into());
    }
    Ok(LoadCase {
        label,
        epsilon: run.epsilon,
        omega: *run.omega.get_ref(),
        t_end: run.t_end,
        start,
        trained,
    })
}

/// The truncations of `sec`, labelled.
fn truncations(sec: &PodSection) -> Vec<(String, Truncation)> {
    if let Some(e) = &sec.energy {
        return e
            .get_ref()
            .iter()
            .map(|&fraction| {
                (
                    format!("pod energy {fraction:e}"),
                    Truncation::Energy { fraction },
                )
            })
            .collect();
    }
    sec.drop
        .as_ref()
        .map_or_else(|| vec![6.0], |d| d.get_ref().clone())
        .into_iter()
        .map(|decades| (format!("pod drop {decades}"), Truncation::Drop { decades }))
        .collect()
}

/// The SSM models of `ssm_pairs`: for each set, the spectral stage with
/// those master pairs and the SSM to the study's order.
fn ssm_roms(scene: &SceneFile, sys: &System, sec: &PodSection) -> Result<Vec<SsmRom>, JobError> {
    let Some(sets) = &sec.ssm_pairs else {
        return Ok(Vec::new());
    };
    let order = sec.ssm_order(scene.scene.ssm.order.as_ref().map(|o| *o.get_ref()));
    sets.get_ref()
        .iter()
        .map(|pairs| {
            let t = Instant::now();
            let mut with_pairs = scene.clone();
            with_pairs.scene.ssm.master_pairs = Spanned::new(sets.span(), pairs.clone());
            let sp = spectral(&with_pairs, sys, order)?;
            let others = ssm::non_master(&sp.spectrum.eigenvalues, &sp.masters);
            let options = SsmOptions {
                order,
                resonance_tol: *scene.scene.ssm.resonance_tol.get_ref(),
            };
            let expansion = ssm::compute(sys, &sp.masters, &others, &options)?;
            Ok(SsmRom {
                label: format!(
                    "ssm pairs {} O({order})",
                    pairs
                        .iter()
                        .map(usize::to_string)
                        .collect::<Vec<_>>()
                        .join("+")
                ),
                pairs: pairs.clone(),
                masters: sp.masters,
                expansion,
                offline_s: t.elapsed().as_secs_f64(),
            })
        })
        .collect()
}

/// Runs the `[pod]` study of `scene` on the full plugin model `full_model`
/// (validated into `sys`).
pub fn pod_stage(
    scene: &SceneFile,
    sec: &PodSection,
    full_model: &ssm_api::Model,
    sys: &System,
    progress: &dyn Progress,
) -> Result<(PodStudy, Vec<String>), JobError> {
    let outputs = pod_outputs(scene, sys, sec)?;
    let settings = StudySettings {
        step: *sec.step.get_ref(),
        alpha: *sec.hht_alpha.get_ref(),
        rank_tol: *sec.rank_tol.get_ref(),
        jacobian_samples: *sec.jacobian_samples.get_ref(),
    };
    let train = load_case(
        scene,
        sys,
        sec.train.get_ref(),
        "train".into(),
        sec.train.span(),
        true,
    )?;
    let mut cases = vec![train];
    for (k, run) in sec.test.get_ref().iter().enumerate() {
        cases.push(load_case(
            scene,
            sys,
            run,
            format!("test {}", k + 1),
            sec.test.span(),
            false,
        )?);
    }
    progress.stage("POD: training run of the full model");
    let training = full_run(sys, &cases[0], &settings, &outputs)?;
    progress.stage("POD: reduced models");
    let pod = pod_roms(
        full_model,
        sys,
        &training.solution,
        &truncations(sec),
        &settings,
    )?;
    if sec.ssm_pairs.is_some() {
        progress.stage("POD: SSM models for comparison");
    }
    let ssm = ssm_roms(scene, sys, sec)?;
    let mut warnings: Vec<String> = cases
        .iter()
        .filter_map(|c| {
            load_sampling(settings.step, c.omega)
                .ok()
                .flatten()
                .map(|w| format!("[pod] {} run: {w}", c.label))
        })
        .collect();
    let mut runs = Vec::with_capacity(cases.len());
    for (k, case) in cases.into_iter().enumerate() {
        progress.stage(&format!("POD: {} (full and reduced runs)", case.label));
        let full = if k == 0 {
            training.clone()
        } else {
            full_run(sys, &case, &settings, &outputs)?
        };
        let mut run = CaseRun::new(case, &full);
        run.pod = pod
            .iter()
            .map(|rom| pod_case_run(rom, sys, &run.case, &full, &settings, &outputs))
            .collect();
        run.ssm = ssm
            .iter()
            .map(|rom| ssm_case_run(rom, sys, &run.case, &full, &outputs))
            .collect();
        let labels = pod
            .iter()
            .map(|r| &r.label)
            .chain(ssm.iter().map(|r| &r.label));
        for (label, r) in labels.zip(run.pod.iter().chain(&run.ssm)) {
            if let Some(f) = &r.failure {
                warnings.push(format!("[pod] {}: {label} failed: {f}", run.case.label));
            }
        }
        runs.push(run);
    }
    Ok((
        PodStudy {
            outputs: outputs.iter().map(|o| o.name.clone()).collect(),
            n_full_states: sys.n_states(),
            settings,
            pod,
            ssm,
            cases: runs,
        },
        warnings,
    ))
}
