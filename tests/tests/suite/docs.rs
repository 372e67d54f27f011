//! The scene format has one source, `ssm-engine/src/scene/format.toml`
//! (`ssm_engine::scene::FORMAT`): the README, `ssm-engine --help` and the
//! module documentation show it, and it is itself a scene the parser accepts,
//! so the documentation cannot drift from the format or from itself.

use std::path::Path;
use std::process::Command;

use ssm_engine::scene::{SceneFile, FORMAT};
use ssm_tests::{engine_binary, repo_root};

/// The ```toml block under "### Scene format" in the README.
fn readme_block() -> String {
    let readme = std::fs::read_to_string(repo_root().join("README.md")).expect("README.md");
    let start = readme
        .find("### Scene format\n\n```toml\n")
        .expect("README has a '### Scene format' section with a toml block")
        + "### Scene format\n\n```toml\n".len();
    let len = readme[start..].find("```").expect("the block is closed");
    readme[start..start + len].to_owned()
}

#[test]
fn readme_shows_the_engine_scene_format() {
    assert_eq!(
        readme_block(),
        FORMAT,
        "README's scene format differs from ssm-engine/src/scene/format.toml"
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
    SceneFile::parse(Path::new("format.toml"), FORMAT.to_owned())
        .unwrap_or_else(|e| panic!("the documented scene format is refused: {e}"));
    // and a key that does not exist is refused, so the check above means something
    let bad = FORMAT.replace("order = 13 ", "orderr = 13");
    assert!(SceneFile::parse(Path::new("format.toml"), bad).is_err());
}

/// The README's "Bring your own model" shows the Python example that the
/// test suite runs (`zoo/files/write_beam.py`), not a copy that may drift.
#[test]
fn readme_shows_the_python_model_example() {
    let readme = std::fs::read_to_string(repo_root().join("README.md")).expect("README.md");
    let script =
        std::fs::read_to_string(repo_root().join("zoo/files/write_beam.py")).expect("script");
    let start = readme
        .find("```python\n")
        .expect("README has a python block")
        + "```python\n".len();
    let len = readme[start..].find("```").expect("the block is closed");
    assert_eq!(
        &readme[start..start + len],
        script,
        "README's Python example differs from zoo/files/write_beam.py"
    );
}
