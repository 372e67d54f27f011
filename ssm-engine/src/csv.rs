//! CSV rows shared by the writers of curves (backbone, damping).

/// The end of a curve point's CSV row: its output amplitudes (`,%.10e`
/// each), then `,` and its error estimate (`%.3e`; empty when there is none
/// or it is not finite), then the newline.
pub(crate) fn push_row_end(csv: &mut String, amplitudes: &[f64], estimate: Option<f64>) {
    for a in amplitudes {
        csv.push_str(&format!(",{a:.10e}"));
    }
    csv.push(',');
    if let Some(e) = estimate.filter(|e| e.is_finite()) {
        csv.push_str(&format!("{e:.3e}"));
    }
    csv.push('\n');
}
