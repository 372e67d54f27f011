//! Plugin `crank-drive`: a crank drive (crankshaft, connecting rods, pistons;
//! 1 to 8 cylinders, inline or V) modeled redundantly in 3-D natural
//! coordinates, the public stand-in for the V8 crank drive of Stadlmayr,
//! Witteveen & Steiner (2017), Sect. 4.1, whose FreeDyn model is not public.
//! Four models: `crank-drive` (below, the crankshaft on a fixed axis),
//! `crank-drive-housing` (the same drive in a housing on spring-damper
//! mounts, described in `housing.rs`), `crank-drive-flexible` (the drive with
//! flexible connecting rods in absolute nodal coordinates) and `ancf-beam`
//! (that flexible member on its own, a cantilever), both in `flexible.rs`.
//!
//! # Model
//! - **Crankshaft**: rotates about the fixed `z` axis; its coordinates are the
//!   unit vector `u` (3 components) pointing along the first crank throw.
//!   Constraints `|u|^2 = 1` and `u_z = 0` (the revolute joint). Inertia `J`
//!   about the axis: kinetic energy `J |u'|^2 / 2`.
//! - **Crank pins**: throw `k` of `K` sits at `P = r R_z(beta_k) u + z_i e_z`,
//!   `beta_k = 2 pi k / K`, linear in `u`; no coordinates of their own.
//!   Inline engines have one throw per cylinder; V engines (`v_angle > 0`)
//!   two cylinders per throw, on the banks at `-v/2` and `+v/2` from `+y`.
//! - **Connecting rod `i`**: a uniform slender rod of mass `m_rod` between the
//!   crank pin `P_i` and the piston pin `S_i` (3 coordinates), kinetic energy
//!   `m_rod (|P'|^2 + P'.S' + |S'|^2) / 6`; constraint `|S_i - P_i|^2 = l^2`.
//! - **Piston `i`**: the point `S_i` with mass `m_piston`, guided along the
//!   cylinder axis `d_i = (sin gamma_i, cos gamma_i, 0)` in the plane
//!   `z = z_i`: constraints `n_i . S_i = 0` (`n_i` the in-plane normal of
//!   `d_i`) and `S_iz = z_i`.
//! - **Loads**: a driving torque `eps (tau_mean + tau_amp cos(Omega t))` about
//!   `+z`, whose generalized force on `u` is `tau (e_z x u) = tau (-u_y, u_x, 0)`
//!   (exact on `|u| = 1`, linear in `u`; the mean part is the harmonic of
//!   multiple 0), viscous friction `c_crank` on the crankshaft (`-c_crank u'`,
//!   the torque `-c_crank theta'`) and `c_piston` on the pistons. No gravity:
//!   its constant forces have no equilibrium at the reference configuration.
//!
//! `3 + 3 n` coordinates, `2 + 3 n` independent constraints (also at the dead
//! centres: the guide rows `n_i`, `e_z` and the rod row span the piston's
//! space whenever `l > r`), one degree of freedom. The coordinates are
//! deviations from the reference configuration `theta = 0` (`u = (0, 1, 0)`),
//! where the unforced model is at rest, so the constraints have no constant
//! term. The mass matrix is constant (natural coordinates), and the motion is
//! planar: `u_z` and every `S_iz` stay at zero and each piston moves on a line,
//! which POD finds (zero out-of-plane POVs), after which the constraints
//! `u_z = 0`, `S_iz = z_i`, `n_i . S_i = 0` vanish under the projection and the
//! rods of pistons moving alike become redundant: the situation of the
//! paper's Sect. 3.3.
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint reduction
//! method for reduced order MBS models*, Multibody Syst. Dyn. (2017), Sects. 3-4;
//! J. Garcia de Jalon, E. Bayo, *Kinematic and Dynamic Simulation of
//! Multibody Systems*, Springer (1994), Ch. 2-3 (natural coordinates).

