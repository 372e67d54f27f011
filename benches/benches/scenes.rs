//! Whole zoo scenes, timed as the engine runs them (the model built by its
//! plugin, the plan resolved and executed, the files assembled in memory,
//! nothing written): the cost of everything between the scene and its
//! outputs, for the before/after comparison of changes to the engine's
//! structure. Cases, each a stage of its own:
//!
//! - `spatial_oscillator_cubic`: the README's scene (SSM to order 5 of a
//!   constrained oscillator, backbone, invariance error, forced response);
//! - `pendulum_chain_fig13`: a large sparse DAE (the chain of pendulums);
//! - `pendulum_simple_fig7_c0.1`: the simple pendulum's backbone and transient;
//! - `crank_drive_v8_pod`: the POD study of the V8 crank drive.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench scenes`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use ssm_core::model::plugin::Registry;
use ssm_engine::job::run;
use ssm_engine::pipeline::Quiet;
use ssm_engine::scene::SceneFile;
use ssm_tests::{plugin_path, repo_root};

const CASES: [&str; 4] = [
    "spatial_oscillator_cubic",
    "pendulum_chain_fig13",
    "pendulum_simple_fig7_c0.1",
    "crank_drive_v8_pod",
];

fn scenes(c: &mut Criterion) {
    let mut g = c.benchmark_group("whole scene");
    g.sample_size(10);
    let mut reg = Registry::discover(&[
        plugin_path("spatial-oscillator"),
        plugin_path("pendulum"),
        plugin_path("crank-drive"),
    ])
    .expect("the plugins load");
    for name in CASES {
        let path = repo_root().join("zoo").join(format!("{name}.toml"));
        let scene = SceneFile::load(&path).expect("a zoo scene");
        g.bench_function(name, |b| {
            b.iter(|| black_box(run(&scene, &mut reg, &Quiet).expect("the scene runs")))
        });
    }
    g.finish();
}

criterion_group!(benches, scenes);
criterion_main!(benches);
