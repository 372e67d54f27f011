//! Any analysis of the engine's registry ([`ssm_engine::analyses::REGISTRY`])
//! run on an SSM, as a scene's run runs it: its spec read and checked with
//! the scene's keys and defaults, costed by the engine's one gate, run on
//! the SSM already computed (no TOML, no plan of a whole run), and its
//! results returned as the JSON `summary.json` keeps, the files its writer
//! makes, its warnings and error estimates, and, for the reduced transient
//! and the full system's reference, the numbers themselves as numpy arrays.
//! Also the full state on the SSM at a reduced point, `W(p)`.

use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyComplex, PyDict};

use crate::errors::{raise, Failure, Family};
use crate::reduced::{self, table, Ssm};
use ssm_core::fom::periodic::frc::ReferenceFrc;
use ssm_core::rom::autonomous::{polar_point, LiftedTransient};
use ssm_engine::analyses::reference::Reference;
use ssm_engine::analyses::transient::Transient;
use ssm_engine::analyses::{self, output_of, Beside, Context, Finished, Needs};
use ssm_engine::plan::budget::{self, Limits};
use ssm_engine::plan::Plan;
use ssm_engine::plan::PlannedAnalysis;

/// Runs the analysis `name` with the spec `spec` (JSON text: the keys of its
/// scene table, defaults filled in) on the SSM `ssm`, its answers read at
/// `outputs` and held to the relative `tolerance`: a dictionary of its
/// `summary` (JSON text), `files` (`(name, bytes)`), `warnings`, `estimates`,
/// `measured` and, for `transient` and `reference`, `arrays`.
#[pyfunction]
#[pyo3(signature = (ssm, name, spec, outputs=Vec::new(), tolerance=0.01, progress=None))]
pub(crate) fn analyze<'py>(
    py: Python<'py>,
    ssm: &Ssm,
    name: &str,
    spec: &str,
    outputs: Vec<String>,
    tolerance: f64,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let input = |message: String| raise(py, Family::Input, message);
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(input(format!(
            "tolerance: {tolerance} is not a positive, finite relative error"
        )));
    }
    let entry = analyses::find(name).map_err(|e| input(format!("name: {e}")))?;
    let json: serde_json::Value =
        serde_json::from_str(spec).map_err(|e| input(format!("{name}: {e}")))?;
    let order = ssm.expansion.order;
    let needs = Needs {
        pairs: ssm.masters.len(),
        max_order: order,
    };
    let spec = entry.spec(json, &needs).map_err(|e| input(e.to_string()))?;
    let orders = entry.orders(&spec).map_err(|e| input(e.to_string()))?;
    if let Some(o) = orders.into_iter().find(|&o| o > order) {
        return Err(input(format!(
            "{name}: order {o} is above the SSM's order {order}; compute the SSM to order {o}"
        )));
    }
    let maps: Vec<_> = reduced::outputs(py, &ssm.system, &outputs)?
        .into_iter()
        .cloned()
        .collect();
    // the engine's one gate: the analysis's work and memory within the
    // machine's limits, before anything is allocated
    let plan = Plan {
        coordinates: outputs.clone(),
        analyses: vec![PlannedAnalysis {
            name: name.to_owned(),
            spec: spec.clone(),
        }],
        ..Plan::default()
    };
    budget::check_analyses(
        &plan,
        &ssm.system,
        &ssm.masters,
        order,
        &Limits::of_machine(),
    )
    .map_err(|e| input(e.to_string()))?;
    let (system, expansion) = (Arc::clone(&ssm.system), Arc::clone(&ssm.expansion));
    let (masters, others) = (ssm.masters.clone(), ssm.others.clone());
    let names = outputs.clone();
    let (done, files) = crate::work::interruptible(py, progress.as_ref(), move |progress| {
        progress.begin(entry.stage().unwrap_or(entry.name()));
        let refs: Vec<_> = maps.iter().collect();
        let cx = Context::new(&system, &masters, &expansion, &refs, tolerance)
            .with_others(&others)
            .with_progress(progress);
        let done = entry
            .run(&spec, &cx)
            .map_err(|e| Failure::of(Family::Analysis, e))?;
        let files = done
            .files(&names, &Beside::default())
            .map_err(|e| Failure::of(Family::Analysis, e))?;
        Ok::<_, Failure>((done, files))
    })?
    .map_err(|f| f.raise(py))?;
    results(py, done, files, &outputs)
}