use ssm_api::{
    ErrorKind, Harmonic, Model, ModelInfo, MotionKind, PluginError, PolyVector, SparseMatrix,
};
use ssm_plugin_kit::{Constraints, MechanicalSystem, ParamSpec, Params};

mod flexible;
mod housing;

const MODEL: &str = "crank-drive";

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::count("cylinders", 4, "number of cylinders, 1 to 8"),
        ParamSpec::float(
            "v_angle",
            0.0,
            "bank angle of a V engine in degrees (0: inline, one throw per cylinder)",
        ),
        ParamSpec::float("r", 0.05, "crank radius [m]"),
        ParamSpec::float("l", 0.15, "connecting-rod length [m], l > r"),
        ParamSpec::float(
            "pitch",
            0.1,
            "distance between cylinders along the crank axis [m]",
        ),
        ParamSpec::float(
            "m_rod",
            0.5,
            "connecting-rod mass [kg] (uniform slender rod)",
        ),
        ParamSpec::float("m_piston", 0.4, "piston mass [kg]"),
        ParamSpec::float(
            "j_crank",
            0.02,
            "crankshaft inertia about its axis [kg m^2]",
        ),
        ParamSpec::float("c_crank", 0.02, "crankshaft viscous friction [N m s]"),
        ParamSpec::float("c_piston", 0.5, "piston viscous friction [N s/m]"),
        ParamSpec::float(
            "tau_mean",
            1.0,
            "mean driving torque [N m], eps * tau_mean (forcing harmonic of multiple 0)",
        ),
        ParamSpec::float(
            "tau_amp",
            0.0,
            "torque fluctuation [N m], eps * tau_amp cos(Omega t)",
        ),
    ]
}

/// The parameters of the housing model: the crank drive's and the housing's.
fn housing_specs() -> Vec<ParamSpec> {
    let mut s = specs();
    s.extend(housing::specs());
    s
}

fn models() -> Vec<ModelInfo> {
    vec![
        ModelInfo {
            name: MODEL.into(),
            description: "crank drive, 1-8 cylinders inline or V, redundant 3-D natural coordinates (Stadlmayr et al. 2017, Sect. 4.1 stand-in)".into(),
            params: specs().iter().map(ParamSpec::info).collect(),
        },
        ModelInfo {
            name: housing::MODEL.into(),
            description: "the crank drive in an engine housing on nine spring-damper mounts, seven degrees of freedom (Stadlmayr et al. 2017, Sect. 4.1)".into(),
            params: housing_specs().iter().map(ParamSpec::info).collect(),
        },
        ModelInfo {
            name: flexible::FLEXIBLE_DRIVE.into(),
            description: "the crank drive with flexible connecting rods (planar ANCF beams pinned to crank and pistons), the flexible case of Stadlmayr et al. 2017".into(),
            params: flexible::drive_specs().iter().map(ParamSpec::info).collect(),
        },
        ModelInfo {
            name: flexible::MODEL.into(),
            description: "a cantilever of planar beam elements in absolute nodal coordinates (ANCF), the element for flexible members of the crank drive".into(),
            params: flexible::specs().iter().map(ParamSpec::info).collect(),
        },
    ]
}

fn invalid(name: &str, message: &str) -> PluginError {
    PluginError::new(ErrorKind::InvalidParameter, name, message)
}

/// Refuses the first parameter of `names` that is not positive (the
/// parameters are finite: [`Params::parse`] refuses others).
fn positive(p: &Params, names: &[&str]) -> Result<(), PluginError> {
    match names.iter().find(|n| p.float(n) <= 0.0) {
        Some(n) => Err(invalid(n, &format!("must be positive, got {}", p.float(n)))),
        None => Ok(()),
    }
}

/// Refuses the first parameter of `names` that is negative.
fn non_negative(p: &Params, names: &[&str]) -> Result<(), PluginError> {
    match names.iter().find(|n| p.float(n) < 0.0) {
        Some(n) => Err(invalid(
            n,
            &format!("must be non-negative, got {}", p.float(n)),
        )),
        None => Ok(()),
    }
}

