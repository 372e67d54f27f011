//! The HHT-alpha integrator (`fom::hht`) against closed forms and the
//! theory of the method (Hilber, Hughes & Taylor 1977; Negrut et al. 2007):
//! second-order convergence on a constrained oscillator, the trapezoidal
//! rule at `alpha = 0`, the spectral radius `(1 + alpha) / (1 - alpha)` at
//! infinite frequency, and agreement with the Radau integrator on a
//! nonlinear index-3 model.

use ssm_api::SparseMatrix;
use ssm_core::fom::hht::{integrate, HhtOptions};
use ssm_core::fom::{DaeProblem, Radau, RadauOptions, SimError};
use ssm_core::model::system::System;
use ssm_plugin_kit::MechanicalSystem;
use ssm_tests::{linear_constrained_oscillator, system};

/// The undamped oscillator `x'' + w^2 x = 0` as a mechanical model.
fn undamped(w: f64) -> System {
    let mut m = MechanicalSystem::new("undamped", &["x"]);
    m.mass = SparseMatrix::diagonal(&[1.0]);
    m.stiffness = SparseMatrix::diagonal(&[w * w]);
    System::from_model("catalogue", m.into_model().expect("valid model")).expect("valid system")
}

/// The reference end state of Radau IIA at `(rtol, atol)` from the
/// consistent start nearest `guess` over `[0, t_end]`.
fn radau_reference(p: &DaeProblem, guess: &[f64], t_end: f64, rtol: f64, atol: f64) -> Vec<f64> {
    let z0 = ssm_core::fom::consistent_initial(p, 0.0, guess).unwrap().z;
    let opts = RadauOptions {
        rtol,
        atol,
        ..RadauOptions::default()
    };
    let mut radau = Radau::new(p, 0.0, &z0, t_end, opts).unwrap();
    while radau.t() < t_end {
        radau.step(t_end).unwrap();
    }
    radau.z().to_vec()
}

/// Reference: the closed-form motion of two masses tied by `x1 = x2`
/// (`3 x'' + 0.3 x' + 8 x = 0`, the catalogue's `linear_constrained_oscillator`)
/// and its multiplier. Halving the step four times, the errors at `t = 4` of
/// the position, the velocity and the multiplier fall at rate 2 (observed
/// rates within 0.1 of 2), for `alpha = -0.1` and `-1/3`; the constraint
/// holds to round-off at every step.
#[test]
fn second_order_on_a_constrained_oscillator() {
    let (sys, exact) = linear_constrained_oscillator(0.5);
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let guess = [0.5, 0.5, 0.0, 0.0, 0.0];
    let t_end = 4.0;
    let (xe, ve, mue) = exact.at(t_end);
    for alpha in [-0.1, -1.0 / 3.0] {
        let errors: Vec<[f64; 3]> = [0.04, 0.02, 0.01, 0.005]
            .iter()
            .map(|&h| {
                let s = integrate(&p, &guess, 0.0, t_end, &HhtOptions::new(alpha, h)).unwrap();
                for z in &s.states {
                    assert!((z[0] - z[1]).abs() < 1e-13, "constraint {}", z[0] - z[1]);
                }
                let z = s.states.last().unwrap();
                [(z[0] - xe).abs(), (z[2] - ve).abs(), (z[4] - mue).abs()]
            })
            .collect();
        for w in errors.windows(2) {
            for (k, name) in ["x", "x'", "mu"].iter().enumerate() {
                let rate = (w[0][k] / w[1][k]).log2();
                assert!(
                    (rate - 2.0).abs() < 0.1,
                    "alpha {alpha}, {name}: rate {rate:.3} ({:.3e} -> {:.3e})",
                    w[0][k],
                    w[1][k]
                );
            }
        }
        eprintln!(
            "alpha {alpha}: errors (x, v, mu) {:?}",
            errors
                .iter()
                .map(|e| format!("{:.2e} {:.2e} {:.2e}", e[0], e[1], e[2]))
                .collect::<Vec<_>>()
        );
    }
}

