//! The engine's layers, checked on its sources and its crates:
//! - the numerics are crates of their own, `ssm-kernel` (series, Chebyshev
//!   tables, continuation) and `ssm-core` (model, spectrum, SSM, answers,
//!   full-order model, reducers, comparisons); neither depends, even
//!   indirectly, on `toml`, a plot or command-line crate, the plugin kit or
//!   the front end
//!   (`ssm-engine`), and no file of theirs (nor of the engine's analyses
//!   and pipeline) names the scene's types or spans: they take the
//!   span-free specs of `ssm_core::spec` (a plan);
//! - no two files and no two folders import each other, directly or around
//!   a longer loop, in any crate of the engine, `ssm-api` and
//!   `ssm-model-files`;
//! - no source file is longer than 800 lines, no function of the pipeline
//!   longer than 150.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use ssm_tests::repo_root;

/// Source folders that must not read the scene: the kernel, the core, the
/// engine's analyses (vertical slices whose numerics take specs, not scene
/// tables) and the engine's pipeline (which runs a plan).
const NUMERICS: [&str; 4] = [
    "ssm-kernel/src",
    "ssm-core/src",
    "ssm-engine/src/analyses",
    "ssm-engine/src/pipeline",
];

/// Crates the core crates must not reach through any dependency.
const FRONT_END_CRATES: [&str; 6] = [
    "toml",
    "ssm-engine",
    "ssm-plugin-kit",
    "plotters",
    "clap",
    "indicatif",
];

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
    let root = repo_root();
    let mut files = Vec::new();
    for part in NUMERICS {
        rust_files(&root.join(part), &mut files);
    }
    assert!(files.len() > 50, "only {} core files found", files.len());
    let mut offenders = Vec::new();
    for file in &files {
        let rel = file
            .strip_prefix(&root)
            .expect("under src")
            .to_string_lossy()
            .replace('\\', "/");
        let uses = scene_uses(&std::fs::read_to_string(file).expect("a source file"));
        if !uses.is_empty() {
            offenders.push(format!("{rel}: {}", uses.join(" | ")));
        }
    }
    assert!(
        offenders.is_empty(),
        "core code reads the scene (take a spec from ssm_core::spec instead):\n{}",
        offenders.join("\n")
    );
}

/// The packages `krate` depends on, directly or not, as `cargo tree` resolves
/// its normal and build dependencies.
fn dependencies_of(krate: &str) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .current_dir(repo_root())
        .args(["tree", "--offline", "-p", krate, "-e", "normal,build"])
        .args(["--prefix", "none", "-f", "{p}"])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree -p {krate} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut names: Vec<String> = String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .filter_map(|l| l.split_whitespace().next().map(str::to_owned))
        .collect();
    names.sort();
    names.dedup();
    names
}

#[test]
fn core_crates_do_not_depend_on_the_front_end() {
    // the ABI crate too: plugins and the core share it, TOML parsing of
    // parameters is the plugin kit's
    for krate in ["ssm-api", "ssm-kernel", "ssm-core"] {
        let deps = dependencies_of(krate);
        assert!(
            deps.iter().any(|d| d == "abi_stable"),
            "{krate}: cargo tree listed {deps:?}"
        );
        let reached: Vec<&str> = FRONT_END_CRATES
            .into_iter()
            .filter(|f| deps.iter().any(|d| d == f))
            .collect();
        assert!(
            reached.is_empty(),
            "{krate} depends on front-end crates {reached:?} \
             (`cargo tree -p {krate} -i <crate>` shows the path)"
        );
    }
}

/// A module's path (`["fom", "periodic", "frc"]`) from its file's path under
/// `src` (`mod.rs`, `lib.rs` and `main.rs` name their folder).
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .with_extension("")
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The code of a file without comments, string contents and its test
/// module (`#[cfg(test)]` to the end).
fn code_of(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let line = line.split("//").next().unwrap_or("");
        let mut in_string = false;
        let mut escaped = false;
        for c in line.chars() {
            if in_string {
                if escaped {
                    escaped = false;
                } else if c == '\\' {
                    escaped = true;
                } else if c == '"' {
                    in_string = false;
                    out.push('"');
                }
                continue;
            }
            if c == '"' {
                in_string = true;
            }
            out.push(c);
        }
        out.push('\n');
    }
    out
}

