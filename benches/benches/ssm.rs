//! Autonomous SSM benchmarks: the parametrization method alone (spectrum and
//! master modes precomputed). Each benchmark first prints the error it buys:
//! the relative deviation from the published eqs. (28)-(30) (oscillator) or
//! the invariance error (41) of the expansion (chain), then times it.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench ssm`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_core::spectrum;
use ssm_core::spectrum::Normalization;
use ssm_core::ssm::analysis::{invariance_error, polar};
use ssm_core::ssm::{self, SsmOptions};
use ssm_tests::{
    chain_with_sparse_spectrum, oscillator_published_polar, oscillator_with_spectrum,
    pendulum_with_spectrum, ssm_of, system, OSCILLATOR_CONSTRAINTS,
};

fn oscillator(c: &mut Criterion) {
    let mut g = c.benchmark_group("ssm spatial-oscillator");
    for constraint in OSCILLATOR_CONSTRAINTS {
        let (sys, sp) = oscillator_with_spectrum(constraint);
        let masters =
            spectrum::master_modes(&sys, &sp, &[1], Normalization::Scale(0.8306)).unwrap();
        let others = ssm::non_master(&sp.eigenvalues, &masters);
        let s = ssm_of(&sys, &sp, &[1], 13, Normalization::Scale(0.8306));
        let p = polar(&s).unwrap();
        let (a, _) = oscillator_published_polar(constraint);
        let dev = a
            .iter()
            .zip(p.rho_dot())
            .skip(1)
            .map(|(x, y)| (y - x.parse::<f64>().unwrap()).abs() / x.parse::<f64>().unwrap().abs())
            .fold(0.0, f64::max);
        println!(
            "ssm oscillator {constraint} O(13): max relative deviation of rho' coefficients from eqs. (28)-(30) with s = 0.8306: {dev:.1e}; invariance error at rho = 0.1: {:.2e}",
            invariance_error(&s, &sys, 13, 0.1, 10, 30)
        );
        g.bench_function(BenchmarkId::new("O(13)", constraint), |b| {
            b.iter(|| {
                black_box(
                    ssm::compute(
                        &sys,
                        &masters,
                        &others,
                        &SsmOptions {
                            order: 13,
                            resonance_tol: 0.02,
                        },
                    )
                    .unwrap(),
                )
            })
        });
    }
    g.finish();
}

fn chain(c: &mut Criterion) {
    let mut g = c.benchmark_group("ssm oscillator-chain");
    g.sample_size(10);
    for n in [1_000usize, 10_000, 100_000] {
        let (sys, sp) = chain_with_sparse_spectrum(n, 4);
        let masters = spectrum::master_modes(&sys, &sp, &[1], Normalization::Unit).unwrap();
        let others = ssm::non_master(&sp.eigenvalues, &masters);
        let o = SsmOptions {
            order: 5,
            resonance_tol: 0.02,
        };
        let s = ssm::compute(&sys, &masters, &others, &o).unwrap();
        println!(
            "ssm chain n = {n} O(5): invariance error at rho = 1: O(3) {:.2e}, O(5) {:.2e}; time split: composition {:.3} s, factorization {:.3} s, solves {:.3} s, total {:.3} s",
            invariance_error(&s, &sys, 3, 1.0, 10, 30),
            invariance_error(&s, &sys, 5, 1.0, 10, 30),
            s.timing.compose_s,
            s.timing.linear.factor_s,
            s.timing.linear.solve_s,
            s.timing.total_s
        );
        g.bench_with_input(BenchmarkId::new("O(5)", n), &n, |b, _| {
            b.iter(|| black_box(ssm::compute(&sys, &masters, &others, &o).unwrap()))
        });
    }
    g.finish();
}

/// The pendulum family after the recast: the simple pendulum at O(35), the
/// slider's 4-D SSM at O(13), and the 405-state chain of pendulums at O(5) and
/// O(13) (the paper reports only its 2 s MATLAB FRC at O(5)), plus the whole
/// front end of the chain: plugin build, recast and sparse spectrum.
fn pendulum(c: &mut Criterion) {
    let mut g = c.benchmark_group("ssm pendulum");
    g.sample_size(20);
    let cases: [(&str, &str, &[usize], usize, f64); 4] = [
        ("simple", "c = 0.001", &[1], 35, 0.6),
        ("slider", "", &[1, 2], 13, 2.0),
        ("chain", "", &[1], 5, 8.0),
        ("chain", "", &[1], 13, 8.0),
    ];
    for (model, params, pairs, order, radius) in cases {
        let (sys, sp) = pendulum_with_spectrum(model, params);
        let masters = spectrum::master_modes(&sys, &sp, pairs, Normalization::Unit).unwrap();
        let others = ssm::non_master(&sp.eigenvalues, &masters);
        let o = SsmOptions {
            order,
            resonance_tol: 0.02,
        };
        let s = ssm::compute(&sys, &masters, &others, &o).unwrap();
        println!(
            "ssm pendulum {model} O({order}), {} states: invariance error at rho = {radius}: {:.2e}",
            sys.n_states(),
            invariance_error(&s, &sys, order, radius, 4, 12),
        );
        g.bench_function(
            BenchmarkId::new(format!("{model} O({order})"), sys.n_states()),
            |b| b.iter(|| black_box(ssm::compute(&sys, &masters, &others, &o).unwrap())),
        );
    }
    g.bench_function("chain n = 41: plugin build, recast, sparse spectrum", |b| {
        b.iter(|| black_box(pendulum_with_spectrum("chain", "")))
    });
    g.bench_function("chain n = 41: plugin build and recast", |b| {
        b.iter(|| black_box(system("pendulum", "chain", "")))
    });
    g.finish();
}

criterion_group!(benches, oscillator, chain, pendulum);
criterion_main!(benches);
