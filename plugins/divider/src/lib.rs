//! Plugin `divider`: the frequency divider of Li, Jain & Haller (2023),
//! Sect. 5.3, eqs. (48)-(49). A horizontal cantilever (length `l1`, `n1`
//! elements) and a vertical cantilever (`l2`, `n2` elements) of planar von
//! Karman beam elements, clamped at their roots, whose free ends are joined by
//! a revolute joint:
//!
//! `g1 = u_h(l1) + w_v(l2) = 0`, `g2 = w_h(l1) - u_v(l2) = 0` (eq. 49).
//!
//! Rayleigh damping `C = beta K` of each beam; a transverse point load
//! `eps cos(Omega t)` on the horizontal beam at `load_position * l1` (the
//! midpoint by default), distributed by the Hermite shape functions when it
//! falls inside an element. With the defaults (`n1 = 10`, `n2 = 14`) the phase
//! space `(x, x', mu)` has 146 dimensions and the first two frequencies are near
//! 1:2 (eq. 50).
//!
//! Units: mm, kg, s (forces in kg mm/s^2, moduli in kPa).
//!
//! Displacements are named `h<k>_<u|w|phi>` (horizontal beam, node `k` counted
//! from the clamp, `k = 1..n1`) and `v<k>_<u|w|phi>` (vertical beam); the outputs
//! `w_hori_mid` and `w_vert_mid` are the transverse deflections at the beams'
//! midpoints (Figs. 19 and 22).
//!
//! The model `beam` is one clamped-clamped beam of the same
//! element, the stand-in for the experiment of the NAR paper (Sect. 9b).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5.3 and
//! Appendix G.2.

mod beam;

use ssm_api::{
    ErrorKind, Harmonic, Model, ModelInfo, MotionKind, PluginError, PolyVector, SparseMatrix,
};
use ssm_plugin_kit::{Constraints, MechanicalSystem, ParamSpec, Params};
use von_karman_beam::{Mesh, Section, Support};

/// Largest number of elements per beam accepted: the limit of double
/// precision for this element. The pencil's condition grows as the fourth
/// power of the elements per beam; measured on the divider with k (10, 14)
/// elements, the relative noise of the sparse solves (seen in the forced
/// response's `X0` table) is 7e-8 at 1,400 elements on the longer beam,
/// 4.8e-3 at 3,500, 1.3e-2 at 4,900, and at 14,000 the first eigenvalue is
/// off by 6e-4, where the SSM and forced response become meaningless.
/// (Elements this short, a fraction of the thickness, are also beyond the
/// Euler-Bernoulli kinematics of the element.)
const MAX_ELEMENTS: u64 = 4_000;

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::count("n1", 10, "elements of the horizontal beam (N1)"),
        ParamSpec::count("n2", 14, "elements of the vertical beam (N2)"),
        ParamSpec::float("l1", 707.0, "length of the horizontal beam [mm]"),
        ParamSpec::float("l2", 1000.0, "length of the vertical beam [mm]"),
        ParamSpec::float("b1", 10.0, "width of the horizontal beam [mm]"),
        ParamSpec::float("b2", 1.0, "width of the vertical beam [mm]"),
        ParamSpec::float("h1", 1.0, "thickness of the horizontal beam [mm]"),
        ParamSpec::float("h2", 1.0, "thickness of the vertical beam [mm]"),
        ParamSpec::float("density", 2700e-9, "density [kg/mm^3]"),
        ParamSpec::float("young", 70e6, "Young's modulus [kPa]"),
        ParamSpec::float(
            "beta",
            1e-3 / 7.0,
            "Rayleigh damping C = beta K of both beams [s]",
        ),
        ParamSpec::float(
            "load_position",
            0.5,
            "point of the transverse load on the horizontal beam, as a fraction of l1 from the clamp",
        ),
    ]
}

fn models() -> Vec<ModelInfo> {
    vec![
        ModelInfo {
            name: "divider".into(),
            description: "two von Karman cantilevers joined by a revolute joint, 1:2 internal resonance (Li, Jain & Haller 2023, Sect. 5.3)".into(),
            params: specs().iter().map(ParamSpec::info).collect(),
        },
        ModelInfo {
            name: "beam".into(),
            description: "one clamped-clamped von Karman beam, the stand-in for the experiment of Szalai, Ehrhardt & Haller (2017), Sect. 9b".into(),
            params: beam::specs().iter().map(ParamSpec::info).collect(),
        },
    ]
}

fn invalid(name: &str, why: String) -> PluginError {
    PluginError::new(ErrorKind::InvalidParameter, name, &why)
}

fn positive(p: &Params, name: &str) -> Result<f64, PluginError> {
    let v = p.float(name);
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(invalid(
            name,
            format!("must be positive and finite, got {v}"),
        ))
    }
}

