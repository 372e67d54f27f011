//! Stopped and resumed full-system references: the journal of orbits a
//! stopped run keeps, and the checkpoint of its continuation runs from which
//! `--resume` goes on to what the uninterrupted run computes.

use std::path::{Path, PathBuf};

use ssm_core::fom::periodic::{
    reference_frc_resumable, ReferenceBranch, ReferenceError, ReferenceSettings, Runs, Seed,
};
use ssm_core::model::system::{OutputMap, System};
use ssm_engine::output::checkpoint::{Checkpoint, CheckpointError};
use ssm_model_files::input::InputError;
use ssm_tests::{duffing_orbits, forced_duffing, parametric_pump};

/// The branch with its cost counters zeroed (a resumed run factors less).
fn results(mut b: ReferenceBranch) -> ReferenceBranch {
    b.factorizations = 0;
    b.doubled = b.doubled.into_iter().map(results).collect();
    b.seeded = b.seeded.into_iter().map(results).collect();
    b
}

fn output(name: &str, state: usize) -> OutputMap {
    OutputMap {
        name: name.into(),
        weights: vec![(state, 1.0)],
    }
}

/// Where the printouts of `a` and `b` first differ, with some context.
fn first_difference(a: &ReferenceBranch, b: &ReferenceBranch) -> String {
    let (a, b) = (format!("{a:?}"), format!("{b:?}"));
    let at = a
        .bytes()
        .zip(b.bytes())
        .position(|(x, y)| x != y)
        .unwrap_or(a.len().min(b.len()));
    let from = at.saturating_sub(300);
    format!(
        "...{} | {} against {}",
        &a[from..at],
        &a[at..(at + 80).min(a.len())],
        &b[at..(at + 80).min(b.len())]
    )
}

/// The 1:2 parametric pump through both period doublings, with the branch
/// of period 2T between them: two continuation runs.
fn pump() -> (System, ReferenceSettings) {
    let sys = parametric_pump(0.01, 0.01, 1.0, 0.5, 0.005);
    let settings = ssm_tests::parametric_pump_reference(vec![2.0]);
    (sys, settings)
}

/// The Duffing oscillator from inside its bistable band, with a seed on the
/// upper orbit: the branch from rest, and the seeded branch in two halves
/// (three runs, the second half's start not shown again).
fn duffing_seeded() -> (System, ReferenceSettings) {
    let (zeta, gamma, eps) = (0.005, 1.0, 0.002);
    let sys = forced_duffing(zeta, gamma, &[(1.0, 1.0)]);
    let band: Vec<f64> = (0..400)
        .map(|k| 1.0 + 0.03 * k as f64 / 400.0)
        .filter(|w| duffing_orbits(zeta, gamma, eps, *w).len() == 3)
        .collect();
    let (lo, w) = (
        0.5 * (band[0] + band[band.len() - 1]),
        0.25 * band[0] + 0.75 * band[band.len() - 1],
    );
    let (a, b) = duffing_orbits(zeta, gamma, eps, w)[2];
    let states = (0..16)
        .map(|s| {
            let (sn, cs) = (2.0 * std::f64::consts::PI * s as f64 / 16.0).sin_cos();
            vec![a * cs + b * sn, w * (b * cs - a * sn)]
        })
        .collect();
    let settings = ReferenceSettings {
        epsilon: eps,
        omega_range: (lo, 1.1),
        harmonics: 1,
        step: 0.5,
        tol: 1e-11,
        max_steps: 2000,
        outputs: vec![output("x", 0)],
        points_at: Vec::new(),
        seeds: vec![Seed {
            omega: w,
            period_multiple: 1,
            states,
            origin: "closed form".into(),
        }],
        period_doubling: false,
        stability: true,
    };
    (sys, settings)
}

/// The reference with its checkpoint `ck`; the number of orbits shown.
fn run(
    sys: &System,
    settings: &ReferenceSettings,
    ck: &Checkpoint,
) -> Result<(ReferenceBranch, usize), ReferenceError> {
    let mut shown = 0;
    let mut runs = Runs::new(ck, |_| {
        shown += 1;
        true
    });
    let b = reference_frc_resumable(sys, settings, &mut runs)?;
    drop(runs);
    Ok((results(b), shown))
}

