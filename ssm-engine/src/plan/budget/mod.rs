//! Work and memory of a plan's requests, estimated before any of it starts.
//!
//! Every request whose cost grows with a plan's value (the expansion order,
//! numbers of points and samples, integration times, period counts, the size
//! of a dense pencil) is costed here from the model's size and spectrum. A
//! request that would not finish within [`Limits`] is refused with a
//! [`PlanError`] at its key (a scene's line), naming the estimate, the limit
//! and what to change, instead of hanging, exhausting memory or overflowing
//! an allocation.
//!
//! The estimates count elementary operations from the size of each algorithm
//! (multi-indices, series products, sparse solves, integration steps) and
//! convert them with a rate measured on a 2-core machine (`OPS_PER_SECOND`).
//! They are meant to separate "seconds to minutes" from "days", not to
//! predict run times: a factor of a few either way is expected.

mod runs;

pub(crate) use runs::{check_pod, check_pod_reducer};

use super::{Plan, PlanError};
use ssm_core::model::system::System;
use ssm_core::spec::{ReferenceSpec, SsmSpec, ValidationSpec};
use ssm_core::spectrum::{MasterMode, Method, DENSE_LIMIT};
use ssm_core::ssm::Dynamics;

/// Elementary operations per second assumed by the estimates (complex
/// multiply-adds and sparse-solve entries on one core of a 2-core machine,
/// conservatively rounded down from the SSM and Radau timings of the zoo).
pub(crate) const OPS_PER_SECOND: f64 = 2e8;

/// Integration steps per period assumed for adaptive integrators at the
/// tolerances scenes use (the Radau IIA runs of the zoo take 40-60, DOPRI5
/// on the reduced model 20-40).
const STEPS_PER_PERIOD: f64 = 60.0;

/// Environment variable that raises (or lowers) the time limit, in minutes.
pub(crate) const TIME_LIMIT_VAR: &str = "SSM_TIME_LIMIT_MINUTES";

/// What one run may use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Estimated seconds of work.
    pub seconds: f64,
    /// Bytes of memory.
    pub bytes: f64,
    /// The limit that sets `bytes` (see [`ssm_api::limits::MemoryRoom`]).
    pub memory_source: &'static str,
}

impl Limits {
    /// One hour (or `SSM_TIME_LIMIT_MINUTES`), and three quarters of the
    /// memory this process may still allocate: the smallest of the machine's
    /// available memory, the address space left under `ulimit -v` and the
    /// room under the cgroup's memory limit
    /// ([`ssm_api::limits::memory_room`]).
    pub fn of_machine() -> Self {
        let minutes = std::env::var(TIME_LIMIT_VAR)
            .ok()
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|m| m.is_finite() && *m > 0.0)
            .unwrap_or(60.0);
        let room = ssm_api::limits::memory_room();
        Self {
            seconds: minutes * 60.0,
            bytes: 0.75 * room.bytes,
            memory_source: room.source,
        }
    }
}

/// Periods of the fastest master mode per unit time for a flow, steps per
/// unit time for a map of period `T`.
fn periods_per_time(dynamics: Dynamics, masters: &[MasterMode]) -> f64 {
    match dynamics {
        Dynamics::Map { period } => 1.0 / period.max(f64::MIN_POSITIVE),
        Dynamics::Flow => {
            let omega = masters
                .iter()
                .map(|m| m.lambda.norm())
                .fold(0.0, f64::max)
                .max(f64::MIN_POSITIVE);
            omega / (2.0 * std::f64::consts::PI)
        }
    }
}

/// The work of each analysis of `[analysis]` on an SSM of the masters'
/// pairs to `order` within `limits`; a refusal names the key that sets the
/// size.
pub(crate) fn check_analyses(
    plan: &Plan,
    system: &System,
    masters: &[MasterMode],
    order: usize,
    limits: &Limits,
) -> Result<(), PlanError> {
    let model = Sizes::of(system);
    let dynamics = Dynamics::from(system.time);
    let sizes = crate::analyses::Sizes {
        multi_indices: multi_indices(2 * masters.len().max(1), order),
        outputs: plan.coordinates.len(),
        pairs: masters.len().max(1),
        states: model.states,
        factors: model.factors,
        dynamics,
        periods_per_time: periods_per_time(dynamics, masters),
        steps_per_period: STEPS_PER_PERIOD,
        implicit_step: runs::RADAU_STEP * model.sparse_solve(),
        masters,
        fixed_order: plan.ssm.order,
    };
    for a in plan.requested() {
        let entry = crate::analyses::find(&a.name)
            .map_err(|e| PlanError::new(&format!("analysis.{}", a.name), e.to_string()))?;
        let work = entry
            .work(&a.spec, &sizes)
            .map_err(|e| PlanError::new(&entry.table(), e.to_string()))?;
        let cost = Cost {
            ops: work.ops,
            bytes: work.bytes,
        };
        ensure(work.key, work.what, &cost, limits, work.advice)?;
    }
    Ok(())
}

