//! The plate element against plate theory: frequencies of the simply supported
//! (closed form) and clamped (Leissa) square plate with their convergence
//! rates, static deflections under a point force and a pressure (Navier's
//! series, Timoshenko's tables), the energy structure of the polynomial force,
//! and the von Karman hardening of the first mode against an independent
//! single-mode Galerkin calculation.

use std::f64::consts::PI;

use faer::linalg::solvers::{PartialPivLu, SelfAdjointEigen, Solve};
use faer::{Mat, Side};
use ssm_api::{PolyVector, SparseMatrix};
use von_karman_plate::{InPlane, Material, Mesh, Numbering, Support};

/// The plugin's default plate: 1 m x 1 m x 10 mm aluminium (SI units).
fn material() -> Material {
    Material {
        young: 70e9,
        poisson: 0.33,
        density: 2700.0,
        thickness: 0.01,
    }
}

fn square(n: usize, support: Support, inplane: InPlane) -> Mesh {
    Mesh {
        a: 1.0,
        b: 1.0,
        nx: n,
        ny: n,
        material: material(),
        support,
        inplane,
    }
}

struct Assembled {
    numbering: Numbering,
    mass: Mat<f64>,
    stiffness: Mat<f64>,
    force: PolyVector,
}

fn assemble(mesh: &Mesh) -> Assembled {
    let numbering = mesh.number(0);
    let n = numbering.len();
    let (mut m, mut k) = (SparseMatrix::zeros(n, n), SparseMatrix::zeros(n, n));
    let mut force = PolyVector::zeros(n, n);
    mesh.assemble(&numbering, &mut m, &mut k, &mut force);
    let dense = |s: &SparseMatrix| {
        let mut d = Mat::<f64>::zeros(n, n);
        for (r, c, v) in s.iter() {
            d[(r, c)] += v;
        }
        d
    };
    Assembled {
        mass: dense(&m),
        stiffness: dense(&k),
        numbering,
        force,
    }
}

/// Bending frequencies (ascending) and mass-normalized bending modes (over
/// every unknown, zero in-plane) of `K v = omega^2 M v`. The flat plate's
/// bending and membrane unknowns decouple in `K` and `M`; the bending block is
/// scaled by `diag(M)^(-1/2)` (the unknowns `w`, `w_x`, `w_xy` differ by powers
/// of the element size) and solved through the Cholesky factor of the scaled
/// mass: `L^-1 K L^-T u = omega^2 u`.
fn modes(a: &Assembled) -> (Vec<f64>, Mat<f64>) {
    let bending: Vec<usize> = a
        .numbering
        .nodes
        .iter()
        .flat_map(|d| {
            d.iter()
                .enumerate()
                .filter(|(k, _)| !Numbering::is_membrane(*k))
        })
        .filter_map(|(_, g)| *g)
        .collect();
    let nb = bending.len();
    let scale: Vec<f64> = bending
        .iter()
        .map(|&g| 1.0 / a.mass[(g, g)].sqrt())
        .collect();
    let block = |m: &Mat<f64>| {
        Mat::from_fn(nb, nb, |i, j| {
            scale[i] * m[(bending[i], bending[j])] * scale[j]
        })
    };
    let (mb, kb) = (block(&a.mass), block(&a.stiffness));
    let llt = mb.llt(Side::Lower).expect("the mass is positive definite");
    let l = llt.L();
    let mut x = kb.clone();
    l.solve_lower_triangular_in_place(x.as_mut());
    let mut c = x.transpose().to_owned();
    l.solve_lower_triangular_in_place(c.as_mut());
    let sym = Mat::from_fn(nb, nb, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    let evd = SelfAdjointEigen::new(sym.as_ref(), Side::Lower).expect("symmetric eigenproblem");
    let omega = (0..nb).map(|i| evd.S()[i].max(0.0).sqrt()).collect();
    let mut u = evd.U().to_owned();
    l.transpose().solve_upper_triangular_in_place(u.as_mut());
    let mut v = Mat::<f64>::zeros(a.mass.nrows(), nb);
    for (i, &g) in bending.iter().enumerate() {
        for k in 0..nb {
            v[(g, k)] = scale[i] * u[(i, k)];
        }
    }
    (omega, v)
}

fn solve(a: &Mat<f64>, b: &[f64]) -> Vec<f64> {
    let rhs = Mat::from_fn(b.len(), 1, |i, _| b[i]);
    let x = PartialPivLu::new(a.as_ref()).solve(&rhs);
    (0..b.len()).map(|i| x[(i, 0)]).collect()
}

/// `f(z) = f2(z) + f3(z)` and its Jacobian.
fn polynomial(force: &PolyVector, z: &[f64]) -> (Vec<f64>, Mat<f64>) {
    let n = z.len();
    let mut f = vec![0.0; n];
    let mut jac = Mat::<f64>::zeros(n, n);
    for t in force.terms.iter() {
        let eq = t.eq as usize;
        let value: f64 = t
            .factors
            .iter()
            .map(|p| z[p.var as usize].powi(p.power as i32))
            .product();
        f[eq] += t.coeff * value;
        for (i, p) in t.factors.iter().enumerate() {
            let rest: f64 = t
                .factors
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, o)| z[o.var as usize].powi(o.power as i32))
                .product();
            let d = p.power as f64 * z[p.var as usize].powi(p.power as i32 - 1) * rest;
            jac[(eq, p.var as usize)] += t.coeff * d;
        }
    }
    (f, jac)
}

