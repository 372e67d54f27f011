//! The run of `[reference]`: one branch per forcing amplitude (and one
//! amplitude response per frequency of `amplitude_at`), with the warnings a
//! user must see (truncation estimate above the accuracy target,
//! multipliers not computed, a branch that stopped short).

use std::time::Instant;

use super::ReferenceRunError;
use crate::progress::Progress;
use ssm_core::compare::seeds::ssm_seeds;
use ssm_core::compare::validation::{frc_error_at, reference_points};
use ssm_core::fom::periodic::frc::{ReferenceBranch, ReferenceFrc};
use ssm_core::fom::periodic::{
    reference_amplitude_resumable, reference_frc_resumable, AmplitudeSettings, ReferenceOrbit,
    ReferenceSettings, Runs,
};
use ssm_core::model::system::{OutputMap, System};
use ssm_core::rom::accuracy::MeasuredError;
use ssm_core::rom::forced_response::ForcedResponse;
use ssm_core::spec::ReferenceSpec;
use ssm_core::ssm::SsmExpansion;
use ssm_kernel::continuation::{NoLedger, Stop};

/// Runs the reference `sec` (its frequency range and start resolved by the
/// plan), with seeds from the reduced model's forced response `reduced`
/// where it starts from the SSM; returns the curves and the warnings.
pub(super) fn reference_stage(
    sec: &ReferenceSpec,
    system: &System,
    coordinates: &[&OutputMap],
    reduced: Option<(&SsmExpansion, &ForcedResponse)>,
    tolerance: f64,
    progress: &dyn Progress,
) -> Result<(ReferenceFrc, Vec<String>), ReferenceRunError> {
    let t = Instant::now();
    let outputs: Vec<OutputMap> = super::super::outputs_named(
        system,
        sec.outputs.as_deref(),
        coordinates,
        ReferenceRunError::Output,
    )?
    .into_iter()
    .cloned()
    .collect();
    let h = sec.harmonics;
    let from_ssm = sec.from_ssm(false);
    let range = sec.omega_range(None).ok_or(ReferenceRunError::NoRange)?;
    let mut warnings = Vec::new();
    let names: Vec<String> = outputs.iter().map(|o| o.name.clone()).collect();
    let ledger = progress.checkpoint().unwrap_or(&NoLedger);
    let mut branches = Vec::new();
    let mut samples = 0;
    for &eps in &sec.epsilon {
        progress.stage(&format!("full-system reference, eps = {eps:e}"));
        let seeds = match reduced.filter(|_| from_ssm) {
            Some((ssm, frc)) => ssm_seeds(ssm, frc, system.n_states(), eps, range, h),
            None => Vec::new(),
        };
        if from_ssm && seeds.is_empty() {
            warnings.push(format!(
                "[reference] eps = {eps}: no forced response of the reduced model at this amplitude to start from; the reference starts from rest only (add eps to [forcing] epsilon)", eps = ssm_kernel::number::short(eps)
            ));
        }
        let settings = ReferenceSettings {
            epsilon: eps,
            omega_range: range,
            harmonics: h,
            step: sec.step,
            tol: sec.tol,
            max_steps: sec.max_steps,
            outputs: outputs.clone(),
            points_at: Vec::new(),
            period_doubling: sec.period_doubling,
            seeds,
            stability: sec.stability,
        };
        let (lo, hi) = range;
        let mut count = 0usize;
        let mut runs = Runs::new(ledger, |o: &ReferenceOrbit| {
            progress.reference_orbit(&names, o);
            count += 1;
            let at = ((o.omega - lo) / (hi - lo) * 100.0).clamp(0.0, 100.0);
            progress.detail(&format!(
                "full-system reference, eps = {eps:e}: orbit {count}, branch {} (period {}T), Omega = {:.5} ({at:.0} % of the range)",
                o.branch, o.period_multiple, o.omega
            ));
            true
        });
        let mut branch = reference_frc_resumable(system, &settings, &mut runs)?;
        samples = branch.samples;
        warnings.extend(branch_warnings(
            &branch,
            &format!(
                "[reference] eps = {eps}",
                eps = ssm_kernel::number::short(eps)
            ),
            ("Omega", range.1 - range.0),
            tolerance,
        ));
        warnings.extend(branch.notes.iter().map(|n| {
            format!(
                "[reference] eps = {eps}: a start from the reduced model was dropped: {n}",
                eps = ssm_kernel::number::short(eps)
            )
        }));
        warnings.extend(branch.failed.iter().map(|f| {
            format!("[reference] eps = {eps}: {f}; the branches traced are written without it")
        }));
        let mut doubled = std::mem::take(&mut branch.doubled);
        let seeded = std::mem::take(&mut branch.seeded);
        let first = branches.len();
        branches.push(branch);
        branches.append(&mut doubled);
        for mut b in seeded {
            let mut doubled = std::mem::take(&mut b.doubled);
            branches.push(b);
            branches.append(&mut doubled);
        }
        for b in &branches[first..] {
            let number = b.orbits.first().map_or(0, |o| o.branch);
            let at = format!(
                "[reference] eps = {eps}, branch {number}",
                eps = ssm_kernel::number::short(eps)
            );
            warnings.extend(b.multiplier_warning(&at));
        }
    }
    let responses = AmplitudeResponses {
        sec,
        system,
        outputs: &outputs,
        names: &names,
        tolerance,
        progress,
    };
    let amplitude = responses.trace(&mut samples, &mut warnings)?;
    Ok((
        ReferenceFrc {
            outputs: names,
            harmonics: h,
            samples,
            branches,
            amplitude,
            seconds: t.elapsed().as_secs_f64(),
        },
        warnings,
    ))
}