/// The count parameter `name`, refused outside `range`.
fn count_in(
    p: &Params,
    name: &str,
    range: std::ops::RangeInclusive<usize>,
) -> Result<usize, PluginError> {
    let n = p.count(name) as usize;
    if range.contains(&n) {
        Ok(n)
    } else {
        Err(invalid(
            name,
            &format!("must be {} to {}, got {n}", range.start(), range.end()),
        ))
    }
}

/// The driving torque `tau` about `+z` as the generalized force on the
/// crank's `u = u_ref + q_u` (coordinates 0..3 of `nd`): `tau (-u_y, u_x,
/// 0)`, `u_ref = (0, 1, 0)`.
fn crank_torque(nd: usize, tau: f64) -> PolyVector {
    let mut cos = PolyVector::zeros(nd, 2 * nd);
    cos.push(0, -tau, &[]);
    cos.push(0, -tau, &[(1, 1)]);
    cos.push(1, tau, &[(0, 1)]);
    cos
}

/// `R_z(beta)`, the rotation by `beta` about `z`.
fn rot_z(beta: f64) -> [[f64; 3]; 3] {
    let (s, c) = beta.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// Pushes `(sum_a c_a x_a)^2` into equation `eq` of `g`.
fn push_square(g: &mut PolyVector, eq: usize, form: &[(usize, f64)]) {
    for (i, &(a, ca)) in form.iter().enumerate() {
        g.push(eq, ca * ca, &[(a, 2)]);
        for &(b, cb) in &form[i + 1..] {
            g.push(eq, 2.0 * ca * cb, &[(a, 1), (b, 1)]);
        }
    }
}

/// Geometry of one cylinder.
struct Cylinder {
    /// Rotation of its throw, `R_z(beta_k)`.
    throw: [[f64; 3]; 3],
    /// Cylinder axis `d` and its in-plane normal `n`.
    axis: [f64; 3],
    normal: [f64; 3],
    /// Piston pin in the reference configuration.
    pin: [f64; 3],
    /// Crank pin in the reference configuration.
    crank_pin: [f64; 3],
}

fn cylinders(p: &Params) -> Result<Vec<Cylinder>, PluginError> {
    let n = count_in(p, "cylinders", 1..=8)?;
    let v = p.float("v_angle");
    if !(0.0..180.0).contains(&v) {
        return Err(invalid(
            "v_angle",
            &format!("must lie in [0, 180) degrees, got {v}"),
        ));
    }
    positive(p, &["r", "pitch", "m_rod", "m_piston", "j_crank"])?;
    non_negative(p, &["c_crank", "c_piston"])?;
    let (r, l) = (p.float("r"), p.float("l"));
    if !(l.is_finite() && l > r) {
        return Err(invalid(
            "l",
            &format!("the rod must be longer than the crank radius r = {r}, got {l}"),
        ));
    }
    let v_engine = v > 0.0 && n > 1;
    let throws = if v_engine { n.div_ceil(2) } else { n };
    Ok((0..n)
        .map(|i| {
            let (k, gamma) = if v_engine {
                let side = if i % 2 == 0 { -0.5 } else { 0.5 };
                (i / 2, side * v.to_radians())
            } else {
                (i, 0.0)
            };
            let throw = rot_z(std::f64::consts::TAU * k as f64 / throws as f64);
            let (sg, cg) = gamma.sin_cos();
            let axis = [sg, cg, 0.0];
            let z = p.float("pitch") * i as f64;
            // crank direction of the throw at theta = 0: R_z(beta) (0, 1, 0)
            let c = [throw[0][1], throw[1][1], 0.0];
            let cos_psi = axis[0] * c[0] + axis[1] * c[1];
            let s = r * cos_psi + (l * l - r * r * (1.0 - cos_psi * cos_psi)).sqrt();
            Cylinder {
                throw,
                axis,
                normal: [cg, -sg, 0.0],
                pin: [s * axis[0], s * axis[1], z],
                crank_pin: [r * c[0], r * c[1], z],
            }
        })
        .collect())
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    if name == housing::MODEL {
        return housing::build(&Params::parse(params, &housing_specs())?);
    }
    if name == flexible::MODEL {
        return flexible::build(&Params::parse(params, &flexible::specs())?);
    }
    if name == flexible::FLEXIBLE_DRIVE {
        return flexible::build_drive(&Params::parse(params, &flexible::drive_specs())?);
    }
    if !name.is_empty() && name != MODEL {
        return Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            &format!(
                "this plugin offers '{MODEL}', '{}', '{}' and '{}'",
                housing::MODEL,
                flexible::FLEXIBLE_DRIVE,
                flexible::MODEL
            ),
        ));
    }
    let p = Params::parse(params, &specs())?;
    let cyl = cylinders(&p)?;
    let n_cyl = cyl.len();
    let r = p.float("r");
    let (m_rod, m_piston) = (p.float("m_rod"), p.float("m_piston"));
    let mut names: Vec<String> = vec!["ux".into(), "uy".into(), "uz".into()];
    for i in 1..=n_cyl {
        names.extend([format!("x{i}"), format!("y{i}"), format!("z{i}")]);
    }
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let nd = refs.len();
    let mut s = MechanicalSystem::new(MODEL, &refs);
    s.dof_motion = (0..nd)
        .map(|d| {
            if d < 3 {
                MotionKind::Rotational
            } else {
                MotionKind::Translational
            }
        })
        .collect();
    // mass: J |u'|^2 / 2 + sum_i m_rod (|P_i'|^2 + P_i'.S_i' + |S_i'|^2) / 6
    // + m_piston |S_i'|^2 / 2, with P_i' = r R_i u' (R_i orthogonal)
    let mut mass = SparseMatrix::zeros(nd, nd);
    let ju = p.float("j_crank") + n_cyl as f64 * m_rod * r * r / 3.0;
    for a in 0..3 {
        mass.push(a, a, ju);
    }
    for (i, c) in cyl.iter().enumerate() {
        let o = 3 + 3 * i;
        for a in 0..3 {
            mass.push(o + a, o + a, m_rod / 3.0 + m_piston);
            for b in 0..3 {
                // u'^T (m_rod r / 6) R_i^T S_i'
                let v = m_rod * r / 6.0 * c.throw[b][a];
                if v != 0.0 {
                    mass.push(a, o + b, v);
                    mass.push(o + b, a, v);
                }
            }
        }
    }
    s.mass = mass;
    let mut damping = vec![p.float("c_crank"); 3];
    damping.extend(std::iter::repeat_n(p.float("c_piston"), 3 * n_cyl));
    s.damping = SparseMatrix::diagonal(&damping);
    // constraints in the deviations q from the reference configuration
    let mut g = PolyVector::zeros(2 + 3 * n_cyl, nd);
    // |u_ref + u|^2 - 1 = 2 u_ref . u + |u|^2, u_ref = (0, 1, 0)
    g.push(0, 2.0, &[(1, 1)]);
    for a in 0..3 {
        g.push(0, 1.0, &[(a, 2)]);
    }
    g.push(1, 1.0, &[(2, 1)]);
    for (i, c) in cyl.iter().enumerate() {
        let o = 3 + 3 * i;
        let eq = 2 + 3 * i;
        // |D_ref + delta|^2 - l^2 = 2 D_ref . delta + |delta|^2 with
        // delta = S_i - r R_i u, D_ref = S_ref - P_ref (|D_ref| = l)
        let d_ref: Vec<f64> = (0..3).map(|a| c.pin[a] - c.crank_pin[a]).collect();
        for (k, &dk) in d_ref.iter().enumerate() {
            let mut form = vec![(o + k, 1.0)];
            for a in 0..3 {
                let w = -r * c.throw[k][a];
                if w != 0.0 {
                    form.push((a, w));
                }
            }
            for &(var, w) in &form {
                if dk != 0.0 {
                    g.push(eq, 2.0 * dk * w, &[(var, 1)]);
                }
            }
            push_square(&mut g, eq, &form);
        }
        for a in 0..2 {
            if c.normal[a] != 0.0 {
                g.push(eq + 1, c.normal[a], &[(o + a, 1)]);
            }
        }
        g.push(eq + 2, 1.0, &[(o + 2, 1)]);
    }
    s.constraints = Some(Constraints::polynomial(g.canonical()));
    s.forcing = torque_harmonics(&p, nd, |tau| crank_torque(nd, tau));
    s.extra_outputs = strokes(&cyl, |i| 3 + 3 * i);
    Ok(s.into_model()?)
}

