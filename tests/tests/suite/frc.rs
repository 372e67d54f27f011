//! Forced response curves from the leading-order periodic SSM against
//! independent references: the first-order harmonic-balance closed form of the
//! Duffing oscillator (peak and folds), and direct simulation of the reduced
//! dynamics around unstable fixed points.

use num_complex::Complex64 as C64;
use ssm_core::model::system::System;
use ssm_core::rom::frc::{one_pair_frc, response_amplitudes, Bifurcation, Frc, OnePair};
use ssm_core::spectrum::Normalization;
use ssm_core::spectrum::{self, MasterMode};
use ssm_core::ssm::analysis::polar;
use ssm_core::ssm::forced::ForcedSsm;
use ssm_core::ssm::SsmExpansion;
use ssm_kernel::continuation::BifurcationKind;
use ssm_tests::{spectrum_options, ssm_of, system};

const ZETA: f64 = 0.002;
const OMEGA: f64 = 1.0;
const KAPPA: f64 = 1.0;

struct Duffing {
    sys: System,
    masters: Vec<MasterMode>,
    ssm: SsmExpansion,
}

fn duffing(order: usize) -> Duffing {
    let sys = system(
        "duffing",
        "duffing",
        &format!("zeta = {ZETA}\nomega = {OMEGA}\nkappa = {KAPPA}\nf = 1.0"),
    );
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &spectrum_options(None, 0))
        .expect("spectrum");
    let masters = spectrum::master_modes(&sys, &sp, &[1], Normalization::Unit).unwrap();
    let ssm = ssm_of(&sys, &sp, &[1], order, Normalization::Unit);
    Duffing { sys, masters, ssm }
}

/// The FRC at forcing `eps` and the x-amplitude (L-infinity) of each point.
fn frc_with_amplitudes(d: &Duffing, order: usize, eps: f64, range: (f64, f64)) -> (Frc, Vec<f64>) {
    let mut forced = ForcedSsm::new(&d.sys, &d.masters, &[1.0]).unwrap();
    let s = forced.at(OMEGA).unwrap().resonant_forcing(0);
    let p = polar(&d.ssm).unwrap();
    let pb = OnePair::new(&p, order, eps * s);
    let frc = one_pair_frc(&pb, 2.0, 400, range);
    let weights = &d.sys.output("x").unwrap().weights;
    let series = d.ssm.output_series(weights);
    let amps = frc
        .points
        .iter()
        .map(|pt| {
            let x0 = forced.at(pt.omega).unwrap();
            response_amplitudes(&d.ssm, &series, order, pt, &|_, phi| {
                eps * x0.output_at(weights, phi)
            })
            .0
        })
        .collect();
    (frc, amps)
}

/// First-order harmonic balance of `x'' + 2 zeta omega x' + omega^2 x + kappa x^3
/// = eps cos(Omega t)` with `x = A cos(Omega t - psi)`:
/// `H(A, Omega) = ((omega^2 + 3/4 kappa A^2 - Omega^2)^2 + (2 zeta omega Omega)^2) A^2 - eps^2`.
fn hb(a: f64, w: f64, eps: f64) -> f64 {
    let k = OMEGA * OMEGA + 0.75 * KAPPA * a * a - w * w;
    (k * k + (2.0 * ZETA * OMEGA * w).powi(2)) * a * a - eps * eps
}

/// Peak of the harmonic-balance FRC: `Omega^2 = omega^2 + 3/4 kappa A^2` and
/// `2 zeta omega Omega A = eps`, solved by fixed-point iteration.
fn hb_peak(eps: f64) -> (f64, f64) {
    let mut a = eps / (2.0 * ZETA * OMEGA * OMEGA);
    for _ in 0..200 {
        let w = (OMEGA * OMEGA + 0.75 * KAPPA * a * a).sqrt();
        a = eps / (2.0 * ZETA * OMEGA * w);
    }
    ((OMEGA * OMEGA + 0.75 * KAPPA * a * a).sqrt(), a)
}

