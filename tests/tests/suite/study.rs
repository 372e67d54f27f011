//! `ssm-engine study`: a study's points run as shards of a job array and
//! merged give the single run's table; a point's figures are those of the
//! scene run with the point's values written into it; reruns compute only
//! what is missing; bad studies end in typed errors or per-point records.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use ssm_engine::study::store::{read_records, Cell, Record};
use ssm_tests::{engine_binary, plugin_path, repo_root, tmp_dir};

/// The base scene of the bundled study.
fn base_scene() -> String {
    std::fs::read_to_string(repo_root().join("zoo/studies/spatial_oscillator_frc.toml"))
        .expect("the bundled base scene")
}

/// A folder holding the bundled base scene and the study `text`.
fn study_dir(name: &str, text: &str) -> (PathBuf, PathBuf) {
    let dir = tmp_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("spatial_oscillator_frc.toml"), base_scene()).unwrap();
    let study = dir.join("s.study.toml");
    std::fs::write(&study, text).unwrap();
    (dir, study)
}

/// Twelve points: four forcing amplitudes (up to the folds) by three
/// damping ratios.
const GRID: &str = r#"scene = "spatial_oscillator_frc.toml"
backbone_at = [0.05, 0.1]
[[grid]]
parameter = "frc.epsilon"
values = [0.002, 0.01, 0.03, 0.06]
[[grid]]
parameter = "model.zeta1"
values = [0.01, 0.02, 0.03]
"#;

fn engine(args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    let plugins = plugin_path("spatial_oscillator");
    let mut c = Command::new(engine_binary());
    c.arg("study").env("CI", "1").env(
        "SSM_PLUGIN_PATH",
        plugins.parent().expect("the plugins' folder"),
    );
    for a in args {
        c.arg(a);
    }
    c.output().expect("ssm-engine runs")
}

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn err(o: &Output) -> String {
    assert!(
        !o.status.success(),
        "succeeded: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(e.starts_with("error: ") && !e.contains("panicked"), "{e}");
    e
}

fn cell<'a>(r: &'a Record, name: &str) -> &'a Cell {
    &r.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no column {name} in {r:?}"))
        .1
}

/// The table without the wall times.
fn without_seconds(table: Vec<Record>) -> Vec<Record> {
    table
        .into_iter()
        .map(|r| r.into_iter().filter(|(n, _)| n != "seconds").collect())
        .collect()
}

fn merged(study: &Path, store: &Path) -> Vec<Record> {
    let out = ok(&engine(&[&study, &"--store", &store, &"--merge"]));
    assert!(out.contains("merged 12 points (0 failed)"), "{out}");
    read_records(&store.join("table.parquet")).expect("the merged table")
}

