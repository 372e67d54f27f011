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
use ssm_core::rom::frc::NONAUTONOMOUS_NODES;
use ssm_core::spec::SsmSpec;
use ssm_core::spectrum::{MasterMode, Method, DENSE_LIMIT};
use ssm_core::ssm::{band_vectors, lu_bytes_estimate, Dynamics, LU_BYTES_PER_ENTRY, SERIES_TERMS};

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
    /// The dense kernels' per-thread buffers ([`ssm_kernel::workspace`]);
    /// when the address-space limit cannot hold them, no computation with
    /// the model fits ([`check_spectrum`] and every later gate refuse),
    /// though building it may.
    pub workspace: ssm_kernel::workspace::Workspace,
}

impl Limits {
    /// One hour (or `SSM_TIME_LIMIT_MINUTES`), and three quarters of the
    /// memory this process may still allocate: the smallest of the machine's
    /// available memory, the address space left under `ulimit -v` and the
    /// room under the cgroup's memory limit
    /// ([`ssm_api::limits::memory_room`]), read after the dense kernels'
    /// per-thread buffers are reserved ([`ssm_kernel::workspace::reserve`]).
    pub fn of_machine() -> Self {
        let minutes = std::env::var(TIME_LIMIT_VAR)
            .ok()
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|m| m.is_finite() && *m > 0.0)
            .unwrap_or(60.0);
        let workspace = ssm_kernel::workspace::reserve();
        let room = ssm_api::limits::memory_room();
        Self {
            seconds: minutes * 60.0,
            bytes: 0.75 * room.bytes,
            memory_source: room.source,
            workspace,
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

/// The work of each analysis the plan asks for ([`Plan::requested`]) on an
/// SSM of the masters' pairs to `order` within `limits`; a refusal names
/// the key that sets the size.
pub fn check_analyses(
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
        nnz: model.nnz,
        sparse_solve: model.sparse_solve(),
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
    /// Factors of all monomials of `F` (what composing `F` with `W` costs).
    factors: f64,
    /// Nodes of the composition's trie (`Composition::nodes_of`), each one
    /// series of the multi-indices; `factors` (a bound) until
    /// [`Sizes::with_factors`] counts them.
    nodes: f64,
    /// Heap of one sparse LU of the pencil and of the mass matrix's LU held
    /// with them ([`lu_bytes_estimate`]; 0 until [`Sizes::with_factors`]
    /// computes it).
    lu_bytes: f64,
    /// Heap of one complex sparse LU of the same matrix (the spectrum's).
    spectrum_lu_bytes: f64,
    mass_lu_bytes: f64,
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
            nodes: factors as f64,
            lu_bytes: 0.0,
            spectrum_lu_bytes: 0.0,
            mass_lu_bytes: 0.0,
        }
    }

