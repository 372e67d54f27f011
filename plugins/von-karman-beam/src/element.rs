//! The planar von Karman beam element: two nodes, three degrees of freedom per
//! node `(u, w, phi)` (axial displacement, transverse displacement, rotation
//! `phi = w'`), local order `q = (u1, w1, phi1, u2, w2, phi2)`.
//!
//! Axial displacement is interpolated linearly, transverse displacement by the
//! cubic Hermite polynomials. With the von Karman axial strain
//! `e = u' + w'^2 / 2` and the curvature `kappa = w''`, the strain energy is
//!
//! `U = int_0^L [ EA/2 (u' + w'^2/2)^2 + EI/2 w''^2 ] dx`
//!   `= int EA/2 u'^2 + EI/2 w''^2`   (quadratic: stiffness `K`)
//!   `+ int EA/2 u' w'^2`             (cubic energy: quadratic force)
//!   `+ int EA/8 w'^4`                (quartic energy: cubic force),
//!
//! and the internal force is `dU/dq = K q + f2(q) + f3(q)`. With
//! `b = dN_u/dx` (constant) and `a(x) = dN_w/dx` (quadratic in `x`):
//!
//! - `f2_u[i] = EA/2 b_i sum_kl A2_kl w_k w_l`,
//! - `f2_w[j] = EA sum_m sum_k b_m A2_kj u_m w_k`,
//! - `f3_w[j] = EA/2 sum_klm A4_jklm w_k w_l w_m`,
//!
//! where `A2_kl = int a_k a_l dx` and `A4_jklm = int a_j a_k a_l a_m dx`. The
//! integrands are polynomials of degree at most 8 in `x`, so the 5-point
//! Gauss-Legendre rule (exact to degree 9) integrates every term exactly. The
//! consistent mass is `int rhoA (N_u^T N_u + N_w^T N_w) dx` (no rotary inertia,
//! Euler-Bernoulli kinematics).
//!
//! # References
//! - S. Jain, P. Tiso, G. Haller, *Exact nonlinear model reduction for a von
//!   Karman beam: slow-fast decomposition and spectral submanifolds*, J. Sound
//!   Vib. 423 (2018) 195-211, Sect. 2 (the element used for the frequency divider).
//! - J. N. Reddy, *An Introduction to Nonlinear Finite Element Analysis*, 2nd ed.,
//!   Oxford (2015), Ch. 5 (Euler-Bernoulli beams with von Karman strain).

/// Local index of the axial displacements `(u1, u2)` in `q`.
pub const AXIAL: [usize; 2] = [0, 3];
/// Local index of the bending unknowns `(w1, phi1, w2, phi2)` in `q`.
pub const BENDING: [usize; 4] = [1, 2, 4, 5];

/// Gauss-Legendre rule with 5 points on `[0, 1]`: `(abscissa, weight)`.
pub(crate) const GAUSS5: [(f64, f64); 5] = [
    (0.046_910_077_030_668_004, 0.118_463_442_528_094_54),
    (0.230_765_344_947_158_45, 0.239_314_335_249_683_23),
    (0.5, 0.284_444_444_444_444_45),
    (0.769_234_655_052_841_6, 0.239_314_335_249_683_23),
    (0.953_089_922_969_332, 0.118_463_442_528_094_54),
];

/// Section and material of a beam, per unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    /// Axial stiffness `E A`.
    pub ea: f64,
    /// Bending stiffness `E I`.
    pub ei: f64,
    /// Mass per unit length `rho A`.
    pub rho_a: f64,
}

impl Section {
    /// Rectangular section of `width x thickness`, bending across the thickness
    /// (`I = width thickness^3 / 12`), of a material with Young's modulus
    /// `young` and density `density`.
    pub fn rectangular(width: f64, thickness: f64, young: f64, density: f64) -> Self {
        let area = width * thickness;
        Self {
            ea: young * area,
            ei: young * width * thickness.powi(3) / 12.0,
            rho_a: density * area,
        }
    }
}

