//! Spectrum of the pencil against published and closed-form references.

use num_complex::Complex64 as C64;
use ssm_core::model::system::System;
use ssm_core::spectrum::Normalization;
use ssm_core::spectrum::{self, Method};
use ssm_tests::{chain_eigenvalues, oscillator_published_eigenvalues, system, CHAIN_DEFAULTS};

use ssm_tests::spectrum_options as opts;
use ssm_tests::{oscillator_with_spectrum, OSCILLATOR_CONSTRAINTS};

/// True when `value` rounds to the printed decimal `printed` (half a unit in
/// its last printed digit).
fn agrees_to_printed(value: f64, printed: &str) -> bool {
    let decimals = printed.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    let p: f64 = printed.parse().unwrap();
    (value - p).abs() <= 0.5 * 10f64.powi(-decimals) + 1e-15
}

/// Li, Jain & Haller (2023) eqs. (26)-(27), printed digits:
/// -0.02 +- 1.9999i, -0.15 +- 2.9962i, (-0.25 +- 4.9937i unconstrained).
#[test]
fn oscillator_eigenvalues_match_eqs_26_27_to_printed_digits() {
    let printed = [
        ("-0.02", "1.9999"),
        ("-0.15", "2.9962"),
        ("-0.25", "4.9937"),
    ];
    for constraint in OSCILLATOR_CONSTRAINTS {
        let (sys, sp) = oscillator_with_spectrum(constraint);
        let expected = oscillator_published_eigenvalues(constraint);
        // exactly the finite pairs of the paper, nothing spurious: the 3 n_c = 3
        // infinite constraint modes are excluded
        assert_eq!(
            sp.eigenvalues.len(),
            2 * expected.len(),
            "{constraint}: {:?}",
            sp.eigenvalues
        );
        assert_eq!(sys.n_states(), if constraint == "none" { 6 } else { 7 });
        for (j, _) in expected.iter().enumerate() {
            let l = sp.eigenvalues[2 * j];
            let (re, im) = printed[j];
            assert!(
                agrees_to_printed(l.re, re) && agrees_to_printed(l.im, im),
                "{constraint}: pair {} = {l}, printed {re} + {im}i",
                j + 1
            );
            assert_eq!(sp.eigenvalues[2 * j + 1], l.conj());
        }
    }
}

/// Master modes satisfy A v = lambda B v and u^* A = lambda u^* B, with the
/// documented normalization and phase.
#[test]
fn master_modes_are_normalized_eigenvectors() {
    for constraint in OSCILLATOR_CONSTRAINTS {
        let (sys, sp) = oscillator_with_spectrum(constraint);
        for norm in [
            Normalization::Unit,
            Normalization::Mass,
            Normalization::Scale(0.8306),
        ] {
            let modes = spectrum::master_modes(&sys, &sp, &[1, 2], norm).unwrap();
            for m in &modes {
                check_mode(&sys, m, norm);
            }
        }
    }
}

fn check_mode(sys: &System, m: &spectrum::MasterMode, norm: Normalization) {
    use ssm_core::spectrum::modes::{spmv, spmv_t};
    let (a, b) = (sys.a.as_ref(), sys.b.as_ref());
    let av = spmv(a, &m.right);
    let bv = spmv(b, &m.right);
    let r: f64 = av
        .iter()
        .zip(&bv)
        .map(|(x, y)| (x - m.lambda * y).norm_sqr())
        .sum::<f64>()
        .sqrt();
    assert!(r < 1e-12, "right residual {r}");
    // left: A^T u = conj(lambda) B^T u for u^* A = lambda u^* B (real A, B)
    let atu = spmv_t(a, &m.left);
    let btu = spmv_t(b, &m.left);
    let r: f64 = atu
        .iter()
        .zip(&btu)
        .map(|(x, y)| (x - m.lambda.conj() * y).norm_sqr())
        .sum::<f64>()
        .sqrt();
    let un: f64 = m.left.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
    assert!(r < 1e-11 * un.max(1.0), "left residual {r}");
    let ubv: C64 = m.left.iter().zip(&bv).map(|(u, v)| u.conj() * v).sum();
    assert!((ubv - 1.0).norm() < 1e-12, "u^* B v = {ubv}");
    match norm {
        Normalization::Unit | Normalization::Scale(_) => {
            let target = match norm {
                Normalization::Scale(s) => s,
                _ => 1.0,
            };
            let n: f64 = m.right.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
            assert!((n - target).abs() < 1e-13 * target);
        }
        Normalization::Mass => {
            let mech = sys.mechanical.as_ref().unwrap();
            let x = &m.right[..mech.n_dof];
            let mx = spmv(mech.mass.as_ref(), x);
            let q: C64 = x.iter().zip(&mx).map(|(a, b)| a.conj() * b).sum();
            assert!((q - 1.0).norm() < 1e-12, "x^H M x = {q}");
        }
    }
    let vmax = m.right.iter().map(|c| c.norm()).fold(0.0, f64::max);
    let first = m
        .right
        .iter()
        .find(|c| c.norm() >= vmax * (1.0 - 1e-8))
        .unwrap();
    assert!(
        first.im.abs() < 1e-14 * vmax && first.re > 0.0,
        "phase: {first}"
    );
}

