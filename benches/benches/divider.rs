//! The frequency divider's forced response (Sect. 5.3, Figs. 18-19; the
//! paper: 10 s in MATLAB for the SSM forced response): the whole scene
//! `zoo/divider_frc.toml` without its full-system validation (sparse
//! spectrum, O(5) 4-D SSM, continuation with branch switching, physical
//! amplitudes, error estimate), and the same scene without `[forcing]`, whose
//! difference is the forced response itself. Each case first prints what it
//! computes (points, bifurcations, the curve's error estimate), then is timed
//! on the paper's mesh and on a ten times finer one.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench divider`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_tests::{repo_root, run_scene_text};

/// The zoo scene without its `[validate...]` sections, on the mesh `k (10, 14)`,
/// with or without `[forcing]`.
fn scene(k: usize, forcing: bool) -> String {
    let text =
        std::fs::read_to_string(repo_root().join("zoo/divider_frc.toml")).expect("zoo scene");
    let head = text.split("[validate").next().unwrap_or_default();
    let head = if forcing {
        head.to_owned()
    } else {
        head.split("[forcing]")
            .next()
            .unwrap_or_default()
            .to_owned()
    };
    head.replace(
        "plugin = \"divider\"",
        &format!(
            "plugin = \"divider\"\n[model.params]\nn1 = {}\nn2 = {}",
            10 * k,
            14 * k
        ),
    )
}

fn divider(c: &mut Criterion) {
    let mut g = c.benchmark_group("divider");
    g.sample_size(10);
    for k in [1, 10] {
        let full = scene(k, true);
        let bare = scene(k, false);
        let job = run_scene_text(&full).expect("divider scene");
        let frc = job.frc.as_ref().expect("forced response");
        for curve in &frc.curves {
            println!(
                "divider k = {k} ({} states): O({}), eps = {}: {} points on {} branches, {} bifurcations, error estimate {:.2e}",
                job.system.n_states(),
                curve.order,
                curve.epsilon,
                curve.points,
                curve.branches,
                curve.bifurcations.len(),
                curve.error_estimate()
            );
        }
        let states = job.system.n_states();
        g.bench_function(BenchmarkId::new("scene without validation", states), |b| {
            b.iter(|| black_box(run_scene_text(&full).expect("divider scene")))
        });
        g.bench_function(BenchmarkId::new("spectrum and SSM only", states), |b| {
            b.iter(|| black_box(run_scene_text(&bare).expect("divider scene")))
        });
    }
    g.finish();
}

criterion_group!(benches, divider);
criterion_main!(benches);
