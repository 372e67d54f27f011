//! Autonomous SSM benchmarks: the parametrization method alone (spectrum and
//! master modes precomputed). Each benchmark first prints the error it buys:
//! the relative deviation from the published eqs. (28)-(30) (oscillator) or
//! the invariance error (41) of the expansion (chain), then times it.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench ssm`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_engine::scene::Normalization;
use ssm_engine::spectrum;
use ssm_engine::ssm::analysis::{invariance_error, polar};
use ssm_engine::ssm::{self, SsmOptions};
use ssm_tests::{
    chain_with_sparse_spectrum, oscillator_published_polar, oscillator_with_spectrum, ssm_of,
    OSCILLATOR_CONSTRAINTS,
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

criterion_group!(benches, oscillator, chain);
criterion_main!(benches);
