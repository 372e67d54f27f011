//! The run of the `[pod]` study: the training run, the POD models of each
//! truncation, the SSM models of `ssm_pairs`, and every model run on every
//! load ([`ssm_core::compare::pod`]).

use std::time::Instant;

use super::PodError;
use crate::progress::Progress;
use ssm_core::compare::pod::SsmRom;
use ssm_core::compare::pod::{
    full_run, pod_case_run, pod_roms, CaseRun, LoadCase, PodStudy, StudySettings,
};
use ssm_core::compare::ssm_run::ssm_case_run;
use ssm_core::fom::hht::load_sampling;
use ssm_core::model::system::OutputMap;
use ssm_core::model::system::System;
use ssm_core::reduce::hyper::Sample;
use ssm_core::reduce::pod::Truncation;
use ssm_core::spec::SpectrumSpec;
use ssm_core::spec::{PodRunSpec, PodSpec, PodTruncations, SsmSpec};
use ssm_core::ssm::spectral::spectral;
use ssm_core::ssm::{self, SsmOptions};

/// The load case of a POD run.
fn load_case(run: &PodRunSpec, label: String, trained: bool) -> LoadCase {
    LoadCase {
        label,
        epsilon: run.epsilon,
        omega: run.omega,
        t_end: run.t_end,
        start: run.start.clone(),
        steps: run.steps.clone(),
        trained,
    }
}

/// The truncations of `sec`, labelled.
fn truncations(sec: &PodSpec) -> Vec<(String, Truncation)> {
    match &sec.truncations {
        PodTruncations::Energy(e) => e
            .iter()
            .map(|&fraction| {
                (
                    format!("pod energy {fraction:e}"),
                    Truncation::Energy { fraction },
                )
            })
            .collect(),
        PodTruncations::Drop(d) => d
            .iter()
            .map(|&decades| (format!("pod drop {decades}"), Truncation::Drop { decades }))
            .collect(),
    }
}

/// The SSM models of `ssm_pairs`: for each set, the spectral stage with
/// those master pairs (the rest of the SSM's spec `ssm`, the eigensolver's
/// `spectrum`) and the SSM to the study's order.
fn ssm_roms(
    (ssm_spec, spectrum): (&SsmSpec, &SpectrumSpec),
    sys: &System,
    sec: &PodSpec,
) -> Result<Vec<SsmRom>, PodError> {
    let order = sec.ssm_order(ssm_spec.order);
    sec.ssm_pairs
        .iter()
        .map(|pairs| {
            let t = Instant::now();
            let with_pairs = SsmSpec {
                master_pairs: pairs.clone(),
                ..ssm_spec.clone()
            };
            let sp = spectral(&with_pairs, spectrum, sys, order)?;
            let others = ssm::non_master(&sp.spectrum.eigenvalues, &sp.masters);
            let options = SsmOptions {
                order,
                resonance_tol: ssm_spec.resonance_tol,
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

/// Runs the POD study `sec` on the full plugin model `full_model`
/// (validated into `sys`; the runs' states checked by the plan), comparing
/// `outputs`; its SSM models follow `specs` (the SSM's and the
/// eigensolver's specs of the plan).
pub(super) fn pod_stage(
    sec: &PodSpec,
    specs: (&SsmSpec, &SpectrumSpec),
    full_model: &ssm_api::Model,
    sys: &System,
    outputs: &[&OutputMap],
    progress: &dyn Progress,
) -> Result<(PodStudy, Vec<String>), PodError> {
    let settings = StudySettings {
        step: sec.step,
        alpha: sec.hht_alpha,
        rank_tol: sec.rank_tol,
        jacobian_samples: sec.jacobian_samples,
    };
    let mut cases = vec![load_case(&sec.train, "train".into(), true)];
    for (k, run) in sec.tests.iter().enumerate() {
        cases.push(load_case(run, format!("test {}", k + 1), false));
    }
    progress.stage("POD: training run of the full model");
    let training = full_run(sys, &cases[0], &settings, outputs)?;
    progress.stage("POD: reduced models");
    let pod = pod_roms(
        full_model,
        sys,
        &training.solution,
        &truncations(sec),
        &sec.hyper
            .iter()
            .map(|&t| Sample::Tolerance(t))
            .collect::<Vec<_>>(),
        &settings,
    )?;
    if !sec.ssm_pairs.is_empty() {
        progress.stage("POD: SSM models for comparison");
    }
    let ssm = ssm_roms(specs, sys, sec)?;
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
            full_run(sys, &case, &settings, outputs)?
        };
        let mut run = CaseRun::new(case, &full);
        run.pod = pod
            .iter()
            .map(|rom| pod_case_run(rom, sys, &run.case, &full, &settings, outputs))
            .collect();
        run.ssm = ssm
            .iter()
            .map(|rom| ssm_case_run(rom, sys, &run.case, &full, outputs))
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
