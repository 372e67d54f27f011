//! The engine's layers, checked on its sources: below the plan layer
//! (`ssm_engine::plan`) nothing reads the scene's types, TOML or its spans.
//! The numerics take the span-free specs of `ssm_engine::spec`.

use std::path::{Path, PathBuf};

use ssm_tests::repo_root;

/// Folders and files of the engine that make up the core and the numerics.
const CORE: [&str; 11] = [
    "rom",
    "ssm",
    "fom",
    "spectrum",
    "continuation",
    "compare",
    "model",
    "reduce",
    "poly.rs",
    "chebyshev.rs",
    "spec.rs",
];

/// Core files that still build models from the scene (the model source and
/// the reducer front end); each leaves this list when it moves to the plan
/// layer, and the test fails if a listed file no longer needs to be here.
const NOT_YET: [&str; 3] = ["model/source.rs", "reduce/engine.rs", "reduce/scene.rs"];

fn rust_files(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        for entry in std::fs::read_dir(path).expect("a source folder") {
            rust_files(&entry.expect("an entry").path(), out);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        out.push(path.to_owned());
    }
}

/// The lines of `text` (comments left out) that name the scene or TOML.
fn scene_uses(text: &str) -> Vec<String> {
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .filter(|l| {
            l.contains("crate::scene")
                || l.contains("toml::")
                || l.contains("Spanned")
                || l.contains("get_ref()")
        })
        .map(|l| l.trim().to_owned())
        .collect()
}

#[test]
fn numerics_do_not_read_the_scene() {
    let src = repo_root().join("ssm-engine/src");
    let mut files = Vec::new();
    for part in CORE {
        rust_files(&src.join(part), &mut files);
    }
    assert!(files.len() > 50, "only {} core files found", files.len());
    let mut offenders = Vec::new();
    for file in &files {
        let rel = file
            .strip_prefix(&src)
            .expect("under src")
            .to_string_lossy()
            .replace('\\', "/");
        let uses = scene_uses(&std::fs::read_to_string(file).expect("a source file"));
        match (NOT_YET.contains(&rel.as_str()), uses.is_empty()) {
            (false, false) => offenders.push(format!("{rel}: {}", uses.join(" | "))),
            (true, true) => offenders.push(format!(
                "{rel} no longer reads the scene: take it off NOT_YET"
            )),
            _ => {}
        }
    }
    assert!(
        offenders.is_empty(),
        "core code reads the scene (take a spec from ssm_engine::spec instead):\n{}",
        offenders.join("\n")
    );
}
