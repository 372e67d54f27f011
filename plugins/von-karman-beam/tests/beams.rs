//! The element against beam theory: static tip deflection, the stiffening of an
//! axially restrained beam under a large load, and the first bending frequency
//! with its convergence rate.

use faer::prelude::Solve;
use faer::Mat;
use ssm_api::{PolyVector, SparseMatrix};
use von_karman_beam::{Mesh, Numbering, Section, Support};

/// The horizontal beam of the divider: 707 x 10 x 1 mm, aluminium (mm, kg, s).
fn section() -> Section {
    Section::rectangular(10.0, 1.0, 70e6, 2700e-9)
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

/// Internal force `K q + f(q)` and its Jacobian `K + df/dq`.
fn internal(a: &Assembled, q: &[f64]) -> (Vec<f64>, Mat<f64>) {
    let n = q.len();
    let mut f: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| a.stiffness[(i, j)] * q[j]).sum())
        .collect();
    let mut jac = a.stiffness.clone();
    for t in a.force.terms.iter() {
        let eq = t.eq as usize;
        let value: f64 = t
            .factors
            .iter()
            .map(|p| q[p.var as usize].powi(p.power as i32))
            .product();
        f[eq] += t.coeff * value;
        for (i, p) in t.factors.iter().enumerate() {
            let rest: f64 = t
                .factors
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, o)| q[o.var as usize].powi(o.power as i32))
                .product();
            let d = p.power as f64 * q[p.var as usize].powi(p.power as i32 - 1) * rest;
            jac[(eq, p.var as usize)] += t.coeff * d;
        }
    }
    (f, jac)
}

fn solve(a: &Mat<f64>, b: &[f64]) -> Vec<f64> {
    let rhs = Mat::from_fn(b.len(), 1, |i, _| b[i]);
    let x = a.partial_piv_lu().solve(&rhs);
    (0..b.len()).map(|i| x[(i, 0)]).collect()
}

/// Static equilibrium `K q + f(q) = load` by Newton with load stepping.
fn static_solution(a: &Assembled, load: &[f64], steps: usize) -> Vec<f64> {
    let mut q = vec![0.0; load.len()];
    for s in 1..=steps {
        let scale = s as f64 / steps as f64;
        for _ in 0..50 {
            let (f, jac) = internal(a, &q);
            let r: Vec<f64> = f.iter().zip(load).map(|(f, l)| f - scale * l).collect();
            let dq = solve(&jac, &r);
            let norm = dq.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            q.iter_mut().zip(&dq).for_each(|(q, d)| *q -= d);
            if norm < 1e-12 * q.iter().fold(1e-30f64, |m, q| m.max(q.abs())) {
                break;
            }
        }
    }
    q
}

/// Linear tip deflection of a cantilever under an end load `P` against Euler-
/// Bernoulli theory, `w = P L^3 / (3 EI)`. Hermite elements reproduce the
/// cubic static deflection exactly, so the tolerance is round-off (1e-9).
#[test]
fn cantilever_tip_deflection_matches_p_l3_over_3ei() {
    let mesh = Mesh {
        length: 707.0,
        section: section(),
        elements: 10,
        start: Support::Clamped,
        end: Support::Free,
    };
    let a = assemble(&mesh);
    let tip = a.numbering.get(10, 1).unwrap();
    let p = 1e-3;
    let mut load = vec![0.0; a.numbering.len()];
    load[tip] = p;
    let q = solve(&a.stiffness, &load);
    let exact = p * 707f64.powi(3) / (3.0 * section().ei);
    let rel = (q[tip] - exact).abs() / exact;
    assert!(rel < 1e-9, "tip {} vs PL^3/3EI {exact}: {rel:e}", q[tip]);
}

