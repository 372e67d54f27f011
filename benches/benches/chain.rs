//! The oscillator chain from 10^3 to 10^5 masses (2 * 10^3 to 2 * 10^5
//! states): the whole backbone scene (sparse spectrum of 10 modes, O(5)
//! 2-D SSM of the slowest pair, backbone of the middle mass with its error
//! estimate). Each size first prints the slowest eigenvalue's error against
//! the closed form, the backbone's error estimate and the time split of one
//! run, then is timed whole.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench chain`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_tests::{chain_eigenvalues, run_scene_text, CHAIN_DEFAULTS};

fn scene(n: usize) -> String {
    format!(
        "[model]\nplugin = \"oscillator-chain\"\n[model.params]\nn = {n}\n\
         [spectrum]\nmethod = \"sparse\"\nmodes = 10\n\
         [ssm]\nmaster_pairs = [1]\norder = 5\n\
         [outputs]\ncoordinates = [\"x{}\"]\n\
         [outputs.backbone]\nrho_max = 0.1\n",
        n / 2
    )
}

fn chain(c: &mut Criterion) {
    let mut g = c.benchmark_group("oscillator-chain backbone O(5)");
    g.sample_size(10);
    let (k, alpha, beta) = CHAIN_DEFAULTS;
    for n in [1_000usize, 10_000, 100_000] {
        let text = scene(n);
        let job = run_scene_text(&text).expect("chain scene");
        let exact = chain_eigenvalues(n, k, alpha, beta, 1)[0];
        let lambda = job.masters[0].lambda;
        let summary: serde_json::Value = serde_json::from_slice(
            job.outputs
                .get("summary.json")
                .expect("summary.json among the outputs"),
        )
        .expect("summary.json parses");
        println!(
            "oscillator-chain n = {n} ({} states): lambda_1 relative error vs closed form {:.2e}; backbone estimate {}; seconds {}",
            job.system.n_states(),
            (lambda - exact).norm() / exact.norm(),
            summary["accuracy"]["answers"][0]["error_estimate"],
            summary["timing_s"]
        );
        g.bench_with_input(BenchmarkId::new("scene", n), &n, |b, _| {
            b.iter(|| black_box(run_scene_text(&text).expect("chain scene")))
        });
    }
    g.finish();
}

criterion_group!(benches, chain);
criterion_main!(benches);
