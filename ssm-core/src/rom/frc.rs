//! Forced response curves (FRCs) of a two-dimensional SSM: fixed points of the
//! reduced dynamics in the rotating frame, their stability and bifurcations.
//!
//! With one master pair, external resonance ratio `r = 1`, the normal-form
//! reduced dynamics `p' = p g(|p|^2) + eps s e^{i Omega t}`,
//! `g(u) = sum_j c_j u^j` (`c_0 = lambda`, the backbone coefficients of
//! [`crate::ssm::analysis::Polar`]), become autonomous for
//! `p = q e^{i Omega t}`:
//!
//! `q' = G(q) = q (g(|q|^2) - i Omega) + eps s`.
//!
//! A fixed point with `|q| = rho`, `g = alpha + i beta` satisfies
//! `rho^2 (alpha^2 + (beta - Omega)^2) = eps^2 |s|^2`, so every branch is given
//! explicitly by the amplitude equation
//! `Omega = beta(rho) -+ sqrt(eps^2 |s|^2 / rho^2 - alpha(rho)^2)` on the
//! intervals of `rho` where the root is real: one closed curve per interval, the
//! main branch from the smallest interval and isolas from the others. The
//! Jacobian of `G` in `(Re q, Im q)` has trace `2 Re(dG/dq)` and determinant
//! `|dG/dq|^2 - |dG/dconj q|^2`, with `dG/dq = g + u g'(u) - i Omega` and
//! `dG/dconj q = q^2 g'(u)`: a point is stable when the trace is negative and
//! the determinant positive; the determinant vanishes at saddle-node (fold)
//! points and the trace (with a positive determinant) at Hopf points, both
//! located by bisection along the branch.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Nonlinear analysis of forced mechanical systems
//! with internal resonance using spectral submanifolds, Part I*, Nonlinear Dyn.
//! 110 (2022), Sect. 4; S. Ponsioen, S. Jain, G. Haller, J. Sound Vib. 488 (2020)
//! 115640 (explicit FRC of two-dimensional SSMs); M. Li, S. Jain, G. Haller,
//! Nonlinear Dyn. 111 (2023), Sect. 5.1.2.

use crate::ssm::analysis::Polar;
use crate::C64;
use ssm_kernel::continuation::BifurcationKind;

/// A located bifurcation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bifurcation {
    /// Kind: [`BifurcationKind::Fold`] where the determinant of the
    /// Jacobian vanishes, [`BifurcationKind::Hopf`] where a complex pair
    /// crosses the imaginary axis.
    pub kind: BifurcationKind,
    /// Forcing frequency.
    pub omega: f64,
    /// Polar amplitude.
    pub rho: f64,
    /// Branch number (1 = main branch).
    pub branch: usize,
}

/// One fixed point of the rotating-frame reduced dynamics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrcPoint {
    /// Forcing frequency.
    pub omega: f64,
    /// Polar amplitude `|q|`.
    pub rho: f64,
    /// Phase of `q` (the response `p = rho e^{i (theta + Omega t)}`).
    pub theta: f64,
    /// Linear stability of the fixed point.
    pub stable: bool,
    /// Branch number (1 = main branch, then isolas).
    pub branch: usize,
}

/// An FRC at one forcing amplitude and expansion order.
#[derive(Debug, Clone)]
pub struct Frc {
    /// Points, branch by branch, in order along each branch.
    pub points: Vec<FrcPoint>,
    /// Located bifurcations.
    pub bifurcations: Vec<Bifurcation>,
}

/// Higher-order non-autonomous coefficients of the rotating-frame dynamics
/// `q' = q (g(u) - i Omega) + eps (sigma(u) + q^2 tau(u))`, `u = |q|^2`, as
/// functions of `Omega` (Chebyshev interpolation between exact expansions).
#[derive(Debug, Clone)]
pub struct ForcedCoefficients {
    /// Interpolation nodes in `Omega`.
    nodes: Vec<f64>,
    /// `(sigma_0, sigma_1, ..., tau_0, tau_1, ...)` at each node.
    values: Vec<Vec<C64>>,
    /// Number of `sigma` coefficients.
    n_sigma: usize,
    /// `eps`.
    eps: f64,
}

/// Chebyshev nodes in `Omega` at which the one-pair forced response computes
/// its higher non-autonomous terms exactly (interpolated in between); their
/// expansions are held together while they are computed.
pub const NONAUTONOMOUS_NODES: usize = 17;