/// The paths a `use` tree names (`a::{b, c::{d, e}}` gives `a::b`, `a::c::d`,
/// `a::c::e`), each as its segments.
fn expand_use(tree: &str, prefix: &[String], out: &mut Vec<Vec<String>>) {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        let mut path = prefix.to_vec();
        let head = tree.split(" as ").next().unwrap_or("");
        path.extend(
            head.split("::")
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(String::from),
        );
        out.push(path);
        return;
    };
    let mut head = prefix.to_vec();
    head.extend(
        tree[..open]
            .split("::")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from),
    );
    let body = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let (mut depth, mut start) = (0, 0);
    for (i, c) in body.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                expand_use(&body[start..i], &head, out);
                start = i + 1;
            }
            _ => {}
        }
    }
    if !body[start..].trim().is_empty() {
        expand_use(&body[start..], &head, out);
    }
}

/// Every `crate::`, `super::` or `self::` path of `code`, in `use` trees and
/// inline.
fn paths_of(code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("use ") {
        let before = rest[..at].chars().last();
        rest = &rest[at + 4..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(end) = rest.find(';') {
            expand_use(&rest[..end], &[], &mut out);
            rest = &rest[end..];
        }
    }
    let bytes = code.as_bytes();
    for start in ["crate::", "super::", "self::"] {
        for (at, _) in code.match_indices(start) {
            if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_') {
                continue;
            }
            let path: Vec<String> = code[at..]
                .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .next()
                .unwrap_or("")
                .split("::")
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect();
            out.push(path);
        }
    }
    out
}

/// The module (a key of `modules`) that `path`, written in module `from`,
/// refers to: the longest module prefix of the absolute path.
fn resolve(
    modules: &BTreeMap<Vec<String>, PathBuf>,
    from: &[String],
    path: &[String],
) -> Option<Vec<String>> {
    let (mut base, mut rest): (Vec<String>, &[String]) = match path.first()?.as_str() {
        "crate" => (Vec::new(), &path[1..]),
        "super" => (from[..from.len().saturating_sub(1)].to_vec(), &path[1..]),
        "self" => (from.to_vec(), &path[1..]),
        _ => return None,
    };
    while rest.first().is_some_and(|s| s == "super") {
        base.pop();
        rest = &rest[1..];
    }
    base.extend(rest.iter().cloned());
    (0..=base.len())
        .rev()
        .map(|k| base[..k].to_vec())
        .find(|m| modules.contains_key(m))
}

