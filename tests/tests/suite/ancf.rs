//! The planar ANCF beam element (`von_karman_beam::ancf`) through the
//! `ancf-beam` cantilever of the `crank-drive` plugin, against the closed
//! forms of beam theory: the static tip deflection, the uniform stretch of a
//! bar with Green strain, and the first bending and axial frequencies, with
//! the convergence of the frequencies under mesh refinement.

use faer::prelude::Solve;
use ssm_api::{Model, PolyVector, SparseMatrix};
use ssm_core::spectrum;
use ssm_tests::{model_and_system, spectrum_options, upper_half};

/// `(M, z) -> sum coeff prod z^p` of each component.
fn eval_poly(p: &PolyVector, z: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; p.n_eq as usize];
    for t in p.terms.iter() {
        out[t.eq as usize] += t.coeff
            * t.factors
                .iter()
                .map(|f| z[f.var as usize].powi(f.power as i32))
                .product::<f64>();
    }
    out
}

fn mat_vec(a: &SparseMatrix, z: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.nrows as usize];
    for (r, c, v) in a.iter() {
        out[r] += v * z[c];
    }
    out
}

/// The first-order right-hand side `A z + F(z) + Fext_0` of the model
/// (the symmetric form of eqs. 4-5 of Li, Jain & Haller 2023) at rest in the
/// configuration `q` (velocities zero), on its first `n` rows: the static
/// residual `f_ext - K q - f(q)`.
/// With `nonlinear` false, the nonlinear force is left out.
fn static_residual(model: &Model, q: &[f64], nonlinear: bool) -> Vec<f64> {
    let n = q.len();
    let mut z = q.to_vec();
    z.extend(std::iter::repeat_n(0.0, n));
    let mut r = mat_vec(&model.a, &z);
    if nonlinear {
        for (ri, fi) in r.iter_mut().zip(eval_poly(&model.nonlinearity, &z)) {
            *ri += fi;
        }
    }
    for h in model.forcing.iter().filter(|h| h.multiple == 0.0) {
        for (ri, fi) in r.iter_mut().zip(eval_poly(&h.cos, &z)) {
            *ri += fi;
        }
    }
    r.truncate(n);
    r
}

/// Reference: Euler-Bernoulli beam theory, `w_tip = P L^3 / (3 EI)` for a
/// transverse tip load `P` on a cantilever (the cubic Hermite elements
/// reproduce the cubic deflection exactly, so to rounding: 1e-9), and the
/// exact solution of a bar under an axial tip force `F` with the Green strain
/// `e = (lambda^2 - 1) / 2`: the uniform stretch `lambda` with
/// `EA e lambda = F` (here `lambda = 1.3`, a strain no linear model
/// represents), in which the model's static residual vanishes to 1e-12 of
/// `F`.
#[test]
fn cantilever_statics_match_beam_theory() {
    let (ea, ei, length) = (1.0e4_f64, 2.0_f64, 1.5_f64);
    let n_el = 6;
    let params = |fx: f64, fy: f64| {
        format!(
            "elements = {n_el}\nlength = {length}\nea = {ea}\nei = {ei}\ntip_fx = {fx}\ntip_fy = {fy}\ntip_amp = 0.0"
        )
    };
    // transverse: the linear solve K q = f (the load is small; the linear
    // stiffness is the model's)
    let p = 1e-3;
    let (model, sys) = model_and_system("crank-drive", "ancf-beam", &params(0.0, p));
    let n = sys.mechanical.as_ref().expect("mechanical").n_dof;
    assert_eq!(n, 1 + 4 * n_el);
    let mut k = faer::Mat::<f64>::zeros(n, n);
    for (r, c, v) in model.a.iter() {
        if r < n && c < n {
            k[(r, c)] -= v;
        }
    }
    let f = static_residual(&model, &vec![0.0; n], true);
    let rhs = faer::Mat::<f64>::from_fn(n, 1, |i, _| f[i]);
    let q = k.partial_piv_lu().solve(&rhs);
    let w_tip = q[(n - 3, 0)];
    let want = p * length.powi(3) / (3.0 * ei);
    eprintln!("w_tip {w_tip:e}, P L^3 / 3 EI {want:e}");
    assert!((w_tip / want - 1.0).abs() < 1e-9, "{w_tip} {want}");

    // axial: the exact stretched configuration solves the nonlinear model
    let lambda = 1.3_f64;
    let force = ea * (lambda * lambda - 1.0) / 2.0 * lambda;
    let (model, _) = model_and_system("crank-drive", "ancf-beam", &params(force, 0.0));
    let h = length / n_el as f64;
    // positions, then slopes scaled by the element length (`h r'`)
    let q: Vec<f64> = std::iter::once((lambda - 1.0) * h)
        .chain(
            (1..=n_el).flat_map(|j| [(lambda - 1.0) * h * j as f64, 0.0, (lambda - 1.0) * h, 0.0]),
        )
        .collect();
    let largest = |r: Vec<f64>| r.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let worst = largest(static_residual(&model, &q, true));
    // the linear stiffness alone is far from it (the check has teeth)
    let linear = largest(static_residual(&model, &q, false));
    eprintln!(
        "stretch {lambda}: residual {:e} of F, {:e} without the nonlinear force",
        worst / force,
        linear / force
    );
    assert!(worst < 1e-12 * force, "{worst:e}");
    assert!(linear > 0.1 * force, "{linear:e}");
}

