//! `damping.csv` and `damping.svg`.

use super::DampingCurves;
use crate::csv::push_row_end;
use crate::plot::estimate_label;
use crate::plot::{stacked_plot, Curve, Panel, PlotError, Scale};

/// `damping.csv`: `order,rho,omega,decay_rate,zeta,<output>...,error_estimate`
/// (the last empty where there is no estimate).
pub(super) fn csv(d: &DampingCurves, outputs: &[String]) -> String {
    let mut csv = String::from("order,rho,omega,decay_rate,zeta");
    for o in outputs {
        csv.push(',');
        csv.push_str(o);
    }
    csv.push_str(",error_estimate\n");
    for c in &d.curves {
        for p in &c.points {
            csv.push_str(&format!(
                "{},{:.10e},{:.10e},{:.10e},{:.10e}",
                c.order, p.rho, p.omega, p.decay_rate, p.zeta
            ));
            push_row_end(&mut csv, &p.amplitudes, p.error_estimate);
        }
    }
    csv
}

/// `damping.svg`: the backbone `omega` above and the damping ratio `zeta`
/// below, against the amplitude of the first output (`rho` without
/// outputs), one colour per order; the part of a curve beyond the amplitude
/// up to which its estimate meets the tolerance is dashed.
pub(super) fn svg(d: &DampingCurves, outputs: &[String]) -> Result<String, PlotError> {
    let x = |p: &super::DampingPoint| p.amplitudes.first().copied().unwrap_or(p.rho);
    let curves = |y: fn(&super::DampingPoint) -> f64| -> Vec<Curve> {
        let mut drawn = Vec::new();
        for (k, c) in d.curves.iter().enumerate() {
            let limit = c.trusted_up_to.unwrap_or(f64::INFINITY);
            let trusted = c.points.iter().filter(|p| p.rho <= limit);
            drawn.push(Curve {
                label: estimate_label(c.order, c.error_estimate, c.untrusted),
                points: trusted.map(|p| (x(p), y(p))).collect(),
                color: Some(k),
                ..Curve::default()
            });
            // the untrusted part, from the last trusted point on
            let from = c.points.iter().rposition(|p| p.rho <= limit).unwrap_or(0);
            if from + 1 < c.points.len() {
                drawn.push(Curve {
                    label: String::new(),
                    points: c.points[from..].iter().map(|p| (x(p), y(p))).collect(),
                    dashed: true,
                    color: Some(k),
                    ..Curve::default()
                });
            }
        }
        drawn
    };
    let x_label = outputs
        .first()
        .map_or_else(|| "rho".to_owned(), |o| format!("amplitude of {o}"));
    let (top, bottom) = (curves(|p| p.omega), curves(|p| p.zeta));
    stacked_plot(
        &[
            Panel {
                title: "backbone",
                x_label: &x_label,
                y_label: "omega",
                curves: &top,
                scale: Scale::Linear,
            },
            Panel {
                title: "damping (dashed: beyond the accuracy target)",
                x_label: &x_label,
                y_label: "zeta = -rho' / (rho omega)",
                curves: &bottom,
                scale: Scale::Linear,
            },
        ],
        480,
    )
}
