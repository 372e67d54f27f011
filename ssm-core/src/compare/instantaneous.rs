//! Backbones read directly off decaying signals, independent of any model:
//! the instantaneous amplitude and frequency of each signal by zero crossings
//! and by the Hilbert transform, as overlaid on the SSM backbones in Fig. 4
//! of Szalai, Ehrhardt & Haller (2017).
//!
//! - **Zero crossings**: upward crossings are located by linear
//!   interpolation; each cycle between two of them gives `omega = 2 pi /`
//!   (its duration) at the largest `|y|` within it.
//! - **Hilbert transform** (Feldman 1997): the analytic signal
//!   `y + i H[y]` by FFT (negative frequencies removed, positive doubled)
//!   of the signal divided by a smooth envelope (the cycles' peaks, log-linear
//!   in time), multiplied back afterwards;
//!   its modulus is the envelope and the derivative of its unwrapped phase
//!   the instantaneous frequency, both averaged over each cycle (between
//!   upward crossings) to suppress the modulation a second harmonic or a
//!   slightly decaying envelope leaves; the damping ratio
//!   `zeta = -A' / (A omega)` from the cycle means of neighbouring cycles. The cycles in the first and last
//!   5 % of the record (at least two) are dropped: the FFT's periodic
//!   extension distorts the ends.
//!
//! Both assume one dominant frequency in the signal: a signal started near
//! one SSM after its faster modes have decayed.
//!
//! # References
//! M. Feldman, *Non-linear free vibration identification via the Hilbert
//! transform*, J. Sound Vib. 208 (1997) 475-489; R. Szalai, D. Ehrhardt,
//! G. Haller, Proc. R. Soc. A 473 (2017) 20160759, Sect. 9b and Fig. 4.

use std::f64::consts::PI;

use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

/// How a data-based backbone was read off a signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Periods between upward zero crossings.
    ZeroCrossings,
    /// Envelope and phase of the analytic signal.
    Hilbert,
}

impl Method {
    /// Name used in files.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::ZeroCrossings => "zero_crossings",
            Self::Hilbert => "hilbert",
        }
    }
}

/// Instantaneous `(amplitude, omega)` points of one signal, one per cycle.
#[derive(Debug, Clone, PartialEq, serde::Serialize, schemars::JsonSchema)]
pub struct DataBackbone {
    /// Method used.
    pub method: Method,
    /// Where the signal came from (file).
    pub source: String,
    /// Points, in time order (amplitude decreasing for a decaying signal).
    pub points: Vec<(f64, f64)>,
}

/// Times of the upward zero crossings of `y` sampled at period `dt`.
fn upward_crossings(y: &[f64], dt: f64) -> Vec<f64> {
    y.windows(2)
        .enumerate()
        .filter(|(_, w)| w[0] < 0.0 && w[1] >= 0.0)
        .map(|(k, w)| (k as f64 + w[0] / (w[0] - w[1])) * dt)
        .collect()
}

/// Largest `|y|` within samples `a..=b`, refined by the parabola through the
/// largest sample and its neighbours (a few samples per cycle put the
/// largest sample up to `1 - cos(pi / samples)` below the peak).
fn peak(y: &[f64], a: usize, b: usize) -> f64 {
    let b = b.min(y.len() - 1);
    let a = a.min(b);
    let (k, _) = (a..=b).fold((a, 0.0f64), |(bk, bv), k| {
        if y[k].abs() > bv {
            (k, y[k].abs())
        } else {
            (bk, bv)
        }
    });
    if k == 0 || k + 1 >= y.len() {
        return y[k].abs();
    }
    let (l, c, r) = (y[k - 1].abs(), y[k].abs(), y[k + 1].abs());
    let curvature = l - 2.0 * c + r;
    if curvature >= 0.0 {
        return c;
    }
    let d = 0.5 * (l - r) / curvature;
    if d.abs() > 1.0 {
        return c;
    }
    c - 0.25 * (l - r) * d
}

/// The zero-crossing backbone of `y` (sampling period `dt`).
pub(crate) fn zero_crossing_backbone(y: &[f64], dt: f64) -> Vec<(f64, f64)> {
    let up = upward_crossings(y, dt);
    up.windows(2)
        .filter(|c| c[1] > c[0])
        .map(|c| {
            let (a, b) = ((c[0] / dt).ceil() as usize, (c[1] / dt).floor() as usize);
            (peak(y, a, b), 2.0 * PI / (c[1] - c[0]))
        })
        .collect()
}

