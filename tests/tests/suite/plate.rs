//! The von Karman plate plugin through the engine: the SSM backbone of the
//! simply supported plate's first mode against the single-mode Galerkin
//! hardening (an independent calculation: trigonometric Ritz functions, no
//! finite elements), and its forced expansions solved in bands against
//! direct solves.

use ssm_core::spectrum::{self, Method, Normalization};
use ssm_core::ssm::analysis::polar;
use ssm_tests::{spectrum_options, ssm_of, system};
use von_karman_plate::galerkin::single_mode_hardening;
use von_karman_plate::Material;

/// The leading backbone coefficient `kappa` of `omega = omega_0 + kappa A^2 +
/// O(A^4)`, `A` the amplitude of `w_center`, of the O(3) SSM of the first
/// pair of the `n x n` simply supported unit square plate (sliding in-plane
/// edges, nearly undamped): `kappa = Im c_1 / (4 |w_1|^2)` with `c_1` the
/// cubic polar coefficient and `w_1` the output's linear coefficient
/// (`A = 2 |w_1| rho + O(rho^3)`).
fn backbone_coefficient(n: usize) -> (f64, f64) {
    let params = format!(
        "nx = {n}\nny = {n}\ninplane = \"sliding\"\nbeta = 1e-9\nsupport = \"simply_supported\""
    );
    let sys = system("von-karman-plate", "plate", &params);
    let sp = spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &spectrum_options(Some(Method::Sparse), 12),
    )
    .expect("plate spectrum");
    let ssm = ssm_of(&sys, &sp, &[1], 3, Normalization::default());
    let pol = polar(&ssm).expect("one pair");
    let out = sys
        .outputs
        .iter()
        .find(|o| o.name == "w_center")
        .expect("w_center output");
    let series = ssm.output_series(&out.weights);
    let w1 = series[ssm.set.index(&[1, 0]).expect("linear index")].norm();
    (pol.c[0].im, pol.c[1].im / (4.0 * w1 * w1))
}

/// The engine's backbone on the plate plugin hardens as the single-mode
/// Galerkin model predicts, `kappa = 3 gamma m / (8 omega_0)` (`m = rho h a b
/// / 4` the modal mass, so that `w_center = eta / sqrt(m)` for the mass-
/// normalized `eta`): the 8 x 8 and 16 x 16 meshes' coefficients, Richardson-
/// extrapolated at the elements' second order, agree with it within 0.3 %
/// (what remains is the in-plane inertia the Galerkin model condenses
/// statically, `O((omega_b / omega_m)^2)`, and the coupling to the other
/// bending modes), and the 16 x 16 mesh's within 3 % (the slopes of the
/// membrane strain converge at `O(h^2)`).
#[test]
fn plate_backbone_hardens_like_the_single_mode_galerkin() {
    let mat = Material {
        young: 70e9,
        poisson: 0.33,
        density: 2700.0,
        thickness: 0.01,
    };
    let gamma = single_mode_hardening(&mat, 1.0, 1.0);
    let omega0 = 2.0 * std::f64::consts::PI.powi(2) * (mat.rigidity() / mat.areal_mass()).sqrt();
    let m = mat.areal_mass() / 4.0;
    let reference = 3.0 * gamma * m / (8.0 * omega0);
    let (w8, k8) = backbone_coefficient(8);
    let (w16, k16) = backbone_coefficient(16);
    assert!(
        (w16 - omega0).abs() < 1e-5 * omega0,
        "omega_0 {w16} vs {omega0} (8: {w8})"
    );
    let limit = k16 + (k16 - k8) / 3.0;
    assert!(
        (k16 - reference).abs() < 3e-2 * reference,
        "{k16} vs {reference}"
    );
    assert!(
        (limit - reference).abs() < 3e-3 * reference,
        "Richardson {limit} vs {reference}"
    );
}

/// The forced response's non-autonomous expansions on the 8 x 8 plate (708
/// states, factors dear enough for band solves): at the 17 Chebyshev nodes
/// of a band around the first frequency, to order 4 in `p`, the band solves
/// (one factorization per anchor, one shared search space for the nodes)
/// agree with a direct sparse LU solve (refined to componentwise backward
/// stability) at every node and multi-index within 1e-10 of each
/// coefficient vector, with one factorization per distinct
/// anchor at most (the imaginary parts of `Omega + k . lambda`,
/// `k_1 - k_2` in `-4..=4`: 9) against one per node and multi-index (255).
#[test]
fn band_solved_expansions_agree_with_direct_solves_on_the_plate() {
    use ssm_core::rom::frc::ForcedCoefficients;
    use ssm_core::ssm::forced::ForcedSsm;
    let sys = system("von-karman-plate", "plate", "nx = 8\nny = 8\nbeta = 2e-5");
    let sp = spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &spectrum_options(Some(Method::Sparse), 6),
    )
    .expect("plate spectrum");
    let norm = Normalization::default();
    let masters = spectrum::master_modes(&sys, &sp, &[1], norm).expect("master pair");
    let ssm = ssm_of(&sys, &sp, &[1], 5, norm);
    let nodes = ForcedCoefficients::nodes(280.0, 380.0, 17);
    let order = 4;
    let run = |anchor: Option<f64>| {
        let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
        let na = forced
            .expansions(&ssm, &sys, &nodes, order, anchor)
            .expect("expansions");
        (na, forced.counts())
    };
    let (band, band_counts) = run(Some(330.0));
    let (direct, direct_counts) = run(None);
    eprintln!("band: {band_counts:?}; direct: {direct_counts:?}");
    assert_eq!(direct_counts.iterations, 0);
    assert!(band_counts.iterations > 0, "{band_counts:?}");
    assert!(band_counts.factorizations <= 9, "{band_counts:?}");
    let per_node = band[0].set.len();
    assert_eq!(direct_counts.factorizations, nodes.len() * per_node);
    let mut worst = 0.0f64;
    for (b, d) in band.iter().zip(&direct) {
        for (hb, hd) in b.harmonics.iter().zip(&d.harmonics) {
            for (xb, xd) in hb.x.iter().zip(&hd.x).chain(hb.s.iter().zip(&hd.s)) {
                let scale = xd.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
                let diff = xb
                    .iter()
                    .zip(xd)
                    .map(|(p, q)| (p - q).norm_sqr())
                    .sum::<f64>()
                    .sqrt();
                if scale > 0.0 {
                    worst = worst.max(diff / scale);
                } else {
                    assert_eq!(diff, 0.0);
                }
            }
        }
    }
    eprintln!("band vs direct: worst relative difference {worst:.2e}");
    assert!(worst <= 1e-10, "{worst:e}");
}
