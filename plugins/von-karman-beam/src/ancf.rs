//! The planar beam element in absolute nodal coordinates (ANCF, gradient
//! deficient): two nodes, four coordinates per node, the position `r` and the
//! slope `r' = dr/dx` in the plane, local order
//! `q = (x1, y1, x1', y1', x2, y2, x2', y2')`, each component interpolated by
//! the cubic Hermite functions of [`super::element`] in the undeformed arc
//! length `x`.
//!
//! The coordinates are deviations from a straight reference configuration of
//! unit tangent `t` (`r_ref' = t` everywhere). With the Green axial strain
//! `e = (|r'|^2 - 1) / 2 = t.d + |d|^2 / 2`, `d = r' - t` the slope deviation,
//! and the curvature measured by `r''` (the linear bending model of the
//! references, exact for small strains), the strain energy is
//!
//! `U = int_0^L [ EA/2 e^2 + EI/2 |r''|^2 ] dx`,
//!
//! and the internal force `dU/dq = K q + f2(q) + f3(q)`. With `a_k(x)` the
//! Hermite slopes of unknown `k` of component `c`,
//!
//! - `K = int EA (a t)(a t)^T + EI r''-terms dx` (axial along `t`, bending per
//!   component),
//! - `f2_(c,k) = int EA a_k [ (t.d) d_c + |d|^2 t_c / 2 ] dx`,
//! - `f3_(c,k) = int EA a_k |d|^2 d_c / 2 dx`.
//!
//! The integrands are polynomials of degree at most 8 in `x`; the 5-point
//! Gauss rule integrates them exactly. The mass `int rhoA N^T N dx` is
//! constant: absolute coordinates carry the rigid rotations of the element in
//! its coordinates, not in its mass matrix, and a rigid motion of the element
//! (rotation and translation of every node, slopes rotated) leaves `e = 0`
//! and `r'' = 0`, hence no elastic force. That is why a flexible member of a
//! multibody model in natural coordinates is built from this element rather
//! than in a floating frame of reference: the mass matrix stays constant and
//! the forces polynomial, which the model interface requires.
//!
//! # References
//! - A. A. Shabana, *Dynamics of Multibody Systems*, 4th ed., Cambridge
//!   (2013), Ch. 7 (the absolute nodal coordinate formulation).
//! - D. Garcia-Vallejo, J. Mayo, J. L. Escalona, J. Dominguez, *Efficient
//!   evaluation of the elastic forces and the Jacobian in the absolute nodal
//!   coordinate formulation*, Nonlinear Dyn. 35 (2004) 313-329 (the
//!   polynomial form of the elastic forces).
//! - J. T. Sopanen, A. M. Mikkola, *Description of elastic forces in absolute
//!   nodal coordinate formulation*, Nonlinear Dyn. 34 (2003) 53-74 (the
//!   axial and bending strain measures).

use super::element::{hermite, hermite_curvature, hermite_slope, LocalTerm, Section, GAUSS5};

/// Local index of component `c` (0: x, 1: y) of Hermite unknown `k`
/// (0: node 1 position, 1: node 1 slope, 2: node 2 position, 3: node 2
/// slope).
pub fn local(c: usize, k: usize) -> usize {
    (k / 2) * 4 + (k % 2) * 2 + c
}

/// A two-node planar ANCF beam element of undeformed length `length` whose
/// reference configuration is straight with unit tangent `tangent`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AncfElement {
    /// Undeformed length.
    pub length: f64,
    /// Section and material.
    pub section: Section,
    /// Unit tangent `t` of the reference configuration.
    pub tangent: [f64; 2],
}

/// A linear form `sum coeff q[var]` over the local unknowns.
type Form = Vec<(usize, f64)>;

