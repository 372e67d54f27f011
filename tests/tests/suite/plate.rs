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

/// Largest relative difference, over frequencies, harmonics and
/// multi-indices, between the coefficient vectors `x`, `s` of two sets of
/// expansions (a vector that is zero in `b` must be zero in `a`).
/// `||a - b|| / ||b||` (2-norms), or `Err(||a - b||)` for a zero `b`.
fn relative_gap(a: &[ssm_core::C64], b: &[ssm_core::C64]) -> Result<f64, f64> {
    let scale = b.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
    let diff = a
        .iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm_sqr())
        .sum::<f64>()
        .sqrt();
    if scale > 0.0 {
        Ok(diff / scale)
    } else {
        Err(diff)
    }
}

fn worst_difference(
    a: &[ssm_core::ssm::nonautonomous::NonAutonomous],
    b: &[ssm_core::ssm::nonautonomous::NonAutonomous],
) -> f64 {
    assert_eq!(a.len(), b.len());
    let mut worst = 0.0f64;
    for (ea, eb) in a.iter().zip(b) {
        assert_eq!(ea.omega, eb.omega);
        for (ha, hb) in ea.harmonics.iter().zip(&eb.harmonics) {
            for (xa, xb) in ha.x.iter().zip(&hb.x).chain(ha.s.iter().zip(&hb.s)) {
                match relative_gap(xa, xb) {
                    Ok(gap) => worst = worst.max(gap),
                    Err(diff) => assert_eq!(diff, 0.0),
                }
            }
        }
    }
    worst
}

/// The 8 x 8 clamped plate (light damping) and its 6 eigenvalues nearest
/// the origin by the sparse path.
fn plate_8x8() -> (
    ssm_core::model::system::System,
    ssm_core::spectrum::Spectrum,
) {
    let sys = system("von-karman-plate", "plate", "nx = 8\nny = 8\nbeta = 2e-5");
    let sp = spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &spectrum_options(Some(Method::Sparse), 6),
    )
    .expect("plate spectrum");
    (sys, sp)
}

/// The 8 x 8 plate (708 states, factors dear enough for band solves), its
/// O(5) SSM of the first pair and its forced SSM.
fn plate_forced() -> (
    ssm_core::model::system::System,
    Vec<ssm_core::spectrum::MasterMode>,
    ssm_core::ssm::SsmExpansion,
) {
    let (sys, sp) = plate_8x8();
    let norm = Normalization::default();
    let masters = spectrum::master_modes(&sys, &sp, &[1], norm).expect("master pair");
    let ssm = ssm_of(&sys, &sp, &[1], 5, norm);
    (sys, masters, ssm)
}

