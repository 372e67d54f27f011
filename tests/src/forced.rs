//! Forced problems with closed-form or independently computed answers:
//! the forced Duffing oscillator (its fold and orbits by harmonic balance of
//! one harmonic, the linear steady state in closed form) and the parametric
//! pump (the damped Mathieu equation of its period doublings).

use num_complex::Complex64 as C64;
use ssm_core::model::system::System;

/// The forced Duffing oscillator `x'' + 2 zeta x' + x + gamma x^3 = eps sum_k
/// a_k cos(k Omega t)` with `loads = [(k, a_k), ...]` (`gamma = 0`: the
/// linear oscillator, whose steady state is the closed form
/// [`linear_steady_state`]).
pub fn forced_duffing(zeta: f64, gamma: f64, loads: &[(f64, f64)]) -> System {
    use ssm_api::{Harmonic, PolyVector, SparseMatrix};
    use ssm_plugin_kit::MechanicalSystem;
    let mut m = MechanicalSystem::new("duffing", &["x"]);
    m.mass = SparseMatrix::diagonal(&[1.0]);
    m.damping = SparseMatrix::diagonal(&[2.0 * zeta]);
    m.stiffness = SparseMatrix::diagonal(&[1.0]);
    let mut f = PolyVector::zeros(1, 2);
    if gamma != 0.0 {
        f.push(0, gamma, &[(0, 3)]);
    }
    m.internal_force = f;
    m.forcing = loads
        .iter()
        .map(|&(k, a)| {
            let mut cos = PolyVector::zeros(1, 2);
            cos.push(0, a, &[]);
            Harmonic {
                multiple: k,
                cos,
                sin: PolyVector::zeros(1, 2),
            }
        })
        .collect();
    System::from_model("catalogue", m.into_model().expect("valid model")).expect("valid system")
}

/// The one-harmonic balance of [`forced_duffing`] (one load `eps cos Omega t`)
/// in closed form:
/// `G(a, W) = ((1 + 3/4 gamma a^2 - W)^2 + 4 zeta^2 W) a^2 - eps^2 = 0`,
/// `W = Omega^2`; its folds in `Omega` are where also `G_a = 0`. Newton on
/// `(G, G_a)` from `(a, Omega)`; returns `(a, Omega)`.
pub fn duffing_fold(zeta: f64, gamma: f64, eps: f64, a: f64, omega: f64) -> (f64, f64) {
    let g = |a: f64, w: f64| {
        let d = 1.0 + 0.75 * gamma * a * a - w;
        (d * d + 4.0 * zeta * zeta * w) * a * a - eps * eps
    };
    let ga = |a: f64, w: f64| (g(a + 1e-7, w) - g(a - 1e-7, w)) / 2e-7;
    let (mut a, mut w) = (a, omega * omega);
    for _ in 0..60 {
        let (f1, f2) = (g(a, w), ga(a, w));
        let (da, dw) = (1e-6 * a, 1e-6 * w);
        let j11 = (g(a + da, w) - g(a - da, w)) / (2.0 * da);
        let j12 = (g(a, w + dw) - g(a, w - dw)) / (2.0 * dw);
        let j21 = (ga(a + da, w) - ga(a - da, w)) / (2.0 * da);
        let j22 = (ga(a, w + dw) - ga(a, w - dw)) / (2.0 * dw);
        let det = j11 * j22 - j12 * j21;
        let (sa, sw) = ((f1 * j22 - f2 * j12) / det, (j11 * f2 - j21 * f1) / det);
        a -= sa;
        w -= sw;
        if sa.abs() < 1e-15 * a && sw.abs() < 1e-15 {
            break;
        }
    }
    (a, w.sqrt())
}

