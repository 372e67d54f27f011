//! Writers of the speed-against-error report: `report.csv`, `report.md`,
//! `report.svg` and the summary's `report`. They format a [`Report`] and
//! compute nothing.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::plot::{line_plot, Curve, PlotError, Scale};
use ssm_core::compare::report::{FullKind, Report, ReportRow};

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, |x| format!("{x:.6e}"))
}

/// `report.csv`: `kind,order,ssm_s,backbone_s,transient_s,frc_s,invariance_error,invariance_rho,transient_error,frc_error`.
pub fn csv(report: &Report) -> String {
    let mut s = String::from(
        "kind,order,ssm_s,backbone_s,transient_s,frc_s,invariance_error,invariance_rho,transient_error,frc_error\n",
    );
    for r in &report.rows {
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
    for f in &report.full {
        let secs = f.wall_s;
        let (kind, tr, frc) = match f.kind {
            FullKind::Transient => ("full_transient", format!("{secs:.6e}"), String::new()),
            FullKind::SteadyState => ("full_steady_state", String::new(), format!("{secs:.6e}")),
            FullKind::HarmonicBalance => (
                "full_harmonic_balance",
                String::new(),
                format!("{secs:.6e}"),
            ),
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
pub(crate) fn markdown(model: &str, n_states: usize, report: &Report) -> String {
    let mut s = format!(
        "# Speed against error: {} ({} states)\n\n\
         Times are wall-clock on this machine; errors are relative to the largest \
         full-system value of each output (transient) or to the peak of the \
         steady-state reference (FRC). The invariance error is eq. (41) at the \
         amplitude of the comparison.\n\n\
         | order | SSM build | backbone | transient | FRC | invariance error (rho) | transient error | FRC error |\n\
         |---|---|---|---|---|---|---|---|\n",
        model, n_states
    );
    for r in &report.rows {
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
    if !report.full.is_empty() {
        s.push_str("\nFull-system references (Radau IIA on the DAE):\n\n");
        for f in &report.full {
            s.push_str(&format!("- {}: {}\n", f.what, fmt_s(Some(f.wall_s))));
        }
        if let Some(sp) = &report.speedup {
            s.push_str(&format!(
                "\nO({}) (build + transient) takes {} against {} for the full transient: {}.\n",
                sp.order,
                fmt_s(Some(sp.rom_s)),
                fmt_s(Some(sp.full_s)),
                if sp.ratio >= 1.0 {
                    format!("{:.1}x faster", sp.ratio)
                } else {
                    format!("{:.1}x slower (a small full model; the reduced model pays for its expansion)", 1.0 / sp.ratio)
                }
            ));
        }
    }
    s
}

/// `report.svg`: time to answer against error, one point per order.
pub fn svg(report: &Report) -> Result<String, PlotError> {
    let mut curves: Vec<Curve> = report
        .rows
        .iter()
        .filter_map(|r| r.error().map(|e| (r, e)))
        .map(|(r, e)| Curve {
            label: format!("O({})", r.order),
            points: vec![(e, r.answer_s())],
            markers: vec![(e, r.answer_s())],
            ..Curve::default()
        })
        .collect();
    let errs = report
        .rows
        .iter()
        .filter_map(|r| r.error())
        .filter(|e| *e > 0.0);
    let (lo, hi) = errs.fold((f64::INFINITY, 0.0f64), |(lo, hi), e| {
        (lo.min(e), hi.max(e))
    });
    if lo.is_finite() {
        for f in &report.full {
            curves.push(Curve {
                label: f.what.clone(),
                points: vec![(lo / 2.0, f.wall_s), (hi * 2.0, f.wall_s)],
                dashed: true,
                full: true,
                ..Curve::default()
            });
        }
    }
    line_plot(
        "time to answer against error (one point per order; dashed, pale: full system)",
        "error against the full system",
        "seconds",
        &curves,
        Scale::LogLog,
    )
}

/// `"report"` of `summary.json`: each reduced model's cost and error, and
/// the full-system runs they are measured against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ReportSummary {
    /// One reduced model (expansion order) a row.
    pub rows: Vec<ReportRow>,
    /// The full-system runs.
    pub full_system: Vec<FullCostSummary>,
}

/// A full-system run of the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FullCostSummary {
    /// What ran.
    pub what: String,
    /// Wall time in seconds.
    pub wall_s: f64,
}

impl ReportSummary {
    /// The summary of `report`.
    pub fn new(report: &Report) -> Self {
        ReportSummary {
            rows: report.rows.clone(),
            full_system: report
                .full
                .iter()
                .map(|f| FullCostSummary {
                    what: f.what.clone(),
                    wall_s: f.wall_s,
                })
                .collect(),
        }
    }
}
