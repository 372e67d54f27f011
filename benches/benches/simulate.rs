//! Full-system integration (Radau IIA on the DAE), speed beside error:
//! - the chain of pendulums (405 states): one free period from a point of the
//!   O(13) SSM, printed with steps, steps per second and the constraint
//!   residual;
//! - the Fig. 15 reference: 21 steady states (eps = 0.6, Omega in [1.8, 2.2],
//!   criterion (47) with delta = 1e-3) on both cores; the paper reports
//!   14.6 min with MATLAB's ode15s. Printed with the O(5) FRC's largest
//!   relative error against it.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench simulate`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use num_complex::Complex64 as C64;
use ssm_core::compare::steady_state_reference;
use ssm_core::fom::consistent::algebraic_residual;
use ssm_core::fom::{consistent_initial, DaeProblem, Radau, RadauOptions, SteadyOptions};
use ssm_core::spectrum::Normalization;
use ssm_tests::{pendulum_with_spectrum, ssm_of};

fn simulate(c: &mut Criterion) {
    let mut g = c.benchmark_group("simulate");
    g.sample_size(10);
    let (sys, sp) = pendulum_with_spectrum("chain", "");
    let ssm = ssm_of(&sys, &sp, &[1], 13, Normalization::Mass);
    let q = C64::from_polar(0.8, 3.0);
    let w: Vec<f64> = ssm
        .w_at(&ssm.set.monomials(&[q, q.conj()], 13), 13)
        .iter()
        .map(|c| c.re)
        .collect();
    let p = DaeProblem::new(&sys, 0.0, 0.0);
    let z0 = consistent_initial(&p, 0.0, &w).unwrap().z;
    let period = 2.0 * std::f64::consts::PI / sp.eigenvalues[0].im.abs();
    let run = || {
        let mut r = Radau::new(&p, 0.0, &z0, period, RadauOptions::default()).unwrap();
        while r.t() < period {
            r.step(period).unwrap();
        }
        r
    };
    let t = std::time::Instant::now();
    let r = run();
    let secs = t.elapsed().as_secs_f64();
    println!(
        "chain (405 states), one period from W(p0), rho0 = 0.8 (mass normalization): {} steps ({} rejected, {} LU pairs), {:.0} steps/s, constraint residual at the end {:.1e}",
        r.stats.accepted,
        r.stats.rejected,
        r.stats.factorizations,
        r.stats.accepted as f64 / secs,
        algebraic_residual(&p, r.z()).0
    );
    g.bench_function("chain n = 41, one period, rtol 1e-8", |b| {
        b.iter(|| black_box(run().stats.accepted))
    });
    let outputs = [sys.output("phi_n").unwrap()];
    let omegas: Vec<f64> = (0..21).map(|i| 1.8 + 0.02 * i as f64).collect();
    let opts = SteadyOptions::default();
    let reference = steady_state_reference(&sys, 0.6, &omegas, &outputs, &opts, None).unwrap();
    let steps: usize = reference.iter().map(|r| r.stats.accepted).sum();
    let periods: usize = reference.iter().map(|r| r.periods).sum();
    println!(
        "Fig. 15 reference: 21 steady states, {periods} forcing periods, {steps} steps in all; peak max|phi_n| = {:.4}",
        reference
            .iter()
            .map(|r| r.amplitudes[0])
            .fold(0.0, f64::max)
    );
    g.bench_function("chain n = 41, Fig. 15 reference, 21 steady states", |b| {
        b.iter(|| {
            black_box(steady_state_reference(&sys, 0.6, &omegas, &outputs, &opts, None).unwrap())
        })
    });
    g.finish();
}

criterion_group!(benches, simulate);
criterion_main!(benches);