/// The one-harmonic orbits `x = A cos Omega t + B sin Omega t` of
/// [`forced_duffing`] (one load `eps cos Omega t`) at `omega`, by amplitude:
/// the positive roots `y = a^2` of the cubic `G` of [`duffing_fold`] by a
/// scan and bisection, then `A = eps d / q`, `B = 2 zeta Omega eps / q`,
/// `d = 1 + 3/4 gamma a^2 - Omega^2`, `q = d^2 + 4 zeta^2 Omega^2`.
pub fn duffing_orbits(zeta: f64, gamma: f64, eps: f64, omega: f64) -> Vec<(f64, f64)> {
    let w = omega * omega;
    let g = |y: f64| {
        let d = 1.0 + 0.75 * gamma * y - w;
        (d * d + 4.0 * zeta * zeta * w) * y - eps * eps
    };
    let y_max = 4.0 * (eps / (2.0 * zeta * omega)).powi(2) + 1.0;
    let n = 200_000;
    let mut roots = Vec::new();
    for k in 0..n {
        let (mut lo, mut hi) = (
            y_max * k as f64 / n as f64,
            y_max * (k + 1) as f64 / n as f64,
        );
        if (g(lo) > 0.0) == (g(hi) > 0.0) {
            continue;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if (g(mid) > 0.0) == (g(lo) > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let y = 0.5 * (lo + hi);
        let d = 1.0 + 0.75 * gamma * y - w;
        let q = d * d + 4.0 * zeta * zeta * w;
        roots.push((eps * d / q, 2.0 * zeta * omega * eps / q));
    }
    roots
}

/// The closed-form steady state `x(t)` of [`forced_duffing`] with `gamma =
/// 0`: `sum_k eps a_k Re[e^(i k Omega t) / (1 - (k Omega)^2 + 2 i zeta k
/// Omega)]`, restricted to the harmonics `k > above` (the tail a truncation
/// at `above` harmonics leaves out).
pub fn linear_steady_state(
    zeta: f64,
    eps: f64,
    loads: &[(f64, f64)],
    omega: f64,
    above: f64,
    t: f64,
) -> f64 {
    loads
        .iter()
        .filter(|(k, _)| *k > above)
        .map(|&(k, a)| {
            let w = k * omega;
            let h = C64::new(1.0 - w * w, 2.0 * zeta * w).inv();
            eps * a * (h * C64::new(0.0, w * t).exp()).re
        })
        .sum()
}

/// The full-system reference of [`parametric_pump`]'s period-doubling
/// study: `eps = 1` over `[1.8, 2.2]`, 6 harmonics, both states as outputs,
/// the branch of period `2T` switched to, and orbits also at `points_at`.
pub fn parametric_pump_reference(
    points_at: Vec<f64>,
) -> ssm_core::fom::periodic::ReferenceSettings {
    let output = |name: &str, state: usize| ssm_core::model::system::OutputMap {
        name: name.into(),
        weights: vec![(state, 1.0)],
    };
    ssm_core::fom::periodic::ReferenceSettings {
        epsilon: 1.0,
        omega_range: (1.8, 2.2),
        harmonics: 6,
        step: 0.5,
        tol: 1e-11,
        max_steps: 2000,
        outputs: vec![output("x1", 0), output("x2", 1)],
        points_at,
        seeds: Vec::new(),
        period_doubling: true,
        stability: true,
    }
}

/// Two oscillators in 1:2 resonance where the second pumps the first
/// parametrically: `x1'' + 2 zeta1 x1' + x1 + alpha x1 x2 = 0`, `x2'' + 4
/// zeta2 x2' + 4 x2 + beta x1^2 = f cos(Omega t)`. On `x1 = 0` the second
/// oscillator is linear, so the period-`T` branch is known in closed form
/// and `x1` obeys a damped Mathieu equation whose tongue near `Omega = 2`
/// is bounded by two period doublings.
pub fn parametric_pump(zeta1: f64, zeta2: f64, alpha: f64, beta: f64, f: f64) -> System {
    use ssm_api::{PolyVector, SparseMatrix};
    use ssm_plugin_kit::MechanicalSystem;
    let mut m = MechanicalSystem::new("parametric-pump", &["x1", "x2"]);
    m.mass = SparseMatrix::diagonal(&[1.0, 1.0]);
    m.damping = SparseMatrix::diagonal(&[2.0 * zeta1, 4.0 * zeta2]);
    m.stiffness = SparseMatrix::diagonal(&[1.0, 4.0]);
    let mut nl = PolyVector::zeros(2, 4);
    nl.push(0, alpha, &[(0, 1), (1, 1)]);
    nl.push(1, beta, &[(0, 2)]);
    m.internal_force = nl;
    m.forcing = cosine_load(2, 1, f);
    System::from_model("catalogue", m.into_model().expect("valid model")).expect("valid system")
}

/// The load `f cos(Omega t)` on the coordinate `dof` of `n` (degree-4
/// polynomial vectors, as the catalogue's models use).
pub(crate) fn cosine_load(n: usize, dof: usize, f: f64) -> Vec<ssm_api::Harmonic> {
    let mut cos = ssm_api::PolyVector::zeros(n, 4);
    cos.push(dof, f, &[]);
    vec![ssm_api::Harmonic {
        multiple: 1.0,
        cos,
        sin: ssm_api::PolyVector::zeros(n, 4),
    }]
}
