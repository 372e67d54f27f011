//! Plans without scenes: a plan built in code runs through
//! `pipeline::execute` and writes what the same scene writes; a whole
//! plan, every section in it, survives JSON; a plan's error names its key,
//! and a scene's run turns it into the line of that key.

use std::path::Path;
use std::time::Instant;

use ssm_core::spec::{
    BackboneSpec, FrcSpec, PodTruncations, ReferenceStart, SsmSpec, ValidationStart,
};
use ssm_engine::pipeline::{self, JobError, JobResult, Model, Quiet};
use ssm_engine::plan::budget::Limits;
use ssm_engine::plan::{self, Plan};
use ssm_engine::scene::SceneFile;

/// The Duffing oscillator's backbone and forced response at order 5.
const DUFFING: &str = "[model]\nplugin = \"duffing\"\n[ssm]\norder = 5\n\
[outputs]\ncoordinates = [\"x\"]\n[outputs.backbone]\nrho_max = 0.3\n\
[forcing]\nepsilon = [0.01, 0.02]\nomega_range = [0.9, 1.3]\npoints = 60\n";

/// The plan of [`DUFFING`], written in code.
fn duffing_plan() -> Plan {
    Plan {
        ssm: SsmSpec {
            order: Some(5),
            ..SsmSpec::default()
        },
        coordinates: vec!["x".into()],
        backbone: Some(BackboneSpec::up_to(0.3)),
        frc: Some(FrcSpec {
            points: 60,
            ..FrcSpec::new(vec![0.01, 0.02], [0.9, 1.3])
        }),
        ..Plan::default()
    }
}

fn execute(plan: &Plan, system: ssm_core::model::system::System) -> Result<JobResult, JobError> {
    let model = Model {
        system,
        reduction: None,
        full: None,
        plugins: Vec::new(),
    };
    pipeline::execute(plan, model, &Limits::of_machine(), &Quiet, Instant::now())
}

/// `summary.json` without what differs between two runs of the same
/// computation (timings, memory, the plugin libraries recorded).
fn summary_without_run_facts(job: &JobResult) -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_slice(job.outputs.get("summary.json").expect("a summary")).expect("json");
    let map = v.as_object_mut().expect("an object");
    map.remove("timing_s");
    map.remove("memory");
    map.remove("plugins");
    v
}

/// A determinism check of the two doors (the same code takes the same
/// steps): the plan built in code and the scene's plan give the same
/// files, byte for byte, and the same summary but for its timings, memory
/// and plugin record. The answers themselves are checked against closed forms
/// and other methods elsewhere (`frc`, `ssm_autonomous`).
#[test]
fn a_plan_built_in_code_writes_what_its_scene_writes() {
    let scene = SceneFile::parse(Path::new("duffing.toml"), DUFFING.to_owned()).expect("parses");
    let from_scene = plan::of_scene(&scene).expect("resolves");
    assert_eq!(from_scene, duffing_plan());
    let by_scene = ssm_tests::run_scene_text(DUFFING).expect("the scene runs");
    let by_code =
        execute(&duffing_plan(), ssm_tests::system("duffing", "", "")).expect("the plan runs");
    let names =
        |j: &JobResult| -> Vec<String> { j.outputs.files.iter().map(|(n, _)| n.clone()).collect() };
    assert_eq!(names(&by_scene), names(&by_code));
    assert!(names(&by_code).iter().any(|n| n == "backbone.csv"));
    assert!(names(&by_code).iter().any(|n| n == "frc.csv"));
    for (name, contents) in &by_code.outputs.files {
        if name != "summary.json" {
            assert_eq!(
                Some(contents.as_slice()),
                by_scene.outputs.get(name),
                "{name} differs"
            );
        }
    }
    assert_eq!(
        summary_without_run_facts(&by_code),
        summary_without_run_facts(&by_scene)
    );
}

