//! The `pod` reducer on the crank drive (plugin `crank-drive`): the full
//! HHT run against the reduced one on a load the reduction was not trained
//! on, and the offline cost (training run excluded: POD, constraint
//! reduction, projection). Before timing, each case prints the reduced
//! run's coordinate error against the full one, relative to the peak, and
//! the model sizes, so speed and error are read side by side.
//!
//! - 4 cylinders inline, 8 cylinders in a 90-degree V; HHT alpha = -0.1,
//!   fixed steps of 1 ms over 1.5 s, torque 1.5 (1 + 0.5 cos(30 t)) N m.
//! - The chain of pendulums of Fig. 15 (recast, 405 states), two energy
//!   truncations, 30 s at steps of 0.01 on a frequency not trained on.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench pod`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_core::fom::hht::HhtSolution;
use ssm_core::model::system::System;
use ssm_core::reduce::pod::Truncation;
use ssm_core::reduce::pod_model::{pod_reduce, PodSettings};
use ssm_tests::{hht_from_rest, model_and_system, pod_coordinate_error};

fn hht(sys: &System, eps: f64, omega: f64, t_end: f64) -> HhtSolution {
    hht_from_rest(sys, eps, omega, t_end, 1e-3)
}

fn pod(c: &mut Criterion) {
    let mut g = c.benchmark_group("crank drive: full vs POD-reduced HHT");
    g.sample_size(10);
    for (cylinders, v_angle) in [(4usize, 0.0), (8, 90.0)] {
        let label = format!("{cylinders} cyl V{v_angle}");
        let model = format!("cylinders = {cylinders}\nv_angle = {v_angle}\ntau_amp = 0.5");
        let (raw, full) = model_and_system("crank-drive", "crank-drive", &model);
        let train = hht(&full, 1.0, 0.0, 1.0);
        let settings = PodSettings::default();
        let red = pod_reduce(&raw, &full, &train.states, &settings).expect("POD reduction");
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
            bch.iter(|| black_box(pod_reduce(&raw, &full, &train.states, &settings)))
        });
    }
    g.finish();
}

/// The chain of pendulums (Fig. 15, 405 states): trained at eps = 0.6,
/// Omega = 2 over 30 s, run at Omega = 1.85 over 30 s (HHT, h = 0.01),
/// energy truncations 1e-4 and 1e-7 at rank tolerance 1e-2.
fn chain(c: &mut Criterion) {
    let mut g = c.benchmark_group("chain: full vs POD-reduced HHT");
    g.sample_size(10);
    let run = |sys: &System, omega: f64| hht_from_rest(sys, 0.6, omega, 30.0, 0.01);
    let (raw, full) = model_and_system("pendulum", "chain", "");
    let train = run(&full, 2.0);
    let check = run(&full, 1.85);
    g.bench_function(BenchmarkId::new("full", "405 states"), |bch| {
        bch.iter(|| black_box(run(&full, 1.85)))
    });
    for fraction in [1e-4, 1e-7] {
        let settings = PodSettings {
            truncation: Truncation::Energy { fraction },
            rank_tol: 1e-2,
            ..PodSettings::default()
        };
        let red = pod_reduce(&raw, &full, &train.states, &settings).expect("POD reduction");
        let rsys = System::from_model("pod", red.model.clone()).expect("reduced model");
        let label = format!("energy {fraction:e}");
        println!(
            "chain {label}: r = {}, l = {}, {} -> {} states; error {:.1e} of the peak",
            red.u.ncols(),
            red.constraints.basis.ncols(),
            full.states.len(),
            rsys.states.len(),
            pod_coordinate_error(&check, &run(&rsys, 1.85), red.u.as_ref())
        );
        g.bench_function(BenchmarkId::new("reduced", &label), |bch| {
            bch.iter(|| black_box(run(&rsys, 1.85)))
        });
        g.bench_function(BenchmarkId::new("offline POD", &label), |bch| {
            bch.iter(|| black_box(pod_reduce(&raw, &full, &train.states, &settings)))
        });
    }
    g.finish();
}

criterion_group!(benches, pod, chain);
criterion_main!(benches);