impl ForcedCoefficients {
    /// Chebyshev nodes (second kind) on `[a, b]`.
    pub fn nodes(a: f64, b: f64, count: usize) -> Vec<f64> {
        ssm_kernel::chebyshev::lobatto_nodes(a, b, count)
    }

    /// From `(sigma, tau)` evaluated at [`ForcedCoefficients::nodes`].
    pub fn new(nodes: Vec<f64>, sigma_tau: Vec<(Vec<C64>, Vec<C64>)>, eps: f64) -> Self {
        let n_sigma = sigma_tau.first().map_or(0, |v| v.0.len());
        let values = sigma_tau
            .into_iter()
            .map(|(s, t)| s.into_iter().chain(t).collect())
            .collect();
        Self {
            nodes,
            values,
            n_sigma,
            eps,
        }
    }

    /// `(eps sigma_a, eps tau_b)` at `omega` (barycentric interpolation; held
    /// at the end values outside the nodes, where the FRC is not reported).
    fn at(&self, omega: f64) -> (Vec<C64>, Vec<C64>) {
        let all: Vec<C64> =
            ssm_kernel::chebyshev::interpolate_held(&self.nodes, &self.values, omega)
                .iter()
                .map(|c| c * self.eps)
                .collect();
        (all[..self.n_sigma].to_vec(), all[self.n_sigma..].to_vec())
    }
}

/// `sum_a c_a u^a` and its derivative in `u`.
fn series_u(c: &[C64], u: f64) -> (C64, C64) {
    let mut v = C64::new(0.0, 0.0);
    let mut d = C64::new(0.0, 0.0);
    for (j, cj) in c.iter().enumerate().rev() {
        v = v * u + cj;
        if j > 0 {
            d = d * u + cj * j as f64;
        }
    }
    (v, d)
}

/// The rotating-frame problem of one master pair.
#[derive(Debug, Clone)]
pub struct OnePair {
    /// `c_j`, coefficient of `u^j` in `g(u)`.
    c: Vec<C64>,
    /// `eps |s|`.
    force: f64,
    /// `arg(eps s)`.
    phase: f64,
    /// Higher-order non-autonomous terms, if any.
    forced: Option<ForcedCoefficients>,
}

impl OnePair {
    /// From the polar form truncated at `order` and the resonant forcing
    /// `eps * s`.
    pub fn new(polar: &Polar, order: usize, eps_s: C64) -> Self {
        let c = polar
            .c
            .iter()
            .zip(&polar.orders)
            .filter(|(_, &o)| o <= order)
            .map(|(c, _)| *c)
            .collect();
        Self {
            c,
            force: eps_s.norm(),
            phase: eps_s.arg(),
            forced: None,
        }
    }

    /// With the higher-order non-autonomous terms `coeffs` (which replace the
    /// leading-order forcing `eps s`, their `sigma_0`).
    pub fn with_forced(mut self, coeffs: ForcedCoefficients) -> Self {
        self.forced = Some(coeffs);
        self
    }

    /// `g(u)` and `g'(u)`.
    fn g(&self, u: f64) -> (C64, C64) {
        let mut g = C64::new(0.0, 0.0);
        let mut dg = C64::new(0.0, 0.0);
        for (j, c) in self.c.iter().enumerate().rev() {
            g = g * u + c;
            if j > 0 {
                dg = dg * u + c * j as f64;
            }
        }
        (g, dg)
    }

    /// `eps^2 |s|^2 / rho^2 - alpha^2`: the squared distance of `Omega` from
    /// the backbone; a fixed point exists where it is non-negative.
    pub(crate) fn discriminant(&self, rho: f64) -> f64 {
        let a = self.g(rho * rho).0.re;
        (self.force / rho).powi(2) - a * a
    }

    /// Whether the leading-order problem has a fixed point of amplitude
    /// `rho` at a frequency inside `range`: the discriminant is non-negative
    /// and the backbone frequency `Im g` lies within its square root of the
    /// range (the fixed points are at `Im g -+ sqrt(discriminant)`).
    pub fn reaches(&self, rho: f64, range: (f64, f64)) -> bool {
        let d = self.discriminant(rho);
        let w = self.g(rho * rho).0.im;
        let gap = (range.0 - w).max(w - range.1).max(0.0);
        d >= 0.0 && gap <= d.sqrt()
    }