/// The dictionary [`analyze`] returns.
fn results<'py>(
    py: Python<'py>,
    done: Box<dyn Finished>,
    files: Vec<(String, Vec<u8>)>,
    outputs: &[String],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", done.name())?;
    d.set_item("summary", done.to_json().to_string())?;
    let files: Vec<(String, Bound<'py, PyBytes>)> = files
        .into_iter()
        .map(|(name, bytes)| (name, PyBytes::new(py, &bytes)))
        .collect();
    d.set_item("files", files)?;
    d.set_item("warnings", done.warnings())?;
    let estimates = done
        .estimates()
        .into_iter()
        .map(|e| {
            let row = PyDict::new(py);
            row.set_item("answer", e.answer)?;
            row.set_item("order", e.order)?;
            row.set_item("epsilon", e.epsilon)?;
            row.set_item("estimate", e.estimate)?;
            row.set_item("untrusted", e.untrusted)?;
            row.set_item("trusted_up_to", e.trusted_up_to)?;
            Ok(row)
        })
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("estimates", estimates)?;
    let measured = done
        .measured()
        .into_iter()
        .map(|m| {
            let row = PyDict::new(py);
            row.set_item("answer", m.answer)?;
            row.set_item("order", m.order)?;
            row.set_item("epsilon", m.epsilon)?;
            row.set_item("relative_error", m.relative_error)?;
            row.set_item("output", m.output)?;
            row.set_item("against", m.against)?;
            Ok(row)
        })
        .collect::<PyResult<Vec<_>>>()?;
    d.set_item("measured", measured)?;
    let done = [done];
    if let Some(t) = output_of::<Transient>(&done) {
        d.set_item("arrays", transient_arrays(py, &t.transient, outputs.len())?)?;
    } else if let Some(r) = output_of::<Reference>(&done) {
        d.set_item("arrays", reference_arrays(py, &r.frc)?)?;
    }
    Ok(d)
}

/// A reduced transient's samples: `times`, `outputs` (a column per output),
/// `rho` and `theta` (a column per master pair), `steps`, `error_estimate`,
/// `untrusted`.
fn transient_arrays<'py>(
    py: Python<'py>,
    t: &LiftedTransient,
    width: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let pairs = t.polar.first().map_or(0, Vec::len);
    d.set_item("order", t.order)?;
    d.set_item("times", PyArray1::from_slice(py, &t.times))?;
    d.set_item("outputs", table(py, &t.outputs, width))?;
    let rho: Vec<Vec<f64>> = t
        .polar
        .iter()
        .map(|p| p.iter().map(|q| q.0).collect())
        .collect();
    let theta: Vec<Vec<f64>> = t
        .polar
        .iter()
        .map(|p| p.iter().map(|q| q.1).collect())
        .collect();
    d.set_item("rho", table(py, &rho, pairs))?;
    d.set_item("theta", table(py, &theta, pairs))?;
    d.set_item("steps", t.steps)?;
    d.set_item("error_estimate", t.error_estimate)?;
    d.set_item("untrusted", t.untrusted)?;
    Ok(d)
}

