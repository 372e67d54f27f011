//! The plugin boundary, through real `.so` files: loading, listing, two plugins
//! in one process, version refusal, panics and errors reported with names.

use ssm_api::ErrorKind;
use ssm_core::model::plugin::{Plugin, PluginLoadError};
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

/// A real plugin (the duffing plugin as released with ssm-api 0.2.0, built
/// against that API's frozen source) is refused in one line naming both
/// versions, not with abi_stable's layout report.
#[test]
fn plugin_built_against_another_api_version_is_refused_naming_both() {
    let err = Plugin::load(&plugin_path("ssm-fixture-api-0-2")).unwrap_err();
    match &err {
        PluginLoadError::VersionMismatch {
            found, expected, ..
        } => {
            assert_eq!(found, "0.2.0");
            assert_eq!(expected, ssm_api::API_VERSION);
        }
        other => panic!("expected a version mismatch, got {other}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("0.2.0") && msg.contains(ssm_api::API_VERSION) && msg.contains("rebuild"),
        "{msg}"
    );
    assert_eq!(msg.lines().count(), 1, "{msg}");
}

/// Files that are not plugins get one line saying so: a shared library
/// without the plugin symbol (the C math library) and a text file.
#[test]
fn files_that_are_not_plugins_are_refused_in_one_line() {
    let libm = [
        "/lib/x86_64-linux-gnu/libm.so.6",
        "/usr/lib/x86_64-linux-gnu/libm.so.6",
        "/lib64/libm.so.6",
    ]
    .into_iter()
    .map(std::path::PathBuf::from)
    .find(|p| p.exists());
    let dir = ssm_tests::tmp_dir("not-a-plugin");
    std::fs::create_dir_all(&dir).unwrap();
    let text = dir.join("notes.so");
    std::fs::write(&text, "not a library").unwrap();
    for (path, says) in libm
        .map(|p| (p, "exports no"))
        .into_iter()
        .chain([(text, "cannot be opened as a shared library")])
    {
        let err = Plugin::load(&path).unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(err, PluginLoadError::NotAPlugin { .. }) && msg.contains(says),
            "{}: {msg}",
            path.display()
        );
        assert_eq!(msg.lines().count(), 1, "{msg}");
        assert!(!msg.contains("Could load"), "{msg}");
    }
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
