//! The plan layer: a scene's sections resolve to the span-free specs of
//! `ssm_engine::spec`, whose JSON form takes the same documented defaults
//! (one source for each default) and survives a round trip.

use ssm_engine::plan;
use ssm_engine::scene::SceneFile;
use ssm_engine::spec::{
    BackboneSpec, FrcSpec, InvarianceSpec, SteadyStart, SteadyStateSpec, TransientSpec,
    ValidationSpec, ValidationStart,
};

/// A scene that asks every answer with only the keys it must give.
const SCENE: &str = "[model]\nplugin = \"duffing\"\n\
[outputs]\ncoordinates = [\"x\"]\n\
[outputs.backbone]\nrho_max = 0.2\n\
[outputs.invariance_error]\nradii = [0.1]\norders = [3]\n\
[outputs.transient]\nrho0 = [0.1]\nt_end = 20.0\n\
[forcing]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\n\
[validate]\nrho0 = [0.1]\nt_end = 20.0\n\
[validate.steady_state]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\npoints = 3\nstart = \"ssm\"\n";

fn resolved() -> plan::AnswerSpecs {
    let scene = SceneFile::parse(std::path::Path::new("scene.toml"), SCENE.to_owned())
        .expect("the scene parses");
    plan::answers(&scene)
}

#[test]
fn scene_defaults_are_the_spec_defaults() {
    let specs = resolved();
    let json = |text: &str| serde_json::from_str::<serde_json::Value>(text).expect("json");
    let backbone: BackboneSpec = serde_json::from_value(json(r#"{"rho_max": 0.2}"#)).unwrap();
    assert_eq!(specs.backbone.as_ref(), Some(&backbone));
    assert_eq!(backbone.points, BackboneSpec::DEFAULT_POINTS);
    let invariance: InvarianceSpec =
        serde_json::from_value(json(r#"{"radii": [0.1], "orders": [3]}"#)).unwrap();
    assert_eq!(specs.invariance.as_ref(), Some(&invariance));
    let transient: TransientSpec =
        serde_json::from_value(json(r#"{"rho0": [0.1], "t_end": 20.0}"#)).unwrap();
    assert_eq!(specs.transient.as_ref(), Some(&transient));
    let frc: FrcSpec =
        serde_json::from_value(json(r#"{"epsilon": [0.01], "omega_range": [0.9, 1.1]}"#)).unwrap();
    assert_eq!(specs.frc.as_ref(), Some(&frc));
    assert_eq!(frc, FrcSpec::new(vec![0.01], [0.9, 1.1]));
    let validation: ValidationSpec = serde_json::from_value(json(
        r#"{"transient": {"start": {"ssm": {"rho0": [0.1]}}, "t_end": 20.0},
            "steady_state": {"epsilon": 0.01, "omegas": [0.9, 1.0, 1.1], "start": "ssm"}}"#,
    ))
    .unwrap();
    let v = specs.validation.as_ref().expect("validation");
    // the frequencies of `omega_range` and `points` to the last bit of
    // `SteadyStateSpec::uniform`
    assert_eq!(
        v.steady_state.as_ref().map(|s| s.omegas.clone()),
        Some(SteadyStateSpec::uniform([0.9, 1.1], 3))
    );
    let mut expected = validation;
    expected.steady_state.as_mut().unwrap().omegas = SteadyStateSpec::uniform([0.9, 1.1], 3);
    assert_eq!(v, &expected);
    assert_eq!(v.steady_state.as_ref().unwrap().start, SteadyStart::Ssm);
    assert!(matches!(
        v.transient.as_ref().unwrap().start,
        ValidationStart::Ssm { theta0: None, .. }
    ));
}

#[test]
fn specs_round_trip_through_json() {
    let specs = resolved();
    fn round<T: serde::Serialize + serde::de::DeserializeOwned + PartialEq + std::fmt::Debug>(
        v: &T,
    ) {
        let text = serde_json::to_string(v).expect("serializes");
        let back: T = serde_json::from_str(&text).expect("parses back");
        assert_eq!(&back, v, "{text}");
    }
    round(specs.backbone.as_ref().unwrap());
    round(specs.invariance.as_ref().unwrap());
    round(specs.transient.as_ref().unwrap());
    round(specs.frc.as_ref().unwrap());
    round(specs.validation.as_ref().unwrap());
    // given starts by name, too
    round(&ValidationStart::Given {
        values: vec![("x".into(), 0.1), ("x_dot".into(), -0.2)],
    });
}

#[test]
fn unknown_spec_fields_are_refused() {
    let e = serde_json::from_str::<BackboneSpec>(r#"{"rho_max": 0.2, "rhomax": 1}"#)
        .expect_err("a misspelt key");
    assert!(e.to_string().contains("rhomax"), "{e}");
}
