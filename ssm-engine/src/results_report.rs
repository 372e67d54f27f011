//! The speed-against-error report: for each expansion order, the time to build
//! the reduced model and to answer with it (backbone, FRC, transient), its
//! invariance error (eq. 41), and its error against the full-system reference
//! of `[validate]`; written as `report.csv`, `report.md` and `report.svg`
//! (time against error, one point per order, the full-system cost as lines).

use std::time::Instant;

use serde_json::{json, Value};

use crate::model::system::{OutputMap, System};
use crate::output::plot::{line_plot, Curve, PlotError, Scale};
use crate::results_frc::{self, FrcError};
use crate::results_validate::{frc_error, ValidationProducts};
use crate::scene::ForcingSection;
use crate::spectrum::MasterMode;
use crate::ssm::analysis::{amplitude, backbone_frequency, invariance_error, polar};
use crate::ssm::rom::{integrate, RomError};
use crate::ssm::{self, SsmError, SsmOptions};
use crate::C64;
use toml::Spanned;

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
    /// The plot failed.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// One reduced model of the report.
#[derive(Debug, Clone, PartialEq)]
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
    /// Largest relative FRC amplitude error against the steady-state reference.
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
    pub forcing: Option<&'a ForcingSection>,
    /// The full-system references, if any.
    pub validation: Option<&'a ValidationProducts>,
    /// Initial reduced coordinates of the validation transient.
    pub p0: Option<Vec<C64>>,
    /// Relative tolerance of the reduced transients (the full system's).
    pub rtol: f64,
}

/// Computes the rows of the report.
pub fn rows(sys: &System, inp: &ReportInputs<'_>) -> Result<Vec<ReportRow>, ReportError> {
    let mut rows = Vec::with_capacity(inp.orders.len());
    let transient = inp.validation.and_then(|v| v.transient.as_ref());
    let steady = inp.validation.and_then(|v| v.steady.as_ref());
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
            let mut sec = f.clone();
            sec.orders = Some(Spanned::new(0..0, vec![order]));
            if let Some(r) = steady {
                sec.epsilon = Spanned::new(0..0, vec![r.epsilon]);
            }
            let t = Instant::now();
            let rep = results_frc::frc(&ssm, sys, inp.masters, &sec, inp.outputs)
                .map_err(|source| ReportError::Frc { order, source })?;
            row.frc_s = Some(t.elapsed().as_secs_f64());
            if let Some(r) = steady {
                row.frc_error = frc_error(&rep.rows, r, order).0;
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
pub fn full_costs(v: Option<&ValidationProducts>) -> Vec<(String, f64)> {
    let mut out = Vec::new();
    if let Some(v) = v {
        if let Some(t) = &v.transient {
            out.push(("full transient".to_owned(), t.full_s));
        }
        if let Some(s) = &v.steady {
            out.push((
                format!("full steady state, {} frequencies", s.points.len()),
                s.wall_s,
            ));
        }
    }
    out
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, |x| format!("{x:.6e}"))
}

/// `report.csv`: `kind,order,ssm_s,backbone_s,transient_s,frc_s,invariance_error,invariance_rho,transient_error,frc_error`.
pub fn csv(rows: &[ReportRow], full: &[(String, f64)]) -> String {
    let mut s = String::from(
        "kind,order,ssm_s,backbone_s,transient_s,frc_s,invariance_error,invariance_rho,transient_error,frc_error\n",
    );
    for r in rows {
        s.push_str(&format!(
            "rom,{},{:.6e},{},{},{},{},{},{},{}\n",
            r.order,
            r.ssm_s,
            opt(r.backbone_s),
            opt(r.transient_s),
            opt(r.frc_s),
            opt(r.invariance_error),
            opt(r.invariance_rho),
            opt(r.transient_error),
            opt(r.frc_error)
        ));
    }
    for (what, secs) in full {
        let kind = if what.starts_with("full transient") {
            "full_transient"
        } else {
            "full_steady_state"
        };
        let (tr, frc) = if kind == "full_transient" {
            (format!("{secs:.6e}"), String::new())
        } else {
            (String::new(), format!("{secs:.6e}"))
        };
        s.push_str(&format!("{kind},,,,{tr},{frc},,,,\n"));
    }
    s
}

fn fmt_s(v: Option<f64>) -> String {
    match v {
        None => "-".into(),
        Some(x) if x < 1e-3 => format!("{:.1} µs", x * 1e6),
        Some(x) if x < 1.0 => format!("{:.2} ms", x * 1e3),
        Some(x) => format!("{x:.2} s"),
    }
}

fn fmt_e(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |x| format!("{x:.2e}"))
}

