//! Hostile input files and output directories (issue 38, section 3): every
//! reader of a user's file goes through one input layer
//! (`ssm_model_files::input`): regular files only, a size limit, a leading
//! byte-order mark skipped, right line numbers, short escaped excerpts; and a
//! run never writes its results over one of its own inputs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use ssm_core::reduce::{read_signals, SignalsError};
use ssm_engine::output::checkpoint::{Checkpoint, CheckpointError};
use ssm_engine::scene::{SceneError, SceneFile};
use ssm_model_files::input::{InputError, EXCERPT_CHARS};
use ssm_model_files::{FileError, ModelFiles};
use ssm_tests::{engine_binary, repo_root, tmp_dir};

/// A hang guard, not a timing assertion: what a regression would block on
/// forever fails the test after this long instead.
const GUARD: Duration = Duration::from_secs(120);

/// `f()` on another thread; panics (fails the test) if it does not return
/// within [`GUARD`] (the blocked thread is left behind).
fn guarded<T: Send + 'static>(what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(GUARD)
        .unwrap_or_else(|_| panic!("{what}: no answer within {GUARD:?} (it blocks)"))
}

/// The engine with `args`, killed (and the test failed) if it runs longer
/// than [`GUARD`].
fn engine_guarded(args: &[&std::ffi::OsStr]) -> Output {
    let mut child = Command::new(engine_binary())
        .args(args)
        .env("CI", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("engine starts");
    let t0 = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if t0.elapsed() > GUARD {
            let _ = child.kill();
            let _ = child.wait();
            panic!("ssm-engine {args:?}: still running after {GUARD:?} (it blocks)");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    child.wait_with_output().expect("output")
}

fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo")
        .arg(path)
        .status()
        .expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

/// `n` samples of a decaying cosine at step 0.1 as `[data]` CSV text:
/// header `t,x`, one row per line.
fn samples(n: usize) -> String {
    let mut s = String::from("t,x\n");
    for k in 0..n {
        let t = 0.1 * k as f64;
        s.push_str(&format!("{t},{}\n", (-0.05 * t).exp() * t.cos()));
    }
    s
}

/// A scene reducing `[data]` `files` with the NAR identifier.
fn nar_scene(files: &[&Path]) -> String {
    let list: Vec<String> = files
        .iter()
        .map(|f| format!("{:?}", f.display().to_string()))
        .collect();
    format!(
        "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n[reduce.params]\nnu = 1\norder = 3\n\
         [data]\nfiles = [{}]\n[ssm]\nmaster_pairs = [1]\norder = 3\n",
        list.join(", ")
    )
}

/// A FIFO and a link to `/dev/zero` named as a `[data]` file, a scene file,
/// a model file and a checkpoint (and a FIFO as a plugin library) each end at once in an error that says
/// what the path is, in-process and through the binary (before: the `[data]`
/// reader blocked forever on the FIFO and read `/dev/zero` until memory ran
/// out).
#[test]
fn fifos_and_devices_are_refused_by_every_reader_without_blocking() {
    let dir = tmp_dir("inputs-special");
    std::fs::create_dir_all(dir.join("model")).expect("dir");
    let fifo = dir.join("pipe.csv");
    mkfifo(&fifo);
    let zero = dir.join("zero.csv");
    std::os::unix::fs::symlink("/dev/zero", &zero).expect("link");
    for (path, what) in [
        (fifo.clone(), "a FIFO"),
        (zero.clone(), "a character device"),
    ] {
        let p = path.clone();
        let e = guarded("read_signals", move || read_signals(&[p], None)).expect_err("refused");
        assert!(
            matches!(e, SignalsError::Read(InputError::NotAFile { .. })),
            "{e}"
        );
        assert!(e.to_string().contains(what), "{e}");
        let p = path.clone();
        let e = guarded("scene", move || SceneFile::load(&p)).expect_err("refused");
        assert!(
            matches!(e, SceneError::Read(InputError::NotAFile { .. })),
            "{e}"
        );
        let p = path.clone();
        let e = guarded("checkpoint", move || {
            Checkpoint::resume(&p, "s", "t").err().expect("refused")
        });
        assert!(
            matches!(e, CheckpointError::Input(InputError::NotAFile { .. })),
            "{e}"
        );
        // the mass matrix of a model folder
        let m = dir.join("model/M.mtx");
        let _ = std::fs::remove_file(&m);
        std::os::unix::fs::symlink(&path, &m).expect("link");
        let d = dir.join("model");
        let e = guarded("model folder", move || ModelFiles::read(&d, &mut |_| {}))
            .expect_err("refused");
        assert!(
            matches!(e, FileError::Input(InputError::NotAFile { .. })),
            "{e}"
        );
        assert!(e.to_string().contains(what), "{e}");
    }
    // through the binary: the reproduction of the report
    let scene = dir.join("nar.toml");
    std::fs::write(&scene, nar_scene(&[&fifo])).expect("scene");
    let out = dir.join("out");
    let o = engine_guarded(&[scene.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("is a FIFO"), "{err}");
    let o = engine_guarded(&[fifo.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("is a FIFO"), "{err}");
    assert!(!out.exists());
    // a plugin library (dlopen would block on it)
    let so = dir.join("pipe.so");
    mkfifo(&so);
    let o = engine_guarded(&["--plugin".as_ref(), so.as_os_str(), "plugins".as_ref()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("is a FIFO"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A file above its kind's limit is refused from its size, before a byte is
/// read: a sparse `[data]` file of 2 GiB (the limit is 1 GiB) and a sparse
/// scene of 17 MiB (16 MiB).
#[test]
fn files_above_their_limit_are_refused_before_reading() {
    let dir = tmp_dir("inputs-large");
    std::fs::create_dir_all(&dir).expect("dir");
    let big = dir.join("big.csv");
    std::fs::File::create(&big)
        .and_then(|f| f.set_len(2 << 30))
        .expect("sparse file");
    let e = read_signals(std::slice::from_ref(&big), None).expect_err("refused");
    assert!(
        matches!(e, SignalsError::Read(InputError::TooLarge { size, limit, .. })
            if size == 2 << 30 && limit.bytes == 1 << 30),
        "{e}"
    );
    assert!(e.to_string().contains("1073741824 bytes, 1024 MiB"), "{e}");
    let scene = dir.join("big.toml");
    std::fs::File::create(&scene)
        .and_then(|f| f.set_len(17 << 20))
        .expect("sparse file");
    let e = SceneFile::load(&scene).expect_err("refused");
    assert!(
        matches!(e, SceneError::Read(InputError::TooLarge { .. })),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A CSV saved with a UTF-8 byte-order mark reads as the same signals as
/// without (before: refused, with a message showing what looked like the
/// right header); so do a scene and a Matrix Market file.
#[test]
fn a_byte_order_mark_is_skipped() {
    let dir = tmp_dir("inputs-bom");
    std::fs::create_dir_all(dir.join("model")).expect("dir");
    let (plain, marked) = (dir.join("plain.csv"), dir.join("marked.csv"));
    std::fs::write(&plain, samples(50)).expect("write");
    std::fs::write(&marked, format!("\u{feff}{}", samples(50))).expect("write");
    let a = read_signals(&[plain], None).expect("plain");
    let b = read_signals(&[marked], None).expect("with a byte-order mark");
    assert_eq!(a.names, b.names);
    assert_eq!(a.period, b.period);
    assert_eq!(a.trajectories[0].samples, b.trajectories[0].samples);

    let scene = dir.join("s.toml");
    std::fs::write(&scene, "\u{feff}[model]\nplugin = \"duffing\"\n").expect("write");
    let s = SceneFile::load(&scene).expect("scene with a byte-order mark");
    assert_eq!(s.scene.model.expect("model").plugin.get_ref(), "duffing");

    let m = "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 2.0\n";
    std::fs::write(dir.join("model/M.mtx"), format!("\u{feff}{m}")).expect("write");
    std::fs::write(dir.join("model/K.mtx"), m).expect("write");
    let files = ModelFiles::read(&dir.join("model"), &mut |_| {}).expect("model folder");
    assert_eq!(files.mass.iter().collect::<Vec<_>>(), vec![(0, 0, 2.0)]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sample repeated at line 302 of a uniformly sampled file is reported at
/// line 302 (before: line 3, the first step compared with a mean the
/// repeat had shifted), also with blank lines before it; a gap is reported
/// at its own line.
#[test]
fn a_repeated_sample_is_reported_at_its_line() {
    let dir = tmp_dir("inputs-lines");
    std::fs::create_dir_all(&dir).expect("dir");
    let text = samples(400);
    let mut lines: Vec<&str> = text.lines().collect();
    // line 302 repeats line 301's sample
    let repeated = lines[300];
    lines.insert(301, repeated);
    let file = dir.join("repeat.csv");
    std::fs::write(&file, lines.join("\n")).expect("write");
    let line_of = |e: SignalsError| match e {
        SignalsError::NonUniform { line, .. } => line,
        other => panic!("expected a sampling error, got {other}"),
    };
    let e = read_signals(std::slice::from_ref(&file), None).expect_err("refused");
    assert_eq!(line_of(e), 302);
    // two blank lines after the header: the repeat is now at line 304
    lines.insert(1, "");
    lines.insert(1, "  ");
    std::fs::write(&file, lines.join("\n")).expect("write");
    let e = read_signals(std::slice::from_ref(&file), None).expect_err("refused");
    assert_eq!(line_of(e), 304);
    // a missing sample: the step to line 101 is twice the others
    let mut gap: Vec<&str> = text.lines().collect();
    gap.remove(100);
    std::fs::write(&file, gap.join("\n")).expect("write");
    let e = read_signals(std::slice::from_ref(&file), None).expect_err("refused");
    assert_eq!(line_of(e), 101);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A system file named as data is refused with at most a short, escaped
/// excerpt of its first line: no raw NUL or escape byte reaches the
/// terminal (before: the whole line, NUL bytes and all).
#[test]
fn messages_quote_short_escaped_excerpts() {
    let dir = tmp_dir("inputs-excerpt");
    std::fs::create_dir_all(dir.join("model")).expect("dir");
    let hostile = format!("root:x:0\0\x1b[2J{}\n1,2\n", "y".repeat(500));
    let data = dir.join("passwd");
    std::fs::write(&data, &hostile).expect("write");
    let e = read_signals(std::slice::from_ref(&data), None).expect_err("refused");
    let msg = e.to_string();
    assert!(matches!(e, SignalsError::Header { .. }), "{msg}");
    assert!(!msg.contains(['\0', '\x1b']), "{msg:?}");
    assert!(msg.contains("root:x:0\\u{0}\\u{1b}[2J"), "{msg}");
    let quoted = msg.len() - data.display().to_string().len();
    assert!(quoted < 200 + EXCERPT_CHARS, "{msg}");
    // a value that is not a number, and a Matrix Market line
    let bad = format!("t,x\n0,1\n0.1,{}\0\n", "z".repeat(300));
    std::fs::write(&data, bad).expect("write");
    let msg = read_signals(std::slice::from_ref(&data), None)
        .expect_err("refused")
        .to_string();
    assert!(
        !msg.contains('\0') && msg.contains("line 3") && msg.len() < 400,
        "{msg}"
    );
    std::fs::write(
        dir.join("model/M.mtx"),
        format!(
            "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 {}\0\n",
            "9".repeat(400)
        ),
    )
    .expect("write");
    std::fs::write(
        dir.join("model/K.mtx"),
        "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1\n",
    )
    .expect("write");
    let msg = ModelFiles::read(&dir.join("model"), &mut |_| {})
        .expect_err("refused")
        .to_string();
    assert!(
        !msg.contains('\0') && msg.contains("line 3") && msg.len() < 400,
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The engine at `scene` into `out`; stderr and whether it succeeded.
fn run_into(scene: &Path, out: &Path) -> (bool, String) {
    let o = engine_guarded(&[scene.as_os_str(), "--out".as_ref(), out.as_os_str()]);
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The files of `dir`, sorted, with their contents.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut all: Vec<_> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| {
            let p = e.expect("entry").path();
            let c = std::fs::read(&p).unwrap_or_default();
            (p, c)
        })
        .collect();
    all.sort();
    all
}

/// A matrix-model scene whose model folder `mm` was written by `export`
/// (so it carries the result-set marker), run with `--out mm`, and the NAR
/// scene run with `--out` at the `[simulate]` result set whose
/// `simulation_*.csv` it reads, are refused before anything is computed,
/// with an error naming the input, and leave the folders as they were
/// (before: `M.mtx`, `K.mtx`, the CSV files were deleted). So is an
/// `--out` that holds the scene file, and an export into the folder it
/// reads.
#[test]
fn an_output_directory_holding_an_input_is_refused() {
    let dir = tmp_dir("inputs-out");
    std::fs::create_dir_all(&dir).expect("dir");
    let mm = dir.join("mm");
    let o = Command::new(engine_binary())
        .arg("export")
        .arg(repo_root().join("zoo/spatial_oscillator_cubic.toml"))
        .arg(&mm)
        .output()
        .expect("export");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(mm.join(".ssm-engine-output").exists() && mm.join("M.mtx").exists());
    let scene = dir.join("mm.toml");
    std::fs::write(
        &scene,
        "[model]\nplugin = \"matrix-model\"\n[model.params]\ndir = \"mm\"\n[ssm]\nmaster_pairs = [1]\norder = 3\n",
    )
    .expect("scene");
    let before = snapshot(&mm);
    let (ok, err) = run_into(&scene, &mm);
    assert!(
        !ok && err.contains("an input of this run") && err.contains("mm"),
        "{err}"
    );
    assert_eq!(snapshot(&mm), before, "the model folder changed");
    // the same folder by another spelling
    let (ok, err) = run_into(&scene, &dir.join("mm/../mm/."));
    assert!(!ok && err.contains("an input of this run"), "{err}");
    assert_eq!(snapshot(&mm), before);
    // an output directory holding the scene (and the model folder)
    let (ok, err) = run_into(&scene, &dir);
    assert!(!ok && err.contains("an input of this run"), "{err}");
    // export into the folder its scene reads
    let o = Command::new(engine_binary())
        .arg("export")
        .arg(&scene)
        .arg(&mm)
        .output()
        .expect("export");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("an input of this run"),
        "{err}"
    );
    assert_eq!(snapshot(&mm), before);

    // a [simulate] result set read as [data]
    let data = dir.join("data");
    let mut set = ssm_engine::output::OutputSet::default();
    set.add("summary.json", "{}");
    set.add("simulation_1.csv", samples(300));
    set.write(&data).expect("data set");
    let nar = dir.join("nar.toml");
    std::fs::write(&nar, nar_scene(&[&data.join("simulation_1.csv")])).expect("scene");
    let before = snapshot(&data);
    let (ok, err) = run_into(&nar, &data);
    assert!(!ok && err.contains("simulation_1.csv"), "{err}");
    assert!(err.contains("an input of this run"), "{err}");
    assert_eq!(snapshot(&data), before, "the data folder changed");
    let _ = std::fs::remove_dir_all(&dir);
}