/// Fold of the harmonic-balance FRC: `H = 0` and `dH/dA = 0`, Newton from a guess.
fn hb_fold(eps: f64, mut a: f64, mut w: f64) -> (f64, f64) {
    let h = 1e-7;
    for _ in 0..100 {
        let f1 = hb(a, w, eps);
        let f2 = (hb(a + h, w, eps) - hb(a - h, w, eps)) / (2.0 * h);
        let j11 = f2;
        let j12 = (hb(a, w + h, eps) - hb(a, w - h, eps)) / (2.0 * h);
        let d2 = |a: f64, w: f64| (hb(a + h, w, eps) - hb(a - h, w, eps)) / (2.0 * h);
        let j21 = (d2(a + h, w) - d2(a - h, w)) / (2.0 * h);
        let j22 = (d2(a, w + h) - d2(a, w - h)) / (2.0 * h);
        let det = j11 * j22 - j12 * j21;
        let da = (f1 * j22 - j12 * f2) / det;
        let dw = (j11 * f2 - j21 * f1) / det;
        a -= da;
        w -= dw;
        if da.abs() + dw.abs() < 1e-14 {
            break;
        }
    }
    (w, a)
}

/// Reference: the first-order harmonic-balance closed form above. At the
/// smallest forcing (peak amplitude 0.025, where the neglected harmonics and
/// O(A^4) terms are below 1e-4 relative) the SSM FRC's peak frequency and
/// amplitude agree to 1e-3; at the largest forcing (peak 0.15) the two
/// saddle-node frequencies agree with the closed-form fold condition to 1e-3
/// (the fold frequencies shift by `3/8 kappa A^2 = 8e-3`; first-order harmonic
/// balance neglects terms of relative size `(kappa A^2)^2 / 32 < 2e-5`), and
/// the points between them on the middle branch are the unstable ones.
#[test]
fn duffing_frc_matches_harmonic_balance() {
    let d = duffing(7);
    let eps = 1e-4;
    let (frc, amps) = frc_with_amplitudes(&d, 7, eps, (0.95, 1.05));
    assert!(frc.bifurcations.is_empty(), "{:?}", frc.bifurcations);
    let (k, a_max) = amps.iter().enumerate().fold(
        (0, 0.0),
        |acc, (k, &a)| if a > acc.1 { (k, a) } else { acc },
    );
    let (w_hb, a_hb) = hb_peak(eps);
    let w_max = frc.points[k].omega;
    eprintln!("peak: SSM ({w_max}, {a_max}), harmonic balance ({w_hb}, {a_hb})");
    assert!(((a_max - a_hb) / a_hb).abs() < 1e-3);
    assert!(((w_max - w_hb) / w_hb).abs() < 1e-3);

    let eps = 6e-4;
    let (frc, amps) = frc_with_amplitudes(&d, 7, eps, (0.95, 1.05));
    let sn: Vec<_> = frc
        .bifurcations
        .iter()
        .filter(|b| b.kind == BifurcationKind::Fold)
        .collect();
    assert_eq!(sn.len(), 2, "{:?}", frc.bifurcations);
    let (w_lo, w_hi) = (sn[0].omega.min(sn[1].omega), sn[0].omega.max(sn[1].omega));
    // the folds of the harmonic-balance curve, started near ours: at the
    // amplitude of our point nearest to each fold in rho (the largest
    // amplitude within a frequency window would start the lower fold on the
    // upper branch, where Newton may reach either fold)
    let amp_at = |b: &Bifurcation| {
        frc.points
            .iter()
            .zip(&amps)
            .min_by(|(p, _), (q, _)| (p.rho - b.rho).abs().total_cmp(&(q.rho - b.rho).abs()))
            .map(|(_, &a)| a)
            .expect("points on the curve")
    };
    let mut folds: Vec<(f64, f64)> = sn.iter().map(|b| (b.omega, amp_at(b))).collect();
    folds.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (w, a) in folds {
        let (w_ref, _) = hb_fold(eps, a, w);
        eprintln!("fold: SSM {w} (amplitude {a}), harmonic balance {w_ref}");
        assert!(((w - w_ref) / w_ref).abs() < 1e-3, "{w} vs {w_ref}");
    }
    // unstable points lie between the folds
    for p in frc.points.iter().filter(|p| !p.stable) {
        assert!(p.omega > w_lo - 1e-9 && p.omega < w_hi + 1e-9, "{p:?}");
    }
    assert!(frc.points.iter().any(|p| !p.stable));
}