/// The forced response's non-autonomous expansions on the 8 x 8 plate at
/// the 17 Chebyshev nodes of a band around the first frequency `omega_1`,
/// three ways: as Taylor series in `Omega` (one factorization per
/// multi-index, at its value `i Omega + k . lambda` at the band's middle, and
/// a few dozen solves), by band solves (one factorization per imaginary part
/// of that value, one shared search space for the nodes), and by a direct
/// sparse LU solve at every node and multi-index (refined to componentwise
/// backward stability). To order 2 in `p` (the order the plate's forced
/// response takes) the series converge and agree with the direct solves
/// within 1e-10 of each coefficient vector through 6 factorizations against
/// 102, and so do the rotating-frame coefficients and the output `w_center`
/// of each multi-index that the forced response's table reads off the
/// series without forming the states (relative to the largest of each). To
/// order 4
/// the multi-index `(3, 0)` meets the near internal resonance `3 lambda_1 +
/// i Omega ~ lambda_(2,2)` (`omega_(2,2) ~ 4 omega_1` on a square plate)
/// inside the band: its series cannot converge and is refused, and the band
/// solves, which the expansions then take, agree with the direct solves
/// within 1e-10 through at most 9 factorizations against 255.
#[test]
fn series_and_band_expansions_agree_with_direct_solves_on_the_plate() {
    use ssm_core::rom::frc::ForcedCoefficients;
    use ssm_core::ssm::forced::ForcedSsm;
    let (sys, masters, ssm) = plate_forced();
    let nodes = ForcedCoefficients::nodes(280.0, 380.0, 17);
    let fresh = || ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
    let direct = |order: usize| {
        let mut forced = fresh();
        let out = forced
            .expansions_solved(&ssm, &sys, &nodes, order, None)
            .expect("direct");
        let counts = forced.counts();
        assert_eq!(counts.iterations, 0);
        assert_eq!(counts.factorizations, nodes.len() * out[0].set.len());
        out
    };
    // order 2: the series
    let mut forced = fresh();
    let series = forced
        .expansion_series(&ssm, &sys, &nodes, 2, 330.0)
        .expect("series")
        .expect("the series converges over the band and passes its checks");
    let series_counts = forced.counts();
    let series_at: Vec<_> = nodes.iter().map(|&w| series.at(w)).collect();
    let mut forced = fresh();
    let through_expansions = forced
        .expansions(&ssm, &sys, &nodes, 2, Some(330.0))
        .expect("expansions");
    assert_eq!(forced.counts(), series_counts, "expansions take the series");
    assert_eq!(worst_difference(&through_expansions, &series_at), 0.0);
    let per_index = series.set.len();
    assert!(series_counts.factorizations <= 6, "{series_counts:?}");
    assert!(
        series_counts.iterations <= ssm_core::ssm::SERIES_TERMS * per_index,
        "{series_counts:?}"
    );
    let exact = direct(2);
    let s_err = worst_difference(&series_at, &exact);
    eprintln!(
        "series: {series_counts:?} ({} terms at most), worst relative difference to direct {s_err:.2e}",
        series.terms()
    );
    assert!(s_err <= 1e-10, "series {s_err:e}");
    // what the forced response's table reads, from the series without the
    // states: the rotating-frame coefficients and an output of every
    // multi-index's x, against the direct solves'
    let w_center = &sys
        .outputs
        .iter()
        .find(|o| o.name == "w_center")
        .expect("output")
        .weights;
    let output =
        |x: &[ssm_core::C64]| -> ssm_core::C64 { w_center.iter().map(|&(s, w)| x[s] * w).sum() };
    let mut reduced_err = 0.0f64;
    for (&w, e) in nodes.iter().zip(&exact) {
        let (sigma, tau) = series.rotating_frame_coefficients_at(w);
        let (sigma_e, tau_e) = e.rotating_frame_coefficients();
        let outs = series.outputs_at(w, w_center);
        let outs_e: Vec<ssm_core::C64> = e.harmonics[0].x.iter().map(|x| output(x)).collect();
        for (a, b) in [(sigma, sigma_e), (tau, tau_e), (outs, outs_e)] {
            assert_eq!(a.len(), b.len());
            let scale = b.iter().map(|c| c.norm()).fold(0.0, f64::max);
            assert!(scale > 0.0);
            for (x, y) in a.iter().zip(&b) {
                reduced_err = reduced_err.max((x - y).norm() / scale);
            }
        }
    }
    eprintln!("reduced coefficients and outputs from the series: {reduced_err:.2e}");
    assert!(reduced_err <= 1e-10, "reduced {reduced_err:e}");
    // order 4: the series is refused, the band solves take over
    let mut forced = fresh();
    let refused = forced
        .expansion_series(&ssm, &sys, &nodes, 4, 330.0)
        .expect("series");
    assert!(refused.is_none(), "a series across an internal resonance");
    let mut forced = fresh();
    let band = forced
        .expansions_solved(&ssm, &sys, &nodes, 4, Some(330.0))
        .expect("band");
    let band_counts = forced.counts();
    assert!(band_counts.iterations > 0, "{band_counts:?}");
    assert!(band_counts.factorizations <= 9, "{band_counts:?}");
    let mut forced = fresh();
    let through_expansions = forced
        .expansions(&ssm, &sys, &nodes, 4, Some(330.0))
        .expect("expansions");
    assert_eq!(worst_difference(&through_expansions, &band), 0.0);
    let b_err = worst_difference(&band, &direct(4));
    eprintln!("band: {band_counts:?}, worst relative difference to direct {b_err:.2e}");
    assert!(b_err <= 1e-10, "band {b_err:e}");
}

