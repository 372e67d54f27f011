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
//! straight reference, the slopes scaled by the element length (`L_e r'`,
//! [`von_karman_beam::ancf::slope_scaling`]), all tagged flexible. Damping acts on the strain
//! rates: `beta K_T(q) q'`, `K_T` the tangent stiffness (linear part `beta
//! K q'`), which unlike `beta K q'` alone leaves rigid motions undamped.
//! Outputs `u_tip`, `w_tip`: the tip's axial and transverse displacement.

use super::{count_in, non_negative, positive};
use ssm_api::{Harmonic, Model, MotionKind, PluginError, PolyVector, SparseMatrix};
use ssm_plugin_kit::{Constraints, MechanicalSystem, ParamSpec, Params};
use von_karman_beam::ancf::{scaled_matrix, scaled_terms, slope_scaling, AncfElement};
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
        ParamSpec::float(
            "beta",
            0.0,
            "strain-rate damping beta K_T(q) q' [s] (K_T the tangent stiffness)",
        ),
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
    let n_el = count_in(p, "elements", 1..=64)?;
    positive(p, &["length", "ea", "ei", "rho_a"])?;
    non_negative(p, &["beta"])?;
    let beta = p.float("beta");
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
    let sc = slope_scaling(element.length);
    let (me, ke) = (
        scaled_matrix(&element.mass(), &sc),
        scaled_matrix(&element.stiffness(), &sc),
    );
    let mut mass = SparseMatrix::zeros(nd, nd);
    let mut stiffness = SparseMatrix::zeros(nd, nd);
    let mut force = PolyVector::zeros(nd, 2 * nd);
    let mut terms: Vec<LocalTerm> = element.nonlinear_force();
    terms.extend(element.strain_rate_damping(beta));
    let terms = scaled_terms(&terms, &sc);
    for e in 0..n_el {
        // the local unknowns, then their velocities
        let map: Vec<Option<usize>> = (0..16)
            .map(|i| global(e, i % 8).map(|g| if i < 8 { g } else { nd + g }))
            .collect();
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

/// The model's name: the crank drive with flexible connecting rods.
pub(crate) const FLEXIBLE_DRIVE: &str = "crank-drive-flexible";

/// The crank drive's parameters and the rods' elements and section.
pub(crate) fn drive_specs() -> Vec<ParamSpec> {
    let mut s = super::specs();
    s.extend([
        ParamSpec::count(
            "rod_elements",
            2,
            "ANCF elements per connecting rod, 1 to 16",
        ),
        ParamSpec::float("rod_ea", 1.0e5, "connecting rods' axial stiffness E A [N]"),
        ParamSpec::float(
            "rod_ei",
            5.0,
            "connecting rods' bending stiffness E I [N m^2]",
        ),
        ParamSpec::float(
            "rod_beta",
            1.0e-4,
            "connecting rods' Rayleigh damping C = beta K [s]",
        ),
    ]);
    s
}

/// Model `crank-drive-flexible`: the crank drive of the `crank-drive` model
/// with each connecting rod a planar ANCF beam of `rod_elements` elements in
/// its cylinder's plane `z = z_i` (mass `m_rod` spread uniformly), pinned to
/// the crank pin at its first node and to the piston at its last
/// (constraints on the node positions; the slopes are free, so the joints
/// are revolute). Coordinates: the crank's `u` (rotational), per cylinder
/// the piston's in-plane position `(sx_i, sy_i)` (translational) and the
/// rod's nodes' positions and slopes scaled by the element length
/// (flexible), all deviations from the reference configuration `theta = 0` with straight rods. Constraints:
/// `|u|^2 = 1`, `u_z = 0`, per cylinder the two pin joints (2 each) and the
/// piston's guide `n_i . S_i = 0`. A rigid rod's kinetic energy is the
/// rigid model's `m_rod (|P'|^2 + P'.S' + |S'|^2) / 6` (the cubic elements
/// carry rigid motion exactly), so the model tends to `crank-drive` as the
/// rods stiffen. The rods' damping acts on their strain rates
/// ([`AncfElement::strain_rate_damping`]), not on their rigid motion.
/// Outputs: the strokes `stroke_i` and the rods' bending deflections
/// `bend_i` ([`midspan_offset`]).
pub(crate) fn build_drive(p: &Params) -> Result<Model, PluginError> {
    let cyl = super::cylinders(p)?;
    let n_el = count_in(p, "rod_elements", 1..=16)?;
    positive(p, &["rod_ea", "rod_ei"])?;
    non_negative(p, &["rod_beta"])?;
    let beta = p.float("rod_beta");
    let (r, l) = (p.float("r"), p.float("l"));
    let per_cylinder = 2 + 4 * (n_el + 1);
    let base = |i: usize| 3 + i * per_cylinder;
    let node = |i: usize, j: usize, m: usize| base(i) + 2 + 4 * j + m;
    let nd = 3 + cyl.len() * per_cylinder;
    let mut names: Vec<String> = vec!["ux".into(), "uy".into(), "uz".into()];
    let mut motion = vec![MotionKind::Rotational; 3];
    for i in 1..=cyl.len() {
        names.extend([format!("sx{i}"), format!("sy{i}")]);
        motion.extend([MotionKind::Translational; 2]);
        for j in 0..=n_el {
            names.extend([
                format!("rod{i}_x{j}"),
                format!("rod{i}_y{j}"),
                format!("rod{i}_dx{j}"),
                format!("rod{i}_dy{j}"),
            ]);
            motion.extend([MotionKind::Flexible; 4]);
        }
    }
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut s = MechanicalSystem::new(FLEXIBLE_DRIVE, &refs);
    s.dof_motion = motion;
    let mut mass = SparseMatrix::zeros(nd, nd);
    let mut rods = SparseMatrix::zeros(nd, nd);
    let mut force = PolyVector::zeros(nd, 2 * nd);
    let mut damping = SparseMatrix::zeros(nd, nd);
    for a in 0..3 {
        mass.push(a, a, p.float("j_crank"));
        damping.push(a, a, p.float("c_crank"));
    }
    let section = Section {
        ea: p.float("rod_ea"),
        ei: p.float("rod_ei"),
        rho_a: p.float("m_rod") / l,
    };
    for (i, c) in cyl.iter().enumerate() {
        for a in 0..2 {
            mass.push(base(i) + a, base(i) + a, p.float("m_piston"));
            damping.push(base(i) + a, base(i) + a, p.float("c_piston"));
        }
        let tangent = [
            (c.pin[0] - c.crank_pin[0]) / l,
            (c.pin[1] - c.crank_pin[1]) / l,
        ];
        let element = AncfElement {
            length: l / n_el as f64,
            section,
            tangent,
        };
        let sc = slope_scaling(element.length);
        let (me, ke) = (
            scaled_matrix(&element.mass(), &sc),
            scaled_matrix(&element.stiffness(), &sc),
        );
        let mut terms = element.nonlinear_force();
        terms.extend(element.strain_rate_damping(beta));
        let terms = scaled_terms(&terms, &sc);
        for e in 0..n_el {
            // the local unknowns, then their velocities
            let map: Vec<Option<usize>> = (0..16)
                .map(|k| {
                    let g = node(i, e + (k % 8) / 4, k % 4);
                    Some(if k < 8 { g } else { nd + g })
                })
                .collect();
            for a in 0..8 {
                for b in 0..8 {
                    let (ga, gb) = (node(i, e + a / 4, a % 4), node(i, e + b / 4, b % 4));
                    mass.push(ga, gb, me[a][b]);
                    rods.push(ga, gb, ke[a][b]);
                    damping.push(ga, gb, beta * ke[a][b]);
                }
            }
            LocalTerm::scatter(&terms, &map, &mut force);
        }
    }
    s.mass = mass;
    s.stiffness = rods;
    s.damping = damping;
    s.internal_force = force.canonical();
    let mut g = PolyVector::zeros(2 + 5 * cyl.len(), nd);
    // |u_ref + u|^2 - 1 = 2 u_ref . u + |u|^2, u_ref = (0, 1, 0); u_z = 0
    g.push(0, 2.0, &[(1, 1)]);
    for a in 0..3 {
        g.push(0, 1.0, &[(a, 2)]);
    }
    g.push(1, 1.0, &[(2, 1)]);
    for (i, c) in cyl.iter().enumerate() {
        let eq = 2 + 5 * i;
        for k in 0..2 {
            // the rod's first node at the crank pin r R_i (u_ref + u): in
            // deviations, r0_k - r (R_i u)_k = 0
            g.push(eq + k, 1.0, &[(node(i, 0, k), 1)]);
            for a in 0..3 {
                g.push(eq + k, -r * c.throw[k][a], &[(a, 1)]);
            }
            // its last node at the piston pin
            g.push(eq + 2 + k, 1.0, &[(node(i, n_el, k), 1)]);
            g.push(eq + 2 + k, -1.0, &[(base(i) + k, 1)]);
            // the piston on its guide
            g.push(eq + 4, c.normal[k], &[(base(i) + k, 1)]);
        }
    }
    s.constraints = Some(Constraints::polynomial(g.canonical()));
    s.forcing = super::torque_harmonics(p, nd, |tau| super::crank_torque(nd, tau));
    s.extra_outputs = super::strokes(&cyl, base);
    for (i, c) in cyl.iter().enumerate() {
        let t = [
            (c.pin[0] - c.crank_pin[0]) / l,
            (c.pin[1] - c.crank_pin[1]) / l,
        ];
        s.extra_outputs.push((
            format!("bend{}", i + 1),
            midspan_offset(n_el, t, |j, m| node(i, j, m)),
        ));
    }
    Ok(s.into_model()?)
}

/// The weights of output `bend_i`: the rod's midspan point `r(l/2)` (the
/// middle node, or for an odd number of elements the cubic interpolation at
/// the middle of the middle element, `(r_a + r_b)/2 + L_e (r'_a - r'_b)/8`,
/// in the scaled slopes `L_e r'`)
/// less the mean of its end nodes, across the reference axis `t` (along
/// `(-t_y, t_x)`): the rod's bending deflection, linear in the nodal
/// coordinates (the projection on the reference normal is the deflection to
/// `cos` of the rod's swing from its reference direction, within 6 % for
/// `l = 3 r`). `node(j, m)` is the index of unknown `m` of node `j`.
fn midspan_offset(
    n_el: usize,
    t: [f64; 2],
    node: impl Fn(usize, usize) -> usize,
) -> Vec<(usize, f64)> {
    let normal = [-t[1], t[0]];
    let mut w = Vec::new();
    for (k, &nk) in normal.iter().enumerate() {
        if n_el.is_multiple_of(2) {
            w.push((node(n_el / 2, k), nk));
        } else {
            let (a, b) = (n_el / 2, n_el / 2 + 1);
            w.push((node(a, k), 0.5 * nk));
            w.push((node(b, k), 0.5 * nk));
            w.push((node(a, 2 + k), nk / 8.0));
            w.push((node(b, 2 + k), -nk / 8.0));
        }
        w.push((node(0, k), -0.5 * nk));
        w.push((node(n_el, k), -0.5 * nk));
    }
    w
}