    /// The fixed point at amplitude `rho` on side `sign` (`-1`: below the
    /// backbone frequency, `+1`: above), with its stability data
    /// `(trace, det)`. `None` where the discriminant is negative.
    pub fn point(&self, rho: f64, sign: f64) -> Option<(f64, f64, f64, f64)> {
        if self.forced.is_some() {
            return self.point_forced(rho, sign);
        }
        let d = self.discriminant(rho);
        if d < 0.0 {
            return None;
        }
        let u = rho * rho;
        let (g, dg) = self.g(u);
        let omega = g.im + sign * d.sqrt();
        // q (g - i Omega) = -eps s
        let q = -C64::from_polar(self.force, self.phase) / (g - C64::new(0.0, omega));
        let jq = g + dg * u - C64::new(0.0, omega);
        let jqb = q * q * dg;
        let trace = 2.0 * jq.re;
        let det = jq.norm_sqr() - jqb.norm_sqr();
        // beyond the convergence domain the series overflow: no point there
        [omega, q.arg(), trace, det]
            .iter()
            .all(|v| v.is_finite())
            .then_some((omega, q.arg(), trace, det))
    }
}

impl OnePair {
    /// Fixed point with the higher-order terms: for frozen `sigma`, `tau`,
    /// `rho (g - i Omega) + sigma e^{-i theta} + rho^2 tau e^{i theta} = 0`
    /// gives `theta` from its real part (roots on the circle) and `Omega` from
    /// its imaginary part; `Omega` is then iterated to consistency with the
    /// `Omega`-dependence of `sigma`, `tau`.
    fn point_forced(&self, rho: f64, sign: f64) -> Option<(f64, f64, f64, f64)> {
        let fc = self.forced.as_ref()?;
        let u = rho * rho;
        let (g, dg) = self.g(u);
        // start from the leading-order point
        let lead = OnePair {
            forced: None,
            ..self.clone()
        };
        let mut omega = match lead.point(rho, sign) {
            Some(p) => p.0,
            None => g.im,
        };
        let mut theta = 0.0;
        for _ in 0..20 {
            let (sig, tau) = fc.at(omega);
            let (sv, _) = series_u(&sig, u);
            let (tv, _) = series_u(&tau, u);
            // real part: rho alpha + A cos(theta) + B sin(theta) = 0
            let a = sv.re + u * tv.re;
            let b = sv.im - u * tv.im;
            let amp = a.hypot(b);
            let c = -rho * g.re / amp;
            if !(amp > 0.0 && c.abs() <= 1.0) {
                return None;
            }
            let psi = b.atan2(a);
            let om = |t: f64| {
                g.im + (sv * C64::from_polar(1.0, -t) + u * tv * C64::from_polar(1.0, t)).im / rho
            };
            let (t1, t2) = (psi + c.acos(), psi - c.acos());
            let (w1, w2) = (om(t1), om(t2));
            let (t, w) = if (sign < 0.0) == (w1 <= w2) {
                (t1, w1)
            } else {
                (t2, w2)
            };
            theta = t;
            let done = (w - omega).abs() <= 1e-12 * omega.abs().max(1.0);
            omega = w;
            if done {
                break;
            }
        }
        let (sig, tau) = fc.at(omega);
        let (_, ds) = series_u(&sig, u);
        let (tv, dt) = series_u(&tau, u);
        let q = C64::from_polar(rho, theta);
        // G = q (g - i Omega) + sigma(u) + q^2 tau(u), u = q conj(q)
        let jq = g + dg * u - C64::new(0.0, omega)
            + ds * q.conj()
            + 2.0 * q * tv
            + q * q * dt * q.conj();
        let jqb = q * q * dg + ds * q + q * q * dt * q;
        let trace = 2.0 * jq.re;
        let det = jq.norm_sqr() - jqb.norm_sqr();
        [omega, theta, trace, det]
            .iter()
            .all(|v| v.is_finite())
            .then_some((omega, theta, trace, det))
    }
}