/// Sparse shift-invert path against the closed-form chain spectrum
/// (`ssm_tests::chain_eigenvalues`), relative error 1e-9.
#[test]
fn sparse_path_matches_closed_form_chain_spectrum() {
    let n = 1000;
    let sys = system("oscillator-chain", "chain", &format!("n = {n}"));
    let sp = spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &opts(Some(Method::Sparse), 6),
    )
    .unwrap();
    assert_eq!(sp.method, Method::Sparse);
    assert!(!sp.complete);
    let (k, alpha, beta) = CHAIN_DEFAULTS;
    let exact = chain_eigenvalues(n, k, alpha, beta, 3);
    for (j, e) in exact.iter().enumerate() {
        let l = sp.eigenvalues[2 * j];
        assert!(
            (l - e).norm() < 1e-9 * e.norm(),
            "pair {}: {l} vs {e}",
            j + 1
        );
    }
    let modes = spectrum::master_modes(&sys, &sp, &[1, 2], Normalization::Mass).unwrap();
    for m in &modes {
        check_mode(&sys, m, Normalization::Mass);
    }
}

/// Dense and sparse paths agree on the slow modes, also for a constrained
/// pencil with infinite eigenvalues (which the sparse path must never return).
#[test]
fn dense_and_sparse_paths_agree() {
    for (plugin, model, params) in [
        ("oscillator-chain", "chain", "n = 150"),
        ("spatial-oscillator", "", "constraint = \"cubic\""),
        ("spatial-oscillator", "", "constraint = \"spherical\""),
    ] {
        let sys = system(plugin, model, params);
        let d = spectrum::compute(
            sys.a.as_ref(),
            sys.b.as_ref(),
            &opts(Some(Method::Dense), 0),
        )
        .unwrap();
        let s = spectrum::compute(
            sys.a.as_ref(),
            sys.b.as_ref(),
            &opts(Some(Method::Sparse), 4),
        )
        .unwrap();
        assert_eq!(
            s.eigenvalues.len(),
            4,
            "{plugin} {params}: {:?}",
            s.eigenvalues
        );
        for (x, y) in s.eigenvalues.iter().zip(&d.eigenvalues) {
            assert!(
                (x - y).norm() < 1e-10 * y.norm(),
                "{plugin} {params}: {x} vs {y}"
            );
        }
    }
}

/// A master pair beyond the available pairs is an error naming both numbers.
#[test]
fn master_pair_out_of_range_is_an_error() {
    let sys = system("spatial-oscillator", "", "constraint = \"cubic\"");
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts(None, 0)).unwrap();
    let err = spectrum::master_modes(&sys, &sp, &[3], Normalization::Unit).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("master pair 3") && msg.contains("only 2"),
        "{msg}"
    );
}