/// `omega_mn = pi^2 (m^2 / a^2 + n^2 / b^2) sqrt(D / (rho h))`, the simply
/// supported plate's closed form (Leissa 1969, eq. 4.23).
fn navier_frequency(m: f64, n: f64) -> f64 {
    let mat = material();
    PI * PI * (m * m + n * n) * (mat.rigidity() / mat.areal_mass()).sqrt()
}

/// Simply supported square plate: the first four frequencies against the
/// closed form, below 2e-4 relative at 8 x 8 elements and the first below
/// 1e-5, from above (the element is conforming: Rayleigh-Ritz bounds), and
/// the first's error falls at the rate `h^4` of bicubic Hermite elements with
/// consistent mass (Strang & Fix: eigenvalue error `h^(2(p+1-m))`, `p = 3`,
/// `m = 2`): each halving divides it by about 16 (accepted in [12, 20]).
#[test]
fn simply_supported_frequencies_match_the_closed_form_at_fourth_order() {
    let exact = [
        navier_frequency(1.0, 1.0),
        navier_frequency(1.0, 2.0),
        navier_frequency(2.0, 1.0),
        navier_frequency(2.0, 2.0),
    ];
    let mut first = Vec::new();
    for n in [2, 4, 8] {
        let (omega, _) = modes(&assemble(&square(
            n,
            Support::SimplySupported,
            InPlane::Fixed,
        )));
        // the in-plane modes are far above (membrane waves): the lowest four
        // are the bending modes (1,1), (1,2), (2,1), (2,2)
        let errors: Vec<f64> = omega[..4]
            .iter()
            .zip(&exact)
            .map(|(w, e)| (w - e) / e)
            .collect();
        assert!(errors.iter().all(|&e| e > 0.0), "from above: {errors:?}");
        if n == 8 {
            assert!(errors.iter().all(|&e| e < 2e-4), "8 x 8: {errors:?}");
            assert!(errors[0] < 1e-5, "8 x 8: {errors:?}");
        }
        first.push(errors[0]);
    }
    for w in first.windows(2) {
        let ratio = w[0] / w[1];
        assert!((12.0..=20.0).contains(&ratio), "rate {ratio} in {first:?}");
    }
}

