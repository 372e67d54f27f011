//! Model `beam`: one clamped-clamped von Karman beam of the divider's element,
//! the stand-in for the experiment of Szalai, Ehrhardt & Haller (2017),
//! Sect. 9b (a steel beam clamped at both ends, Ehrhardt & Allen 2016), whose
//! data are not public. The defaults are that beam's nominal dimensions
//! (228.6 x 12.7 x 0.787 mm, steel); Rayleigh damping `C = alpha M + beta K`.
//! Clamped at both ends, the beam stretches as it bends, so its backbones
//! harden (the von Karman coupling of axial and transverse motion).
//!
//! Outputs: the transverse deflection and velocity at midspan (`w_mid`,
//! `w_mid_dot`; the second mode has a node there, as the paper notes) and at a
//! quarter of the span (`w_quarter`, `w_quarter_dot`; every mode shows).
//!
//! # References
//! R. Szalai, D. Ehrhardt, G. Haller, Proc. R. Soc. A 473 (2017) 20160759,
//! Sect. 9b; D. A. Ehrhardt, M. S. Allen, Mech. Syst. Signal Process. 76-77
//! (2016) 612-633.

use ssm_api::{Model, MotionKind, Output, PluginError, PolyVector, SparseMatrix, Weight};
use ssm_plugin_kit::{MechanicalSystem, ParamSpec, Params};
use von_karman_beam::{Mesh, Section, Support};

use crate::{elements, invalid, positive};

/// The parameters of `beam`.
pub fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::count("n", 16, "elements (an even number puts a node at midspan)"),
        ParamSpec::float("length", 228.6, "span between the clamps [mm]"),
        ParamSpec::float("width", 12.7, "width [mm]"),
        ParamSpec::float("thickness", 0.787, "thickness [mm]"),
        ParamSpec::float("density", 7800e-9, "density [kg/mm^3]"),
        ParamSpec::float("young", 200e6, "Young's modulus [kPa]"),
        ParamSpec::float(
            "alpha",
            0.5,
            "mass-proportional damping, C = alpha M + beta K [1/s]",
        ),
        ParamSpec::float(
            "beta",
            2e-6,
            "stiffness-proportional damping, C = alpha M + beta K [s]",
        ),
    ]
}

/// The clamped-clamped beam model.
pub fn build(p: &Params) -> Result<Model, PluginError> {
    let mesh = Mesh {
        length: positive(p, "length")?,
        section: Section::rectangular(
            positive(p, "width")?,
            positive(p, "thickness")?,
            positive(p, "young")?,
            positive(p, "density")?,
        ),
        elements: elements(p, "n")?,
        start: Support::Clamped,
        end: Support::Clamped,
    };
    if mesh.elements < 2 {
        return Err(invalid(
            "n",
            "a clamped-clamped beam needs at least 2 elements".into(),
        ));
    }
    let (alpha, beta) = (p.float("alpha"), p.float("beta"));
    for (name, v) in [("alpha", alpha), ("beta", beta)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(name, format!("must be non-negative, got {v}")));
        }
    }
    let dofs = mesh.number(0);
    let n = dofs.len();
    let mut names = vec![String::new(); n];
    for (i, name) in dofs.names("b") {
        names[i] = name;
    }
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut sys = MechanicalSystem::new("beam", &name_refs);
    sys.dof_motion = vec![MotionKind::Flexible; n];
    let (mut mass, mut stiffness) = (SparseMatrix::zeros(n, n), SparseMatrix::zeros(n, n));
    let mut force = PolyVector::zeros(n, 2 * n);
    mesh.assemble(&dofs, &mut mass, &mut stiffness, &mut force);
    sys.damping = SparseMatrix::rayleigh(&mass, &stiffness, alpha, beta);
    sys.mass = mass;
    sys.stiffness = stiffness;
    sys.internal_force = force;
    let at = |s: f64| mesh.transverse_at(&dofs, s);
    sys.extra_outputs = vec![("w_mid".into(), at(0.5)), ("w_quarter".into(), at(0.25))];
    let mut model = sys.into_model()?;
    // the velocities at the same points: the builder's extra outputs weigh
    // displacements, so these are added on the velocity states it laid out
    let velocity_state: Vec<u32> = model
        .mechanical
        .as_ref()
        .into_option()
        .map(|m| m.velocities.to_vec())
        .unwrap_or_default();
    for (name, s) in [("w_mid_dot", 0.5), ("w_quarter_dot", 0.25)] {
        let weights = at(s)
            .into_iter()
            .map(|(i, value)| Weight {
                state: velocity_state[i],
                value,
            })
            .collect();
        model.outputs.push(Output {
            name: name.into(),
            weights,
        });
    }
    Ok(model)
}
