//! The speed-against-error report: for each expansion order, the time to build
//! the reduced model and to answer with it (backbone, FRC, transient), its
//! invariance error (eq. 41), and its error against the full-system reference
//! of `[validate]`, beside the full system's own cost.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5
//! (computing times against the full system), eq. (41).

use std::time::Instant;

use super::validation::{frc_error, frc_error_at, reference_points, Validation};
use crate::fom::periodic::frc::ReferenceFrc;
use crate::model::system::{OutputMap, System};
use crate::rom::forced_response::{forced_response, FrcError};
use crate::spec::FrcSpec;
use crate::spectrum::MasterMode;
use crate::ssm::analysis::{amplitude, backbone_frequency, invariance_error, polar};
use crate::ssm::rom::{integrate, RomError};
use crate::ssm::{self, SsmError, SsmOptions};
use crate::C64;

/// Why the report could not be produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReportError {
    /// An SSM of one order failed.
    #[error("report, O({order}): {source}")]
    Ssm {
        /// Expansion order.
        order: usize,
        /// What failed.
        source: SsmError,
    },
    /// A reduced transient failed.
    #[error("report, O({order}): {source}")]
    Transient {
        /// Expansion order.
        order: usize,
        /// What failed.
        source: RomError,
    },
    /// An FRC failed.
    #[error("report, O({order}): {source}")]
    Frc {
        /// Expansion order.
        order: usize,
        /// What failed.
        source: FrcError,
    },
}

/// One reduced model of the report (`report.rows` of `summary.json`; null:
/// not computed).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReportRow {
    /// Expansion order.
    pub order: usize,
    /// Seconds to compute the SSM and its reduced dynamics.
    pub ssm_s: f64,
    /// Seconds for a backbone curve (200 amplitudes), one pair only.
    pub backbone_s: Option<f64>,
    /// Seconds for the reduced transient of `[validate]`, lifted to the outputs.
    pub transient_s: Option<f64>,
    /// Seconds for the FRCs of `[forcing]` at this order.
    pub frc_s: Option<f64>,
    /// Invariance error (eq. 41) at `invariance_rho`.
    pub invariance_error: Option<f64>,
    /// Radius of the invariance error.
    pub invariance_rho: Option<f64>,
    /// Largest relative output error of the transient against the full system.
    pub transient_error: Option<f64>,
    /// Largest relative FRC amplitude error against the `[reference]` curve,
    /// else against the steady states.
    pub frc_error: Option<f64>,
}

/// The inputs of the report besides the model.
pub struct ReportInputs<'a> {
    /// Expansion orders.
    pub orders: &'a [usize],
    /// Master modes.
    pub masters: &'a [MasterMode],
    /// Non-master eigenvalues (for the non-resonance checks of the SSM).
    pub others: &'a [C64],
    /// Resonance tolerance of the SSM.
    pub resonance_tol: f64,
    /// Outputs (first one: backbone amplitude, FRC amplitude).
    pub outputs: &'a [&'a OutputMap],
    /// `[forcing]`, if any.
    pub forcing: Option<&'a FrcSpec>,
    /// The full-system references, if any.
    pub validation: Option<&'a Validation>,
    /// Initial reduced coordinates of the validation transient.
    pub p0: Option<Vec<C64>>,
    /// Relative tolerance of the reduced transients (the full system's).
    pub rtol: f64,
    /// Accuracy target of the forced response curves (`[ssm] tolerance`).
    pub tolerance: f64,
    /// The full system's forced response of `[reference]`, if any: the FRC
    /// errors are measured against it (else against the steady states).
    pub reference: Option<&'a ReferenceFrc>,
}

