//! The SSM of a model and the answers read off it: the spectral stage and
//! the expansion ([`ssm_core::spectral`], [`ssm_core::compute_ssm`]), the
//! backbone and the forced response ([`ssm_core::backbone`],
//! [`ssm_core::forced_response`]), each answer with its error estimate.
//! Results cross as dictionaries of numpy arrays; the package `ssm` wraps
//! them in result objects.

use std::sync::Arc;

use numpy::{Complex64, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{raise, Failure, Family};
use crate::model::Model;
use ssm_core::spectrum::{MasterMode, Normalization};
use ssm_core::{
    backbone, compute_ssm, forced_response, spectral, BackboneSpec, FrcSpec, SpectrumSpec,
    SsmExpansion, SsmOptions, SsmSpec, System,
};
use ssm_engine::plan::budget::{self, Limits};
use ssm_engine::plan::Plan;

/// An SSM of a model: its master modes, the expansion and the warnings of
/// its spectral stage (resonances, fallbacks).
#[pyclass(module = "ssm._ssm", frozen)]
pub struct Ssm {
    pub(crate) system: Arc<System>,
    pub(crate) masters: Vec<MasterMode>,
    /// The eigenvalues of the spectrum that are not masters.
    pub(crate) others: Vec<Complex64>,
    pub(crate) expansion: Arc<SsmExpansion>,
    warnings: Vec<String>,
}

/// The normalization a Python caller names.
fn normalization(py: Python<'_>, name: &str) -> PyResult<Normalization> {
    match name {
        "unit" => Ok(Normalization::Unit),
        "mass" => Ok(Normalization::Mass),
        other => Err(raise(
            py,
            Family::Input,
            format!("normalization: '{other}' is not 'unit' or 'mass'"),
        )),
    }
}

/// The model's outputs of `names`.
pub(crate) fn outputs<'a>(
    py: Python<'_>,
    system: &'a System,
    names: &[String],
) -> PyResult<Vec<&'a ssm_core::model::system::OutputMap>> {
    names
        .iter()
        .map(|n| {
            system.output(n).ok_or_else(|| {
                raise(
                    py,
                    Family::Input,
                    format!(
                        "outputs: the model has no output '{n}'; it has {:?}",
                        system
                            .outputs
                            .iter()
                            .map(|o| o.name.as_str())
                            .collect::<Vec<_>>()
                    ),
                )
            })
        })
        .collect()
}

/// `values` as a 2-D array of `rows` rows.
pub(crate) fn table<'py>(
    py: Python<'py>,
    rows: &[Vec<f64>],
    width: usize,
) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    let n = rows.len();
    // rows of equal width `width` by construction: the reshape cannot fail
    PyArray1::from_vec(py, flat)
        .reshape([n, width])
        .unwrap_or_else(|_| PyArray2::zeros(py, [n, width], false))
}

impl Ssm {
    /// The model's outputs `names`, once the engine's one gate has passed
    /// the answers `plan` asks of this SSM at them: their work and memory
    /// within the machine's limits, before anything is allocated.
    fn gate(
        &self,
        py: Python<'_>,
        names: &[String],
        plan: Plan,
    ) -> PyResult<Vec<ssm_core::model::system::OutputMap>> {
        let maps: Vec<_> = outputs(py, &self.system, names)?
            .into_iter()
            .cloned()
            .collect();
        let plan = Plan {
            coordinates: names.to_vec(),
            ..plan
        };
        budget::check_analyses(
            &plan,
            &self.system,
            &self.masters,
            self.expansion.order,
            &Limits::of_machine(),
        )
        .map_err(|e| raise(py, Family::Input, e.to_string()))?;
        Ok(maps)
    }
}

