//! The backbone's files: `backbone.csv`, `backbone.svg` and, with `[data]`
//! signals, `data_backbone.csv`.

use crate::csv::push_row_end;
use crate::plot::{estimate_label, line_plot, Curve, PlotError, Scale};
use ssm_core::compare::instantaneous::{DataBackbone, Method};
use ssm_core::rom::autonomous::{BackboneCurve, BackbonePoint};

/// `backbone.csv`: `order,rho,omega,<output>...,error_estimate` (the last
/// empty where there is no estimate).
pub(super) fn backbone_csv(curves: &[BackboneCurve], outputs: &[String]) -> String {
    let mut csv = String::from("order,rho,omega");
    for o in outputs {
        csv.push(',');
        csv.push_str(o);
    }
    csv.push_str(",error_estimate\n");
    for c in curves {
        for p in &c.points {
            csv.push_str(&format!("{},{:.10e},{:.10e}", c.order, p.rho, p.omega));
            push_row_end(&mut csv, &p.amplitudes, p.error_estimate);
        }
    }
    csv
}

/// `data_backbone.csv`: `method,source,amplitude,omega`, the backbones read
/// off the `[data]` signals.
pub(super) fn data_backbone_csv(data: &[DataBackbone]) -> String {
    let mut csv = String::from("method,source,amplitude,omega\n");
    for d in data {
        for (a, w) in &d.points {
            csv.push_str(&format!(
                "{},{},{a:.10e},{w:.10e}\n",
                d.method.as_str(),
                d.source.replace(',', ";")
            ));
        }
    }
    csv
}

/// `backbone.svg`: omega against the amplitude of the first output (or
/// against `rho` without outputs), one curve per order (the part beyond the
/// amplitude up to which its estimate meets the accuracy target dashed, in
/// the same colour, as an entry of its own), and the backbones read off the
/// `[data]` signals (zero crossings as markers, Hilbert dashed).
pub(super) fn backbone_svg(
    curves: &[BackboneCurve],
    data: &[DataBackbone],
    outputs: &[String],
) -> Result<String, PlotError> {
    let n = curves.len();
    let mut drawn: Vec<Curve> = Vec::with_capacity(2 * n + data.len());
    for (k, c) in curves.iter().enumerate() {
        let xy = |p: &BackbonePoint| (p.amplitudes.first().copied().unwrap_or(p.rho), p.omega);
        // the part beyond the accuracy target: dashed, in the curve's
        // colour, its own legend entry (the whole curve when no amplitude
        // meets the target)
        let trusted =
            |p: &BackbonePoint| !c.untrusted || c.trusted_up_to.is_some_and(|r| p.rho <= r);
        let kept: Vec<(f64, f64)> = c.points.iter().filter(|p| trusted(p)).map(xy).collect();
        let mut beyond: Vec<(f64, f64)> = c.points.iter().filter(|p| !trusted(p)).map(xy).collect();
        if let (Some(&last), false) = (kept.last(), beyond.is_empty()) {
            beyond.insert(0, last);
        }
        if !kept.is_empty() {
            drawn.push(Curve {
                label: estimate_label(c.order, c.error_estimate, c.untrusted),
                points: kept,
                color: Some(k),
                ..Curve::default()
            });
        }
        if !beyond.is_empty() {
            drawn.push(Curve {
                label: format!("O({}) beyond the accuracy target", c.order),
                points: beyond,
                dashed: true,
                color: Some(k),
                ..Curve::default()
            });
        }
    }
    for (k, d) in data.iter().enumerate() {
        let file = std::path::Path::new(&d.source)
            .file_name()
            .map_or(d.source.clone(), |f| f.to_string_lossy().into_owned());
        let label = format!("{} of {file}", d.method.as_str().replace('_', " "));
        drawn.push(match d.method {
            Method::ZeroCrossings => Curve {
                label,
                markers: d.points.clone(),
                color: Some(n + k),
                ..Curve::default()
            },
            Method::Hilbert => Curve {
                label,
                points: d.points.clone(),
                dashed: true,
                color: Some(n + k),
                ..Curve::default()
            },
        });
    }
    let x_label = outputs
        .first()
        .map_or_else(|| "rho".to_owned(), |o| format!("amplitude of {o}"));
    line_plot("backbone", &x_label, "omega", &drawn, Scale::Linear)
}