/// The cost of one request.
struct Cost {
    ops: f64,
    bytes: f64,
}

/// `C(n + k, k)` in floating point (no overflow for any scene value), as
/// `C(n + k, min(n, k))`: `min(n, k)` factors, so a scene's `order = 2^63`
/// costs as little as its number of variables.
fn binomial(n: usize, k: usize) -> f64 {
    let m = n.min(k);
    let top = n as f64 + k as f64;
    (1..=m).fold(1.0, |acc, i| acc * (top - (m - i) as f64) / i as f64)
}

/// Multi-indices of degree `0..=order` in `nvar` variables.
fn multi_indices(nvar: usize, order: usize) -> f64 {
    binomial(nvar, order)
}

/// Sizes of the model the costs depend on.
struct Sizes {
    states: f64,
    /// Entries of `A` and `B`.
    nnz: f64,
    /// Factors of all monomials of `F` (a bound on the composition's nodes).
    factors: f64,
}

impl Sizes {
    fn of(system: &System) -> Self {
        let factors: u64 = system
            .nonlinearity
            .terms
            .iter()
            .map(|t| t.factors.iter().map(|f| u64::from(f.power)).sum::<u64>())
            .sum();
        Self {
            states: system.n_states() as f64,
            nnz: (system.a.compute_nnz() + system.b.compute_nnz()) as f64,
            factors: factors as f64,
        }
    }

    /// One sparse factorization and solve of the pencil's size.
    fn sparse_solve(&self) -> f64 {
        50.0 * (self.nnz + self.states)
    }
}

/// `Ok` when `cost` is within `limits`, else the refusal of the request of
/// `key`.
fn ensure(
    key: &str,
    what: String,
    cost: &Cost,
    limits: &Limits,
    advice: &str,
) -> Result<(), PlanError> {
    if within(cost, limits) {
        return Ok(());
    }
    let secs = cost.ops / OPS_PER_SECOND;
    Err(PlanError::new(
            key,
            format!(
                "{what} needs about {} and {} of memory; this run allows {} ({TIME_LIMIT_VAR}) and {} (3/4 of the {}): {advice}",
                duration(secs),
                bytes(cost.bytes),
                duration(limits.seconds),
                bytes(limits.bytes),
                limits.memory_source,
            ),
        ))
}

fn duration(s: f64) -> String {
    if s < 1.0 {
        format!("{s:.1e} s")
    } else if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else if s < 172_800.0 {
        format!("{:.0} h", s / 3600.0)
    } else {
        format!("{:.1e} days", s / 86_400.0)
    }
}

fn bytes(b: f64) -> String {
    if b < 1e9 {
        format!("{:.1} MB", b / 1e6)
    } else if b < 1e12 {
        format!("{:.1} GB", b / 1e9)
    } else {
        format!("{:.1e} GB", b / 1e9)
    }
}

fn within(cost: &Cost, limits: &Limits) -> bool {
    cost.ops / OPS_PER_SECOND <= limits.seconds && cost.bytes <= limits.bytes
}

/// Before the spectral stage: the dense spectrum (a QZ iteration on the
/// `N x N` pencil, about `70 N^3` operations on 6 dense complex matrices) and
/// the SSM order (see [`order_ceiling`]); returns the highest order the run
/// may compute.
pub(crate) fn check_spectrum(
    plan: &Plan,
    system: &System,
    limits: &Limits,
) -> Result<usize, PlanError> {
    let n = system.n_states() as f64;
    let dense = match plan.spectrum.method {
        Some(Method::Dense) => true,
        None => system.n_states() <= DENSE_LIMIT,
        Some(Method::Sparse) => false,
    };
    let cost = Cost {
        ops: 70.0 * n.powi(3),
        bytes: 6.0 * 16.0 * n * n,
    };
    if dense {
        ensure(
            "spectrum.method",
            format!("the dense spectrum of {n} states"),
            &cost,
            limits,
            "use method = \"sparse\" with the modes you need",
        )?;
    }
    let pairs = plan.ssm.master_pairs.len().max(1);
    order_ceiling(plan, system, pairs, limits)
}

