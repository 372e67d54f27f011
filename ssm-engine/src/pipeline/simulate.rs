//! `[simulate]`: the full model sampled from given starts, with optional
//! additive Gaussian noise, for data-driven reducers.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::JobError;
use crate::scene::{SceneFile, SimulateSection};
use ssm_core::fom::{add_noise, sample_run, Integrator, RadauOptions, Simulation};
use ssm_core::model::system::{OutputMap, System};
use ssm_core::rom::autonomous::polar_point;
use ssm_core::ssm::SsmExpansion;

/// Most sampled values per run (samples times outputs; 40 MB of doubles,
/// some 150 MB of CSV text).
const MAX_VALUES: usize = 5_000_000;

/// Runs `[simulate]` on the full system; starts on the SSM use `ssm` at its order.
pub fn simulate(
    scene: &SceneFile,
    sec: &SimulateSection,
    sys: &System,
    ssm: &SsmExpansion,
    coordinates: &[&OutputMap],
) -> Result<Simulation, JobError> {
    let outputs: Vec<&OutputMap> = match &sec.outputs {
        None => coordinates.to_vec(),
        Some(names) => names
            .get_ref()
            .iter()
            .map(|n| {
                sys.outputs.iter().find(|o| &o.name == n).ok_or_else(|| {
                    let have: Vec<&str> = sys.outputs.iter().map(|o| o.name.as_str()).collect();
                    scene.invalid(
                        names.span(),
                        "simulate.outputs",
                        format!("no output '{n}'; the model has: {}", have.join(", ")),
                    )
                })
            })
            .collect::<Result<_, _>>()?,
    };
    if outputs.is_empty() {
        return Err(scene
            .invalid(
                sec.run.span(),
                "simulate.outputs",
                "no output to sample: name them here or in [outputs] coordinates".into(),
            )
            .into());
    }
    let samples = *sec.samples.get_ref();
    if samples.saturating_mul(outputs.len()) > MAX_VALUES {
        return Err(scene
            .invalid(
                sec.samples.span(),
                "simulate.samples",
                format!(
                    "{samples} samples of {} outputs per run exceed {MAX_VALUES} values: sample fewer points or outputs",
                    outputs.len()
                ),
            )
            .into());
    }
    let (rtol, atol) = (*sec.rtol.get_ref(), *sec.atol.get_ref());
    let integrator = match &sec.hht_alpha {
        Some(alpha) => Integrator::Hht {
            alpha: *alpha.get_ref(),
            rtol,
            atol,
        },
        None => Integrator::Radau(RadauOptions {
            rtol,
            atol,
            ..RadauOptions::default()
        }),
    };
    let period = *sec.period.get_ref();
    let mut starts = Vec::with_capacity(sec.run.get_ref().len());
    for (k, run) in sec.run.get_ref().iter().enumerate() {
        starts.push(match &run.rho0 {
            Some(rho0) => {
                let theta0 = run.theta0.clone().unwrap_or_else(|| vec![0.0; rho0.len()]);
                let p0 = polar_point(rho0, &theta0);
                let w = ssm.w_at(&ssm.set.monomials(&p0, ssm.order), ssm.order);
                (w.iter().map(|c| c.re).collect::<Vec<f64>>(), Vec::new())
            }
            None => {
                for (table, part) in [(&run.x0, "x0"), (&run.v0, "v0")] {
                    if let Some(t) = table {
                        let key = format!("simulate.run[{}].{part}", k + 1);
                        super::checks::given_names(scene, sys, t, sec.run.span(), &key)?;
                    }
                }
                sys.given_state(&run.given_start())
            }
        });
    }
    // the runs are independent: integrated in parallel (the first failed run
    // is reported, as in sequence), the noise drawn afterwards in run order
    // so that a seed gives the same files anyway
    let results: Vec<_> = starts
        .par_iter()
        .map(|(z0, keep)| sample_run(sys, z0, keep, period, samples, &outputs, integrator))
        .collect();
    let mut runs = Vec::with_capacity(results.len());
    for (k, r) in results.into_iter().enumerate() {
        runs.push(r.map_err(|source| JobError::Simulate { run: k + 1, source })?);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(*sec.seed.get_ref());
    let noise = *sec.noise.get_ref();
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
        seed: *sec.seed.get_ref(),
        noise_sigma,
    })
}
