//! The rectangular von Karman plate element: four corner nodes, six unknowns
//! per node `(u, v, w, w_x, w_y, w_xy)` (in-plane displacements, transverse
//! displacement and its derivatives), local order `node * 6 + unknown` with the
//! nodes counter-clockwise from `(0, 0)`.
//!
//! Bending: the Bogner-Fox-Schmit element, `w` bicubic (products of cubic
//! Hermite polynomials in `x` and `y`), conforming (`C^1`) on rectangles.
//! Membrane: `u`, `v` bilinear. With the von Karman membrane strain
//! `e = e_L + e_N`, `e_L = (u_x, v_y, u_y + v_x)`,
//! `e_N = (g_x^2 / 2, g_y^2 / 2, g_x g_y)`, and the curvature
//! `k = (w_xx, w_yy, 2 w_xy)`, the strain energy is
//!
//! `U = int [ e^T A e / 2 + k^T D k / 2 ] dx dy`
//!   `= int e_L^T A e_L / 2 + k^T D k / 2`   (quadratic: stiffness `K`)
//!   `+ int e_L^T A e_N`                     (cubic energy: quadratic force)
//!   `+ int e_N^T A e_N / 2`                 (quartic energy: cubic force),
//!
//! `A = E h / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]]`,
//! `D = A h^2 / 12`, and the internal force is `dU/dq = K q + f2(q) + f3(q)`.
//! The slopes `g = grad w` of the membrane strain are those of the bilinear
//! interpolation of the nodal `w` (the membrane's own interpolation), so that
//! `e_N` is consistent with `e_L` in degree and the polynomial forces stay
//! small (288 terms an element: 80 on `u, v` quadratic in `w`, 128 on `w`
//! bilinear in `(u, v)` and `w`, 80 cubic on `w`); `g` converges to `grad w`
//! at `O(h)` and the quartic energy at `O(h^2)`. Every integrand is a
//! polynomial of degree at most 7 in each direction: the 4 x 4 Gauss rule
//! integrates all of them exactly. The mass is consistent,
//! `rho h int (N_u^T N_u + N_v^T N_v + N_w^T N_w)` (no rotary inertia,
//! Kirchhoff kinematics).
//!
//! # References
//! - F. K. Bogner, R. L. Fox, L. A. Schmit, *The generation of interelement-
//!   compatible stiffness and mass matrices by the use of interpolation
//!   formulas*, Proc. Conf. Matrix Methods in Structural Mechanics, AFFDL-TR-
//!   66-80 (1965) 397-443.
//! - J. N. Reddy, *An Introduction to Nonlinear Finite Element Analysis*, 2nd
//!   ed., Oxford (2015), Ch. 7 (plates with von Karman strains).

use std::collections::BTreeMap;

use von_karman_beam::element::{hermite, hermite_curvature, hermite_slope};
use von_karman_beam::LocalTerm;

/// Unknowns per node.
pub const NODE_DOFS: usize = 6;
/// Unknowns per element.
pub const ELEMENT_DOFS: usize = 4 * NODE_DOFS;
/// Names of the nodal unknowns, in local order.
pub const DOF_NAMES: [&str; NODE_DOFS] = ["u", "v", "w", "wx", "wy", "wxy"];
/// Corners `(a, b)` of the nodes in the unit square, counter-clockwise.
pub const CORNERS: [(usize, usize); 4] = [(0, 0), (1, 0), (1, 1), (0, 1)];

/// The 4-point Gauss-Legendre rule on `[0, 1]`: `(abscissa, weight)`, exact
/// for polynomials of degree 7.
const GAUSS4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// Material and thickness of a plate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Young's modulus `E`.
    pub young: f64,
    /// Poisson's ratio `nu`.
    pub poisson: f64,
    /// Density `rho`.
    pub density: f64,
    /// Thickness `h`.
    pub thickness: f64,
}

impl Material {
    /// The membrane stiffness `A` (force per length), row-major 3 x 3.
    pub fn membrane(&self) -> [[f64; 3]; 3] {
        let c = self.young * self.thickness / (1.0 - self.poisson * self.poisson);
        let nu = self.poisson;
        [
            [c, c * nu, 0.0],
            [c * nu, c, 0.0],
            [0.0, 0.0, c * (1.0 - nu) / 2.0],
        ]
    }

