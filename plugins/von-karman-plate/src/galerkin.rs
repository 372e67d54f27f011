//! The single-mode Galerkin model of the simply supported rectangular von
//! Karman plate with sliding in-plane edges, independent of the finite
//! elements: the reference for the hardening of the elements' first mode.
//!
//! With `w = q sin(alpha x) sin(beta y)`, `alpha = pi / a`, `beta = pi / b`,
//! the membrane equations are forced by the slopes of `w` in the harmonics
//! `sin 2 alpha x {1, cos 2 beta y}` (for `u`) and `sin 2 beta y {1, cos 2
//! alpha x}` (for `v`); so the in-plane displacements minimizing the membrane
//! energy are `u = q^2 (c1 sin 2 alpha x + c2 sin 2 alpha x cos 2 beta y)`,
//! `v = q^2 (c3 sin 2 beta y + c4 cos 2 alpha x sin 2 beta y)`, which satisfy
//! `u = 0` on `x = 0, a`, `v = 0` on `y = 0, b` and zero shear there. Ritz
//! with these four functions (quadrature to round-off) gives the minimum
//! `Pi q^4` of the membrane energy, and with the modal mass `m = rho h a b /
//! 4` the mass-normalized modal equation
//! `eta'' + omega^2 eta + gamma eta^3 = 0`, `gamma = 4 Pi / m^2`.
//!
//! # References
//! - H.-N. Chu, G. Herrmann, *Influence of large amplitudes on free flexural
//!   vibrations of rectangular elastic plates*, J. Appl. Mech. 23 (1956)
//!   532-540 (the single-mode method).

use std::f64::consts::PI;

use crate::element::Material;

/// The 4-point Gauss-Legendre rule on `[-1, 1]`.
const GAUSS4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// Composite rule on `[0, len]`: `panels` panels of [`GAUSS4`].
fn composite(len: f64, panels: usize) -> Vec<(f64, f64)> {
    let h = len / panels as f64;
    (0..panels)
        .flat_map(|p| {
            GAUSS4
                .iter()
                .map(move |&(t, w)| (h * (p as f64 + 0.5 * (t + 1.0)), 0.5 * h * w))
        })
        .collect()
}

/// `gamma` of the mass-normalized first mode of the `a x b` plate.
pub fn single_mode_hardening(material: &Material, a: f64, b: f64) -> f64 {
    let am = material.membrane();
    let (al, be) = (PI / a, PI / b);
    let (ta, tb) = (2.0 * al, 2.0 * be);
    let (rx, ry) = (composite(a, 16), composite(b, 16));
    let mut g = [[0.0; 4]; 4];
    let mut h = [0.0; 4];
    let mut c = 0.0;
    let quad = |p: &[f64; 3], q: &[f64; 3]| -> f64 {
        let mut s = 0.0;
        for (pr, row) in p.iter().zip(&am) {
            for (a_rs, qs) in row.iter().zip(q) {
                s += pr * a_rs * qs;
            }
        }
        s
    };
    for &(x, wx) in &rx {
        for &(y, wy) in &ry {
            let w = wx * wy;
            let (sx, cx) = ((ta * x).sin(), (ta * x).cos());
            let (sy, cy) = ((tb * y).sin(), (tb * y).cos());
            // e_L = (u_x, v_y, u_y + v_x) of the four functions
            let e = [
                [ta * cx, 0.0, 0.0],
                [ta * cx * cy, 0.0, -tb * sx * sy],
                [0.0, tb * cy, 0.0],
                [0.0, tb * cx * cy, -ta * sx * sy],
            ];
            let gx = al * (al * x).cos() * (be * y).sin();
            let gy = be * (al * x).sin() * (be * y).cos();
            let en = [0.5 * gx * gx, 0.5 * gy * gy, gx * gy];
            for (i, ei) in e.iter().enumerate() {
                for (j, ej) in e.iter().enumerate() {
                    g[i][j] += w * quad(ei, ej);
                }
                h[i] += w * quad(ei, &en);
            }
            c += w * 0.5 * quad(&en, &en);
        }
    }
    let coef = solve4(g, h);
    let pi4 = c - 0.5 * coef.iter().zip(&h).map(|(x, y)| x * y).sum::<f64>();
    let m = material.areal_mass() * a * b / 4.0;
    4.0 * pi4 / (m * m)
}

/// Solves the symmetric positive definite 4 x 4 system `g c = h` (Gaussian
/// elimination; the Ritz matrix of four independent functions).
fn solve4(mut g: [[f64; 4]; 4], mut h: [f64; 4]) -> [f64; 4] {
    for k in 0..4 {
        let pivot = g[k][k];
        for r in k + 1..4 {
            let f = g[r][k] / pivot;
            let row_k = g[k];
            for (grc, gkc) in g[r].iter_mut().zip(row_k).skip(k) {
                *grc -= f * gkc;
            }
            h[r] -= f * h[k];
        }
    }
    let mut c = [0.0; 4];
    for k in (0..4).rev() {
        let tail: f64 = (k + 1..4).map(|j| g[k][j] * c[j]).sum();
        c[k] = (h[k] - tail) / g[k][k];
    }
    c
}
