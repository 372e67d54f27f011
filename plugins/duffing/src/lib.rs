//! Plugin `duffing`: the minimal example of a plugin (start here to write your own).
//!
//! A single forced Duffing oscillator
//! `x'' + 2 zeta omega x' + omega^2 x + kappa x^3 = eps f cos(Omega t)`,
//! built with the mechanical builder. A plugin needs only: a parameter list with
//! defaults, a `build` function returning a [`Model`], and `declare_plugin!`.

use ssm_api::{
    ErrorKind, Harmonic, Model, ModelInfo, MotionKind, PluginError, PolyVector, SparseMatrix,
};
use ssm_plugin_kit::{MechanicalSystem, ParamSpec, Params};

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("zeta", 0.01, "damping ratio"),
        ParamSpec::float("omega", 1.0, "linear natural frequency"),
        ParamSpec::float("kappa", 1.0, "cubic stiffness coefficient"),
        ParamSpec::float(
            "f",
            1.0,
            "forcing amplitude (multiplied by the scene's epsilon)",
        ),
    ]
}

fn models() -> Vec<ModelInfo> {
    vec![ModelInfo {
        name: "duffing".into(),
        description: "forced Duffing oscillator x'' + 2 zeta omega x' + omega^2 x + kappa x^3 = eps f cos(Omega t)".into(),
        params: specs().iter().map(ParamSpec::info).collect(),
    }]
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    if !name.is_empty() && name != "duffing" {
        return Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            "this plugin offers only 'duffing'",
        ));
    }
    let p = Params::parse(params, &specs())?;
    let (zeta, omega) = (p.float("zeta"), p.float("omega"));
    let mut sys = MechanicalSystem::new("duffing", &["x"]);
    sys.dof_motion = vec![MotionKind::Translational];
    sys.mass = SparseMatrix::diagonal(&[1.0]);
    sys.damping = SparseMatrix::diagonal(&[2.0 * zeta * omega]);
    sys.stiffness = SparseMatrix::diagonal(&[omega * omega]);
    sys.internal_force.push(0, p.float("kappa"), &[(0, 3)]);
    let mut cos = PolyVector::zeros(1, 2);
    cos.push(0, p.float("f"), &[]);
    sys.forcing = vec![Harmonic {
        multiple: 1.0,
        cos,
        sin: PolyVector::zeros(1, 2),
    }];
    Ok(sys.into_model()?)
}

ssm_api::declare_plugin! {
    name: "duffing",
    description: "Minimal example plugin: a forced Duffing oscillator",
    models: models,
    build: build,
}
