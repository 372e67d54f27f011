//! The `pod` reducer (`reduce::pod_model`) on the crank drive of plugin
//! `crank-drive`, the stand-in for the V8 crank drive of Stadlmayr,
//! Witteveen & Steiner (2017), Sect. 4.1: 3-D natural coordinates, planar
//! motion, constraints that become redundant after the projection.
//!
//! References derived here from the kinematics, not from the code: piston
//! `i` on throw `k` of `K` in a bank at `gamma_i` strokes as
//! `s(theta + phi_i)`, `phi_i = beta_k - gamma_i`, along its own axis, with
//! `s(theta) = r cos(theta) + sqrt(l^2 - r^2 sin^2(theta))`. The first part
//! spans two functions whatever the phases; the root depends on
//! `2 (theta + phi)` only, one function per distinct `2 phi mod 360`. So the
//! piston velocities span `min(#phi, 2 + #(2 phi))` directions, the crank
//! vector `u` moves in the `x-y` plane (two directions), and every
//! out-of-plane coordinate stands still. After projection the reduced model
//! keeps `|u| = 1` and as many rod combinations as piston directions,
//! leaving one degree of freedom.

use std::collections::BTreeSet;

use faer::Mat;
use ssm_api::MotionKind;
use ssm_core::fom::hht::HhtSolution;
use ssm_core::model::system::System;
use ssm_core::reduce::pod::Truncation;
use ssm_core::reduce::pod_model::{constraint_jacobian, pod_reduce, PodReduction, PodSettings};
use ssm_tests::{hht_from_rest, model_and_system, pod_coordinate_error};

const STEP: f64 = 1e-3;

fn hht(sys: &System, eps: f64, omega: f64, t_end: f64) -> HhtSolution {
    hht_from_rest(sys, eps, omega, t_end, STEP)
}

/// Piston directions POD must find, `min(#phi, 2 + #(2 phi mod 360))`
/// over the phases `phi_i = beta_k - gamma_i` of the plugin's layout: one
/// throw per cylinder inline, two cylinders per throw on the banks at
/// `-v/2`, `+v/2` for a V engine.
fn piston_directions(cylinders: usize, v_angle: f64) -> usize {
    let v = v_angle > 0.0 && cylinders > 1;
    let throws = if v { cylinders.div_ceil(2) } else { cylinders };
    let phases: Vec<f64> = (0..cylinders)
        .map(|i| {
            let (k, gamma) = if v {
                (
                    i / 2,
                    if i % 2 == 0 {
                        -0.5 * v_angle
                    } else {
                        0.5 * v_angle
                    },
                )
            } else {
                (i, 0.0)
            };
            360.0 * k as f64 / throws as f64 - gamma
        })
        .collect();
    let distinct = |mult: f64| {
        phases
            .iter()
            .map(|p| ((mult * p).rem_euclid(360.0) * 1e6).round() as i64 % 360_000_000)
            .collect::<BTreeSet<_>>()
            .len()
    };
    distinct(1.0).min(2 + distinct(2.0))
}

fn reduce(model: &str, t_end: f64) -> (System, HhtSolution, PodReduction, System) {
    let (raw, full) = model_and_system("crank-drive", "crank-drive", model);
    let train = hht(&full, 1.0, 0.0, t_end);
    let red =
        pod_reduce(&raw, &full, &train.states, &PodSettings::default()).expect("POD reduction");
    let rsys = System::from_model("pod", red.model.clone()).expect("reduced model is valid");
    (full, train, red, rsys)
}

