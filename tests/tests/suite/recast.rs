//! Checks of the recast against the original expressions: the right-hand sides
//! agree on random states, the auxiliaries' algebraic relations hold to round-off,
//! their differential equations match the time derivative of their definitions,
//! and the physical pencil has the recast pencil's spectrum minus the spurious
//! zero modes.

use ssm_api::SparseMatrix;
use ssm_plugin_kit::{Constraints, Equilibrium, Expr, MechanicalSystem};

use ssm_core::model::recast::{AuxKind, RecastError};
use ssm_core::model::system::{ModelError, System};
use ssm_core::spectrum::dense::finite_eigenvalues;
use ssm_core::spectrum::modes::spmv;
use ssm_engine::C64;
use ssm_kernel::poly::eval_poly;

/// Two dofs and one constraint using every supported function, nested ones
/// and a velocity inside a reciprocal; every term vanishes at the origin.
fn every_function() -> System {
    let x = Expr::var;
    let mut s = MechanicalSystem::new("every-function", &["x1", "x2"]);
    s.mass = SparseMatrix::diagonal(&[1.0, 2.0]);
    s.damping = SparseMatrix::diagonal(&[0.1, 0.2]);
    s.stiffness = SparseMatrix::diagonal(&[1.0, 3.0]);
    let f0 = x(0).sin() + (0.3 * x(1)).exp() - 1.0
        + 0.2 * ((2.0 + x(0) * x(1)).ln() - 2f64.ln())
        + 0.1 * ((1.0 + x(0).powi(2)).sqrt() - 1.0)
        + 0.5 * x(1) * (1.0 + x(0).powi(2)).recip();
    let f1 = x(1).sin().sin() * (0.5 + x(0)).cos()
        + ((1.0 + x(1)).powi(-2) - 1.0)
        + 0.1 * x(0) * ((1.0 + x(2).powi(2)).recip() - 1.0);
    s.force_expressions = vec![(0, f0), (1, f1)];
    s.constraints = Some(Constraints::expressions(
        2,
        vec![x(1) - 0.3 * x(0).sin() + 0.05 * (x(0) * x(1)).exp() - 0.05],
    ));
    System::from_model("test", s.into_model().expect("builds")).expect("recasts")
}

fn pseudo_random(k: usize) -> f64 {
    let x = ((k as f64 + 1.0) * 12.9898).sin() * 43758.5453;
    x - x.floor() - 0.5
}

fn recast_rhs(sys: &System, z: &[f64]) -> Vec<f64> {
    let zc: Vec<C64> = z.iter().map(|&v| C64::new(v, 0.0)).collect();
    let mut out = spmv(sys.a.as_ref(), &zc);
    eval_poly(&sys.nonlinearity, &zc, &mut out);
    out.iter().map(|c| c.re).collect()
}

#[test]
fn recast_agrees_with_original_expressions_on_random_states() {
    let sys = every_function();
    let rc = sys.recast.as_ref().expect("recast");
    let n = rc.n_original;
    assert_eq!(n, 5);
    assert!(rc.auxiliaries.len() >= 10, "{:?}", rc.auxiliaries);
    let mut worst_rows: f64 = 0.0;
    let mut worst_alg: f64 = 0.0;
    let mut worst_diff: f64 = 0.0;
    for trial in 0..20 {
        let z_hat: Vec<f64> = (0..n).map(|i| 0.8 * pseudo_random(7 * trial + i)).collect();
        let z = rc.lift(&z_hat);
        let orig = rc.original_rhs(&z_hat);
        let rhs = recast_rhs(&sys, &z);
        for i in 0..n {
            worst_rows = worst_rows.max((rhs[i] - orig[i]).abs() / (1.0 + orig[i].abs()));
        }
        // the auxiliaries: algebraic rows vanish, differential rows are the time
        // derivative of the definition along x' = v (central difference)
        let v: Vec<f64> = z_hat[2..4].to_vec();
        let h = 1e-5;
        let shifted = |s: f64| {
            let mut zz = z_hat.clone();
            zz[0] += s * v[0];
            zz[1] += s * v[1];
            rc.lift(&zz)
        };
        let (zp, zm) = (shifted(h), shifted(-h));
        for a in &rc.auxiliaries {
            let k = a.state;
            if a.kind.is_differential() {
                let fd = (zp[k] - zm[k]) / (2.0 * h);
                worst_diff = worst_diff.max((rhs[k] - fd).abs() / (1.0 + fd.abs()));
            } else {
                worst_alg = worst_alg.max(rhs[k].abs());
            }
        }
    }
    assert!(worst_rows < 1e-14, "original rows differ by {worst_rows:e}");
    assert!(
        worst_alg < 1e-14,
        "algebraic relations violated by {worst_alg:e}"
    );
    // central-difference truncation ~h^2 = 1e-10
    assert!(
        worst_diff < 1e-8,
        "differential rows differ by {worst_diff:e}"
    );
}