/// The highest SSM order of the run, with `pairs` master pairs: the scene's
/// `[ssm] order`, checked against the limits; without one, the highest odd
/// order up to [`SsmSpec::AUTO_MAX_ORDER`] that the limits allow (not below 3 nor
/// the orders the answers name), which the pipeline may then lower. Run
/// before the spectral stage, since the eq. (53) resonance check there
/// enumerates the multi-indices up to this order.
pub(crate) fn order_ceiling(
    plan: &Plan,
    system: &System,
    pairs: usize,
    limits: &Limits,
) -> Result<usize, PlanError> {
    if let Some(o) = plan.ssm.order {
        check_order(plan, system, pairs, o, limits)?;
        return Ok(o);
    }
    let floor = plan.highest_named_order().max(3);
    let top = (floor..=SsmSpec::AUTO_MAX_ORDER.max(floor))
        .rev()
        .filter(|o| o % 2 == 1 || *o == floor)
        .find(|&o| within(&order_cost(plan, system, pairs, o), limits));
    match top {
        Some(o) => Ok(o),
        None => check_order(plan, system, pairs, floor, limits).map(|()| floor),
    }
}

/// The SSM to `order` with `pairs` master pairs, rebuilt by the report.
fn order_cost(plan: &Plan, system: &System, pairs: usize, order: usize) -> Cost {
    let forced = plan.frc.is_some() || plan.validation.is_some();
    let mut ssm = ssm_cost(&Sizes::of(system), pairs, order, forced);
    if let Some(r) = &plan.report {
        // the report rebuilds the SSM at each of its orders (at most `order`;
        // a given list counts with its length)
        ssm.ops *= r.orders.as_ref().map_or(order, Vec::len) as f64;
    }
    ssm
}

/// The SSM order against the limits, with `pairs` master pairs.
fn check_order(
    plan: &Plan,
    system: &System,
    pairs: usize,
    order: usize,
    limits: &Limits,
) -> Result<(), PlanError> {
    let sizes = Sizes::of(system);
    let ssm = order_cost(plan, system, pairs, order);
    ensure(
        "ssm.order",
        format!(
            "an SSM of order {order} with {pairs} master pair(s) of a {}-state model",
            sizes.states
        ),
        &ssm,
        limits,
        if plan.ssm.order.is_some() {
            "lower the order"
        } else {
            "no [ssm] order was given and this is the lowest the answers need: lower the orders they name, or the master pairs"
        },
    )?;
    Ok(())
}

/// The SSM to `order` with `pairs` master pairs: the composition `F(W)`
/// (series products over pairs of multi-indices, eq. 55), one sparse solve
/// per multi-index, and the storage of `W` and of the composition's series;
/// twice that with a forcing (the non-autonomous SSM, eq. 60).
fn ssm_cost(sizes: &Sizes, pairs: usize, order: usize, forced: bool) -> Cost {
    let nvar = 2 * pairs;
    let n_idx = multi_indices(nvar, order);
    let products = binomial(2 * nvar, order);
    let once = Cost {
        ops: 4.0 * sizes.factors * products + 0.5 * n_idx * sizes.sparse_solve(),
        // the series product table holds one 8-byte entry per product (the
        // split pairs of every multi-index, allocated exactly); the index
        // set some 100 + 8 nvar bytes per multi-index (exponents, hash
        // lookup, conjugates, lower neighbours)
        bytes: 16.0 * n_idx * (2.0 * sizes.states + sizes.factors + nvar as f64)
            + n_idx * (100.0 + 8.0 * nvar as f64)
            + 8.0 * products,
    };
    if forced {
        Cost {
            ops: 2.0 * once.ops,
            bytes: 2.0 * once.bytes,
        }
    } else {
        once
    }
}