/// Clamped square plate: the first frequency parameter `omega a^2 sqrt(rho h /
/// D)` against Leissa's 35.985 (NASA SP-160, Table 4.23; no closed form
/// exists), within 1e-4 at 16 x 16 elements, and converging at the element's
/// rate `h^4` (each halving divides the change by about 16, accepted in [12,
/// 20]); Richardson's estimate of the limit agrees with Leissa's value to the
/// digits he prints (within 0.001).
#[test]
fn clamped_first_frequency_matches_leissa() {
    let mat = material();
    let scale = (mat.areal_mass() / mat.rigidity()).sqrt();
    let params: Vec<f64> = [4, 8, 16]
        .iter()
        .map(|&n| modes(&assemble(&square(n, Support::Clamped, InPlane::Fixed))).0[0] * scale)
        .collect();
    let leissa = 35.985;
    let rel = (params[2] - leissa) / leissa;
    assert!(rel > -1e-4 && rel < 1e-4, "{params:?}");
    let ratio = (params[0] - params[1]) / (params[1] - params[2]);
    assert!((12.0..=20.0).contains(&ratio), "rate {ratio} in {params:?}");
    let limit = params[2] - (params[1] - params[2]) / (ratio - 1.0);
    assert!(
        (limit - leissa).abs() < 1e-3,
        "Richardson {limit} in {params:?}"
    );
}

/// Center deflection `w(a/2, b/2)` of the simply supported plate under a unit
/// force at `(a/2, b/2)` from Navier's double sine series (Timoshenko &
/// Woinowsky-Krieger, Sect. 29), `w = 4 / (pi^4 D a b) sum_mn sin^2(m pi/2)
/// sin^2(n pi/2) / ((m/a)^2 + (n/b)^2)^2`, summed over `m, n < 4000` (tail
/// below 1e-7 relative).
fn navier_point_deflection() -> f64 {
    let mut s = 0.0;
    for m in (1..4000).step_by(2) {
        for n in (1..4000).step_by(2) {
            let d = (m * m + n * n) as f64;
            s += 1.0 / (d * d);
        }
    }
    4.0 / (PI.powi(4) * material().rigidity()) * s
}

/// The same under a uniform unit pressure: `w = 16 / (pi^6 D) sum_{m,n odd}
/// (-1)^((m+n)/2 - 1) / (m n ((m/a)^2 + (n/b)^2)^2)` (Sect. 30).
fn navier_pressure_deflection() -> f64 {
    let mut s = 0.0;
    for m in (1..400).step_by(2) {
        for n in (1..400).step_by(2) {
            let sign = if ((m + n) / 2 - 1) % 2 == 0 {
                1.0
            } else {
                -1.0
            };
            let d = (m * m + n * n) as f64;
            s += sign / ((m * n) as f64 * d * d);
        }
    }
    16.0 / (PI.powi(6) * material().rigidity()) * s
}

/// Linear static center deflection `K q = f` under a central unit force and a
/// uniform unit pressure (`f` from the mesh's own point weights and
/// consistent pressure load).
fn static_center(mesh: &Mesh, pressure: bool) -> f64 {
    let a = assemble(mesh);
    let n = a.numbering.len();
    let mut load = vec![0.0; n];
    let entries = if pressure {
        mesh.pressure_load(&a.numbering)
    } else {
        mesh.transverse_at(&a.numbering, 0.5, 0.5)
    };
    for (i, v) in entries {
        load[i] += v;
    }
    let q = solve(&a.stiffness, &load);
    mesh.transverse_at(&a.numbering, 0.5, 0.5)
        .iter()
        .map(|&(i, w)| w * q[i])
        .sum()
}

/// Static center deflections of the square plate against Navier's series
/// (simply supported: within 1e-3 under the point force, 1e-5 under the
/// pressure at 16 x 16) and against Timoshenko & Woinowsky-Krieger's tables
/// for the clamped plate (0.00126 q a^4 / D, Table 35, and 0.00560 P a^2 / D,
/// Table 57: within 0.5 %, the tables' last digit).
#[test]
fn static_deflections_match_navier_and_timoshenko() {
    let d = material().rigidity();
    let ss = square(16, Support::SimplySupported, InPlane::Fixed);
    let point = static_center(&ss, false);
    let pressure = static_center(&ss, true);
    let (np, nq) = (navier_point_deflection(), navier_pressure_deflection());
    assert!((point - np).abs() < 1e-3 * np, "{point} vs {np}");
    assert!((pressure - nq).abs() < 1e-5 * nq, "{pressure} vs {nq}");
    let cl = square(16, Support::Clamped, InPlane::Fixed);
    let point = static_center(&cl, false) * d;
    let pressure = static_center(&cl, true) * d;
    assert!((point - 0.00560).abs() < 0.005 * 0.00560, "{point}");
    assert!((pressure - 0.00126).abs() < 0.005 * 0.00126, "{pressure}");
}

