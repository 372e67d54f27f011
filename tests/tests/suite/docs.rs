//! The documentation cannot drift from the code or claim more than the tests
//! hold. The scene format has one source, `ssm-engine/src/scene/format.toml`
//! (`ssm_engine::scene::FORMAT`): `docs/scenes.md`, `ssm-engine --help` and
//! the module documentation show it, and it is itself a scene the parser
//! accepts. Every figure that README.md or `docs/` states stands in a
//! paragraph that cites the test asserting it, and every cited test exists.

use std::path::Path;
use std::process::Command;

use ssm_engine::scene::{SceneFile, FORMAT};
use ssm_tests::{engine_binary, repo_root};

/// The ```toml block under "## Scene format" in `docs/scenes.md`.
fn readme_block() -> String {
    let readme =
        std::fs::read_to_string(repo_root().join("docs/scenes.md")).expect("docs/scenes.md");
    let start = readme
        .find("## Scene format\n\n```toml\n")
        .expect("docs/scenes.md has a '## Scene format' section with a toml block")
        + "## Scene format\n\n```toml\n".len();
    let len = readme[start..].find("```").expect("the block is closed");
    readme[start..start + len].to_owned()
}

#[test]
fn readme_shows_the_engine_scene_format() {
    assert_eq!(
        readme_block(),
        FORMAT,
        "docs/scenes.md's scene format differs from ssm-engine/src/scene/format.toml"
    );
}

#[test]
fn help_shows_the_engine_scene_format() {
    let o = Command::new(engine_binary())
        .arg("--help")
        .output()
        .expect("engine runs");
    assert!(o.status.success());
    let help = String::from_utf8(o.stdout).expect("UTF-8 help");
    assert!(
        help.contains(FORMAT),
        "`ssm-engine --help` does not show scene/format.toml verbatim:\n{help}"
    );
}

#[test]
fn the_documented_format_is_a_scene_the_parser_accepts() {
    // every key shown uncommented exists and has the documented type
    let scene = SceneFile::parse(Path::new("format.toml"), FORMAT.to_owned())
        .unwrap_or_else(|e| panic!("the documented scene format is refused: {e}"));
    // and every value shown meets its spec's checks
    ssm_engine::plan::of_scene(&scene)
        .unwrap_or_else(|e| panic!("the documented scene format is refused: {e}"));
    // and a key that does not exist is refused, so the check above means something
    let bad = FORMAT.replace("order = 13 ", "orderr = 13");
    assert!(SceneFile::parse(Path::new("format.toml"), bad).is_err());
}

/// `docs/models.md` ("Bring your own model") shows the Python example that
/// the test suite runs (`zoo/files/write_beam.py`), not a copy that may drift.
#[test]
fn docs_show_the_python_model_example() {
    let readme =
        std::fs::read_to_string(repo_root().join("docs/models.md")).expect("docs/models.md");
    let script =
        std::fs::read_to_string(repo_root().join("zoo/files/write_beam.py")).expect("script");
    let start = readme
        .find("```python\n")
        .expect("docs/models.md has a python block")
        + "```python\n".len();
    let len = readme[start..].find("```").expect("the block is closed");
    assert_eq!(
        &readme[start..start + len],
        script,
        "docs/models.md's Python example differs from zoo/files/write_beam.py"
    );
}

