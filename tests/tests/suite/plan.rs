//! The plan layer: a scene's sections resolve to the span-free specs of
//! `ssm_core::spec`, whose JSON form takes the same documented defaults
//! (one source for each default) and survives a round trip; a plan built in
//! code runs through the pipeline without a scene and gives the scene's
//! answers; a plan's errors point at the scene's lines.

use ssm_core::spec::{
    BackboneSpec, FrcSpec, InvarianceSpec, SteadyStart, SteadyStateSpec, TransientSpec,
    ValidationSpec, ValidationStart,
};
use ssm_engine::plan;
use ssm_engine::scene::SceneFile;

/// A scene that asks every answer with only the keys it must give.
const SCENE: &str = "[model]\nplugin = \"duffing\"\n\
[outputs]\ncoordinates = [\"x\"]\n\
[outputs.backbone]\nrho_max = 0.2\n\
[outputs.invariance_error]\nradii = [0.1]\norders = [3]\n\
[outputs.transient]\nrho0 = [0.1]\nt_end = 20.0\n\
[forcing]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\n\
[validate]\nrho0 = [0.1]\nt_end = 20.0\n\
[validate.steady_state]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\npoints = 3\nstart = \"ssm\"\n";

fn resolved() -> plan::Plan {
    let scene = SceneFile::parse(std::path::Path::new("scene.toml"), SCENE.to_owned())
        .expect("the scene parses");
    plan::of_scene(&scene).expect("the scene resolves")
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
    round(&specs);
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

/// A forced-response spec built in code meets the checks a scene's
/// `[forcing]` meets: each bad value is a typed error naming its key, never
/// a panic, a misleading numerical failure or an empty answer (before the
/// check: a NaN range failed in the homological equation, an empty
/// `resonance` panicked, empty `epsilon` or `orders` returned no curve, an
/// order above the SSM's and a negative `rho_max` were ignored).
#[test]
fn hand_built_frc_specs_are_checked_like_scenes() {
    use ssm_core::rom::forced_response::{forced_response, FrcError};
    let sys = ssm_tests::system("duffing", "", "");
    let sp = ssm_core::spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &ssm_tests::spectrum_options(None, 0),
    )
    .expect("spectrum");
    let masters =
        ssm_core::spectrum::master_modes(&sys, &sp, &[1], Default::default()).expect("masters");
    let ssm = ssm_tests::ssm_of(&sys, &sp, &[1], 3, Default::default());
    let x = sys.output("x").expect("output x").clone();
    let base = FrcSpec::new(vec![0.01], [0.9, 1.1]);
    let cases = [
        (
            "forcing.omega_range",
            FrcSpec::new(vec![0.01], [f64::NAN, 1.1]),
        ),
        ("forcing.omega_range", FrcSpec::new(vec![0.01], [1.1, 0.9])),
        ("forcing.epsilon", FrcSpec::new(vec![], [0.9, 1.1])),
        ("forcing.epsilon", FrcSpec::new(vec![f64::NAN], [0.9, 1.1])),
        (
            "forcing.points",
            FrcSpec {
                points: 0,
                ..base.clone()
            },
        ),
        (
            "forcing.rho_max",
            FrcSpec {
                rho_max: Some(-1.0),
                ..base.clone()
            },
        ),
        (
            "forcing.orders",
            FrcSpec {
                orders: Some(vec![]),
                ..base.clone()
            },
        ),
        (
            "forcing.orders",
            FrcSpec {
                orders: Some(vec![99]),
                ..base.clone()
            },
        ),
        (
            "forcing.resonance",
            FrcSpec {
                resonance: Some(vec![]),
                ..base.clone()
            },
        ),
        (
            "forcing.nonautonomous_order",
            FrcSpec {
                nonautonomous_order: Some(3),
                ..base.clone()
            },
        ),
    ];
    for (key, spec) in cases {
        match forced_response(&ssm, &sys, &masters, &spec, &[&x], 0.01) {
            Err(FrcError::Spec(e)) => assert_eq!(e.key, key, "{spec:?}: {e}"),
            other => panic!("{spec:?}: expected a typed error at {key}, got {other:?}"),
        }
    }
    // the sound spec still answers
    let ok = forced_response(&ssm, &sys, &masters, &base, &[&x], 0.01).expect("the base spec");
    assert!(!ok.rows.is_empty());
}
