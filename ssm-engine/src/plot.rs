//! SVG line plots of backbones, trajectories and error curves (plotters, SVG
//! backend; text is emitted as SVG text, no font files are needed).

use plotters::prelude::*;
use ssm_core::rom::accuracy::percent;

/// A plot that could not be drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("plot '{title}': {message}")]
pub struct PlotError {
    /// Plot title.
    pub title: String,
    /// What failed.
    pub message: String,
}

/// One labelled curve.
#[derive(Debug, Clone, Default)]
pub struct Curve {
    /// Legend label (curves with an empty label stay out of the legend).
    pub label: String,
    /// Points `(x, y)`; non-finite points are skipped.
    pub points: Vec<(f64, f64)>,
    /// Drawn dashed (e.g. unstable FRC branches).
    pub dashed: bool,
    /// Marked points (e.g. bifurcations), drawn as circles.
    pub markers: Vec<(f64, f64)>,
    /// Colour index shared by related curves (`None`: the curve's position).
    pub color: Option<usize>,
    /// A full-system reference: drawn first, thick and pale, beneath the
    /// reduced model's curves, which stay visible where the two coincide.
    pub full: bool,
}

/// Axis scaling.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear axes.
    Linear,
    /// Logarithmic x and y axes (non-positive values are skipped).
    LogLog,
    /// Linear x axis, logarithmic y axis (non-positive values of y are
    /// skipped), e.g. an error over time.
    LogY,
}

impl Scale {
    /// Whether the x and the y axes are logarithmic.
    fn logs(self) -> (bool, bool) {
        match self {
            Scale::Linear => (false, false),
            Scale::LogLog => (true, true),
            Scale::LogY => (false, true),
        }
    }
}

fn range(vals: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        if hi <= lo {
            return (lo / 2.0, hi * 2.0);
        }
        return (lo / 1.2, hi * 1.2);
    }
    let pad = if hi > lo {
        0.04 * (hi - lo)
    } else {
        0.5 * lo.abs().max(1.0)
    };
    (lo - pad, hi + pad)
}

/// A tick label: short decimals for moderate values, scientific otherwise
/// (log axes produce ticks such as 0.30000000000000004); a value within
/// round-off of zero on an axis spanning `span` is `0` (not `-5.6e-17`).
fn tick(v: f64, span: f64) -> String {
    let a = v.abs();
    if v == 0.0 || a <= 1e-9 * span {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.6}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        format!("{v:.1e}")
    }
}

/// Width of the legend column beside each panel's axes (pixels).
const LEGEND_WIDTH: u32 = 250;

/// Characters of a legend line before it wraps.
const LEGEND_CHARS: usize = 36;

/// `label` wrapped at spaces into lines of at most [`LEGEND_CHARS`].
fn wrap(label: &str) -> Vec<String> {
    let mut lines = vec![String::new()];
    for word in label.split_whitespace() {
        let line = lines.last_mut().expect("one line at least");
        if !line.is_empty() && line.len() + 1 + word.len() > LEGEND_CHARS {
            lines.push(word.to_owned());
        } else {
            if !line.is_empty() {
                line.push(' ');
            }
            line.push_str(word);
        }
    }
    lines
}

/// The stroke of curve `i` (its position, the colour when it names none),
/// the `rank`-th of the `n` reduced-model curves of a plot with or without
/// full-system curves (`beside_full`): full-system curves thick and pale,
/// the reduced ones over them 1 px wide; without them, the `n` reduced
/// curves narrow by a pixel each from the first to the last (at most 6 px,
/// at least 1 px; 2 px for a single curve), so that a curve drawn over an
/// earlier one leaves the earlier one's edges visible.
fn stroke(c: &Curve, i: usize, rank: usize, n: usize, beside_full: bool) -> ShapeStyle {
    let color = Palette99::pick(c.color.unwrap_or(i));
    if c.full {
        color.mix(0.4).stroke_width(5)
    } else if beside_full {
        color.stroke_width(1)
    } else if n == 1 {
        color.stroke_width(2)
    } else {
        color.stroke_width(n.saturating_sub(rank).clamp(1, 6) as u32)
    }
}

/// One panel of a [`stacked_plot`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct Panel<'a> {
    /// Panel title.
    pub title: &'a str,
    /// Name of the x axis.
    pub x_label: &'a str,
    /// Name of the y axis.
    pub y_label: &'a str,
    /// The curves drawn.
    pub curves: &'a [Curve],
    /// Axis scaling.
    pub scale: Scale,
}

/// Draws `curves` into an SVG document (800 x 560) with axis names and a legend.
pub fn line_plot(
    title: &str,
    x_label: &str,
    y_label: &str,
    curves: &[Curve],
    scale: Scale,
) -> Result<String, PlotError> {
    let panel = Panel {
        title,
        x_label,
        y_label,
        curves,
        scale,
    };
    stacked_plot(&[panel], 560)
}

