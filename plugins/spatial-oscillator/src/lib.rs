//! Plugin `spatial-oscillator`: the oscillator in three-dimensional space of
//! Li, Jain & Haller (2023), eq. (23), optionally moving on the cubic surface
//! (eq. 24) or the sphere (eq. 25), built with the mechanical builder.
//!
//! Defaults are the paper's values (Sect. 5.1): `zeta1 = 0.01`,
//! `zeta2 = zeta3 = 0.05`, `omega1 = 2`, `omega2 = 3`, `omega3 = 5`, `f1 = 1`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5.1, eqs. (23)-(25).

use ssm_api::{
    ErrorKind, Harmonic, Model, ModelInfo, MotionKind, PluginError, PolyVector, SparseMatrix,
};
use ssm_plugin_kit::{Constraints, MechanicalSystem, ParamSpec, Params};

const MODEL: &str = "oscillator";

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("zeta1", 0.01, "damping ratio of x1 (eq. 23)"),
        ParamSpec::float("zeta2", 0.05, "damping ratio of x2 (eq. 23)"),
        ParamSpec::float("zeta3", 0.05, "damping ratio of x3 (eq. 23)"),
        ParamSpec::float("omega1", 2.0, "linear frequency of x1 (eq. 23)"),
        ParamSpec::float("omega2", 3.0, "linear frequency of x2 (eq. 23)"),
        ParamSpec::float("omega3", 5.0, "linear frequency of x3 (eq. 23)"),
        ParamSpec::float(
            "f1",
            1.0,
            "forcing amplitude on x1, eps*f1*cos(Omega t) (eq. 23)",
        ),
        ParamSpec::choice(
            "constraint",
            &["none", "cubic", "spherical"],
            "none",
            "configuration constraint: none, cubic x3 = x1^3 + x2^3 (eq. 24), spherical (eq. 25)",
        ),
    ]
}

fn models() -> Vec<ModelInfo> {
    vec![ModelInfo {
        name: MODEL.into(),
        description: "3-DOF spatial oscillator, eq. (23), with optional path constraint (24)/(25)"
            .into(),
        params: specs().iter().map(ParamSpec::info).collect(),
    }]
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    if !name.is_empty() && name != MODEL {
        return Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            &format!("this plugin offers only '{MODEL}'"),
        ));
    }
    let p = Params::parse(params, &specs())?;
    let zeta = [p.float("zeta1"), p.float("zeta2"), p.float("zeta3")];
    let omega = [p.float("omega1"), p.float("omega2"), p.float("omega3")];
    let w2 = omega.map(|w| w * w);
    let mut sys = MechanicalSystem::new(MODEL, &["x1", "x2", "x3"]);
    sys.dof_motion = vec![MotionKind::Translational; 3];
    sys.mass = SparseMatrix::diagonal(&[1.0; 3]);
    sys.damping = SparseMatrix::diagonal(&[
        2.0 * zeta[0] * omega[0],
        2.0 * zeta[1] * omega[1],
        2.0 * zeta[2] * omega[2],
    ]);
    sys.stiffness = SparseMatrix::diagonal(&w2);
    let s = w2.iter().sum::<f64>();
    let f = &mut sys.internal_force;
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        // omega_i^2/2 (3 x_i^2 + x_j^2 + x_k^2) + omega_j^2 x_i x_j + omega_k^2 x_i x_k
        f.push(i, 1.5 * w2[i], &[(i, 2)]);
        f.push(i, 0.5 * w2[i], &[(j, 2)]);
        f.push(i, 0.5 * w2[i], &[(k, 2)]);
        f.push(i, w2[j], &[(i, 1), (j, 1)]);
        f.push(i, w2[k], &[(i, 1), (k, 1)]);
        // (omega_1^2 + omega_2^2 + omega_3^2)/2 x_i (x_1^2 + x_2^2 + x_3^2)
        for l in 0..3 {
            f.push(i, 0.5 * s, &[(i, 1), (l, 2)]);
        }
    }
    let constraint = p.text("constraint");
    if constraint != "none" {
        let mut g = PolyVector::zeros(1, 3);
        if constraint == "cubic" {
            // eq. (24): x3 - x1^3 - x2^3
            g.push(0, 1.0, &[(2, 1)]);
            g.push(0, -1.0, &[(0, 3)]);
            g.push(0, -1.0, &[(1, 3)]);
        } else {
            // eq. (25): x1^2 + x2^2 + (x3 - 1)^2 - 1 = x1^2 + x2^2 + x3^2 - 2 x3
            g.push(0, -2.0, &[(2, 1)]);
            for l in 0..3 {
                g.push(0, 1.0, &[(l, 2)]);
            }
        }
        sys.constraints = Some(Constraints::polynomial(g));
    }
    let mut cos = PolyVector::zeros(3, 6);
    cos.push(0, p.float("f1"), &[]);
    sys.forcing = vec![Harmonic {
        multiple: 1.0,
        cos,
        sin: PolyVector::zeros(3, 6),
    }];
    Ok(sys.into_model()?)
}

ssm_api::declare_plugin! {
    name: "spatial-oscillator",
    description: "Spatial oscillator with optional path constraint (Li, Jain & Haller 2023, Sect. 5.1)",
    models: models,
    build: build,
}