/// Reference: direct simulation (RK4) of the rotating-frame reduced dynamics
/// `q' = q (g(|q|^2) - i Omega) + eps s` from each unstable fixed point
/// perturbed by (1e-6, 1e-6): the trajectory leaves it (its distance grows tenfold
/// within 2000 time units; the saddles' unstable rates are small), while
/// from a perturbed stable point it returns (below 1e-7 after 2000 time units,
/// 4 damping times; points within 5e-4 of a fold, where the decay rate
/// vanishes, are left out).
#[test]
fn unstable_fixed_points_are_left_by_the_reduced_dynamics() {
    let d = duffing(7);
    let eps = 6e-4;
    let mut forced = ForcedSsm::new(&d.sys, &d.masters, &[1.0]).unwrap();
    let s = forced.at(OMEGA).unwrap().resonant_forcing(0);
    let p = polar(&d.ssm).unwrap();
    let c: Vec<C64> = p.c.clone();
    let frc = one_pair_frc(&OnePair::new(&p, 7, eps * s), 2.0, 100, (0.95, 1.05));
    let rhs = |q: C64, w: f64| {
        let u = q.norm_sqr();
        let g: C64 = c
            .iter()
            .rev()
            .fold(C64::new(0.0, 0.0), |acc, cj| acc * u + cj);
        q * (g - C64::new(0.0, w)) + eps * s
    };
    let run = |q0: C64, w: f64| {
        let (mut q, h) = (q0, 0.05);
        for _ in 0..40_000 {
            let k1 = rhs(q, w);
            let k2 = rhs(q + 0.5 * h * k1, w);
            let k3 = rhs(q + 0.5 * h * k2, w);
            let k4 = rhs(q + h * k3, w);
            q += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        q
    };
    let mut checked = [0, 0];
    let folds: Vec<f64> = frc.bifurcations.iter().map(|b| b.omega).collect();
    for pt in frc.points.iter().step_by(7) {
        if folds.iter().any(|w| (w - pt.omega).abs() < 5e-4) {
            continue;
        }
        let q = C64::from_polar(pt.rho, pt.theta);
        let end = run(q + C64::new(1e-6, 1e-6), pt.omega);
        let dist = (end - q).norm();
        if pt.stable {
            assert!(dist < 1e-7, "stable {pt:?} drifted by {dist:e}");
            checked[0] += 1;
        } else {
            assert!(
                dist > 10.0 * 2f64.sqrt() * 1e-6,
                "unstable {pt:?} kept within {dist:e}"
            );
            checked[1] += 1;
        }
    }
    assert!(checked[0] > 5 && checked[1] > 2, "{checked:?}");
}

/// Reference: Li, Jain & Haller (2023), Fig. 6: on the saddle-node periodic
/// orbit "A" of the unconstrained spatial oscillator (O(11), eps = 0.03, the
/// fold at the top of the FRC) the residual of eq. (60) of the leading-order
/// periodic SSM exceeds 0.015 over the period ("the maximum residual in Fig. 6
/// is more than 0.015", Sect. 5.1.2, paragraph after the Fig. 6 caption). That
/// is the paper's reading of its plot, rounded down; had the maximum reached
/// 0.02 it would have been read as more than 0.02, so we require
/// 0.015 < max ||Res||_2 < 0.02. With the higher-order
/// non-autonomous terms of [`ForcedSsm::expansion`] the residual on the same
/// orbit falls with their order. The residual is also checked to
/// reduce to the autonomous invariance residual at eps = 0, and to shrink on
/// the eps = 0.01 orbit at the same frequency side (it is O(eps |p|)).
#[test]
fn fig6_residual_of_the_leading_order_periodic_ssm() {
    let sys = system("spatial-oscillator", "", "constraint = \"none\"");
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &spectrum_options(None, 0))
        .expect("spectrum");
    let norm = Normalization::Scale(0.8306);
    let masters = spectrum::master_modes(&sys, &sp, &[1], norm).unwrap();
    let ssm = ssm_of(&sys, &sp, &[1], 11, norm);
    let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).unwrap();
    let s = forced.at(2.0).unwrap().resonant_forcing(0);
    let p = polar(&ssm).unwrap();
    let mut max_residual = |eps: f64| -> (Vec<f64>, f64) {
        let pb = OnePair::new(&p, 11, eps * s);
        let frc = one_pair_frc(&pb, 0.5, 400, (1.8, 2.2));
        let a = frc
            .bifurcations
            .iter()
            .filter(|b| b.kind == BifurcationKind::Fold)
            .max_by(|x, y| x.rho.total_cmp(&y.rho))
            .copied();
        // the top of the curve when there is no fold (small eps)
        let (rho, omega) = match a {
            Some(b) => (b.rho, b.omega),
            None => {
                let top = frc
                    .points
                    .iter()
                    .max_by(|x, y| x.rho.total_cmp(&y.rho))
                    .unwrap();
                (top.rho, top.omega)
            }
        };
        let theta = [-1.0, 1.0]
            .iter()
            .filter_map(|&sg| pb.point(rho, sg))
            .min_by(|x, y| (x.0 - omega).abs().total_cmp(&(y.0 - omega).abs()))
            .unwrap()
            .1;
        let worst = |na: &ssm_core::ssm::nonautonomous::NonAutonomous| {
            (0..200)
                .map(|k| {
                    let phi = 2.0 * std::f64::consts::PI * k as f64 / 200.0;
                    let q = C64::from_polar(rho, theta + phi);
                    let r = na.residual(&ssm, &sys, eps, &[q, q.conj()], phi, 11);
                    r.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt()
                })
                .fold(0.0, f64::max)
        };
        let by_order: Vec<f64> = (0..=10)
            .step_by(2)
            .map(|k| worst(&forced.expansion(&ssm, &sys, omega, k).unwrap()))
            .collect();
        (by_order, omega)
    };
    let (res_a, omega_a) = max_residual(0.03);
    let (res_small, _) = max_residual(0.01);
    eprintln!(
        "orbit A at Omega = {omega_a}: max residual by non-autonomous order 0, 2, .., 10: {res_a:?}; eps = 0.01: {res_small:?}"
    );
    // Fig. 6: above the printed 0.015, below the next round value 0.02
    assert!(res_a[0] > 0.015 && res_a[0] < 0.02, "{res_a:?}");
    assert!(res_small[0] < res_a[0] / 3.0, "{res_small:?} vs {res_a:?}");
    // beyond the paper: the O(eps |p|^k) terms remove the O(eps |p|) residual;
    // at eps = 0.03 it falls with every added order (by 10x at k = 10), at
    // eps = 0.01 it drops 40x to the O(eps^2) floor
    assert!(res_a.windows(2).all(|w| w[1] < w[0]), "{res_a:?}");
    assert!(res_a[5] < res_a[0] / 10.0, "{res_a:?}");
    assert!(res_small[5] < res_small[0] / 30.0, "{res_small:?}");
    // eps = 0: the autonomous residual of eq. (55)
    let terms = forced.expansion(&ssm, &sys, 2.0, 3).unwrap();
    let q = C64::from_polar(0.2, 0.7);
    let r0 = terms.residual(&ssm, &sys, 0.0, &[q, q.conj()], 0.3, 11);
    let ra = ssm.residual(&sys, &[q, q.conj()], 11);
    for (x, y) in r0.iter().zip(&ra) {
        assert!((x - y).norm() <= 1e-14 * (1.0 + y.norm()));
    }
}