impl AncfElement {
    /// Gauss points in `x` with weights scaled to the element length.
    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        GAUSS5.iter().map(|&(xi, w)| (xi, w * self.length))
    }

    /// `int s (f^T f) dx` per component, for the Hermite functions `f(xi)`.
    fn per_component(&self, f: impl Fn(f64) -> [f64; 4], s: f64) -> [[f64; 8]; 8] {
        let mut m = [[0.0; 8]; 8];
        for (xi, w) in self.points() {
            let v = f(xi);
            for c in 0..2 {
                for k in 0..4 {
                    for j in 0..4 {
                        m[local(c, k)][local(c, j)] += w * s * v[k] * v[j];
                    }
                }
            }
        }
        m
    }

    /// Consistent mass matrix `int rhoA N^T N dx`.
    pub fn mass(&self) -> [[f64; 8]; 8] {
        let l = self.length;
        self.per_component(|xi| hermite(xi, l), self.section.rho_a)
    }

    /// Linear stiffness at the reference: `int EI N''^T N'' dx` per component
    /// plus the axial `int EA (t.d)(t.d)` part.
    pub fn stiffness(&self) -> [[f64; 8]; 8] {
        let l = self.length;
        let mut k = self.per_component(|xi| hermite_curvature(xi, l), self.section.ei);
        let t = self.tangent;
        for (xi, w) in self.points() {
            let a = hermite_slope(xi, l);
            for (ci, &ti) in t.iter().enumerate() {
                for (cj, &tj) in t.iter().enumerate() {
                    for p in 0..4 {
                        for r in 0..4 {
                            k[local(ci, p)][local(cj, r)] +=
                                w * self.section.ea * a[p] * a[r] * ti * tj;
                        }
                    }
                }
            }
        }
        k
    }

    /// The slope deviation `d_c = sum_k a_k q_(c,k)` at `xi` as two forms,
    /// and the Hermite slopes `a`.
    fn slope_forms(&self, xi: f64) -> ([Form; 2], [f64; 4]) {
        let a = hermite_slope(xi, self.length);
        let form = |c: usize| (0..4).map(|k| (local(c, k), a[k])).collect::<Form>();
        ([form(0), form(1)], a)
    }

    /// The quadratic and cubic internal forces `f2 + f3` as monomials in the
    /// local unknowns (exact, summed over the Gauss points; repeated
    /// monomials are left to the caller's canonical form).
    pub fn nonlinear_force(&self) -> Vec<LocalTerm> {
        let t = self.tangent;
        let ea = self.section.ea;
        let mut out = Vec::new();
        for (xi, w) in self.points() {
            let (d, a) = self.slope_forms(xi);
            let td: Form = d[0]
                .iter()
                .map(|&(v, c)| (v, c * t[0]))
                .chain(d[1].iter().map(|&(v, c)| (v, c * t[1])))
                .collect();
            for c in 0..2 {
                for (k, &ak) in a.iter().enumerate() {
                    let eq = local(c, k);
                    let s = w * ea * ak;
                    // (t.d) d_c
                    product(&mut out, eq, s, &[&td, &d[c]]);
                    // |d|^2 t_c / 2 and |d|^2 d_c / 2
                    for dd in &d {
                        product(&mut out, eq, 0.5 * s * t[c], &[dd, dd]);
                        product(&mut out, eq, 0.5 * s, &[dd, dd, &d[c]]);
                    }
                }
            }
        }
        out
    }

    /// The nonlinear part of the strain-rate (Kelvin-Voigt) damping force
    /// `beta K_T(q) q'`, `K_T = K + d(f2 + f3)/dq` the tangent stiffness:
    /// `beta d(f2 + f3)/dq q'` as monomials in the local unknowns `0..8` and
    /// their velocities `8..16` (the linear part is `beta K q'`). Unlike
    /// `beta K q'` alone, it vanishes under any rigid motion of the element
    /// (the elastic force vanishes along rigid motions, so its derivative
    /// along them does), so it damps deformation rates only.
    pub fn strain_rate_damping(&self, beta: f64) -> Vec<LocalTerm> {
        let mut out = Vec::new();
        if beta == 0.0 {
            return out;
        }
        for t in self.nonlinear_force() {
            for (i, &v) in t.vars.iter().enumerate() {
                // d/dq_v of the monomial: one factor q_v fewer (the repeats
                // of v each contribute once), times q_v'
                let mut vars: Vec<usize> = t.vars[..i]
                    .iter()
                    .chain(&t.vars[i + 1..])
                    .copied()
                    .collect();
                vars.push(v + 8);
                out.push(LocalTerm {
                    eq: t.eq,
                    coeff: beta * t.coeff,
                    vars,
                });
            }
        }
        out
    }

    /// The strain energy at the local deviations `q`, by the same rule
    /// (for checks).
    pub fn strain_energy(&self, q: &[f64; 8]) -> f64 {
        let l = self.length;
        let t = self.tangent;
        let mut u = 0.0;
        for (xi, w) in self.points() {
            let (a, b) = (hermite_slope(xi, l), hermite_curvature(xi, l));
            let mut d = [0.0; 2];
            let mut curv = [0.0; 2];
            for c in 0..2 {
                for k in 0..4 {
                    d[c] += a[k] * q[local(c, k)];
                    curv[c] += b[k] * q[local(c, k)];
                }
            }
            let e = t[0] * d[0] + t[1] * d[1] + 0.5 * (d[0] * d[0] + d[1] * d[1]);
            u += w
                * (0.5 * self.section.ea * e * e
                    + 0.5 * self.section.ei * (curv[0] * curv[0] + curv[1] * curv[1]));
        }
        u
    }
}