/// The torque's harmonics: `eps tau_mean` (multiple 0) and, when given,
/// `eps tau_amp cos(Omega t)`, each the generalized force `torque(tau)`
/// (`nd` equations in `2 nd` variables).
fn torque_harmonics(p: &Params, nd: usize, torque: impl Fn(f64) -> PolyVector) -> Vec<Harmonic> {
    let mut h = vec![Harmonic {
        multiple: 0.0,
        cos: torque(p.float("tau_mean")),
        sin: PolyVector::zeros(nd, 2 * nd),
    }];
    if p.float("tau_amp") != 0.0 {
        h.push(Harmonic {
            multiple: 1.0,
            cos: torque(p.float("tau_amp")),
            sin: PolyVector::zeros(nd, 2 * nd),
        });
    }
    h
}

/// The outputs `stroke<i>`: piston `i`'s displacement along its cylinder's
/// reference axis, its coordinates starting at `first(i)`.
fn strokes(cyl: &[Cylinder], first: impl Fn(usize) -> usize) -> Vec<(String, Vec<(usize, f64)>)> {
    cyl.iter()
        .enumerate()
        .map(|(i, c)| {
            let o = first(i);
            (
                format!("stroke{}", i + 1),
                vec![(o, c.axis[0]), (o + 1, c.axis[1])],
            )
        })
        .collect()
}

