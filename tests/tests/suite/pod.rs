//! POD and the generalized constraint reduction (`reduce::pod`) against the
//! examples and statements of Stadlmayr, Witteveen & Steiner (2017): the
//! one-mass example of Fig. 1 simulated with HHT, snapshots with known POVs
//! for the truncation rules, and redundant constraints in oblique directions.

use faer::Mat;
use ssm_api::{PolyVector, SparseMatrix};
use ssm_core::fom::hht::{integrate, HhtOptions};
use ssm_core::fom::DaeProblem;
use ssm_core::model::system::System;
use ssm_core::reduce::pod::{
    global_projection, pod, reduce_constraints, residual_term, PodError, Truncation,
};
use ssm_plugin_kit::{Constraints, MechanicalSystem};

/// Reference: Sect. 3.5 and Fig. 1 of the paper. A mass `m = 2` on a spring
/// `k = 5` in `x` and `y`, held by the constraint `C_1 = y = 0`, released
/// from `x = 0.1`; its velocity snapshots (HHT, 400 steps) have one nonzero
/// POV and one below 1e-12 of it, the drop rule keeps one POM, `U = [1, 0]^T`
/// (up to sign, to 1e-12), the projected constraint Jacobian `C_q U` is
/// zero, the constraint reduction removes the constraint, and the reduced
/// system's Jacobian `U^T M U` is `[m]`.
#[test]
fn one_mass_example_of_fig_1() {
    let mut s = MechanicalSystem::new("one-mass", &["x", "y"]);
    s.mass = SparseMatrix::diagonal(&[2.0, 2.0]);
    s.stiffness = SparseMatrix::diagonal(&[5.0, 5.0]);
    let mut g = PolyVector::zeros(1, 2);
    g.push(0, 1.0, &[(1, 1)]);
    s.constraints = Some(Constraints::polynomial(g));
    let sys = System::from_model("catalogue", s.into_model().unwrap()).unwrap();
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let run = integrate(
        &p,
        &[0.1, 0.0, 0.0, 0.0, 0.0],
        0.0,
        8.0,
        &HhtOptions::new(-0.1, 0.02),
    )
    .unwrap();
    let snapshots = Mat::from_fn(2, run.states.len(), |i, j| run.states[j][2 + i]);
    let basis = pod(
        snapshots.as_ref(),
        "translational",
        Truncation::Drop { decades: 3.0 },
    )
    .unwrap();
    assert!(basis.values[0] > 0.1, "{:?}", basis.values);
    assert!(
        basis.values[1] < 1e-12 * basis.values[0],
        "{:?}",
        basis.values
    );
    assert_eq!(basis.kept(), 1);
    let u = global_projection(2, &[(&[0, 1], &basis)]);
    assert!((u[(0, 0)].abs() - 1.0).abs() < 1e-12 && u[(1, 0)].abs() < 1e-12);
    // C_q = [0 1]
    let cq_u = Mat::from_fn(1, 1, |_, _| u[(1, 0)]);
    let c = reduce_constraints(cq_u.as_ref(), 1e-10).unwrap();
    assert_eq!(c.removed(), 1);
    let mass = u[(0, 0)] * 2.0 * u[(0, 0)] + u[(1, 0)] * 2.0 * u[(1, 0)];
    assert!((mass - 2.0).abs() < 1e-12, "U^T M U = {mass}");
}

/// Snapshots whose rows are orthogonal signals of norms 1, 1e-3 and 1e-9
/// (sines of 1, 2 and 3 cycles over a full period, sampled uniformly), so
/// that the POVs are those norms times `sqrt(h / 2)`: the POVs match to
/// 1e-9 relative, the drop rule keeps 1 POM at a drop of 2 decades and 2 at
/// 4, the energy rule keeps 1, 2 and 3 for fractions 1e-3, 1e-8 and 1e-20,
/// and the POMs are the coordinate axes.
#[test]
fn truncation_rules_on_known_povs() {
    let h = 400;
    let norms = [1.0, 1e-3, 1e-9];
    let x = Mat::from_fn(3, h, |i, j| {
        let t = 2.0 * std::f64::consts::PI * j as f64 / h as f64;
        norms[i] * ((i + 1) as f64 * t).sin()
    });
    let scale = (h as f64 / 2.0).sqrt();
    let keep = |rule| pod(x.as_ref(), "test", rule).unwrap();
    let b = keep(Truncation::Drop { decades: 2.0 });
    for (v, n) in b.values.iter().zip(norms) {
        assert!((v / (n * scale) - 1.0).abs() < 1e-9, "{:?}", b.values);
    }
    assert_eq!(b.kept(), 1);
    assert!((b.modes[(0, 0)].abs() - 1.0).abs() < 1e-12);
    assert_eq!(keep(Truncation::Drop { decades: 4.0 }).kept(), 2);
    for (fraction, kept) in [(1e-3, 1), (1e-8, 2), (1e-20, 3)] {
        assert_eq!(
            keep(Truncation::Energy { fraction }).kept(),
            kept,
            "{fraction}"
        );
    }
}

