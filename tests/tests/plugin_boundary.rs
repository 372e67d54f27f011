//! The plugin boundary, through real `.so` files: loading, listing, two plugins
//! in one process, version refusal, panics and errors reported with names.

use ssm_api::ErrorKind;
use ssm_engine::model::plugin::{Plugin, PluginLoadError};
use ssm_tests::plugin_path;

#[test]
fn two_plugins_in_one_process_stay_distinct() {
    // abi_stable's load_from_file would cache the first root module and return
    // it for the second library; the engine must not.
    let osc = Plugin::load(&plugin_path("spatial-oscillator")).unwrap();
    let chain = Plugin::load(&plugin_path("oscillator-chain")).unwrap();
    assert_eq!(osc.name(), "spatial-oscillator");
    assert_eq!(chain.name(), "oscillator-chain");
    assert_eq!(osc.models().unwrap()[0].name.as_str(), "oscillator");
    assert_eq!(chain.models().unwrap()[0].name.as_str(), "chain");
    let m = chain.build_model("chain", "n = 7").unwrap();
    assert_eq!(m.states.len(), 14);
    let m = osc.build_model("", "constraint = \"cubic\"").unwrap();
    assert_eq!(m.states.len(), 7);
}

#[test]
fn listed_parameters_carry_the_papers_defaults() {
    let osc = Plugin::load(&plugin_path("spatial-oscillator")).unwrap();
    let models = osc.models().unwrap();
    let params = &models[0].params;
    let get = |n: &str| {
        params
            .iter()
            .find(|p| p.name.as_str() == n)
            .unwrap()
            .default
            .to_string()
    };
    // Li, Jain & Haller (2023), Sect. 5.1: zeta1 = 0.01, zeta2 = zeta3 = 0.05, omega = 2, 3, 5, f1 = 1
    assert_eq!(get("zeta1"), "0.01");
    assert_eq!(get("zeta2"), "0.05");
    assert_eq!(get("omega3"), "5");
    assert_eq!(get("f1"), "1");
}

#[test]
fn plugin_built_against_another_api_version_is_refused_naming_both() {
    let err = Plugin::load(&plugin_path("ssm-fixture-old-api")).unwrap_err();
    match &err {
        PluginLoadError::VersionMismatch {
            found, expected, ..
        } => {
            assert_eq!(found, "0.0.9");
            assert_eq!(expected, ssm_api::API_VERSION);
        }
        other => panic!("expected a version mismatch, got {other}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("0.0.9") && msg.contains(ssm_api::API_VERSION),
        "{msg}"
    );
}

#[test]
fn panic_in_plugin_is_caught_and_reported_with_name_and_message() {
    let p = Plugin::load(&plugin_path("ssm-fixture-panicking")).unwrap();
    let err = p.build_model("panics", "").unwrap_err();
    match &err {
        PluginLoadError::Plugin { plugin, error } => {
            assert_eq!(plugin, "panicking");
            assert_eq!(error.kind, ErrorKind::Panicked);
            assert!(
                error
                    .message
                    .contains("fixture panic: index 3 out of range"),
                "{error}"
            );
        }
        other => panic!("expected a plugin error, got {other}"),
    }
    // the process is intact: the same plugin still answers
    let err = p.build_model("fails", "").unwrap_err();
    assert!(err.to_string().contains("not symmetric"), "{err}");
}

#[test]
fn bad_parameters_are_refused_by_the_plugin_with_the_key() {
    let osc = Plugin::load(&plugin_path("spatial-oscillator")).unwrap();
    for (params, key) in [
        ("zeta = 0.1", "zeta"),
        ("constraint = \"round\"", "constraint"),
        ("omega1 = \"fast\"", "omega1"),
    ] {
        match osc.build_model("", params).unwrap_err() {
            PluginLoadError::Plugin { error, .. } => {
                assert_eq!(error.kind, ErrorKind::InvalidParameter);
                assert_eq!(error.context.as_str(), key);
            }
            other => panic!("unexpected {other}"),
        }
    }
    assert!(matches!(
        osc.build_model("pendulum", "").unwrap_err(),
        PluginLoadError::Plugin { error, .. } if error.kind == ErrorKind::UnknownModel
    ));
}

#[test]
fn missing_file_is_a_clear_error() {
    let err = Plugin::load(std::path::Path::new("/nonexistent/libnothing.so")).unwrap_err();
    assert!(err.to_string().contains("does not exist"), "{err}");
}