/// The leading-order terms `X0`, `S0` of the 8 x 8 plate from the Taylor
/// series the output table of 280..380 rad/s keeps (what the forced
/// response's error figure at its leading order reads at the peak's
/// frequency) against a direct sparse solve at each of 9 frequencies of
/// the band: within 1e-10 of the state vector; none outside the band. With
/// the series expanded over the non-autonomous nodes' wider band
/// (270..390), the order-2 expansion's multi-index 0 takes it (rescaled to
/// its own band) in place of its own series, and the expansion still agrees
/// with direct solves at the 17 nodes within 1e-10, through fewer series
/// terms than without it.
#[test]
fn the_output_tables_series_gives_the_leading_terms_of_a_direct_solve() {
    use ssm_core::rom::frc::ForcedCoefficients;
    use ssm_core::ssm::forced::ForcedSsm;
    let (sys, masters, ssm) = plate_forced();
    let w_center = sys
        .outputs
        .iter()
        .find(|o| o.name == "w_center")
        .expect("output");
    let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
    forced.anchor_at(330.0);
    forced
        .tabulate_outputs(280.0, 380.0, &[w_center.weights.as_slice()])
        .expect("table");
    let mut direct = ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
    for k in 0..9 {
        let omega = 280.0 + 12.5 * k as f64;
        let series = forced.at_series(omega).expect("in the band");
        let exact = direct.at(omega).expect("direct solve");
        let (x, y) = (&series.harmonics[0], &exact.harmonics[0]);
        let scale = y.x.iter().map(|c| c.norm()).fold(0.0, f64::max);
        let gap =
            x.x.iter()
                .zip(&y.x)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
        assert!(gap <= 1e-10 * scale, "{omega}: {gap:e} of {scale:e}");
        let s_gap = (x.s[0] - y.s[0]).norm();
        assert!(s_gap <= 1e-10 * y.s[0].norm(), "{omega}: s {s_gap:e}");
    }
    assert!(forced.at_series(381.0).is_none(), "outside the band");
    // the non-autonomous expansion's multi-index 0 from the table's series
    let nodes = ForcedCoefficients::nodes(270.0, 390.0, 17);
    let expand = |reuse: bool| {
        let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
        forced.anchor_at(330.0);
        if reuse {
            forced
                .tabulate_outputs_within(
                    280.0,
                    380.0,
                    (270.0, 390.0),
                    &[w_center.weights.as_slice()],
                )
                .expect("table");
        }
        let before = forced.counts().iterations;
        let series = forced
            .expansion_series(&ssm, &sys, &nodes, 2, 330.0)
            .expect("series")
            .expect("converges");
        let at: Vec<_> = nodes.iter().map(|&w| series.at(w)).collect();
        (at, forced.counts().iterations - before)
    };
    let (reused, reused_terms) = expand(true);
    let (own, own_terms) = expand(false);
    assert!(reused_terms < own_terms, "{reused_terms} vs {own_terms}");
    let exact = ForcedSsm::new(&sys, &masters, &[1.0])
        .expect("forced SSM")
        .expansions_solved(&ssm, &sys, &nodes, 2, None)
        .expect("direct");
    for (name, got) in [("reused", &reused), ("own", &own)] {
        let err = worst_difference(got, &exact);
        assert!(err <= 1e-10, "{name}: {err:e}");
    }
}

/// A band that holds a non-master eigenvalue of the pencil (the plate's
/// second frequency, near 2.5 times the first): the series of `X0` cannot
/// converge over it, the series is refused, and the expansions, solved
/// frequency by frequency instead, still agree with direct solves within
/// 1e-10 away from that eigenvalue.
#[test]
fn a_band_over_a_pencil_eigenvalue_is_solved_frequency_by_frequency() {
    use ssm_core::rom::frc::ForcedCoefficients;
    use ssm_core::ssm::forced::ForcedSsm;
    let (sys, masters, ssm) = plate_forced();
    let omega2 = ssm_core::spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &spectrum_options(Some(Method::Sparse), 6),
    )
    .expect("plate spectrum")
    .eigenvalues
    .iter()
    .map(|l| l.im)
    .filter(|&w| w > 1.5 * masters[0].lambda.im)
    .fold(f64::INFINITY, f64::min);
    let (lo, hi) = (280.0, 1.3 * omega2);
    let center = 0.5 * (lo + hi);
    assert!((omega2 - center).abs() < 0.5 * (hi - lo), "{omega2}");
    let nodes = ForcedCoefficients::nodes(lo, hi, 8);
    let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
    let series = forced
        .expansion_series(&ssm, &sys, &nodes, 2, center)
        .expect("series");
    assert!(series.is_none(), "a series over a pencil eigenvalue");
    let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
    let solved = forced
        .expansions(&ssm, &sys, &nodes, 2, Some(center))
        .expect("expansions");
    let mut forced = ForcedSsm::new(&sys, &masters, &[1.0]).expect("forced SSM");
    let direct = forced
        .expansions_solved(&ssm, &sys, &nodes, 2, None)
        .expect("direct");
    let err = worst_difference(&solved, &direct);
    assert!(err <= 1e-10, "{err:e}");
}

