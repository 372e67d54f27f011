//! Full-system integration (Radau IIA) against independent references:
//! closed-form solutions, an independently integrated minimal-coordinate ODE,
//! conservation of energy, and constraint residuals over long runs.

use ssm_core::fom::{consistent_initial, DaeProblem, Radau, RadauOptions};
use ssm_tests::{linear_constrained_oscillator, system};

/// Integrates to `t_end` with a fixed step and returns the final state.
fn fixed_step_run(p: &DaeProblem, z0: &[f64], t_end: f64, steps: usize) -> Vec<f64> {
    let h = t_end / steps as f64;
    let opts = RadauOptions {
        fixed_step: Some(h),
        ..RadauOptions::default()
    };
    let mut r = Radau::new(p, 0.0, z0, t_end, opts).expect("starts");
    for _ in 0..steps {
        r.step(t_end).expect("fixed step converges");
    }
    assert!((r.t() - t_end).abs() < 1e-9 * t_end);
    r.z().to_vec()
}

/// Observed order `log2(e(h) / e(h/2))`.
fn order(e_coarse: f64, e_fine: f64) -> f64 {
    (e_coarse / e_fine).log2()
}

#[test]
fn linear_constraint_convergence_orders_match_radau_theory() {
    let (sys, _) = linear_constrained_oscillator(0.5);
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let mut guess = vec![0.0; sys.n_states()];
    guess[0] = 0.5;
    guess[1] = 0.48; // violates x1 = x2: projected with minimal change
    let c = consistent_initial(&p, 0.0, &guess).expect("consistent");
    let xp = 0.49;
    assert!(
        (c.z[0] - xp).abs() < 1e-14 && (c.z[1] - xp).abs() < 1e-14,
        "projected to {} {}",
        c.z[0],
        c.z[1]
    );
    assert!((c.position_correction - (0.5 - xp)).abs() < 1e-14);
    // reference: the closed form from the projected point
    let (_, exact) = linear_constrained_oscillator(xp);
    let (_, v0, mu0) = exact.at(0.0);
    assert!((c.z[2] - v0).abs() < 1e-14);
    assert!(
        (c.z[4] - mu0).abs() < 1e-9 * mu0.abs(),
        "consistent multiplier {} vs closed form {mu0}",
        c.z[4]
    );
    let t_end = 4.0;
    let (xe, ve, mue) = exact.at(t_end);
    let errs: Vec<[f64; 3]> = [20, 40, 80, 160]
        .iter()
        .map(|&steps| {
            let z = fixed_step_run(&p, &c.z, t_end, steps);
            [(z[0] - xe).abs(), (z[2] - ve).abs(), (z[4] - mue).abs()]
        })
        .collect();
    // Radau IIA (s = 3) on index-3 problems: positions O(h^5), velocities at
    // least O(h^3), multipliers at least O(h^2) (Hairer, Lubich & Roche 1989);
    // a linear constraint with constant G is the superconvergent case where
    // all components show order 5 at the step ends.
    for w in errs.windows(2) {
        let ox = order(w[0][0], w[1][0]);
        let ov = order(w[0][1], w[1][1]);
        let om = order(w[0][2], w[1][2]);
        eprintln!("observed orders: x {ox:.2}, x' {ov:.2}, mu {om:.2}");
        assert!((4.6..5.4).contains(&ox), "position order {ox}");
        assert!(ov > 2.8, "velocity order {ov}");
        assert!(om > 1.8, "multiplier order {om}");
    }
    // adaptive steps meet the tolerance against the closed form
    let mut r = Radau::new(&p, 0.0, &c.z, t_end, RadauOptions::default()).expect("starts");
    while r.t() < t_end {
        r.step(t_end).expect("step");
    }
    let z = r.z();
    eprintln!(
        "adaptive rtol 1e-8: {} steps, errors x {:.2e} x' {:.2e} mu {:.2e}",
        r.stats.accepted,
        (z[0] - xe).abs(),
        (z[2] - ve).abs(),
        (z[4] - mue).abs()
    );
    assert!((z[0] - xe).abs() < 1e-7 && (z[2] - ve).abs() < 1e-7 && (z[4] - mue).abs() < 1e-6);
    assert!(
        (z[0] - z[1]).abs() < 1e-14,
        "constraint drift {}",
        z[0] - z[1]
    );
}