/// The modified Galerkin projection (eq. 8): with `U` the first axis of
/// three, `U q_r(0) + R_q0 = q0` for `q_r(0) = U^T q0` exactly, and
/// `R_q0` is orthogonal to `U`.
#[test]
fn residual_term_restores_the_initial_values() {
    let u = Mat::from_fn(3, 1, |i, _| if i == 0 { 1.0 } else { 0.0 });
    let q0 = [0.3, -0.2, 0.7];
    let r = residual_term(u.as_ref(), &q0);
    assert_eq!(r, vec![0.0, -0.2, 0.7]);
}

/// Redundant constraints in oblique directions (the case the method of [27]
/// misses, Sect. 3.4): on a two-dimensional subspace three constraints with
/// `C_q U = [[1, 1], [2, 2], [1e-14, 0]]` carry one independent direction;
/// the reduction keeps `l = 1`, removes 2, and `L^i (L^i)^T C_q U`
/// reproduces `C_q U` to 1e-13.
#[test]
fn oblique_redundant_constraints_reduce_to_their_rank() {
    let rows = [[1.0, 1.0], [2.0, 2.0], [1e-14, 0.0]];
    let cq_u = Mat::from_fn(3, 2, |i, j| rows[i][j]);
    let c = reduce_constraints(cq_u.as_ref(), 1e-10).unwrap();
    assert_eq!((c.basis.ncols(), c.removed()), (1, 2));
    for j in 0..2 {
        let col: Vec<f64> = (0..3).map(|i| rows[i][j]).collect();
        let reduced = c.reduce(&col);
        for (i, row) in rows.iter().enumerate() {
            let back = c.basis[(i, 0)] * reduced[0];
            assert!((back - row[j]).abs() < 1e-13, "({i}, {j}): {back}");
        }
    }
}

/// Bad input: an empty snapshot matrix, a NaN snapshot, a drop of zero
/// decades, an energy fraction of 1 and a rank tolerance of 0 each give a
/// typed error naming the problem.
#[test]
fn bad_snapshots_and_settings_are_refused() {
    let empty = Mat::<f64>::zeros(2, 0);
    let e = pod(empty.as_ref(), "rot", Truncation::Drop { decades: 3.0 }).unwrap_err();
    assert!(matches!(e, PodError::Empty { .. }), "{e}");
    let mut x = Mat::<f64>::from_fn(2, 5, |i, j| (i + j) as f64);
    x[(1, 3)] = f64::NAN;
    let e = pod(x.as_ref(), "rot", Truncation::Drop { decades: 3.0 }).unwrap_err();
    assert!(e.to_string().contains("snapshot 3 of coordinate 1"), "{e}");
    let y = Mat::<f64>::from_fn(2, 5, |i, j| (i + j) as f64);
    for rule in [
        Truncation::Drop { decades: 0.0 },
        Truncation::Energy { fraction: 1.0 },
    ] {
        let e = pod(y.as_ref(), "rot", rule).unwrap_err();
        assert!(matches!(e, PodError::Truncation(_)), "{e}");
    }
    assert!(reduce_constraints(y.as_ref(), 0.0).is_err());
}