/// Reference: the uninterrupted computation. Its checkpoint is cut as a
/// stop would leave it (whole records up to a point, then a line cut short)
/// at the start, inside the first run, at the change of runs and inside the
/// last run, and resumed from: every resumed computation gives the same
/// branches, orbits, events and stops (exactly: the kept numbers read back
/// to the same bits, and the continuation goes on from the same step size
/// and step count), shows every orbit once, and completes the checkpoint to
/// the uninterrupted one's, byte for byte. Cases: the parametric pump (main
/// branch, period doublings, the branch of period 2T) and a seeded Duffing
/// branch traced in two halves.
#[test]
fn a_resumed_reference_equals_the_uninterrupted_one() {
    for (case, (sys, settings)) in [("pump", pump()), ("duffing", duffing_seeded())] {
        let dir = ssm_tests::tmp_dir(&format!("resume-{case}"));
        std::fs::create_dir_all(&dir).expect("dir");
        let out = dir.join("out");
        let whole_ck = Checkpoint::fresh(&out, case, "scene text");
        let (whole, shown) = run(&sys, &settings, &whole_ck).expect("reference");
        let path = whole_ck.written().expect("checkpoint written");
        assert_eq!(path, Checkpoint::default_path(&out));
        drop(whole_ck);
        let text = std::fs::read_to_string(&path).expect("checkpoint");
        let lines: Vec<&str> = text.split_inclusive('\n').collect();
        let runs = lines.iter().filter(|l| l.starts_with("{\"Stop\"")).count();
        assert!(runs >= 2, "{case}: {runs} runs");
        // the first record of the second run
        let second = lines
            .iter()
            .position(|l| l.starts_with("{\"Step\":{\"run\":2,"))
            .expect("a second run");
        let n = lines.len();
        for cut in [
            1,
            2,
            second / 2,
            second,
            second + 1,
            (second + n) / 2,
            n - 1,
        ] {
            let head: String = lines[..cut].concat();
            let torn = &lines[cut][..lines[cut].len() / 2];
            std::fs::write(&path, head + torn).expect("cut");
            let ck = Checkpoint::resume(&path, case, "scene text").expect("resumes");
            let (resumed, seen) = run(&sys, &settings, &ck).expect("resumed reference");
            drop(ck);
            assert!(
                resumed == whole,
                "{case}: cut at line {cut}: {}",
                first_difference(&resumed, &whole)
            );
            assert_eq!(seen, shown, "{case}: cut at line {cut}");
            let completed = std::fs::read_to_string(&path).expect("checkpoint");
            assert!(
                completed == text,
                "{case}: the checkpoint completed from line {cut} differs"
            );
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// A checkpoint that is not this computation's is refused with an error
/// naming the file and what is wrong, and nothing is mixed in: none at the
/// path, one written for an edited scene or another scene, a damaged line
/// (not the last), records out of order, a link, one being resumed by
/// another run (locked), and one of another model under the same scene (its
/// first run's start differs). An empty file (stopped before its header)
/// resumes as nothing kept.
#[test]
fn checkpoints_from_elsewhere_are_refused() {
    let dir = ssm_tests::tmp_dir("resume-refused");
    std::fs::create_dir_all(&dir).expect("dir");
    let out = dir.join("out");
    let path = Checkpoint::default_path(&out);
    let refused = |p: &Path, name: &str, text: &str| {
        Checkpoint::resume(p, name, text).err().expect("refused")
    };
    let e = refused(&path, "pump", "text");
    assert!(matches!(e, CheckpointError::Missing { .. }), "{e}");
    assert!(e.to_string().contains("without --resume"), "{e}");

    let (sys, settings) = pump();
    let ck = Checkpoint::fresh(&out, "pump", "text");
    run(&sys, &settings, &ck).expect("reference");
    drop(ck);
    let text = std::fs::read_to_string(&path).expect("checkpoint");
    let e = refused(&path, "pump", "text edited");
    assert!(
        matches!(e, CheckpointError::Foreign { ref what, .. } if what.contains("edited")),
        "{e}"
    );
    let e = refused(&path, "other", "text");
    assert!(
        matches!(e, CheckpointError::Foreign { ref what, .. } if what.contains("'pump'")),
        "{e}"
    );

    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    let write = |p: &Path, parts: &[&str]| std::fs::write(p, parts.concat()).expect("write");
    let mut damaged = lines.clone();
    damaged[3] = "{\"Step\": garbage}\n";
    write(&path, &damaged);
    let e = refused(&path, "pump", "text");
    assert!(matches!(e, CheckpointError::Damaged { line: 4, .. }), "{e}");
    // the second run's first record right after the header
    let second = lines
        .iter()
        .find(|l| l.starts_with("{\"Step\":{\"run\":2,"))
        .expect("second run");
    write(&path, &[lines[0], second]);
    let e = refused(&path, "pump", "text");
    assert!(matches!(e, CheckpointError::Damaged { line: 2, .. }), "{e}");

    // a readable step whose tangent is shorter than its point
    let mut short = lines.clone();
    let cut = lines[3].replacen("\"tangent\":[", "\"tangent\":[0.5,", 1);
    short[3] = &cut;
    write(&path, &short);
    let e = refused(&path, "pump", "text");
    assert!(matches!(e, CheckpointError::Damaged { line: 4, .. }), "{e}");

    write(&path, &lines);
    let link: PathBuf = dir.join("link.jsonl");
    std::os::unix::fs::symlink(&path, &link).expect("link");
    let e = refused(&link, "pump", "text");
    assert!(
        matches!(e, CheckpointError::Input(InputError::NotAFile { .. })),
        "{e}"
    );

    let holder = Checkpoint::resume(&path, "pump", "text").expect("first resume");
    let e = refused(&path, "pump", "text");
    assert!(matches!(e, CheckpointError::Busy { .. }), "{e}");
    drop(holder);

    // the pump's checkpoint offered to the Duffing oscillator
    let (duffing, duffing_settings) = duffing_seeded();
    let ck = Checkpoint::resume(&path, "pump", "text").expect("reads");
    let e = run(&duffing, &duffing_settings, &ck).expect_err("another model");
    assert!(
        matches!(e, ReferenceError::Checkpoint { run: 1, .. }),
        "{e}"
    );
    drop(ck);

    std::fs::write(&path, "").expect("empty");
    let ck = Checkpoint::resume(&path, "pump", "text").expect("empty resumes");
    let (b, _) = run(&sys, &settings, &ck).expect("computed afresh");
    drop(ck);
    assert!(b.orbits.len() > 10);
    assert_eq!(std::fs::read_to_string(&path).expect("rewritten"), text);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Restored records are checked against what is cheap to recompute, and
/// each edit is refused with the line it is on (before: each resumed and
/// exited 0): an unstable count of 3 where the stored multipliers have none
/// outside the unit circle (before: every restored orbit unstable); a fold
/// recorded as an event kind no test function has (`Test(7)`, before: two
/// branch points) or as a test function that does not change on its step.
/// A checkpoint with a second (hard) link is refused like a symbolic one,
/// and neither name's contents change (before: truncated and appended
/// through the link). A record kind the reader does not know is quoted
/// with its control characters escaped.
#[test]
fn restored_records_are_checked_and_hard_links_refused() {
    let dir = ssm_tests::tmp_dir("resume-checked");
    std::fs::create_dir_all(&dir).expect("dir");
    let out = dir.join("out");
    let path = Checkpoint::default_path(&out);
    let (sys, settings) = duffing_seeded();
    let ck = Checkpoint::fresh(&out, "duffing", "text");
    run(&sys, &settings, &ck).expect("reference");
    drop(ck);
    let text = std::fs::read_to_string(&path).expect("checkpoint");
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    let refused_at = |edited: &[String]| {
        std::fs::write(&path, edited.concat()).expect("write");
        match Checkpoint::resume(&path, "duffing", "text") {
            Err(CheckpointError::Damaged { line, cause, .. }) => (line, cause),
            Err(e) => panic!("expected a damaged line, got {e}"),
            Ok(_) => panic!("the edited checkpoint resumed"),
        }
    };
    let owned: Vec<String> = lines.iter().map(|l| (*l).to_owned()).collect();
    let stable = lines
        .iter()
        .position(|l| l.contains("\"unstable\":0"))
        .expect("a stable orbit");
    let mut edited = owned.clone();
    edited[stable] = edited[stable].replacen("\"unstable\":0", "\"unstable\":3", 1);
    let (line, cause) = refused_at(&edited);
    assert_eq!(line, stable + 1, "{cause}");
    assert!(cause.contains("3 unstable multipliers stated"), "{cause}");

    let fold = lines
        .iter()
        .position(|l| l.contains("\"kind\":\"Fold\""))
        .expect("a fold");
    for kind in ["{\"Test\":7}", "{\"Test\":1}"] {
        let mut edited = owned.clone();
        edited[fold] = edited[fold].replacen("\"Fold\"", kind, 1);
        let (line, cause) = refused_at(&edited);
        assert_eq!(line, fold + 1, "{kind}: {cause}");
        assert!(
            cause.contains("not a change on this step"),
            "{kind}: {cause}"
        );
    }

    // a record kind the reader does not know, quoted escaped
    let mut edited = owned.clone();
    edited[2] = "{\"Hopf\\u0000\\u001b[2J\":1}\n".to_owned();
    let (line, cause) = refused_at(&edited);
    assert_eq!(line, 3, "{cause}");
    assert!(
        !cause.contains(['\0', '\x1b']) && cause.contains("Hopf\\u{0}\\u{1b}[2J"),
        "{cause:?}"
    );

    std::fs::write(&path, &text).expect("restore");
    let other = dir.join("other.jsonl");
    std::fs::hard_link(&path, &other).expect("hard link");
    for p in [&path, &other] {
        let e = Checkpoint::resume(p, "duffing", "text")
            .err()
            .expect("refused");
        assert!(
            matches!(
                e,
                CheckpointError::Input(InputError::HardLinked { links: 2, .. })
            ),
            "{e}"
        );
    }
    assert_eq!(std::fs::read_to_string(&other).expect("other"), text);
    std::fs::remove_file(&other).expect("unlink");
    Checkpoint::resume(&path, "duffing", "text").expect("one name again");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs the engine on `scene` into `out` with `extra` arguments.
fn engine(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    std::process::Command::new(ssm_tests::engine_binary())
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .expect("engine runs")
}

/// The `reference` object of a summary without its costs (seconds,
/// factorizations), which a resumed run does not share.
fn reference_results(out: &Path) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.remove("seconds");
                m.remove("factorizations");
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let mut r = v["reference"].take();
    strip(&mut r);
    r
}

/// A run stopped (killed) in the middle of its full-system reference keeps
/// the orbits it computed and its continuation, and `--resume` goes on to
/// what an uninterrupted run writes.
///
/// - The journal beside the output directory has the header of
///   `reference_frc.csv` and one complete row per accepted orbit (finite,
///   inside the scene's range and amplitudes); the output directory is not
///   created; the checkpoint is there.
/// - A second, fresh run into the same place leaves the first's journal and
///   checkpoint alone (its own go under its process id) and removes its own
///   when its outputs are written.
/// - `--resume` restores the stopped run's continuation runs and writes
///   `reference_frc.csv` and `reference_amplitude.csv` identical to the fresh
///   run's, byte for byte, and the same reference in `summary.json` but for
///   its costs; then no journal or checkpoint is left, and a second
///   `--resume` is an error that says there is nothing to resume.
#[test]
fn a_stopped_reference_keeps_its_orbits_and_resumes() {
    let out = ssm_tests::tmp_dir("stopped-reference");
    let scene = ssm_tests::repo_root().join("zoo/spatial_oscillator_cubic_reference.toml");
    let mut child = std::process::Command::new(ssm_tests::engine_binary())
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("engine starts");
    let journal = out.with_file_name(format!(
        "{}.reference-partial.csv",
        out.file_name().expect("name").to_string_lossy()
    ));
    let checkpoint = Checkpoint::default_path(&out);
    let rows = |p: &Path| {
        std::fs::read_to_string(p)
            .map(|t| {
                t.lines()
                    .filter(|l| l.ends_with(|c: char| c.is_ascii_digit()))
                    .count()
            })
            .unwrap_or(0)
    };
    let t = std::time::Instant::now();
    while rows(&journal) < 60 && t.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().expect("kill");
    let _ = child.wait();
    let text = std::fs::read_to_string(&journal).expect("journal kept");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("omega,epsilon,stable,branch,period_multiple,x1_linf,max_multiplier,tail")
    );
    let mut complete = 0;
    for l in lines {
        let v: Vec<&str> = l.split(',').collect();
        if v.len() < 8 {
            continue; // the row being written at the kill
        }
        let (w, e, a): (f64, f64, f64) = (
            v[0].parse().expect("omega"),
            v[1].parse().expect("epsilon"),
            v[5].parse().expect("amplitude"),
        );
        assert!(w.is_finite() && a.is_finite() && a >= 0.0, "{l}");
        assert!(
            (1.79..=2.21).contains(&w) && [0.01, 0.02, 0.03].contains(&e) || w == 1.97,
            "{l}"
        );
        complete += 1;
    }
    assert!(complete >= 60, "{complete} rows");
    assert!(
        !out.join("summary.json").exists(),
        "no outputs of the stopped run"
    );
    let kept = std::fs::read_to_string(&checkpoint).expect("checkpoint kept");
    assert!(kept.lines().count() > 10, "steps kept");

    // a fresh run: the stopped run's files stay, its own go
    let o = engine(&scene, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        ssm_tests::files_beside(&out, "reference-partial"),
        vec![journal.clone()]
    );
    assert_eq!(std::fs::read_to_string(&journal).expect("journal"), text);
    assert_eq!(
        ssm_tests::files_beside(&out, "reference-checkpoint"),
        vec![checkpoint.clone()]
    );
    assert!(std::fs::read_to_string(&checkpoint).expect("checkpoint") == kept);
    let read = |name: &str| std::fs::read_to_string(out.join(name)).expect(name);
    let (frc, amplitude) = (read("reference_frc.csv"), read("reference_amplitude.csv"));
    let summary = reference_results(&out);

    // the stopped run resumed
    let o = engine(&scene, &out, &["--resume"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("restored from"), "{err}");
    assert!(
        read("reference_frc.csv") == frc,
        "reference_frc.csv differs"
    );
    assert!(read("reference_amplitude.csv") == amplitude);
    assert_eq!(reference_results(&out), summary);
    for kind in ["reference-partial", "reference-checkpoint"] {
        assert_eq!(ssm_tests::files_beside(&out, kind), Vec::<PathBuf>::new());
    }
    let o = engine(&scene, &out, &["--resume"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no checkpoint to resume"), "{err}");
    let _ = std::fs::remove_dir_all(&out);
}

/// Issue 38: a resumed run that fails again (here its outputs cannot be
/// written: the output directory is a non-empty directory that is not a
/// result set) wrote its journal under its process id beside the stopped
/// run's, one more `.reference-partial.<pid>.csv` per attempt. Its journal
/// replays the stopped run's orbits before its own, so it now takes the
/// default name: after a failed run and two failed resumes there is one
/// journal, with the fresh run's rows (the reference is the same), and one
/// checkpoint.
#[test]
fn failed_resumes_do_not_pile_up_journals() {
    let dir = ssm_tests::tmp_dir("resume-pile");
    std::fs::create_dir_all(&dir).expect("scratch");
    let scene = dir.join("duffing.toml");
    std::fs::write(
        &scene,
        "[model]\nplugin = \"duffing\"\n[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs]\n\
         coordinates = [\"x\"]\n[reference]\nepsilon = [0.01]\nomega_range = [0.8, 1.2]\nharmonics = 3\n",
    )
    .expect("scene");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).expect("out");
    std::fs::write(out.join("keep.txt"), "a user's file").expect("user file");
    let o = engine(&scene, &out, &[]);
    assert!(
        !o.status.success(),
        "the outputs cannot replace a user's directory"
    );
    let journals = ssm_tests::files_beside(&out, "reference-partial");
    assert_eq!(journals.len(), 1, "{journals:?}");
    let first = std::fs::read_to_string(&journals[0]).expect("journal");
    assert!(first.lines().count() > 10, "{first}");
    for _ in 0..2 {
        let o = engine(&scene, &out, &["--resume"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{err}");
        assert!(err.contains("restored from"), "{err}");
        assert_eq!(ssm_tests::files_beside(&out, "reference-partial"), journals);
        assert_eq!(
            ssm_tests::files_beside(&out, "reference-checkpoint").len(),
            1
        );
        let text = std::fs::read_to_string(&journals[0]).expect("journal");
        assert_eq!(text, first);
    }
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).expect("kept"),
        "a user's file"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
