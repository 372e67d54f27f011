use ssm_engine::simulate::SteadyOptions;
use ssm_engine::validate::steady_state_reference;
use ssm_tests::system;

#[test]
fn scratch() {
    let sys = system("pendulum", "chain", "");
    let outs: Vec<_> = ["phi_n", "x1"]
        .iter()
        .map(|n| sys.output(n).unwrap())
        .collect();
    let omegas: Vec<f64> = vec![1.9, 2.0, 2.02, 2.04, 2.1];
    let t = std::time::Instant::now();
    let res = steady_state_reference(
        &sys,
        0.6,
        &omegas,
        &outs,
        &SteadyOptions {
            delta: 1e-6,
            ..SteadyOptions::default()
        },
    )
    .unwrap();
    eprintln!("21 points in {:.2}s", t.elapsed().as_secs_f64());
    for r in &res {
        eprintln!(
            "omega {:.3}: periods {} change {:.1e} phi_n {:.4e} x1 {:.4e} steps {}",
            r.omega, r.periods, r.change, r.amplitudes[0], r.amplitudes[1], r.stats.accepted
        );
    }
}
