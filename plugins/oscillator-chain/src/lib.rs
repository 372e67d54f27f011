//! Plugin `oscillator-chain`: a synthetic sparse benchmark, a fixed-fixed chain
//! of `n` unit masses coupled by springs with linear stiffness `k` and cubic
//! stiffness `kappa`, with Rayleigh damping `C = alpha M + beta K`:
//!
//! `x_i'' + [C x']_i + k (2 x_i - x_{i-1} - x_{i+1}) + kappa (x_i - x_{i-1})^3 - kappa (x_{i+1} - x_i)^3 = 0`,
//! `x_0 = x_{n+1} = 0`.
//!
//! Its linear spectrum is known in closed form, which makes it the reference for
//! the sparse eigen-solver: `omega_j = 2 sqrt(k) sin(j pi / (2 (n + 1)))`,
//! `lambda_j = -zeta_j omega_j +- i omega_j sqrt(1 - zeta_j^2)` with
//! `2 zeta_j omega_j = alpha + beta omega_j^2`.

use ssm_api::{ErrorKind, Model, ModelInfo, MotionKind, PluginError, SparseMatrix};
use ssm_plugin_kit::{MechanicalSystem, ParamSpec, Params};

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::count("n", 100, "number of masses"),
        ParamSpec::float("k", 1.0, "linear spring stiffness"),
        ParamSpec::float("kappa", 0.5, "cubic spring stiffness"),
        ParamSpec::float(
            "alpha",
            1e-5,
            "mass-proportional damping, C = alpha M + beta K",
        ),
        ParamSpec::float(
            "beta",
            1e-3,
            "stiffness-proportional damping, C = alpha M + beta K",
        ),
    ]
}

fn models() -> Vec<ModelInfo> {
    vec![ModelInfo {
        name: "chain".into(),
        description: "fixed-fixed chain of n masses with cubic springs and Rayleigh damping (sparse benchmark)".into(),
        params: specs().iter().map(ParamSpec::info).collect(),
    }]
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    if !name.is_empty() && name != "chain" {
        return Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            "this plugin offers only 'chain'",
        ));
    }
    let p = Params::parse(params, &specs())?;
    let n = p.count("n") as usize;
    if !(1..=5_000_000).contains(&n) {
        return Err(PluginError::new(
            ErrorKind::InvalidParameter,
            "n",
            "must be between 1 and 5000000",
        ));
    }
    let (k, kappa, alpha, beta) = (
        p.float("k"),
        p.float("kappa"),
        p.float("alpha"),
        p.float("beta"),
    );
    let names: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut sys = MechanicalSystem::new("chain", &name_refs);
    sys.dof_motion = vec![MotionKind::Translational; n];
    sys.mass = SparseMatrix::diagonal(&vec![1.0; n]);
    let mut stiff = SparseMatrix::zeros(n, n);
    let mut damp = SparseMatrix::zeros(n, n);
    for i in 0..n {
        stiff.push(i, i, 2.0 * k);
        damp.push(i, i, alpha + 2.0 * beta * k);
        if i + 1 < n {
            for (r, c) in [(i, i + 1), (i + 1, i)] {
                stiff.push(r, c, -k);
                damp.push(r, c, -beta * k);
            }
        }
    }
    sys.stiffness = stiff;
    sys.damping = damp;
    // spring s between masses s-1 and s (s = 0..=n, walls at -1 and n):
    // elongation d = x_s - x_{s-1}; force kappa d^3 acts +on s, -on s-1.
    let f = &mut sys.internal_force;
    for s in 0..=n {
        let right = (s < n).then_some(s);
        let left = s.checked_sub(1);
        // d^3 = sum over binomial expansion of (x_r - x_l)^3
        let mut cube: Vec<(f64, Vec<(usize, u32)>)> = Vec::new();
        match (left, right) {
            (Some(l), Some(r)) => {
                cube.push((1.0, vec![(r, 3)]));
                cube.push((-3.0, vec![(r, 2), (l, 1)]));
                cube.push((3.0, vec![(r, 1), (l, 2)]));
                cube.push((-1.0, vec![(l, 3)]));
            }
            (None, Some(r)) => cube.push((1.0, vec![(r, 3)])),
            (Some(l), None) => cube.push((-1.0, vec![(l, 3)])),
            (None, None) => {}
        }
        for (c, mono) in &cube {
            if let Some(r) = right {
                f.push(r, kappa * c, mono);
            }
            if let Some(l) = left {
                f.push(l, -kappa * c, mono);
            }
        }
    }
    Ok(sys.into_model()?)
}

ssm_api::declare_plugin! {
    name: "oscillator-chain",
    description: "Synthetic sparse benchmark: chain of n cubic oscillators with closed-form linear spectrum",
    models: models,
    build: build,
}
