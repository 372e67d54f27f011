//! The Rust example without a scene (`ssm-engine/examples/duffing.rs`:
//! a model built from matrices, backbone, damping, forced response and the
//! full-system reference through the typed API) runs; `cargo test` builds it.

use ssm_tests::profile_dir;

/// The example exits successfully (it fails itself when the reduced peak
/// amplitude and the full system's differ beyond the reduced curve's
/// estimate) and prints every answer with its estimate, and the full
/// system's two folds beside the reduced model's.
#[test]
fn duffing_example_runs_and_agrees_with_the_full_system() {
    let path = profile_dir().join("examples").join("duffing");
    assert!(
        path.exists(),
        "{} not found: `cargo test --release --workspace` builds it",
        path.display()
    );
    let out = std::process::Command::new(&path)
        .output()
        .expect("the example starts");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for needle in ["zeta(x)", "estimate", "reduced FRC", "full system"] {
        assert!(text.contains(needle), "missing '{needle}' in:\n{text}");
    }
    assert_eq!(text.matches("SN at").count(), 2, "{text}");
    assert_eq!(text.matches("Fold at").count(), 2, "{text}");
}