/// Checks every request of `scene` against `limits`, once the model and its
/// master modes are known and before the SSM is computed to `order`.
pub fn check(
    plan: &Plan,
    system: &System,
    masters: &[MasterMode],
    order: usize,
    limits: &Limits,
) -> Result<(), PlanError> {
    check_reference(plan, system, limits)?;
    let sizes = Sizes::of(system);
    let pairs = masters.len().max(1);
    let nvar = 2 * pairs;
    check_order(plan, system, pairs, order, limits)?;
    let n_idx = multi_indices(nvar, order);
    let per_time = periods_per_time(Dynamics::from(system.time), masters);
    let periods = |t_end: f64| t_end * per_time;
    let steps = |t_end: f64| match Dynamics::from(system.time) {
        Dynamics::Map { .. } => periods(t_end),
        Dynamics::Flow => periods(t_end) * STEPS_PER_PERIOD,
    };
    let coords = plan.coordinates.len() as f64;
    if let Some(v) = &plan.validation {
        let scale = Scale {
            n_idx,
            nvar,
            coords,
        };
        check_validate(v, &sizes, &scale, &steps, &periods, limits)?;
    }
    Ok(())
}

/// The sizes of the SSM that costs of its answers depend on.
#[derive(Clone, Copy)]
struct Scale {
    /// Multi-indices up to the expansion order.
    n_idx: f64,
    /// Reduced variables (twice the master pairs).
    nvar: usize,
    /// Outputs of `[outputs] coordinates`.
    coords: f64,
}

/// The full-system transient and steady states of `[validate]` (`steps`
/// and `periods` of a time span on the model).
fn check_validate(
    v: &ValidationSpec,
    sizes: &Sizes,
    scale: &Scale,
    steps: &dyn Fn(f64) -> f64,
    periods: &dyn Fn(f64) -> f64,
    limits: &Limits,
) -> Result<(), PlanError> {
    let Scale {
        n_idx,
        nvar,
        coords,
    } = *scale;
    let coords = v.outputs.as_ref().map_or(coords, |o| o.len() as f64);
    let step = sizes.sparse_solve();
    if let Some(tr) = &v.transient {
        let t_end = tr.t_end;
        let n = steps(t_end);
        let samples = tr.samples as f64;
        // each sample: the integrator stops there (dense output at worst a
        // step), the reduced model is lifted through W, and the distance
        // to the SSM is a Newton projection (about ten evaluations of W
        // and its Jacobian)
        let per_sample = 10.0 * n_idx * sizes.states * (nvar as f64 + 1.0);
        let cost = Cost {
            ops: n.max(samples) * step + samples * per_sample,
            bytes: samples * 8.0 * (3.0 * sizes.states + 4.0 * coords),
        };
        let key = if n * step > samples * per_sample {
            "validate.t_end"
        } else {
            "validate.samples"
        };
        ensure(
            key,
            format!(
                "the full-system transient over {:.1e} periods with {samples:.1e} samples",
                periods(t_end)
            ),
            &cost,
            limits,
            "shorten [validate] t_end or take fewer samples",
        )?;
    }
    if let Some(ss) = &v.steady_state {
        let freqs = ss.omegas.len() as f64;
        let periods = ss.max_periods as f64 * ss.max_period_multiple as f64;
        let per_period = STEPS_PER_PERIOD.max(ss.samples_per_period as f64);
        // frequencies run in parallel on the machine's cores
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
        let cost = Cost {
            ops: freqs * periods * per_period * step / cores,
            bytes: freqs * (8.0 * sizes.states * per_period + 1e3),
        };
        ensure(
            "validate.steady_state.max_periods",
            format!(
                "steady states at {freqs:.0} frequencies over up to {periods:.1e} periods each"
            ),
            &cost,
            limits,
            "lower max_periods (or the number of frequencies)",
        )?;
    }
    Ok(())
}

/// Continuation steps assumed per reference branch when `max_steps` allows
/// more (measured: 143 orbits a branch on the spatial oscillator's zoo
/// scene, 377 on the divider's, below).
const REFERENCE_STEPS: f64 = 400.0;

/// Factor of the reference's per-orbit operation count, fitted to two
/// measured runs (release build, 2 shared cores; CPU time of the reference,
/// since the machine was loaded):
/// - `zoo/spatial_oscillator_cubic_reference.toml` (7 states, H = 9, three
///   branches in `Omega` and one amplitude response, 643 orbits): 11.2 s
///   wall, under 6 s of CPU; the uncalibrated count said 83 s (at 500 steps
///   a branch);
/// - the divider of `benches/benches/reference.rs` (146 states, H = 5,
///   1606 Fourier coefficients, multipliers by the monodromy map; one
///   branch from rest at eps = 0.1 over [43.07, 49.87], 377 orbits): 651 s
///   wall, 329 s of CPU; the uncalibrated count said 14 min.
///
/// With 400 steps a branch and this factor the divider is estimated at
/// 5.6 min (its CPU time) and the oscillator at 33 s, an overestimate of
/// about 6 for small models, where the Hill eigenproblem's `(N (2H+1))^3`
/// bound is loose; the old count refused sound requests at 7-15 times their
/// run time.
const REFERENCE_CALIBRATION: f64 = 0.5;