/// The amplitude responses of `[reference] amplitude_at`: what they share.
struct AmplitudeResponses<'a> {
    sec: &'a ReferenceSpec,
    system: &'a System,
    outputs: &'a [OutputMap],
    names: &'a [String],
    tolerance: f64,
    progress: &'a dyn Progress,
}

impl AmplitudeResponses<'_> {
    /// One branch over `eps` per frequency of `amplitude_at`, with its
    /// warnings; `samples` is set to the Fourier samples of the last.
    fn trace(
        &self,
        samples: &mut usize,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<ReferenceBranch>, ReferenceRunError> {
        let (sec, system, outputs, names) = (self.sec, self.system, self.outputs, self.names);
        let (tolerance, progress) = (self.tolerance, self.progress);
        let ledger = progress.checkpoint().unwrap_or(&NoLedger);
        let h = sec.harmonics;
        let mut amplitude = Vec::new();
        let eps_range = sec.amplitude_range();
        for (k, &omega) in sec.amplitude_at.iter().enumerate() {
            progress.stage(&format!(
                "full-system amplitude response, Omega = {omega}",
                omega = ssm_kernel::number::short(omega)
            ));
            let settings = AmplitudeSettings {
                omega,
                epsilon_range: eps_range,
                harmonics: h,
                step: sec.step,
                tol: sec.tol,
                max_steps: sec.max_steps,
                outputs: outputs.to_vec(),
                points_at: Vec::new(),
                stability: sec.stability,
            };
            let mut count = 0usize;
            let mut runs = Runs::new(ledger, |o: &ReferenceOrbit| {
                progress.reference_orbit(names, o);
                count += 1;
                progress.detail(&format!(
                    "full-system amplitude response, Omega = {omega}: orbit {count}, eps = {:.4e}",
                    o.epsilon,
                    omega = ssm_kernel::number::short(omega)
                ));
                true
            });
            let branch = reference_amplitude_resumable(system, &settings, k + 1, &mut runs)?;
            *samples = branch.samples;
            let at = format!(
                "[reference] amplitude response at Omega = {omega}",
                omega = ssm_kernel::number::short(omega)
            );
            warnings.extend(branch_warnings(
                &branch,
                &at,
                ("eps", eps_range.1 - eps_range.0),
                tolerance,
            ));
            warnings.extend(branch.notes.iter().map(|n| format!("{at}: {n}")));
            warnings.extend(branch.multiplier_warning(&at));
            amplitude.push(branch);
        }
        Ok(amplitude)
    }
}

/// What a user must know of a traced branch, each warning led by `at`: a
/// truncation estimate above the accuracy target, and a stop before the
/// parameter (`name`, scaled by `scale` in the continuation) left its range.
fn branch_warnings(
    branch: &ReferenceBranch,
    at: &str,
    (name, scale): (&str, f64),
    tolerance: f64,
) -> Vec<String> {
    let mut warnings = Vec::new();
    let tail = branch.orbits.iter().map(|o| o.tail).fold(0.0, f64::max);
    if tail > tolerance {
        warnings.push(format!(
            "{at}: the highest harmonic carries {tail:.2e} of the orbit amplitude, above the accuracy target {tolerance:e}: the reference is truncated; raise harmonics"
        ));
    }
    match &branch.stop {
        Stop::Range => {}
        Stop::StepTooSmall { parameter, cause } => warnings.push(format!(
            "{at}: the continuation stopped at {name} = {:.6e}: {cause}; the curve ends there (lower step, raise harmonics or tol)",
            parameter * scale
        )),
        Stop::MaxSteps => warnings.push(format!(
            "{at}: max_steps reached before {name} left the range; the curve ends there (raise max_steps or step)"
        )),
        other => warnings.push(format!("{at}: the branch ended early ({other:?})")),
    }
    warnings
}

/// Each forced response curve's error against the reference curve of its
/// forcing amplitude: per output both have, the largest amplitude error over
/// the reference's orbits (stable and unstable) relative to the reference's
/// largest amplitude.
pub(super) fn reference_errors(f: &ForcedResponse, r: &ReferenceFrc) -> Vec<MeasuredError> {
    let mut list = Vec::new();
    for c in &f.curves {
        let Some(points) = reference_points(r, c.epsilon) else {
            continue;
        };
        for (k, name) in f.outputs.iter().enumerate() {
            let Some(j) = r.outputs.iter().position(|o| o == name) else {
                continue;
            };
            // the reference's amplitudes of this output at the FRC's index k
            let pts: Vec<(f64, Vec<f64>)> = points
                .iter()
                .map(|(w, a)| {
                    let mut v = vec![f64::NAN; k + 1];
                    v[k] = a[j];
                    (*w, v)
                })
                .collect();
            let (err, _) = frc_error_at(&f.rows, &pts, c.epsilon, c.order, k);
            list.push(MeasuredError {
                answer: "frc",
                order: c.order,
                epsilon: Some(c.epsilon),
                relative_error: err,
                output: Some(name.clone()),
                against: "harmonic_balance",
            });
        }
    }
    list
}
