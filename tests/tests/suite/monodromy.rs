//! Floquet multipliers from the monodromy matrix (Radau IIA integration of
//! the variational DAE on the harmonic-balance orbit) against Hill's method
//! (an independent computation: an eigenproblem of the Fourier-Galerkin
//! Jacobian, no time stepping), on an ODE, an index-3 DAE and a recast
//! model with a gauge.

use num_complex::Complex64 as C64;
use ssm_core::fom::periodic::floquet::floquet;
use ssm_core::fom::periodic::monodromy::floquet_by_monodromy;
use ssm_core::fom::periodic::HarmonicBalance;
use ssm_core::model::system::System;
use ssm_kernel::continuation::{solve_at_parameter, Settings};
use ssm_tests::{duffing_orbits, forced_duffing};

/// The orbits of `hb` at the frequencies `omegas` in turn, each by Newton
/// from the previous one (from rest for the first): natural continuation,
/// for ranges without folds.
fn orbits_along(hb: &mut HarmonicBalance<'_>, omegas: &[f64]) -> Vec<Vec<f64>> {
    let mut c = vec![0.0; hb.n_coefficients()];
    let mut out = Vec::new();
    for &omega in omegas {
        hb.frequency_scale = 1.0;
        let s = Settings {
            tol: 1e-11,
            max_newton: 40,
            ..Settings::new((0.0, 10.0), 0.1)
        };
        let guess = hb.scale(&c, omega);
        let u = solve_at_parameter(hb, guess, &s).expect("Newton converges");
        c = hb.unscale(&u).0;
        out.push(c.clone());
    }
    out
}

