use num_complex::Complex64 as C64;
use ssm_engine::scene::Normalization;
use ssm_engine::simulate::{
    consistent::algebraic_residual, consistent_initial, DaeProblem, Radau, RadauOptions,
};
use ssm_tests::{pendulum_with_spectrum, ssm_of};

#[test]
fn scratch() {
    let (sys, sp) = pendulum_with_spectrum("chain", "");
    for norm in [Normalization::Unit, Normalization::Mass] {
        let ssm = ssm_of(&sys, &sp, &[1], 13, norm);
        let q = C64::from_polar(1.0, 3.0);
        let lin = ssm.w_at(&ssm.set.monomials(&[q, q.conj()], 1), 1);
        let x1 = lin[0].re;
        let phin = sys.output("phi_n").unwrap();
        let pn: f64 = phin.weights.iter().map(|&(s, w)| w * lin[s].re).sum();
        eprintln!("{norm:?}: per unit rho: x1 {x1:.4e}, phi_n {pn:.4e}");
    }
    let ssm = ssm_of(&sys, &sp, &[1], 13, Normalization::Unit);
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    for rho in [8.0, 25.0] {
        let q = C64::from_polar(rho, 3.0);
        let w = ssm.w_at(&ssm.set.monomials(&[q, q.conj()], 13), 13);
        let guess: Vec<f64> = w.iter().map(|c| c.re).collect();
        let t = std::time::Instant::now();
        let c = consistent_initial(&p, 0.0, &guess).expect("consistent");
        eprintln!("rho {rho}: correction x {:.2e} v {:.2e} resid {:.2e} vres {:.2e} mu0 err {:.2e} ({:.3}s)", c.position_correction, c.velocity_correction, c.constraint_residual, c.velocity_residual,
          (0..sys.n_states()).filter(|&i| sys.states[i].kind == ssm_api::StateKind::Multiplier).map(|i| (c.z[i]-guess[i]).abs()).fold(0.0, f64::max), t.elapsed().as_secs_f64());
        let t_end = 100.0 * 2.0 * std::f64::consts::PI / 1.9939;
        let t = std::time::Instant::now();
        let mut r = Radau::new(&p, 0.0, &c.z, t_end, RadauOptions::default()).unwrap();
        let mut worst: f64 = 0.0;
        while r.t() < t_end {
            r.step(t_end).unwrap();
            worst = worst.max(algebraic_residual(&p, r.z()).0);
        }
        let el = t.elapsed().as_secs_f64();
        eprintln!("rho {rho}: {} steps ({} rejected, {} jac, {} lu, {} newton) in {el:.3}s = {:.0} steps/s; worst algebraic residual {worst:.2e}", r.stats.accepted, r.stats.rejected, r.stats.jacobians, r.stats.factorizations, r.stats.newton, r.stats.accepted as f64 / el);
    }
}