/// The pages whose figures are claims: README.md and every `docs/*.md`.
fn pages() -> Vec<(String, String)> {
    let root = repo_root();
    let mut pages = vec![(
        "README.md".to_owned(),
        std::fs::read_to_string(root.join("README.md")).expect("README.md"),
    )];
    let mut docs: Vec<_> = std::fs::read_dir(root.join("docs"))
        .expect("docs/")
        .map(|e| e.expect("docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    docs.sort();
    assert!(!docs.is_empty(), "docs/ has no page");
    for p in docs {
        let name = format!("docs/{}", p.file_name().unwrap().to_string_lossy());
        pages.push((name, std::fs::read_to_string(&p).expect("docs page")));
    }
    pages
}

/// The units a figure must be cited in: paragraphs, list items and tables
/// outside fenced code, each with the number of its first line.
fn units(text: &str) -> Vec<(usize, String)> {
    let mut units = Vec::new();
    let mut current: Option<(usize, String)> = None;
    let mut fenced = false;
    for (k, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            units.extend(current.take());
            continue;
        }
        if fenced {
            continue;
        }
        let t = line.trim_start();
        let item = t.starts_with("- ")
            || t.starts_with("* ")
            || t.split_once(". ")
                .is_some_and(|(n, _)| n.chars().all(|c| c.is_ascii_digit()) && !n.is_empty());
        if t.is_empty() || t.starts_with('#') || item {
            units.extend(current.take());
        }
        if !t.is_empty() && !t.starts_with('#') {
            let unit = current.get_or_insert_with(|| (k + 1, String::new()));
            unit.1.push_str(line);
            unit.1.push('\n');
        }
    }
    units.extend(current);
    units
}

/// Whether a unit states a figure: a decimal, an exponent or a percentage,
/// once references to the papers (`Sect. 5.3`, `eq. (4.2)`, `Fig. 22`,
/// `(3.1)`) are removed.
fn states_a_figure(unit: &str) -> bool {
    let mut s = String::new();
    let mut rest = unit;
    // drop the cited references themselves
    while let Some(i) = rest.find("`test: ") {
        s.push_str(&rest[..i]);
        rest = rest[i + 1..].find('`').map_or("", |j| &rest[i + 2 + j..]);
    }
    s.push_str(rest);
    let b = s.as_bytes();
    let paper_ref = |i: usize| {
        let before = s[..i].trim_end_matches([' ', '(']);
        [
            "Sect.", "Sects.", "eq.", "eqs.", "Eq.", "Fig.", "Figs.", "App.", "Table", "and", "-",
            ",",
        ]
        .iter()
        .any(|w| before.ends_with(w))
            && ["Sect", "eq", "Eq", "Fig", "App", "Table"]
                .iter()
                .any(|w| s[..i].rfind(w).is_some_and(|j| i - j < 24))
            || (i > 0
                && b[i - 1] == b'('
                && s[i..]
                    .find(')')
                    .is_some_and(|j| s[i..i + j].chars().all(|c| c.is_ascii_digit() || c == '.')))
    };
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'))
        {
            let start = i;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            let decimal = i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit();
            if decimal {
                i += 1;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
            let exponent = i + 1 < b.len()
                && b[i] == b'e'
                && (b[i + 1].is_ascii_digit()
                    || (b[i + 1] == b'-' && i + 2 < b.len() && b[i + 2].is_ascii_digit()));
            let percent = s[i..].trim_start_matches(' ').starts_with('%');
            if (decimal || exponent || percent) && !paper_ref(start) {
                return true;
            }
        } else {
            i += 1;
        }
    }
    false
}

/// The tests a unit cites: `` `test: module::name` `` (a module of this
/// suite), `` `test: path/to/file.rs::name` `` (a unit test elsewhere) or
/// `` `test: python/tests/file.py::test_name` `` (a test of the Python
/// package's pytest suite).
fn citations(unit: &str) -> Vec<String> {
    unit.split("`test: ")
        .skip(1)
        .filter_map(|r| r.split_once('`').map(|(c, _)| c.to_owned()))
        .flat_map(|c| c.split(", ").map(str::to_owned).collect::<Vec<_>>())
        .collect()
}

/// Where a citation points: the file and the test function, if both exist
/// and the function is a test.
fn resolve(citation: &str) -> Result<(), String> {
    let (file, name) = citation
        .rsplit_once("::")
        .ok_or_else(|| format!("`{citation}` is not `module::name`"))?;
    let path = if file.contains('/') {
        repo_root().join(file)
    } else {
        repo_root()
            .join("tests/tests/suite")
            .join(format!("{file}.rs"))
    };
    let source = std::fs::read_to_string(&path)
        .map_err(|e| format!("`{citation}`: {} ({e})", path.display()))?;
    if file.ends_with(".py") {
        // a pytest test: a module-level `def test_...(`
        return if name.starts_with("test_")
            && source
                .lines()
                .any(|l| l.starts_with(&format!("def {name}(")))
        {
            Ok(())
        } else {
            Err(format!(
                "`{citation}`: no pytest test {name} in {}",
                path.display()
            ))
        };
    }
    let lines: Vec<&str> = source.lines().collect();
    let at = lines
        .iter()
        .position(|l| {
            l.trim_start().starts_with(&format!("fn {name}("))
                || l.contains(&format!(" fn {name}("))
        })
        .ok_or_else(|| format!("`{citation}`: no fn {name} in {}", path.display()))?;
    let is_test = lines[at.saturating_sub(12)..at]
        .iter()
        .any(|l| l.contains("#[test]") || l.contains("proptest!"));
    if is_test {
        Ok(())
    } else {
        Err(format!("`{citation}`: fn {name} is not a #[test]"))
    }
}

/// Every figure README.md and `docs/` state cites the test that asserts it,
/// and every cited test exists. A paragraph whose numbers are not results
/// (version numbers, scene inputs alone) says so with `<!-- not a result -->`.
#[test]
fn every_documented_figure_cites_an_existing_test() {
    let mut problems = Vec::new();
    for (page, text) in pages() {
        for (line, unit) in units(&text) {
            let cited = citations(&unit);
            for c in &cited {
                if let Err(e) = resolve(c) {
                    problems.push(format!("{page}:{line}: {e}"));
                }
            }
            if cited.is_empty() && !unit.contains("<!-- not a result -->") && states_a_figure(&unit)
            {
                let excerpt: String = unit.chars().take(90).collect();
                problems.push(format!(
                    "{page}:{line}: a figure without a test: {}",
                    excerpt.replace('\n', " ")
                ));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "{} problems:\n{}",
        problems.len(),
        problems.join("\n")
    );
}

#[test]
fn the_figure_check_sees_figures_and_citations() {
    assert!(states_a_figure("the folds move by 1.2e-3"));
    assert!(states_a_figure("within 0.18 % of the steady states"));
    assert!(states_a_figure("error 3e-10"));
    assert!(!states_a_figure(
        "Sect. 5.3 and eq. (4.2), Figs. 18-19, eqs. 53-58"
    ));
    assert!(!states_a_figure("the 146-state DAE of order 5 (9.1)"));
    assert_eq!(
        citations("x `test: a::b, c/d.rs::e` y `test: f::g`"),
        ["a::b", "c/d.rs::e", "f::g"]
    );
    assert_eq!(units("a 1.5\nb\n\n- c\n- d 2 %\n```\n3.5\n```\n").len(), 3);
    assert!(resolve("docs::the_figure_check_sees_figures_and_citations").is_ok());
    assert!(resolve("docs::units").is_err());
    assert!(resolve("docs::no_such_test").is_err());
    assert!(resolve(
        "python/tests/test_models.py::test_dense_and_sparse_inputs_give_the_same_model"
    )
    .is_ok());
    assert!(resolve("python/tests/test_models.py::chain").is_err());
}

/// `.ci/run` runs the README's test command, as written there.
#[test]
fn ci_runs_the_readme_test_command() {
    let readme = std::fs::read_to_string(repo_root().join("README.md")).expect("README.md");
    let after = readme
        .split_once("Run the tests")
        .expect("README says how to run the tests")
        .1;
    let block = after
        .split_once("```sh\n")
        .and_then(|(_, b)| b.split_once("\n```"))
        .expect("a sh block with the test command")
        .0;
    let ci = std::fs::read_to_string(repo_root().join(".ci/run")).expect(".ci/run");
    assert!(
        ci.lines().any(|l| l.trim() == block.trim()),
        ".ci/run does not run the README's test command `{block}`"
    );
}
