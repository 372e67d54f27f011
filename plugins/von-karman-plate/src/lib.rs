//! Rectangular von Karman plates of any mesh density, and the plugin
//! `von-karman-plate` that builds them.
//!
//! - [`element`]: one rectangular element (Bogner-Fox-Schmit bending, bilinear
//!   membrane); mass, linear stiffness and the quadratic and cubic internal
//!   forces as exact sparse polynomials.
//! - [`mesh`]: the plate `[0, a] x [0, b]` of `nx x ny` elements with clamped
//!   or simply supported edges (fixed or sliding in-plane), assembled into the
//!   sparse arrays of an `ssm_plugin_kit::MechanicalSystem`.
//! - [`galerkin`]: the single-mode Galerkin hardening of the simply supported
//!   plate, the elements' independent reference.
//!
//! The model (`plate`, the plugin's only one): Rayleigh damping
//! `C = alpha M + beta K`, a transverse load `cos(Omega t)` of unit size (a
//! point force at `(load_x a, load_y b)` or a uniform pressure), and the
//! outputs `w_center`, `w_quarter` (at `(a / 4, b / 4)`) and `w_load` (at the
//! point force). Units are whatever the parameters use consistently (the
//! defaults: a 1 m x 1 m x 10 mm aluminium plate in SI units).
//!
//! # References
//! - S. Jain, G. Haller, *How to compute invariant manifolds and their reduced
//!   dynamics in high-dimensional finite element models*, Nonlinear Dyn. 107
//!   (2022) (von Karman plates and shells as SSM benchmarks).
//! - A. W. Leissa, *Vibration of Plates*, NASA SP-160 (1969) (frequencies).
//! - S. Timoshenko, S. Woinowsky-Krieger, *Theory of Plates and Shells*, 2nd
//!   ed., McGraw-Hill (1959) (static deflections).

pub mod element;
pub mod galerkin;
pub mod mesh;

pub use element::{Element, Material};
pub use mesh::{InPlane, Mesh, Numbering, Support};

use ssm_api::SparseMatrix;
use ssm_api::{ErrorKind, Harmonic, Model, ModelInfo, MotionKind, PluginError, PolyVector};
use ssm_plugin_kit::{MechanicalSystem, ParamSpec, Params};

/// Elements a plate may have: the model's arrays are built before the
/// engine's memory gate sees them, and the polynomial terms are the memory
/// driver (a 100 x 100 mesh peaks at 2.1 GB while built, exported and handed
/// over, about 0.2 MB an element), so the plugin bounds them itself: 10^5
/// elements (about 20 GB, 6 x 10^5 unknowns).
pub const MAX_ELEMENTS: usize = 100_000;

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("a", 1.0, "side along x"),
        ParamSpec::float("b", 1.0, "side along y"),
        ParamSpec::float("thickness", 0.01, "plate thickness h"),
        ParamSpec::float("young", 70e9, "Young's modulus E"),
        ParamSpec::float("poisson", 0.33, "Poisson's ratio nu"),
        ParamSpec::float("density", 2700.0, "density rho"),
        ParamSpec::count("nx", 10, "elements along x"),
        ParamSpec::count("ny", 10, "elements along y"),
        ParamSpec::choice(
            "support",
            &["simply_supported", "clamped"],
            "simply_supported",
            "transverse condition on the four edges",
        ),
        ParamSpec::choice(
            "inplane",
            &["fixed", "sliding"],
            "fixed",
            "in-plane condition on the edges: u = v = 0, or zero normal displacement only",
        ),
        ParamSpec::float(
            "alpha",
            0.0,
            "mass-proportional damping, C = alpha M + beta K",
        ),
        ParamSpec::float(
            "beta",
            2e-5,
            "stiffness-proportional damping, C = alpha M + beta K",
        ),
        ParamSpec::choice(
            "load",
            &["point", "pressure"],
            "point",
            "transverse load of unit size: a point force or a uniform pressure",
        ),
        ParamSpec::float("load_x", 0.5, "point force at x = load_x a"),
        ParamSpec::float("load_y", 0.5, "point force at y = load_y b"),
    ]
}

fn models() -> Vec<ModelInfo> {
    vec![ModelInfo {
        name: "plate".into(),
        description: "rectangular von Karman plate of nx x ny Bogner-Fox-Schmit elements, clamped or simply supported".into(),
        params: specs().iter().map(ParamSpec::info).collect(),
    }]
}