/// A scene with every section that is not an answer of the reduced model.
const EVERY_SECTION: &str = "[model]\nplugin = \"duffing\"\n\
[ssm]\nmaster_pairs = [1]\ntolerance = 0.02\nnormalization = { scale = 2.0 }\n\
[spectrum]\nmethod = \"sparse\"\nmodes = 4\nshift = 0.5\n\
[outputs]\ncoordinates = [\"x\"]\n\
[forcing]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\n\
[reference]\nepsilon = [0.01, 0.02]\nharmonics = 5\nstart = \"rest\"\n\
amplitude_at = [1.0]\namplitude_range = [0.0, 0.05]\n\
[report]\norders = [3, 5]\n\
[simulate]\nperiod = 0.1\nsamples = 100\nnoise = 0.01\n\
[[simulate.run]]\nrho0 = [0.1]\n[[simulate.run]]\nx0 = { x = 0.1 }\nv0 = { x_dot = 0.2 }\n\
[pod]\nstep = 0.01\nenergy = [1e-3, 1e-5]\nssm_pairs = [[1]]\n\
[pod.train]\nepsilon = 0.1\nomega = 1.0\nt_end = 10.0\n\
[[pod.test]]\nt_end = 5.0\nx0 = { x = 0.2 }\n";

#[test]
fn a_whole_plan_round_trips_through_json() {
    let scene =
        SceneFile::parse(Path::new("every.toml"), EVERY_SECTION.to_owned()).expect("parses");
    let plan = plan::of_scene(&scene).expect("resolves");
    // the sections arrived, with the values the scene gave
    assert_eq!(plan.ssm.tolerance, 0.02);
    assert_eq!(
        plan.ssm.normalization,
        ssm_core::spectrum::Normalization::Scale(2.0)
    );
    assert_eq!(plan.spectrum.modes, Some(4));
    let r = plan.reference.as_ref().expect("reference");
    assert_eq!(r.harmonics, 5);
    assert_eq!(r.start, Some(ReferenceStart::Rest));
    assert!(!r.from_ssm(true));
    assert_eq!(r.omega_range(Some([0.9, 1.1])), Some((0.9, 1.1)));
    assert_eq!(r.amplitude_range(), (0.0, 0.05));
    assert_eq!(plan.report.as_ref().unwrap().orders_up_to(7), vec![3, 5]);
    let s = plan.simulate.as_ref().expect("simulate");
    assert!(matches!(s.runs[0], ValidationStart::Ssm { .. }));
    assert!(
        matches!(&s.runs[1], ValidationStart::Given { values } if values.len() == 2),
        "{:?}",
        s.runs[1]
    );
    let p = plan.pod.as_ref().expect("pod");
    assert_eq!(p.truncations, PodTruncations::Energy(vec![1e-3, 1e-5]));
    assert_eq!(p.tests[0].start, vec![("x".to_owned(), 0.2)]);
    let text = serde_json::to_string_pretty(&plan).expect("serializes");
    let back: Plan = serde_json::from_str(&text).expect("parses back");
    assert_eq!(back, plan, "{text}");
    // the defaults of a plan written as JSON are the scene's
    let minimal: Plan = serde_json::from_str(r#"{"coordinates": ["x"]}"#).expect("json");
    let bare = SceneFile::parse(
        Path::new("bare.toml"),
        "[model]\nplugin = \"duffing\"\n[outputs]\ncoordinates = [\"x\"]\n".into(),
    )
    .expect("parses");
    assert_eq!(minimal, plan::of_scene(&bare).expect("resolves"));
    let e = serde_json::from_str::<Plan>(r#"{"sssm": {}}"#).expect_err("a misspelt key");
    assert!(e.to_string().contains("sssm"), "{e}");
}

/// A plan's mistakes against its model are typed errors naming the key,
/// before anything runs; through a scene they point at the key's line.
#[test]
fn plan_errors_name_the_key_and_the_scene_line() {
    let sys = || ssm_tests::system("duffing", "", "");
    let mut plan = duffing_plan();
    plan.coordinates = vec!["x".into(), "y".into()];
    match execute(&plan, sys()) {
        Err(JobError::Plan(e)) => {
            assert_eq!(e.key, "outputs.coordinates");
            assert!(e.problem.contains("no output 'y'"), "{e}");
        }
        other => panic!("expected a plan error, got {other:?}"),
    }
    let mut plan = duffing_plan();
    plan.reference = Some(ssm_core::spec::ReferenceSpec {
        harmonics: 1_000_000,
        ..ssm_core::spec::ReferenceSpec::new(vec![0.01])
    });
    match execute(&plan, sys()) {
        Err(JobError::Plan(e)) => assert_eq!(e.key, "reference.harmonics", "{e}"),
        other => panic!("expected a plan error, got {other:?}"),
    }
    // the same mistake in a scene: its line
    let text = DUFFING.replace("coordinates = [\"x\"]", "coordinates = [\"x\", \"y\"]");
    let (line, msg) = ssm_tests::scene_error(&text);
    assert_eq!(line, 6, "{msg}");
    assert!(msg.starts_with("outputs.coordinates: "), "{msg}");
}

/// Where a key path is written: its value's line; a default's, the line of
/// the nearest table on its path; `[n]` the n-th of an array of tables.
#[test]
fn keys_are_located_in_the_scene_text() {
    let scene =
        SceneFile::parse(Path::new("every.toml"), EVERY_SECTION.to_owned()).expect("parses");
    let line = |path: &str| ssm_engine::scene::line_of(&scene.text, scene.locate(path).start);
    let line_of = |needle: &str| {
        EVERY_SECTION
            .lines()
            .position(|l| l.starts_with(needle))
            .expect("the needle")
            + 1
    };
    assert_eq!(line("reference.harmonics"), line_of("harmonics = 5"));
    // a default: the table's header
    assert_eq!(line("reference.step"), line_of("[reference]"));
    assert_eq!(line("simulate.run[2]"), line_of("[[simulate.run]]") + 2);
    assert_eq!(line("simulate.run[2].v0"), line_of("v0 = "));
    assert_eq!(line("pod.train.t_end"), line_of("[pod.train]") + 3);
    assert_eq!(line("pod.test[1]"), line_of("[[pod.test]]"));
    // nothing of it written: the start of the file
    assert_eq!(line("validate.t_end"), 1);
    assert_eq!(line("simulate.run[9]"), line_of("[[simulate.run]]"));
}

/// A plan built in code meets the checks a scene's sections meet, each bad
/// value a typed error at its key before anything runs (the scene's checks
/// of these values are the specs' own, so the keys and messages agree).
#[test]
fn hand_built_plans_are_checked_like_scenes() {
    use ssm_core::spec::{
        InvarianceSpec, PodRunSpec, PodSpec, ReferenceSpec, SimulateSpec, SpectrumSpec,
        TransientSpec,
    };
    let base = duffing_plan;
    let transient = TransientSpec {
        rho0: vec![0.1],
        theta0: None,
        t_end: 10.0,
        samples: 11,
        order: None,
        rtol: 1e-9,
    };
    let pod_run = PodRunSpec {
        epsilon: 0.0,
        omega: 0.0,
        t_end: 1.0,
        start: Vec::new(),
        steps: Vec::new(),
    };
    let pod: PodSpec =
        serde_json::from_str(r#"{"step": 0.01, "train": {"t_end": 1.0}}"#).expect("a pod spec");
    let cases: Vec<(&str, Plan)> = vec![
        ("ssm.tolerance", {
            let mut p = base();
            p.ssm.tolerance = 2.0;
            p
        }),
        ("ssm.master_pairs", {
            let mut p = base();
            p.ssm.master_pairs = vec![1, 1];
            p
        }),
        ("spectrum.modes", {
            let mut p = base();
            p.spectrum = SpectrumSpec {
                modes: Some(0),
                ..SpectrumSpec::default()
            };
            p
        }),
        ("outputs.backbone.rho_max", {
            let mut p = base();
            p.backbone = Some(BackboneSpec::up_to(f64::NAN));
            p
        }),
        ("outputs.backbone.orders", {
            let mut p = base();
            p.backbone.as_mut().unwrap().orders = Some(vec![7]);
            p
        }),
        ("outputs.invariance_error.radii", {
            let mut p = base();
            p.invariance = Some(InvarianceSpec {
                radii: vec![],
                orders: vec![3],
                n_alpha: 4,
                n_theta: 4,
            });
            p
        }),
        ("outputs.transient.rtol", {
            let mut p = base();
            p.transient = Some(TransientSpec {
                rtol: 0.5,
                ..transient.clone()
            });
            p
        }),
        ("outputs.transient.rho0", {
            let mut p = base();
            p.transient = Some(TransientSpec {
                rho0: vec![0.1, 0.2],
                ..transient.clone()
            });
            p
        }),
        ("forcing.points", {
            let mut p = base();
            p.frc.as_mut().unwrap().points = 1;
            p
        }),
        ("reference.harmonics", {
            let mut p = base();
            p.reference = Some(ReferenceSpec {
                harmonics: 0,
                ..ReferenceSpec::new(vec![0.01])
            });
            p
        }),
        ("reference.omega_range", {
            let mut p = base();
            p.frc = None;
            p.reference = Some(ReferenceSpec::new(vec![0.01]));
            p
        }),
        ("simulate.noise", {
            let mut p = base();
            p.simulate = Some(SimulateSpec {
                period: 0.1,
                samples: 10,
                outputs: None,
                noise: 2.0,
                seed: 1,
                rtol: 1e-10,
                atol: 1e-12,
                hht_alpha: None,
                runs: vec![ValidationStart::Ssm {
                    rho0: vec![0.1],
                    theta0: None,
                }],
            });
            p
        }),
        ("pod.step", {
            let mut p = base();
            p.pod = Some(PodSpec {
                step: -1.0,
                ..pod.clone()
            });
            p
        }),
        ("pod.test[1]", {
            let mut p = base();
            p.pod = Some(PodSpec {
                tests: vec![PodRunSpec {
                    t_end: f64::INFINITY,
                    ..pod_run.clone()
                }],
                ..pod.clone()
            });
            p
        }),
        ("pod.test[1].steps", {
            let mut p = base();
            p.pod = Some(PodSpec {
                tests: vec![PodRunSpec {
                    steps: vec![(0.5, 1.0), (0.2, 2.0)],
                    ..pod_run.clone()
                }],
                ..pod.clone()
            });
            p
        }),
        ("pod.ssm_pairs", {
            let mut p = base();
            p.pod = Some(PodSpec {
                train: PodRunSpec {
                    steps: vec![(0.5, 2.0)],
                    ..pod_run.clone()
                },
                ssm_pairs: vec![vec![1]],
                ..pod.clone()
            });
            p
        }),
        ("analysis.damping.rho_max", {
            let mut p = base();
            p.analyses = vec![plan::PlannedAnalysis {
                name: "damping".into(),
                spec: serde_json::json!({"rho_max": -1.0}),
            }];
            p
        }),
    ];
    for (key, plan) in cases {
        match plan.validate() {
            Err(e) => assert_eq!(e.key, key, "{e}"),
            Ok(()) => panic!("{key}: the bad value was accepted"),
        }
        match execute(&plan, ssm_tests::system("duffing", "", "")) {
            Err(JobError::Plan(e)) => assert_eq!(e.key, key, "{e}"),
            other => panic!("{key}: expected a plan error, got {other:?}"),
        }
    }
    base().validate().expect("the sound plan passes");
}

/// The invariance error runs as an analysis of the registry
/// (`ssm_engine::analyses::invariance`) and writes what it wrote before its
/// move: its rows under `invariance_error` of `summary.json` (not under
/// `analyses`) and `invariance.csv`/`.svg`. Checks: a determinism check
/// against `invariance_table` called on the run's own SSM (the same code:
/// the same bits, its sum over the torus taken in the points' order on any
/// number of threads); eq. (41) falls with the order at a radius inside the
/// convergence (the residual is `O(rho^(order + 1))`). Asking for it in
/// `[analysis.invariance]` or in a plan's `analyses` is refused: its table
/// is `[outputs.invariance_error]`.
#[test]
fn the_invariance_error_runs_as_an_analysis_and_keeps_its_key() {
    use ssm_core::rom::autonomous::invariance_table;
    use ssm_core::spec::InvarianceSpec;
    let table = "[outputs.invariance_error]\nradii = [0.05, 0.1]\norders = [3, 5]\n";
    let (job, summary) = run_with(table, "invariance");
    let rows = summary["invariance_error"]
        .as_array()
        .expect("invariance_error");
    let spec = InvarianceSpec {
        radii: vec![0.05, 0.1],
        orders: vec![3, 5],
        n_alpha: InvarianceSpec::DEFAULT_N_ALPHA,
        n_theta: InvarianceSpec::DEFAULT_N_THETA,
    };
    let direct =
        invariance_table(job.ssm.as_ref().expect("an SSM"), &job.system, &spec).expect("the table");
    assert_eq!(rows.len(), direct.len());
    for (row, d) in rows.iter().zip(&direct) {
        assert_eq!(row["order"], d.order);
        assert_eq!(row["radius"].as_f64(), Some(d.radius));
        assert_eq!(row["error"].as_f64(), Some(d.error));
    }
    let at = |order: usize, radius: f64| {
        direct
            .iter()
            .find(|d| d.order == order && d.radius == radius)
            .expect("a row")
            .error
    };
    assert!(at(5, 0.05) < at(3, 0.05), "{direct:?}");
    let csv = std::str::from_utf8(job.outputs.get("invariance.csv").expect("csv")).unwrap();
    assert!(csv.starts_with("order,radius,error\n") && csv.lines().count() == 5);
    assert!(job.outputs.get("invariance.svg").is_some());
    refused_as_an_analysis(
        "invariance",
        "radii = [0.1]\norders = [3]\n",
        "outputs.invariance_error",
    );
    let mut plan = duffing_plan();
    plan.analyses = vec![plan::PlannedAnalysis {
        name: "invariance".into(),
        spec: serde_json::to_value(&spec).expect("json"),
    }];
    let e = plan.validate().expect_err("refused");
    assert_eq!(e.key, "analysis.invariance", "{e}");
    assert!(e.problem.contains("[outputs.invariance_error]"), "{e}");
}

/// The reduced transient runs as an analysis of the registry
/// (`ssm_engine::analyses::transient`) and writes what it wrote before its
/// move: its steps under `rom_steps` of `summary.json` (not under
/// `analyses`), `rom_trajectory.csv`, and its estimate in
/// `accuracy.answers` between the backbone's and the forced responses'.
/// Checks: a determinism check against `autonomous::transient` called on
/// the run's own SSM (the same code: the same bits in the file's 10
/// significant digits); the free decay of the damped Duffing oscillator
/// loses amplitude (`rho` falls from `rho0`, each of the 11 samples below
/// the one before). Started far out (`rho0 = 2`, beyond the backbone's
/// convergence) its estimate exceeds the tolerance: the entry is untrusted
/// and the run warns about it in the transient's words. `[analysis.transient]`
/// is refused at its line: its table is `[outputs.transient]`.
#[test]
fn the_transient_runs_as_an_analysis_and_keeps_its_key() {
    use ssm_core::rom::autonomous::transient;
    use ssm_core::spec::TransientSpec;
    let table = "[outputs.transient]\nrho0 = [0.2]\nt_end = 20.0\nsamples = 11\n";
    let (job, summary) = run_with(table, "transient");
    let answers: Vec<&str> = summary["accuracy"]["answers"]
        .as_array()
        .expect("answers")
        .iter()
        .map(|a| a["answer"].as_str().expect("a name"))
        .collect();
    assert_eq!(answers, ["backbone", "transient", "frc", "frc"]);
    let spec = TransientSpec {
        rho0: vec![0.2],
        theta0: None,
        t_end: 20.0,
        samples: 11,
        order: None,
        rtol: TransientSpec::DEFAULT_RTOL,
    };
    let x = job.system.output("x").expect("output x");
    let direct = transient(
        job.ssm.as_ref().expect("an SSM"),
        &job.system,
        &job.masters,
        &spec,
        &[x],
        SsmSpec::default().tolerance,
    )
    .expect("the transient");
    assert_eq!(summary["rom_steps"], direct.steps);
    assert_eq!(direct.order, 5);
    let entry = &summary["accuracy"]["answers"][1];
    assert_eq!(entry["order"], 5);
    assert_eq!(entry["error_estimate"].as_f64(), direct.error_estimate);
    assert_eq!(entry["untrusted"], false);
    let csv = std::str::from_utf8(job.outputs.get("rom_trajectory.csv").expect("csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t,x,rho_1,theta_1"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), 11);
    for (k, row) in rows.iter().enumerate() {
        let want = [
            direct.times[k],
            direct.outputs[k][0],
            direct.polar[k][0].0,
            direct.polar[k][0].1,
        ];
        for (a, b) in row.iter().zip(want) {
            assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-300), "{a} {b}");
        }
        if k > 0 {
            assert!(row[2] < rows[k - 1][2], "rho grows at sample {k}");
        }
    }
    // far out: untrusted, with the transient's warning
    let far = "[outputs.transient]\nrho0 = [2.0]\nt_end = 1.0\nsamples = 3\n";
    let job = ssm_tests::run_scene_text(&format!("{DUFFING}{far}")).expect("scene runs");
    let summary = summary_of(&job);
    let entry = &summary["accuracy"]["answers"][1];
    assert_eq!(entry["answer"], "transient");
    assert_eq!(entry["untrusted"], true, "{entry}");
    assert!(
        job.warnings.iter().any(|w| w.starts_with(
            "transient O(5): the estimated error, "
        ) && w.ends_with(
            "do not trust it: start nearer the equilibrium (rho0), shorten t_end or raise the expansion order"
        )),
        "{:?}",
        job.warnings
    );
    refused_as_an_analysis(
        "transient",
        "rho0 = [0.1]\nt_end = 1.0\n",
        "outputs.transient",
    );
}

/// The backbone runs as an analysis of the registry
/// (`ssm_engine::analyses::backbone`) and writes what it wrote before its
/// move: `backbone.csv`/`.svg`, no key of its own in `summary.json`, and
/// its estimates first in `accuracy.answers`. Checks: a determinism check
/// against `autonomous::backbone` called on the run's own SSM (the same
/// code: the same numbers in the file's 10 significant digits, 4 for the
/// estimates); at `rho = 0` the curve starts at the master eigenvalue's frequency `Im lambda`
/// (the spectrum's, computed apart from the polar form). Taken far out
/// (`rho_max = 3`, beyond the expansion's convergence) the curve is
/// untrusted beyond the amplitude its estimate names, and the run warns
/// about it in the backbone's words. `[analysis.backbone]` is refused at its
/// line: its table is `[outputs.backbone]`.
#[test]
fn the_backbone_runs_as_an_analysis_and_keeps_its_files() {
    use ssm_core::rom::autonomous::backbone;
    let job = ssm_tests::run_scene_text(DUFFING).expect("scene runs");
    let summary = summary_of(&job);
    assert!(summary.get("analyses").is_none(), "{}", summary["analyses"]);
    assert!(summary.get("backbone").is_none());
    let x = job.system.output("x").expect("output x");
    let spec = BackboneSpec::up_to(0.3);
    let direct = backbone(
        job.ssm.as_ref().expect("an SSM"),
        &job.system,
        &job.masters[0],
        &spec,
        &[x],
        SsmSpec::default().tolerance,
    )
    .expect("the backbone");
    assert_eq!(direct.len(), 1);
    let entry = &summary["accuracy"]["answers"][0];
    assert_eq!(entry["answer"], "backbone");
    assert_eq!(entry["order"], 5);
    assert_eq!(entry["error_estimate"].as_f64(), direct[0].error_estimate);
    let csv = std::str::from_utf8(job.outputs.get("backbone.csv").expect("csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("order,rho,omega,x,error_estimate"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("a number")).collect())
        .collect();
    assert_eq!(rows.len(), direct[0].points.len());
    for (row, p) in rows.iter().zip(&direct[0].points) {
        let want = [
            5.0,
            p.rho,
            p.omega,
            p.amplitudes[0],
            p.error_estimate.expect("an estimate"),
        ];
        // the estimate is written to 4 significant digits
        for (k, (a, b)) in row.iter().zip(want).enumerate() {
            let digits = if k == 4 { 1e-3 } else { 1e-9 };
            assert!((a - b).abs() <= digits * b.abs().max(1e-300), "{a} {b}");
        }
    }
    let omega0 = job.masters[0].lambda.im;
    assert_eq!(rows[0][1], 0.0);
    assert!(
        (rows[0][2] - omega0).abs() <= 1e-9 * omega0,
        "{} {omega0}",
        rows[0][2]
    );
    assert!(job.outputs.get("backbone.svg").is_some());
    assert!(job.outputs.get("data_backbone.csv").is_none());
    // far out: untrusted beyond an amplitude, with the backbone's warning
    let far = DUFFING.replace("rho_max = 0.3", "rho_max = 3.0");
    let job = ssm_tests::run_scene_text(&far).expect("scene runs");
    let summary = summary_of(&job);
    let entry = &summary["accuracy"]["answers"][0];
    assert_eq!(entry["untrusted"], true, "{entry}");
    let trusted = entry["trusted_up_to_rho"].as_f64().expect("an amplitude");
    assert!(trusted > 0.0 && trusted < 3.0, "{entry}");
    assert!(
        job.warnings
            .iter()
            .any(|w| w.starts_with("backbone O(5): the estimated error, ")
                && w.contains(&format!(
                    " beyond rho = {trusted:.4}; do not trust it: lower [outputs.backbone] rho_max"
                ))),
        "{:?}",
        job.warnings
    );
    refused_as_an_analysis("backbone", "rho_max = 0.1\n", "outputs.backbone");
}

/// The forced response runs as an analysis of the registry
/// (`ssm_engine::analyses::frc`) and writes what it wrote before its move:
/// its summary under `frc` of `summary.json` (not under `analyses`),
/// `frc.csv`, and `frc.svg` with the full system's steady states of
/// `[validate]` drawn in; `JobResult::frc` holds the curves. Checks: a
/// determinism check against `forced_response` called on the run's own SSM
/// (the same code: equal curves, an equal summary); the estimates of
/// `accuracy.answers` come in the plan's order whatever the order of the
/// scene's tables (backbone, transient, the two forced responses, then the
/// damping curve of `[analysis.damping]`).
#[test]
fn the_forced_response_runs_as_an_analysis_and_keeps_its_key() {
    use ssm_core::rom::forced_response::forced_response;
    use ssm_engine::analyses::frc::FrcSummary;
    let scene = format!(
        "[analysis.damping]\nrho_max = 0.2\n{DUFFING}[outputs.transient]\nrho0 = [0.1]\nt_end = 5.0\n\
         [validate.steady_state]\nepsilon = 0.01\nomega_range = [1.0, 1.1]\npoints = 2\n"
    );
    let job = ssm_tests::run_scene_text(&scene).expect("scene runs");
    ssm_tests::assert_job_summary_valid(&job, "frc-slice");
    let summary = summary_of(&job);
    let x = job.system.output("x").expect("output x");
    let spec = FrcSpec {
        points: 60,
        ..FrcSpec::new(vec![0.01, 0.02], [0.9, 1.3])
    };
    let direct = forced_response(
        job.ssm.as_ref().expect("an SSM"),
        &job.system,
        &job.masters,
        &spec,
        &[x],
        SsmSpec::default().tolerance,
    )
    .expect("the forced response");
    assert_eq!(job.frc.as_ref(), Some(&direct));
    assert_eq!(
        summary["frc"],
        serde_json::to_value(FrcSummary::new(&direct)).expect("json")
    );
    assert!(summary["analyses"].get("frc").is_none());
    let answers: Vec<&str> = summary["accuracy"]["answers"]
        .as_array()
        .expect("answers")
        .iter()
        .map(|a| a["answer"].as_str().expect("a name"))
        .collect();
    assert_eq!(answers, ["backbone", "transient", "frc", "frc", "damping"]);
    let csv = std::str::from_utf8(job.outputs.get("frc.csv").expect("csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + direct.rows.len());
    let svg = std::str::from_utf8(job.outputs.get("frc.svg").expect("svg")).unwrap();
    assert!(ssm_tests::svg_text(svg).contains("full system, eps = 0.01 (steady state)"));
}

/// Stages seen by a progress display.
#[derive(Default)]
struct Stages(std::sync::Mutex<Vec<String>>);

impl pipeline::Progress for Stages {
    fn stage(&self, name: &str) {
        self.0.lock().expect("stages").push(name.to_owned());
    }
}

/// The sampled full-system runs run as an analysis of the registry's
/// full-system phase (`ssm_engine::analyses::simulate`): once, on the SSM
/// of the order the run chose, although the choice tried several orders;
/// they keep `simulation` of `summary.json` and the files
/// `simulation_<k>.csv`. Checks: a determinism check against `sample_run`
/// from the start `Re W(p0)` on the run's own SSM with the spec's default
/// tolerances (the same code: the same numbers, which the files write in
/// shortest round-trip form); the damped oscillator's free decay loses
/// amplitude (the largest `|x|` of the last quarter of the samples below
/// that of the first).
#[test]
fn the_sampled_runs_run_once_after_the_order_is_chosen() {
    use ssm_core::fom::{sample_run, Integrator, RadauOptions};
    use ssm_core::rom::autonomous::polar_point;
    use ssm_core::spec::SimulateSpec;
    let text = DUFFING.replace("order = 5", "tolerance = 1e-6")
        + "[simulate]\nperiod = 0.5\nsamples = 41\n[[simulate.run]]\nrho0 = [0.1]\n\
           [[simulate.run]]\nrho0 = [0.2]\n";
    let scene = SceneFile::parse(Path::new("simulate.toml"), text).expect("scene");
    let stages = Stages::default();
    let job = ssm_engine::job::run(&scene, &mut ssm_tests::registry(), &stages).expect("runs");
    let stages = stages.0.into_inner().expect("stages");
    let orders = stages
        .iter()
        .filter(|s| s.starts_with("SSM to order"))
        .count();
    assert!(orders >= 2, "{stages:?}");
    let sampled = stages
        .iter()
        .filter(|s| *s == "sampling full-system runs")
        .count();
    assert_eq!(sampled, 1, "{stages:?}");
    let summary = summary_of(&job);
    assert_eq!(
        summary["simulation"]["runs"].as_array().map(Vec::len),
        Some(2)
    );
    assert!(summary.get("analyses").is_none());
    let ssm = job.ssm.as_ref().expect("an SSM");
    let x = job.system.output("x").expect("output x");
    for (k, rho) in [0.1, 0.2].into_iter().enumerate() {
        let p0 = polar_point(&[rho], &[0.0]);
        let z0: Vec<f64> = ssm
            .w_at(&ssm.set.monomials(&p0, ssm.order), ssm.order)
            .iter()
            .map(|c| c.re)
            .collect();
        let options = RadauOptions {
            rtol: SimulateSpec::DEFAULT_RTOL,
            atol: SimulateSpec::DEFAULT_ATOL,
            ..RadauOptions::default()
        };
        let direct = sample_run(
            &job.system,
            &z0,
            &[],
            0.5,
            41,
            &[x],
            Integrator::Radau(options),
        )
        .expect("the run");
        let name = format!("simulation_{}.csv", k + 1);
        let csv = std::str::from_utf8(job.outputs.get(&name).expect("csv")).unwrap();
        let values: Vec<f64> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(1).expect("x").parse().expect("a number"))
            .collect();
        assert_eq!(values, direct.values[0], "{name}");
        let peak = |s: &[f64]| s.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(peak(&values[30..]) < peak(&values[..10]), "{name}");
    }
}

/// [`DUFFING`] with `table`: the run, and its `summary.json` checked
/// against the schema (as `name`) and without `analyses`.
fn run_with(table: &str, name: &str) -> (JobResult, serde_json::Value) {
    let job = ssm_tests::run_scene_text(&format!("{DUFFING}{table}")).expect("scene runs");
    ssm_tests::assert_job_summary_valid(&job, name);
    let summary = summary_of(&job);
    assert!(summary.get("analyses").is_none(), "{}", summary["analyses"]);
    (job, summary)
}

/// The `summary.json` of a run.
fn summary_of(job: &JobResult) -> serde_json::Value {
    serde_json::from_slice(job.outputs.get("summary.json").expect("summary")).expect("json")
}

/// `[analysis.<name>]` with `body` is refused at its line, naming the
/// answer's own table `own`.
fn refused_as_an_analysis(name: &str, body: &str, own: &str) {
    let text = format!("{DUFFING}[analysis.{name}]\n{body}");
    let (line, msg) = ssm_tests::scene_error(&text);
    assert_eq!(line, 1 + DUFFING.lines().count(), "{msg}");
    assert!(
        msg.contains(&format!("analysis.{name}")) && msg.contains(&format!("[{own}]")),
        "{msg}"
    );
}