/// The memory `summary.json` reports for the 16 x 16 clamped plate (2,948
/// states, the default damping), its O(5) SSM of the first pair and its
/// forced response over 280..380 rad/s, as the engine's counting allocator
/// measured it: every order's coefficients are `16 N` bytes a multi-index;
/// the factors an order holds (one per distinct `k . lambda`, each of the
/// pencil with its velocities eliminated, and the mass matrix's LU) hold
/// between half and all of the gate's estimate before the run
/// (`lu_bytes_estimate`: 80 bytes an entry of the symbolic Cholesky factor
/// of the condensed pattern, whose real form's `L B L^T` the solves use, 64
/// of the mass matrix's); the forced response
/// holds at most the four factors the gate counts (`FRC_FACTORS_HELD`); and
/// the peak heap of the run, above the heap the model and its spectrum held
/// when the SSM began, stays within twice the most the factors (with the
/// forced response's search spaces) held at once plus all coefficients
/// (issue 43's bound).
#[test]
fn the_memory_of_the_plate_is_counted_per_order_and_bounded_by_its_factors() {
    let params = "nx = 16\nny = 16";
    let sys = system("von-karman-plate", "plate", params);
    let n = sys.n_states();
    let estimate =
        ssm_core::ssm::lu_bytes_estimate(sys.a.as_ref(), sys.b.as_ref(), sys.velocities())
            .expect("a pattern");
    assert!(
        estimate.shared > 0.0,
        "the plate's velocities are eliminated"
    );
    let dir = ssm_tests::tmp_dir("plate-memory");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let scene = dir.join("plate.toml");
    std::fs::write(
        &scene,
        format!(
            "[model]\nplugin = \"von-karman-plate\"\nname = \"plate\"\n[model.params]\n{params}\n\
             [ssm]\nmaster_pairs = [1]\norder = 5\n[outputs]\ncoordinates = [\"w_center\"]\n\
             [outputs.backbone]\npoints = 11\nrho_max = 0.05\norders = [5]\n\
             [forcing]\nepsilon = [1.0]\nomega_range = [280.0, 380.0]\norders = [5]\n"
        ),
    )
    .expect("scene written");
    let plugin = ssm_tests::plugin_path("von-karman-plate");
    let s = ssm_tests::run_binary(
        &["--plugin".as_ref(), plugin.as_os_str()],
        &scene,
        &dir.join("out"),
    );
    let _ = std::fs::remove_dir_all(&dir);
    let m = &s["memory"];
    let bytes = |v: &serde_json::Value| v.as_f64().expect("a counted figure");
    let orders = m["ssm_orders"].as_array().expect("orders");
    assert_eq!(
        orders
            .iter()
            .map(|o| o["order"].as_u64().unwrap())
            .collect::<Vec<_>>(),
        [2, 3, 4, 5]
    );
    let mut coefficients = 0.0;
    for o in orders {
        let k = o["order"].as_u64().unwrap();
        let count = o["multi_indices"].as_f64().unwrap();
        assert_eq!(count, (k + 1) as f64, "order {k}: one pair");
        assert_eq!(bytes(&o["coefficient_bytes"]), 16.0 * n as f64 * count);
        coefficients += bytes(&o["coefficient_bytes"]);
        let factors = o["factorizations"].as_f64().unwrap();
        // one factor per value k . lambda up to conjugation
        assert_eq!(factors, ((k + 2) / 2) as f64, "order {k}");
        let held = bytes(&o["factor_bytes"]);
        let (lo, hi) = (
            0.5 * factors * estimate.each,
            factors * estimate.each + estimate.shared,
        );
        assert!(
            held <= hi && held >= lo,
            "order {k}: {held:.4e} bytes in {factors} factors, estimated {lo:.4e}..{hi:.4e}"
        );
    }
    let ssm = bytes(&m["ssm_factor_bytes"]);
    let frc = bytes(&m["frc_factor_bytes"]);
    assert!(
        frc <= 4.0 * estimate.each + estimate.shared,
        "{frc:.4e} > 4 x {:.4e} + {:.4e}",
        estimate.each,
        estimate.shared
    );
    let peak = bytes(&m["peak_heap_bytes"]) - bytes(&m["heap_before_ssm_bytes"]);
    // the forced response's band solves hold their search spaces besides
    // their factors (`band_vectors` vectors of the system's size)
    let krylov = 16.0
        * n as f64
        * ssm_core::ssm::band_vectors(ssm_core::rom::frc::NONAUTONOMOUS_NODES) as f64;
    let bound = 2.0 * (ssm.max(frc + krylov) + coefficients);
    assert!(
        peak > 0.0 && peak <= bound,
        "peak heap {peak:.4e} above the model's > {bound:.4e}"
    );
    assert!(bytes(&m["peak_resident_bytes"]) > 0.0);
}

