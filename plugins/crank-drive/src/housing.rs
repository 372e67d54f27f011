//! Model `crank-drive-housing`: the crank drive of [`crate`] in an engine
//! housing that is a free rigid body on spring-damper mounts, the stand-in
//! for the V8 of Stadlmayr, Witteveen & Steiner (2017), Sect. 4.1, whose
//! housing vibrations make the cylinders' constraint directions tumble.
//!
//! # Model (natural coordinates, García de Jalón & Bayo, Ch. 2-3)
//! - **Housing**: its centre `h` (on the crank axis, midway along the
//!   cylinders) and its unit axes `e1, e2, e3` (`e3` the crank axis): 12
//!   coordinates, 6 constraints `e_i . e_j = delta_ij`. Mass `m_housing` at
//!   `h`, principal moments `i_xx, i_yy, i_zz` about `e1, e2, e3`; in
//!   natural coordinates the kinetic energy `m |h'|^2 / 2 + sum_j Jb_j
//!   |e_j'|^2 / 2` has the second moments `Jb_1 = (i_yy + i_zz - i_xx) / 2`
//!   (and cyclically) and a constant mass matrix.
//! - **Crankshaft**: turns about `e3` through `h`; its unit vectors `u`
//!   (along the first throw) and `w = e3 x u`: 6 coordinates, 5 constraints
//!   `|u|^2 = |w|^2 = 1`, `u . w = u . e3 = w . e3 = 0`. A thin flywheel of
//!   polar moment `j_crank` (diametral `j_crank / 2`): kinetic energy
//!   `j_crank (|u'|^2 + |w'|^2) / 4`, gyroscopic coupling with the housing
//!   included. Its mass is part of `m_housing`.
//! - **Crank pins**: `P_k = h + (z_k - z_c) e3 + r (cos beta_k u + sin beta_k w)`,
//!   linear in the coordinates.
//! - **Rods and pistons** as in [`crate`], the pistons `S_i` (3 coordinates
//!   each) guided in the housing: `n_i . (S_i - h) = 0` and
//!   `e3 . (S_i - h) = z_i - z_c` with the housing-fixed normal
//!   `n_i = cos gamma_i e1 - sin gamma_i e2`, and the rod `|S_i - P_i|^2 = l^2`:
//!   3 constraints each, bilinear in the coordinates.
//! - **Mounts**: three points `a_m` fixed in the housing (two engine mounts
//!   at `(+-mount_dx, mount_dy, -mount_dz)` and one gearbox mount at
//!   `(0, mount_dy, +mount_dz)` from `h`), each on a linear spring of
//!   stiffness `mount_k` and a damper `mount_k / mount_ratio` in each global
//!   direction: nine springs and nine dampers, as in the paper (75 N/mm; the
//!   paper's "damping ratio of 50" read as `k / c = 50 1/s`).
//! - **Loads**: the driving torque `eps (tau_mean + tau_amp cos(Omega t))`
//!   acts between the housing and the crankshaft (the engine's own torque),
//!   `Q_u = tau w` on the crank and `Q_e1 = -tau e2` on the housing (the
//!   reaction that rolls the engine on its mounts); the crank's viscous drag
//!   `c_crank` is against the ground (the driveline's load, absolute
//!   rotation), the pistons' `c_piston` too (absolute velocity, linear; the
//!   housing's motion is small against the strokes). No gravity: the
//!   reference configuration is the rest position of the pre-loaded mounts.
//!
//! `18 + 3 n` coordinates, `11 + 3 n` independent constraints, seven degrees
//! of freedom: the housing's six and the crank's rotation (the paper's V8:
//! 126 coordinates and 119 constraints in Euler parameters, the same seven).
//! The coordinates are deviations from the reference configuration
//! (`theta = 0`, housing axes along the global ones).
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint reduction
//! method for reduced order MBS models*, Multibody Syst. Dyn. (2017), Sect.
//! 4.1; J. García de Jalón, E. Bayo, *Kinematic and Dynamic Simulation of
//! Multibody Systems*, Springer (1994), Ch. 2-3.