/// Theorem 1, eq. (53): with omega2 = 3 omega1 and equal light damping,
/// lambda_3 ~ 3 lambda_1 (|a + b| = 3 <= order) must be named, with the fix.
#[test]
fn internal_resonance_is_named_with_its_fix() {
    let sys = system("spatial-oscillator", "", "omega2 = 6.0\nzeta2 = 0.01");
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts(None, 0)).unwrap();
    let rep = spectrum::check_resonances(&sp.eigenvalues, &[0], 5, 0.02, true);
    let w = rep
        .warnings
        .iter()
        .find(|w| w.contains("lambda_3 ~ 3 lambda_1"))
        .unwrap_or_else(|| panic!("{:?}", rep.warnings));
    assert!(w.contains("add pair 2 to the master pairs"), "{w}");
    // the default oscillator has no such resonance up to order 13
    let sys = system("spatial-oscillator", "", "");
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts(None, 0)).unwrap();
    let rep = spectrum::check_resonances(&sp.eigenvalues, &[0], 13, 0.02, true);
    assert!(rep.warnings.is_empty(), "{:?}", rep.warnings);
    // eq. (54): sigma(E) = Int(-0.25 / -0.02) = 12 for the unconstrained oscillator
    assert_eq!(rep.quotients.relative, Some(12));
}

/// The answers do not depend on units: `x'' + 2 zeta w x' + w^2 x + w^2 x^3 = 0`
/// in time `t` is the unit oscillator in time `w t`, so with mass-normalized
/// modes its eigenvalues are `w (-zeta +- i sqrt(1 - zeta^2))` (closed form)
/// and its polar coefficients divided by `w` are those of `w = 1`. At
/// `w = 3e7` and `3e-8` the dense path used to lose the modes (the position
/// rows of `(A - sigma B)^{-1} B` sat thirty decades below the velocity rows,
/// under the rank threshold), and at `w = 1e-7` the border rows of the
/// homological equation were measured against the wrong scale. Tolerance:
/// 1e-10 relative on eigenvalues (twelve digits of rounding in the
/// shift-invert), 1e-8 on the polar coefficients (homological solves of
/// conditioning `1/zeta`).
#[test]
fn spectrum_and_backbone_do_not_depend_on_units() {
    let zeta = 0.01;
    let scaled_polar = |w: f64, method: Method| -> Vec<C64> {
        let sys = system(
            "duffing",
            "",
            &format!("omega = {w:e}\nkappa = {:e}\nzeta = {zeta}", w * w),
        );
        let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts(Some(method), 2))
            .unwrap_or_else(|e| panic!("omega = {w:e}, {method:?}: {e}"));
        let exact = C64::new(-zeta, (1.0 - zeta * zeta).sqrt()) * w;
        let found = sp
            .eigenvalues
            .iter()
            .find(|l| l.im > 0.0)
            .unwrap_or_else(|| panic!("omega = {w:e}, {method:?}: {:?}", sp.eigenvalues));
        assert!(
            (found - exact).norm() <= 1e-10 * exact.norm(),
            "omega = {w:e}, {method:?}: {found} vs {exact}"
        );
        let ssm = ssm_tests::ssm_of(&sys, &sp, &[1], 5, Normalization::Mass);
        let polar = ssm_core::ssm::analysis::polar(&ssm).unwrap();
        polar.c.iter().map(|c| c / w).collect()
    };
    let unit = scaled_polar(1.0, Method::Dense);
    for w in [3e7, 3e-8, 1e-7] {
        for method in [Method::Dense, Method::Sparse] {
            let p = scaled_polar(w, method);
            assert_eq!(p.len(), unit.len(), "omega = {w:e}, {method:?}");
            for (k, (a, b)) in p.iter().zip(&unit).enumerate() {
                assert!(
                    (a - b).norm() <= 1e-8 * unit[0].norm(),
                    "omega = {w:e}, {method:?}, rho^{}: {a} vs {b}",
                    2 * k + 1
                );
            }
        }
    }
}