#[test]
fn physical_pencil_is_recast_spectrum_without_spurious_modes() {
    let sys = every_function();
    let rc = sys.recast.as_ref().expect("recast");
    let n_diff = rc
        .auxiliaries
        .iter()
        .filter(|a| a.kind.is_differential())
        .count();
    let shift = -0.37;
    let full = finite_eigenvalues(sys.a.as_ref(), sys.b.as_ref(), shift).expect("recast pencil");
    let phys = finite_eigenvalues(rc.physical_a.as_ref(), rc.physical_b.as_ref(), shift)
        .expect("physical pencil");
    // 2 dofs, 1 constraint: one finite pair
    assert_eq!(phys.len(), 2, "{phys:?}");
    assert_eq!(full.len(), phys.len() + n_diff, "{full:?}");
    let zeros = full.iter().filter(|l| l.norm() < 1e-9).count();
    assert_eq!(zeros, n_diff);
    for l in &phys {
        let d = full
            .iter()
            .map(|m| (m - l).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(
            d < 1e-10 * l.norm(),
            "{l} not in the recast spectrum ({d:e})"
        );
    }
}

#[test]
fn trig_auxiliaries_follow_eq22() {
    let mut s = MechanicalSystem::new("pendulum", &["phi"]);
    s.mass = SparseMatrix::diagonal(&[1.0]);
    s.damping = SparseMatrix::diagonal(&[0.1]);
    s.force_expressions = vec![(0, Expr::var(0).sin())];
    let sys = System::from_model("test", s.into_model().expect("builds")).expect("recasts");
    let rc = sys.recast.as_ref().expect("recast");
    let kinds: Vec<AuxKind> = rc.auxiliaries.iter().map(|a| a.kind).collect();
    assert_eq!(kinds, vec![AuxKind::Sin, AuxKind::OneMinusCos]);
    assert_eq!(rc.auxiliaries[0].definition, "u1 = sin(phi)");
    assert_eq!(rc.auxiliaries[1].definition, "u2 = 1 - cos(phi)");
    assert_eq!(sys.n_states(), 4);
    // eq. (22): the phi' row carries -u1, u1' = phi_dot - u2 phi_dot, 0 = u1^2 - 2 u2 + u2^2
    let a = sys.a.to_dense();
    assert_eq!(a[(0, 2)], -1.0);
    assert_eq!(a[(2, 1)], 1.0);
    assert_eq!(a[(3, 3)], -2.0);
    assert_eq!(sys.b.to_dense()[(2, 2)], 1.0);
    assert_eq!(sys.b.to_dense()[(3, 3)], 0.0);
    assert_eq!(sys.nonlinearity.terms.len(), 3);
}

#[test]
fn bad_models_give_typed_errors() {
    let recast_err = |s: MechanicalSystem| match System::from_model("t", s.into_model().unwrap()) {
        Err(ModelError::Recast { source, .. }) => source,
        other => panic!("expected a recast error, got {other:?}"),
    };
    // gravity without an equilibrium
    let mut s = MechanicalSystem::new("t", &["x", "y"]);
    s.mass = SparseMatrix::diagonal(&[1.0, 1.0]);
    s.force_expressions = vec![(1, Expr::constant(-9.8)), (0, Expr::var(0).sin())];
    let e = recast_err(s.clone());
    assert!(
        matches!(&e, RecastError::NotAnEquilibrium { state, .. } if state == "y"),
        "{e}"
    );
    // with a consistent equilibrium (a spring holds y) the model is accepted
    s.stiffness = SparseMatrix::diagonal(&[0.0, 2.0]);
    s.equilibrium = Some(Equilibrium {
        x: vec![0.0, 4.9],
        mu: vec![],
    });
    assert!(System::from_model("t", s.into_model().unwrap()).is_ok());
    // a velocity inside sin
    let mut s = MechanicalSystem::new("t", &["x"]);
    s.mass = SparseMatrix::diagonal(&[1.0]);
    s.force_expressions = vec![(0, Expr::var(1).sin())];
    let e = recast_err(s);
    assert!(
        matches!(&e, RecastError::NoTimeDerivative { state, .. } if state == "x_dot"),
        "{e}"
    );
    // ln at a zero argument
    let mut s = MechanicalSystem::new("t", &["x"]);
    s.mass = SparseMatrix::diagonal(&[1.0]);
    s.force_expressions = vec![(0, Expr::var(0).ln())];
    let e = recast_err(s);
    assert!(
        matches!(&e, RecastError::Singular { function: "ln", .. }),
        "{e}"
    );
}