use ssm_api::{ErrorKind, Model, MotionKind, PluginError, PolyVector, SparseMatrix};
use ssm_plugin_kit::{Constraints, MechanicalSystem, ParamSpec, Params};

use crate::{cylinders, invalid, strokes, torque_harmonics, Cylinder};

/// The model's name.
pub(crate) const MODEL: &str = "crank-drive-housing";

/// The housing's parameters (added to the crank drive's).
pub(crate) fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("m_housing", 150.0, "housing mass with the crankshaft [kg]"),
        ParamSpec::float("i_xx", 12.5, "housing moment of inertia about e1 [kg m^2]"),
        ParamSpec::float("i_yy", 12.5, "housing moment of inertia about e2 [kg m^2]"),
        ParamSpec::float(
            "i_zz",
            9.0,
            "housing moment of inertia about e3, the crank axis [kg m^2]",
        ),
        ParamSpec::float(
            "mount_k",
            75e3,
            "stiffness of each mount in each global direction [N/m]",
        ),
        ParamSpec::float(
            "mount_ratio",
            50.0,
            "stiffness-to-damping ratio k / c of the mounts [1/s]",
        ),
        ParamSpec::float(
            "mount_dx",
            0.25,
            "half the lateral spacing of the two engine mounts [m]",
        ),
        ParamSpec::float("mount_dy", -0.2, "height of the mounts above the crank axis [m]"),
        ParamSpec::float(
            "mount_dz",
            0.4,
            "axial distance of the engine mounts (front) and the gearbox mount (rear) from the centre [m]",
        ),
    ]
}

/// A vector of three coordinates: its first index and its reference value.
#[derive(Clone, Copy, Debug)]
struct Block {
    first: usize,
    reference: [f64; 3],
}

/// A linear combination `sum_k c_k v_k` of vector blocks.
type Combo = Vec<(Block, f64)>;

fn reference(a: &Combo) -> [f64; 3] {
    let mut v = [0.0; 3];
    for (b, c) in a {
        for (x, r) in v.iter_mut().zip(b.reference) {
            *x += c * r;
        }
    }
    v
}

/// Pushes the constraint `a . b = target` into equation `eq` of `g`, in the
/// deviations `q` from the reference values (`v = v_ref + q`): the linear
/// terms `a_ref . q_b + b_ref . q_a` and the bilinear `q_a . q_b`. Returns
/// the reference configuration's defect `(a . b)_ref - target` (zero: the
/// constraint has no constant term).
fn push_dot(g: &mut PolyVector, eq: usize, a: &Combo, b: &Combo, target: f64) -> f64 {
    let (ar, br) = (reference(a), reference(b));
    for (x, y) in [(a, br), (b, ar)] {
        for (blk, c) in x {
            for (k, yk) in y.iter().enumerate() {
                g.push(eq, c * yk, &[(blk.first + k, 1)]);
            }
        }
    }
    for (ba, ca) in a {
        for (bb, cb) in b {
            for k in 0..3 {
                g.push(eq, ca * cb, &[(ba.first + k, 1), (bb.first + k, 1)]);
            }
        }
    }
    (0..3).map(|k| ar[k] * br[k]).sum::<f64>() - target
}

/// Adds the quadratic form `w a' . b'` to `q'^T M q' / 2` (or `w a . b` to
/// `q^T K q / 2`): `M += w (T_a^T T_b + T_b^T T_a)` for the linear maps
/// `T` of the combinations.
fn add_form(m: &mut [Vec<f64>], w: f64, a: &Combo, b: &Combo) {
    for (ba, ca) in a {
        for (bb, cb) in b {
            for k in 0..3 {
                let (i, j) = (ba.first + k, bb.first + k);
                m[i][j] += w * ca * cb;
                m[j][i] += w * ca * cb;
            }
        }
    }
}