/// The Hilbert-transform backbone of `y` (sampling period `dt`): the
/// `(amplitude, omega)` of each [`hilbert_cycles`] cycle.
pub(crate) fn hilbert_backbone(y: &[f64], dt: f64) -> Vec<(f64, f64)> {
    hilbert_cycles(y, dt)
        .iter()
        .map(|c| (c.amplitude, c.omega))
        .collect()
}

/// One cycle of a decaying signal read by the Hilbert transform (between two
/// upward zero crossings).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HilbertCycle {
    /// Mid-cycle time.
    pub time: f64,
    /// Envelope averaged over the cycle.
    pub amplitude: f64,
    /// Instantaneous frequency averaged over the cycle (phase advance over
    /// its duration).
    pub omega: f64,
    /// Damping ratio `zeta = -A' / (A omega)` at the cycle, `A' / A` from the
    /// amplitudes of the neighbouring cycles (NaN for a lone cycle); the convention of
    /// the SSM's `zeta(rho) = -rho' / (rho omega)`, `delta / (2 pi)` for
    /// a logarithmic decrement `delta` per period.
    pub zeta: f64,
}

/// The Hilbert-transform reading of `y` (sampling period `dt`), one
/// [`HilbertCycle`] per full cycle away from the record's ends.
pub fn hilbert_cycles(y: &[f64], dt: f64) -> Vec<HilbertCycle> {
    let n = y.len();
    if n < 8 {
        return Vec::new();
    }
    // the signal is first divided by a smooth envelope (the per-cycle peaks,
    // interpolated in log): transformed as it is, the leakage of a decaying
    // record's large start swamps its small end
    let up = upward_crossings(y, dt);
    let mut knots: Vec<(f64, f64)> = up
        .windows(2)
        .filter(|c| c[1] > c[0])
        .map(|c| {
            let (a, b) = ((c[0] / dt).ceil() as usize, (c[1] / dt).floor() as usize);
            (0.5 * (c[0] + c[1]), peak(y, a, b))
        })
        .filter(|k| k.1 > 0.0)
        .map(|(t, p)| (t, p.ln()))
        .collect();
    knots.dedup_by(|b, a| b.0 <= a.0);
    let envelope_at = |t: f64| -> f64 {
        match knots.len() {
            0 => 1.0,
            1 => knots[0].1.exp(),
            _ => {
                let i = knots.partition_point(|k| k.0 < t).clamp(1, knots.len() - 1);
                let (a, b) = (knots[i - 1], knots[i]);
                let s = ((t - a.0) / (b.0 - a.0)).clamp(-1.0, 2.0);
                (a.1 + s * (b.1 - a.1)).exp()
            }
        }
    };
    let env: Vec<f64> = (0..n).map(|k| envelope_at(k as f64 * dt)).collect();
    let mut z: Vec<Complex<f64>> = y
        .iter()
        .zip(&env)
        .map(|(&v, e)| Complex::new(v / e, 0.0))
        .collect();
    let mut planner = FftPlanner::new();
    planner.plan_fft_forward(n).process(&mut z);
    // analytic signal: keep DC (and Nyquist for even n), double the positive half
    for (k, c) in z.iter_mut().enumerate() {
        let positive = k > 0 && 2 * k < n;
        let negative = 2 * k > n;
        if positive {
            *c *= 2.0;
        } else if negative {
            *c = Complex::new(0.0, 0.0);
        }
    }
    planner.plan_fft_inverse(n).process(&mut z);
    let scale = 1.0 / n as f64;
    let envelope: Vec<f64> = z
        .iter()
        .zip(&env)
        .map(|(c, e)| c.norm() * scale * e)
        .collect();
    let mut phase: Vec<f64> = z.iter().map(|c| c.im.atan2(c.re)).collect();
    for k in 1..n {
        let d = phase[k] - phase[k - 1];
        phase[k] -= 2.0 * PI * (d / (2.0 * PI)).round();
    }
    let cycles: Vec<(usize, usize)> = up
        .windows(2)
        .map(|c| ((c[0] / dt).ceil() as usize, (c[1] / dt).floor() as usize))
        .filter(|(a, b)| b > a && *b < n)
        .collect();
    // the periodic extension of the FFT joins the record's large start to its
    // small end: the ringing reaches a few per cent of the record inwards
    let margin = n / 20;
    let keep = cycles.len().saturating_sub(2);
    let cycles: Vec<HilbertCycle> = cycles
        .iter()
        .take(keep)
        .skip(2)
        .filter(|(a, b)| *a >= margin && *b + margin < n)
        .map(|&(a, b)| {
            let span = (b - a) as f64 * dt;
            let omega = (phase[b] - phase[a]) / span;
            HilbertCycle {
                time: 0.5 * (a + b) as f64 * dt,
                amplitude: envelope[a..=b].iter().sum::<f64>() / (b - a + 1) as f64,
                omega,
                zeta: f64::NAN,
            }
        })
        .collect::<Vec<_>>();
    // the envelope's decay rate from the cycle means of its neighbours
    // (central differences of ln A; one-sided at the ends): the means are
    // smooth where single samples of the envelope carry a ripple
    let n = cycles.len();
    let mut out = cycles.clone();
    for (k, c) in out.iter_mut().enumerate() {
        let (i, j) = (k.saturating_sub(1), (k + 1).min(n - 1));
        if i == j {
            continue;
        }
        let rate =
            (cycles[j].amplitude / cycles[i].amplitude).ln() / (cycles[j].time - cycles[i].time);
        c.zeta = -rate / c.omega;
    }
    out
}

