//! The full system's forced response (`[reference]`: harmonic balance,
//! continuation, Floquet multipliers) on the Duffing oscillator through its
//! folds, the spatial oscillator with the cubic constraint (index-3 DAE),
//! the 405-state chain of pendulums of Fig. 15 and the 146-state frequency
//! divider of Figs. 18-19 (main and period-2T branches). Each first prints its error
//! against an independent reference (the one-harmonic closed form of the
//! folds; the truncation estimate; the chain's steady state by Radau
//! integration at Omega = 2), the orbits and factorizations, then is timed.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench reference`
//! (the chain alone: `... --bench reference -- chain`, about 10 minutes; the
//! divider: `... -- divider`, about 25 minutes).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use ssm_core::fom::periodic::{reference_frc, ReferenceSettings};
use ssm_core::fom::{steady_state, DaeProblem, SteadyOptions};
use ssm_core::model::system::{OutputMap, System};
use ssm_kernel::continuation::BifurcationKind;
use ssm_tests::{duffing_fold, forced_duffing, system};

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
        stability: true,
    }
}

fn outputs(sys: &System, names: &[&str]) -> Vec<OutputMap> {
    names
        .iter()
        .map(|n| sys.output(n).expect("output").clone())
        .collect()
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
            .filter(|e| e.kind == BifurcationKind::Fold)
            .map(|e| {
                let (_, w) = duffing_fold(zeta, 1.0, eps, e.orbit.linf[0], e.orbit.omega);
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

/// The frequency divider of Sect. 5.3 (146 states, index-3 joint) at eps =
/// 0.1 over Fig. 18's range with 5 harmonics (1606 Fourier coefficients:
/// multipliers by the monodromy matrix): the main branch, its two period
/// doublings, and the branch of period 2T between them with its
/// saddle-node. Printed first: the period doublings and the saddle-node
/// against the O(5) SSM's branch points and saddle-node (the reduced
/// model's 1:2 rotating frame turns the period doublings into branch
/// points).
fn divider(c: &mut Criterion) {
    let sys = system("divider", "", "");
    let mut s = settings(
        0.1,
        (43.07, 49.87),
        5,
        outputs(&sys, &["w_hori_mid", "w_vert_mid"]),
    );
    s.period_doubling = true;
    let scene = r#"
[model]
plugin = "divider"
[spectrum]
method = "sparse"
modes = 20
[ssm]
master_pairs = [1, 2]
order = 5
[outputs]
coordinates = ["w_hori_mid", "w_vert_mid"]
[forcing]
epsilon = [0.1]
omega_range = [43.07, 49.87]
orders = [5]
"#;
    let rom = ssm_tests::run_scene_text(scene).expect("divider ROM");
    let frc = rom.frc.expect("forced response");
    let rom_at = |kind: &str, branch: usize| -> Vec<f64> {
        frc.curves
            .iter()
            .flat_map(|c| &c.bifurcations)
            .filter(|b| b.kind == kind && b.branch == branch)
            .map(|b| b.omega)
            .collect()
    };
    let t = std::time::Instant::now();
    let b = reference_frc(&sys, &s, |_| true).expect("reference");
    let seconds = t.elapsed().as_secs_f64();
    let nearest = |w: f64, list: &[f64]| {
        list.iter()
            .map(|r| (w - r).abs() / r)
            .fold(f64::INFINITY, f64::min)
    };
    let pds: Vec<String> = b
        .events
        .iter()
        .filter(|e| e.kind == BifurcationKind::PeriodDoubling)
        .map(|e| {
            format!(
                "{:.5} ({:.1e} from the SSM's BP)",
                e.orbit.omega,
                nearest(e.orbit.omega, &rom_at("BP", 1))
            )
        })
        .collect();
    let sns: Vec<String> = b
        .doubled
        .iter()
        .flat_map(|d| &d.events)
        .filter(|e| e.kind == BifurcationKind::Fold)
        .map(|e| {
            format!(
                "{:.5} ({:.1e} from the SSM's SN)",
                e.orbit.omega,
                nearest(e.orbit.omega, &rom_at("SN", 2))
            )
        })
        .collect();
    println!(
        "divider (146 states), eps = 0.1, H = 5: main branch {} orbits, period doublings {}; {} branch(es) of period 2T, {} orbits, saddle-nodes {}; {seconds:.0} s once",
        b.orbits.len(),
        pds.join(", "),
        b.doubled.len(),
        b.doubled.iter().map(|d| d.orbits.len()).sum::<usize>(),
        sns.join(", ")
    );
    let mut g = c.benchmark_group("reference divider");
    g.sample_size(10);
    g.bench_function("main and 2T branches, eps = 0.1, H = 5", |bch| {
        bch.iter(|| black_box(reference_frc(&sys, &s, |_| true).expect("reference")))
    });
    g.finish();
}

criterion_group!(benches, duffing, spatial, chain, divider);
criterion_main!(benches);