/// `report.md`: a table a person reads.
pub fn markdown(sys: &System, rows: &[ReportRow], full: &[(String, f64)]) -> String {
    let mut s = format!(
        "# Speed against error: {} ({} states)\n\n\
         Times are wall-clock on this machine; errors are relative to the largest \
         full-system value of each output (transient) or to the peak of the \
         steady-state reference (FRC). The invariance error is eq. (41) at the \
         amplitude of the comparison.\n\n\
         | order | SSM build | backbone | transient | FRC | invariance error (rho) | transient error | FRC error |\n\
         |---|---|---|---|---|---|---|---|\n",
        sys.name,
        sys.n_states()
    );
    for r in rows {
        s.push_str(&format!(
            "| O({}) | {} | {} | {} | {} | {} ({}) | {} | {} |\n",
            r.order,
            fmt_s(Some(r.ssm_s)),
            fmt_s(r.backbone_s),
            fmt_s(r.transient_s),
            fmt_s(r.frc_s),
            fmt_e(r.invariance_error),
            r.invariance_rho.map_or("-".into(), |x| format!("{x:.3}")),
            fmt_e(r.transient_error),
            fmt_e(r.frc_error),
        ));
    }
    if !full.is_empty() {
        s.push_str("\nFull-system references (Radau IIA on the DAE):\n\n");
        for (what, secs) in full {
            s.push_str(&format!("- {what}: {}\n", fmt_s(Some(*secs))));
        }
        if let (Some(best), Some((_, ft))) = (
            rows.iter()
                .filter(|r| r.transient_s.is_some())
                .max_by_key(|r| r.order),
            full.iter().find(|(w, _)| w.starts_with("full transient")),
        ) {
            let rom = best.ssm_s + best.transient_s.unwrap_or(0.0);
            let ratio = ft / rom.max(1e-12);
            s.push_str(&format!(
                "\nO({}) (build + transient) takes {} against {} for the full transient: {}.\n",
                best.order,
                fmt_s(Some(rom)),
                fmt_s(Some(*ft)),
                if ratio >= 1.0 {
                    format!("{ratio:.1}x faster")
                } else {
                    format!("{:.1}x slower (a small full model; the reduced model pays for its expansion)", 1.0 / ratio)
                }
            ));
        }
    }
    s
}

/// `report.svg`: time to answer against error, one point per order.
pub fn svg(rows: &[ReportRow], full: &[(String, f64)]) -> Result<String, PlotError> {
    let error = |r: &ReportRow| r.transient_error.or(r.frc_error).or(r.invariance_error);
    let time = |r: &ReportRow| {
        r.ssm_s
            + r.transient_s.unwrap_or(0.0)
            + r.frc_s.unwrap_or(0.0)
            + r.backbone_s.unwrap_or(0.0)
    };
    let mut curves: Vec<Curve> = rows
        .iter()
        .filter_map(|r| error(r).map(|e| (r, e)))
        .map(|(r, e)| Curve {
            label: format!("O({})", r.order),
            points: vec![(e, time(r))],
            markers: vec![(e, time(r))],
            ..Curve::default()
        })
        .collect();
    let errs: Vec<f64> = rows.iter().filter_map(error).filter(|e| *e > 0.0).collect();
    let (lo, hi) = (
        errs.iter().copied().fold(f64::INFINITY, f64::min),
        errs.iter().copied().fold(0.0, f64::max),
    );
    if lo.is_finite() {
        for (what, secs) in full {
            curves.push(Curve {
                label: what.clone(),
                points: vec![(lo / 2.0, *secs), (hi * 2.0, *secs)],
                dashed: true,
                ..Curve::default()
            });
        }
    }
    line_plot(
        "time to answer against error (one point per order; dashed: full system)",
        "error against the full system",
        "seconds",
        &curves,
        Scale::LogLog,
    )
}

/// The summary's `report`.
pub fn json(rows: &[ReportRow], full: &[(String, f64)]) -> Value {
    json!({
        "rows": rows.iter().map(|r| json!({
            "order": r.order,
            "ssm_s": r.ssm_s,
            "backbone_s": r.backbone_s,
            "transient_s": r.transient_s,
            "frc_s": r.frc_s,
            "invariance_error": r.invariance_error,
            "invariance_rho": r.invariance_rho,
            "transient_error": r.transient_error,
            "frc_error": r.frc_error,
        })).collect::<Vec<_>>(),
        "full_system": full.iter().map(|(w, s)| json!({"what": w, "wall_s": s})).collect::<Vec<_>>(),
    })
}