/// Reference: the trapezoidal rule on `y' = [[0, 1], [-w^2, 0]] y`,
/// `y_{n+1} = (I - h A / 2)^{-1} (I + h A / 2) y_n`, written out here. With
/// `alpha = 0` (gamma = 1/2, beta = 1/4) HHT is that method: 500 steps agree
/// to 1e-11 (the round-off of 500 steps), and the energy
/// `(x'^2 + w^2 x^2) / 2` is conserved to 1e-11.
#[test]
fn alpha_zero_is_the_trapezoidal_rule() {
    let w = 2.0;
    let sys = undamped(w);
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let h = 0.1;
    let s = integrate(&p, &[1.0, 0.0], 0.0, 50.0, &HhtOptions::new(0.0, h)).unwrap();
    assert_eq!(s.states.len(), 501);
    // (I - hA/2)^{-1} (I + hA/2) for A = [[0, 1], [-w^2, 0]]
    let c = h * h * w * w / 4.0;
    let det = 1.0 + c;
    let m = [
        [(1.0 - c) / det, h / det],
        [-h * w * w / det, (1.0 - c) / det],
    ];
    let mut y = [1.0, 0.0];
    let energy = |x: f64, v: f64| 0.5 * (v * v + w * w * x * x);
    for z in &s.states[1..] {
        y = [
            m[0][0] * y[0] + m[0][1] * y[1],
            m[1][0] * y[0] + m[1][1] * y[1],
        ];
        assert!(
            (z[0] - y[0]).abs() < 1e-11 && (z[1] - y[1]).abs() < 1e-11,
            "HHT {z:?}, trapezoidal {y:?}"
        );
        assert!((energy(z[0], z[1]) - energy(1.0, 0.0)).abs() < 1e-11);
    }
}

/// Reference: the spectral radius of HHT at infinite frequency,
/// `rho_inf = (1 + alpha) / (1 - alpha)` (Hilber, Hughes & Taylor 1977).
/// On `x'' + w^2 x = 0` with `w h = 1e8`, the size `S_n` of the state
/// `(x, h x', h^2 x'')` behaves like `C n^m rho^n` (`m > 0` where the roots
/// coincide, as at `alpha = -1/3`, where at `w h = 1e4` they still differ
/// by 1 %); a least-squares fit of `ln S_n` to
/// `c + m ln n + n ln rho` over steps 200 to 900 gives `rho` within 1e-4 of
/// the theory for `alpha = -0.05, -0.2, -1/3`.
#[test]
fn numerical_damping_is_the_spectral_radius_at_infinity() {
    let w = 1e8;
    let sys = undamped(w);
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    for alpha in [-0.05, -0.2, -1.0 / 3.0] {
        let s = integrate(&p, &[1.0, 0.0], 0.0, 900.0, &HhtOptions::new(alpha, 1.0)).unwrap();
        // normal equations of the 3-parameter fit, solved by Cramer's rule
        let rows: Vec<([f64; 3], f64)> = (200..=900)
            .step_by(10)
            .map(|k| {
                let z = &s.states[k];
                let size = z[0].abs() + z[1].abs() + s.accelerations[k][0].abs();
                ([1.0, (k as f64).ln(), k as f64], size.ln())
            })
            .collect();
        let mut n = [[0.0; 3]; 3];
        let mut r = [0.0; 3];
        for (x, y) in &rows {
            for i in 0..3 {
                r[i] += x[i] * y;
                for j in 0..3 {
                    n[i][j] += x[i] * x[j];
                }
            }
        }
        let det = |m: &[[f64; 3]; 3]| {
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        };
        let mut n2 = n;
        for i in 0..3 {
            n2[i][2] = r[i];
        }
        let rate = (det(&n2) / det(&n)).exp();
        let rho = (1.0 + alpha) / (1.0 - alpha);
        eprintln!("alpha {alpha}: rho measured {rate:.6}, theory {rho:.6}");
        assert!(
            ((rate - rho) / rho).abs() < 1e-4,
            "alpha {alpha}: measured {rate:.5}, theory {rho:.5}"
        );
    }
}

/// Reference: the Radau IIA integrator (order 5, rtol 1e-11) on the spatial
/// oscillator with the cubic constraint `x3 = x1^3 + x2^3`, a nonlinear
/// index-3 DAE, from `x1 = 0.3, x2 = 0.2`. HHT (`alpha = -0.1`) converges to
/// it at rate 2 in the displacements (within 0.15 over three halvings) and
/// keeps the constraint to 1e-12 at every step.
#[test]
fn converges_to_radau_on_a_nonlinear_constrained_model() {
    let sys = system("spatial-oscillator", "", "constraint = \"cubic\"");
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let (guess, _) = sys.given_state(&[("x1".into(), 0.3), ("x2".into(), 0.2)]);
    let t_end = 3.0;
    let reference = radau_reference(&p, &guess, t_end, 1e-11, 1e-13);
    let mut errors = Vec::new();
    for h in [0.02, 0.01, 0.005, 0.0025] {
        let s = integrate(&p, &guess, 0.0, t_end, &HhtOptions::new(-0.1, h)).unwrap();
        for z in &s.states {
            let g = z[2] - z[0].powi(3) - z[1].powi(3);
            assert!(g.abs() < 1e-12, "constraint residual {g:.2e}");
        }
        let z = s.states.last().unwrap();
        errors.push(
            (0..3)
                .map(|i| (z[i] - reference[i]).abs())
                .fold(0.0, f64::max),
        );
    }
    eprintln!(
        "errors against Radau: {:?}",
        errors
            .iter()
            .map(|e| format!("{e:.3e}"))
            .collect::<Vec<_>>()
    );
    for w in errors.windows(2) {
        let rate = (w[0] / w[1]).log2();
        assert!((rate - 2.0).abs() < 0.15, "rate {rate:.3}: {errors:.3?}");
    }
}