/// Computes the rows of the report.
pub fn rows(sys: &System, inp: &ReportInputs<'_>) -> Result<Vec<ReportRow>, ReportError> {
    let mut rows = Vec::with_capacity(inp.orders.len());
    let transient = inp
        .validation
        .and_then(|v| v.transient.as_ref())
        .map(|t| &t.result);
    let steady = inp.validation.and_then(|v| v.steady.as_ref());
    // the reference curve of the first output, at the first forcing amplitude
    let harmonic = inp.reference.and_then(|r| {
        let name = &inp.outputs.first()?.name;
        let j = r.outputs.iter().position(|o| o == name)?;
        let eps = r.branches.first()?.orbits.first()?.epsilon;
        let points: Vec<(f64, Vec<f64>)> = reference_points(r, eps)?
            .into_iter()
            .map(|(w, a)| (w, vec![a[j]]))
            .collect();
        Some((eps, points))
    });
    for &order in inp.orders {
        let t = Instant::now();
        let ssm = ssm::compute(
            sys,
            inp.masters,
            inp.others,
            &SsmOptions {
                order,
                resonance_tol: inp.resonance_tol,
            },
        )
        .map_err(|source| ReportError::Ssm { order, source })?;
        let ssm_s = t.elapsed().as_secs_f64();
        let mut row = ReportRow {
            order,
            ssm_s,
            backbone_s: None,
            transient_s: None,
            frc_s: None,
            invariance_error: None,
            invariance_rho: None,
            transient_error: None,
            frc_error: None,
        };
        if let (Ok(pol), Some(first)) = (polar(&ssm), inp.outputs.first()) {
            let t = Instant::now();
            let series = ssm.output_series(&first.weights);
            let rho_max = inp.p0.as_ref().map_or(0.1, |p| p[0].norm().max(1e-12));
            let curve: Vec<(f64, f64)> = (0..200)
                .map(|i| {
                    let rho = rho_max * i as f64 / 199.0;
                    (
                        amplitude(&ssm, &series, rho, order),
                        backbone_frequency(&ssm, &pol, rho, order),
                    )
                })
                .collect();
            std::hint::black_box(&curve);
            row.backbone_s = Some(t.elapsed().as_secs_f64());
        }
        if let (Some(tv), Some(p0)) = (transient, &inp.p0) {
            let t = Instant::now();
            let t_end = *tv.times.last().unwrap_or(&0.0);
            let tr = integrate(&ssm, order, p0, t_end, tv.times.len(), inp.rtol)
                .map_err(|source| ReportError::Transient { order, source })?;
            let end = ssm.set.of_order(order).end;
            let mut err = 0.0f64;
            for (k, o) in inp.outputs.iter().enumerate() {
                let series = ssm.output_series(&o.weights);
                let scale = tv.full[k].iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for (j, p) in tr.states.iter().enumerate() {
                    let mono = ssm.set.monomials(p, order);
                    let y = (1..end).map(|i| series[i] * mono[i]).sum::<C64>().re;
                    err = err.max((y - tv.full[k][j]).abs() / scale.max(f64::MIN_POSITIVE));
                }
            }
            row.transient_s = Some(t.elapsed().as_secs_f64());
            row.transient_error = Some(err);
            let rho = p0
                .iter()
                .step_by(2)
                .map(|q| q.norm_sqr())
                .sum::<f64>()
                .sqrt();
            row.invariance_rho = Some(rho);
        }
        if let Some(f) = inp.forcing {
            let mut sec = f.at_order(order);
            if let Some((eps, _)) = &harmonic {
                sec.epsilon = vec![*eps];
            } else if let Some(r) = steady {
                sec.epsilon = vec![r.epsilon];
            }
            let t = Instant::now();
            let rep = forced_response(&ssm, sys, inp.masters, &sec, inp.outputs, inp.tolerance)
                .map_err(|source| ReportError::Frc { order, source })?;
            row.frc_s = Some(t.elapsed().as_secs_f64());
            if let Some((eps, points)) = &harmonic {
                row.frc_error = frc_error_at(&rep.rows, points, *eps, order, 0).0;
            } else if let Some(r) = steady {
                row.frc_error = frc_error(&rep.rows, r, order, 0).0;
            }
            if row.invariance_rho.is_none() {
                row.invariance_rho = rep.rows.iter().map(|r| r.rho).reduce(f64::max);
            }
        }
        if let Some(rho) = row.invariance_rho.filter(|r| *r > 0.0) {
            row.invariance_error = Some(invariance_error(&ssm, sys, order, rho, 4, 30));
        }
        rows.push(row);
    }
    Ok(rows)
}