ssm_api::declare_plugin! {
    name: "crank-drive",
    description: "Crank drive in redundant 3-D natural coordinates (Stadlmayr, Witteveen & Steiner 2017, Sect. 4.1 stand-in)",
    models: models,
    build: build,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference configuration satisfies every rod constraint exactly
    /// (`|S_ref - P_ref| = l`) and the pistons sit on their cylinder axes.
    #[test]
    fn reference_configuration_is_assembled() {
        for (n, v) in [(1, 0.0), (4, 0.0), (8, 90.0), (3, 60.0)] {
            let specs = specs();
            let p = Params::parse(&format!("cylinders = {n}\nv_angle = {v}"), &specs).unwrap();
            for c in cylinders(&p).unwrap() {
                let d: f64 = (0..3)
                    .map(|a| (c.pin[a] - c.crank_pin[a]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!((d - 0.15).abs() < 1e-15, "{d}");
                let off = c.normal[0] * c.pin[0] + c.normal[1] * c.pin[1];
                assert!(off.abs() < 1e-15);
            }
        }
    }

    /// Out-of-range parameters are refused with the parameter named.
    #[test]
    fn bad_parameters_are_refused() {
        for (text, name) in [
            ("cylinders = 9", "cylinders"),
            ("cylinders = 0", "cylinders"),
            ("v_angle = 180", "v_angle"),
            ("l = 0.04", "l"),
            ("r = 0", "r"),
            ("c_crank = -1", "c_crank"),
            ("m_rod = nan", "m_rod"),
        ] {
            let e = build("", text).unwrap_err();
            assert!(e.to_string().contains(name), "{text}: {e}");
        }
    }
}
