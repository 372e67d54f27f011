//! The `pod` reducer on the crank drive (plugin `crank-drive`): the full
//! HHT run against the reduced one on a load the reduction was not trained
//! on, and the offline cost (training run excluded: POD, constraint
//! reduction, projection). Before timing, each case prints the reduced
//! run's coordinate error against the full one, relative to the peak, and
//! the model sizes, so speed and error are read side by side.
//!
//! - 4 cylinders inline, 8 cylinders in a 90-degree V; HHT alpha = -0.1,
//!   fixed steps of 1 ms over 1.5 s, torque 1.5 (1 + 0.5 cos(30 t)) N m.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench pod`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_engine::fom::hht::HhtSolution;
use ssm_engine::model::system::System;
use ssm_engine::reduce::pod_model::{pod_reduce, PodSettings};
use ssm_tests::{hht_from_rest, pod_coordinate_error, system};

fn hht(sys: &System, eps: f64, omega: f64, t_end: f64) -> HhtSolution {
    hht_from_rest(sys, eps, omega, t_end, 1e-3)
}

fn pod(c: &mut Criterion) {
    let mut g = c.benchmark_group("crank drive: full vs POD-reduced HHT");
    g.sample_size(10);
    for (cylinders, v_angle) in [(4usize, 0.0), (8, 90.0)] {
        let label = format!("{cylinders} cyl V{v_angle}");
        let model = format!("cylinders = {cylinders}\nv_angle = {v_angle}\ntau_amp = 0.5");
        let full = system("crank-drive", "crank-drive", &model);
        let train = hht(&full, 1.0, 0.0, 1.0);
        let settings = PodSettings::default();
        let red = pod_reduce(&full, &train.states, &settings).expect("POD reduction");
        let rsys = System::from_model("pod", red.model.clone()).expect("reduced model");
        let (a, b) = (hht(&full, 1.5, 30.0, 1.5), hht(&rsys, 1.5, 30.0, 1.5));
        println!(
            "{label}: {} -> {} states, {} -> {} polynomial terms; error {:.1e} of the peak",
            full.states.len(),
            rsys.states.len(),
            full.nonlinearity.terms.len(),
            rsys.nonlinearity.terms.len(),
            pod_coordinate_error(&a, &b, red.u.as_ref())
        );
        g.bench_function(BenchmarkId::new("full", &label), |bch| {
            bch.iter(|| black_box(hht(&full, 1.5, 30.0, 1.5)))
        });
        g.bench_function(BenchmarkId::new("reduced", &label), |bch| {
            bch.iter(|| black_box(hht(&rsys, 1.5, 30.0, 1.5)))
        });
        g.bench_function(BenchmarkId::new("offline POD", &label), |bch| {
            bch.iter(|| black_box(pod_reduce(&full, &train.states, &settings)))
        });
    }
    g.finish();
}

criterion_group!(benches, pod);
criterion_main!(benches);