/// One monomial of an element force: `coeff * prod q[vars]` added to force
/// component `eq` (all indices local, `0..6`).
#[derive(Clone, Debug, PartialEq)]
pub struct LocalTerm {
    /// Local force component.
    pub eq: usize,
    /// Coefficient.
    pub coeff: f64,
    /// Local unknowns of the monomial, non-decreasing (repeats are powers).
    pub vars: Vec<usize>,
}

impl LocalTerm {
    /// Adds `terms` to `force` at the global indices `global` of the
    /// element's local unknowns; a term whose component or a factor is a
    /// removed unknown (`None`) vanishes.
    pub fn scatter(terms: &[Self], global: &[Option<usize>], force: &mut ssm_api::PolyVector) {
        let mut factors: Vec<(usize, u32)> = Vec::with_capacity(3);
        'term: for t in terms {
            let Some(eq) = global[t.eq] else { continue };
            factors.clear();
            for &v in &t.vars {
                let Some(gv) = global[v] else { continue 'term };
                factors.push((gv, 1));
            }
            force.push(eq, t.coeff, &factors);
        }
    }
}

/// A two-node von Karman beam element of length `length`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Element length.
    pub length: f64,
    /// Section and material.
    pub section: Section,
}

/// `A4_jklm = int a_j a_k a_l a_m dx` over the four bending unknowns.
type SlopeMoment4 = [[[[f64; 4]; 4]; 4]; 4];

/// Cubic Hermite shape functions at `xi = x / l` on `(w1, phi1, w2, phi2)`.
pub fn hermite(xi: f64, l: f64) -> [f64; 4] {
    let (x2, x3) = (xi * xi, xi * xi * xi);
    [
        1.0 - 3.0 * x2 + 2.0 * x3,
        l * (xi - 2.0 * x2 + x3),
        3.0 * x2 - 2.0 * x3,
        l * (x3 - x2),
    ]
}

/// Slopes `dN/dx` of the Hermite functions at `xi = x / l`.
pub fn hermite_slope(xi: f64, l: f64) -> [f64; 4] {
    let x2 = xi * xi;
    [
        (6.0 * x2 - 6.0 * xi) / l,
        1.0 - 4.0 * xi + 3.0 * x2,
        (6.0 * xi - 6.0 * x2) / l,
        3.0 * x2 - 2.0 * xi,
    ]
}

/// Curvatures `d2N/dx2` of the Hermite functions at `xi = x / l`.
pub fn hermite_curvature(xi: f64, l: f64) -> [f64; 4] {
    [
        (12.0 * xi - 6.0) / (l * l),
        (6.0 * xi - 4.0) / l,
        (6.0 - 12.0 * xi) / (l * l),
        (6.0 * xi - 2.0) / l,
    ]
}

impl Element {
    /// Gauss points in `x` with weights scaled to the element length.
    fn points(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        GAUSS5.iter().map(|&(xi, w)| (xi, w * self.length))
    }

    /// Consistent mass matrix `int rhoA (N_u^T N_u + N_w^T N_w) dx`.
    pub fn mass(&self) -> [[f64; 6]; 6] {
        let l = self.length;
        self.integrate(
            |xi| ([1.0 - xi, xi], hermite(xi, l)),
            self.section.rho_a,
            self.section.rho_a,
        )
    }

    /// Linear stiffness matrix `int EA N_u'^T N_u' + EI N_w''^T N_w'' dx`.
    pub fn stiffness(&self) -> [[f64; 6]; 6] {
        let l = self.length;
        let b = [-1.0 / l, 1.0 / l];
        self.integrate(
            |xi| (b, hermite_curvature(xi, l)),
            self.section.ea,
            self.section.ei,
        )
    }

    /// `int a (f_u^T f_u) + c (f_w^T f_w) dx` for the axial functions `f_u`
    /// and bending functions `f_w` that `at(xi)` returns, placed in the
    /// local order of `q`.
    fn integrate(&self, at: impl Fn(f64) -> ([f64; 2], [f64; 4]), a: f64, c: f64) -> [[f64; 6]; 6] {
        let mut m = [[0.0; 6]; 6];
        for (xi, w) in self.points() {
            let (fu, fw) = at(xi);
            for (p, &i) in AXIAL.iter().enumerate() {
                for (r, &j) in AXIAL.iter().enumerate() {
                    m[i][j] += w * a * fu[p] * fu[r];
                }
            }
            for (p, &i) in BENDING.iter().enumerate() {
                for (r, &j) in BENDING.iter().enumerate() {
                    m[i][j] += w * c * fw[p] * fw[r];
                }
            }
        }
        m
    }