/// Both data-based backbones of each signal `(source, samples)` with
/// sampling period `dt`.
pub fn data_backbones(signals: &[(String, Vec<f64>)], dt: f64) -> Vec<DataBackbone> {
    let mut out = Vec::new();
    for (source, y) in signals {
        out.push(DataBackbone {
            method: Method::ZeroCrossings,
            source: source.clone(),
            points: zero_crossing_backbone(y, dt),
        });
        out.push(DataBackbone {
            method: Method::Hilbert,
            source: source.clone(),
            points: hilbert_backbone(y, dt),
        });
    }
    out
}

/// The points of each backbone within the fraction `rel` of `omega0` (the
/// parts of the signals that decay along the SSM whose backbone they are
/// compared with; the rest belongs to other modes, or to the noise of the
/// signal's tail); backbones left empty are dropped.
pub fn near_frequency(list: Vec<DataBackbone>, omega0: f64, rel: f64) -> Vec<DataBackbone> {
    list.into_iter()
        .map(|mut d| {
            d.points.retain(|p| (p.1 - omega0).abs() <= rel * omega0);
            d
        })
        .filter(|d| !d.points.is_empty())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A decaying chirp `a(t) cos(phi(t))` with known `a` and `phi' = omega(t)`:
    /// both methods recover `omega` against `a` to 1e-3 at 125 samples per
    /// cycle; at 8 (the sampling of Sect. 9a, `T = 0.8`) zero crossings to
    /// 5e-3 and the Hilbert transform to 2e-3 (without the envelope division
    /// it is off by 1.5e-2 at 2.6 % of the starting amplitude).
    #[test]
    fn recover_a_known_amplitude_frequency_law() {
        for (dt, tol_zc, tol_h) in [(0.05, 1e-3, 1e-3), (0.8, 5e-3, 2e-3)] {
            let n = (2000.0 / dt) as usize;
            // omega = 1 + 0.2 a^2, a = e^{-0.002 t}
            let a = |t: f64| (-0.002 * t).exp();
            let mut y = Vec::with_capacity(n);
            // the phase on a fine grid, sampled every dt
            let fine = 200;
            let h = dt / fine as f64;
            let mut phi = 0.0f64;
            for k in 0..n {
                let t = k as f64 * dt;
                y.push(a(t) * phi.cos());
                for j in 0..fine {
                    let tm = t + (j as f64 + 0.5) * h;
                    phi += h * (1.0 + 0.2 * a(tm) * a(tm));
                }
            }
            // the damping ratio -a'/(a omega) = 0.002 / omega: 0.19 % at 125
            // samples per cycle, 2.3 % at 8 (measured)
            let tol_zeta = if dt < 0.1 { 5e-3 } else { 3e-2 };
            for c in hilbert_cycles(&y, dt) {
                let exact = 0.002 / (1.0 + 0.2 * (-0.004 * c.time).exp());
                assert!(
                    (c.zeta / exact - 1.0).abs() < tol_zeta,
                    "dt = {dt}, t = {}: zeta {} vs {exact}",
                    c.time,
                    c.zeta
                );
            }
            for (name, pts, tol) in [
                ("zero crossings", zero_crossing_backbone(&y, dt), tol_zc),
                ("hilbert", hilbert_backbone(&y, dt), tol_h),
            ] {
                assert!(pts.len() > 100, "{name}: {} points", pts.len());
                for &(amp, w) in pts.iter().skip(3).take(pts.len() - 6) {
                    let exact = 1.0 + 0.2 * amp * amp;
                    assert!(
                        (w - exact).abs() < tol,
                        "{name}, dt = {dt}: a = {amp}: {w} vs {exact}"
                    );
                }
            }
        }
    }
}