/// The cantilever's finite eigenvalues nearest zero (undamped: imaginary
/// parts) in increasing frequency.
fn frequencies(n_el: usize, count: usize) -> Vec<f64> {
    let (_, sys) = model_and_system(
        "crank-drive",
        "ancf-beam",
        &format!("elements = {n_el}\nea = 1.0e4\nei = 1.0\nrho_a = 1.0\nlength = 1.0"),
    );
    let sp = spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &spectrum_options(None, 2 * count),
    )
    .expect("spectrum");
    upper_half(&sp.eigenvalues)
        .iter()
        .map(|l| l.im)
        .take(count)
        .collect()
}

/// Reference: the Euler-Bernoulli cantilever, `omega_k = (beta_k L)^2
/// sqrt(EI / (rhoA L^4))` with `beta_k L = 1.8751040687, 4.6940911330,
/// 7.8547574382`, and the fixed-free bar, `omega = k sqrt(EA / rhoA)`, `k =
/// pi / 2L` (here 157.08, between the fourth and fifth bending
/// frequencies). The element's bending measure `|r''|^2` also stiffens axial
/// waves (`EI u''^2`): the bar's frequency is raised by `EI k^2 / (2 EA)` to
/// first order (1.234e-4 here); the model's axial frequency is the bar's with
/// that shift to 1e-5 (the neglected boundary layer), on both meshes. The
/// bending frequencies at 8 elements are within 1e-3 relative, and from 4 to
/// 8 elements their errors fall at least 12 times (the cubic elements'
/// `h^4`, 16 times, up to the pre-asymptotic range; measured 15.7, 14.6,
/// 12.7).
#[test]
fn cantilever_frequencies_match_beam_theory_and_converge() {
    let bending = [1.875_104_068_7_f64, 4.694_091_133_0, 7.854_757_438_2].map(|b| b * b);
    let k = std::f64::consts::FRAC_PI_2;
    let (ea, ei) = (1.0e4_f64, 1.0_f64);
    let axial = k * ea.sqrt();
    let shift = ei * k * k / (2.0 * ea);
    let errors = |n_el: usize| -> (Vec<f64>, f64) {
        let w = frequencies(n_el, 6);
        eprintln!("{n_el} elements: {w:?}");
        let nearest = |x: f64| {
            w.iter()
                .map(|v| v / x - 1.0)
                .min_by(|a, b| a.abs().total_cmp(&b.abs()))
                .expect("frequencies")
        };
        let e: Vec<f64> = bending.iter().map(|&b| nearest(b).abs()).collect();
        (e, nearest(axial))
    };
    let ((coarse, axial_coarse), (fine, axial_fine)) = (errors(4), errors(8));
    eprintln!(
        "bending errors at 4 elements {coarse:?}, at 8 {fine:?}; axial {axial_coarse:e}, {axial_fine:e} against the shift {shift:e}"
    );
    for (c, f) in coarse.iter().zip(&fine) {
        assert!(*f < 1e-3, "{fine:?}");
        assert!(c / f > 12.0, "{coarse:?} -> {fine:?}");
    }
    for a in [axial_coarse, axial_fine] {
        assert!((a - shift).abs() < 1e-5, "{a:e} against {shift:e}");
    }
}