/// Steady-state amplitude `max |x|` of the Duffing oscillator
/// `x'' + 2 zeta x' + x + x^3 = eps cos(Omega t)` (unit frequency and cubic
/// coefficient) from rest, by RK4 at 400 steps per period over `16 / zeta`
/// (the start's transient decays like `exp(-zeta t)`, to 1.1e-7). The maximum
/// over the last two periods is refined by the parabola through the largest
/// sample and its neighbours (sampling alone would be up to
/// `1 - cos(pi / 400) = 3e-5` low; the parabola leaves `O((pi / 400)^4)`).
/// Its own error is thus about 1e-6 relative.
fn duffing_steady_state(zeta: f64, eps: f64, omega: f64) -> f64 {
    let f = |t: f64, x: f64, v: f64| -> (f64, f64) {
        (v, eps * (omega * t).cos() - 2.0 * zeta * v - x - x * x * x)
    };
    let period = 2.0 * std::f64::consts::PI / omega;
    let steps_per_period = 400;
    let h = period / steps_per_period as f64;
    let periods = (16.0 / zeta / period).ceil() as usize;
    let (mut t, mut x, mut v) = (0.0, 0.0, 0.0);
    let mut last = Vec::with_capacity(2 * steps_per_period);
    for p in 0..periods {
        for _ in 0..steps_per_period {
            let (k1x, k1v) = f(t, x, v);
            let (k2x, k2v) = f(t + 0.5 * h, x + 0.5 * h * k1x, v + 0.5 * h * k1v);
            let (k3x, k3v) = f(t + 0.5 * h, x + 0.5 * h * k2x, v + 0.5 * h * k2v);
            let (k4x, k4v) = f(t + h, x + h * k3x, v + h * k3v);
            x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            t += h;
            if p + 2 >= periods {
                last.push(x.abs());
            }
        }
    }
    let k = (1..last.len() - 1)
        .max_by(|&i, &j| last[i].total_cmp(&last[j]))
        .expect("two periods sampled");
    let (a, b, c) = (last[k - 1], last[k], last[k + 1]);
    b + (a - c) * (a - c) / (8.0 * (2.0 * b - a - c))
}

