//! `summary.json` follows its JSON Schema, `docs/summary.schema.json`: the
//! schema is generated from the engine's typed summary
//! (`ssm_engine::output::summary::SummaryFile`, `ssm-engine schema`) and the
//! files are checked by an independent implementation of JSON Schema (the
//! Python package `jsonschema`, draft 2020-12; `additionalProperties` is
//! false throughout, so a key the types do not name fails too).
//!
//! Every summary the suite makes from a zoo scene is checked where it is
//! made (`ssm_tests::run_zoo_with`, `zoo_data`, the NAR helpers); the test
//! below runs the zoo scenes no other test runs, except the three too slow
//! for the suite, whose shapes the others cover (`tests/scripts/zoo_compare.py
//! --run` checks their summaries with every other zoo scene's).

use ssm_engine::output::summary::{schema_json, SummaryFile, SCHEMA_VERSION};
use ssm_tests::{repo_root, run_zoo_in};

/// Zoo scenes another test runs through a helper that checks the summary,
/// and the file of that test.
const ELSEWHERE: &[(&str, &str)] = &[
    ("beam_data.toml", "src/lib.rs"),
    ("beam_nar.toml", "tests/suite/nar_models.rs"),
    (
        "crank_drive_flexible_pod.toml",
        "tests/suite/crank_flexible.rs",
    ),
    ("crank_drive_v8_pod.toml", "tests/suite/pod_report.rs"),
    ("divider_fig22_ic1.toml", "tests/suite/divider.rs"),
    ("divider_frc.toml", "tests/suite/divider.rs"),
    ("pendulum_chain_data.toml", "tests/suite/nar_models.rs"),
    ("pendulum_chain_fig13.toml", "tests/suite/scenes.rs"),
    ("pendulum_chain_fig14.toml", "tests/suite/validation.rs"),
    ("pendulum_chain_fig15.toml", "tests/suite/validation.rs"),
    ("pendulum_chain_nar.toml", "tests/suite/nar_models.rs"),
    ("pendulum_chain_pod.toml", "tests/suite/pod_report.rs"),
    ("pendulum_simple_fig7_c0.1.toml", "tests/suite/scenes.rs"),
    ("pendulum_slider_fig10_ic2.toml", "tests/suite/scenes.rs"),
    ("pendulum_slider_fig11.toml", "tests/suite/scenes.rs"),
    ("shaw_pierre_data.toml", "tests/suite/nar.rs"),
    ("shaw_pierre_nar.toml", "tests/suite/nar.rs"),
    ("spatial_oscillator_cubic.toml", "tests/suite/accuracy.rs"),
    (
        "spatial_oscillator_cubic_reference.toml",
        "tests/suite/reference_branches.rs",
    ),
    ("spatial_oscillator_data.toml", "tests/suite/nar_models.rs"),
    ("spatial_oscillator_nar.toml", "tests/suite/nar_models.rs"),
    ("spatial_oscillator_none.toml", "tests/suite/accuracy.rs"),
    ("spatial_oscillator_none_fig5.toml", "tests/suite/scenes.rs"),
    (
        "spatial_oscillator_none_fig5_nonautonomous.toml",
        "tests/suite/scenes.rs",
    ),
    (
        "spatial_oscillator_spherical.toml",
        "tests/suite/accuracy.rs",
    ),
];

/// Zoo scenes too slow for the suite (seconds on this machine), each with a
/// scene of the same sections that runs in it.
const SLOW: &[(&str, &str)] = &[
    // 15 s: the invariance error of the 4-D SSM at 8 radii and 3 orders
    ("divider_fig21.toml", "divider_fig22_ic1.toml"),
    // 13 s: the transient of the 146-state DAE
    ("divider_fig22_ic2.toml", "divider_fig22_ic1.toml"),
    // 30 s: the slider's transient and report at four orders
    (
        "pendulum_slider_fig9_fig10_ic1.toml",
        "pendulum_slider_fig10_ic2.toml",
    ),
];

/// The kept schema is the one the types generate: a change of the summary's
/// types shows in the repository's schema (regenerate it with
/// `cargo run --release --bin ssm-engine -- schema > docs/summary.schema.json`
/// and raise `SCHEMA_VERSION` when the shape changed).
#[test]
fn kept_schema_is_the_generated_one() {
    let kept = std::fs::read_to_string(repo_root().join("docs/summary.schema.json"))
        .expect("docs/summary.schema.json");
    assert!(
        kept == schema_json(),
        "docs/summary.schema.json differs from the schema of the summary's types: \
         regenerate it with `cargo run --release --bin ssm-engine -- schema > \
         docs/summary.schema.json`"
    );
    let schema: serde_json::Value = serde_json::from_str(&kept).unwrap();
    assert_eq!(
        schema["$schema"],
        "https://json-schema.org/draft/2020-12/schema"
    );
}

/// Every zoo scene's summary follows the schema: the scenes no other test
/// runs run here, and each reads back into the typed summary with this
/// version.
#[test]
fn every_zoo_scene_summary_follows_the_schema() {
    let zoo = repo_root().join("zoo");
    let mut scenes: Vec<String> = std::fs::read_dir(&zoo)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    scenes.sort();
    for (scene, file) in ELSEWHERE {
        assert!(scenes.iter().any(|s| s == scene), "no zoo/{scene}");
        let text = std::fs::read_to_string(repo_root().join("tests").join(file)).unwrap();
        assert!(
            text.contains(scene),
            "{file} no longer runs zoo/{scene}: run it here"
        );
    }
    for (scene, like) in SLOW {
        assert!(scenes.iter().any(|s| s == scene), "no zoo/{scene}");
        assert!(ELSEWHERE.iter().any(|(s, _)| s == like), "{like}");
    }
    let mut ran = Vec::new();
    for scene in &scenes {
        let covered = ELSEWHERE.iter().chain(SLOW).any(|(s, _)| s == scene);
        if covered {
            continue;
        }
        // run_zoo_in checks the file against the schema
        let (summary, out) = run_zoo_in(scene);
        let typed: SummaryFile = serde_json::from_value(summary)
            .unwrap_or_else(|e| panic!("zoo/{scene}: the summary reads back: {e}"));
        let version = match &typed {
            SummaryFile::Run(s) => s.schema_version,
            SummaryFile::PodOnly(s) => s.schema_version,
        };
        assert_eq!(version, SCHEMA_VERSION, "zoo/{scene}");
        let _ = std::fs::remove_dir_all(out);
        ran.push(scene.clone());
    }
    assert!(ran.len() >= 4, "{ran:?}");
}
