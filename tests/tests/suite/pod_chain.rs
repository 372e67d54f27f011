//! The `pod` reducer on the chain of pendulums in its redundant absolute
//! coordinates (plugin `pendulum`, model `chain`, Li, Jain & Haller 2023,
//! Appendix F, the 405-state DAE of Fig. 15): a model with non-polynomial
//! constraints (`x_i - x_{i-1} = l/2 (sin phi_i + sin phi_{i-1})`), which
//! the engine recasts with auxiliaries `sin phi`, `1 - cos phi`.
//!
//! The projection keeps the `sin` and `cos` terms as expressions of the
//! lifted angles `phi = (U q_r)_phi`, and the engine recasts the reduced
//! model in turn. Unlike the crank drive, the chain's motion does not lie
//! in a linear subspace: its POVs decay gradually, the projected nonlinear
//! constraints are all independent, and the number of constraint
//! combinations kept is a choice (the rank tolerance) that the reducer
//! refuses to make silently when it would lock the model.
//!
//! Reference: the full HHT run (alpha = -0.1, the same fixed steps), from
//! rest, on the training load and on a load not used for training.

use ssm_core::fom::hht::HhtSolution;
use ssm_core::model::system::System;
use ssm_core::reduce::pod::Truncation;
use ssm_core::reduce::pod_model::{pod_reduce, PodReduceError, PodSettings};
use ssm_tests::{hht_from_rest, model_and_system, pod_coordinate_error};

const STEP: f64 = 0.01;
const T_END: f64 = 30.0;
const EPS: f64 = 0.6;

fn run(sys: &System, omega: f64) -> HhtSolution {
    hht_from_rest(sys, EPS, omega, T_END, STEP)
}

/// Trained on 30 s from rest at eps = 0.6, Omega = 2 (the resonance of
/// Fig. 15), checked on the same load and on Omega = 1.85. Energy
/// truncations 1e-4 and 1e-7 (rank tolerance 1e-2) keep 3 + 2 and 6 + 5
/// POMs (translational + rotational) and 3 and 7 constraint combinations,
/// 93 and 109 states (asserted). The largest coordinate error
/// over the run, relative to the peak, is at most 5 % for the smaller and
/// 0.5 % for the larger model on both loads (measured 2.2 / 3.6 % and
/// 0.20 / 0.20 %), and falls by at least a factor 5 between them: the
/// error is the truncation's, not the integrator's (the HHT error of the
/// full run at this step is 6e-4 of the peak, tests/hht.rs). The 1e-7
/// model's Jacobian has more entries than the full model's: every lifted
/// angle mixes all POMs.
#[test]
fn chain_pod_error_falls_with_the_truncation() {
    let (raw, full) = model_and_system("pendulum", "chain", "");
    let train = run(&full, 2.0);
    let check = run(&full, 1.85);
    let mut errors = Vec::new();
    let nnz = |s: &System| {
        ssm_core::fom::DaeProblem::new(s, EPS, 2.0)
            .pattern()
            .row_idx()
            .len()
    };
    let full_nnz = nnz(&full);
    for (fraction, bound, poms, kept, states) in
        [(1e-4, 5e-2, [3, 2], 3, 93), (1e-7, 5e-3, [6, 5], 7, 109)]
    {
        let settings = PodSettings {
            truncation: Truncation::Energy { fraction },
            rank_tol: 1e-2,
            ..PodSettings::default()
        };
        let red = pod_reduce(&raw, &full, &train.states, &settings).expect("POD reduction");
        let (r, l) = (red.u.ncols(), red.constraints.basis.ncols());
        assert!(l < r, "{fraction}: r = {r}, l = {l}");
        let rsys = System::from_model("pod", red.model.clone()).expect("reduced model is valid");
        // the reduced model is recast on its own: one sin and one 1 - cos
        // auxiliary per lifted angle, as in the full model
        let aux = |s: &System| s.recast.as_ref().map_or(0, |x| x.auxiliaries.len());
        assert_eq!(aux(&rsys), aux(&full), "{fraction}");
        let e: Vec<f64> = [(&train, 2.0), (&check, 1.85)]
            .iter()
            .map(|(full_run, omega)| {
                pod_coordinate_error(full_run, &run(&rsys, *omega), red.u.as_ref())
            })
            .collect();
        let kept_poms: Vec<usize> = red.kinds.iter().map(|k| k.basis.kept()).collect();
        eprintln!(
            "energy {fraction:e}: POMs {kept_poms:?}, r = {r}, l = {l}, states {}, errors {e:.2?}, Jacobian entries {} (full {full_nnz})",
            rsys.n_states(),
            nnz(&rsys),
        );
        assert!(e.iter().all(|&x| x < bound), "{fraction}: {e:?}");
        assert_eq!(
            (kept_poms, l, rsys.n_states()),
            (poms.to_vec(), kept, states)
        );
        if fraction < 1e-5 {
            assert!(nnz(&rsys) > full_nnz, "{} against {full_nnz}", nnz(&rsys));
        }
        errors.push(e);
    }
    for k in 0..2 {
        assert!(errors[1][k] * 5.0 < errors[0][k], "{errors:?}");
    }
}

/// At the default rank tolerance (1e-8, exact redundancy) every projected
/// chain constraint is independent, so as many combinations as reduced
/// coordinates would be kept and the model could not move: a typed error
/// that names the counts and the singular values, not a locked model.
#[test]
fn chain_pod_refuses_to_lock_the_model() {
    let (raw, full) = model_and_system("pendulum", "chain", "n = 11");
    let train = hht_from_rest(&full, EPS, 2.0, 5.0, STEP);
    let settings = PodSettings {
        truncation: Truncation::Energy { fraction: 1e-4 },
        ..PodSettings::default()
    };
    let e = pod_reduce(&raw, &full, &train.states, &settings).unwrap_err();
    match &e {
        PodReduceError::NoFreedom { r, kept, values } => {
            assert_eq!(r, kept, "{e}");
            assert!(values.starts_with("1.00e0"), "{e}");
        }
        other => panic!("expected NoFreedom, got {other}"),
    }
    assert!(e.to_string().contains("raise rank_tol"), "{e}");
}