/// Reference: direct simulation of the Duffing oscillator to steady state
/// (RK4, above). At eps = 0.01 with zeta = 0.01 (response amplitude about
/// 0.2 below the folds, where the O(eps |p|) terms the leading order neglects
/// matter), the FRC amplitude at frequencies below the bistable region, where
/// the simulation from rest reaches the same branch, agrees with the
/// simulation at least five times as well, and within 5e-4, once the
/// non-autonomous terms up to order 6 are included (measured: 2.1e-3 ->
/// 3.5e-4 at Omega = 0.93, 4.3e-3 -> 1.2e-4 at 0.95, 8.2e-3 -> 1.9e-5 at
/// 0.98; the simulation's own error is about 1e-6).
#[test]
fn higher_order_nonautonomous_terms_improve_the_frc() {
    use ssm_core::rom::frc::ForcedCoefficients;
    let zeta = 0.01;
    let sys = system(
        "duffing",
        "duffing",
        &format!("zeta = {zeta}\nomega = 1\nkappa = 1\nf = 1"),
    );
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &spectrum_options(None, 0))
        .expect("spectrum");
    let masters = spectrum::master_modes(&sys, &sp, &[1], Normalization::Unit).unwrap();
    let order = 9;
    let ssm = ssm_of(&sys, &sp, &[1], order, Normalization::Unit);
    let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).unwrap();
    let s = forced.at(1.0).unwrap().resonant_forcing(0);
    let p = polar(&ssm).unwrap();
    let eps = 0.01;
    let range = (0.9, 1.1);
    let nodes = ForcedCoefficients::nodes(0.85, 1.15, 13);
    let coeffs: Vec<_> = nodes
        .iter()
        .map(|&w| {
            forced
                .expansion(&ssm, &sys, w, 6)
                .unwrap()
                .rotating_frame_coefficients()
        })
        .collect();
    let lead = OnePair::new(&p, order, eps * s);
    let high = lead
        .clone()
        .with_forced(ForcedCoefficients::new(nodes, coeffs, eps));
    let weights = sys.output("x").unwrap().weights.clone();
    let series = ssm.output_series(&weights);
    // amplitude of x on the FRC at frequency w (lower side, linear interpolation)
    let mut amp_at = |pb: &OnePair, w: f64| -> f64 {
        let f = one_pair_frc(pb, 2.0, 400, range);
        let pts: Vec<_> = f.points.iter().filter(|q| q.branch == 1).collect();
        let k = (1..pts.len())
            .find(|&k| (pts[k - 1].omega - w) * (pts[k].omega - w) <= 0.0)
            .expect("frequency on the curve");
        let mut amp = |q: &ssm_core::rom::frc::FrcPoint| {
            let x0 = forced.at(q.omega).unwrap();
            response_amplitudes(&ssm, &series, order, q, &|_, phi| {
                eps * x0.output_at(&weights, phi)
            })
            .0
        };
        let (a, b) = (pts[k - 1], pts[k]);
        let t = (w - a.omega) / (b.omega - a.omega);
        amp(a) + t * (amp(b) - amp(a))
    };
    for w in [0.93, 0.95, 0.98] {
        let reference = duffing_steady_state(zeta, eps, w);
        let e0 = ((amp_at(&lead, w) - reference) / reference).abs();
        let e6 = ((amp_at(&high, w) - reference) / reference).abs();
        eprintln!("Omega {w}: simulation {reference:.6}, relative error leading {e0:.2e}, with O(eps p^6) {e6:.2e}");
        assert!(e6 < e0 / 5.0 && e6 < 5e-4, "Omega {w}: {e6:e} vs {e0:e}");
    }
}