/// Bisection for a sign change of `f` between `a` and `b` (`f(a) f(b) < 0`).
fn bisect(f: &dyn Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    let fa = f(a);
    for _ in 0..80 {
        let m = 0.5 * (a + b);
        if (f(m) > 0.0) == (fa > 0.0) {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// All branches of the FRC for `rho` in `(0, rho_max]`, with `samples` points
/// per side of each branch; points outside `omega_range` are dropped,
/// bifurcations inside it are located.
pub fn one_pair_frc(pb: &OnePair, rho_max: f64, samples: usize, omega_range: (f64, f64)) -> Frc {
    // intervals of rho with a non-negative discriminant, on a fine scan
    let scan = (20 * samples).max(2000);
    let h = rho_max / scan as f64;
    let mut intervals: Vec<(f64, f64)> = Vec::new();
    let mut start: Option<f64> = None;
    // existence of fixed points: the discriminant, or a root pair with the
    // higher-order terms
    let d = |r: f64| match pb.forced {
        None => pb.discriminant(r),
        Some(_) => {
            if pb.point(r, -1.0).is_some() {
                1.0
            } else {
                -1.0
            }
        }
    };
    for k in 1..=scan {
        let r = k as f64 * h;
        let ok = d(r) >= 0.0;
        match (ok, start) {
            (true, None) => {
                start = Some(if k == 1 { r } else { bisect(&d, r - h, r) });
            }
            (false, Some(a)) => {
                intervals.push((a, bisect(&d, r - h, r)));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(a) = start {
        intervals.push((a, rho_max));
    }
    let in_range = |w: f64| w >= omega_range.0 && w <= omega_range.1;
    let mut points = Vec::new();
    let mut bifurcations = Vec::new();
    for (bi, &(a, b)) in intervals.iter().enumerate() {
        let branch = bi + 1;
        for sign in [-1.0, 1.0] {
            // rho samples denser near the ends, where Omega(rho) turns
            let rhos: Vec<f64> = (0..=samples)
                .map(|k| {
                    let t = k as f64 / samples as f64;
                    let s = 0.5 - 0.5 * (std::f64::consts::PI * t).cos();
                    a + (b - a) * s
                })
                .collect();
            let ordered: Vec<f64> = if sign < 0.0 {
                rhos
            } else {
                rhos.into_iter().rev().collect()
            };
            let mut prev: Option<(f64, f64, f64)> = None;
            let mut prev_omega: Option<(f64, f64)> = None;
            for &r in &ordered {
                let Some((omega, theta, trace, det)) = pb.point(r, sign) else {
                    continue;
                };
                if let Some((pr, ptr, pdet)) = prev {
                    for (kind, before, after) in [
                        (BifurcationKind::Fold, pdet, det),
                        (BifurcationKind::Hopf, ptr, trace),
                    ] {
                        let hopf_ok = kind == BifurcationKind::Fold || det > 0.0;
                        if before * after < 0.0 && hopf_ok {
                            let f = |x: f64| {
                                // the determinant for a fold, the trace for Hopf
                                pb.point(x, sign).map_or(0.0, |p| {
                                    if kind == BifurcationKind::Fold {
                                        p.3
                                    } else {
                                        p.2
                                    }
                                })
                            };
                            let rb = bisect(&f, pr, r);
                            if let Some(p) = pb.point(rb, sign) {
                                if in_range(p.0) {
                                    bifurcations.push(Bifurcation {
                                        kind,
                                        omega: p.0,
                                        rho: rb,
                                        branch,
                                    });
                                }
                            }
                        }
                    }
                }
                // a branch leaving or entering the range ends exactly on its edge
                if let Some((pr, pw)) = prev_omega {
                    if in_range(pw) != in_range(omega) {
                        let edge = if pw.min(omega) < omega_range.0 {
                            omega_range.0
                        } else {
                            omega_range.1
                        };
                        let g = |x: f64| pb.point(x, sign).map_or(f64::NAN, |p| p.0 - edge);
                        let rb = bisect(&g, pr, r);
                        if let Some(p) = pb.point(rb, sign) {
                            points.push(FrcPoint {
                                omega: edge,
                                rho: rb,
                                theta: p.1,
                                stable: p.2 < 0.0 && p.3 > 0.0,
                                branch,
                            });
                        }
                    }
                }
                prev_omega = Some((r, omega));
                prev = Some((r, trace, det));
                if in_range(omega) {
                    points.push(FrcPoint {
                        omega,
                        rho: r,
                        theta,
                        stable: trace < 0.0 && det > 0.0,
                        branch,
                    });
                }
            }
        }
    }
    Frc {
        points,
        bifurcations,
    }
}

/// Amplitudes of one output on the periodic response of an FRC point:
/// `max_t |y(t)|` (L-infinity) and the first-harmonic amplitude, with
/// `y = W(p(t)) + eps X(p(t), Omega t)` sampled at 64 phases over one forcing
/// period (`series`: the output's coefficients in `W`; `forced(q, phi)`: the
/// output's non-autonomous part `eps sum_h 2 Re(X_h(p) e^{i kappa_h phi})` at
/// `p = (q, conj q)`).
pub fn response_amplitudes(
    ssm: &crate::ssm::SsmExpansion,
    series: &[C64],
    order: usize,
    point: &FrcPoint,
    forced: &dyn Fn(C64, f64) -> f64,
) -> (f64, f64) {
    let n = 64;
    let end = ssm.set.of_order(order.min(ssm.order)).end;
    let mut linf: f64 = 0.0;
    let mut first = C64::new(0.0, 0.0);
    for k in 0..n {
        let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
        let q = C64::from_polar(point.rho, point.theta + phi);
        let mono = ssm.set.monomials(&[q, q.conj()], order);
        let y = (0..end).map(|i| series[i] * mono[i]).sum::<C64>().re + forced(q, phi);
        linf = linf.max(y.abs());
        first += y * C64::from_polar(1.0, -phi);
    }
    (linf, 2.0 * first.norm() / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Linear oscillator: `g = lambda`; the FRC is `rho = eps |s| / |lambda - i Omega|`,
    /// stable everywhere, no bifurcation.
    #[test]
    fn linear_frc_is_the_resonance_curve() {
        let lambda = C64::new(-0.01, 1.0);
        let polar = Polar {
            c: vec![lambda],
            orders: vec![1],
        };
        let pb = OnePair::new(&polar, 1, C64::new(0.0, -0.005));
        let frc = one_pair_frc(&pb, 1.0, 200, (0.9, 1.1));
        assert!(frc.bifurcations.is_empty());
        assert!(frc.points.len() > 100);
        for p in &frc.points {
            let exact = 0.005 / (lambda - C64::new(0.0, p.omega)).norm();
            assert!((p.rho - exact).abs() < 1e-9 * exact, "{p:?}");
            assert!(p.stable);
        }
    }

    /// Negative nonlinear damping: `g(u) = lambda + c1 u + c2 u^2` with
    /// `Re c1 > 0 > Re c2`. The trace `2 Re(g + u g') = 2 Re(lambda + 2 c1 u + 3 c2 u^2)`
    /// vanishes at the roots of that quadratic in `u`; where the determinant is
    /// positive there, a Hopf point must be reported at that `rho`, and the same
    /// point must be found by the continuation of the Cartesian rotating frame.
    #[test]
    fn hopf_points_match_the_trace_condition() {
        let lambda = C64::new(-0.01, 1.0);
        let (c1, c2) = (C64::new(0.2, 0.3), C64::new(-0.3, 0.1));
        let polar = Polar {
            c: vec![lambda, c1, c2],
            orders: vec![1, 3, 5],
        };
        let pb = OnePair::new(&polar, 5, C64::new(0.0, -0.02));
        let frc = one_pair_frc(&pb, 1.5, 400, (0.5, 1.5));
        let hopf: Vec<_> = frc
            .bifurcations
            .iter()
            .filter(|b| b.kind == BifurcationKind::Hopf)
            .collect();
        assert!(!hopf.is_empty(), "{:?}", frc.bifurcations);
        // roots of Re(lambda) + 2 Re(c1) u + 3 Re(c2) u^2 = 0
        let (a, b, c) = (3.0 * c2.re, 2.0 * c1.re, lambda.re);
        let disc = (b * b - 4.0 * a * c).sqrt();
        let roots = [(-b + disc) / (2.0 * a), (-b - disc) / (2.0 * a)];
        for h in &hopf {
            let u = h.rho * h.rho;
            let d = roots
                .iter()
                .map(|r| (r - u).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-9, "Hopf at u = {u}, trace roots {roots:?}");
        }
        // the continuation finds the same Hopf frequencies
        use crate::rom::continuation::{PolarTerm, RotatingFrame, Settings};
        let frame = RotatingFrame {
            terms: vec![
                PolarTerm {
                    pair: 0,
                    exponents: vec![1, 0],
                    coeff: lambda,
                },
                PolarTerm {
                    pair: 0,
                    exponents: vec![2, 1],
                    coeff: c1,
                },
                PolarTerm {
                    pair: 0,
                    exponents: vec![3, 2],
                    coeff: c2,
                },
            ],
            ratios: vec![1.0],
            force: vec![C64::new(0.0, -0.02)],
        };
        let settings = Settings {
            omega_range: (0.5, 1.5),
            h_max: 2e-3,
            h_min: 1e-12,
            max_steps: 20_000,
            max_amplitude: None,
        };
        let q = C64::new(0.0, 0.02) / (lambda - C64::new(0.0, 0.5));
        let br = frame.start(0.5, vec![q.re, q.im], &settings).unwrap();
        let found: Vec<f64> = br
            .located
            .iter()
            .filter(|l| l.kind == BifurcationKind::Hopf)
            .map(|l| l.at.omega)
            .collect();
        for h in &hopf {
            assert!(
                found.iter().any(|w| (w - h.omega).abs() < 1e-6),
                "Hopf at Omega = {} not found by continuation: {found:?}",
                h.omega
            );
        }
    }
}
