use num_complex::Complex64 as C64;
use ssm_engine::scene::Normalization;
use ssm_engine::simulate::RadauOptions;
use ssm_engine::ssm::analysis::invariance_error;
use ssm_engine::validate::transient;
use ssm_tests::{oscillator_with_spectrum, ssm_of};

#[test]
fn scratch() {
    for (c, rho) in [("none", 0.35), ("cubic", 0.35), ("spherical", 0.24)] {
        let (sys, sp) = oscillator_with_spectrum(c);
        let ssm = ssm_of(&sys, &sp, &[1], 13, Normalization::Scale(0.8306));
        let outs: Vec<_> = ["x1", "x2", "x3"]
            .iter()
            .map(|n| sys.output(n).unwrap())
            .collect();
        for order in [3, 7, 13] {
            let q = C64::from_polar(rho, 0.5);
            let v = transient(
                &ssm,
                &sys,
                order,
                &[q, q.conj()],
                100.0,
                1001,
                &outs,
                RadauOptions::default(),
            )
            .unwrap();
            let ie = invariance_error(&ssm, &sys, order, rho, 1, 60);
            let dmax = v.distance.iter().cloned().fold(0.0, f64::max);
            eprintln!("{c} O({order}) rho {rho}: inv err {ie:.2e}; max dist {dmax:.2e}; rel err x1 {:.2e} x2 {:.2e}; proj {:.2e}; steps {} full {:.3}s rom {:.4}s; alg {:.2e}", v.relative_error(0), v.relative_error(1), v.initial.position_correction, v.stats.accepted, v.full_s, v.rom_s, v.algebraic_residual.iter().cloned().fold(0.0, f64::max));
        }
    }
}
