//! Plugin `shaw-pierre`: the modified Shaw-Pierre oscillator of Szalai,
//! Ehrhardt & Haller (2017), eq. (9.1): two unit masses, each tied to a wall
//! and to the other by springs `k0` and dampers `c` (damping proportional to
//! stiffness), and a cubic spring `kappa x1^3` on the first mass,
//!
//! `x1'' = -c x1' - k0 x1 - kappa x1^3 - k0 (x1 - x2) - c (x1' - x2')`,
//! `x2'' = -c x2' - k0 x2 - k0 (x2 - x1) - c (x2' - x1')`,
//!
//! optionally forced by `eps f1 cos(Omega t)` on the first mass. Defaults are
//! the paper's values (Sect. 9a): `c = 0.003`, `k0 = 1`, `kappa = 0.5`. The
//! linear spectrum is `lambda_{1,2} = -c/2 +- i sqrt(k0 (1 - c^2 / (4 k0)))`,
//! `lambda_{3,4} = -3c/2 +- i sqrt(3 k0 (1 - 3 c^2 / (4 k0)))`.
//!
//! # References
//! R. Szalai, D. Ehrhardt, G. Haller, *Nonlinear model identification and
//! spectral submanifolds for multi-degree-of-freedom mechanical vibrations*,
//! Proc. R. Soc. A 473 (2017) 20160759, Sect. 9a, eqs. (9.1)-(9.2).

use ssm_api::{
    ErrorKind, Harmonic, Model, ModelInfo, MotionKind, PluginError, PolyVector, SparseMatrix,
};
use ssm_plugin_kit::{MechanicalSystem, ParamSpec, Params};

const MODEL: &str = "oscillator";

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float(
            "c",
            0.003,
            "damping of each damper, C = c [[2, -1], [-1, 2]] (eq. 9.1)",
        ),
        ParamSpec::float(
            "k0",
            1.0,
            "stiffness of each linear spring, K = k0 [[2, -1], [-1, 2]] (eq. 9.1)",
        ),
        ParamSpec::float(
            "kappa",
            0.5,
            "cubic spring on the first mass, kappa x1^3 (eq. 9.1)",
        ),
        ParamSpec::float(
            "f1",
            1.0,
            "forcing amplitude on the first mass, eps*f1*cos(Omega t)",
        ),
    ]
}

fn models() -> Vec<ModelInfo> {
    vec![ssm_plugin_kit::model_info(
        MODEL,
        "modified Shaw-Pierre oscillator, 2 DOF, damping proportional to stiffness, eq. (9.1)",
        &specs(),
    )]
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    ssm_api::select_model(name, &[MODEL])?;
    let p = Params::parse(params, &specs())?;
    let (c, k0, kappa) = (p.float("c"), p.float("k0"), p.float("kappa"));
    if k0 <= 0.0 {
        return Err(PluginError::new(
            ErrorKind::InvalidParameter,
            "k0",
            "must be positive (the springs hold the masses at the origin)",
        ));
    }
    if c < 0.0 {
        return Err(PluginError::new(
            ErrorKind::InvalidParameter,
            "c",
            "must be non-negative (a negative damper feeds energy in)",
        ));
    }
    let mut sys = MechanicalSystem::new(MODEL, &["x1", "x2"]);
    sys.dof_motion = vec![MotionKind::Translational; 2];
    sys.mass = SparseMatrix::diagonal(&[1.0, 1.0]);
    let tridiagonal = |s: f64| {
        let mut m = SparseMatrix::zeros(2, 2);
        for (i, j, v) in [(0, 0, 2.0), (0, 1, -1.0), (1, 0, -1.0), (1, 1, 2.0)] {
            m.push(i, j, s * v);
        }
        m
    };
    sys.stiffness = tridiagonal(k0);
    sys.damping = tridiagonal(c);
    sys.internal_force.push(0, kappa, &[(0, 3)]);
    let mut cos = PolyVector::zeros(2, 4);
    cos.push(0, p.float("f1"), &[]);
    sys.forcing = vec![Harmonic {
        multiple: 1.0,
        cos,
        sin: PolyVector::zeros(2, 4),
    }];
    Ok(sys.into_model()?)
}

ssm_api::declare_plugin! {
    name: "shaw-pierre",
    description: "Modified Shaw-Pierre oscillator (Szalai, Ehrhardt & Haller 2017, eq. 9.1)",
    models: models,
    build: build,
}