/// Hostile settings and models: alpha outside `[-1/3, 0]`, a zero or NaN
/// step, an empty interval and bad tolerances each give a typed settings
/// error saying what is wrong.
#[test]
fn bad_settings_and_models_are_refused() {
    let sys = undamped(1.0);
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let err = |r: Result<_, SimError>| match r {
        Err(SimError::Settings(m)) => m,
        Err(e) => panic!("wrong error: {e}"),
        Ok(_) => panic!("accepted"),
    };
    let m = err(integrate(
        &p,
        &[1.0, 0.0],
        0.0,
        1.0,
        &HhtOptions::new(0.1, 0.01),
    ));
    assert!(m.contains("[-1/3, 0]"), "{m}");
    let m = err(integrate(
        &p,
        &[1.0, 0.0],
        0.0,
        1.0,
        &HhtOptions::new(-0.5, 0.01),
    ));
    assert!(m.contains("[-1/3, 0]"), "{m}");
    for h in [0.0, f64::NAN, -1.0] {
        let m = err(integrate(
            &p,
            &[1.0, 0.0],
            0.0,
            1.0,
            &HhtOptions::new(-0.1, h),
        ));
        assert!(m.contains("step"), "{m}");
    }
    let m = err(integrate(
        &p,
        &[1.0, 0.0],
        1.0,
        1.0,
        &HhtOptions::new(-0.1, 0.01),
    ));
    assert!(m.contains("interval"), "{m}");
}

/// Reference: the constrained oscillator's closed form, as above. With
/// step-size control on the positions' local error (`alpha = -0.1`,
/// `atol = rtol / 100`), each hundredfold tightening of `rtol` (1e-4, 1e-6,
/// 1e-8) cuts the error at `t = 4` by 10 to 50 (the theory: the local error
/// `O(h^3)` sets `h ~ rtol^(1/3)`, the global error `O(h^2) ~ rtol^(2/3)`,
/// a factor 21.5; measured 17.6 and 20.3) and multiplies the steps by 3 to
/// 7 (theory 4.6; measured 4.7 twice); the error stays below
/// `rtol^(2/3)` (measured 0.33 to 0.43 times it).
#[test]
fn adaptive_steps_follow_the_tolerance() {
    let (sys, exact) = linear_constrained_oscillator(0.5);
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let (xe, _, _) = exact.at(4.0);
    let runs: Vec<(f64, usize)> = [1e-4, 1e-6, 1e-8]
        .iter()
        .map(|&rtol| {
            let o = HhtOptions::adaptive(-0.1, 0.5, rtol, rtol * 1e-2);
            let s = integrate(&p, &[0.5, 0.5, 0.0, 0.0, 0.0], 0.0, 4.0, &o).unwrap();
            let e = (s.states.last().unwrap()[0] - xe).abs();
            eprintln!(
                "rtol {rtol:.0e}: error {e:.2e}, {} steps, {} rejected",
                s.stats.steps, s.stats.rejected
            );
            assert!(e < rtol.powf(2.0 / 3.0), "rtol {rtol}: error {e:.2e}");
            (e, s.stats.steps)
        })
        .collect();
    for w in runs.windows(2) {
        let (cut, more) = (w[0].0 / w[1].0, w[1].1 as f64 / w[0].1 as f64);
        assert!((10.0..=50.0).contains(&cut), "error cut {cut:.1}: {runs:?}");
        assert!((3.0..=7.0).contains(&more), "steps x{more:.1}: {runs:?}");
    }
}