/// Pushes `scale * prod forms` expanded into monomials of equation `eq`.
fn product(out: &mut Vec<LocalTerm>, eq: usize, scale: f64, forms: &[&Form]) {
    fn rec(
        out: &mut Vec<LocalTerm>,
        eq: usize,
        coeff: f64,
        forms: &[&Form],
        vars: &mut Vec<usize>,
    ) {
        match forms.split_first() {
            None => {
                let mut v = vars.clone();
                v.sort_unstable();
                out.push(LocalTerm { eq, coeff, vars: v });
            }
            Some((first, rest)) => {
                for &(var, c) in first.iter() {
                    if c != 0.0 {
                        vars.push(var);
                        rec(out, eq, coeff * c, rest, vars);
                        vars.pop();
                    }
                }
            }
        }
    }
    if scale != 0.0 {
        rec(out, eq, scale, forms, &mut Vec::with_capacity(forms.len()));
    }
}

/// `sum` of `terms` at the local deviations `q`.
pub fn evaluate(terms: &[LocalTerm], q: &[f64; 8]) -> [f64; 8] {
    let mut f = [0.0; 8];
    for t in terms {
        f[t.eq] += t.coeff * t.vars.iter().map(|&v| q[v]).product::<f64>();
    }
    f
}

/// The factors `S` of the length-scaled unknowns `xi`, `q = S xi`: one for
/// the positions, `1 / L` for the slopes (`xi = L r'`, a length like the
/// positions). In slopes the unknowns' mass is `rho A L^3 / 105`, so the
/// round-off floor of their accelerations (the axial force `EA e` carries
/// an absolute error of order `EA` times the machine epsilon) grows as
/// `L^-3` under mesh refinement, which stalls a Newton iteration on fine
/// meshes; scaled, it grows as `L^-2` and the slope unknowns' accelerations
/// are of the positions' size.
pub fn slope_scaling(length: f64) -> [f64; 8] {
    let l = 1.0 / length;
    [1.0, 1.0, l, l, 1.0, 1.0, l, l]
}

/// `S A S` for the diagonal `S` of [`slope_scaling`]: the mass or stiffness
/// in the scaled unknowns.
pub fn scaled_matrix(a: &[[f64; 8]; 8], s: &[f64; 8]) -> [[f64; 8]; 8] {
    let mut out = *a;
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v *= s[i] * s[j];
        }
    }
    out
}