/// The polynomial force derives from a strain energy: its Jacobian is
/// symmetric at any state (checked at a pseudo-random one on a 3 x 2 mesh of
/// oblong elements, to 1e-12 of its largest entry).
#[test]
fn the_polynomial_force_has_a_symmetric_jacobian() {
    let mesh = Mesh {
        nx: 3,
        ny: 2,
        a: 1.2,
        ..square(3, Support::SimplySupported, InPlane::Sliding)
    };
    let a = assemble(&mesh);
    let n = a.numbering.len();
    let mut seed = 12345u64;
    let z: Vec<f64> = (0..n)
        .map(|_| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e-2
        })
        .collect();
    let (_, jac) = polynomial(&a.force, &z);
    let big = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .fold(0.0f64, |m, (i, j)| m.max(jac[(i, j)].abs()));
    for i in 0..n {
        for j in 0..n {
            let d = (jac[(i, j)] - jac[(j, i)]).abs();
            assert!(
                d <= 1e-12 * big,
                "J[{i}][{j}] - J[{j}][{i}] = {d:e} of {big:e}"
            );
        }
    }
    // 288 terms an element before merging those the elements share
    assert!(!a.force.terms.is_empty() && a.force.terms.len() <= 288 * 6);
}

/// The element's hardening of the first mode `Phi` (mass-normalized), with
/// the in-plane unknowns condensed statically as in the Galerkin reference:
/// `gamma = Phi . f3(Phi) - 2 f2_m(Phi) . K_mm^-1 f2_m(Phi)`.
fn element_hardening(n: usize) -> f64 {
    let a = assemble(&square(n, Support::SimplySupported, InPlane::Sliding));
    let (_, v) = modes(&a);
    let phi: Vec<f64> = (0..v.nrows()).map(|i| v[(i, 0)]).collect();
    let (f, _) = polynomial(&a.force, &phi);
    let membrane: Vec<usize> = a
        .numbering
        .nodes
        .iter()
        .flat_map(|d| {
            d.iter()
                .enumerate()
                .filter(|(k, _)| Numbering::is_membrane(*k))
        })
        .filter_map(|(_, g)| *g)
        .collect();
    let kmm = Mat::from_fn(membrane.len(), membrane.len(), |i, j| {
        a.stiffness[(membrane[i], membrane[j])]
    });
    let fm: Vec<f64> = membrane.iter().map(|&g| f[g]).collect();
    let um = solve(&kmm, &fm);
    let cubic: f64 = phi.iter().zip(&f).map(|(p, f)| p * f).sum();
    cubic - 2.0 * fm.iter().zip(&um).map(|(a, b)| a * b).sum::<f64>()
}

/// The von Karman hardening of the first mode of the simply supported square
/// plate (sliding in-plane edges) against the independent single-mode
/// Galerkin calculation: within 2 % at 16 x 16 elements (below), the error
/// falls at second order (each halving divides it by about 4, accepted in [3,
/// 6]: the membrane strain's slopes are those of the bilinear interpolation
/// of `w`, an `O(h)` slope error that enters the energy at `O(h^2)`), and the
/// Richardson extrapolation of the 8 x 8 and 16 x 16 values meets the
/// reference within 0.2 %.
#[test]
fn first_mode_hardening_matches_the_single_mode_galerkin() {
    let reference = von_karman_plate::galerkin::single_mode_hardening(&material(), 1.0, 1.0);
    let errors: Vec<f64> = [4, 8, 16]
        .iter()
        .map(|&n| (element_hardening(n) - reference) / reference)
        .collect();
    assert!(errors[2].abs() < 2e-2, "{errors:?}");
    for w in errors.windows(2) {
        let ratio = w[0] / w[1];
        assert!((3.0..=6.0).contains(&ratio), "rate {ratio} in {errors:?}");
    }
    let limit = errors[2] + (errors[2] - errors[1]) / 3.0;
    assert!(limit.abs() < 2e-3, "Richardson {limit} in {errors:?}");
}
