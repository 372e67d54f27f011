//! Spectrum benchmarks. Each benchmark first prints its error against the
//! reference of the shared catalogue (`ssm_tests`), then times the computation:
//! speed is never reported without the error it was bought with.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_core::spectrum::Normalization;
use ssm_core::spectrum::{self, Method};
use ssm_tests::{
    chain_eigenvalues, chain_with_sparse_spectrum, oscillator_published_eigenvalues, CHAIN_DEFAULTS,
};

use ssm_tests::spectrum_options as opts;
use ssm_tests::{oscillator_with_spectrum, OSCILLATOR_CONSTRAINTS};

fn oscillator(c: &mut Criterion) {
    let mut g = c.benchmark_group("spatial-oscillator");
    for constraint in OSCILLATOR_CONSTRAINTS {
        let (sys, sp) = oscillator_with_spectrum(constraint);
        let published = oscillator_published_eigenvalues(constraint);
        let err = published
            .iter()
            .enumerate()
            .map(|(j, p)| (sp.eigenvalues[2 * j] - p).norm() / p.norm())
            .fold(0.0, f64::max);
        println!("spatial-oscillator {constraint}: max relative deviation from the printed eqs. (26)-(27): {err:.2e} (printing precision ~2.5e-5)");
        g.bench_function(BenchmarkId::new("spectrum+master", constraint), |b| {
            b.iter(|| {
                let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts(None, 0)).unwrap();
                black_box(spectrum::master_modes(&sys, &sp, &[1], Normalization::Unit).unwrap())
            })
        });
    }
    g.finish();
}

fn chain(c: &mut Criterion) {
    let mut g = c.benchmark_group("oscillator-chain");
    g.sample_size(10);
    let (k, alpha, beta) = CHAIN_DEFAULTS;
    for n in [100usize, 1_000, 10_000, 100_000] {
        let (sys, sp) = chain_with_sparse_spectrum(n, 4);
        let exact = chain_eigenvalues(n, k, alpha, beta, 2);
        let err = exact
            .iter()
            .enumerate()
            .map(|(j, e)| (sp.eigenvalues[2 * j] - e).norm() / e.norm())
            .fold(0.0, f64::max);
        println!("oscillator-chain n = {n} (N = {}): 2 slowest pairs, max relative error vs closed form {err:.2e}", 2 * n);
        g.bench_with_input(
            BenchmarkId::new("sparse 2 pairs + master", n),
            &n,
            |b, _| {
                b.iter(|| {
                    let sp = spectrum::compute(
                        sys.a.as_ref(),
                        sys.b.as_ref(),
                        &opts(Some(Method::Sparse), 4),
                    )
                    .unwrap();
                    black_box(spectrum::master_modes(&sys, &sp, &[1], Normalization::Unit).unwrap())
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, oscillator, chain);
criterion_main!(benches);