/// The terms of `S f(S xi)` (generalized forces on the scaled unknowns);
/// local unknowns `8..16` are velocities, scaled like their coordinates.
pub fn scaled_terms(terms: &[LocalTerm], s: &[f64; 8]) -> Vec<LocalTerm> {
    terms
        .iter()
        .map(|t| LocalTerm {
            eq: t.eq,
            coeff: t.coeff * s[t.eq] * t.vars.iter().map(|&v| s[v % 8]).product::<f64>(),
            vars: t.vars.clone(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn element(tangent: [f64; 2]) -> AncfElement {
        AncfElement {
            length: 0.3,
            section: Section {
                ea: 7.0,
                ei: 0.4,
                rho_a: 2.0,
            },
            tangent,
        }
    }

    fn force(e: &AncfElement, q: &[f64; 8]) -> [f64; 8] {
        let k = e.stiffness();
        let mut f = evaluate(&e.nonlinear_force(), q);
        for (i, fi) in f.iter_mut().enumerate() {
            *fi += (0..8).map(|j| k[i][j] * q[j]).sum::<f64>();
        }
        f
    }

    /// Reference: the strain energy evaluated directly; its central
    /// differences (step 1e-5, error of order 1e-10 of the force) equal
    /// `K q + f2 + f3` at a large deformation.
    #[test]
    fn internal_force_is_the_gradient_of_the_strain_energy() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let e = element([s, s]);
        let q = [0.03, -0.02, 0.2, -0.15, 0.05, 0.04, -0.1, 0.3];
        let f = force(&e, &q);
        let scale = f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for i in 0..8 {
            let (mut p, mut m) = (q, q);
            p[i] += 1e-5;
            m[i] -= 1e-5;
            let g = (e.strain_energy(&p) - e.strain_energy(&m)) / 2e-5;
            assert!((g - f[i]).abs() < 1e-8 * scale, "{i}: {g} {}", f[i]);
        }
    }

    /// The element rotated by 1.2 rad about its first node and moved: the
    /// deviations `q` of that configuration, and the velocities `q'` of the
    /// rigid motion through it (unit angular velocity, a translation rate).
    fn rigid(t: [f64; 2]) -> ([f64; 8], [f64; 8]) {
        let (s, c) = 1.2_f64.sin_cos();
        let rot = |v: [f64; 2]| [c * v[0] - s * v[1], s * v[0] + c * v[1]];
        let spin = |v: [f64; 2]| [-s * v[0] - c * v[1], c * v[0] - s * v[1]];
        let (p2, t2) = (rot([0.3 * t[0], 0.3 * t[1]]), rot(t));
        let (dp2, dt2) = (spin([0.3 * t[0], 0.3 * t[1]]), spin(t));
        let (shift, rate) = ([0.4, -0.7], [2.0, 0.5]);
        let q = [
            shift[0],
            shift[1],
            t2[0] - t[0],
            t2[1] - t[1],
            shift[0] + p2[0] - 0.3 * t[0],
            shift[1] + p2[1] - 0.3 * t[1],
            t2[0] - t[0],
            t2[1] - t[1],
        ];
        let v = [
            rate[0],
            rate[1],
            dt2[0],
            dt2[1],
            rate[0] + dp2[0],
            rate[1] + dp2[1],
            dt2[0],
            dt2[1],
        ];
        (q, v)
    }

    /// Reference: a rigid motion strains nothing. The reference element
    /// rotated by 1.2 rad about its first node and moved leaves no elastic
    /// force (to rounding: 1e-13 of the axial stiffness), and the
    /// strain-rate damping of a rigid motion through it vanishes too (while
    /// `beta K q'` alone does not: the rotated element's rigid velocity is
    /// not in the null space of the reference stiffness).
    #[test]
    fn a_rigid_motion_leaves_no_elastic_force() {
        let t = [0.6, 0.8];
        let e = element(t);
        let (q, v) = rigid(t);
        let f = force(&e, &q);
        assert!(f.iter().all(|x| x.abs() < 1e-13 * 7.0), "{f:?}");
        let beta = 0.01;
        let k = e.stiffness();
        let mut d = [0.0; 8];
        for t in e.strain_rate_damping(beta) {
            d[t.eq] += t.coeff
                * t.vars
                    .iter()
                    .map(|&i| if i < 8 { q[i] } else { v[i - 8] })
                    .product::<f64>();
        }
        let linear: Vec<f64> = (0..8)
            .map(|i| beta * (0..8).map(|j| k[i][j] * v[j]).sum::<f64>())
            .collect();
        let worst = |x: &[f64]| x.iter().fold(0.0_f64, |m, y| m.max(y.abs()));
        let total: Vec<f64> = d.iter().zip(&linear).map(|(a, b)| a + b).collect();
        assert!(worst(&total) < 1e-13 * beta * 7.0, "{total:?}");
        assert!(worst(&linear) > 1e-2 * beta * 7.0, "{linear:?}");
    }

    /// Reference: the chain rule. In the scaled unknowns `xi` (`q = S xi`)
    /// the energy `U(S xi)` has the gradient `S dU/dq`, and the scaled
    /// stiffness and terms give exactly that (to 1e-13); the mass scales
    /// alike (`S M S`, the kinetic energy unchanged).
    #[test]
    fn scaled_unknowns_carry_the_same_energy() {
        let e = element([0.6, 0.8]);
        let sc = slope_scaling(e.length);
        let xi = [0.03, -0.02, 0.06, -0.045, 0.05, 0.04, -0.03, 0.09];
        let q: [f64; 8] = std::array::from_fn(|i| sc[i] * xi[i]);
        let f = force(&e, &q);
        let k = scaled_matrix(&e.stiffness(), &sc);
        let mut g = evaluate(&scaled_terms(&e.nonlinear_force(), &sc), &xi);
        for (i, gi) in g.iter_mut().enumerate() {
            *gi += (0..8).map(|j| k[i][j] * xi[j]).sum::<f64>();
        }
        for i in 0..8 {
            assert!((g[i] - sc[i] * f[i]).abs() < 1e-13 * 7.0, "{i}");
        }
        let (m, ms) = (e.mass(), scaled_matrix(&e.mass(), &sc));
        let energy = |a: &[[f64; 8]; 8], v: &[f64; 8]| -> f64 {
            (0..8)
                .map(|i| (0..8).map(|j| v[i] * a[i][j] * v[j]).sum::<f64>())
                .sum()
        };
        assert!((energy(&m, &q) - energy(&ms, &xi)).abs() < 1e-15);
    }
}
