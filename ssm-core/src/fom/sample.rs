//! Uniformly sampled full-system runs: the data a data-driven reducer (the
//! NAR identifier) is given, made from a known model.
//!
//! A flow is integrated by Radau IIA ([`super::Radau`]) and sampled at
//! `t_k = k T` through its collocation polynomial (dense output), so the
//! step size follows the error control and not the sampling period, or by
//! HHT-alpha ([`super::hht`]) with its Hermite dense output; a map is
//! iterated, one sample per iterate.

use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use ssm_api::TimeKind;

use super::hht::{Hht, HhtOptions};
use super::{consistent_initial_keeping, DaeProblem, Radau, RadauOptions, SimError};
use crate::model::system::{OutputMap, System};
use ssm_kernel::stepper::sample;

/// The sampled runs of `[simulate]`.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// Output names (the CSV columns after `t`).
    pub outputs: Vec<String>,
    /// The runs, noise included.
    pub runs: Vec<SampledRun>,
    /// Noise level (relative to each output's largest value in its run).
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Standard deviation of the noise added, per run and output.
    pub noise_sigma: Vec<Vec<f64>>,
}

/// One sampled run.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledRun {
    /// Sample times `k T`.
    pub times: Vec<f64>,
    /// `values[j][k]`: output `j` at sample `k`.
    pub values: Vec<Vec<f64>>,
    /// Largest change the consistent start made to a displacement.
    pub start_correction: f64,
    /// Integrator steps accepted (iterates for a map).
    pub steps: usize,
}

/// The integrator of a flow's runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Integrator {
    /// Radau IIA (order 5) with these tolerances.
    Radau(RadauOptions),
    /// HHT-alpha at `alpha`, its step controlled at `(rtol, atol)` on the
    /// positions' local error, the sampling period the largest step.
    Hht {
        /// `alpha` in `[-1/3, 0]`.
        alpha: f64,
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance.
        atol: f64,
    },
}

/// Samples `outputs` of the unforced system from `z0` (displacements `keep`
/// held where the constraints allow) at `samples` times `k period`.
pub fn sample_run(
    sys: &System,
    z0: &[f64],
    keep: &[usize],
    period: f64,
    samples: usize,
    outputs: &[&OutputMap],
    integrator: Integrator,
) -> Result<SampledRun, SimError> {
    if !(period.is_finite() && period > 0.0) || samples < 2 {
        return Err(SimError::Settings(format!(
            "sampling period {period} and {samples} samples: the period must be positive and the samples at least 2"
        )));
    }
    let problem = DaeProblem::new(sys, 0.0, 0.0);
    let times: Vec<f64> = (0..samples).map(|k| k as f64 * period).collect();
    let observe = |z: &[f64], values: &mut [Vec<f64>]| {
        for (o, v) in outputs.iter().zip(values.iter_mut()) {
            v.push(o.weights.iter().map(|&(s, w)| w * z[s]).sum());
        }
    };
    let mut values = vec![Vec::with_capacity(samples); outputs.len()];
    match sys.time {
        TimeKind::Map { period: map_period } => {
            if (map_period - period).abs() > 1e-9 * map_period {
                return Err(SimError::Settings(format!(
                    "the model is a map with period {map_period}: sample it with that period, not {period}"
                )));
            }
            let mut z = z0.to_vec();
            let mut next = vec![0.0; z.len()];
            observe(&z, &mut values);
            for &t in &times[1..] {
                problem.autonomous_rhs(&z, &mut next);
                if let Some(i) = next.iter().position(|v| !v.is_finite()) {
                    return Err(SimError::NonFinite {
                        t,
                        state: problem.state_name(i).to_owned(),
                    });
                }
                std::mem::swap(&mut z, &mut next);
                observe(&z, &mut values);
            }
            Ok(SampledRun {
                times,
                values,
                start_correction: 0.0,
                steps: samples - 1,
            })
        }
        TimeKind::Flow => {
            let initial = consistent_initial_keeping(&problem, 0.0, z0, keep)?;
            let t_end = times[samples - 1];
            observe(&initial.z, &mut values);
            let mut zt = |_: f64, z: &[f64]| observe(z, &mut values);
            // one sampling for every integrator: each sample by the dense
            // output of the step that reaches it
            let steps = match integrator {
                Integrator::Radau(opts) => {
                    let mut radau = Radau::new(&problem, 0.0, &initial.z, t_end, opts)?;
                    sample(&mut radau, &times[1..], t_end, &mut zt)?;
                    radau.stats.accepted
                }
                Integrator::Hht { alpha, rtol, atol } => {
                    let o = HhtOptions::adaptive(alpha, period, rtol, atol);
                    let mut hht = Hht::new(&problem, &initial.z, 0.0, &o)?;
                    sample(&mut hht, &times[1..], t_end, &mut zt)?;
                    hht.hht_stats().steps
                }
            };
            Ok(SampledRun {
                times,
                values,
                start_correction: initial.position_correction,
                steps,
            })
        }
    }
}

/// Adds Gaussian noise of standard deviation `level * max |v|` to `v`
/// (a sensor's noise relative to its full scale); returns that deviation.
pub fn add_noise(v: &mut [f64], level: f64, rng: &mut ChaCha8Rng) -> f64 {
    let sigma = level * v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if sigma > 0.0 {
        for x in v.iter_mut() {
            let e: f64 = StandardNormal.sample(rng);
            *x += sigma * e;
        }
    }
    sigma
}