fn sparse(m: &[Vec<f64>]) -> SparseMatrix {
    let mut s = SparseMatrix::zeros(m.len(), m.len());
    for (i, row) in m.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            s.push(i, j, v);
        }
    }
    s
}

/// The positive housing parameters, and the second moments
/// `Jb = ((i_yy + i_zz - i_xx) / 2, ...)` (positive: the triangle
/// inequality of a rigid body's principal moments).
fn second_moments(p: &Params) -> Result<[f64; 3], PluginError> {
    super::positive(
        p,
        &[
            "m_housing",
            "i_xx",
            "i_yy",
            "i_zz",
            "mount_k",
            "mount_ratio",
        ],
    )?;
    if p.float("mount_dx") == 0.0 || p.float("mount_dz") == 0.0 {
        return Err(invalid(
            "mount_dx",
            "the mounts must span the housing: mount_dx and mount_dz nonzero (else the housing can turn freely about an axis through them)",
        ));
    }
    let i = [p.float("i_xx"), p.float("i_yy"), p.float("i_zz")];
    let jb = [
        (i[1] + i[2] - i[0]) / 2.0,
        (i[2] + i[0] - i[1]) / 2.0,
        (i[0] + i[1] - i[2]) / 2.0,
    ];
    if let Some(k) = jb.iter().position(|&j| j <= 0.0) {
        let name = ["i_xx", "i_yy", "i_zz"][k];
        return Err(invalid(
            name,
            &format!(
                "the principal moments {i:?} violate the triangle inequality of a rigid body: {name} must be below the sum of the other two"
            ),
        ));
    }
    Ok(jb)
}

/// The model `crank-drive-housing` from parsed parameters (the crank
/// drive's and [`specs`]).
pub(crate) fn build(p: &Params) -> Result<Model, PluginError> {
    Ok(system(p)?.into_model()?)
}