/// The symbolic substitution of `reduce::galerkin` against evaluation
/// through the full model: on the spatial oscillator with the cubic
/// constraint (quadratic and cubic forces, a cubic constraint and its
/// multiplier terms, a forcing harmonic), with an oblique orthonormal `U`
/// (`3 x 2`) and `L = [-1]`, the reduced right-hand side at 20 pseudo-random
/// states equals `V^T (A + F + eps Fext)(V y)` and `B_r y = V^T B V y`, to
/// 1e-13 of their size.
#[test]
fn galerkin_projection_equals_projected_evaluation() {
    use ssm_api::MotionKind;
    use ssm_core::reduce::galerkin::{project_mechanical, ReducedCoordinates};
    let (raw, sys) =
        ssm_tests::model_and_system("spatial-oscillator", "", "constraint = \"cubic\"");
    // orthonormal columns (1, 2, 2)/3 and (2, 1, -2)/3
    let u = Mat::from_fn(3, 2, |i, j| {
        [[1.0, 2.0], [2.0, 1.0], [2.0, -2.0]][i][j] / 3.0
    });
    let l = Mat::from_fn(1, 1, |_, _| -1.0);
    let coords = ReducedCoordinates {
        names: vec!["a".into(), "b".into()],
        motion: vec![MotionKind::Translational; 2],
    };
    let (model, lift) = project_mechanical(&raw, u.as_ref(), l.as_ref(), &coords).unwrap();
    let red = System::from_model("pod", model).unwrap();
    assert_eq!(red.states.len(), 5);
    let mut v = Mat::<f64>::zeros(7, 5);
    for (i, j, w) in lift.basis.iter() {
        v[(i, j)] = w;
    }
    let (eps, omega, t) = (0.3, 1.7, 0.9);
    let (pf, pr) = (
        DaeProblem::new(&sys, eps, omega),
        DaeProblem::new(&red, eps, omega),
    );
    let mut next = uniform(7u64);
    for _ in 0..20 {
        let y: Vec<f64> = (0..5).map(|_| next()).collect();
        let z: Vec<f64> = (0..7)
            .map(|i| (0..5).map(|j| v[(i, j)] * y[j]).sum())
            .collect();
        let (mut fz, mut bz) = (vec![0.0; 7], vec![0.0; 7]);
        pf.rhs(t, &z, &mut fz);
        pf.b_mul(&z, &mut bz);
        let (mut fy, mut by) = (vec![0.0; 5], vec![0.0; 5]);
        pr.rhs(t, &y, &mut fy);
        pr.b_mul(&y, &mut by);
        for (full, reduced) in [(&fz, &fy), (&bz, &by)] {
            let projected: Vec<f64> = (0..5)
                .map(|j| (0..7).map(|i| v[(i, j)] * full[i]).sum())
                .collect();
            let size = projected.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for (p, r) in projected.iter().zip(reduced.iter()) {
                assert!((p - r).abs() < 1e-13 * size, "{projected:?} vs {reduced:?}");
            }
        }
    }
}

/// Hostile bases for the projection: NaN entries, wrong row counts and
/// mismatched names are typed errors naming the input; a map or a model
/// without mechanical structure is refused, and so is a model with a
/// polynomial term in a state it does not have.
#[test]
fn galerkin_projection_refuses_bad_bases() {
    use ssm_api::MotionKind;
    use ssm_core::reduce::galerkin::{project_mechanical, GalerkinError, ReducedCoordinates};
    let (sys, _) = ssm_tests::model_and_system("spatial-oscillator", "", "constraint = \"cubic\"");
    let coords = |r: usize| ReducedCoordinates {
        names: (0..r).map(|k| format!("c{k}")).collect(),
        motion: vec![MotionKind::Translational; r],
    };
    let l = Mat::from_fn(1, 1, |_, _| 1.0);
    let mut u = Mat::from_fn(3, 1, |i, _| if i == 0 { 1.0 } else { 0.0 });
    u[(2, 0)] = f64::NAN;
    let e = project_mechanical(&sys, u.as_ref(), l.as_ref(), &coords(1)).unwrap_err();
    assert!(
        matches!(
            e,
            GalerkinError::NotFinite {
                what: "U",
                row: 2,
                col: 0
            }
        ),
        "{e}"
    );
    let u = Mat::<f64>::zeros(2, 1);
    let e = project_mechanical(&sys, u.as_ref(), l.as_ref(), &coords(1)).unwrap_err();
    assert!(
        matches!(
            e,
            GalerkinError::Shape {
                what: "U",
                found: 2,
                expected: 3
            }
        ),
        "{e}"
    );
    let u = Mat::from_fn(3, 1, |i, _| if i == 0 { 1.0 } else { 0.0 });
    let e = project_mechanical(&sys, u.as_ref(), l.as_ref(), &coords(2)).unwrap_err();
    assert!(e.to_string().contains("names"), "{e}");
    let mut corrupt = sys.clone();
    corrupt.nonlinearity.push(0, 1.0, &[(99, 2)]);
    let e = project_mechanical(&corrupt, u.as_ref(), l.as_ref(), &coords(1)).unwrap_err();
    assert!(matches!(e, GalerkinError::Invalid { .. }), "{e}");
    let map = ssm_tests::cubic_map_model();
    let e = project_mechanical(&map, u.as_ref(), l.as_ref(), &coords(1)).unwrap_err();
    assert!(matches!(e, GalerkinError::Unsupported { .. }), "{e}");
}

