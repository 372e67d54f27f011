//! Forced response curves from the leading-order periodic SSM: the chain of
//! pendulums at O(5) (the paper: 2 s in MATLAB for the whole FRC, Sect. 5.2.3)
//! and the spatial oscillator's Fig. 5 curves. Each benchmark first prints what
//! it computes (points, folds, the invariance error at the peak), then times
//! the FRC alone (SSM precomputed) and the FRC with the physical amplitudes of
//! every point (one `X0` solve per point).
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench frc`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_core::rom::frc::{one_pair_frc, response_amplitudes, OnePair};
use ssm_core::spectrum;
use ssm_core::spectrum::Normalization;
use ssm_core::ssm::analysis::{invariance_error, polar};
use ssm_core::ssm::forced::ForcedSsm;
use ssm_tests::{oscillator_with_spectrum, pendulum_with_spectrum, ssm_of};

fn frc(c: &mut Criterion) {
    let mut g = c.benchmark_group("frc");
    g.sample_size(10);
    let chain = pendulum_with_spectrum("chain", "");
    let osc = oscillator_with_spectrum("none");
    let cases = [
        (
            "chain n = 41, O(5), eps = 0.6",
            &chain,
            "phi_n",
            5,
            0.6,
            (1.8, 2.2),
            25.0,
        ),
        (
            "oscillator, O(11), eps = 0.03",
            &osc,
            "x1",
            11,
            0.03,
            (1.8, 2.2),
            0.5,
        ),
    ];
    for (name, (sys, sp), output, order, eps, range, rho_max) in cases {
        let masters = spectrum::master_modes(sys, sp, &[1], Normalization::Unit).unwrap();
        let ssm = ssm_of(sys, sp, &[1], order, Normalization::Unit);
        let mut forced = ForcedSsm::new(sys, &masters, &[1.0]).unwrap();
        let s = forced.at(2.0).unwrap().resonant_forcing(0);
        let p = polar(&ssm).unwrap();
        let pb = OnePair::new(&p, order, eps * s);
        let f = one_pair_frc(&pb, rho_max, 200, range);
        let peak = f.points.iter().map(|q| q.rho).fold(0.0, f64::max);
        println!(
            "frc {name}: {} points on {} branch(es), {} folds, invariance error at the peak rho = {peak:.3}: {:.2e}",
            f.points.len(),
            f.points.iter().map(|q| q.branch).max().unwrap_or(0),
            f.bifurcations.len(),
            invariance_error(&ssm, sys, order, peak, 2, 30)
        );
        g.bench_function(BenchmarkId::new("curve", name), |b| {
            b.iter(|| black_box(one_pair_frc(&pb, rho_max, 200, range)))
        });
        let weights = sys.output(output).unwrap().weights.clone();
        let series = ssm.output_series(&weights);
        g.bench_function(BenchmarkId::new("curve + amplitudes", name), |b| {
            b.iter(|| {
                let f = one_pair_frc(&pb, rho_max, 200, range);
                let amps: Vec<f64> = f
                    .points
                    .iter()
                    .map(|q| {
                        let x0 = forced.at(q.omega).unwrap();
                        response_amplitudes(&ssm, &series, order, q, &|_, phi| {
                            eps * x0.output_at(&weights, phi)
                        })
                        .0
                    })
                    .collect();
                black_box(amps)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, frc);
criterion_main!(benches);