/// Refuses a `[reference]` that would not finish within `limits`: per step
/// five sparse factorizations of the harmonic-balance Jacobian (a dense
/// `(2H+1)^2` block per nonzero of the pencil, eliminated at `(2H+1)^3` each)
/// and one Floquet analysis: up to the dense Hill limit one Hill
/// eigenproblem (`(N (2H+1))^3`), above it the monodromy matrix.
pub(crate) fn check_reference(
    plan: &Plan,
    system: &System,
    limits: &Limits,
) -> Result<(), PlanError> {
    let Some(r) = &plan.reference else {
        return Ok(());
    };
    let sizes = Sizes::of(system);
    let k = 2.0 * r.harmonics as f64 + 1.0;
    let nu = sizes.states * k;
    let factor = 2.0 * (sizes.nnz + sizes.factors) * k.powi(3);
    // multipliers: the dense Hill eigenproblem, or the monodromy matrix (16
    // H steps, each a sparse LU of the 3N stages and N solves, then a dense
    // N x N eigenproblem; measured 0.23 s per orbit on the divider, N = 146,
    // H = 5, which this estimate puts at 0.3 s); above 200 states the
    // dominant multipliers by subspace iteration (the 16 H LUs kept, about
    // three passes of a block of 16: some 64 solves per step)
    let n = sizes.states;
    let stage_steps = 8.0 * (k - 1.0);
    let hill = if !r.stability {
        0.0
    } else if nu <= ssm_core::fom::periodic::floquet::MAX_HILL_COEFFICIENTS as f64 {
        nu.powi(3)
    } else if n <= ssm_core::fom::periodic::monodromy::MAX_MONODROMY_STATES as f64 {
        stage_steps * 2.0 * n * (sizes.nnz + sizes.factors) + 10.0 * n.powi(3)
    } else {
        stage_steps * 2.0 * 64.0 * (sizes.nnz + sizes.factors)
    };
    // the kept LUs of the period's steps (9 blocks of the pencil's pattern
    // and fill each)
    let kept_lus =
        if r.stability && nu > ssm_core::fom::periodic::floquet::MAX_HILL_COEFFICIENTS as f64 {
            stage_steps * 9.0 * (sizes.nnz + sizes.factors) * 16.0
        } else {
            0.0
        };
    let branches = (r.epsilon.len() + r.amplitude_at.len()) as f64;
    // a branch's scaled arclength is of order ten: small steps take more
    let max_steps = r.max_steps as f64;
    let by_step = REFERENCE_STEPS.max(10.0 / r.step);
    let steps = max_steps.min(by_step);
    // each orbit's amplitudes of every output (a sum over the harmonics)
    let outputs = r.outputs.as_ref().unwrap_or(&plan.coordinates).len() as f64;
    let cost = Cost {
        ops: REFERENCE_CALIBRATION * branches * steps * (5.0 * factor + hill)
            + branches * steps * outputs * 8.0 * nu,
        bytes: 8.0 * (sizes.nnz + sizes.factors) * k * k * 4.0
            + 8.0 * nu * nu.min(1500.0)
            + kept_lus
            + branches * steps * 8.0 * (outputs + 8.0),
    };
    // the key that drives the cost: the number of steps when it exceeds a
    // typical branch's (max_steps when it caps the steps a small step asks
    // for, unless only step was changed from its default), else the
    // harmonics
    let caps = max_steps <= by_step
        && (r.max_steps != ReferenceSpec::DEFAULT_MAX_STEPS
            || r.step == ReferenceSpec::DEFAULT_STEP);
    let (key, advice) = if steps > REFERENCE_STEPS && caps {
        ("reference.max_steps", "lower max_steps")
    } else if steps > REFERENCE_STEPS {
        ("reference.step", "raise step (fewer, longer steps)")
    } else {
        (
            "reference.harmonics",
            "lower harmonics, or give fewer epsilon or amplitude_at",
        )
    };
    ensure(
        key,
        format!(
            "the full-system reference ({branches:.0} branches of up to {steps:.0} orbits with {nu:.0} Fourier coefficients)"
        ),
        &cost,
        limits,
        advice,
    )
}