/// The undamped two-harmonic balance of `x'' + x + x^3 = eps cos(Omega t)`,
/// `x = A cos(Omega t) + C cos(3 Omega t)`:
/// `(1 - Omega^2) A + 3/4 A^3 + 3/4 A^2 C + 3/2 A C^2 = eps`,
/// `(1 - 9 Omega^2) C + 1/4 A^3 + 3/2 A^2 C + 3/4 C^3 = 0`, by Newton from
/// `(a, 0)`; returns `A`. It neglects the fifth harmonic, of relative size
/// `(A^2 / 32)^2`.
fn duffing_two_harmonics(eps: f64, omega: f64, a: f64) -> f64 {
    let w = omega * omega;
    let f = |a: f64, c: f64| {
        [
            (1.0 - w) * a + 0.75 * a.powi(3) + 0.75 * a * a * c + 1.5 * a * c * c - eps,
            (1.0 - 9.0 * w) * c + 0.25 * a.powi(3) + 1.5 * a * a * c + 0.75 * c.powi(3),
        ]
    };
    let (mut a, mut c) = (a, 0.0);
    for _ in 0..50 {
        let r = f(a, c);
        let j11 = (1.0 - w) + 2.25 * a * a + 1.5 * a * c + 1.5 * c * c;
        let j12 = 0.75 * a * a + 3.0 * a * c;
        let j21 = 0.75 * a * a + 3.0 * a * c;
        let j22 = (1.0 - 9.0 * w) + 1.5 * a * a + 2.25 * c * c;
        let det = j11 * j22 - j12 * j21;
        a -= (r[0] * j22 - j12 * r[1]) / det;
        c -= (j11 * r[1] - j21 * r[0]) / det;
    }
    a
}