/// The full system's periodic orbits, one row per orbit of every branch
/// (`continued` says in which parameter), and the bifurcations located on
/// them.
fn reference_arrays<'py>(py: Python<'py>, r: &ReferenceFrc) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let branches = r
        .branches
        .iter()
        .map(|b| ("omega", b))
        .chain(r.amplitude.iter().map(|b| ("epsilon", b)));
    let (mut continued, mut omega, mut epsilon, mut stable) = (vec![], vec![], vec![], vec![]);
    let (mut branch, mut multiple, mut linf, mut multiplier, mut tail) =
        (vec![], vec![], vec![], vec![], vec![]);
    let mut events = Vec::new();
    for (parameter, b) in branches {
        for o in &b.orbits {
            continued.push(parameter);
            omega.push(o.omega);
            epsilon.push(o.epsilon);
            stable.push(o.stable.map_or(f64::NAN, |s| if s { 1.0 } else { 0.0 }));
            branch.push(o.branch as u64);
            multiple.push(o.period_multiple as u64);
            linf.push(o.linf.clone());
            multiplier.push(o.max_multiplier.unwrap_or(f64::NAN));
            tail.push(o.tail);
        }
        for e in &b.events {
            let row = PyDict::new(py);
            row.set_item("kind", e.kind.label())?;
            row.set_item("omega", e.orbit.omega)?;
            row.set_item("epsilon", e.orbit.epsilon)?;
            row.set_item("branch", e.orbit.branch)?;
            row.set_item("continued", parameter)?;
            row.set_item(
                "multiplier",
                e.multiplier
                    .map(|m| PyComplex::from_doubles(py, m.re, m.im)),
            )?;
            events.push(row);
        }
    }
    d.set_item("outputs", r.outputs.clone())?;
    d.set_item("harmonics", r.harmonics)?;
    d.set_item("continued", continued)?;
    d.set_item("omega", PyArray1::from_vec(py, omega))?;
    d.set_item("epsilon", PyArray1::from_vec(py, epsilon))?;
    d.set_item("stable", PyArray1::from_vec(py, stable))?;
    d.set_item("branch", PyArray1::from_vec(py, branch))?;
    d.set_item("period_multiple", PyArray1::from_vec(py, multiple))?;
    d.set_item("amplitudes", table(py, &linf, r.outputs.len()))?;
    d.set_item("max_multiplier", PyArray1::from_vec(py, multiplier))?;
    d.set_item("tail", PyArray1::from_vec(py, tail))?;
    d.set_item("events", events)?;
    d.set_item("seconds", r.seconds)?;
    Ok(d)
}

/// The state `z = W(p)` on the SSM at the reduced point of polar amplitudes
/// `rho` and phases `theta` (one of each per master pair; `p_j = rho_j
/// e^{i theta_j}` and its conjugate), the expansion truncated at `order`
/// (default the SSM's): the real first-order state of the model (for a
/// mechanical model `(x, x')`, then any multipliers of its constraints).
#[pyfunction]
#[pyo3(signature = (ssm, rho, theta=None, order=None))]
pub(crate) fn state_on_ssm<'py>(
    py: Python<'py>,
    ssm: &Ssm,
    rho: Vec<f64>,
    theta: Option<Vec<f64>>,
    order: Option<usize>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let input = |message: String| raise(py, Family::Input, message);
    let pairs = ssm.masters.len();
    let theta = theta.unwrap_or_else(|| vec![0.0; rho.len()]);
    if rho.len() != pairs || theta.len() != pairs {
        return Err(input(format!(
            "rho, theta: {} and {} value(s) for {pairs} master pair(s)",
            rho.len(),
            theta.len()
        )));
    }
    if let Some(x) = rho.iter().chain(&theta).find(|x| !x.is_finite()) {
        return Err(input(format!("rho, theta: {x} is not finite")));
    }
    let order = order.unwrap_or(ssm.expansion.order);
    if order == 0 || order > ssm.expansion.order {
        return Err(input(format!(
            "order: {order}; give 1 to the SSM's order {}",
            ssm.expansion.order
        )));
    }
    let p = polar_point(&rho, &theta);
    let mono = ssm.expansion.set.monomials(&p, order);
    let z = ssm.expansion.w_at(&mono, order);
    let real: Vec<f64> = z.iter().map(|c| c.re).collect();
    Ok(PyArray1::from_vec(py, real))
}
