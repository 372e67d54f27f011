//! `ssm._ssm`: the engine's core for Python, a thin layer that converts
//! arrays and results and releases the GIL while the core computes. The
//! Python package `ssm` (`python/ssm`) wraps it: it accepts dense and
//! `scipy.sparse` arrays, turns results into objects with `.to_pandas()`,
//! and owns the exception and warning classes this module raises
//! (`ssm.errors`).
//!
//! Every computation runs on the typed API of `ssm-core` (models through the
//! model-files path of `ssm-model-files` and `ssm-plugin-kit`, the spectral
//! stage, the SSM, the backbone and the forced response with their specs,
//! and every other analysis of the engine's registry on an SSM); no TOML is
//! written.

mod analysis;
mod errors;
mod model;
mod plan;
mod plugin;
mod reduced;
mod study;
mod work;

use pyo3::prelude::*;

/// Counts the heap, for the memory the summaries report (the extension's
/// own allocations; Python's are not counted).
#[global_allocator]
static HEAP: ssm_kernel::heap::Counting = ssm_kernel::heap::Counting;

/// The module `ssm._ssm`.
#[pymodule]
fn _ssm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<model::Model>()?;
    m.add_class::<reduced::Ssm>()?;
    m.add_function(wrap_pyfunction!(analysis::analyze, m)?)?;
    m.add_function(wrap_pyfunction!(analysis::state_on_ssm, m)?)?;
    m.add_function(wrap_pyfunction!(plan::run_plan, m)?)?;
    m.add_function(wrap_pyfunction!(plan::run_scene, m)?)?;
    m.add_function(wrap_pyfunction!(plan::model_from_scene, m)?)?;
    m.add_function(wrap_pyfunction!(plugin::model_from_plugin, m)?)?;
    m.add_function(wrap_pyfunction!(plugin::model_from_signals, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_figures, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_sample, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_check_parameter, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_plan_at, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_open_store, m)?)?;
    m.add_function(wrap_pyfunction!(study::study_write_record, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