/// Acceptance of issue 17: POD of a training run (mean torque, from rest,
/// one second: about three revolutions) finds the planar motion, its
/// out-of-plane POVs at round-off (below 1e-12 of the largest of the kind);
/// the constraints reduce to the regular set `|u| = 1` plus one rod
/// combination per piston direction (smallest kept singular value above
/// 1e-3 of the largest; the rest below 1e-3 of it: round-off, or, for the
/// V8 at 179 degrees, two combinations that only the turning of the
/// Jacobian along the motion brings in, at 7e-5, beyond the instantaneous
/// rank); the reduced model has one degree of freedom and
/// reproduces the full coordinates on the training load and on a load it
/// was not trained on (1.5 times the torque plus a fluctuation at
/// Omega = 30 rad/s, 1.5 s). The acceptance asks for 1 %. The subspace is
/// exact here (the kinematics keep every coordinate in it), so two HHT runs
/// on the same steps differ only by their Newton tolerance: below 1e-10 of
/// the peak (measured 3.6e-14 to 1.5e-11); where one run halves a step
/// whose Newton iteration failed, by the HHT discretization error, below
/// 1e-4 (no run halves a step at present; at least four of the ten
/// comparisons must be on equal steps).
#[test]
fn crank_drive_pod_finds_the_planes_and_reduces_the_constraints() {
    let mut exact = 0;
    for (cylinders, v_angle) in [(4usize, 0.0), (8, 90.0), (3, 60.0), (1, 0.0), (8, 179.0)] {
        let model = format!("cylinders = {cylinders}\nv_angle = {v_angle}\ntau_amp = 0.5");
        let (full, train, red, rsys) = reduce(&model, 1.0);
        let phases = piston_directions(cylinders, v_angle);
        let label = format!("{cylinders} cylinders, V {v_angle}");
        for k in &red.kinds {
            let expected = if k.motion == MotionKind::Rotational {
                2
            } else {
                phases
            };
            let v = &k.basis.values;
            assert_eq!(
                k.basis.kept(),
                expected,
                "{label} {:?}: POVs {v:?}",
                k.motion
            );
            assert!(v[expected - 1] > 1e-6 * v[0], "{label}: {v:?}");
            assert!(
                v[expected..].iter().all(|&s| s < 1e-12 * v[0]),
                "{label}: out-of-plane POVs {v:?}"
            );
        }
        let m = 2 + 3 * cylinders;
        let l = 1 + phases;
        let sv = &red.constraints.singular_values;
        assert_eq!(red.constraints.basis.ncols(), l, "{label}: {sv:?}");
        assert_eq!(red.constraints.removed(), m - l);
        assert!(sv[l - 1] > 1e-3 * sv[0], "{label}: {sv:?}");
        assert!(sv[l..].iter().all(|&s| s < 1e-3 * sv[0]), "{label}: {sv:?}");
        assert_eq!(red.u.ncols() - l, 1, "{label}: one degree of freedom");
        assert_eq!(red.initial_residual, [0.0, 0.0]);
        let same = hht(&rsys, 1.0, 0.0, 1.0);
        let e_train = pod_coordinate_error(&train, &same, red.u.as_ref());
        let other_full = hht(&full, 1.5, 30.0, 1.5);
        let other_red = hht(&rsys, 1.5, 30.0, 1.5);
        let e_test = pod_coordinate_error(&other_full, &other_red, red.u.as_ref());
        for (e, a, b) in [(e_train, &train, &same), (e_test, &other_full, &other_red)] {
            eprintln!(
                "{label}: coordinate error {e:.2e} (rejected steps {} / {})",
                a.stats.rejected, b.stats.rejected
            );
            assert!(e < 1e-4, "{label}: {e:e}");
            if a.stats.rejected == 0 && b.stats.rejected == 0 {
                assert!(e < 1e-10, "{label}: {e:e} on equal steps");
                exact += 1;
            }
        }
    }
    assert!(exact >= 4, "{exact} comparisons on equal steps");
}