    /// [`Sizes::of`] with the estimate of one sparse LU's heap (a symbolic
    /// Cholesky analysis of the pattern) and the composition's nodes counted
    /// (its trie built without its series).
    fn with_factors(system: &System) -> Self {
        let lu = lu_bytes_estimate(system.a.as_ref(), system.b.as_ref(), system.velocities());
        Self {
            nodes: ssm_kernel::poly::Composition::nodes_of(&system.nonlinearity) as f64,
            lu_bytes: lu.map_or(0.0, |f| f.each),
            spectrum_lu_bytes: lu.map_or(0.0, |f| f.lu),
            mass_lu_bytes: lu.map_or(0.0, |f| f.shared),
            ..Self::of(system)
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
    if let Some(note) = workspace_note(limits) {
        return Err(PlanError::new(
            key,
            format!(
                "{what} needs about {} of memory, but {note}",
                bytes(cost.bytes)
            ),
        ));
    }
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

/// Why nothing fits when the address-space limit cannot hold the dense
/// kernels' buffers, with what to change.
fn workspace_note(limits: &Limits) -> Option<String> {
    let w = &limits.workspace;
    if w.missing <= 0.0 {
        return None;
    }
    // with one pool thread, the caller and that thread reserve
    let spared = w.per_thread * w.threads.saturating_sub(2) as f64;
    let single = if spared >= w.missing {
        "run with RAYON_NUM_THREADS=1".to_owned()
    } else {
        format!(
            "run with RAYON_NUM_THREADS=1 and raise it by {}",
            bytes(w.missing - spared)
        )
    };
    Some(format!(
        "the address-space limit (ulimit -v) cannot hold the {} of address space faer's dense matrix kernels reserve for {} thread(s) ({} each: twice the L3 cache this CPU reports): raise ulimit -v by at least {}, or {single}",
        bytes(w.per_thread * w.threads as f64),
        w.threads,
        bytes(w.per_thread),
        bytes(w.missing),
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

/// Whether `cost` fits; nothing does when the address-space limit cannot
/// hold the dense kernels' buffers (a run could abort at any large
/// product).
fn within(cost: &Cost, limits: &Limits) -> bool {
    limits.workspace.missing <= 0.0
        && cost.ops / OPS_PER_SECOND <= limits.seconds
        && cost.bytes <= limits.bytes
}

/// Before the spectral stage: the dense spectrum (a QZ iteration on the
/// `N x N` pencil, about `70 N^3` operations on 6 dense complex matrices),
/// or the sparse one (`sparse_spectrum_cost`), and the SSM order (see
/// `order_ceiling`); returns the highest order the run may compute.
pub fn check_spectrum(plan: &Plan, system: &System, limits: &Limits) -> Result<usize, PlanError> {
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
    let pairs = plan.ssm.master_pairs.len().max(1);
    // one symbolic analysis of the pattern for the spectrum's and the
    // order's estimates
    let sizes = Sizes::with_factors(system);
    if dense {
        ensure(
            "spectrum.method",
            format!("the dense spectrum of {n} states"),
            &cost,
            limits,
            "use method = \"sparse\" with the modes you need",
        )?;
    } else {
        let highest = plan.ssm.master_pairs.iter().copied().max().unwrap_or(1);
        let modes = plan
            .spectrum
            .modes
            .unwrap_or(2 * highest + 10)
            .max(2 * highest);
        ensure(
            "spectrum.modes",
            format!("the sparse spectrum of {n} states ({modes} modes)"),
            &sparse_spectrum_cost(&sizes, modes, pairs),
            limits,
            "ask for fewer modes, or coarsen the model",
        )?;
    }
    order_ceiling(plan, &sizes, pairs, limits)
}

/// The sparse spectrum of `modes` modes and the inverse iteration of
/// `pairs` master modes: one sparse LU of the shifted pencil, held while
/// the Krylov iteration runs, and one at a time the complex LU of a master
/// mode ([`lu_bytes_estimate`]'s `lu` is the complex LU's, so it
/// bounds both), the pencil's shifted copy, and the Arnoldi basis of `m + 1`
/// vectors, `m = max(2 modes + 8, 20)` (as `spectrum::krylov` sizes it).
/// Work: the real factorization and each complex one (four times as dear)
/// as the SSM's sparse factorization is costed, the `3 m` Krylov solves of
/// a few restarts and the 6 inverse-iteration solves per pair, each a pass
/// over the factors' entries (`L + U`, twice the symbolic Cholesky entries
/// the memory estimate counts; a complex entry four operations), and the
/// basis's orthogonalization, `2 N m^2` per restart.
fn sparse_spectrum_cost(sizes: &Sizes, modes: usize, pairs: usize) -> Cost {
    let m = ((2 * modes + 8).max(20) as f64).min(sizes.states);
    let entries = 2.0 * sizes.spectrum_lu_bytes / LU_BYTES_PER_ENTRY;
    let pairs = pairs as f64;
    Cost {
        ops: sizes.sparse_solve() * (1.0 + 4.0 * pairs)
            + entries * (3.0 * m + 24.0 * pairs)
            + 6.0 * sizes.states * m * m,
        bytes: sizes.spectrum_lu_bytes
            + sizes.mass_lu_bytes
            + 16.0 * sizes.nnz
            + 8.0 * sizes.states * (m + 3.0),
    }
}

/// The highest SSM order of the run, with `pairs` master pairs: the scene's
/// `[ssm] order`, checked against the limits; without one, the highest odd
/// order up to [`SsmSpec::AUTO_MAX_ORDER`] that the limits allow (not below 3 nor
/// the orders the answers name), which the pipeline may then lower. Run
/// before the spectral stage, since the eq. (53) resonance check there
/// enumerates the multi-indices up to this order.
fn order_ceiling(
    plan: &Plan,
    sizes: &Sizes,
    pairs: usize,
    limits: &Limits,
) -> Result<usize, PlanError> {
    if let Some(o) = plan.ssm.order {
        check_order(plan, sizes, pairs, o, limits)?;
        return Ok(o);
    }
    let floor = plan.highest_named_order().max(3);
    let top = (floor..=SsmSpec::AUTO_MAX_ORDER.max(floor))
        .rev()
        .filter(|o| o % 2 == 1 || *o == floor)
        .find(|&o| within(&order_cost(plan, sizes, pairs, o), limits));
    match top {
        Some(o) => Ok(o),
        None => check_order(plan, sizes, pairs, floor, limits).map(|()| floor),
    }
}

/// The SSM to `order` with `pairs` master pairs, rebuilt by the report.
fn order_cost(plan: &Plan, sizes: &Sizes, pairs: usize, order: usize) -> Cost {
    let forced = plan.frc.is_some() || plan.validation.is_some();
    let mut ssm = ssm_cost(sizes, pairs, order, forced);
    if let Some(r) = &plan.report {
        // the report rebuilds the SSM at each of its orders (at most `order`;
        // a given list counts with its length)
        ssm.ops *= r.orders.as_ref().map_or(order, Vec::len) as f64;
    }
    ssm
}

/// The scene's explicit SSM order against `limits` before the model is
/// built: its cost on the smallest model the master pairs allow (their own
/// `2 pairs` states, no nonlinearity) is a lower bound on its cost on any,
/// so an order that cannot fit even there is refused without building a
/// model or computing its spectrum (an order of `1e13` typed for 13).
///
/// # Errors
/// The order does not fit, naming `ssm.order`.
pub fn check_before_model(plan: &Plan, limits: &Limits) -> Result<(), PlanError> {
    // where the dense kernels' buffers do not fit, nothing does: the first
    // gate of the model's own computations says so at its key
    let Some(order) = plan.ssm.order.filter(|_| workspace_note(limits).is_none()) else {
        return Ok(());
    };
    let pairs = plan.ssm.master_pairs.len().max(1);
    let states = 2.0 * pairs as f64;
    let smallest = Sizes {
        states,
        nnz: states,
        factors: 0.0,
        nodes: 0.0,
        lu_bytes: 0.0,
        spectrum_lu_bytes: 0.0,
        mass_lu_bytes: 0.0,
    };
    let cost = order_cost(plan, &smallest, pairs, order);
    ensure(
        "ssm.order",
        format!(
            "an SSM of order {order} with {pairs} master pair(s), even of the smallest model ({states} states),"
        ),
        &cost,
        limits,
        "lower the order",
    )
}

/// The SSM order against the limits, with `pairs` master pairs.
fn check_order(
    plan: &Plan,
    sizes: &Sizes,
    pairs: usize,
    order: usize,
    limits: &Limits,
) -> Result<(), PlanError> {
    let ssm = order_cost(plan, sizes, pairs, order);
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
/// twice that with a forcing (the non-autonomous SSM, eq. 60), whose
/// expansions at the forced response's interpolation nodes are held
/// together (every node's `x_k`, [`NONAUTONOMOUS_NODES`] times the SSM's
/// coefficients) and solved in bands: as Taylor series in `Omega` (at most
/// [`SERIES_TERMS`] vectors of the model's size per multi-index, kept with
/// the nodes' expansions) or, where a series fails, by band solves (at most
/// [`band_vectors`] such vectors at once). The sparse factors count with
/// the most an order holds at once (one per distinct value of
/// `Lambda_k = k . lambda` among the order's multi-indices up to
/// conjugation), and the forced response's with [`FRC_FACTORS_HELD`]
/// (the SSM's are dropped by then).
fn ssm_cost(sizes: &Sizes, pairs: usize, order: usize, forced: bool) -> Cost {
    let nvar = 2 * pairs;
    let n_idx = multi_indices(nvar, order);
    let products = binomial(2 * nvar, order);
    // multi-indices of the highest order, half of them up to conjugation
    let held = (binomial(nvar - 1, order) / 2.0).ceil().max(1.0);
    let once = Cost {
        ops: 4.0 * sizes.factors * products + 0.5 * n_idx * sizes.sparse_solve(),
        // the composition one series of the multi-indices per trie node
        // (with 48 bytes of node and vector header) and 24 bytes per term
        // (at most one per factor); the series product table one 8-byte
        // entry per product (the split pairs of every multi-index, allocated
        // exactly); the index set some 100 + 8 nvar bytes per multi-index
        // (exponents, hash lookup, conjugates, lower neighbours)
        bytes: 16.0 * n_idx * (2.0 * sizes.states + sizes.nodes + nvar as f64)
            + 48.0 * sizes.nodes
            + 24.0 * sizes.factors
            + n_idx * (100.0 + 8.0 * nvar as f64)
            + 8.0 * products,
    };
    if forced {
        Cost {
            ops: 2.0 * once.ops,
            bytes: 2.0 * once.bytes
                + held.max(FRC_FACTORS_HELD) * sizes.lu_bytes
                + sizes.mass_lu_bytes
                + 16.0 * NONAUTONOMOUS_NODES as f64 * n_idx * (sizes.states + nvar as f64)
                + 16.0
                    * (SERIES_TERMS as f64 * n_idx).max(band_vectors(NONAUTONOMOUS_NODES) as f64)
                    * sizes.states,
        }
    } else {
        Cost {
            ops: once.ops,
            bytes: once.bytes + held * sizes.lu_bytes + sizes.mass_lu_bytes,
        }
    }
}

/// Sparse factors a forced response holds at once where band solves run
/// (its leading-order anchor, kept for the whole response, and those of the
/// non-autonomous table's multi-indices, released one by one; 4 measured
/// on the clamped plates, asserted in the suite's `plate` tests).
const FRC_FACTORS_HELD: f64 = 4.0;

/// Checks every request of `scene` against `limits`, once the model and its
/// master modes are known and before the SSM is computed to `order`.
pub fn check(
    plan: &Plan,
    system: &System,
    masters: &[MasterMode],
    order: usize,
    limits: &Limits,
) -> Result<(), PlanError> {
    check_order(
        plan,
        &Sizes::with_factors(system),
        masters.len().max(1),
        order,
        limits,
    )
}
