//! The invariance error's entry of `summary.json` and its files,
//! `invariance.csv` and `invariance.svg`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::plot::{line_plot, Curve, PlotError, Scale};
use ssm_core::rom::autonomous::InvarianceEntry;

/// One row of `"invariance_error"` of `summary.json` (eq. 41).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InvarianceSummary {
    /// Expansion order.
    pub order: usize,
    /// Radius `rho` of the circle of reduced coordinates.
    pub radius: f64,
    /// Relative invariance error there.
    pub error: f64,
}

impl InvarianceSummary {
    /// One entry per row of `rows`.
    pub fn new(rows: &[InvarianceEntry]) -> Vec<Self> {
        rows.iter()
            .map(|r| InvarianceSummary {
                order: r.order,
                radius: r.radius,
                error: r.error,
            })
            .collect()
    }
}

/// `invariance.csv`: `order,radius,error`, one row per order and radius
/// (eq. 41; Fig. 21 of Li, Jain & Haller 2023).
pub(super) fn invariance_csv(rows: &[InvarianceSummary]) -> String {
    let mut csv = String::from("order,radius,error\n");
    for r in rows {
        csv.push_str(&format!("{},{:.10e},{:.10e}\n", r.order, r.radius, r.error));
    }
    csv
}

/// `invariance.svg`: the invariance error against the radius, one curve per
/// order, logarithmic axes.
pub(super) fn invariance_svg(rows: &[InvarianceSummary]) -> Result<String, PlotError> {
    let mut orders: Vec<usize> = rows.iter().map(|r| r.order).collect();
    orders.sort_unstable();
    orders.dedup();
    let drawn: Vec<Curve> = orders
        .iter()
        .map(|&o| Curve {
            label: format!("O({o})"),
            points: rows
                .iter()
                .filter(|r| r.order == o)
                .map(|r| (r.radius, r.error))
                .collect(),
            ..Curve::default()
        })
        .collect();
    line_plot(
        "invariance error (eq. 41)",
        "radius rho",
        "relative invariance error",
        &drawn,
        Scale::LogLog,
    )
}