/// Reference: Radau IIA (rtol 1e-11) on recast models, whose auxiliaries
/// `u_s = sin(phi)`, `u_c = 1 - cos(phi)` HHT carries along with the
/// positions (trapezoidal rule on `u_s' = (1 - u_c) phi'`, the algebraic
/// `0 = u_s^2 - 2 u_c + u_c^2` exactly): the simple pendulum from
/// `phi = 1` and the pendulum on the sprung slider (a constraint through
/// `sin phi2`, shifted equilibrium) from `x1 = 0.2`. Over three halvings of
/// the step the displacement errors at `t = 3` fall at rate 2 (within
/// 0.15); the auxiliaries stay on their definitions, `|u - u(phi)|` below
/// 1e-6 at the finest step (measured 4.1e-7), and the algebraic rows hold
/// to 1e-14 (round-off).
#[test]
fn converges_to_radau_on_recast_models() {
    for (model, start) in [("simple", ("phi", 1.0)), ("slider", ("x1", 0.2))] {
        let sys = system("pendulum", model, "");
        let rc = sys.recast.as_ref().expect("a recast model");
        let n0 = rc.n_original;
        let p = DaeProblem::new(&sys, 0.0, 0.0);
        let (guess, _) = sys.given_state(&[(start.0.into(), start.1)]);
        let t_end = 3.0;
        let reference = radau_reference(&p, &guess, t_end, 1e-11, 1e-13);
        let n_dof = sys.mechanical.as_ref().unwrap().n_dof;
        let mut errors = Vec::new();
        let mut drift = 0.0f64;
        let mut algebraic = 0.0f64;
        for h in [0.02, 0.01, 0.005, 0.0025] {
            let s = integrate(&p, &guess, 0.0, t_end, &HhtOptions::new(-0.1, h)).unwrap();
            let z = s.states.last().unwrap();
            errors.push(
                (0..n_dof)
                    .map(|i| (z[i] - reference[i]).abs())
                    .fold(0.0, f64::max),
            );
            drift = 0.0;
            for z in &s.states {
                let exact = rc.lift(&z[..n0]);
                drift = (n0..z.len())
                    .map(|i| (z[i] - exact[i]).abs())
                    .fold(drift, f64::max);
                let mut f = vec![0.0; z.len()];
                p.rhs(0.0, z, &mut f);
                let b = sys.b.as_ref();
                for (i, fi) in f.iter().enumerate().skip(n0) {
                    let has_b = (0..b.ncols()).any(|j| b.row_idx_of_col(j).any(|r| r == i));
                    if !has_b {
                        algebraic = algebraic.max(fi.abs());
                    }
                }
            }
        }
        eprintln!("{model}: errors {errors:?}, drift {drift:.2e}, algebraic {algebraic:.1e}");
        for w in errors.windows(2) {
            let rate = (w[0] / w[1]).log2();
            assert!(
                (rate - 2.0).abs() < 0.15,
                "{model}: rate {rate:.3}: {errors:?}"
            );
        }
        assert!(
            drift < 1e-6,
            "{model}: auxiliaries off their definitions by {drift:.2e}"
        );
        assert!(algebraic < 1e-14, "{model}: algebraic rows {algebraic:.2e}");
    }
}

/// Reference: Radau IIA (rtol 1e-10) on the chain of pendulums of Fig. 15
/// (405 states: 122 absolute coordinates, 80 constraints through `sin phi`
/// and `cos phi`, 80 auxiliaries), forced at `eps = 0.6`, `Omega = 2` from
/// `x1 = 0.05`: the HHT errors of the coordinates at `t = 10` fall at rate 2
/// (within 0.15) from `h = 0.01` to `0.0025` and stay below 1e-3 of the
/// peak at `h = 0.005`.
#[test]
fn integrates_the_pendulum_chain_at_second_order() {
    let sys = system("pendulum", "chain", "");
    assert_eq!(sys.n_states(), 405);
    let n_dof = sys.mechanical.as_ref().unwrap().n_dof;
    let p = DaeProblem::new(&sys, 0.6, 2.0);
    let (guess, _) = sys.given_state(&[("x1".into(), 0.05)]);
    let t_end = 10.0;
    let reference = radau_reference(&p, &guess, t_end, 1e-10, 1e-12)[..n_dof].to_vec();
    let peak = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let errors: Vec<f64> = [0.01, 0.005, 0.0025]
        .iter()
        .map(|&h| {
            let s = integrate(&p, &guess, 0.0, t_end, &HhtOptions::new(-0.1, h)).unwrap();
            let z = s.states.last().unwrap();
            (0..n_dof)
                .map(|i| (z[i] - reference[i]).abs())
                .fold(0.0, f64::max)
        })
        .collect();
    eprintln!("chain: errors {errors:?} (peak {peak:.3})");
    for w in errors.windows(2) {
        let rate = (w[0] / w[1]).log2();
        assert!((rate - 2.0).abs() < 0.15, "rate {rate:.3}: {errors:?}");
    }
    assert!(errors[1] < 1e-3 * peak, "{errors:?}");
}
