//! The full system's forced response (`[reference]`: harmonic balance,
//! continuation, Floquet multipliers) on the Duffing oscillator through its
//! folds, the spatial oscillator with the cubic constraint (index-3 DAE) and
//! the 405-state chain of pendulums of Fig. 15. Each first prints its error
//! against an independent reference (the one-harmonic closed form of the
//! folds; the truncation estimate; the chain's steady state by Radau
//! integration at Omega = 2), the orbits and factorizations, then is timed.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench reference`
//! (the chain alone: `... --bench reference -- chain`, about 10 minutes).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use ssm_engine::fom::periodic::{reference_frc, ReferenceEventKind, ReferenceSettings};
use ssm_engine::fom::{steady_state, DaeProblem, SteadyOptions};
use ssm_engine::model::system::{OutputMap, System};
use ssm_tests::{forced_duffing, system};

fn settings(
    epsilon: f64,
    range: (f64, f64),
    harmonics: usize,
    outputs: Vec<OutputMap>,
) -> ReferenceSettings {
    ReferenceSettings {
        epsilon,
        omega_range: range,
        harmonics,
        step: 0.5,
        tol: 1e-10,
        max_steps: 5000,
        outputs,
        points_at: Vec::new(),
        seeds: Vec::new(),
        period_doubling: true,
    }
}

fn outputs(sys: &System, names: &[&str]) -> Vec<OutputMap> {
    names
        .iter()
        .map(|n| sys.output(n).expect("output").clone())
        .collect()
}

/// `((1 + 3/4 a^2 - W)^2 + 4 zeta^2 W) a^2 = eps^2` at the fold nearest
/// `(a, Omega)` (Newton on the curve and its `a`-derivative).
fn closed_form_fold(zeta: f64, eps: f64, a: f64, omega: f64) -> f64 {
    let g = |a: f64, w: f64| {
        ((1.0 + 0.75 * a * a - w).powi(2) + 4.0 * zeta * zeta * w) * a * a - eps * eps
    };
    let ga = |a: f64, w: f64| (g(a + 1e-7, w) - g(a - 1e-7, w)) / 2e-7;
    let (mut a, mut w) = (a, omega * omega);
    for _ in 0..60 {
        let (f1, f2) = (g(a, w), ga(a, w));
        let (da, dw) = (1e-6 * a, 1e-6 * w);
        let j11 = (g(a + da, w) - g(a - da, w)) / (2.0 * da);
        let j12 = (g(a, w + dw) - g(a, w - dw)) / (2.0 * dw);
        let j21 = (ga(a + da, w) - ga(a - da, w)) / (2.0 * da);
        let j22 = (ga(a, w + dw) - ga(a, w - dw)) / (2.0 * dw);
        let det = j11 * j22 - j12 * j21;
        a -= (f1 * j22 - f2 * j12) / det;
        w -= (j11 * f2 - j21 * f1) / det;
    }
    w.sqrt()
}

fn duffing(c: &mut Criterion) {
    let (zeta, eps) = (0.005, 0.002);
    let sys = forced_duffing(zeta, 1.0, &[(1.0, 1.0)]);
    let out = vec![OutputMap {
        name: "x".into(),
        weights: vec![(0, 1.0)],
    }];
    let mut g = c.benchmark_group("reference Duffing");
    for h in [1usize, 9] {
        let s = settings(eps, (0.9, 1.1), h, out.clone());
        let b = reference_frc(&sys, &s, |_| true).expect("reference");
        let errors: Vec<String> = b
            .events
            .iter()
            .filter(|e| e.kind == ReferenceEventKind::Fold)
            .map(|e| {
                let w = closed_form_fold(zeta, eps, e.orbit.linf[0], e.orbit.omega);
                format!("{:.2e}", (e.orbit.omega - w).abs() / w)
            })
            .collect();
        println!(
            "Duffing H = {h}: {} orbits, {} factorizations, fold frequencies vs the one-harmonic closed form {}",
            b.orbits.len(),
            b.factorizations,
            errors.join(", ")
        );
        g.bench_function(format!("FRC through the folds, H = {h}"), |bch| {
            bch.iter(|| black_box(reference_frc(&sys, &s, |_| true).expect("reference")))
        });
    }
    g.finish();
}

fn spatial(c: &mut Criterion) {
    let sys = system("spatial-oscillator", "oscillator", "constraint = \"cubic\"");
    let s = settings(0.02, (1.8, 2.2), 9, outputs(&sys, &["x1"]));
    let b = reference_frc(&sys, &s, |_| true).expect("reference");
    println!(
        "spatial oscillator (cubic), eps = 0.02: {} orbits, {} factorizations, largest truncation estimate {:.2e}",
        b.orbits.len(),
        b.factorizations,
        b.orbits.iter().map(|o| o.tail).fold(0.0, f64::max)
    );
    let mut g = c.benchmark_group("reference spatial oscillator");
    g.sample_size(10);
    g.bench_function("FRC eps = 0.02, H = 9", |bch| {
        bch.iter(|| black_box(reference_frc(&sys, &s, |_| true).expect("reference")))
    });
    g.finish();
}

fn chain(c: &mut Criterion) {
    let sys = system("pendulum", "chain", "");
    let mut s = settings(0.6, (1.8, 2.2), 9, outputs(&sys, &["phi_n", "x1"]));
    s.points_at = vec![2.0];
    let b = reference_frc(&sys, &s, |_| true).expect("reference");
    let p = DaeProblem::new(&sys, 0.6, 2.0);
    let refs: Vec<&OutputMap> = s.outputs.iter().collect();
    let opts = SteadyOptions {
        delta: 1e-6,
        max_periods: 3000,
        ..SteadyOptions::default()
    };
    let ss = steady_state(&p, &vec![0.0; sys.n_states()], &refs, &opts).expect("steady state");
    let norm = ss.z_end.iter().map(|v| v * v).sum::<f64>().sqrt();
    let gap =
        b.at.iter()
            .map(|(_, z)| {
                z.iter()
                    .zip(&ss.z_end)
                    .map(|(a, b)| (a - b) * (a - b))
                    .sum::<f64>()
                    .sqrt()
                    / norm
            })
            .fold(f64::INFINITY, f64::min);
    println!(
        "chain (405 states), eps = 0.6: {} orbits, {} factorizations; state at Omega = 2 vs the Radau steady state (delta = 1e-6): {gap:.2e}",
        b.orbits.len(),
        b.factorizations
    );
    s.points_at.clear();
    let mut g = c.benchmark_group("reference chain");
    g.sample_size(10);
    g.bench_function("FRC eps = 0.6 over [1.8, 2.2], H = 9", |bch| {
        bch.iter(|| black_box(reference_frc(&sys, &s, |_| true).expect("reference")))
    });
    g.finish();
}

criterion_group!(benches, duffing, spatial, chain);
criterion_main!(benches);