    /// The bending stiffness `D = A h^2 / 12` (moment per length and curvature).
    pub fn bending(&self) -> [[f64; 3]; 3] {
        let s = self.thickness * self.thickness / 12.0;
        self.membrane().map(|row| row.map(|v| v * s))
    }

    /// The flexural rigidity `D = E h^3 / (12 (1 - nu^2))`.
    pub fn rigidity(&self) -> f64 {
        self.young * self.thickness.powi(3) / (12.0 * (1.0 - self.poisson * self.poisson))
    }

    /// Mass per unit area `rho h`.
    pub fn areal_mass(&self) -> f64 {
        self.density * self.thickness
    }
}

/// A rectangular element of `hx x hy`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Element {
    /// Side along `x`.
    pub hx: f64,
    /// Side along `y`.
    pub hy: f64,
    /// Material and thickness.
    pub material: Material,
}

/// Bending functions at one point: values, `d/dx`, `d/dy`, `d2/dx2`,
/// `d2/dy2` and `d2/dxdy` of the 16 functions, function `4 node + k` on
/// unknown `k` of `(w, w_x, w_y, w_xy)`.
pub struct Bending {
    /// Values.
    pub n: [f64; 16],
    /// `d/dx`.
    pub x: [f64; 16],
    /// `d/dy`.
    pub y: [f64; 16],
    /// `d2/dx2`.
    pub xx: [f64; 16],
    /// `d2/dy2`.
    pub yy: [f64; 16],
    /// `d2/dxdy`.
    pub xy: [f64; 16],
}

/// Hermite functions of the corner `a` (0 or 1) of a side: `(value, slope)`
/// entries of `[h1, h2, h3, h4]`.
fn corner(h: &[f64; 4], a: usize) -> (f64, f64) {
    (h[2 * a], h[2 * a + 1])
}

/// Local index of bending function `f` (`4 node + k`) in `q`.
pub fn bending_dof(f: usize) -> usize {
    (f / 4) * NODE_DOFS + 2 + f % 4
}

/// Local index of membrane function `node` of `u` (`c = 0`) or `v` (`c = 1`).
pub fn membrane_dof(node: usize, c: usize) -> usize {
    node * NODE_DOFS + c
}

impl Element {
    /// The bending functions at `(xi, eta)` of the unit square.
    pub fn bending_at(&self, xi: f64, eta: f64) -> Bending {
        let (hx, dhx, ddhx) = (
            hermite(xi, self.hx),
            hermite_slope(xi, self.hx),
            hermite_curvature(xi, self.hx),
        );
        let (hy, dhy, ddhy) = (
            hermite(eta, self.hy),
            hermite_slope(eta, self.hy),
            hermite_curvature(eta, self.hy),
        );
        let mut b = Bending {
            n: [0.0; 16],
            x: [0.0; 16],
            y: [0.0; 16],
            xx: [0.0; 16],
            yy: [0.0; 16],
            xy: [0.0; 16],
        };
        for (node, &(a, c)) in CORNERS.iter().enumerate() {
            let (fx, dfx, ddfx) = (corner(&hx, a), corner(&dhx, a), corner(&ddhx, a));
            let (fy, dfy, ddfy) = (corner(&hy, c), corner(&dhy, c), corner(&ddhy, c));
            // (w, w_x, w_y, w_xy): (V V, S V, V S, S S)
            let pick = |p: (f64, f64), s: bool| if s { p.1 } else { p.0 };
            for (k, (sx, sy)) in [(false, false), (true, false), (false, true), (true, true)]
                .into_iter()
                .enumerate()
            {
                let f = 4 * node + k;
                b.n[f] = pick(fx, sx) * pick(fy, sy);
                b.x[f] = pick(dfx, sx) * pick(fy, sy);
                b.y[f] = pick(fx, sx) * pick(dfy, sy);
                b.xx[f] = pick(ddfx, sx) * pick(fy, sy);
                b.yy[f] = pick(fx, sx) * pick(ddfy, sy);
                b.xy[f] = pick(dfx, sx) * pick(dfy, sy);
            }
        }
        b
    }

