//! The sampled runs: starts, the integrations in parallel, the noise.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::SimulateError;
use ssm_core::fom::{add_noise, sample_run, Integrator, RadauOptions, Simulation};
use ssm_core::model::system::{OutputMap, System};
use ssm_core::rom::autonomous::polar_point;
use ssm_core::spec::{SimulateSpec, ValidationStart};
use ssm_core::ssm::SsmExpansion;

/// Runs the sampled runs `sec` on the full system (their outputs and sizes
/// checked by [`crate::plan::Plan::check`]); starts on the SSM use `ssm` at
/// its order.
pub(super) fn simulate(
    sec: &SimulateSpec,
    sys: &System,
    ssm: &SsmExpansion,
    coordinates: &[&OutputMap],
) -> Result<Simulation, SimulateError> {
    let outputs = super::super::outputs_named(
        sys,
        sec.outputs.as_deref(),
        coordinates,
        SimulateError::Output,
    )?;
    let samples = sec.samples;
    let (rtol, atol) = (sec.rtol, sec.atol);
    let integrator = match sec.hht_alpha {
        Some(alpha) => Integrator::Hht { alpha, rtol, atol },
        None => Integrator::Radau(RadauOptions {
            rtol,
            atol,
            ..RadauOptions::default()
        }),
    };
    let period = sec.period;
    let mut starts = Vec::with_capacity(sec.runs.len());
    for run in &sec.runs {
        starts.push(match run {
            ValidationStart::Ssm { rho0, theta0 } => {
                let theta0 = theta0.clone().unwrap_or_else(|| vec![0.0; rho0.len()]);
                let p0 = polar_point(rho0, &theta0);
                let w = ssm.w_at(&ssm.set.monomials(&p0, ssm.order), ssm.order);
                (w.iter().map(|c| c.re).collect::<Vec<f64>>(), Vec::new())
            }
            ValidationStart::Given { values } => sys.given_state(values),
        });
    }
    // the runs are independent: integrated in parallel (the first failed run
    // is reported, as in sequence), the noise drawn afterwards in run order
    // so that a seed gives the same files anyway
    // (the caller's cancellation flag goes along to the threads that run them)
    let flag = ssm_kernel::cancel::current();
    let results: Vec<_> = starts
        .par_iter()
        .map(|(z0, keep)| {
            ssm_kernel::cancel::within(flag.as_ref(), || {
                sample_run(sys, z0, keep, period, samples, &outputs, integrator)
            })
        })
        .collect();
    let mut runs = Vec::with_capacity(results.len());
    for (k, r) in results.into_iter().enumerate() {
        runs.push(r.map_err(|source| SimulateError::Run { run: k + 1, source })?);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(sec.seed);
    let noise = sec.noise;
    let noise_sigma = runs
        .iter_mut()
        .map(|r| {
            r.values
                .iter_mut()
                .map(|v| add_noise(v, noise, &mut rng))
                .collect()
        })
        .collect();
    Ok(Simulation {
        outputs: outputs.iter().map(|o| o.name.clone()).collect(),
        runs,
        noise,
        seed: sec.seed,
        noise_sigma,
    })
}