/// Four shards at once (as a job array starts them) then `--merge` give the
/// single run's table, every column but the wall times bit for bit (a
/// determinism check); each shard ran its three points.
#[test]
fn four_shards_then_merge_equal_the_single_run() {
    let (dir, study) = study_dir("study-shards", GRID);
    let single = dir.join("single");
    let out = ok(&engine(&[&study, &"--store", &single]));
    assert!(
        out.contains("12 points, 12 computed (0 failed), 0 already"),
        "{out}"
    );
    let sharded = dir.join("sharded");
    let shards: Vec<_> = (1..=4)
        .map(|i| {
            let plugins = plugin_path("spatial_oscillator");
            Command::new(engine_binary())
                .args([
                    "study".as_ref(),
                    study.as_os_str(),
                    "--store".as_ref(),
                    sharded.as_os_str(),
                ])
                .arg("--shard")
                .arg(format!("{i}/4"))
                .env("CI", "1")
                .env("SSM_PLUGIN_PATH", plugins.parent().unwrap())
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for (i, child) in shards.into_iter().enumerate() {
        let out = ok(&child.wait_with_output().unwrap());
        assert!(
            out.contains(&format!("shard {}/4: 3 points, 3 computed", i + 1)),
            "{out}"
        );
    }
    let (a, b) = (merged(&study, &single), merged(&study, &sharded));
    assert_eq!(a.len(), 12);
    for (k, r) in a.iter().enumerate() {
        assert_eq!(*cell(r, "point"), Cell::Int(k as i64));
        assert_eq!(*cell(r, "error"), Cell::Null, "{r:?}");
    }
    assert_eq!(without_seconds(a.clone()), without_seconds(b));
    // the largest forcing at the lightest damping folds; the smallest does not
    let folds = |k: usize| match cell(&a[k], "fold_omegas") {
        Cell::Text(t) => serde_json::from_str::<Vec<f64>>(t).unwrap().len(),
        other => panic!("{other:?}"),
    };
    assert_eq!(folds(0), 0);
    assert!(folds(9) >= 1, "{:?}", a[9]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A point's figures are those of `ssm-engine` run on the base scene with
/// the point's values written into its TOML (`[forcing] epsilon`,
/// `[model.params] zeta1`): the peak of `frc.csv`'s `x1_linf`, its
/// frequency and the folds of `summary.json`, equal bit for bit; a
/// backbone shift is NaN beyond the curve.
#[test]
fn a_point_s_figures_are_those_of_the_scene_with_its_values() {
    let text = r#"scene = "spatial_oscillator_frc.toml"
[[point]]
frc.epsilon = 0.06
model.zeta1 = 0.01
[[point]]
"frc.epsilon" = 0.03
"model.zeta1" = 0.02
"#;
    let (dir, study) = study_dir("study-point", text);
    let store = dir.join("store");
    ok(&engine(&[&study, &"--store", &store]));
    for (k, (eps, zeta)) in [(0.06, 0.01), (0.03, 0.02)].into_iter().enumerate() {
        let scene = base_scene()
            .replace("epsilon = [0.01]", &format!("epsilon = [{eps}]"))
            .replace(
                "plugin = \"spatial-oscillator\"",
                &format!("plugin = \"spatial-oscillator\"\nparams = {{ zeta1 = {zeta} }}"),
            );
        let path = dir.join(format!("scene{k}.toml"));
        std::fs::write(&path, scene).unwrap();
        let out = dir.join(format!("out{k}"));
        let plugins = plugin_path("spatial_oscillator");
        let o = Command::new(engine_binary())
            .arg(&path)
            .arg("--out")
            .arg(&out)
            .env("CI", "1")
            .env("SSM_PLUGIN_PATH", plugins.parent().unwrap())
            .output()
            .unwrap();
        ok(&o);
        let csv = std::fs::read_to_string(out.join("frc.csv")).unwrap();
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let (jx, jw) = (
            head.iter().position(|h| *h == "x1_linf").unwrap(),
            head.iter().position(|h| *h == "omega").unwrap(),
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                l.split(',')
                    .map(|c| c.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        let peak = rows
            .iter()
            .fold(&rows[0], |p, r| if r[jx] > p[jx] { r } else { p });
        let summary: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
        let mut folds: Vec<f64> = summary["frc"]["bifurcations"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|b| b["kind"] == "SN")
            .map(|b| b["omega"].as_f64().unwrap())
            .collect();
        folds.sort_by(f64::total_cmp);
        let record = &read_records(&store.join(format!("points/{k:08}.parquet"))).unwrap()[0];
        assert_eq!(*cell(record, "peak_amplitude"), Cell::Float(peak[jx]));
        assert_eq!(*cell(record, "peak_omega"), Cell::Float(peak[jw]));
        assert_eq!(
            *cell(record, "fold_omegas"),
            Cell::Text(serde_json::to_string(&folds).unwrap().replace(',', ", "))
        );
        assert_eq!(*cell(record, "param:frc.epsilon"), Cell::Float(eps));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A rerun computes only the points without a record; a merge with points
/// missing names them; a point whose model fails is a record with its typed
/// error, and the others run.
#[test]
fn reruns_compute_only_missing_points_and_failures_are_records() {
    let (dir, study) = study_dir("study-rerun", GRID);
    let store = dir.join("store");
    ok(&engine(&[&study, &"--store", &store, &"--shard", &"2/3"]));
    let e = err(&engine(&[&study, &"--store", &store, &"--merge"]));
    assert!(
        e.contains("8 of 12 points have no record yet (0, 2, 3, 5, 6, 8, 9, 11)"),
        "{e}"
    );
    std::fs::remove_file(store.join("points/00000004.parquet")).unwrap();
    // a link planted under a record's name is no record, and is replaced,
    // not written through
    let target = dir.join("not-a-record.txt");
    std::fs::write(&target, "mine").unwrap();
    std::os::unix::fs::symlink(&target, store.join("points/00000000.parquet")).unwrap();
    let out = ok(&engine(&[&study, &"--store", &store]));
    assert!(
        out.contains("12 points, 9 computed (0 failed), 3 already"),
        "{out}"
    );
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "mine");
    assert!(
        std::fs::symlink_metadata(store.join("points/00000000.parquet"))
            .unwrap()
            .is_file()
    );
    // a damping ratio the plugin refuses (a string): recorded per point
    let bad = GRID.replace("values = [0.01, 0.02, 0.03]", "values = [0.01, \"light\"]");
    let (dir2, study2) = study_dir("study-bad-point", &bad);
    let store2 = dir2.join("store");
    let out = ok(&engine(&[&study2, &"--store", &store2]));
    assert!(out.contains("8 points, 8 computed (4 failed)"), "{out}");
    let out = ok(&engine(&[&study2, &"--store", &store2, &"--merge"]));
    assert!(out.contains("merged 8 points (4 failed)"), "{out}");
    let table = read_records(&store2.join("table.parquet")).unwrap();
    for (k, r) in table.iter().enumerate() {
        if k % 2 == 1 {
            assert_eq!(
                *cell(r, "error_type"),
                Cell::Text("InputError".into()),
                "{r:?}"
            );
            assert!(
                matches!(cell(r, "error"), Cell::Text(t) if t.contains("zeta1")),
                "{r:?}"
            );
            assert_eq!(*cell(r, "peak_amplitude"), Cell::Null);
            // text and numbers in one column: a text column
            assert_eq!(*cell(r, "param:model.zeta1"), Cell::Text("light".into()));
        } else {
            assert!(
                matches!(cell(r, "peak_amplitude"), Cell::Float(x) if *x > 0.0),
                "{r:?}"
            );
        }
    }
    for d in [dir, dir2] {
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// Bad studies and stores end in typed errors before any point runs.
#[test]
fn bad_studies_and_stores_are_refused() {
    let cases: &[(&str, &str, &str)] = &[
        ("frc.epsilon", "frc.epsilonn", "unknown field `epsilonn`"),
        (
            "frc.epsilon",
            "forcing.epsilon",
            "unknown parameter 'forcing.epsilon'",
        ),
        (
            "values = [0.002, 0.01, 0.03, 0.06]",
            "values = []",
            "the range of 'frc.epsilon' is empty",
        ),
        (
            "values = [0.002, 0.01, 0.03, 0.06]",
            "values = [nan]",
            "give a finite number",
        ),
        (
            "values = [0.002, 0.01, 0.03, 0.06]",
            "values = [-1.0]",
            "frc.epsilon",
        ),
        (
            "scene = \"spatial_oscillator_frc.toml\"",
            "scene = \"nothere.toml\"",
            "nothere.toml",
        ),
        (
            "backbone_at = [0.05, 0.1]",
            "backbone_at = [inf]",
            "backbone_at",
        ),
        (
            "[[grid]]\nparameter = \"frc.epsilon\"",
            "[sample]\nn = 4\nseed = 1\nranges = {}\n[[grid]]\nparameter = \"frc.epsilon\"",
            "one way",
        ),
    ];
    for (i, (from, to, says)) in cases.iter().enumerate() {
        let text = GRID.replacen(from, to, 1);
        assert_ne!(text, GRID, "case {i}");
        let (dir, study) = study_dir(&format!("study-bad-{i}"), &text);
        let store = dir.join("store");
        let e = err(&engine(&[&study, &"--store", &store]));
        assert!(e.contains(says), "case {i}: {e}");
        assert!(!store.exists(), "case {i}: a store was made");
        let _ = std::fs::remove_dir_all(&dir);
    }
    let (dir, study) = study_dir("study-bad-store", GRID);
    for shard in ["0/4", "5/4", "x", "1/0", "1/4/2"] {
        let e = err(&engine(&[
            &study,
            &"--store",
            &dir.join("s"),
            &"--shard",
            &shard,
        ]));
        assert!(e.contains("is not a slice"), "{shard}: {e}");
    }
    // a store of another study, a file, a folder of other things
    let other = dir.join("other");
    let small = GRID.replace("values = [0.01, 0.02, 0.03]", "values = [0.5]");
    std::fs::write(dir.join("small.study.toml"), &small).unwrap();
    ok(&engine(&[
        &dir.join("small.study.toml"),
        &"--store",
        &other,
        &"--shard",
        &"9/9",
    ]));
    let e = err(&engine(&[&study, &"--store", &other]));
    assert!(e.contains("holds another study"), "{e}");
    let e = err(&engine(&[&study, &"--store", &other, &"--merge"]));
    assert!(e.contains("holds another study"), "{e}");
    let e = err(&engine(&[
        &study,
        &"--store",
        &dir.join("spatial_oscillator_frc.toml"),
    ]));
    assert!(e.contains("is not a directory"), "{e}");
    let e = err(&engine(&[&study, &"--store", &dir]));
    assert!(e.contains("is not empty and holds no study"), "{e}");
    let e = err(&engine(&[
        &study,
        &"--store",
        &dir.join("none"),
        &"--merge",
    ]));
    assert!(e.contains("holds no study"), "{e}");
    assert_eq!(
        base_scene(),
        std::fs::read_to_string(dir.join("spatial_oscillator_frc.toml")).unwrap()
    );
    // the points are costed before they are made: nine million of them under
    // a 1.5 GB address space are refused, naming the limit
    let huge = "scene = \"spatial_oscillator_frc.toml\"\n[sample]\nn = 9000000\nseed = 1\nranges = { frc.epsilon = [0.01, 0.02], model.zeta1 = [0.01, 0.02] }\n";
    std::fs::write(dir.join("huge.study.toml"), huge).unwrap();
    let o = Command::new("bash")
        .arg("-c")
        .arg("ulimit -v 1500000 && exec \"$0\" study \"$1\" --store \"$2\"")
        .arg(engine_binary())
        .arg(dir.join("huge.study.toml"))
        .arg(dir.join("huge"))
        .output()
        .unwrap();
    let e = err(&o);
    assert!(
        e.contains("9000000 points of 2 parameters") && e.contains("ulimit -v"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `zoo/studies/study.sbatch` run by bash as Slurm runs it for each task
/// of `--array=1-2` (the array's environment set by hand) computes the
/// task's shard, and the merged store is the single run's table (a
/// determinism check); without the array's environment it refuses to run.
#[test]
fn the_sbatch_script_runs_one_shard_per_array_task() {
    let small = GRID.replace("values = [0.01, 0.02, 0.03]", "values = [0.02]");
    let (dir, study) = study_dir("study-sbatch", &small);
    let script = repo_root().join("zoo/studies/study.sbatch");
    let plugins = plugin_path("spatial_oscillator");
    let store = dir.join("store");
    for task in ["1", "2"] {
        let o = Command::new("bash")
            .arg(&script)
            .arg(&study)
            .arg(&store)
            .env("SLURM_ARRAY_TASK_ID", task)
            .env("SLURM_ARRAY_TASK_COUNT", "2")
            .env("SSM_ENGINE", engine_binary())
            .env("SSM_PLUGIN_PATH", plugins.parent().unwrap())
            .env("CI", "1")
            .output()
            .unwrap();
        let out = ok(&o);
        assert!(
            out.contains(&format!("shard {task}/2: 2 points, 2 computed")),
            "{out}"
        );
    }
    let o = Command::new("bash")
        .arg(&script)
        .arg(&study)
        .arg(&store)
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("submit with sbatch --array=1-N"));
    let single = dir.join("single");
    ok(&engine(&[&study, &"--store", &single]));
    let merge = |s: &Path| {
        ok(&engine(&[&study, &"--store", &s, &"--merge"]));
        without_seconds(read_records(&s.join("table.parquet")).unwrap())
    };
    assert_eq!(merge(&store), merge(&single));
    let _ = std::fs::remove_dir_all(&dir);
}