/// Two copies of one constraint (`x1 = 0` twice) make the pencil singular at
/// every shift: the error says so, names the likely causes, and does not send
/// the user to the shift (the advice used to be "set [spectrum] shift"
/// whatever the shift, with faer's `SymbolicSingular { index: .. }` beside it).
#[test]
fn redundant_constraints_are_named_not_blamed_on_the_shift() {
    use ssm_api::{PolyVector, SparseMatrix};
    use ssm_plugin_kit::{Constraints, MechanicalSystem};
    let mut m = MechanicalSystem::new("redundant", &["x1", "x2"]);
    m.mass = SparseMatrix::diagonal(&[1.0, 1.0]);
    m.damping = SparseMatrix::diagonal(&[0.02, 0.02]);
    m.stiffness = SparseMatrix::diagonal(&[1.0, 2.0]);
    let mut g = PolyVector::zeros(2, 2);
    g.push(0, 1.0, &[(0, 1)]);
    g.push(1, 1.0, &[(0, 1)]);
    m.constraints = Some(Constraints::polynomial(g));
    let sys = System::from_model("catalogue", m.into_model().unwrap()).unwrap();
    for method in [Method::Dense, Method::Sparse] {
        let err =
            spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts(Some(method), 2)).unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(err, spectrum::SpectrumError::SingularPencil { .. })
                && msg.contains("redundant constraints")
                && msg.contains("cannot help")
                && !msg.contains("SymbolicSingular"),
            "{method:?}: {msg}"
        );
    }
}

/// A shift that is an eigenvalue (0 for an oscillator without stiffness) is
/// told apart from a singular pencil, and the error names a shift at which
/// `A - sigma B` is regular (not the one that failed).
#[test]
fn a_shift_on_an_eigenvalue_gets_a_working_shift_suggested() {
    let sys = system("duffing", "", "omega = 0.0");
    for method in [Method::Dense, Method::Sparse] {
        let err =
            spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts(Some(method), 1)).unwrap_err();
        let spectrum::SpectrumError::SingularShift {
            shift, suggestion, ..
        } = err
        else {
            panic!("{method:?}: expected a singular shift, got {err}");
        };
        assert_eq!(shift, 0.0);
        let s = suggestion.expect("a regular shift is named");
        assert!(s != 0.0 && spectrum::sparse::is_regular_at(sys.a.as_ref(), sys.b.as_ref(), s));
    }
}

/// Reference: the closed-form chain spectrum (`chain_eigenvalues`). Without
/// `[spectrum] modes`, `auto` takes the sparse path for 1,000 states and
/// widens it until it holds every eigenvalue eq. (53) can involve up to
/// O(13): all closed-form eigenvalues with `|lambda| <= 13 |lambda_1|
/// (1 + resonance_tol)` (14 pairs, more than the 6 pairs of the default
/// count) are among the computed ones, to 1e-9. A chain of 3 masses on the
/// sparse path finds all 6 finite modes and reports a complete spectrum.
#[test]
fn sparse_path_covers_what_the_resonance_checks_need() {
    let (k, alpha, beta) = CHAIN_DEFAULTS;
    let scene = |n: usize, method: &str| {
        format!(
            "[model]\nplugin = \"oscillator-chain\"\n[model.params]\nn = {n}\n\
             [spectrum]\nmethod = \"{method}\"\n[ssm]\norder = 13\n\
             [outputs]\ncoordinates = [\"x1\"]\n"
        )
    };
    let job = ssm_tests::run_scene_text(&scene(500, "auto")).unwrap();
    let spectrum = job.spectrum.as_ref().expect("spectrum");
    assert_eq!(spectrum.method, Method::Sparse);
    let exact = chain_eigenvalues(500, k, alpha, beta, 40);
    let radius = 13.0 * exact[0].norm() * 1.02;
    let needed: Vec<&C64> = exact.iter().filter(|l| l.norm() <= radius).collect();
    assert!(
        needed.len() >= 13,
        "{} pairs inside the radius",
        needed.len()
    );
    for l in needed {
        assert!(
            spectrum
                .eigenvalues
                .iter()
                .any(|c| (c - l).norm() <= 1e-9 * l.norm()),
            "{l} (|lambda| = {:.4e} <= {radius:.4e}) was not computed",
            l.norm()
        );
    }
    assert!(!spectrum.complete);
    let small = ssm_tests::run_scene_text(&scene(3, "sparse")).unwrap();
    let small = small.spectrum.as_ref().expect("spectrum");
    assert_eq!(small.eigenvalues.len(), 6);
    assert!(small.complete, "every finite mode was found");
}