    /// `A2_kl = int a_k a_l dx` and `A4_jklm = int a_j a_k a_l a_m dx` over the
    /// Hermite slopes `a = dN_w/dx`, integrated exactly.
    fn slope_moments(&self) -> ([[f64; 4]; 4], SlopeMoment4) {
        let mut a2 = [[0.0; 4]; 4];
        let mut a4 = [[[[0.0; 4]; 4]; 4]; 4];
        for (xi, w) in self.points() {
            let a = hermite_slope(xi, self.length);
            for j in 0..4 {
                for k in 0..4 {
                    a2[j][k] += w * a[j] * a[k];
                    for l in 0..4 {
                        for m in 0..4 {
                            a4[j][k][l][m] += w * a[j] * a[k] * a[l] * a[m];
                        }
                    }
                }
            }
        }
        (a2, a4)
    }

    /// The quadratic internal force `f2(q)` (from `int EA/2 u' w'^2 dx`), one
    /// term per distinct monomial and component.
    pub fn quadratic_force(&self) -> Vec<LocalTerm> {
        let ea = self.section.ea;
        let b = [-1.0 / self.length, 1.0 / self.length];
        let (a2, _) = self.slope_moments();
        let mut terms = Vec::new();
        // f2_u[i] = EA/2 b_i sum_{k,l} A2_kl w_k w_l
        for (i, &eq) in AXIAL.iter().enumerate() {
            for k in 0..4 {
                for l in k..4 {
                    let multiplicity = if k == l { 1.0 } else { 2.0 };
                    terms.push(LocalTerm {
                        eq,
                        coeff: 0.5 * ea * b[i] * multiplicity * a2[k][l],
                        vars: vec![BENDING[k], BENDING[l]],
                    });
                }
            }
        }
        // f2_w[j] = EA sum_m sum_k b_m A2_kj u_m w_k
        for (j, &eq) in BENDING.iter().enumerate() {
            for (m, &um) in AXIAL.iter().enumerate() {
                for k in 0..4 {
                    let mut vars = vec![um, BENDING[k]];
                    vars.sort_unstable();
                    terms.push(LocalTerm {
                        eq,
                        coeff: ea * b[m] * a2[k][j],
                        vars,
                    });
                }
            }
        }
        terms.retain(|t| t.coeff != 0.0);
        terms
    }

    /// The cubic internal force `f3(q)` (from `int EA/8 w'^4 dx`), one term per
    /// distinct monomial and component.
    pub fn cubic_force(&self) -> Vec<LocalTerm> {
        let ea = self.section.ea;
        let (_, a4) = self.slope_moments();
        let mut terms = Vec::new();
        for (j, &eq) in BENDING.iter().enumerate() {
            for k in 0..4 {
                for l in k..4 {
                    for m in l..4 {
                        // number of orderings of the multiset {k, l, m}
                        let orderings = match (k == l, l == m) {
                            (true, true) => 1.0,
                            (false, false) => 6.0,
                            _ => 3.0,
                        };
                        terms.push(LocalTerm {
                            eq,
                            coeff: 0.5 * ea * orderings * a4[j][k][l][m],
                            vars: vec![BENDING[k], BENDING[l], BENDING[m]],
                        });
                    }
                }
            }
        }
        terms.retain(|t| t.coeff != 0.0);
        terms
    }