/// The Hausdorff distance of the sets of multipliers `a` and `b` (the
/// largest distance from a member of either to the nearest of the other),
/// after checking that they have as many distinct members (Hill's method
/// may keep both copies of an exponent on the strip's edge).
fn set_distance(a: &[C64], b: &[C64]) -> f64 {
    let distinct = |v: &[C64]| {
        let mut d: Vec<C64> = Vec::new();
        for x in v {
            if d.iter().all(|y| (x - y).norm() > 1e-6) {
                d.push(*x);
            }
        }
        d.len()
    };
    assert_eq!(distinct(a), distinct(b), "{a:?} against {b:?}");
    let one_way = |a: &[C64], b: &[C64]| {
        a.iter()
            .map(|x| {
                b.iter()
                    .map(|y| (x - y).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    };
    one_way(a, b).max(one_way(b, a))
}

/// Duffing oscillator (an ODE), the three coexisting orbits at `Omega =
/// 1.013` with 15 harmonics. Reference: Hill's multipliers (which equal an
/// RK4 monodromy to 1e-6, `periodic.rs`). The monodromy's multipliers agree
/// to 1e-9 with the default steps, and their error falls at the order of
/// Radau IIA, 5: by a factor above 2^5 / 1.5 = 21 per halving of the step
/// (64 -> 128 steps), and the unstable count is the same (middle orbit).
#[test]
fn duffing_monodromy_multipliers_converge_at_order_five_to_hill() {
    let (zeta, gamma, eps) = (0.005, 1.0, 0.002);
    let sys = forced_duffing(zeta, gamma, &[(1.0, 1.0)]);
    let omega = 1.013;
    let starts = duffing_orbits(zeta, gamma, eps, omega);
    assert_eq!(starts.len(), 3);
    let mut counts = Vec::new();
    for (a, b) in starts {
        let mut hb = HarmonicBalance::new(&sys, eps, 15, 1).expect("setup");
        let kk = 31;
        let mut c = vec![0.0; hb.n_coefficients()];
        c[1] = a;
        c[2] = b;
        c[kk + 1] = omega * b;
        c[kk + 2] = -omega * a;
        hb.frequency_scale = 1.0;
        let s = Settings {
            tol: 1e-13,
            ..Settings::new((0.0, 10.0), 0.1)
        };
        let guess = hb.scale(&c, omega);
        let u = solve_at_parameter(&mut hb, guess, &s).expect("Newton");
        let c = hb.unscale(&u).0;
        let hill = floquet(&hb, &c, omega).expect("Hill");
        let dflt = floquet_by_monodromy(&hb, &c, omega, None).expect("monodromy");
        let e_default = set_distance(&dflt.multipliers, &hill.multipliers);
        assert!(e_default < 1e-9, "a = {a}: {e_default:e}");
        assert_eq!(dflt.unstable, hill.unstable);
        counts.push(hill.unstable);
        let err = |steps: usize| {
            let m = floquet_by_monodromy(&hb, &c, omega, Some(steps)).expect("monodromy");
            set_distance(&m.multipliers, &hill.multipliers)
        };
        let (e64, e128) = (err(64), err(128));
        eprintln!(
            "a = {a}: default {e_default:e}, 64 steps {e64:e}, 128 steps {e128:e}, ratio {}",
            e64 / e128
        );
        assert!(e64 / e128 > 21.0, "a = {a}: {e64:e} -> {e128:e}");
    }
    assert_eq!(counts, vec![0, 1, 0]);
}

/// The largest distance between the multipliers of `hb`'s orbits at every
/// `every`-th of `omegas` by both methods, checking that they are as many
/// and give the same stability.
fn compare_along(sys: &System, eps: f64, h: usize, omegas: &[f64], every: usize) -> f64 {
    let mut hb = HarmonicBalance::new(sys, eps, h, 1).expect("setup");
    let orbits = orbits_along(&mut hb, omegas);
    let mut worst = 0.0f64;
    for (c, &omega) in orbits.iter().zip(omegas).step_by(every) {
        let hill = floquet(&hb, c, omega).expect("Hill");
        let mono = floquet_by_monodromy(&hb, c, omega, None).expect("monodromy");
        let e = set_distance(&mono.multipliers, &hill.multipliers);
        eprintln!(
            "{} at Omega = {omega}, H = {h}: {} multipliers, largest |rho| {:.6}, distance {e:e}",
            sys.name,
            mono.multipliers.len(),
            hill.max_modulus()
        );
        assert_eq!(mono.unstable, hill.unstable);
        worst = worst.max(e);
    }
    worst
}

/// Spatial oscillator with the cubic constraint (index-3 DAE: the
/// multiplier's constraint force is algebraic), eps = 0.01, through its
/// resonance: the monodromy's multipliers (the algebraic directions' zeros
/// dropped) are Hill's four to 1e-8.
#[test]
fn index_3_oscillator_monodromy_agrees_with_hill() {
    let sys = ssm_tests::system("spatial-oscillator", "", "constraint = \"cubic\"");
    let omegas: Vec<f64> = (0..=80).map(|k| 1.9 + 0.0025 * k as f64).collect();
    let worst = compare_along(&sys, 0.01, 9, &omegas, 10);
    assert!(worst < 1e-8, "{worst:e}");
}

/// Pendulum slider (recast: `sin phi`, `cos phi` as differential
/// auxiliaries with gauges), eps = 0.08 below Fig. 11's range: the spurious
/// multiplier 1 of each gauge is deflated, and the rest are Hill's (whose
/// gauge rows are algebraic). Hill's multipliers carry the truncation of the
/// perturbation at `H` harmonics, which the time integration does not: the
/// gap falls as `H` grows (measured 4.7e-8 at H = 12, 1.1e-8 at H = 16), so
/// it must fall by a third at least from 12 to 16 harmonics and stay below
/// 2e-8 at 16.
#[test]
fn recast_slider_monodromy_deflates_the_gauges_and_agrees_with_hill() {
    let sys = ssm_tests::system("pendulum", "slider", "");
    let omegas: Vec<f64> = (0..=20).map(|k| 1.6 + 0.01 * k as f64).collect();
    let coarse = compare_along(&sys, 0.08, 12, &omegas, 5);
    let fine = compare_along(&sys, 0.08, 16, &omegas, 5);
    assert!(fine < 2e-8 && fine < coarse / 1.5, "{coarse:e} -> {fine:e}");
}

/// The multipliers above `floor` in modulus, largest first.
fn above(m: &[C64], floor: f64) -> Vec<C64> {
    let mut v: Vec<C64> = m.iter().filter(|r| r.norm() > floor).copied().collect();
    v.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
    v
}

/// Chain of pendulums (405 states, recast, above the 200 states of the
/// monodromy matrix), eps = 0.6, H = 9, at Omega = 1.9 and 2.05 (either side
/// of Fig. 15's peak). Reference: the eigenvalues of the whole monodromy
/// matrix of the same steps (the period's map applied to the identity), its
/// gauges' spurious multipliers 1 set aside. The subspace iteration's
/// multipliers above 1e-3 are the same ones (as many, none at 1) to 1e-8:
/// both carry rounding amplified by the multipliers' condition, the map
/// being far from normal (`||Phi||` of order 30 with all multipliers below
/// 1; measured 8e-11 and 1.5e-9, while a Ritz residual below 1e-12 of
/// `||Phi X||` is out of reach). The largest multiplier is below 1 (Fig.
/// 15's branch is stable there).
#[test]
fn chain_dominant_multipliers_are_the_monodromy_matrix_ones() {
    use ssm_core::fom::periodic::monodromy::{check_multipliers, default_steps, PeriodSteps};
    let sys = ssm_tests::system("pendulum", "chain", "");
    let mut hb = HarmonicBalance::new(&sys, 0.6, 9, 1).expect("setup");
    let omegas = [1.8, 1.85, 1.9, 1.95, 2.0, 2.05];
    let orbits = orbits_along(&mut hb, &omegas);
    for (c, &omega) in orbits.iter().zip(&omegas).skip(2).step_by(3) {
        let t = std::time::Instant::now();
        let sub = floquet_by_monodromy(&hb, c, omega, None).expect("subspace");
        let seconds = t.elapsed().as_secs_f64();
        let steps = PeriodSteps::factor(&hb, c, omega, default_steps(&hb)).expect("steps");
        let n = hb.n_states();
        let mut phi = faer::Mat::<f64>::identity(n, n);
        steps.apply(&mut phi).expect("matrix");
        let all: Vec<C64> = phi
            .eigenvalues()
            .expect("eigenvalues")
            .iter()
            .map(|r| C64::new(r.re, r.im))
            .filter(|r| (r - 1.0).norm() > 1e-6)
            .collect();
        let (want, got) = (above(&all, 1e-3), above(&sub.multipliers, 1e-3));
        eprintln!(
            "Omega = {omega}: {} multipliers above 1e-3, largest {:.6}, subspace {seconds:.2} s, distance {:e}",
            want.len(),
            want[0].norm(),
            set_distance(&got, &want)
        );
        assert_eq!(got.len(), want.len(), "{got:?} against {want:?}");
        assert!(set_distance(&got, &want) < 1e-8, "{got:?} against {want:?}");
        assert!(sub.multipliers.iter().all(|r| (r - 1.0).norm() > 1e-6));
        assert!(sub.max_modulus() < 1.0 && sub.stable());
        // the check with twice the steps is the Richardson estimate of the
        // default steps' error: with errors falling as h^5, its distance to
        // the default multipliers is (1 - 2^-5) / (1 - 4^-5) = 0.970 of the
        // distance to those with four times the steps (0.941 at order 4;
        // measured 0.9695)
        let (s2, d2) = check_multipliers(&hb, c, omega, &sub).expect("check");
        let four = floquet_by_monodromy(&hb, c, omega, Some(4 * default_steps(&hb))).expect("4S");
        let d4 = sub.distance(&four);
        eprintln!(
            "Omega = {omega}: {s2} steps {d2:e}, 4 S {d4:e}, ratio {}",
            d2 / d4
        );
        assert!(
            d2 < 1e-5 && (0.955..0.985).contains(&(d2 / d4)),
            "{d2:e} {d4:e}"
        );
    }
}
