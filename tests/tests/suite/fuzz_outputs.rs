//! The output directory under hostile conditions: a full disk, an
//! unwritable parent, an output path that is a link. Each ends in a typed
//! error naming the output, and an earlier result set stays whole.

use std::path::{Path, PathBuf};

/// The engine binary on `scene` into `out`, with a shell prefix (a `ulimit`).
fn engine_with(prefix: &str, scene: &Path, out: &Path) -> std::process::Output {
    std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("{prefix} exec \"$0\" \"$1\" --out \"$2\""))
        .arg(ssm_tests::engine_binary())
        .arg(scene)
        .arg(out)
        .env("CI", "1")
        .output()
        .expect("sh runs")
}

/// The zoo's cubic oscillator with its report switched off (small outputs).
fn small_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[model]\nplugin = \"duffing\"\n[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs]\ncoordinates = [\"x\"]\n\
         [outputs.backbone]\nrho_max = 0.2\npoints = 2001\norders = [3]\n",
    )
    .expect("scene");
    scene
}

/// A full disk (the file-size limit of `ulimit -f`: writes fail with
/// `EFBIG`) ends in a typed error naming the output, not a signal, and
/// leaves the earlier result set whole and no private directory behind.
#[test]
fn a_full_disk_is_a_typed_error_that_keeps_the_old_results() {
    let dir = ssm_tests::tmp_dir("full-disk");
    std::fs::create_dir_all(&dir).expect("dir");
    let scene = small_scene(&dir);
    let out = dir.join("out");
    let first = engine_with("", &scene, &out);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let before = std::fs::read(out.join("summary.json")).expect("summary");
    // 8 blocks of 512 bytes: the summary fits, the backbone table does not
    let o = engine_with("ulimit -f 8;", &scene, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        o.status.code(),
        Some(1),
        "not a typed error: {:?}\n{err}",
        o.status
    );
    assert!(err.contains("out"), "{err}");
    assert_eq!(
        std::fs::read(out.join("summary.json")).expect("summary"),
        before
    );
    let left: Vec<_> = std::fs::read_dir(&dir)
        .expect("dir")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n != "out" && n != "scene.toml")
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// An output directory whose parent cannot be written ends in a typed error
/// naming it (root may write anywhere, so the parent is a file's path).
#[test]
fn an_unwritable_output_parent_is_a_typed_error() {
    let dir = ssm_tests::tmp_dir("unwritable");
    std::fs::create_dir_all(&dir).expect("dir");
    let scene = small_scene(&dir);
    std::fs::write(dir.join("file"), "not a directory").expect("file");
    let o = engine_with("", &scene, &dir.join("file").join("out"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{:?}\n{err}", o.status);
    assert!(err.contains("file"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("file")).expect("file"),
        "not a directory"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--out` given as a link to a directory, or as a link to a file, is never
/// written through: a typed error, and what the link points at is unchanged.
#[test]
fn an_output_path_that_is_a_link_is_not_written_through() {
    let dir = ssm_tests::tmp_dir("out-link");
    std::fs::create_dir_all(dir.join("target")).expect("dir");
    std::fs::write(dir.join("target/keep.txt"), "mine").expect("file");
    std::fs::write(dir.join("victim"), "mine").expect("file");
    let scene = small_scene(&dir);
    for (link, to) in [("link-dir", "target"), ("link-file", "victim")] {
        std::os::unix::fs::symlink(dir.join(to), dir.join(link)).expect("link");
        let o = engine_with("", &scene, &dir.join(link));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_ne!(o.status.code(), Some(0), "{link}: written through the link");
        assert!(
            o.status.code().is_some(),
            "{link}: killed by a signal\n{err}"
        );
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("target/keep.txt")).expect("kept"),
        "mine"
    );
    assert_eq!(
        std::fs::read_dir(dir.join("target")).expect("dir").count(),
        1
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("victim")).expect("kept"),
        "mine"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
