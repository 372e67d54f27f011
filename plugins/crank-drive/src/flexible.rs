//! Model `ancf-beam`: the flexible member of the crank drive on its own, a
//! straight cantilever of `elements` planar ANCF elements
//! ([`von_karman_beam::ancf`]) along `x`, clamped at `x = 0` (the first
//! node's position and slope fixed), free at `x = length`, with a tip load
//! `eps (tip_fx, tip_fy)` (constant, the harmonic of multiple 0) and
//! `eps tip_amp cos(Omega t)` across it. The checks of the element against
//! the closed forms of beam theory (static deflection, axial stretch with
//! Green strain, the first bending and axial frequencies) run on it.
//!
//! Coordinates: the clamp fixes the first node's position and the direction
//! of its slope (`y_0' = 0`), not the slope's length, which is the axial
//! stretch at the root: `dx0` first, then node `j = 1..elements` contributes
//! the deviations `(x_j, y_j, dx_j, dy_j)` of its position and slope from the
//! straight reference, all tagged flexible. Damping is Rayleigh, `C = beta K`.
//! Outputs `u_tip`, `w_tip`: the tip's axial and transverse displacement.

use ssm_api::{Harmonic, Model, MotionKind, PluginError, PolyVector, SparseMatrix};
use ssm_plugin_kit::{MechanicalSystem, ParamSpec, Params};
use von_karman_beam::ancf::AncfElement;
use von_karman_beam::{LocalTerm, Section};

/// The model's name.
pub(crate) const MODEL: &str = "ancf-beam";

pub(crate) fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::count("elements", 8, "number of equal elements, 1 to 64"),
        ParamSpec::float("length", 1.0, "undeformed length [m]"),
        ParamSpec::float("ea", 1.0e4, "axial stiffness E A [N]"),
        ParamSpec::float("ei", 1.0, "bending stiffness E I [N m^2]"),
        ParamSpec::float("rho_a", 1.0, "mass per unit length rho A [kg/m]"),
        ParamSpec::float("beta", 0.0, "Rayleigh damping C = beta K [s]"),
        ParamSpec::float("tip_fx", 0.0, "constant axial tip force [N], times eps"),
        ParamSpec::float(
            "tip_fy",
            0.0,
            "constant transverse tip force [N], times eps",
        ),
        ParamSpec::float(
            "tip_amp",
            1.0,
            "transverse tip force eps tip_amp cos(Omega t) [N]",
        ),
    ]
}

fn invalid(name: &str, message: &str) -> PluginError {
    PluginError::new(ssm_api::ErrorKind::InvalidParameter, name, message)
}

/// Global index of local unknown `i` of element `e` (`None`: fixed by the
/// clamp).
fn global(e: usize, i: usize) -> Option<usize> {
    match (e + i / 4, i % 4) {
        (0, 2) => Some(0),
        (0, _) => None,
        (node, m) => Some(1 + 4 * (node - 1) + m),
    }
}

pub(crate) fn build(p: &Params) -> Result<Model, PluginError> {
    let n_el = p.count("elements") as usize;
    if !(1..=64).contains(&n_el) {
        return Err(invalid("elements", &format!("must be 1 to 64, got {n_el}")));
    }
    for name in ["length", "ea", "ei", "rho_a"] {
        let x = p.float(name);
        if !(x.is_finite() && x > 0.0) {
            return Err(invalid(name, &format!("must be positive, got {x}")));
        }
    }
    let beta = p.float("beta");
    if !(beta.is_finite() && beta >= 0.0) {
        return Err(invalid(
            "beta",
            &format!("must be non-negative, got {beta}"),
        ));
    }
    for name in ["tip_fx", "tip_fy", "tip_amp"] {
        let x = p.float(name);
        if !x.is_finite() {
            return Err(invalid(name, &format!("must be finite, got {x}")));
        }
    }
    let element = AncfElement {
        length: p.float("length") / n_el as f64,
        section: Section {
            ea: p.float("ea"),
            ei: p.float("ei"),
            rho_a: p.float("rho_a"),
        },
        tangent: [1.0, 0.0],
    };
    let nd = 1 + 4 * n_el;
    let mut names = vec!["dx0".to_string()];
    for j in 1..=n_el {
        names.extend([
            format!("x{j}"),
            format!("y{j}"),
            format!("dx{j}"),
            format!("dy{j}"),
        ]);
    }
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut s = MechanicalSystem::new(MODEL, &refs);
    s.dof_motion = vec![MotionKind::Flexible; nd];
    let (me, ke) = (element.mass(), element.stiffness());
    let mut mass = SparseMatrix::zeros(nd, nd);
    let mut stiffness = SparseMatrix::zeros(nd, nd);
    let mut force = PolyVector::zeros(nd, 2 * nd);
    let terms: Vec<LocalTerm> = element.nonlinear_force();
    for e in 0..n_el {
        let map: Vec<Option<usize>> = (0..8).map(|i| global(e, i)).collect();
        for i in 0..8 {
            for j in 0..8 {
                if let (Some(a), Some(b)) = (map[i], map[j]) {
                    mass.push(a, b, me[i][j]);
                    stiffness.push(a, b, ke[i][j]);
                }
            }
        }
        LocalTerm::scatter(&terms, &map, &mut force);
    }
    s.damping = SparseMatrix::rayleigh(&mass, &stiffness, 0.0, beta);
    s.mass = mass;
    s.stiffness = stiffness;
    s.internal_force = force.canonical();
    // the tip node's position (the last node, first two coordinates)
    let (tip_x, tip_y) = (nd - 4, nd - 3);
    let constant = |fx: f64, fy: f64| {
        let mut v = PolyVector::zeros(nd, 2 * nd);
        v.push(tip_x, fx, &[]);
        v.push(tip_y, fy, &[]);
        v
    };
    s.forcing = vec![Harmonic {
        multiple: 0.0,
        cos: constant(p.float("tip_fx"), p.float("tip_fy")),
        sin: PolyVector::zeros(nd, 2 * nd),
    }];
    if p.float("tip_amp") != 0.0 {
        s.forcing.push(Harmonic {
            multiple: 1.0,
            cos: constant(0.0, p.float("tip_amp")),
            sin: PolyVector::zeros(nd, 2 * nd),
        });
    }
    s.extra_outputs = vec![
        ("u_tip".into(), vec![(tip_x, 1.0)]),
        ("w_tip".into(), vec![(tip_y, 1.0)]),
    ];
    Ok(s.into_model()?)
}