#[pymethods]
impl Ssm {
    /// The SSM of `model` over the master pairs `master_pairs` (1-based,
    /// slowest first) to `order`, after the spectral stage (spectrum,
    /// master modes, non-resonance checks up to `order`).
    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (model, master_pairs, order, resonance_tol=0.02, normalization="unit", progress=None))]
    fn compute(
        py: Python<'_>,
        model: &Model,
        master_pairs: Vec<usize>,
        order: usize,
        resonance_tol: f64,
        normalization: &str,
        progress: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Ssm> {
        let spec = SsmSpec {
            master_pairs,
            order: Some(order),
            normalization: self::normalization(py, normalization)?,
            resonance_tol,
            ..SsmSpec::default()
        };
        let system = Arc::clone(&model.system);
        let sys = Arc::clone(&system);
        let (masters, others, expansion, warnings) =
            crate::work::interruptible(py, progress.as_ref(), move |progress| {
                // the engine's one gate, as for a scene: the spec's values,
                // the spectrum's and the order's cost within the machine's
                // limits, before anything is allocated
                let plan = Plan {
                    ssm: spec,
                    ..Plan::default()
                };
                let limits = Limits::of_machine();
                let ceiling = plan
                    .check(&sys, &limits)
                    .map_err(|e| Failure::of(Family::Input, e))?;
                let spec = plan.ssm;
                progress.begin("spectrum");
                let sp = spectral(&spec, &SpectrumSpec::default(), &sys, ceiling)
                    .map_err(|e| Failure::of(Family::Spectrum, e))?;
                let others = ssm_core::ssm::non_master(&sp.spectrum.eigenvalues, &sp.masters);
                let plan = Plan {
                    ssm: spec,
                    ..Plan::default()
                };
                budget::check(&plan, &sys, &sp.masters, ceiling, &limits)
                    .map_err(|e| Failure::of(Family::Input, e))?;
                let options = SsmOptions {
                    order: ceiling,
                    resonance_tol: plan.ssm.resonance_tol,
                };
                progress.begin("SSM");
                let expansion = compute_ssm(&sys, &sp.masters, &others, &options)
                    .map_err(|e| Failure::of(Family::Expansion, e))?;
                Ok::<_, Failure>((sp.masters, others, expansion, sp.warnings))
            })?
            .map_err(|f| f.raise(py))?;
        Ok(Ssm {
            system,
            masters,
            others,
            expansion: Arc::new(expansion),
            warnings,
        })
    }

    /// The expansion order.
    #[getter]
    fn order(&self) -> usize {
        self.expansion.order
    }

    /// The master eigenvalues.
    #[getter]
    fn master_eigenvalues<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Complex64>> {
        PyArray1::from_vec(py, self.masters.iter().map(|m| m.lambda).collect())
    }

    /// The warnings of the spectral stage.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The coefficients of `W`: one row per multi-index of the expansion,
    /// one column per state.
    #[getter]
    fn w<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Complex64>> {
        let rows = self.expansion.w.len();
        let width = self.system.n_states();
        let flat: Vec<Complex64> = self
            .expansion
            .w
            .iter()
            .flat_map(|r| (0..width).map(move |k| r.get(k).copied().unwrap_or_default()))
            .collect();
        PyArray1::from_vec(py, flat)
            .reshape([rows, width])
            .unwrap_or_else(|_| PyArray2::zeros(py, [rows, width], false))
    }

    /// The backbone curves of one master pair up to the polar amplitude
    /// `rho_max` at `points` amplitudes, one per order of `orders` (default
    /// the SSM's), with the amplitudes of `outputs` and their error
    /// estimates held to the relative `tolerance`: a list of dictionaries.
    #[pyo3(signature = (rho_max, points=101, orders=None, outputs=Vec::new(), tolerance=0.01, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn backbone<'py>(
        &self,
        py: Python<'py>,
        rho_max: f64,
        points: usize,
        orders: Option<Vec<usize>>,
        outputs: Vec<String>,
        tolerance: f64,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let spec = BackboneSpec {
            rho_max,
            points,
            orders,
        };
        spec.check(self.masters.len(), self.expansion.order)
            .map_err(|e| raise(py, Family::Input, e.to_string()))?;
        let maps = self.gate(
            py,
            &outputs,
            Plan {
                backbone: Some(spec.clone()),
                ..Plan::default()
            },
        )?;
        let (system, expansion) = (Arc::clone(&self.system), Arc::clone(&self.expansion));
        let master = self.masters[0].clone();
        let curves = crate::work::interruptible(py, progress.as_ref(), move |progress| {
            progress.begin("backbone");
            let refs: Vec<_> = maps.iter().collect();
            backbone(&expansion, &system, &master, &spec, &refs, tolerance)
                .map_err(|e| Failure::of(Family::Analysis, e))
        })?
        .map_err(|f| f.raise(py))?;
        let width = outputs.len();
        curves
            .iter()
            .map(|c| {
                let d = PyDict::new(py);
                d.set_item("order", c.order)?;
                let rho: Vec<f64> = c.points.iter().map(|p| p.rho).collect();
                let omega: Vec<f64> = c.points.iter().map(|p| p.omega).collect();
                let estimate: Vec<f64> = c
                    .points
                    .iter()
                    .map(|p| p.error_estimate.unwrap_or(f64::NAN))
                    .collect();
                let amplitudes: Vec<Vec<f64>> =
                    c.points.iter().map(|p| p.amplitudes.clone()).collect();
                d.set_item("rho", PyArray1::from_vec(py, rho))?;
                d.set_item("omega", PyArray1::from_vec(py, omega))?;
                d.set_item("error_estimate", PyArray1::from_vec(py, estimate))?;
                d.set_item("amplitudes", table(py, &amplitudes, width))?;
                d.set_item("outputs", outputs.clone())?;
                d.set_item("curve_error_estimate", c.error_estimate)?;
                d.set_item("untrusted", c.untrusted)?;
                d.set_item("trusted_up_to", c.trusted_up_to)?;
                Ok(d)
            })
            .collect()
    }

    /// The forced response curves of the reduced model to
    /// `eps fext cos(Omega t)` for each amplitude of `epsilon` over
    /// `omega_range` (`points` per curve, one curve per order of `orders`),
    /// with the amplitudes of `outputs`: a dictionary of the table's columns
    /// and the curves (estimate, untrusted flag, bifurcations).
    #[pyo3(signature = (epsilon, omega_range, points=200, orders=None, outputs=Vec::new(), tolerance=0.01, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn forced_response<'py>(
        &self,
        py: Python<'py>,
        epsilon: Vec<f64>,
        omega_range: (f64, f64),
        points: usize,
        orders: Option<Vec<usize>>,
        outputs: Vec<String>,
        tolerance: f64,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let spec = FrcSpec {
            points,
            orders,
            ..FrcSpec::new(epsilon, [omega_range.0, omega_range.1])
        };
        spec.check(self.masters.len(), self.expansion.order)
            .map_err(|e| raise(py, Family::Input, e.to_string()))?;
        if self.system.forcing.is_empty() {
            return Err(raise(
                py,
                Family::Input,
                "fext: the model has no load shape to force it with",
            ));
        }
        let maps = self.gate(
            py,
            &outputs,
            Plan {
                frc: Some(spec.clone()),
                ..Plan::default()
            },
        )?;
        let (system, expansion) = (Arc::clone(&self.system), Arc::clone(&self.expansion));
        let masters = self.masters.clone();
        let frc = crate::work::interruptible(py, progress.as_ref(), move |progress| {
            progress.begin("forced response");
            let refs: Vec<_> = maps.iter().collect();
            forced_response(&expansion, &system, &masters, &spec, &refs, tolerance)
                .map_err(|e| Failure::of(Family::Analysis, e))
        })?
        .map_err(|f| f.raise(py))?;
        let d = PyDict::new(py);
        let rows = &frc.rows;
        d.set_item(
            "order",
            PyArray1::from_vec(py, rows.iter().map(|r| r.order as u64).collect()),
        )?;
        d.set_item(
            "epsilon",
            PyArray1::from_vec(py, rows.iter().map(|r| r.epsilon).collect()),
        )?;
        d.set_item(
            "omega",
            PyArray1::from_vec(py, rows.iter().map(|r| r.omega).collect()),
        )?;
        d.set_item(
            "branch",
            PyArray1::from_vec(py, rows.iter().map(|r| r.branch as u64).collect()),
        )?;
        d.set_item(
            "stable",
            PyArray1::from_vec(py, rows.iter().map(|r| r.stable).collect()),
        )?;
        d.set_item(
            "rho",
            PyArray1::from_vec(py, rows.iter().map(|r| r.rho).collect()),
        )?;
        let linf: Vec<Vec<f64>> = rows.iter().map(|r| r.linf.clone()).collect();
        d.set_item("amplitudes", table(py, &linf, frc.outputs.len()))?;
        d.set_item("outputs", frc.outputs.clone())?;
        let curves = frc
            .curves
            .iter()
            .map(|c| {
                let cd = PyDict::new(py);
                cd.set_item("order", c.order)?;
                cd.set_item("epsilon", c.epsilon)?;
                cd.set_item("error_estimate", c.error_estimate())?;
                cd.set_item("untrusted", c.untrusted)?;
                let bifurcations: Vec<(String, f64, usize)> = c
                    .bifurcations
                    .iter()
                    .map(|b| (b.kind.to_owned(), b.omega, b.branch))
                    .collect();
                cd.set_item("bifurcations", bifurcations)?;
                Ok(cd)
            })
            .collect::<PyResult<Vec<_>>>()?;
        d.set_item("curves", curves)?;
        d.set_item("warnings", frc.warnings.clone())?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Ssm(O({}), {} master pair(s) of '{}')",
            self.expansion.order,
            self.masters.len(),
            self.system.name
        )
    }
}