/// Classical RK4 on `phi'' + c phi' + sin(phi) = 0` (eq. 21), written here
/// independently of the engine.
fn pendulum_rk4(phi0: f64, c: f64, t_end: f64, steps: usize) -> (f64, f64) {
    let f = |y: [f64; 2]| [y[1], -c * y[1] - y[0].sin()];
    let h = t_end / steps as f64;
    let mut y = [phi0, 0.0];
    for _ in 0..steps {
        let k1 = f(y);
        let k2 = f([y[0] + 0.5 * h * k1[0], y[1] + 0.5 * h * k1[1]]);
        let k3 = f([y[0] + 0.5 * h * k2[0], y[1] + 0.5 * h * k2[1]]);
        let k4 = f([y[0] + h * k3[0], y[1] + h * k3[1]]);
        for i in 0..2 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    (y[0], y[1])
}

#[test]
fn recast_pendulum_dae_converges_at_order_five_to_the_minimal_ode() {
    let sys = system("pendulum", "simple", "c = 0.1");
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let phi0 = 1.2;
    let mut guess = vec![0.0; sys.n_states()];
    guess[0] = phi0;
    let c = consistent_initial(&p, 0.0, &guess).expect("lifted");
    assert!((c.z[2] - phi0.sin()).abs() < 1e-15 && (c.z[3] - (1.0 - phi0.cos())).abs() < 1e-15);
    let t_end = 5.0;
    let (phi_ref, v_ref) = pendulum_rk4(phi0, 0.1, t_end, 200_000);
    let errs: Vec<f64> = [20, 40, 80, 160]
        .iter()
        .map(|&steps| {
            let z = fixed_step_run(&p, &c.z, t_end, steps);
            (z[0] - phi_ref).abs().max((z[1] - v_ref).abs())
        })
        .collect();
    for w in errs.windows(2) {
        let o = order(w[0], w[1]);
        eprintln!(
            "pendulum recast: error {:.3e} -> {:.3e}, order {o:.2}",
            w[0], w[1]
        );
        assert!((4.5..5.6).contains(&o), "observed order {o}");
    }
}

#[test]
fn conservative_pendulum_keeps_its_energy_over_100_periods() {
    let sys = system("pendulum", "simple", "c = 0.0");
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let phi0 = 1.0;
    let mut guess = vec![0.0; sys.n_states()];
    guess[0] = phi0;
    let c = consistent_initial(&p, 0.0, &guess).expect("lifted");
    let energy = |z: &[f64]| 0.5 * z[1] * z[1] + (1.0 - z[0].cos());
    let e0 = energy(&c.z);
    // period of the conservative pendulum: pi / AGM(1, cos(phi0 / 2))
    let (mut a, mut b) = (1.0f64, (0.5 * phi0).cos());
    for _ in 0..30 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    let period = std::f64::consts::PI / a;
    let t_end = 100.0 * period;
    let opts = RadauOptions {
        rtol: 1e-10,
        atol: 1e-10,
        ..RadauOptions::default()
    };
    let mut r = Radau::new(&p, 0.0, &c.z, t_end, opts).expect("starts");
    let (mut worst_e, mut worst_alg) = (0.0f64, 0.0f64);
    while r.t() < t_end {
        r.step(t_end).expect("step");
        worst_e = worst_e.max((energy(r.z()) - e0).abs() / e0);
        // the recast's algebraic equation u2 = 1 - cos(phi) in the form (22)
        let (us, uc) = (r.z()[2], r.z()[3]);
        worst_alg = worst_alg.max((us * us - 2.0 * uc + uc * uc).abs());
    }
    eprintln!(
        "c = 0, 100 periods ({} steps): relative energy error {worst_e:.2e}, algebraic residual {worst_alg:.2e}",
        r.stats.accepted
    );
    assert!(worst_e < 1e-8, "energy drift {worst_e}");
    // no drift: the algebraic equation holds at the Newton tolerance of the
    // stage equations for the whole run, below the local tolerance RADAU5
    // actually applies, 0.1 rtol^(2/3) = 2.2e-8
    assert!(worst_alg < 2.2e-8, "algebraic residual {worst_alg}");
    // the end point is back at the start after 100 periods
    assert!(
        (r.z()[0] - phi0).abs() < 1e-6,
        "phase error {}",
        r.z()[0] - phi0
    );
}

#[test]
fn trajectory_started_on_the_o13_oscillator_ssm_stays_on_it() {
    use num_complex::Complex64 as C64;
    use ssm_core::compare::{transient, TransientSettings};
    use ssm_core::spectrum::Normalization;
    use ssm_core::ssm::analysis::invariance_error;
    use ssm_tests::{oscillator_with_spectrum, ssm_of};
    // Fig. 4: rho0 = 0.35 (0.24 spherical), theta0 = 0.5, in the published
    // normalization (eigenvector 2-norm 0.8306)
    for (constraint, rho0) in [("none", 0.35), ("cubic", 0.35), ("spherical", 0.24)] {
        let (sys, sp) = oscillator_with_spectrum(constraint);
        let ssm = ssm_of(&sys, &sp, &[1], 13, Normalization::Scale(0.8306));
        let outs: Vec<_> = ["x1", "x2", "x3"]
            .iter()
            .map(|n| sys.output(n).expect("output"))
            .collect();
        let q = C64::from_polar(rho0, 0.5);
        let mut last: Option<(f64, f64)> = None;
        for order in [3, 7, 13] {
            let v = transient(
                &ssm,
                &sys,
                &TransientSettings {
                    order,
                    p0: &[q, q.conj()],
                    t_end: 100.0,
                    samples: 1001,
                    outputs: &outs,
                    radau: RadauOptions::default(),
                    full_start: None,
                },
            )
            .expect("validation runs");
            let inv = invariance_error(&ssm, &sys, order, rho0, 2, 60);
            let dist = v.distance.iter().copied().fold(0.0, f64::max);
            let err = (0..3).map(|k| v.relative_error(k)).fold(0.0, f64::max);
            let alg = v.algebraic_residual.iter().copied().fold(0.0, f64::max);
            eprintln!(
                "{constraint} O({order}): invariance error {inv:.2e}, max distance to the SSM {dist:.2e}, ROM error {err:.2e}, algebraic residual {alg:.1e}, {} steps",
                v.stats.accepted
            );
            // the full trajectory stays within the invariance error scale of
            // the manifold it started on (eq. (41) is a mean over the circle,
            // the distance a maximum over 100 time units)
            assert!(
                dist < 12.0 * inv,
                "distance {dist} vs invariance error {inv}"
            );
            assert!(alg < 1e-8, "constraint residual {alg}");
            if let Some((d0, e0)) = last {
                assert!(dist < d0, "distance does not fall with the order");
                assert!(err < e0, "ROM error does not fall with the order");
            }
            last = Some((dist, err));
        }
        assert!(last.expect("three orders").1 < 0.05);
    }
}

#[test]
fn chain_constraints_hold_over_100_periods_from_given_displacements() {
    use ssm_core::fom::consistent::algebraic_residual;
    let sys = system("pendulum", "chain", "");
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    // given displacements: the whole chain moved sideways by 0.3 (consistent)
    // and pendulum 10 swung by 0.4 rad about its centre, which breaks its two
    // joints by about l/2 * 0.4 = 6e-3; the projection repairs them
    let mut guess = vec![0.0; sys.n_states()];
    for (i, s) in sys.states.iter().enumerate() {
        if s.kind == ssm_api::StateKind::Displacement && s.name.as_str().starts_with('x') {
            guess[i] = 0.3;
        }
    }
    let phi10 = sys
        .states
        .iter()
        .position(|s| s.name.as_str() == "phi10")
        .expect("state phi10");
    guess[phi10] = 0.4;
    let c = consistent_initial(&p, 0.0, &guess).expect("projectable");
    assert!(c.constraint_residual < 1e-13 && c.velocity_residual < 1e-13);
    assert!(
        c.position_correction > 1e-3,
        "the guess violated the joints"
    );
    assert!(c.position_correction < 0.4, "the repair stays local");
    let period = 2.0 * std::f64::consts::PI / 1.9939;
    let t_end = 100.0 * period;
    let t0 = std::time::Instant::now();
    let mut r = Radau::new(&p, 0.0, &c.z, t_end, RadauOptions::default()).expect("starts");
    let (mut first, mut last) = (0.0f64, 0.0f64);
    while r.t() < t_end {
        r.step(t_end).expect("step");
        let res = algebraic_residual(&p, r.z()).0;
        if r.t() < 10.0 * period {
            first = first.max(res);
        } else if r.t() > 90.0 * period {
            last = last.max(res);
        }
    }
    let secs = t0.elapsed().as_secs_f64();
    eprintln!(
        "chain, 100 periods: {} steps in {secs:.2} s ({:.0} steps/s); largest constraint residual: first 10 periods {first:.2e}, last 10 {last:.2e}",
        r.stats.accepted,
        r.stats.accepted as f64 / secs
    );
    // the constraints hold at the Newton tolerance of the stage equations
    // (0.1 rtol^(2/3) = 4.6e-7 relative for rtol = 1e-8) and do not drift
    assert!(first < 1e-7 && last < 1e-7);
    assert!(
        last < 10.0 * first.max(1e-12),
        "drift: {first:.2e} -> {last:.2e}"
    );
}

#[test]
fn bad_inputs_give_errors_naming_time_and_cause() {
    use ssm_api::{PolyVector, SparseMatrix};
    use ssm_core::fom::SimError;
    use ssm_core::model::system::System;
    use ssm_plugin_kit::{Constraints, MechanicalSystem};
    use ssm_tests::oscillator_with_spectrum;
    // 1. an initial point the constraints cannot be evaluated at
    let (sys, _) = oscillator_with_spectrum("cubic");
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let mut guess = vec![0.0; sys.n_states()];
    guess[0] = 1e120;
    let e = consistent_initial(&p, 0.0, &guess).expect_err("beyond repair");
    assert!(
        matches!(e, SimError::Inconsistent { t, .. } if t == 0.0),
        "{e}"
    );
    eprintln!("{e}");
    guess[0] = f64::NAN;
    let e = consistent_initial(&p, 0.0, &guess).expect_err("NaN");
    assert!(e.to_string().contains("'x1'"), "{e}");
    // 2. a solution that escapes to infinity in finite time: x'' + x - 5 x^3 = 0
    let mut m = MechanicalSystem::new("escape", &["x"]);
    m.mass = SparseMatrix::diagonal(&[1.0]);
    m.stiffness = SparseMatrix::diagonal(&[1.0]);
    m.internal_force.push(0, -5.0, &[(0, 3)]);
    let sys = System::from_model("test", m.into_model().expect("valid")).expect("valid");
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let mut r = Radau::new(&p, 0.0, &[1.0, 0.0], 10.0, RadauOptions::default()).expect("starts");
    let e = loop {
        match r.step(10.0) {
            Ok(()) if r.t() < 10.0 => {}
            Ok(()) => panic!("the solution cannot reach t = 10"),
            Err(e) => break e,
        }
    };
    eprintln!("{e}");
    match &e {
        SimError::StepCollapse { t, .. } | SimError::NonFinite { t, .. } => {
            assert!(*t > 0.1 && *t < 3.0, "blow-up time {t}")
        }
        other => panic!("unexpected error {other}"),
    }
    assert!(e.to_string().contains("t = "));
    // 3. redundant constraints (x1 = x2 twice): G and the iteration matrix are singular
    let mut m = MechanicalSystem::new("redundant", &["x1", "x2"]);
    m.mass = SparseMatrix::diagonal(&[1.0, 2.0]);
    m.stiffness = SparseMatrix::diagonal(&[3.0, 5.0]);
    let mut g = PolyVector::zeros(2, 2);
    for j in 0..2 {
        g.push(j, 1.0, &[(0, 1)]);
        g.push(j, -1.0, &[(1, 1)]);
    }
    m.constraints = Some(Constraints::polynomial(g));
    let sys = System::from_model("test", m.into_model().expect("valid")).expect("valid");
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let z0 = [0.1, 0.1, 0.0, 0.0, 0.0, 0.0];
    let e = consistent_initial(&p, 0.0, &z0).expect_err("redundant");
    assert!(e.to_string().contains("redundant"), "{e}");
    let e = Radau::new(&p, 0.0, &z0, 1.0, RadauOptions::default())
        .and_then(|mut r| r.step(1.0))
        .expect_err("singular iteration matrix");
    eprintln!("{e}");
    assert!(
        matches!(e, SimError::SingularIteration { t, .. } if t == 0.0),
        "{e}"
    );
}

/// A frequency divider: `x1'' + 0.04 x1' + x1 + 0.5 x1 x2 + ... = 0`,
/// `x2'' + 0.08 x2' + 4 x2 + ... = 0.04 cos(Omega t)` ([`one_to_two_forced`]).
/// At `Omega = 2` the forced `x2` (amplitude about 0.25) exceeds the Mathieu
/// threshold `0.5 |x2| > 4 zeta = 0.08` for `x1`, whose response grows from a
/// small perturbation and locks at `Omega / 2`: a period-2T steady state, which
/// criterion (47) at period T never accepts. At `Omega = 1.6`, outside the
/// tongue, `x1` decays and the response has period T.
#[test]
fn period_doubled_steady_state_is_found_with_period_multiples() {
    use ssm_core::fom::{steady_state, SimError, SteadyOptions};
    use ssm_tests::one_to_two_forced;
    let sys = one_to_two_forced(0.02, 1.0);
    let outs = [sys.output("x1").unwrap(), sys.output("x2").unwrap()];
    let mut z0 = vec![0.0; sys.n_states()];
    z0[0] = 1e-3;
    let opts = |k: usize| SteadyOptions {
        delta: 1e-6,
        max_periods: 3000,
        max_multiple: k,
        ..SteadyOptions::default()
    };
    let p = DaeProblem::new(&sys, 0.04, 2.0);
    let s2 = steady_state(&p, &z0, &outs, &opts(2)).expect("period-2T response");
    eprintln!(
        "Omega = 2: period {} T after {} periods, |x1| = {:.4}, |x2| = {:.4}",
        s2.multiple, s2.periods, s2.amplitudes[0], s2.amplitudes[1]
    );
    assert_eq!(s2.multiple, 2);
    assert!(
        s2.amplitudes[0] > 0.05,
        "x1 is pumped: {}",
        s2.amplitudes[0]
    );
    // the same run with period T only cannot converge
    let e = steady_state(
        &p,
        &z0,
        &outs,
        &SteadyOptions {
            max_periods: s2.periods + 50,
            ..opts(1)
        },
    )
    .expect_err("not T-periodic");
    assert!(matches!(e, SimError::NotPeriodic { .. }), "{e}");
    assert!(e.to_string().contains("subharmonic"), "{e}");
    let p = DaeProblem::new(&sys, 0.04, 1.6);
    let s1 = steady_state(&p, &z0, &outs, &opts(2)).expect("period-T response");
    eprintln!(
        "Omega = 1.6: period {} T, |x1| = {:.2e}, |x2| = {:.4}",
        s1.multiple, s1.amplitudes[0], s1.amplitudes[1]
    );
    assert_eq!(s1.multiple, 1);
    assert!(s1.amplitudes[0] < 1e-6);
    // x2 on the linear response 0.04 / |4 - Omega^2 + 0.08 i Omega|, up to the cubic term
    let linear = 0.04 / ((4.0f64 - 2.56).powi(2) + (0.08f64 * 1.6).powi(2)).sqrt();
    assert!(
        (s1.amplitudes[1] - linear).abs() < 0.01 * linear,
        "{} vs {linear}",
        s1.amplitudes[1]
    );
}

/// `[simulate]` samples the full system: for the Shaw-Pierre oscillator
/// without its cubic spring (`kappa = 0`), the first mode started at
/// `x1 = x2 = a` gives the closed form
/// `x1'(t) = -a (c^2/4 + w_d^2) / w_d e^{-c t/2} sin(w_d t)`,
/// `w_d = sqrt(1 - c^2/4)`, matched to 1e-8 of `a` at every sample. Noise
/// is seeded: the same seed gives the same file, another seed another, and
/// the added noise has the standard deviation asked for (to 5 %).
#[test]
fn simulate_samples_the_closed_form_and_seeds_its_noise() {
    let (a, c) = (0.3f64, 0.02f64);
    let scene = |noise: f64, seed: u64| {
        format!(
            "[model]\nplugin = \"shaw-pierre\"\n[model.params]\nkappa = 0.0\nc = {c}\n[ssm]\norder = 3\n\
             [outputs]\ncoordinates = [\"x1\"]\n[simulate]\nperiod = 0.5\nsamples = 2000\n\
             outputs = [\"x1_dot\"]\nnoise = {noise}\nseed = {seed}\n\
             [[simulate.run]]\nx0 = {{ x1 = {a}, x2 = {a} }}\n"
        )
    };
    let csv = |noise: f64, seed: u64| {
        let r = ssm_tests::run_scene_text(&scene(noise, seed)).unwrap();
        String::from_utf8(r.outputs.get("simulation_1.csv").unwrap().to_vec()).unwrap()
    };
    let rows = |text: &str| -> Vec<(f64, f64)> {
        text.lines()
            .skip(1)
            .map(|l| {
                let (t, v) = l.split_once(',').unwrap();
                (t.parse().unwrap(), v.parse().unwrap())
            })
            .collect()
    };
    let wd = (1.0 - c * c / 4.0).sqrt();
    let exact = |t: f64| -a * (c * c / 4.0 + wd * wd) / wd * (-c * t / 2.0).exp() * (wd * t).sin();
    let clean = rows(&csv(0.0, 1));
    assert_eq!(clean.len(), 2000);
    for &(t, v) in &clean {
        assert!(
            (v - exact(t)).abs() < 1e-8 * a,
            "t = {t}: {v} vs {}",
            exact(t)
        );
    }
    let (n1, n1b, n2) = (csv(0.01, 7), csv(0.01, 7), csv(0.01, 8));
    assert_eq!(n1, n1b, "same seed, same data");
    assert_ne!(n1, n2, "another seed, other data");
    let peak = clean.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
    let noisy = rows(&n1);
    let var = noisy
        .iter()
        .zip(&clean)
        .map(|(n, c)| (n.1 - c.1).powi(2))
        .sum::<f64>()
        / clean.len() as f64;
    let sigma = var.sqrt();
    assert!(
        (sigma / (0.01 * peak) - 1.0).abs() < 0.05,
        "{sigma} vs {}",
        0.01 * peak
    );
}

/// Bad `[simulate]` settings are scene errors naming the key.
#[test]
fn simulate_refuses_bad_settings() {
    let base = "[model]\nplugin = \"shaw-pierre\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x1\"]\n[simulate]\n";
    let run = "[[simulate.run]]\nx0 = { x1 = 0.1 }\n";
    for (body, key, words) in [
        (
            format!("period = -1\nsamples = 10\n{run}"),
            "simulate.period",
            "positive",
        ),
        (
            format!("period = 0.1\nsamples = 1\n{run}"),
            "simulate.samples",
            "2 to",
        ),
        (
            format!("period = 0.1\nsamples = 10\nnoise = 2\n{run}"),
            "simulate.noise",
            "[0, 1]",
        ),
        (
            "period = 0.1\nsamples = 10\nrun = []\n".to_owned(),
            "simulate.run",
            "at least one",
        ),
        (
            "period = 0.1\nsamples = 10\n[[simulate.run]]\nx0 = { x1 = 0.1 }\nrho0 = [0.1]\n"
                .to_owned(),
            "simulate.run[1]",
            "not both",
        ),
        (
            "period = 0.1\nsamples = 10\n[[simulate.run]]\nx0 = { q9 = 0.1 }\n".to_owned(),
            "simulate.run[1].x0",
            "no Displacement state 'q9'",
        ),
        (
            "period = 0.1\nsamples = 10\n[[simulate.run]]\nv0 = { x1 = 0.1 }\n".to_owned(),
            "simulate.run[1].v0",
            "no Velocity state 'x1'",
        ),
        (format!("period = 1e306\nsamples = 1000\n{run}"), "simulate.period", "not a time"),
        (
            format!("period = 0.1\nsamples = 2000000\noutputs = [\"x1\", \"x2\", \"x1_dot\", \"x2_dot\"] \n{run}"),
            "simulate.samples",
            "exceed",
        ),
        (
            format!("period = 0.1\nsamples = 10\noutputs = [\"nope\"]\n{run}"),
            "simulate.outputs",
            "no output 'nope'",
        ),
        (
            format!("period = 0.1\nsamples = 10\nhht_alpha = 0.2\n{run}"),
            "simulate.hht_alpha",
            "[-1/3, 0]",
        ),
    ] {
        let (_, msg) = ssm_tests::scene_error(&format!("{base}{body}"));
        assert!(msg.starts_with(key) && msg.contains(words), "{key}: {msg}");
    }
}

/// Reference: the same `[simulate]` run integrated by Radau (rtol 1e-11):
/// with `hht_alpha = -0.1` (rtol 1e-8, atol 1e-10 on the positions' local
/// error) the samples agree within 1e-4 of the signal's peak over 200
/// samples, on the spatial oscillator with the cubic constraint (an index-3
/// DAE, `x1`) and on the pendulum on the sprung slider (recast: the
/// auxiliaries `sin phi2`, `1 - cos phi2` in its constraint, `phi2`).
#[test]
fn simulate_with_hht_matches_radau() {
    let cases = [
        (
            "plugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"cubic\"",
            "x1",
            "x0 = { x1 = 0.3, x2 = 0.2 }",
        ),
        (
            "plugin = \"pendulum\"\nname = \"slider\"",
            "phi2",
            "x0 = { x1 = 0.2 }",
        ),
    ];
    for (model, output, start) in cases {
        let scene = |integrator: &str| {
            format!(
                "[model]\n{model}\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"{output}\"]\n\
                 [simulate]\nperiod = 0.1\nsamples = 200\n{integrator}\n\
                 [[simulate.run]]\n{start}\n"
            )
        };
        let values = |text: &str| -> Vec<f64> {
            let r = ssm_tests::run_scene_text(text).expect("simulation runs");
            String::from_utf8(r.outputs.get("simulation_1.csv").unwrap().to_vec())
                .unwrap()
                .lines()
                .skip(1)
                .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
                .collect()
        };
        let radau = values(&scene("rtol = 1e-11\natol = 1e-13"));
        let hht = values(&scene("hht_alpha = -0.1\nrtol = 1e-8\natol = 1e-10"));
        let peak = radau.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gap = radau
            .iter()
            .zip(&hht)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "{output}: HHT against Radau: {:.2e} of the peak",
            gap / peak
        );
        assert_eq!(radau.len(), 200);
        assert!(
            gap < 1e-4 * peak && gap > 0.0,
            "{output}: gap {gap:.2e}, peak {peak}"
        );
    }
}