fn invalid(key: &str, why: String) -> PluginError {
    PluginError::new(ErrorKind::InvalidParameter, key, &why)
}

/// The mesh the parameters describe, checked.
///
/// # Errors
/// A parameter out of its range, named.
pub fn mesh_of(p: &Params) -> Result<Mesh, PluginError> {
    for key in ["a", "b", "thickness", "young", "density"] {
        let v = p.float(key);
        if !(v.is_finite() && v > 0.0) {
            return Err(invalid(
                key,
                format!("must be positive and finite, got {v}"),
            ));
        }
    }
    let nu = p.float("poisson");
    if !(-1.0 < nu && nu < 0.5) {
        return Err(invalid(
            "poisson",
            format!("must lie in (-1, 0.5), got {nu}"),
        ));
    }
    let (nx, ny) = (p.count("nx") as usize, p.count("ny") as usize);
    for (key, n) in [("nx", nx), ("ny", ny)] {
        if n == 0 {
            return Err(invalid(key, "must be at least 1".into()));
        }
    }
    if nx.saturating_mul(ny) > MAX_ELEMENTS {
        return Err(invalid(
            "nx",
            format!("nx * ny = {nx} * {ny} elements exceed the plugin's limit of {MAX_ELEMENTS}"),
        ));
    }
    Ok(Mesh {
        a: p.float("a"),
        b: p.float("b"),
        nx,
        ny,
        material: Material {
            young: p.float("young"),
            poisson: nu,
            density: p.float("density"),
            thickness: p.float("thickness"),
        },
        support: match p.text("support") {
            "clamped" => Support::Clamped,
            _ => Support::SimplySupported,
        },
        inplane: match p.text("inplane") {
            "sliding" => InPlane::Sliding,
            _ => InPlane::Fixed,
        },
    })
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    if !name.is_empty() && name != "plate" {
        return Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            "this plugin offers only 'plate'",
        ));
    }
    let p = Params::parse(params, &specs())?;
    let mesh = mesh_of(&p)?;
    let (alpha, beta) = (p.float("alpha"), p.float("beta"));
    for (key, v) in [("alpha", alpha), ("beta", beta)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(key, format!("must be non-negative, got {v}")));
        }
    }
    let (lx, ly) = (p.float("load_x"), p.float("load_y"));
    for (key, v) in [("load_x", lx), ("load_y", ly)] {
        if !(0.0..=1.0).contains(&v) {
            return Err(invalid(
                key,
                format!("must lie in [0, 1] (fraction of the side), got {v}"),
            ));
        }
    }
    let numbering = mesh.number(0);
    let n = numbering.len();
    let mut names = vec![String::new(); n];
    for (i, name) in numbering.names() {
        names[i] = name;
    }
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut sys = MechanicalSystem::new("plate", &name_refs);
    sys.dof_motion = vec![MotionKind::Flexible; n];
    let (mut mass, mut stiffness) = (SparseMatrix::zeros(n, n), SparseMatrix::zeros(n, n));
    let mut force = PolyVector::zeros(n, 2 * n);
    mesh.assemble(&numbering, &mut mass, &mut stiffness, &mut force);
    sys.damping = SparseMatrix::rayleigh(&mass, &stiffness, alpha, beta);
    sys.mass = mass;
    sys.stiffness = stiffness;
    sys.internal_force = force;
    let (a, b) = (mesh.a, mesh.b);
    let load = match p.text("load") {
        "pressure" => mesh.pressure_load(&numbering),
        _ => mesh.transverse_at(&numbering, lx * a, ly * b),
    };
    let mut cos = PolyVector::zeros(n, 2 * n);
    for (i, w) in load {
        cos.push(i, w, &[]);
    }
    sys.forcing = vec![Harmonic {
        multiple: 1.0,
        cos,
        sin: PolyVector::zeros(n, 2 * n),
    }];
    sys.extra_outputs = vec![
        (
            "w_center".into(),
            mesh.transverse_at(&numbering, 0.5 * a, 0.5 * b),
        ),
        (
            "w_quarter".into(),
            mesh.transverse_at(&numbering, 0.25 * a, 0.25 * b),
        ),
        (
            "w_load".into(),
            mesh.transverse_at(&numbering, lx * a, ly * b),
        ),
    ];
    Ok(sys.into_model()?)
}

ssm_api::declare_plugin! {
    name: "von-karman-plate",
    description: "Rectangular von Karman plate (Bogner-Fox-Schmit bending, bilinear membrane), clamped or simply supported, any mesh density",
    models: models,
    build: build,
}
