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
use ssm_engine::fom::hht::{integrate, HhtOptions, HhtSolution};
use ssm_engine::fom::DaeProblem;
use ssm_engine::model::system::System;
use ssm_engine::reduce::pod_model::{pod_reduce, PodReduction, PodSettings};
use ssm_tests::system;

fn hht(sys: &System, eps: f64, omega: f64, t_end: f64) -> HhtSolution {
    let p = DaeProblem::new(sys, eps, omega);
    let z0 = vec![0.0; sys.states.len()];
    integrate(&p, &z0, 0.0, t_end, &HhtOptions::new(-0.1, 1e-3)).expect("HHT run")
}

fn error(full: &HhtSolution, reduced: &HhtSolution, red: &PodReduction) -> f64 {
    let (n, r) = (red.u.nrows(), red.u.ncols());
    let (mut err, mut peak) = (0.0f64, 0.0f64);
    for (&t, z) in full.times.iter().zip(&full.states) {
        let y = reduced.at(t, r);
        for (i, zi) in z[..n].iter().enumerate() {
            let lifted: f64 = (0..r).map(|j| red.u[(i, j)] * y[j]).sum();
            err = err.max((lifted - zi).abs());
            peak = peak.max(zi.abs());
        }
    }
    err / peak
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
            error(&a, &b, &red)
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