/// Center deflection of a clamped-clamped, axially restrained beam under a
/// central load `P`, from the von Karman beam equations `EI w'''' - N w'' = P
/// delta(x - L/2)` with the membrane force `N = EA/(2L) int_0^L w'^2 dx`
/// (axial equilibrium, `u(0) = u(L) = 0`): for a given `N` the half beam has the
/// closed-form deflection `w = A + B x + C cosh(kx) + D sinh(kx)`, `k^2 =
/// N/EI`, and `N` is the root of the scalar compatibility equation (bisection).
/// An independent solution: no finite elements, no polynomial force.
fn membrane_reference(p: f64, l: f64, s: Section) -> f64 {
    let h = 0.5 * l;
    let shape = |n: f64| {
        let k = (n / s.ei).sqrt();
        let b = p / (2.0 * n);
        let d = -b / k;
        let c = p / (2.0 * s.ei * k.powi(3)) * ((k * h).cosh() - 1.0) / (k * h).sinh();
        (k, b, c, d)
    };
    let slope_integral = |n: f64| {
        let (k, b, c, d) = shape(n);
        let m = 20_000;
        let dx = h / m as f64;
        // Simpson's rule, error ~ (k h)^4 dx^4 / 180 relative: negligible
        (0..=m)
            .map(|i| {
                let x = i as f64 * dx;
                let ws = b + k * c * (k * x).sinh() + k * d * (k * x).cosh();
                let weight = if i == 0 || i == m {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                weight * ws * ws
            })
            .sum::<f64>()
            * dx
            / 3.0
    };
    // N L / EA = int_0^L w'^2 / 2 = int_0^h w'^2
    let residual = |n: f64| n - s.ea / l * slope_integral(n);
    let (mut lo, mut hi) = (1e-6f64, 1e9f64);
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if residual(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let (k, b, c, d) = shape(lo);
    b * h + c * (k * h).cosh() + d * (k * h).sinh() - c
}

/// The axially restrained beam stiffens: under a load whose linear deflection
/// is 15.8 thicknesses the center deflection is 2.72 thicknesses. The FE
/// center deflection agrees with the membrane solution within 0.15 % at 40
/// elements (measured 0.083 %), and the error falls at second order (each
/// halving divides it by about 4, accepted in [3, 6]): the element's axial
/// strain `u' + w'^2/2` is not constant inside an element, while the exact
/// membrane force is, an O(h^2) discrepancy.
#[test]
fn clamped_clamped_beam_stiffens_like_the_membrane_solution() {
    let (l, p) = (707.0, 500.0);
    let reference = membrane_reference(p, l, section());
    let linear = p * l.powi(3) / (192.0 * section().ei);
    assert!(
        reference < 0.5 * linear,
        "reference {reference} vs linear {linear}"
    );
    let mut errors = Vec::new();
    for elements in [10, 20, 40] {
        let mesh = Mesh {
            length: l,
            section: section(),
            elements,
            start: Support::Clamped,
            end: Support::Clamped,
        };
        let a = assemble(&mesh);
        let mid = a.numbering.get(elements / 2, 1).unwrap();
        let mut load = vec![0.0; a.numbering.len()];
        load[mid] = p;
        let q = static_solution(&a, &load, 10);
        errors.push((q[mid] - reference).abs() / reference);
    }
    assert!(errors[2] < 1.5e-3, "errors {errors:?}");
    for w in errors.windows(2) {
        let ratio = w[0] / w[1];
        assert!((3.0..=6.0).contains(&ratio), "rate {ratio} in {errors:?}");
    }
}

/// Lowest eigenvalue of `K v = omega^2 M v` by inverse iteration.
fn lowest_frequency(a: &Assembled) -> f64 {
    let n = a.numbering.len();
    let mut x = vec![1.0; n];
    let mut omega2 = 0.0;
    for _ in 0..200 {
        let mx: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| a.mass[(i, j)] * x[j]).sum())
            .collect();
        let y = solve(&a.stiffness, &mx);
        let ky: f64 = (0..n)
            .map(|i| y[i] * (0..n).map(|j| a.stiffness[(i, j)] * y[j]).sum::<f64>())
            .sum();
        let my: f64 = (0..n)
            .map(|i| y[i] * (0..n).map(|j| a.mass[(i, j)] * y[j]).sum::<f64>())
            .sum();
        let next = ky / my;
        let norm = my.sqrt();
        x = y.iter().map(|v| v / norm).collect();
        if (next - omega2).abs() < 1e-15 * next {
            break;
        }
        omega2 = next;
    }
    omega2.sqrt()
}

/// First bending frequency of a cantilever against `(beta1 L)^2 sqrt(EI /
/// (rhoA L^4))`, `beta1 L = 1.875104068711961` (root of `cos x cosh x = -1`):
/// below 1e-5 relative at 8 elements, and the error falls at the rate `h^4`
/// of cubic Hermite elements with consistent mass (Strang & Fix: eigenvalue
/// error `h^(2(p+1-m))`, `p = 3`, `m = 2`): each halving divides it by 16
/// (accepted in [12, 20]).
#[test]
fn cantilever_frequency_converges_at_fourth_order() {
    let (l, s) = (707.0f64, section());
    let beta_l: f64 = 1.875_104_068_711_961;
    let exact = beta_l * beta_l * (s.ei / (s.rho_a * l.powi(4))).sqrt();
    let errors: Vec<f64> = [2, 4, 8]
        .iter()
        .map(|&elements| {
            let mesh = Mesh {
                length: l,
                section: s,
                elements,
                start: Support::Clamped,
                end: Support::Free,
            };
            (lowest_frequency(&assemble(&mesh)) - exact) / exact
        })
        .collect();
    assert!(
        errors.iter().all(|&e| e > 0.0),
        "Rayleigh-Ritz bounds from above: {errors:?}"
    );
    assert!(errors[2] < 1e-5, "errors {errors:?}");
    for w in errors.windows(2) {
        let ratio = w[0] / w[1];
        assert!((12.0..=20.0).contains(&ratio), "rate {ratio} in {errors:?}");
    }
}