/// Full-system costs `(what, seconds)` of the references.
pub(crate) fn full_costs(
    v: Option<&Validation>,
    reference: Option<&ReferenceFrc>,
) -> Vec<FullCost> {
    let mut out = Vec::new();
    if let Some(r) = reference {
        let orbits: usize = r.branches.iter().map(|b| b.orbits.len()).sum();
        out.push(FullCost {
            kind: FullKind::HarmonicBalance,
            what: format!(
                "full forced response (harmonic balance, {} branches, {orbits} orbits)",
                r.branches.len()
            ),
            wall_s: r.seconds,
        });
    }
    if let Some(v) = v {
        if let Some(t) = &v.transient {
            out.push(FullCost {
                kind: FullKind::Transient,
                what: "full transient".to_owned(),
                wall_s: t.result.full_s,
            });
        }
        if let Some(s) = &v.steady {
            out.push(FullCost {
                kind: FullKind::SteadyState,
                what: format!("full steady state, {} frequencies", s.points.len()),
                wall_s: s.wall_s,
            });
        }
    }
    out
}

/// Kind of a full-system reference cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FullKind {
    /// The transient of `[validate]`.
    Transient,
    /// The steady states of `[validate.steady_state]`.
    SteadyState,
    /// The forced response of `[reference]`.
    HarmonicBalance,
}

/// What one full-system reference cost.
#[derive(Debug, Clone, PartialEq)]
pub struct FullCost {
    /// Which reference.
    pub kind: FullKind,
    /// Description.
    pub what: String,
    /// Wall time.
    pub wall_s: f64,
}

/// The reduced model's speed-up on the transient: the highest order with a
/// transient, built and integrated, against the full integration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Speedup {
    /// Expansion order.
    pub order: usize,
    /// SSM build plus reduced transient.
    pub rom_s: f64,
    /// Full transient.
    pub full_s: f64,
    /// `full_s / rom_s`.
    pub ratio: f64,
}

/// The report: one row per order and the full-system costs.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// One row per expansion order.
    pub rows: Vec<ReportRow>,
    /// The full-system references.
    pub full: Vec<FullCost>,
    /// The transient speed-up, if both sides ran.
    pub speedup: Option<Speedup>,
}

impl ReportRow {
    /// The error an order is plotted with: transient, else FRC, else invariance.
    pub fn error(&self) -> Option<f64> {
        self.transient_error
            .or(self.frc_error)
            .or(self.invariance_error)
    }

    /// Time to build the model and give every answer.
    pub fn answer_s(&self) -> f64 {
        self.ssm_s
            + self.transient_s.unwrap_or(0.0)
            + self.frc_s.unwrap_or(0.0)
            + self.backbone_s.unwrap_or(0.0)
    }
}

/// The report of `inp`: its rows, the full-system costs and the speed-up.
pub fn report(sys: &System, inp: &ReportInputs<'_>) -> Result<Report, ReportError> {
    let rows = rows(sys, inp)?;
    let full = full_costs(inp.validation, inp.reference);
    let speedup = match (
        rows.iter()
            .filter(|r| r.transient_s.is_some())
            .max_by_key(|r| r.order),
        full.iter().find(|f| f.kind == FullKind::Transient),
    ) {
        (Some(best), Some(ft)) => {
            let rom_s = best.ssm_s + best.transient_s.unwrap_or(0.0);
            Some(Speedup {
                order: best.order,
                rom_s,
                full_s: ft.wall_s,
                ratio: ft.wall_s / rom_s.max(1e-12),
            })
        }
        _ => None,
    };
    Ok(Report {
        rows,
        full,
        speedup,
    })
}