/// The constraint-force caveat of the paper (Sect. 3.5), quantified on the
/// four-cylinder engine: the reduced reactions `C_q^T L mu_l` agree with
/// the full ones `C_q^T mu` inside the POD subspace (`U^T` of both to 1e-8
/// of the peak reaction; measured 2e-10), while in the full space they miss
/// the reactions of the removed constraints, the pistons' side thrust
/// against the cylinder walls, which reaches a fixed fraction of the rod
/// force (about `r / l`): more than 20 % of the peak reaction (measured
/// 21.8 %).
#[test]
fn crank_drive_reduced_reactions_miss_the_side_thrust() {
    let (full, train, red, rsys) = reduce("cylinders = 4", 1.0);
    let reduced = hht(&rsys, 1.0, 0.0, 1.0);
    let (n, r) = (red.u.nrows(), red.u.ncols());
    let nc = red.constraints.basis.nrows();
    let (mut peak, mut in_subspace, mut full_space) = (0.0f64, 0.0f64, 0.0f64);
    for (z, y) in train.states.iter().zip(&reduced.states).skip(1) {
        let cq = constraint_jacobian(&full, z);
        let mu = Mat::from_fn(nc, 1, |j, _| z[2 * n + j]);
        let mu_l = Mat::from_fn(red.constraints.basis.ncols(), 1, |j, _| y[2 * r + j]);
        let full_reaction = cq.transpose() * &mu;
        let reduced_reaction = cq.transpose() * (&red.constraints.basis * &mu_l);
        let diff = &full_reaction - &reduced_reaction;
        peak = peak.max(full_reaction.norm_max());
        full_space = full_space.max(diff.norm_max());
        in_subspace = in_subspace.max((red.u.transpose() * &diff).norm_max());
    }
    eprintln!(
        "reactions: in the subspace {:.2e}, full space {:.3} of the peak",
        in_subspace / peak,
        full_space / peak
    );
    assert!(in_subspace < 1e-8 * peak, "{in_subspace:e} of {peak:e}");
    assert!(full_space > 0.2 * peak, "{full_space:e} of {peak:e}");
}

/// A run in which nothing moves has no POD basis; bad settings and a model
/// with auxiliary states are refused with typed errors.
#[test]
fn pod_reducer_refuses_bad_input() {
    let (raw, full) = model_and_system("crank-drive", "crank-drive", "cylinders = 2");
    let rest = vec![vec![0.0; full.states.len()]; 10];
    let e = pod_reduce(&raw, &full, &rest, &PodSettings::default()).unwrap_err();
    assert!(e.to_string().contains("nothing moves"), "{e}");
    let e = pod_reduce(&raw, &full, &rest[..1], &PodSettings::default()).unwrap_err();
    assert!(e.to_string().contains("at least two"), "{e}");
    let short = vec![vec![0.0; 3]; 4];
    let e = pod_reduce(&raw, &full, &short, &PodSettings::default()).unwrap_err();
    assert!(e.to_string().contains("states"), "{e}");
    let train = hht(&full, 1.0, 0.0, 0.2);
    for settings in [
        PodSettings {
            truncation: Truncation::Energy { fraction: 1.5 },
            ..PodSettings::default()
        },
        PodSettings {
            rank_tol: f64::NAN,
            ..PodSettings::default()
        },
        PodSettings {
            jacobian_samples: 0,
            ..PodSettings::default()
        },
    ] {
        assert!(pod_reduce(&raw, &full, &train.states, &settings).is_err());
    }
    let mut nan = train.states.clone();
    nan[3][full.states.len() / 2] = f64::NAN;
    assert!(pod_reduce(&raw, &full, &nan, &PodSettings::default()).is_err());
    let (chain_raw, chain) = model_and_system("pendulum", "chain", "n = 3");
    let z = vec![vec![0.0; chain.states.len()]; 3];
    let e = pod_reduce(&chain_raw, &chain, &z, &PodSettings::default()).unwrap_err();
    assert!(e.to_string().contains("nothing moves"), "{e}");
    let e = pod_reduce(&raw, &chain, &z, &PodSettings::default()).unwrap_err();
    assert!(e.to_string().contains("is not the model"), "{e}");
}

/// Extreme but valid geometries build and integrate (a rod barely longer
/// than the crank, a tiny engine), and
/// the reduction of such a run still keeps one degree of freedom.
#[test]
fn extreme_geometries_reduce_to_one_degree_of_freedom() {
    for model in [
        "cylinders = 2\nl = 0.0501",
        "cylinders = 5\nr = 1e-3\nl = 2e-3\nj_crank = 1e-6",
    ] {
        let (_, _, red, rsys) = reduce(model, 0.5);
        assert_eq!(red.u.ncols() - red.constraints.basis.ncols(), 1, "{model}");
        hht(&rsys, 1.0, 0.0, 0.5);
    }
}