    /// Bilinear functions at `(xi, eta)`: values, `d/dx`, `d/dy` per node.
    pub fn bilinear_at(&self, xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
        let mut n = [0.0; 4];
        let mut dx = [0.0; 4];
        let mut dy = [0.0; 4];
        for (node, &(a, c)) in CORNERS.iter().enumerate() {
            let (fx, sx) = if a == 0 { (1.0 - xi, -1.0) } else { (xi, 1.0) };
            let (fy, sy) = if c == 0 {
                (1.0 - eta, -1.0)
            } else {
                (eta, 1.0)
            };
            n[node] = fx * fy;
            dx[node] = sx * fy / self.hx;
            dy[node] = fx * sy / self.hy;
        }
        (n, dx, dy)
    }

    /// Gauss points of the element with weights scaled to its area.
    fn points(&self) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        let area = self.hx * self.hy;
        GAUSS4.iter().flat_map(move |&(xi, wx)| {
            GAUSS4
                .iter()
                .map(move |&(eta, wy)| (xi, eta, wx * wy * area))
        })
    }

    /// The membrane strain-displacement rows `e_L = B q`, each as
    /// `(local index, factor)` pairs.
    fn membrane_rows(dx: &[f64; 4], dy: &[f64; 4]) -> [Vec<(usize, f64)>; 3] {
        let mut rows: [Vec<(usize, f64)>; 3] = Default::default();
        for node in 0..4 {
            rows[0].push((membrane_dof(node, 0), dx[node]));
            rows[1].push((membrane_dof(node, 1), dy[node]));
            rows[2].push((membrane_dof(node, 0), dy[node]));
            rows[2].push((membrane_dof(node, 1), dx[node]));
        }
        rows
    }

    /// Consistent mass matrix.
    pub fn mass(&self) -> Vec<[f64; ELEMENT_DOFS]> {
        let mut m = vec![[0.0; ELEMENT_DOFS]; ELEMENT_DOFS];
        let rho_h = self.material.areal_mass();
        for (xi, eta, w) in self.points() {
            let b = self.bending_at(xi, eta);
            for f in 0..16 {
                for g in 0..16 {
                    m[bending_dof(f)][bending_dof(g)] += w * rho_h * b.n[f] * b.n[g];
                }
            }
            let (n, _, _) = self.bilinear_at(xi, eta);
            for p in 0..4 {
                for r in 0..4 {
                    for c in 0..2 {
                        m[membrane_dof(p, c)][membrane_dof(r, c)] += w * rho_h * n[p] * n[r];
                    }
                }
            }
        }
        m
    }

    /// Linear stiffness matrix: `int B^T A B + C^T D C` with the membrane
    /// strains `e_L = B q` and curvatures `k = C q`.
    pub fn stiffness(&self) -> Vec<[f64; ELEMENT_DOFS]> {
        let mut k = vec![[0.0; ELEMENT_DOFS]; ELEMENT_DOFS];
        let (am, db) = (self.material.membrane(), self.material.bending());
        for (xi, eta, w) in self.points() {
            let b = self.bending_at(xi, eta);
            let curv = [b.xx, b.yy, b.xy.map(|v| 2.0 * v)];
            for f in 0..16 {
                for g in 0..16 {
                    let mut s = 0.0;
                    for r in 0..3 {
                        for c in 0..3 {
                            s += curv[r][f] * db[r][c] * curv[c][g];
                        }
                    }
                    k[bending_dof(f)][bending_dof(g)] += w * s;
                }
            }
            let (_, dx, dy) = self.bilinear_at(xi, eta);
            let rows = Self::membrane_rows(&dx, &dy);
            for r in 0..3 {
                for c in 0..3 {
                    for &(i, bi) in &rows[r] {
                        for &(j, bj) in &rows[c] {
                            k[i][j] += w * bi * am[r][c] * bj;
                        }
                    }
                }
            }
        }
        k
    }

    /// The quadratic and cubic internal forces `f2(q) + f3(q)`, one term per
    /// distinct monomial and component (local indices).
    ///
    /// With the slopes `g_x = a_x . w`, `g_y = a_y . w` of the nodal `w`, the
    /// components of `e_N` are `w^T E_c w` with `E_1 = a_x a_x^T / 2`,
    /// `E_2 = a_y a_y^T / 2`, `E_3 = (a_x a_y^T + a_y a_x^T) / 2`. Then
    /// `f2_m = int B^T A e_N` on the membrane unknowns,
    /// `f2_w = int 2 E_c w (A B q_m)_c` on `w` and
    /// `f3_w = int 2 E_c w (A e_N)_c`.
    #[expect(
        clippy::needless_range_loop,
        reason = "the tensor sums read best with their indices"
    )]
    pub fn polynomial_force(&self) -> Vec<LocalTerm> {
        let am = self.material.membrane();
        let mut acc: BTreeMap<(usize, Vec<usize>), f64> = BTreeMap::new();
        let wdof = |node: usize| node * NODE_DOFS + 2;
        for (xi, eta, w) in self.points() {
            let (_, ax, ay) = self.bilinear_at(xi, eta);
            let mut e = [[[0.0; 4]; 4]; 3];
            for k in 0..4 {
                for l in 0..4 {
                    e[0][k][l] = 0.5 * ax[k] * ax[l];
                    e[1][k][l] = 0.5 * ay[k] * ay[l];
                    e[2][k][l] = 0.5 * (ax[k] * ay[l] + ay[k] * ax[l]);
                }
            }
            let rows = Self::membrane_rows(&ax, &ay);
            // (A B)_{c j} for each membrane unknown j
            let mut ab: Vec<(usize, [f64; 3])> = Vec::new();
            for (r, row) in rows.iter().enumerate() {
                for &(j, bj) in row {
                    let slot = match ab.iter().position(|(i, _)| *i == j) {
                        Some(p) => p,
                        None => {
                            ab.push((j, [0.0; 3]));
                            ab.len() - 1
                        }
                    };
                    for c in 0..3 {
                        ab[slot].1[c] += am[c][r] * bj;
                    }
                }
            }
            for &(j, abj) in &ab {
                for k in 0..4 {
                    for l in k..4 {
                        let mult = if k == l { 1.0 } else { 2.0 };
                        // f2 on membrane unknown j: (B^T A)_{j c} = (A B)_{c j} (A symmetric)
                        let s: f64 = (0..3).map(|c| abj[c] * e[c][k][l]).sum();
                        *acc.entry((j, vec![wdof(k), wdof(l)])).or_default() += w * mult * s;
                    }
                }
                // f2 on w_k: monomial q_j w_l
                for k in 0..4 {
                    for l in 0..4 {
                        let s: f64 = (0..3).map(|c| abj[c] * e[c][k][l]).sum();
                        let mut vars = vec![j, wdof(l)];
                        vars.sort_unstable();
                        *acc.entry((wdof(k), vars)).or_default() += w * 2.0 * s;
                    }
                }
            }
            // f3 on w_k: 2 sum_{c c'} A_{c c'} E_{c,kl} E_{c',mn} w_l w_m w_n
            for k in 0..4 {
                for l in 0..4 {
                    for m in 0..4 {
                        for n in 0..4 {
                            let mut s = 0.0;
                            for c in 0..3 {
                                for d in 0..3 {
                                    s += am[c][d] * e[c][k][l] * e[d][m][n];
                                }
                            }
                            let mut vars = vec![wdof(l), wdof(m), wdof(n)];
                            vars.sort_unstable();
                            *acc.entry((wdof(k), vars)).or_default() += w * 2.0 * s;
                        }
                    }
                }
            }
        }
        let scale = acc.values().fold(0.0_f64, |m, v| m.max(v.abs()));
        acc.into_iter()
            .filter(|(_, c)| c.abs() > 1e-14 * scale)
            .map(|((eq, vars), coeff)| LocalTerm { eq, coeff, vars })
            .collect()
    }

    /// The consistent nodal load `int N_w` of a unit pressure on the element,
    /// per bending function.
    pub fn pressure_load(&self) -> [f64; 16] {
        let mut f = [0.0; 16];
        for (xi, eta, w) in self.points() {
            let b = self.bending_at(xi, eta);
            for (fi, n) in f.iter_mut().zip(b.n) {
                *fi += w * n;
            }
        }
        f
    }
}