/// The sparse path's shift-invert through the condensed `K + sigma C +
/// sigma^2 M` (half the size, no solve with the mass matrix) against the LU
/// of the whole first-order pencil `A - sigma B`: the 8 x 8 plate's
/// eigenvalues nearest the origin (those of the 12 computed that lie within
/// 0.9 of the largest's modulus) agree within 1e-10 relative, and so does
/// the master eigenvalue its inverse iteration refines (the condensed
/// stiffness factorized by Cholesky at the shift 0, and the inverse
/// iteration through the `L B L^T` of the condensed pencil's real form),
/// and the displacements of its right vector lie within 1e-8 (relative,
/// after the best complex scaling) of those the whole pencil's LU gives.
#[test]
fn the_spectrum_through_the_condensed_pencil_is_the_whole_pencils() {
    let sys = system("von-karman-plate", "plate", "nx = 8\nny = 8\nbeta = 2e-5");
    let whole = spectrum_options(Some(Method::Sparse), 12);
    let condensed = ssm_core::spectrum::SpectrumOptions {
        velocities: sys.velocities(),
        ..whole.clone()
    };
    assert!(condensed.velocities.is_some());
    let a = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &whole).expect("spectrum");
    let b = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &condensed).expect("spectrum");
    assert_eq!(a.eigenvalues.len(), b.eigenvalues.len());
    // the square plate's pairs (1, 2) and (2, 1) nearly coincide, and the
    // iteration keeps whichever it converges first at the edge of the 12:
    // every eigenvalue of the condensed path below the edge has its match
    let edge = b.eigenvalues.iter().map(|l| l.norm()).fold(0.0, f64::max);
    let mut compared = 0;
    for y in b.eigenvalues.iter().filter(|l| l.norm() < 0.9 * edge) {
        let d = a
            .eigenvalues
            .iter()
            .map(|x| (x - y).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(
            d <= 1e-10 * y.norm(),
            "{y}: nearest whole-pencil eigenvalue {d:e} away"
        );
        compared += 1;
    }
    assert!(compared >= 6, "{compared} compared");
    let mut plain = sys.clone();
    plain.mechanical = None;
    let norm = Normalization::default();
    let m = spectrum::master_modes(&sys, &b, &[1], norm).expect("master pair");
    let p = spectrum::master_modes(&plain, &a, &[1], norm).expect("master pair");
    let (x, y) = (m[0].lambda, p[0].lambda);
    assert!((x - y).norm() <= 1e-10 * x.norm(), "{x} against {y}");
    // and the right vectors' displacements (the velocities are set from
    // them on the condensed path only) span the same direction as the whole
    // pencil's LU finds: the first mode is well separated, so independent
    // factorizations agree to near the solves' accuracy
    let nd = sys.velocities().expect("mechanical").start;
    let (xc, xw) = (&m[0].right[..nd], &p[0].right[..nd]);
    let dot = |x: &[ssm_core::C64], y: &[ssm_core::C64]| -> ssm_core::C64 {
        x.iter().zip(y).map(|(a, b)| a.conj() * b).sum()
    };
    let alpha = dot(xw, xc) / dot(xw, xw);
    let gap = xc
        .iter()
        .zip(xw)
        .map(|(c, w)| (c - alpha * w).norm_sqr())
        .sum::<f64>()
        .sqrt()
        / dot(xc, xc).re.sqrt();
    eprintln!("displacements of the master vector: {gap:e} apart");
    assert!(gap <= 1e-8, "{gap:e}");
}