/// The default amplitude grid of a lightly damped Duffing oscillator
/// (`zeta = 1e-9`: linear peak `eps |s| / |Re lambda|` some 1e7) ends near
/// the response the backbone lets into the frequency range, not at three
/// times the linear peak, where its 2000 amplitudes all missed the response
/// and the run failed. Reference: the two-harmonic balance above at the
/// range's upper end, where the upper branch leaves the range with its
/// largest amplitude (A = 0.31 at Omega = 1.02, 0.55 at 1.1); the first
/// harmonic `h1` of the O(7) curve agrees to 1e-4 and 2e-2 (measured 8e-6
/// and 8.5e-3: the expansion's own error at A = 0.55).
#[test]
fn default_grid_finds_the_response_of_a_lightly_damped_duffing() {
    let eps = 0.01;
    for (top, tol) in [(1.02, 1e-4), (1.1, 2e-2)] {
        let scene = format!(
            "[model]\nplugin = \"duffing\"\n[model.params]\nzeta = 1e-9\n[ssm]\nmaster_pairs = [1]\norder = 7\n\
             [outputs]\ncoordinates = [\"x\"]\n[forcing]\nepsilon = [{eps}]\nomega_range = [0.9, {top}]\n"
        );
        let r = ssm_tests::run_scene_text(&scene).expect("the default grid finds the response");
        let frc = r.frc.expect("forced response");
        let ssm = frc
            .rows
            .iter()
            .filter(|row| (row.omega - top).abs() < 1e-12)
            .map(|row| row.h1[0])
            .fold(0.0, f64::max);
        // from above the backbone amplitude sqrt(4/3 (Omega^2 - 1)): Newton
        // descends onto the largest orbit
        let hb = duffing_two_harmonics(eps, top, 1.2 * (4.0 / 3.0 * (top * top - 1.0)).sqrt());
        eprintln!(
            "Omega = {top}: SSM {ssm}, two-harmonic balance {hb}, rho_max {:?}",
            frc.rho_max
        );
        assert!((ssm - hb).abs() < tol * hb, "{ssm} vs {hb}");
    }
}

/// The amplitude scan's search (`ssm_kernel::search::first_true`, which
/// bounds a forced response's amplitudes where its backbone estimate
/// diverges) finds what a test of every index finds whenever the test
/// switches once, for every length, stride and switching point up to 80, in
/// at most `n / stride + log2(stride) + 2` evaluations; its batched form
/// (`first_true_par`, the tests of a batch one per thread) finds the same.
#[test]
fn the_strided_search_finds_the_first_failing_index_of_a_full_scan() {
    use ssm_kernel::search::{first_true, first_true_par};
    for n in 0..=80usize {
        for stride in 1..=40usize {
            for switch in 0..=n {
                let mut calls = 0usize;
                let found = first_true(n, stride, |k| {
                    calls += 1;
                    k >= switch
                });
                let full = (0..n).find(|&k| k >= switch);
                assert_eq!(found, full, "n {n}, stride {stride}, switch {switch}");
                let batched = first_true_par(n, stride, |k| k >= switch);
                assert_eq!(
                    batched, full,
                    "batched: n {n}, stride {stride}, switch {switch}"
                );
                let bound = n / stride + (stride as f64).log2().ceil() as usize + 2;
                assert!(
                    calls <= bound,
                    "n {n}, stride {stride}: {calls} calls > {bound}"
                );
            }
        }
    }
}