/// The strongly connected components with more than one node (Tarjan).
fn cycles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        for w in s.edges.get(v).into_iter().flatten() {
            if !s.index.contains_key(w.as_str()) {
                visit(s, w);
                let lw = s.low[w.as_str()];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if s.stack.contains(&w.as_str()) {
                let iw = s.index[w.as_str()];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = s.stack.pop() {
                comp.push(w.to_owned());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                s.out.push(comp);
            }
        }
    }
    let mut s = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The file-level and folder-level import cycles of the crate at `src`. An
/// edge is a file naming an item of another file's module; a module's own
/// submodules (its `mod` declarations and the re-exports of a facade) are
/// not edges, and test modules (`tests.rs`, `#[cfg(test)]`) are left out.
fn import_cycles(src: &Path) -> (Vec<Vec<String>>, Vec<Vec<String>>, usize) {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeMap<Vec<String>, PathBuf> = files
        .into_iter()
        // the binary's main.rs is a crate of its own, over the library's API
        .filter(|f| {
            f.file_name()
                .is_some_and(|n| n != "tests.rs" && n != "main.rs")
        })
        .map(|f| (module_of(f.strip_prefix(src).expect("under src")), f))
        .collect();
    let name = |m: &[String]| {
        if m.is_empty() {
            "lib".to_owned()
        } else {
            m.join("/")
        }
    };
    let mut file_edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut folder_edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut n_edges = 0;
    for (module, file) in &modules {
        let code = code_of(&std::fs::read_to_string(file).expect("a source file"));
        let entry = file_edges.entry(name(module)).or_default();
        for path in paths_of(&code) {
            let Some(target) = resolve(&modules, module, &path) else {
                continue;
            };
            if target.starts_with(module) {
                continue; // itself or its own submodules
            }
            n_edges += 1;
            entry.insert(name(&target));
            if let (Some(a), Some(b)) = (module.first(), target.first()) {
                if a != b {
                    folder_edges.entry(a.clone()).or_default().insert(b.clone());
                }
            }
        }
    }
    (cycles(&file_edges), cycles(&folder_edges), n_edges)
}

#[test]
fn no_import_cycles_between_files_or_folders() {
    let root = repo_root();
    let mut found = Vec::new();
    for krate in [
        "ssm-kernel/src",
        "ssm-core/src",
        "ssm-engine/src",
        "ssm-api/src",
        "ssm-plugin-kit/src",
        "model-files/src",
    ] {
        let (files, folders, n_edges) = import_cycles(&root.join(krate));
        assert!(n_edges > 3, "{krate}: only {n_edges} imports seen");
        found.extend(
            files
                .iter()
                .map(|c| format!("{krate}: files {}", c.join(" -> "))),
        );
        found.extend(
            folders
                .iter()
                .map(|c| format!("{krate}: folders {}", c.join(" -> "))),
        );
    }
    assert!(
        found.is_empty(),
        "import cycles (move what both sides need into a file of its own):\n{}",
        found.join("\n")
    );
}

/// The checker sees a planted loop: two files naming each other's items,
/// through a `use` tree and an inline path, and two folders doing the same.
#[test]
fn the_cycle_check_sees_a_planted_loop() {
    let dir = ssm_tests::tmp_dir("planted-cycle");
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).expect("a folder");
    std::fs::create_dir_all(src.join("b")).expect("b folder");
    std::fs::write(src.join("lib.rs"), "pub mod a;\npub mod b;\n").expect("lib.rs");
    std::fs::write(src.join("a/mod.rs"), "pub mod x;\npub mod y;\n").expect("a/mod.rs");
    std::fs::write(
        src.join("a/x.rs"),
        "use super::{y::{Y, Z as W}};\n// use crate::b::q::Q; (a comment)\npub struct X;\n",
    )
    .expect("a/x.rs");
    std::fs::write(
        src.join("a/y.rs"),
        "pub struct Y;\npub struct Z;\nfn f() -> crate::a::x::X { crate::a::x::X }\n",
    )
    .expect("a/y.rs");
    std::fs::write(src.join("b/mod.rs"), "pub mod q;\n").expect("b/mod.rs");
    std::fs::write(
        src.join("b/q.rs"),
        "pub struct Q;\nconst S: &str = \"crate::a::x\";\nuse crate::a::y::Y;\n",
    )
    .expect("b/q.rs");
    let (files, folders, _) = import_cycles(&src);
    assert_eq!(files, vec![vec!["a/x".to_owned(), "a/y".to_owned()]]);
    assert!(folders.is_empty(), "{folders:?}");
    // b's file now names a, and a names b back: a loop of folders
    std::fs::write(
        src.join("a/mod.rs"),
        "pub mod x;\npub mod y;\nuse crate::b::q::Q;\n",
    )
    .expect("a/mod.rs");
    let (_, folders, _) = import_cycles(&src);
    assert_eq!(folders, vec![vec!["a".to_owned(), "b".to_owned()]]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Longest source file, in lines, anywhere in the workspace.
const MAX_FILE_LINES: usize = 800;

/// Longest function of the pipeline, in lines (signature to closing brace).
const MAX_PIPELINE_FN_LINES: usize = 150;

/// The functions of `text` longer than `limit` lines, as `(name, lines)`:
/// each `fn` with a body, from its line to the line of the brace that
/// closes the body (comments and string contents left out, so their braces
/// do not count).
fn long_functions(text: &str, limit: usize) -> Vec<(String, usize)> {
    let code = code_of(text);
    let lines: Vec<&str> = code.lines().collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(at) = line.find("fn ").filter(|&at| {
            at == 0
                || !line.as_bytes()[at - 1].is_ascii_alphanumeric()
                    && line.as_bytes()[at - 1] != b'_'
        }) else {
            continue;
        };
        let name: String = line[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() {
            continue;
        }
        // the body opens at the first `{` before a `;` (a declaration
        // without a body ends at the `;`)
        let (mut depth, mut opened, mut end) = (0i64, false, None);
        'scan: for (j, l) in lines.iter().enumerate().skip(i) {
            let from = if j == i { at } else { 0 };
            for c in l[from..].chars() {
                match c {
                    ';' if !opened => break 'scan,
                    '{' => {
                        depth += 1;
                        opened = true;
                    }
                    '}' => {
                        depth -= 1;
                        if opened && depth == 0 {
                            end = Some(j);
                            break 'scan;
                        }
                    }
                    _ => {}
                }
            }
        }
        if let Some(end) = end {
            let n = end - i + 1;
            if n > limit {
                found.push((name, n));
            }
        }
    }
    found
}

/// Reference: the files' line counts and a brace count of each function.
/// No source file of the workspace is longer than 800 lines, and no
/// function of the engine's pipeline longer than 150: a longer one is split
/// along what it does.
#[test]
fn no_file_over_800_lines_and_no_pipeline_function_over_150() {
    let root = repo_root();
    let mut files = Vec::new();
    for dir in [
        "ssm-kernel",
        "ssm-core",
        "ssm-engine",
        "ssm-api",
        "ssm-plugin-kit",
        "model-files",
        "plugins",
        "python",
        "tests",
        "benches",
    ] {
        rust_files(&root.join(dir), &mut files);
    }
    // the frozen copies of old ABI crates that the loading fixtures build
    files.retain(|f| {
        !f.components().any(|c| {
            c.as_os_str() == "vendor" || c.as_os_str() == "api-1.0" || c.as_os_str() == "target"
        })
    });
    assert!(files.len() > 200, "only {} files seen", files.len());
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let n = std::fs::read_to_string(f)
                .expect("a source file")
                .lines()
                .count();
            (n > MAX_FILE_LINES).then(|| format!("{}: {n} lines", f.display()))
        })
        .collect();
    assert!(
        long.is_empty(),
        "files over {MAX_FILE_LINES} lines:\n{}",
        long.join("\n")
    );
    let mut pipeline = Vec::new();
    rust_files(&root.join("ssm-engine/src/pipeline"), &mut pipeline);
    // the pipeline is its runner: its stages are the analyses' and the
    // core's (the spectral stage)
    assert!(!pipeline.is_empty(), "{pipeline:?}");
    let long: Vec<String> = pipeline
        .iter()
        .flat_map(|f| {
            let text = std::fs::read_to_string(f).expect("a source file");
            long_functions(&text, MAX_PIPELINE_FN_LINES)
                .into_iter()
                .map(move |(name, n)| format!("{}: fn {name}, {n} lines", f.display()))
        })
        .collect();
    assert!(
        long.is_empty(),
        "pipeline functions over {MAX_PIPELINE_FN_LINES} lines:\n{}",
        long.join("\n")
    );
}

/// The function measure on planted text: a body of 160 lines is seen with
/// its exact length, braces in comments and strings do not count, and
/// declarations without a body and short functions are not reported.
#[test]
fn the_function_measure_sees_a_planted_long_function() {
    let body = "    let x = 1;\n".repeat(158);
    let text = format!(
        "trait T {{\n    fn declared(&self);\n}}\n\
         fn short() {{ let s = \"{{{{ not a brace\"; }} // }}}}\n\
         pub(crate) fn long_one(a: usize) -> usize {{\n{body}}}\n\
         fn after() {{}}\n"
    );
    assert_eq!(
        long_functions(&text, 150),
        vec![("long_one".to_owned(), 160)]
    );
    assert!(long_functions(&text, 160).is_empty());
}
