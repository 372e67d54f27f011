//! Steady-state forced response by integration until the response repeats
//! over a forcing period, the reference of Fig. 15.
//!
//! After every period `T = 2 pi / Omega` the criterion (47),
//! `|z(iT) - z((i-1)T)| / |z((i-1)T)| < delta`, is checked on the physical
//! states (displacements and velocities; multipliers and auxiliaries are
//! functions of them); with `max_multiple = k > 1` also against `z((i-m)T)`,
//! `m <= k`, the smallest repeating `m` being the period of a subharmonic
//! response. The integrator lands exactly on every `iT`. The
//! amplitude of each output is its largest magnitude over the last period,
//! from the dense output at `samples_per_period` equally spaced times plus the
//! step ends.
//!
//! # References
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), Sect. 5.2.3, eq. (47).

use std::collections::VecDeque;

use ssm_api::StateKind;

use super::{DaeProblem, Radau, RadauOptions, RadauStats, SimError};
use crate::model::system::OutputMap;

/// Settings of a steady-state run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyOptions {
    /// Relative tolerance `delta` of criterion (47).
    pub delta: f64,
    /// Periods integrated at most.
    pub max_periods: usize,
    /// Output samples per period for the amplitudes.
    pub samples_per_period: usize,
    /// Largest multiple `k` of the forcing period accepted as the response's
    /// period (1: criterion (47) as published; 2 and more find subharmonic
    /// responses, such as a frequency divider's).
    pub max_multiple: usize,
    /// Integrator settings.
    pub radau: RadauOptions,
}

impl Default for SteadyOptions {
    fn default() -> Self {
        Self {
            delta: 1e-3,
            max_periods: 2000,
            samples_per_period: 128,
            max_multiple: 1,
            radau: RadauOptions::default(),
        }
    }
}

/// A converged periodic response.
#[derive(Debug, Clone, PartialEq)]
pub struct SteadyState {
    /// Forcing frequency.
    pub omega: f64,
    /// Periods integrated.
    pub periods: usize,
    /// The response's period in forcing periods (1, or more for a
    /// subharmonic response).
    pub multiple: usize,
    /// Final value of criterion (47) (against the state `multiple` periods back).
    pub change: f64,
    /// Largest `|output|` over the last response period, per output.
    pub amplitudes: Vec<f64>,
    /// The state at the end of the last period.
    pub z_end: Vec<f64>,
    /// Integrator work.
    pub stats: RadauStats,
}

/// The physical states compared by criterion (47).
fn physical_states(p: &DaeProblem) -> Vec<usize> {
    p.sys
        .states
        .iter()
        .enumerate()
        .filter(|(_, s)| !matches!(s.kind, StateKind::Multiplier | StateKind::Auxiliary))
        .map(|(i, _)| i)
        .collect()
}

/// Integrates `p` from the consistent state `z0` at `t = 0` until criterion
/// (47) holds, and returns the amplitudes of `outputs` over the last period.
pub fn steady_state(
    p: &DaeProblem,
    z0: &[f64],
    outputs: &[&OutputMap],
    opts: &SteadyOptions,
) -> Result<SteadyState, SimError> {
    if !(p.omega.is_finite() && p.omega > 0.0) {
        return Err(SimError::Settings(format!(
            "forcing frequency must be positive, got {}",
            p.omega
        )));
    }
    if opts.delta.is_nan()
        || opts.delta <= 0.0
        || opts.max_periods == 0
        || opts.samples_per_period < 4
    {
        return Err(SimError::Settings(format!(
            "steady state needs delta > 0, max_periods > 0 and at least 4 samples per period \
             (delta = {}, max_periods = {}, samples = {})",
            opts.delta, opts.max_periods, opts.samples_per_period
        )));
    }
    let period = 2.0 * std::f64::consts::PI / p.omega;
    let phys = physical_states(p);
    let mut radau = Radau::new(
        p,
        0.0,
        z0,
        period * opts.max_periods as f64,
        RadauOptions {
            h_max: opts.radau.h_max.min(period / 8.0),
            ..opts.radau
        },
    )?;
    // period-end states and per-period amplitudes of the last `max_multiple` periods
    let mut ends: VecDeque<Vec<f64>> = VecDeque::from([phys.iter().map(|&i| z0[i]).collect()]);
    let mut period_amps: VecDeque<Vec<f64>> = VecDeque::new();
    let mut zt = vec![0.0; p.n()];
    let mut change = f64::INFINITY;
    let mut first_pass: Option<usize> = None;
    for i in 1..=opts.max_periods {
        let t_end = period * i as f64;
        let t_start = t_end - period;
        let mut amps = vec![0.0f64; outputs.len()];
        let mut k = 1usize;
        while radau.t() < t_end * (1.0 - 1e-15) {
            radau.step(t_end)?;
            let t_now = radau.t();
            while k <= opts.samples_per_period {
                let ts = t_start + period * k as f64 / opts.samples_per_period as f64;
                if ts > t_now {
                    break;
                }
                radau.dense(ts, &mut zt);
                record(&mut amps, outputs, &zt);
                k += 1;
            }
            record(&mut amps, outputs, radau.z());
        }
        let now: Vec<f64> = phys.iter().map(|&j| radau.z()[j]).collect();
        period_amps.push_back(amps);
        if period_amps.len() > opts.max_multiple {
            period_amps.pop_front();
        }
        // criterion (47) against the state one, two, ... periods back: the
        // smallest multiple that repeats is the response's period. A longer
        // period is accepted only after it has held for 2 max_multiple more
        // periods without period T repeating: a decaying free oscillation can
        // repeat better over 2T than over T before both fall below delta.
        let mut pass: Option<(usize, f64)> = None;
        for m in 1..=opts.max_multiple.min(ends.len()) {
            let back = &ends[ends.len() - m];
            let diff = ssm_kernel::continuation::distance(&now, back);
            let base = back.iter().map(|a| a * a).sum::<f64>().sqrt();
            if base == 0.0 {
                continue;
            }
            let c = diff / base;
            if m == 1 {
                change = c;
            }
            if c < opts.delta && period_amps.len() >= m {
                pass = Some((m, c));
                break;
            }
        }
        match pass {
            Some((m, c))
                if m == 1 || first_pass.is_some_and(|f| i >= f + 2 * opts.max_multiple) =>
            {
                let amplitudes = (0..outputs.len())
                    .map(|o| {
                        period_amps
                            .iter()
                            .rev()
                            .take(m)
                            .map(|a| a[o])
                            .fold(0.0, f64::max)
                    })
                    .collect();
                return Ok(SteadyState {
                    omega: p.omega,
                    periods: i,
                    multiple: m,
                    change: c,
                    amplitudes,
                    z_end: radau.z().to_vec(),
                    stats: radau.stats,
                });
            }
            Some(_) => {
                first_pass.get_or_insert(i);
            }
            None => first_pass = None,
        }
        ends.push_back(now);
        if ends.len() > opts.max_multiple {
            ends.pop_front();
        }
    }
    Err(SimError::NotPeriodic {
        omega: p.omega,
        periods: opts.max_periods,
        t: radau.t(),
        change,
        delta: opts.delta,
        max_multiple: opts.max_multiple,
    })
}

fn record(amps: &mut [f64], outputs: &[&OutputMap], z: &[f64]) {
    for (a, o) in amps.iter_mut().zip(outputs) {
        let y: f64 = o.weights.iter().map(|&(s, w)| w * z[s]).sum();
        *a = a.max(y.abs());
    }
}