/// Draws `panels` one above the other into an SVG document 800 wide and
/// `height` per panel high, each with its axis names and legend.
pub(crate) fn stacked_plot(panels: &[Panel<'_>], height: u32) -> Result<String, PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError {
        title: panels.first().map_or("", |p| p.title).to_owned(),
        message: e.to_string(),
    };
    let mut svg = String::new();
    {
        let n = panels.len().max(1) as u32;
        let root = SVGBackend::with_string(&mut svg, (800, height * n)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        for (area, panel) in root.split_evenly((panels.len(), 1)).iter().zip(panels) {
            // the legend beside the axes, never over the curves
            let (plot, legend) = area.split_horizontally(800 - LEGEND_WIDTH);
            draw_panel(&plot, panel)?;
            draw_legend(&legend, panel.curves).map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(svg)
}

/// Draws one panel into `root`.
fn draw_panel(
    root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    panel: &Panel<'_>,
) -> Result<(), PlotError> {
    let Panel {
        title,
        x_label,
        y_label,
        curves,
        scale,
    } = *panel;
    let fail = |e: &dyn std::fmt::Display| PlotError {
        title: title.to_owned(),
        message: e.to_string(),
    };
    let (log_x, log_y) = scale.logs();
    let keep = |p: &&(f64, f64)| {
        p.0.is_finite() && p.1.is_finite() && (!log_x || p.0 > 0.0) && (!log_y || p.1 > 0.0)
    };
    let xs = range(
        curves
            .iter()
            .flat_map(|c| c.points.iter().chain(&c.markers).filter(keep).map(|p| p.0)),
        log_x,
    );
    let ys = range(
        curves
            .iter()
            .flat_map(|c| c.points.iter().chain(&c.markers).filter(keep).map(|p| p.1)),
        log_y,
    );
    {
        let mut builder = ChartBuilder::on(root);
        builder
            .caption(title, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(x_label)
                    .y_desc(y_label)
                    .x_label_formatter(&|v| tick(*v, xs.1 - xs.0))
                    .y_label_formatter(&|v| tick(*v, ys.1 - ys.0))
                    .draw()
                    .map_err(|e| fail(&e))?;
                let beside_full = curves.iter().any(|c| c.full);
                let n = curves
                    .iter()
                    .filter(|c| !c.full && !c.points.is_empty())
                    .count();
                // the full system first, beneath the reduced model
                let order = curves
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| c.full)
                    .chain(curves.iter().enumerate().filter(|(_, c)| !c.full));
                let mut rank = 0;
                for (i, c) in order {
                    let style = stroke(c, i, rank, n, beside_full);
                    if !c.full && !c.points.is_empty() {
                        rank += 1;
                    }
                    let pts = c.points.iter().filter(keep).copied();
                    if c.dashed {
                        chart.draw_series(DashedLineSeries::new(pts, 8, 5, style))
                    } else {
                        chart.draw_series(LineSeries::new(pts, style))
                    }
                    .map_err(|e| fail(&e))?;
                    chart
                        .draw_series(
                            c.markers
                                .iter()
                                .filter(keep)
                                .map(|&p| Circle::new(p, 5, style.color.stroke_width(3))),
                        )
                        .map_err(|e| fail(&e))?;
                }
            }};
        }
        if log_x {
            draw!(builder
                .build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale())
                .map_err(|e| fail(&e))?);
        } else if log_y {
            draw!(builder
                .build_cartesian_2d(xs.0..xs.1, (ys.0..ys.1).log_scale())
                .map_err(|e| fail(&e))?);
        } else {
            draw!(builder
                .build_cartesian_2d(xs.0..xs.1, ys.0..ys.1)
                .map_err(|e| fail(&e))?);
        }
    }
    Ok(())
}

/// The legend of `curves` in the column `area` beside the axes: a sample
/// of each labelled curve's line (or marker) and its label, wrapped.
fn draw_legend(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    curves: &[Curve],
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    let font = ("sans-serif", 13).into_font();
    let mut y = 60;
    for (i, c) in curves
        .iter()
        .enumerate()
        .filter(|(_, c)| !c.label.is_empty())
    {
        let style = if c.full {
            stroke(c, i, 0, 1, true)
        } else {
            Palette99::pick(c.color.unwrap_or(i)).stroke_width(3)
        };
        if c.points.is_empty() {
            area.draw(&Circle::new((18, y + 7), 5, style.color.stroke_width(3)))?;
        } else if c.dashed {
            area.draw(&PathElement::new(vec![(4, y + 7), (14, y + 7)], style))?;
            area.draw(&PathElement::new(vec![(20, y + 7), (30, y + 7)], style))?;
        } else {
            area.draw(&PathElement::new(vec![(4, y + 7), (30, y + 7)], style))?;
        }
        for line in wrap(&c.label) {
            area.draw(&Text::new(line, (38, y), font.clone()))?;
            y += 16;
        }
        y += 6;
    }
    Ok(())
}

/// A curve's legend: its order, estimate and, above the target, a warning.
pub(crate) fn estimate_label(order: usize, estimate: Option<f64>, untrusted: bool) -> String {
    let mut label = format!("O({order})");
    if let Some(e) = estimate {
        label.push_str(&format!(", estimated error {}", percent(e)));
    }
    if untrusted {
        label.push_str("  UNTRUSTED: error estimate above [ssm] tolerance");
    }
    label
}
