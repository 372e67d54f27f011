//! Forced response with internal resonance: continuation of the rotating-frame
//! reduced dynamics of a 1:2 resonant SSM, against branch points derived in
//! closed form from its averaged (quadratic) equations.

use num_complex::Complex64 as C64;
use ssm_core::rom::continuation::{PolarTerm, RotatingFrame, Settings};
use ssm_core::spectrum;
use ssm_core::spectrum::Normalization;
use ssm_kernel::continuation::BifurcationKind;
use ssm_tests::{one_to_two_resonant, spectrum_options, ssm_of};

/// Reference: the averaged equations of the 1:2 resonant pair with the second
/// mode forced (`r = (1/2, 1)`), truncated at the resonant quadratic terms of
/// the computed SSM,
/// `q1' = (lambda1 - i Omega/2) q1 + c1 conj(q1) q2`,
/// `q2' = (lambda2 - i Omega) q2 + c2 q1^2 + f`.
/// On the main branch `q1 = 0`, `q2 = -f / (lambda2 - i Omega)`, and the
/// `q1`-block `q1 -> a q1 + b conj(q1)` (`a = lambda1 - i Omega/2`,
/// `b = c1 q2`) is singular where `|a|^2 = |b|^2`, i.e.
/// `|lambda1 - i Omega/2|^2 |lambda2 - i Omega|^2 = |c1|^2 |f|^2`: the two branch
/// points, found here by bisection on that quartic. The continuation must
/// locate both to 1e-11 relative, the main branch must be unstable exactly
/// between them, and switching at the first must trace a branch with
/// `q1 != 0` that reconnects with the main branch at the second.
#[test]
fn one_to_two_branch_points_match_the_closed_form() {
    let sys = one_to_two_resonant(0.01);
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &spectrum_options(None, 0))
        .expect("spectrum");
    let s = ssm_of(&sys, &sp, &[1, 2], 3, Normalization::Unit);
    let lam1 = s.lambda[0];
    let lam2 = s.lambda[2];
    let coeff = |coord: usize, e: [u16; 4]| {
        let idx = s.set.index(&e).unwrap();
        s.r.iter()
            .filter(|t| t.coord == coord && t.index == idx)
            .map(|t| t.coeff)
            .sum::<C64>()
    };
    let c1 = coeff(0, [0, 1, 1, 0]);
    let c2 = coeff(2, [2, 0, 0, 0]);
    assert!(c1.norm() > 1e-3 && c2.norm() > 1e-3, "1:2 terms {c1} {c2}");
    let fmag = 6.0 * lam1.re.abs() * lam2.re.abs() / c1.norm();
    let f = C64::new(0.0, -fmag);
    let frame = RotatingFrame {
        terms: vec![
            PolarTerm {
                pair: 0,
                exponents: vec![1, 0, 0, 0],
                coeff: lam1,
            },
            PolarTerm {
                pair: 0,
                exponents: vec![0, 1, 1, 0],
                coeff: c1,
            },
            PolarTerm {
                pair: 1,
                exponents: vec![0, 0, 1, 0],
                coeff: lam2,
            },
            PolarTerm {
                pair: 1,
                exponents: vec![2, 0, 0, 0],
                coeff: c2,
            },
        ],
        ratios: vec![0.5, 1.0],
        force: vec![C64::new(0.0, 0.0), f],
    };
    let w2 = lam2.im;
    let range = (0.9 * w2, 1.1 * w2);
    // closed-form branch points
    let g = |w: f64| {
        (lam1 - C64::new(0.0, 0.5 * w)).norm_sqr() * (lam2 - C64::new(0.0, w)).norm_sqr()
            - c1.norm_sqr() * fmag * fmag
    };
    let mut exact = Vec::new();
    let n = 4000;
    for k in 0..n {
        let (a, b) = (
            range.0 + (range.1 - range.0) * k as f64 / n as f64,
            range.0 + (range.1 - range.0) * (k + 1) as f64 / n as f64,
        );
        if g(a) * g(b) < 0.0 {
            let (mut lo, mut hi) = (a, b);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if (g(mid) > 0.0) == (g(lo) > 0.0) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            exact.push(0.5 * (lo + hi));
        }
    }
    assert_eq!(exact.len(), 2, "closed form: {exact:?}");
    let settings = Settings {
        omega_range: range,
        h_max: 0.002 * w2,
        h_min: 1e-9,
        max_steps: 4000,
        max_amplitude: None,
    };
    let q2 = -f / (lam2 - C64::new(0.0, range.0));
    let main = frame
        .start(range.0, vec![0.0, 0.0, q2.re, q2.im], &settings)
        .expect("main branch");
    let bps: Vec<_> = main
        .located
        .iter()
        .filter(|l| l.kind == BifurcationKind::BranchPoint)
        .collect();
    eprintln!(
        "branch points: continuation {:?}, closed form {exact:?}",
        bps.iter().map(|b| b.at.omega).collect::<Vec<_>>()
    );
    assert_eq!(bps.len(), 2);
    // Tolerance: on the main branch q1 = 0 exactly, so the closed form holds
    // for this frame without truncation. Bisection halves an arc step
    // <= h_max = 0.002 w2 fifty times (~1e-18 relative), and the test
    // function det(q1-block) = |a|^2 - |b|^2 is exact to rounding (~1e-16);
    // what is left is the corrector's stop at |F| < 1e-12, which moves q2 by
    // 1e-12 / |lambda2 - i Omega|, |b|^2 = |c1 q2|^2 by 2e-12 / |f| relative and
    // the root by 2e-12 |a|^2 / (|f| |d(|a|^2 - |b|^2)/dOmega|): here
    // |a|^2 ~ 6e-4, slope ~ 0.045, |f| = 1.2e-3 / |c1|, at most 1.1e-11 |c1|
    // relative, ~1e-12 with |c1| ~ 0.1; so 1e-11 relative.
    for (b, e) in bps.iter().zip(&exact) {
        assert!(
            ((b.at.omega - e) / e).abs() < 1e-11,
            "{} vs {e} (|c1| = {})",
            b.at.omega,
            c1.norm()
        );
    }
    // the main branch (q1 = 0) is unstable exactly between the branch points
    for p in &main.points {
        assert!(p.q[0].norm() < 1e-10);
        let inside = p.omega > exact[0] && p.omega < exact[1];
        let near = (p.omega - exact[0]).abs().min((p.omega - exact[1]).abs()) < 1e-6;
        if !near {
            assert_eq!(p.stable, !inside, "{p:?}");
        }
    }
    // branch switching at the first branch point: q1 != 0, back to q1 = 0 near the second
    let switched = frame.switch(bps[0], &settings);
    assert!(!switched.is_empty());
    let coupled = switched
        .iter()
        .max_by(|a, b| {
            let m = |br: &ssm_core::rom::continuation::Branch| {
                br.points.iter().map(|p| p.q[0].norm()).fold(0.0, f64::max)
            };
            m(a).total_cmp(&m(b))
        })
        .unwrap();
    let peak = coupled
        .points
        .iter()
        .map(|p| p.q[0].norm())
        .fold(0.0, f64::max);
    assert!(peak > 1e-2, "secondary branch peak |q1| = {peak}");
    let rejoins = coupled.located.iter().any(|l| {
        l.kind == BifurcationKind::BranchPoint && ((l.at.omega - exact[1]) / exact[1]).abs() < 1e-4
    }) || coupled
        .points
        .iter()
        .any(|p| p.q[0].norm() < 1e-6 && ((p.omega - exact[1]) / exact[1]).abs() < 1e-3);
    eprintln!(
        "secondary branch: {} points, peak |q1| {peak:.4}, located {:?}",
        coupled.points.len(),
        coupled
            .located
            .iter()
            .map(|l| (l.kind, l.at.omega))
            .collect::<Vec<_>>()
    );
    assert!(
        rejoins,
        "the secondary branch does not reach the second branch point"
    );
    // with [forcing] rho_max below that peak the branch stops where |q1|
    // passes it, and says so
    let bounded = Settings {
        max_amplitude: Some(0.5 * peak),
        ..settings
    };
    let stopped = frame.switch(bps[0], &bounded);
    assert!(stopped.iter().any(|b| b.reached_max_amplitude));
    for b in &stopped {
        let inside = &b.points[..b.points.len() - 1];
        assert!(
            inside
                .iter()
                .all(|p| p.q.iter().all(|q| q.norm() <= 0.5 * peak)),
            "a point beyond max_amplitude before the last"
        );
    }
}