fn elements(p: &Params, name: &str) -> Result<usize, PluginError> {
    let n = p.count(name);
    if (1..=MAX_ELEMENTS).contains(&n) {
        Ok(n as usize)
    } else {
        Err(invalid(
            name,
            format!(
                "must be between 1 and {MAX_ELEMENTS}, got {n} (beyond, the eigenvalues lose digits in double precision: the pencil's condition grows as the fourth power of the elements per beam)"
            ),
        ))
    }
}

/// The two cantilevers of eq. (48), from the parameters.
fn beams(p: &Params) -> Result<(Mesh, Mesh), PluginError> {
    let (density, young) = (positive(p, "density")?, positive(p, "young")?);
    let beam = |l: &str, b: &str, h: &str, n: &str| -> Result<Mesh, PluginError> {
        Ok(Mesh {
            length: positive(p, l)?,
            section: Section::rectangular(positive(p, b)?, positive(p, h)?, young, density),
            elements: elements(p, n)?,
            start: Support::Clamped,
            end: Support::Free,
        })
    };
    Ok((beam("l1", "b1", "h1", "n1")?, beam("l2", "b2", "h2", "n2")?))
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    if name == "beam" {
        return beam::build(&Params::parse(params, &beam::specs())?);
    }
    if !name.is_empty() && name != "divider" {
        return Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            "this plugin offers 'divider' (the default) and 'beam'",
        ));
    }
    let p = Params::parse(params, &specs())?;
    let (hori, vert) = beams(&p)?;
    let beta = p.float("beta");
    if !(beta.is_finite() && beta >= 0.0) {
        return Err(invalid("beta", format!("must be non-negative, got {beta}")));
    }
    let load_at = p.float("load_position");
    if !(0.0..=1.0).contains(&load_at) {
        return Err(invalid(
            "load_position",
            format!("must lie in [0, 1] (fraction of l1), got {load_at}"),
        ));
    }

    let h_dofs = hori.number(0);
    let v_dofs = vert.number(h_dofs.len());
    let n = h_dofs.len() + v_dofs.len();
    let mut names = vec![String::new(); n];
    for (i, name) in h_dofs.names("h").into_iter().chain(v_dofs.names("v")) {
        names[i] = name;
    }
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut sys = MechanicalSystem::new("divider", &name_refs);
    sys.dof_motion = vec![MotionKind::Flexible; n];
    let (mut mass, mut stiffness) = (SparseMatrix::zeros(n, n), SparseMatrix::zeros(n, n));
    let mut force = PolyVector::zeros(n, 2 * n);
    hori.assemble(&h_dofs, &mut mass, &mut stiffness, &mut force);
    vert.assemble(&v_dofs, &mut mass, &mut stiffness, &mut force);
    let mut damping = SparseMatrix::zeros(n, n);
    for (r, c, v) in stiffness.iter() {
        damping.push(r, c, beta * v);
    }
    sys.mass = mass;
    sys.stiffness = stiffness;
    sys.damping = damping;
    sys.internal_force = force;

    // eq. (49): the revolute joint at the free ends
    let tip = |dofs: &von_karman_beam::Numbering, mesh: &Mesh, d: usize| {
        dofs.get(mesh.elements, d)
            .expect("a free end keeps its unknowns")
    };
    let mut g = PolyVector::zeros(2, n);
    g.push(0, 1.0, &[(tip(&h_dofs, &hori, 0), 1)]);
    g.push(0, 1.0, &[(tip(&v_dofs, &vert, 1), 1)]);
    g.push(1, 1.0, &[(tip(&h_dofs, &hori, 1), 1)]);
    g.push(1, -1.0, &[(tip(&v_dofs, &vert, 0), 1)]);
    sys.constraints = Some(Constraints::polynomial(g));

    let mut cos = PolyVector::zeros(n, 2 * n);
    for (i, w) in hori.transverse_at(&h_dofs, load_at) {
        cos.push(i, w, &[]);
    }
    sys.forcing = vec![Harmonic {
        multiple: 1.0,
        cos,
        sin: PolyVector::zeros(n, 2 * n),
    }];
    sys.extra_outputs = vec![
        ("w_hori_mid".into(), hori.transverse_at(&h_dofs, 0.5)),
        ("w_vert_mid".into(), vert.transverse_at(&v_dofs, 0.5)),
    ];
    Ok(sys.into_model()?)
}

ssm_api::declare_plugin! {
    name: "divider",
    description: "Frequency divider: von Karman beams joined by a revolute joint (Li, Jain & Haller 2023, Sect. 5.3)",
    models: models,
    build: build,
}