/// The projection of a model with non-polynomial terms and an equilibrium
/// (the chain of pendulums, n = 4: `sin phi`, `cos phi mu` terms, gravity
/// balanced by the multipliers `mu_eq`), against evaluation through the
/// full model's original (unrecast) right-hand side: for an oblique `U`
/// (`11 x 3`) and `L` (`7 x 2`), the reduced model's original right-hand
/// side at 20 pseudo-random `y` equals `V^T` of the full one at
/// `z_eq + V y`, to 1e-12 of its size; at `y = 0` both vanish (the reduced
/// model is written about the equilibrium).
#[test]
fn galerkin_projection_keeps_expressions_and_the_equilibrium() {
    use ssm_api::MotionKind;
    use ssm_core::reduce::galerkin::{project_mechanical, ReducedCoordinates};
    let (raw, full) = ssm_tests::model_and_system("pendulum", "chain", "n = 4");
    let (n, nc) = (11, 7);
    assert_eq!(raw.states.len(), 2 * n + nc);
    assert!(!raw.equilibrium.is_empty() && !raw.expressions.is_empty());
    let mut next = uniform(11u64);
    let u = Mat::from_fn(n, 3, |_, _| next());
    let l = Mat::from_fn(nc, 2, |_, _| next());
    let coords = ReducedCoordinates {
        names: vec!["a".into(), "b".into(), "c".into()],
        motion: vec![MotionKind::Translational; 3],
    };
    let (model, lift) = project_mechanical(&raw, u.as_ref(), l.as_ref(), &coords).unwrap();
    assert_eq!(lift.offset.as_slice(), raw.equilibrium.as_slice());
    let red = System::from_model("pod", model).expect("the reduced model recasts");
    let (rf, rr) = (full.recast.as_ref().unwrap(), red.recast.as_ref().unwrap());
    let nr = rr.n_original;
    assert_eq!(nr, 8);
    let mut v = Mat::<f64>::zeros(2 * n + nc, nr);
    for (i, j, w) in lift.basis.iter() {
        v[(i, j)] = w;
    }
    for k in 0..21 {
        let y: Vec<f64> = (0..nr)
            .map(|_| if k == 0 { 0.0 } else { 0.4 * next() })
            .collect();
        let z: Vec<f64> = (0..2 * n + nc)
            .map(|i| (0..nr).map(|j| v[(i, j)] * y[j]).sum())
            .collect();
        let fz = rf.original_rhs(&z);
        let fy = rr.original_rhs(&y);
        let projected: Vec<f64> = (0..nr)
            .map(|j| (0..2 * n + nc).map(|i| v[(i, j)] * fz[i]).sum())
            .collect();
        let size = projected.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        for (p, r) in projected.iter().zip(&fy) {
            assert!((p - r).abs() < 1e-12 * size, "{projected:?} vs {fy:?}");
        }
    }
}

/// Reproducible numbers uniform in `[-0.5, 0.5)` (a 64-bit linear
/// congruential generator seeded with `seed`).
fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// Steps per period `2 pi / (omega step)`: 1.9 is an error (above
/// Nyquist), 2.1 and 19 are warnings, 21 and a free run are silent.
#[test]
fn load_sampling_refuses_aliasing_and_warns_on_coarse_steps() {
    let step = 0.01;
    let omega = |per_period: f64| 2.0 * std::f64::consts::PI / (per_period * step);
    let e = ssm_engine::scene::load_sampling(step, omega(1.9)).unwrap_err();
    assert!(e.contains("Nyquist"), "{e}");
    for n in [2.1, 19.0] {
        let w = ssm_engine::scene::load_sampling(step, omega(n))
            .unwrap()
            .expect("warning");
        assert!(w.contains("fewer than 20"), "{w}");
    }
    assert_eq!(
        ssm_engine::scene::load_sampling(step, omega(21.0)),
        Ok(None)
    );
    assert_eq!(ssm_engine::scene::load_sampling(step, 0.0), Ok(None));
}
