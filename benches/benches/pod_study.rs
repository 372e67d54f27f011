//! The `[pod]` study's runs (`ssm_core::compare::pod`): the full HHT run
//! against the POD model evaluated through the lift, and against its DEIM
//! hyper-reductions, on the same fixed steps from rest. Timed: the HHT
//! integration alone (the online cost; the study's comparisons, the lift of
//! every step and the reaction gaps, are not). Before timing, each case
//! prints the reduced run's output error against the full run (relative to
//! each output's peak) and the sizes, so speed and error are read side by
//! side.
//!
//! - The V8 crank drive in its housing (zoo scene
//!   `crank_drive_v8_housing_pod.toml`: 119 states, 34 POD coordinates),
//!   the paper's load schedule over 2 s at 0.5 ms.
//! - The divider (4 + 6 elements, 62 states) at 30 rad/s over 0.6 s at
//!   2 ms, POD at a drop of 6 decades, DEIM of 6 and 12 force rows.
//! - The crank drive with flexible rods (zoo scene
//!   `crank_drive_flexible_pod.toml`: four rods of eight ANCF elements, 332
//!   states), its training load over 1 s at 0.2 ms, POD at an energy of
//!   1e-13 left out (28 coordinates), DEIM at training tolerances 1e-7 and
//!   1e-8.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench pod_study`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_core::compare::pod::{full_run, pod_case_run, pod_roms, LoadCase, StudySettings};
use ssm_core::fom::hht::{integrate, HhtOptions};
use ssm_core::fom::DaeProblem;
use ssm_core::reduce::hyper::Sample;
use ssm_core::reduce::pod::Truncation;
use ssm_tests::model_and_system;

/// One study case: the model, its load, the study's settings, the outputs,
/// the truncation and the DEIM samples.
struct Case {
    label: &'static str,
    plugin: &'static str,
    model: &'static str,
    params: &'static str,
    load: LoadCase,
    settings: StudySettings,
    outputs: &'static [&'static str],
    truncation: Truncation,
    hyper: Vec<Sample>,
}

fn cases() -> Vec<Case> {
    let load = |epsilon, omega, t_end, steps: &[(f64, f64)]| LoadCase {
        label: "train".into(),
        epsilon,
        omega,
        t_end,
        start: Vec::new(),
        steps: steps.to_vec(),
        trained: true,
    };
    vec![
        Case {
            label: "V8 in housing",
            plugin: "crank-drive",
            model: "crank-drive-housing",
            params: "cylinders = 8\nv_angle = 90.0\nj_crank = 0.2\nc_crank = 1.0\ntau_mean = 50.0",
            load: load(1.0, 0.0, 2.0, &[(0.2, 1.0), (1.5, 5.0)]),
            settings: StudySettings {
                step: 5e-4,
                alpha: -0.1,
                rank_tol: 1e-3,
                jacobian_samples: 64,
            },
            outputs: &["stroke1", "stroke8", "hx", "hy", "rot_z"],
            truncation: Truncation::Energy { fraction: 1e-12 },
            hyper: Vec::new(),
        },
        Case {
            label: "divider 4+6",
            plugin: "divider",
            model: "divider",
            params: "n1 = 4\nn2 = 6",
            load: load(0.1, 30.0, 0.6, &[]),
            settings: StudySettings {
                step: 2e-3,
                alpha: -0.1,
                rank_tol: 1e-8,
                jacobian_samples: 64,
            },
            outputs: &["w_hori_mid", "w_vert_mid"],
            truncation: Truncation::Drop { decades: 6.0 },
            hyper: vec![Sample::Points(6), Sample::Points(12)],
        },
        Case {
            label: "flexible drive 4x8",
            plugin: "crank-drive",
            model: "crank-drive-flexible",
            params: "cylinders = 4\ntau_mean = 1.0\ntau_amp = 0.5\nrod_elements = 8",
            load: load(1.0, 0.0, 1.0, &[]),
            settings: StudySettings {
                step: 2e-4,
                alpha: -0.1,
                rank_tol: 1e-4,
                jacobian_samples: 64,
            },
            outputs: &["stroke1", "stroke4", "bend1", "bend4"],
            truncation: Truncation::Energy { fraction: 1e-13 },
            hyper: vec![Sample::Tolerance(1e-7), Sample::Tolerance(1e-8)],
        },
    ]
}

fn study(c: &mut Criterion) {
    let mut g = c.benchmark_group("pod study: full vs lifted POD vs DEIM (HHT)");
    g.sample_size(10);
    for case in cases() {
        let (model, sys) = model_and_system(case.plugin, case.model, case.params);
        let outputs: Vec<_> = case
            .outputs
            .iter()
            .map(|o| sys.output(o).expect("output"))
            .collect();
        let full = full_run(&sys, &case.load, &case.settings, &outputs).expect("full run");
        let roms = pod_roms(
            &model,
            &sys,
            &full.solution,
            &[("pod".into(), case.truncation)],
            &case.hyper,
            &case.settings,
        )
        .expect("POD models");
        assert!(case.load.start.is_empty(), "from rest");
        let options = HhtOptions::new(case.settings.alpha, case.settings.step);
        let (eps, omega, t_end) = (case.load.epsilon, case.load.omega, case.load.t_end);
        let problem = DaeProblem::new(&sys, eps, omega).with_steps(&case.load.steps);
        let rest = vec![0.0; sys.n_states()];
        g.bench_function(BenchmarkId::new("full", case.label), |b| {
            b.iter(|| black_box(integrate(&problem, &rest, 0.0, t_end, &options)))
        });
        for rom in &roms {
            let run = pod_case_run(rom, &sys, &case.load, &full, &case.settings, &outputs);
            println!(
                "{}: {} -> {} states, {}; error {:.1e} of the peak",
                case.label,
                sys.n_states(),
                rom.system.n_states(),
                rom.label,
                run.errors.map_or(f64::NAN, |e| e.max)
            );
            let reduced = match &rom.lifted {
                Some(l) => DaeProblem::lifted(&rom.system, eps, omega, l),
                None => DaeProblem::new(&rom.system, eps, omega),
            }
            .with_steps(&case.load.steps);
            let rest = vec![0.0; rom.system.n_states()];
            g.bench_function(BenchmarkId::new(rom.label.as_str(), case.label), |b| {
                b.iter(|| black_box(integrate(&reduced, &rest, 0.0, t_end, &options)))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, study);
criterion_main!(benches);
