//! The modified Shaw-Pierre oscillator (plugin `shaw-pierre`) against the
//! closed forms of Szalai, Ehrhardt & Haller (2017), Sect. 9a: its spectrum
//! and its backbone curves at small amplitude.

use num_complex::Complex64 as C64;
use ssm_tests::{run_scene_text, spectrum_options, system};

/// Reference: Sect. 9a, `lambda_{1,2} = -c/2 +- i sqrt(k0 (1 - c^2/(4 k0)))`,
/// `lambda_{3,4} = -3c/2 +- i sqrt(3 k0 (1 - 3 c^2/(4 k0)))`, to 1e-12, at
/// the paper's values and at a heavier damping.
#[test]
fn spectrum_matches_the_closed_form() {
    for (c, k0) in [(0.003f64, 1.0f64), (0.2, 2.5)] {
        let sys = system("shaw-pierre", "", &format!("c = {c}\nk0 = {k0}"));
        let sp =
            ssm_core::spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &spectrum_options(None, 0))
                .unwrap();
        let upper = ssm_tests::upper_half(&sp.eigenvalues);
        let exact = [
            C64::new(-c / 2.0, (k0 * (1.0 - c * c / (4.0 * k0))).sqrt()),
            C64::new(
                -1.5 * c,
                (3.0 * k0 * (1.0 - 3.0 * c * c / (4.0 * k0))).sqrt(),
            ),
        ];
        assert_eq!(upper.len(), 2, "{:?}", sp.eigenvalues);
        for (l, e) in upper.iter().zip(exact) {
            assert!((l - e).norm() < 1e-12 * e.norm(), "{l} against {e}");
        }
    }
}

/// Reference: the backbone curves of Sect. 9a (O(3), from the supplement's
/// Theorem S2), `omega(rho_1) = (sqrt(4 k0 - c^2) + 3 kappa rho_1^2 /
/// sqrt(4 k0 - c^2)) / 2`, `omega(rho_2) = (sqrt(3 (4 k0 - 3 c^2)) + sqrt(3)
/// kappa rho_2^2 / sqrt(4 k0 - 3 c^2)) / 2`, with the amplitude of `x1`
/// `Amp = 2 rho`. They hold to O(rho^4), so at amplitudes up to 0.03 the
/// engine's frequency shift at O(3) and O(7) must match the closed-form
/// shift to 1e-3 of itself (the next term is relatively `O(kappa Amp^2)`,
/// below 5e-4 there).
#[test]
fn backbones_match_the_closed_form_at_small_amplitude() {
    let (c, k0, kappa) = (0.003f64, 1.0f64, 0.5f64);
    let closed = [
        (
            0.5 * (4.0 * k0 - c * c).sqrt(),
            3.0 * kappa / (8.0 * (4.0 * k0 - c * c).sqrt()),
        ),
        (
            0.5 * (3.0 * (4.0 * k0 - 3.0 * c * c)).sqrt(),
            3f64.sqrt() * kappa / (8.0 * (4.0 * k0 - 3.0 * c * c).sqrt()),
        ),
    ];
    for (pair, (w0, coefficient)) in [1usize, 2].into_iter().zip(closed) {
        let scene = format!(
            "[model]\nplugin = \"shaw-pierre\"\n[ssm]\nmaster_pairs = [{pair}]\norder = 7\n\
             [outputs]\ncoordinates = [\"x1\"]\n[outputs.backbone]\nrho_max = 0.05\npoints = 11\norders = [3, 7]\n"
        );
        let job = run_scene_text(&scene).expect("Shaw-Pierre scene");
        let csv = String::from_utf8(job.outputs.get("backbone.csv").unwrap().to_vec()).unwrap();
        let mut checked = 0;
        for row in csv.lines().skip(1) {
            let v: Vec<f64> = row.split(',').map(|x| x.parse().unwrap()).collect();
            let (omega, amp) = (v[2], v[3]);
            if amp == 0.0 {
                // backbone.csv prints 11 significant digits
                assert!(
                    (omega - w0).abs() < 1e-10 * w0,
                    "pair {pair}: {omega} against {w0}"
                );
                continue;
            }
            if amp > 0.03 {
                continue;
            }
            let shift = coefficient * amp * amp;
            assert!(
                ((omega - w0) - shift).abs() < 1e-3 * shift,
                "pair {pair}, order {}, amplitude {amp}: shift {} against {shift}",
                v[0],
                omega - w0
            );
            checked += 1;
        }
        assert!(checked >= 8, "pair {pair}: {checked} rows checked");
    }
}
