//! The workspace's build stays lean: what `.ci/run` and the README's test
//! command rely on to compile each crate once.
//!
//! - `cargo build --release --workspace --exclude ssm-python` and `cargo test
//!   --release --workspace --exclude ssm-python` (the README's test command)
//!   resolve one feature set for every crate both build, so the test step
//!   reuses the build's faer, serde and engine (a feature that only a
//!   dev-dependency turns on gives a second copy of everything above it).
//! - The Python wheel's build (maturin builds `ssm-python` alone, with pyo3
//!   configured for an extension module, which is why the cargo steps leave
//!   it out) resolves the workspace build's features for every crate it
//!   shares with it, so `pip install ./python` reuses that build.
//! - A crate or binary that declares `test = false` has no unit tests to lose.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use ssm_tests::repo_root;

/// `package version -> features` as `cargo tree` resolves them for the
/// packages `selected` (`--workspace`, or `-p NAME`) and the edges given
/// (`normal,build` is what `cargo build` compiles; adding `dev` is what
/// `cargo test` compiles).
fn resolved_features(selected: &[&str], edges: &str) -> BTreeMap<String, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(repo_root())
        .arg("tree")
        .args(selected)
        .args(["--offline", "--prefix", "none"])
        .args(["-e", edges, "-f", "{p}|{f}"])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree -e {edges} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    let mut map = BTreeMap::new();
    for line in text.lines() {
        let line = line.trim_end_matches(" (*)");
        let Some((package, features)) = line.split_once('|') else {
            continue;
        };
        // one name and version; a path suffix or "(proc-macro)" kept apart
        let key = package
            .split_whitespace()
            .take(2)
            .collect::<Vec<_>>()
            .join(" ");
        let kind = if package.contains("(proc-macro)") {
            " (host)"
        } else {
            ""
        };
        map.insert(format!("{key}{kind}"), features.trim().to_owned());
    }
    map
}

/// The packages of `other` (named `name`) whose features differ from the
/// workspace build's `build`, as `package: build [..], name [..]`.
fn drift(
    build: &BTreeMap<String, String>,
    other: &BTreeMap<String, String>,
    name: &str,
) -> Vec<String> {
    assert!(
        other.len() > 50,
        "cargo tree listed {} packages for the {name}",
        other.len()
    );
    other
        .iter()
        .filter_map(|(package, features)| {
            let built = build.get(package)?;
            (built != features).then(|| format!("{package}: build [{built}], {name} [{features}]"))
        })
        .collect()
}

/// What the README's test command builds and tests with cargo.
const BUILT: &[&str] = &["--workspace", "--exclude", "ssm-python"];

#[test]
fn build_and_test_resolve_one_feature_set() {
    let build = resolved_features(BUILT, "normal,build");
    let test = resolved_features(BUILT, "normal,build,dev");
    let drift = drift(&build, &test, "test");
    assert!(
        drift.is_empty(),
        "dev-dependencies turn on features the build lacks, so `cargo test` \
         compiles these (and everything above them) a second time; ask for the \
         features in tests/Cargo.toml [dependencies]:\n{}",
        drift.join("\n")
    );
}

#[test]
fn the_wheel_resolves_the_build_feature_set() {
    let build = resolved_features(BUILT, "normal,build");
    let wheel = resolved_features(&["-p", "ssm-python"], "normal,build");
    let drift = drift(&build, &wheel, "wheel");
    assert!(
        drift.is_empty(),
        "the wheel's build (ssm-python alone) resolves other features than the \
         workspace's build, so `pip install ./python` compiles these (and \
         everything above them) a second time; ask for the features in \
         python/Cargo.toml [dependencies]:\n{}",
        drift.join("\n")
    );
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a source directory") {
        let path = entry.expect("an entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn holds_tests(file: &Path) -> bool {
    let text = std::fs::read_to_string(file).expect("a source file");
    text.contains("#[test]") || text.contains("#[cfg(test)]")
}

#[test]
fn crates_without_a_test_harness_hold_no_tests() {
    let root = repo_root();
    let workspace: toml::Table = std::fs::read_to_string(root.join("Cargo.toml"))
        .expect("Cargo.toml")
        .parse()
        .expect("the workspace manifest");
    let members = workspace["workspace"]["members"]
        .as_array()
        .expect("members");
    let mut checked = 0;
    for member in members {
        let dir = root.join(member.as_str().expect("a path"));
        let manifest: toml::Table = std::fs::read_to_string(dir.join("Cargo.toml"))
            .expect("a member manifest")
            .parse()
            .expect("a member manifest parses");
        if let Some(lib) = manifest.get("lib") {
            if lib.get("test").and_then(|t| t.as_bool()) == Some(false) {
                let path = lib
                    .get("path")
                    .and_then(|p| p.as_str())
                    .unwrap_or("src/lib.rs");
                let src = dir.join(path);
                let mut files = Vec::new();
                rust_files(src.parent().expect("a source folder"), &mut files);
                for file in files {
                    assert!(
                        !holds_tests(&file),
                        "{} has tests, but its crate says `test = false`: they never run",
                        file.display()
                    );
                }
                checked += 1;
            }
        }
        for bin in manifest
            .get("bin")
            .and_then(|b| b.as_array())
            .into_iter()
            .flatten()
        {
            if bin.get("test").and_then(|t| t.as_bool()) == Some(false) {
                let path = bin
                    .get("path")
                    .and_then(|p| p.as_str())
                    .expect("a bin path");
                let file = dir.join(path);
                assert!(
                    !holds_tests(&file),
                    "{} has tests, but its binary says `test = false`: they never run",
                    file.display()
                );
                checked += 1;
            }
        }
    }
    assert!(
        checked >= 13,
        "only {checked} targets without a test harness were checked"
    );
}
