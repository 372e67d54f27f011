//! The `[pod]` study of the V8 crank drive in its engine housing on mounts
//! (plugin `crank-drive`, model `crank-drive-housing`, zoo scene
//! `crank_drive_v8_housing_pod.toml`): the case of Stadlmayr, Witteveen &
//! Steiner (2017), Sect. 4.1, where the housing's vibration makes the
//! constraint directions tumble.
//!
//! References: the model's own kinematics (the null space of its
//! constraint Jacobian at the reference configuration: the housing's six
//! rigid motions and the crank's rotation) and its full HHT runs on the
//! same steps.

use faer::Mat;
use ssm_core::reduce::pod_model::constraint_jacobian;
use ssm_tests::{repo_root, run_scene_text};

/// Acceptance of issue 42, item 1: the POD of the housing model holds the
/// seven degrees of freedom at the reference configuration (each unit
/// vector of the null space of `C_q(0)`, which the housing's rigid motions
/// and the crank's rotation span, lies in the POD subspace to 5e-3;
/// measured 1.4e-3), and the reduced model keeps exactly seven (`r - l`).
/// The generalized constraint reduction removes combinations while no
/// constraint's projected Jacobian row vanishes over the training run, so
/// the reduction along fixed axes (the paper's reference [27]) removes
/// none, as the paper reports. The reduced runs match the full runs
/// within 2 % of each output's peak (the strokes of pistons 1 and 8, the
/// housing's displacements `hx`, `hy` and its roll `rot_z`) on the
/// training load and on an unseen load (measured 0.13 % and 0.17 %).
#[test]
fn housing_pod_keeps_seven_freedoms_and_reduces_tumbling_constraints() {
    let path = repo_root().join("zoo/crank_drive_v8_housing_pod.toml");
    let text = std::fs::read_to_string(&path).expect("zoo scene");
    let result = run_scene_text(&text).expect("the housing scene runs");
    let study = result.pod.expect("a POD study");
    let sys = &result.system;
    let mech = sys.mechanical.as_ref().expect("mechanical");
    let (n, nc) = (mech.n_dof, mech.n_constraints);
    assert_eq!((n, nc), (42, 35));
    let cq = constraint_jacobian(sys, &vec![0.0; sys.n_states()]);
    let svd = cq.svd().expect("SVD of C_q(0)");
    let s = svd.S().column_vector();
    assert!(s[nc - 1] > 1e-6 * s[0], "the constraints are independent");
    let v = svd.V();
    let null = Mat::from_fn(n, n - nc, |i, j| v[(i, nc + j)]);
    assert_eq!(study.pod.len(), 1);
    let rom = &study.pod[0];
    let u = &rom.reduction.u;
    let missed = &null - u * (u.transpose() * &null);
    let worst = (0..n - nc)
        .map(|j| missed.col(j).norm_l2())
        .fold(0.0, f64::max);
    eprintln!(
        "tangent space missed by the POD subspace: {worst:.2e}; {} coordinates, {} constraint combinations",
        u.ncols(),
        rom.reduction.constraints.basis.ncols()
    );
    assert!(worst < 5e-3, "{worst:e}");
    let kept = rom.reduction.constraints.basis.ncols();
    assert_eq!(u.ncols() - kept, n - nc, "seven degrees of freedom");
    assert!(rom.reduction.constraints.removed() > 0);
    assert!(
        rom.reduction.vanishing.is_empty(),
        "{:?}",
        rom.reduction.vanishing
    );
    assert_eq!(study.cases.len(), 2);
    for case in &study.cases {
        let run = &case.pod[0];
        let e = run.errors.as_ref().expect("the reduced run succeeds");
        eprintln!(
            "{}: error {:.2e} (late {:.2e}), full {:.3} s, reduced {:.3} s",
            case.case.label, e.max, e.late, case.full_s, run.online_s
        );
        assert!(e.max < 0.02, "{}: {:e}", case.case.label, e.max);
    }
}

/// A load switched in steps (`[pod.train] steps`, `DaeProblem::with_steps`)
/// against the closed form: the damped linear oscillator
/// `x'' + 2 zeta x' + x = eps a(t) f` (plugin `duffing` with `kappa = 0`, `Omega = 0`) from
/// rest, with `a = 0` before `t = 2`, 1 from there and -0.5 from `t = 5`,
/// responds as the superposed step responses `sum_k (a_k - a_{k-1}) eps f
/// g(t - t_k)`, `g(s) = 1 - e^{-zeta s} (cos w_d s + zeta / w_d sin w_d s)`.
/// HHT (alpha = -0.1, step 2^-10, the switch times on grid points) matches
/// it to 1e-3 of the peak (measured 6.4e-4) and converges at first order
/// (the error falls by 4 when the step falls by 4; measured 6.37e-4 ->
/// 1.59e-4): the jump costs the scheme its second order, since the step
/// ending at a switch time blends the new load into it (without steps the
/// same runs converge at second order, 3.8e-7 -> 2.4e-8). Without steps the
/// load acts from `t = 0` and the same comparison fails by more than 10 %.
#[test]
fn load_steps_give_the_superposed_step_responses() {
    use ssm_core::fom::hht::{integrate, HhtOptions};
    use ssm_core::fom::DaeProblem;
    let (_, sys) =
        ssm_tests::model_and_system("duffing", "duffing", "kappa = 0\nzeta = 0.05\nf = 2");
    let steps = [(2.0, 1.0), (5.0, -0.5)];
    let (zeta, eps, f) = (0.05, 0.3, 2.0);
    let wd = (1.0f64 - zeta * zeta).sqrt();
    let g = |s: f64| {
        if s < 0.0 {
            0.0
        } else {
            1.0 - (-zeta * s).exp() * ((wd * s).cos() + zeta / wd * (wd * s).sin())
        }
    };
    let exact = |t: f64| {
        let mut previous = 0.0;
        let mut x = 0.0;
        for &(tk, a) in &steps {
            x += (a - previous) * eps * f * g(t - tk);
            previous = a;
        }
        x
    };
    let z0 = vec![0.0; sys.n_states()];
    let run = |p: &DaeProblem, h: f64| {
        integrate(p, &z0, 0.0, 12.0, &HhtOptions::new(-0.1, h)).expect("HHT run")
    };
    let h = 1.0 / 1024.0;
    let stepped = run(&DaeProblem::new(&sys, eps, 0.0).with_steps(&steps), h);
    let finer = run(&DaeProblem::new(&sys, eps, 0.0).with_steps(&steps), h / 4.0);
    let always = run(&DaeProblem::new(&sys, eps, 0.0), h);
    let peak = stepped
        .times
        .iter()
        .map(|&t| exact(t).abs())
        .fold(0.0, f64::max);
    let error = |sol: &ssm_core::fom::hht::HhtSolution| {
        sol.times
            .iter()
            .zip(&sol.states)
            .map(|(&t, z)| (z[0] - exact(t)).abs())
            .fold(0.0, f64::max)
            / peak
    };
    let (e, e_finer, e_always) = (error(&stepped), error(&finer), error(&always));
    eprintln!(
        "step responses: error {e:.2e} of the peak {peak:.3} (half the step: {e_finer:.2e}); without the steps {e_always:.2e}"
    );
    assert!(e < 1e-3, "{e:e}");
    let ratio = e / e_finer;
    assert!(
        (3.5..4.5).contains(&ratio),
        "first order: {e:e} -> {e_finer:e}"
    );
    assert!(e_always > 0.1, "{e_always:e}");
}