/// The mechanical system of [`build`].
fn system(p: &Params) -> Result<MechanicalSystem, PluginError> {
    let cyl = cylinders(p)?;
    let jb = second_moments(p)?;
    let n_cyl = cyl.len();
    let (r, l) = (p.float("r"), p.float("l"));
    let zc = p.float("pitch") * (n_cyl - 1) as f64 / 2.0;
    let mut names: Vec<String> = Vec::new();
    let mut motion = Vec::new();
    let mut block = |name: &str, reference: [f64; 3], kind: MotionKind| {
        let first = names.len();
        for c in ["x", "y", "z"] {
            names.push(format!("{name}{c}"));
            motion.push(kind);
        }
        Block { first, reference }
    };
    let h = block("h", [0.0, 0.0, zc], MotionKind::Translational);
    let e = [
        block("e1", [1.0, 0.0, 0.0], MotionKind::Rotational),
        block("e2", [0.0, 1.0, 0.0], MotionKind::Rotational),
        block("e3", [0.0, 0.0, 1.0], MotionKind::Rotational),
    ];
    let u = block("u", [0.0, 1.0, 0.0], MotionKind::Rotational);
    let w = block("w", [-1.0, 0.0, 0.0], MotionKind::Rotational);
    let pistons: Vec<Block> = cyl
        .iter()
        .enumerate()
        .map(|(i, c)| block(&format!("s{}", i + 1), c.pin, MotionKind::Translational))
        .collect();
    let nd = names.len();
    let crank_pin = |c: &Cylinder| -> Combo {
        // R_z(beta) (0, 1, 0) = cos beta u_ref + sin beta w_ref at theta = 0
        let (cb, sb) = (c.throw[0][0], c.throw[1][0]);
        vec![(h, 1.0), (e[2], c.pin[2] - zc), (u, r * cb), (w, r * sb)]
    };
    // kinetic energy
    let mut mass = vec![vec![0.0; nd]; nd];
    add_form(
        &mut mass,
        p.float("m_housing") / 2.0,
        &vec![(h, 1.0)],
        &vec![(h, 1.0)],
    );
    for (ej, j) in e.iter().zip(jb) {
        add_form(&mut mass, j / 2.0, &vec![(*ej, 1.0)], &vec![(*ej, 1.0)]);
    }
    let j4 = p.float("j_crank") / 4.0;
    add_form(&mut mass, j4, &vec![(u, 1.0)], &vec![(u, 1.0)]);
    add_form(&mut mass, j4, &vec![(w, 1.0)], &vec![(w, 1.0)]);
    let (m_rod, m_piston) = (p.float("m_rod"), p.float("m_piston"));
    for (c, s) in cyl.iter().zip(&pistons) {
        let pin = crank_pin(c);
        let sv = vec![(*s, 1.0)];
        add_form(&mut mass, m_rod / 6.0, &pin, &pin);
        add_form(&mut mass, m_rod / 6.0, &pin, &sv);
        add_form(&mut mass, m_rod / 6.0 + m_piston / 2.0, &sv, &sv);
    }
    // mounts: energy k |q_m|^2 / 2, dissipation c |q_m'|^2 / 2
    let (k, ratio) = (p.float("mount_k"), p.float("mount_ratio"));
    let (dx, dy, dz) = (
        p.float("mount_dx"),
        p.float("mount_dy"),
        p.float("mount_dz"),
    );
    let mut stiffness = vec![vec![0.0; nd]; nd];
    let mut damping = vec![vec![0.0; nd]; nd];
    for a in [[dx, dy, -dz], [-dx, dy, -dz], [0.0, dy, dz]] {
        let point: Combo = std::iter::once((h, 1.0))
            .chain(e.iter().zip(a).map(|(ej, aj)| (*ej, aj)))
            .collect();
        add_form(&mut stiffness, k / 2.0, &point, &point);
        add_form(&mut damping, k / ratio / 2.0, &point, &point);
    }
    let c_crank = p.float("c_crank") / 4.0;
    add_form(&mut damping, c_crank, &vec![(u, 1.0)], &vec![(u, 1.0)]);
    add_form(&mut damping, c_crank, &vec![(w, 1.0)], &vec![(w, 1.0)]);
    for s in &pistons {
        add_form(
            &mut damping,
            p.float("c_piston") / 2.0,
            &vec![(*s, 1.0)],
            &vec![(*s, 1.0)],
        );
    }
    // constraints, each `a . b = (a . b)_ref` (held by the reference)
    let mut g = PolyVector::zeros(11 + 3 * n_cyl, nd);
    let one = |b: Block| vec![(b, 1.0)];
    let mut eq = 0;
    let mut defect = 0.0f64;
    let mut dot = |g: &mut PolyVector, a: &Combo, b: &Combo, target: f64| {
        defect = defect.max(push_dot(g, eq, a, b, target).abs());
        eq += 1;
    };
    for i in 0..3 {
        for j in i..3 {
            dot(&mut g, &one(e[i]), &one(e[j]), f64::from(u8::from(i == j)));
        }
    }
    dot(&mut g, &one(u), &one(u), 1.0);
    dot(&mut g, &one(w), &one(w), 1.0);
    dot(&mut g, &one(u), &one(w), 0.0);
    dot(&mut g, &one(u), &one(e[2]), 0.0);
    dot(&mut g, &one(w), &one(e[2]), 0.0);
    for (c, s) in cyl.iter().zip(&pistons) {
        let mut rod: Combo = vec![(*s, 1.0)];
        rod.extend(crank_pin(c).into_iter().map(|(b, x)| (b, -x)));
        dot(&mut g, &rod, &rod, l * l);
        let rel = vec![(*s, 1.0), (h, -1.0)];
        let (sg, cg) = (c.axis[0], c.axis[1]);
        dot(&mut g, &vec![(e[0], cg), (e[1], -sg)], &rel, 0.0);
        dot(&mut g, &one(e[2]), &rel, c.pin[2] - zc);
    }
    if defect > 1e-12 * (1.0 + l * l) {
        return Err(PluginError::new(
            ErrorKind::BuildFailed,
            MODEL,
            &format!("the reference configuration violates a constraint by {defect:e}"),
        ));
    }
    let mut s = MechanicalSystem::new(MODEL, &names.iter().map(String::as_str).collect::<Vec<_>>());
    s.dof_motion = motion;
    s.mass = sparse(&mass);
    s.stiffness = sparse(&stiffness);
    s.damping = sparse(&damping);
    s.constraints = Some(Constraints::polynomial(g.canonical()));
    // the torque pair: Q_u = tau (w_ref + q_w), Q_e1 = -tau (e2_ref + q_e2)
    let torque = |tau: f64| {
        let mut cos = PolyVector::zeros(nd, 2 * nd);
        for (target, source, sign) in [(u, w, 1.0), (e[0], e[1], -1.0)] {
            for k in 0..3 {
                cos.push(target.first + k, sign * tau * source.reference[k], &[]);
                cos.push(target.first + k, sign * tau, &[(source.first + k, 1)]);
            }
        }
        cos
    };
    s.forcing = torque_harmonics(p, nd, torque);
    s.extra_outputs = strokes(&cyl, |i| pistons[i].first);
    // small rotations of the housing about the global axes
    for (name, vector, component) in [("rot_x", 1, 2), ("rot_y", 2, 0), ("rot_z", 0, 1)] {
        s.extra_outputs
            .push((name.into(), vec![(e[vector].first + component, 1.0)]));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(text: &str) -> Params {
        Params::parse(text, &crate::housing_specs()).unwrap()
    }

    /// `v^T m v` of a sparse matrix (duplicates summed).
    fn form(m: &SparseMatrix, v: &[f64]) -> f64 {
        m.iter().map(|(i, j, x)| v[i] * x * v[j]).sum()
    }

    fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        (0..3).map(|k| a[k] * b[k]).sum()
    }

    fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }

    /// The reference positions of the coordinate blocks, in their order
    /// (h, e1, e2, e3, u, w, s1, ...), and whether each is a point.
    fn blocks(p: &Params) -> Vec<([f64; 3], bool)> {
        let cyl = cylinders(p).unwrap();
        let zc = p.float("pitch") * (cyl.len() - 1) as f64 / 2.0;
        let mut b = vec![
            ([0.0, 0.0, zc], true),
            ([1.0, 0.0, 0.0], false),
            ([0.0, 1.0, 0.0], false),
            ([0.0, 0.0, 1.0], false),
            ([0.0, 1.0, 0.0], false),
            ([-1.0, 0.0, 0.0], false),
        ];
        b.extend(cyl.iter().map(|c| (c.pin, true)));
        b
    }

    /// The coordinate velocities of the whole engine moving rigidly (crank
    /// locked) with velocity `v` of the housing centre and angular velocity
    /// `omega`.
    fn rigid(p: &Params, v: [f64; 3], omega: [f64; 3]) -> Vec<f64> {
        let b = blocks(p);
        let h = b[0].0;
        b.iter()
            .flat_map(|&(x, point)| {
                if point {
                    let r = cross(omega, sub(x, h));
                    [v[0] + r[0], v[1] + r[1], v[2] + r[2]]
                } else {
                    cross(omega, x)
                }
            })
            .collect()
    }

    /// The six unit rigid motions of the whole engine: translations along
    /// and rotations about the global axes.
    fn unit_rigid_motions(p: &Params) -> Vec<Vec<f64>> {
        (0..6)
            .map(|k| {
                let mut v = [0.0; 3];
                let mut omega = [0.0; 3];
                if k < 3 {
                    v[k] = 1.0;
                } else {
                    omega[k - 3] = 1.0;
                }
                rigid(p, v, omega)
            })
            .collect()
    }

    /// The linear part of the constraints, `C_q(0)` (`n_c` rows).
    fn jacobian(s: &MechanicalSystem) -> Vec<Vec<f64>> {
        let g = &s.constraints.as_ref().unwrap().g;
        let mut c = vec![vec![0.0; s.n_dof()]; g.n_eq as usize];
        for t in g.terms.iter().filter(|t| t.degree() == 1) {
            c[t.eq as usize][t.factors[0].var as usize] += t.coeff;
        }
        c
    }

    /// Rank of `rows` by Gram-Schmidt with a relative tolerance.
    fn rank(rows: &[Vec<f64>]) -> usize {
        let mut basis: Vec<Vec<f64>> = Vec::new();
        for r in rows {
            let mut v = r.clone();
            for _ in 0..2 {
                for b in &basis {
                    let d: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
                    v.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
                }
            }
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            let scale = r.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm > 1e-10 * scale {
                basis.push(v.iter().map(|x| x / norm).collect());
            }
        }
        basis.len()
    }

    /// The constraints are independent at the reference configuration
    /// (also of the V engines, whose rods and guides meet at angles) and
    /// leave exactly the paper's seven degrees of freedom: `C_q(0)` has full
    /// row rank `11 + 3 n` in `18 + 3 n` coordinates, and the six rigid
    /// motions of the whole engine lie in its null space (the guides move
    /// with the housing; on the fixed-axis model they would not).
    #[test]
    fn seven_degrees_of_freedom_and_rigid_motions_are_free() {
        for text in [
            "cylinders = 8\nv_angle = 90",
            "cylinders = 4",
            "cylinders = 3\nv_angle = 60",
        ] {
            let p = params(text);
            let s = system(&p).unwrap();
            let c = jacobian(&s);
            let n_cyl = cylinders(&p).unwrap().len();
            assert_eq!(s.n_dof(), 18 + 3 * n_cyl);
            assert_eq!(c.len(), 11 + 3 * n_cyl);
            assert_eq!(rank(&c), c.len(), "{text}");
            for (k, q) in unit_rigid_motions(&p).iter().enumerate() {
                for (i, row) in c.iter().enumerate() {
                    let r: f64 = row.iter().zip(q).map(|(a, b)| a * b).sum();
                    assert!(r.abs() < 1e-14, "{text}: motion {k}, constraint {i}: {r:e}");
                }
            }
        }
    }

    /// The natural-coordinate mass matrix gives the kinetic energy of rigid
    /// motions of the whole engine computed body by body from the geometry:
    /// `m_total |v|^2 / 2` for translations, and for rotations about each
    /// global axis through the centre the housing's principal moment, the
    /// flywheel's (polar `j_crank` about the crank axis, diametral
    /// `j_crank / 2`), the pistons' point masses and the rods' kinetic
    /// energy integrated along their length (2-point Gauss, exact for the
    /// quadratic integrand).
    #[test]
    fn mass_matrix_gives_the_rigid_bodies_kinetic_energy() {
        let p =
            params("cylinders = 8\nv_angle = 90\nm_housing = 130\ni_xx = 11\ni_yy = 13\ni_zz = 7");
        let s = system(&p).unwrap();
        let cyl = cylinders(&p).unwrap();
        let (m_rod, m_piston) = (p.float("m_rod"), p.float("m_piston"));
        let m_total = p.float("m_housing") + 8.0 * (m_rod + m_piston);
        let v = [0.3, -1.1, 0.7];
        let q = rigid(&p, v, [0.0; 3]);
        let expected = m_total * dot(v, v);
        assert!((form(&s.mass, &q) - expected).abs() < 1e-12 * expected);
        let h = blocks(&p)[0].0;
        let j = p.float("j_crank");
        let gauss = [0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt()];
        for axis in 0..3 {
            let mut omega = [0.0; 3];
            omega[axis] = 1.0;
            let moments = [p.float("i_xx"), p.float("i_yy"), p.float("i_zz")];
            let mut energy = moments[axis] + if axis == 2 { j } else { j / 2.0 };
            for c in &cyl {
                let pin = [c.crank_pin[0], c.crank_pin[1], c.pin[2]];
                let vp = cross(omega, sub(pin, h));
                let vs = cross(omega, sub(c.pin, h));
                energy += m_piston * dot(vs, vs);
                for g in gauss {
                    let vx: Vec<f64> = (0..3).map(|k| (1.0 - g) * vp[k] + g * vs[k]).collect();
                    energy += m_rod * 0.5 * vx.iter().map(|x| x * x).sum::<f64>();
                }
            }
            let q = rigid(&p, [0.0; 3], omega);
            let got = form(&s.mass, &q);
            assert!(
                (got - energy).abs() < 1e-12 * energy,
                "axis {axis}: {got} against {energy}"
            );
        }
    }

    /// The mounts' springs resist rigid motions with the energy of nine
    /// global springs at the three mount points, `k sum_m |v + omega x a_m|^2`
    /// (twice the potential energy), for translations, rotations and both.
    #[test]
    fn mounts_are_nine_springs_at_three_points() {
        let p = params("cylinders = 8\nv_angle = 90\nmount_k = 8e4\nmount_ratio = 40");
        let s = system(&p).unwrap();
        let (dx, dy, dz) = (
            p.float("mount_dx"),
            p.float("mount_dy"),
            p.float("mount_dz"),
        );
        let mounts = [[dx, dy, -dz], [-dx, dy, -dz], [0.0, dy, dz]];
        for (v, omega) in [
            ([1.0, 0.0, 0.0], [0.0; 3]),
            ([0.0, 1.0, 0.0], [0.0; 3]),
            ([0.2, -0.4, 0.9], [0.3, 0.1, -0.5]),
            ([0.0; 3], [0.0, 0.0, 1.0]),
        ] {
            let q = rigid(&p, v, omega);
            let expected: f64 = mounts
                .iter()
                .map(|a| {
                    let x = cross(omega, *a);
                    8e4 * dot(
                        [v[0] + x[0], v[1] + x[1], v[2] + x[2]],
                        [v[0] + x[0], v[1] + x[1], v[2] + x[2]],
                    )
                })
                .sum();
            let got = form(&s.stiffness, &q);
            assert!(
                (got - expected).abs() < 1e-10 * expected,
                "{got} against {expected}"
            );
        }
    }

    /// The torque acts between the crank and the housing: it does the work
    /// `tau theta'` on the crank's spin and none on any rigid motion of the
    /// whole engine (an internal torque).
    #[test]
    fn the_torque_is_internal() {
        let p = params("cylinders = 8\nv_angle = 90\ntau_mean = 2.5");
        let s = system(&p).unwrap();
        let f = &s.forcing[0].cos;
        let nd = s.n_dof();
        let mut q0 = vec![0.0; nd];
        for t in f.terms.iter().filter(|t| t.degree() == 0) {
            q0[t.eq as usize] += t.coeff;
        }
        for (k, q) in unit_rigid_motions(&p).iter().enumerate() {
            let power: f64 = q0.iter().zip(q).map(|(a, b)| a * b).sum();
            assert!(power.abs() < 1e-14, "motion {k}: {power}");
        }
        // the crank's spin at theta' = 1: u' = w, w' = -u
        let mut spin = vec![0.0; nd];
        spin[12..15].copy_from_slice(&[-1.0, 0.0, 0.0]);
        spin[15..18].copy_from_slice(&[0.0, -1.0, 0.0]);
        let power: f64 = q0.iter().zip(&spin).map(|(a, b)| a * b).sum();
        assert!((power - 2.5).abs() < 1e-14, "{power}");
    }

    /// Housing parameters out of range are refused with their names.
    #[test]
    fn bad_housing_parameters_are_refused() {
        for (text, name) in [
            ("m_housing = 0", "m_housing"),
            ("i_zz = 30", "i_zz"),
            ("mount_k = -1", "mount_k"),
            ("mount_ratio = nan", "mount_ratio"),
            ("mount_dx = 0", "mount_dx"),
        ] {
            let e = crate::build(MODEL, text).unwrap_err();
            assert!(e.to_string().contains(name), "{text}: {e}");
        }
    }
}