/// The master mode of the 8 x 8 plate does not depend on where inverse
/// iteration starts: moving the starting eigenvalue by 1e-12 and 1e-9
/// relative moves the normalized right and left eigenvectors by at most
/// 1e-10 relative (measured 8.6e-12 and 6.2e-12). The velocity rows of the mechanical pencil fix the
/// velocities as `lambda` times the displacements; inverse iteration alone
/// finds them only through the mass matrix, whose near-null directions (the
/// slopes carry tiny masses) it leaves to rounding. The same model without
/// its mechanical layout, where they are not set, drifts by more than 1e-7
/// (measured 5.5e-5 for the 1e-12 change), which is what makes this a test
/// of the gauge and not of the iteration.
#[test]
fn the_master_mode_does_not_depend_on_the_starting_eigenvalue() {
    let (sys, sp) = plate_8x8();
    let norm = Normalization::default();
    let drift = |sys: &ssm_core::model::system::System, shift: f64| -> f64 {
        let base = spectrum::master_modes(sys, &sp, &[1], norm).expect("master pair");
        let mut moved = sp.clone();
        let index = base[0].index;
        moved.eigenvalues[index] *= 1.0 + shift;
        let other = spectrum::master_modes(sys, &moved, &[1], norm).expect("master pair");
        let gap = |a: &[ssm_core::C64], b: &[ssm_core::C64]| {
            let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_sqr()).sum();
            let s: f64 = a.iter().map(|x| x.norm_sqr()).sum();
            (d / s).sqrt()
        };
        gap(&base[0].right, &other[0].right).max(gap(&base[0].left, &other[0].left))
    };
    for shift in [1e-12, 1e-9] {
        let d = drift(&sys, shift);
        eprintln!("starting eigenvalue moved by {shift:e}: eigenvectors moved by {d:.2e}");
        assert!(d <= 1e-10, "{shift:e}: {d:.2e}");
    }
    let mut whole = sys.clone();
    whole.mechanical = None;
    let d = drift(&whole, 1e-12);
    eprintln!("without the mechanical layout: {d:.2e}");
    assert!(d > 1e-7, "{d:.2e}");
}

/// A mechanical model's homological equations solved with its velocities
/// eliminated (the symmetric `Lambda^2 M + Lambda C + K`, half the size,
/// factorized as the `L B L^T` of its real form) against
/// the LU of the whole first-order pencil `Lambda B - A` (the same model
/// and master modes, without its mechanical layout): on the 8 x 8 plate
/// every coefficient vector of the O(5) SSM and every coefficient of its
/// reduced dynamics agree within 1e-10 relative, and the symbolic analysis
/// before the run finds the condensed factors at most a third of the whole
/// pencil's (the first-order graph doubles every vertex of the second-order
/// one, so its factor holds about four times the entries).
#[test]
fn the_velocities_eliminated_solve_the_whole_pencil() {
    use ssm_core::ssm::{self as ssm_mod, SsmOptions};
    let (sys, masters, condensed) = plate_forced();
    let mut whole = sys.clone();
    whole.mechanical = None;
    assert_eq!(whole.velocities(), None);
    let sp = spectrum::compute(
        whole.a.as_ref(),
        whole.b.as_ref(),
        &spectrum_options(Some(Method::Sparse), 6),
    )
    .expect("plate spectrum");
    let others = ssm_mod::non_master(&sp.eigenvalues, &masters);
    let options = SsmOptions {
        order: 5,
        resonance_tol: 0.02,
    };
    let reference = ssm_mod::compute(&whole, &masters, &others, &options).expect("SSM");
    // the condensed pencil is symmetric: its real form's L B L^T solved it;
    // the whole pencil is not: an LU
    assert!(condensed.timing.linear.symmetric_factorizations > 0);
    assert_eq!(reference.timing.linear.symmetric_factorizations, 0);
    assert_eq!(condensed.w.len(), reference.w.len());
    let mut worst = 0.0f64;
    for (a, b) in condensed.w.iter().zip(&reference.w) {
        match relative_gap(a, b) {
            Ok(gap) => worst = worst.max(gap),
            Err(diff) => assert_eq!(diff, 0.0),
        }
    }
    assert!(worst <= 1e-10, "W: worst relative difference {worst:.2e}");
    assert_eq!(condensed.r.len(), reference.r.len());
    for (a, b) in condensed.r.iter().zip(&reference.r) {
        assert_eq!((a.coord, a.index), (b.coord, b.index));
        let d = (a.coeff - b.coeff).norm();
        assert!(
            d <= 1e-10 * b.coeff.norm().max(1e-300),
            "R: {a:?} against {b:?}"
        );
    }
    let est = |s: &ssm_core::model::system::System| {
        ssm_core::ssm::lu_bytes_estimate(s.a.as_ref(), s.b.as_ref(), s.velocities())
            .expect("a pattern")
    };
    let (c, f) = (est(&sys), est(&whole));
    assert_eq!(f.shared, 0.0);
    assert!(
        c.each <= f.each / 3.0 && c.shared < c.each,
        "condensed {c:?} against the whole pencil's {f:?}"
    );
}