    /// Strain energy `U(q)` of eq. above, by the same exact quadrature.
    pub fn strain_energy(&self, q: &[f64; 6]) -> f64 {
        let l = self.length;
        let du = (q[3] - q[0]) / l;
        let wq = [q[1], q[2], q[4], q[5]];
        self.points()
            .map(|(xi, w)| {
                let slope: f64 = dot4(&hermite_slope(xi, l), &wq);
                let curv: f64 = dot4(&hermite_curvature(xi, l), &wq);
                let strain = du + 0.5 * slope * slope;
                w * (0.5 * self.section.ea * strain * strain + 0.5 * self.section.ei * curv * curv)
            })
            .sum()
    }
}

fn dot4(a: &[f64; 4], b: &[f64; 4]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Evaluates local force terms at `q`.
pub fn evaluate(terms: &[LocalTerm], q: &[f64; 6]) -> [f64; 6] {
    let mut f = [0.0; 6];
    for t in terms {
        f[t.eq] += t.coeff * t.vars.iter().map(|&v| q[v]).product::<f64>();
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    fn element() -> Element {
        Element {
            length: 70.7,
            section: Section::rectangular(10.0, 1.0, 70e6, 2700e-9),
        }
    }

    /// The internal force `K q + f2 + f3` is the gradient of the strain energy:
    /// central differences with step 1e-4 (error O(h^2) ~ 1e-8 relative).
    #[test]
    fn internal_force_is_the_gradient_of_the_strain_energy() {
        let e = element();
        let q = [0.013, -0.41, 0.021, -0.007, 0.83, -0.012];
        let k = e.stiffness();
        let f2 = evaluate(&e.quadratic_force(), &q);
        let f3 = evaluate(&e.cubic_force(), &q);
        for i in 0..6 {
            let h = 1e-4 * q[i].abs().max(1e-3);
            let (mut qp, mut qm) = (q, q);
            qp[i] += h;
            qm[i] -= h;
            let grad = (e.strain_energy(&qp) - e.strain_energy(&qm)) / (2.0 * h);
            let force: f64 = (0..6).map(|j| k[i][j] * q[j]).sum::<f64>() + f2[i] + f3[i];
            let scale = force.abs().max(grad.abs());
            assert!(
                (force - grad).abs() <= 1e-6 * scale,
                "component {i}: force {force} vs energy gradient {grad}"
            );
        }
    }

    /// Stiffness and mass against the textbook closed forms (Reddy 2015,
    /// eqs. 5.2.x): `EI/L^3 [12 6L -12 6L; ...]`, `rhoA L/420 [156 22L 54 -13L; ...]`.
    #[test]
    fn linear_matrices_match_the_closed_forms() {
        let e = element();
        let (l, s) = (e.length, e.section);
        let kb = [
            [12.0, 6.0 * l, -12.0, 6.0 * l],
            [6.0 * l, 4.0 * l * l, -6.0 * l, 2.0 * l * l],
            [-12.0, -6.0 * l, 12.0, -6.0 * l],
            [6.0 * l, 2.0 * l * l, -6.0 * l, 4.0 * l * l],
        ];
        let mb = [
            [156.0, 22.0 * l, 54.0, -13.0 * l],
            [22.0 * l, 4.0 * l * l, 13.0 * l, -3.0 * l * l],
            [54.0, 13.0 * l, 156.0, -22.0 * l],
            [-13.0 * l, -3.0 * l * l, -22.0 * l, 4.0 * l * l],
        ];
        let (k, m) = (e.stiffness(), e.mass());
        for p in 0..4 {
            for r in 0..4 {
                let kref = s.ei / l.powi(3) * kb[p][r];
                let mref = s.rho_a * l / 420.0 * mb[p][r];
                assert!((k[BENDING[p]][BENDING[r]] - kref).abs() <= 1e-12 * kref.abs().max(1.0));
                assert!((m[BENDING[p]][BENDING[r]] - mref).abs() <= 1e-12 * mref.abs().max(1e-12));
            }
        }
        assert!((k[0][0] - s.ea / l).abs() <= 1e-12 * s.ea / l);
        assert!((k[0][3] + s.ea / l).abs() <= 1e-12 * s.ea / l);
        assert!((m[0][0] - s.rho_a * l / 3.0).abs() <= 1e-15);
        assert!((m[0][3] - s.rho_a * l / 6.0).abs() <= 1e-15);
    }
}