/// `summary.json` counts the forced response's sparse linear algebra with
/// the SSM's and the spectrum's: `linear_algebra.stages` holds `spectrum`,
/// `ssm` and `frc`, the totals are their sums, the forced response's own
/// entry repeats its stage, a scene without forcing has no `frc` stage,
/// and one with `[validate]` has a `validation` stage that counts its
/// full-system run as the run's own section does.
/// On the spatial oscillator the forced response solves at least once per
/// Chebyshev node of its X0 table (17 at the least) and its non-autonomous
/// table (17 nodes). Its spectrum (7 states, dense path, one master pair)
/// is one dense LU solved for the 7 columns of `B`, then the master mode's
/// inverse iteration: one sparse LU and 3 right and 3 left solves, so 1
/// symbolic, 2 numeric factorizations and 13 solves, exactly.
#[test]
fn the_forced_response_s_factorizations_and_solves_are_counted() {
    let s = ssm_tests::run_zoo("spatial_oscillator_cubic_fig5.toml");
    let la = &s["linear_algebra"];
    let stages = la["stages"].as_object().expect("stages");
    assert_eq!(
        stages.keys().collect::<Vec<_>>(),
        ["frc", "spectrum", "ssm"]
    );
    assert_eq!(s["model"]["n_states"], 7);
    let sp = &stages["spectrum"];
    assert_eq!(
        (
            &sp["symbolic_factorizations"],
            &sp["numeric_factorizations"],
            &sp["solves"]
        ),
        (&1.into(), &2.into(), &13.into()),
        "{sp}"
    );
    for key in [
        "symbolic_factorizations",
        "numeric_factorizations",
        "solves",
    ] {
        let sum: u64 = stages.values().map(|v| v[key].as_u64().unwrap()).sum();
        assert_eq!(la[key].as_u64(), Some(sum), "{key}");
        assert_eq!(s["frc"]["linear_algebra"][key], stages["frc"][key], "{key}");
    }
    let frc = &stages["frc"];
    assert!(frc["solves"].as_u64().unwrap() >= 34, "{frc}");
    assert!(
        frc["numeric_factorizations"].as_u64().unwrap() >= 34,
        "{frc}"
    );
    let none = ssm_tests::run_zoo("spatial_oscillator_cubic.toml");
    let stages = none["linear_algebra"]["stages"]
        .as_object()
        .expect("stages");
    assert_eq!(
        stages.keys().collect::<Vec<_>>(),
        ["spectrum", "ssm", "validation"]
    );
    // the transient's Radau IIA run: two symbolic analyses (real and complex
    // iteration matrices), two numeric factorizations per pair and two
    // solves per Newton iteration, as its own section counts them
    let run = &none["validation"]["transient"]["full_system"];
    let v = &stages["validation"];
    let count = |x: &serde_json::Value| x.as_u64().expect("a count");
    assert_eq!(count(&v["symbolic_factorizations"]), 2);
    assert_eq!(
        count(&v["numeric_factorizations"]),
        2 * count(&run["factorizations"])
    );
    assert_eq!(count(&v["solves"]), 2 * count(&run["newton_iterations"]));
    assert!(count(&run["factorizations"]) > 0, "{run}");
}

/// The sparse path counts one symbolic and one numeric factorization of the
/// shifted pencil and one solve per application of the shift-invert
/// operator: two for the start vector, and at least one per Krylov
/// direction, so at least two more than the modes asked for (here 4 of the
/// unconstrained spatial oscillator's 6 states; the sparse eigenvalues are
/// the dense ones to 1e-10, whose path is one dense LU solved for the 6
/// columns of `B`).
#[test]
fn the_sparse_spectrum_counts_its_factorization_and_solves() {
    let sys = system("spatial-oscillator", "", "constraint = \"none\"");
    let (a, b) = sys.spectral_pencil();
    let sparse = spectrum::compute(a, b, &spectrum_options(Some(spectrum::Method::Sparse), 4))
        .expect("sparse spectrum");
    let dense = spectrum::compute(a, b, &spectrum_options(Some(spectrum::Method::Dense), 6))
        .expect("dense spectrum");
    let w = sparse.work;
    eprintln!("sparse spectrum: {w:?}; dense: {:?}", dense.work);
    assert_eq!((w.symbolic, w.factorizations), (1, 1));
    assert!(w.solves >= 2 + 4, "{w:?}");
    assert_eq!(dense.work.factorizations, 1);
    assert_eq!(dense.work.solves, sys.n_states());
    for l in &sparse.eigenvalues {
        let near = dense
            .eigenvalues
            .iter()
            .map(|d| (d - l).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(near < 1e-10 * (1.0 + l.norm()), "{l}: {near:e}");
    }
}
