//! Regression corpus of issue "Trustworthy under any input", second part:
//! requests whose work or memory cannot finish are refused up front with the
//! key, the estimate and the limit; plugin polynomials with impossible
//! exponents are typed model errors; lax tolerances and repeated master
//! eigenvalues are refused or warned about; forced response curves carry an
//! error estimate checked against the accuracy target.

use ssm_api::VarPower;
use ssm_core::model::system::{ModelError, System, MAX_DEGREE};
use ssm_core::rom::forced_response::CurveDetails;
use ssm_tests::{cubic_map_model, repo_root, run_scene_text, scene_error};

const OSCILLATOR: &str =
    "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"none\"\n";

fn oscillator(rest: &str) -> String {
    format!("{OSCILLATOR}{rest}")
}

/// Each request is refused at its key and line, with an estimate beyond the
/// limit, before any of the work starts (the whole test takes milliseconds
/// where the requests would take days or terabytes).
#[test]
fn unbounded_requests_are_refused_at_their_key_with_the_estimate() {
    let cases = [
        (
            "[ssm]\nmaster_pairs = [1, 2, 3]\norder = 300\n[outputs]\ncoordinates = [\"x1\"]\n",
            "ssm.order",
            7,
        ),
        // one pair: refused before the eq. (53) resonance check, which
        // enumerates the multi-indices up to the order (found by the scene
        // fuzzer in tests/fuzz.rs: it ran for hours)
        (
            "[ssm]\norder = 1000000\n[outputs]\ncoordinates = [\"x1\"]\n",
            "ssm.order",
            6,
        ),
        // the estimate itself must not loop over the order (fuzzer again)
        (
            "[ssm]\nmaster_pairs = [1, 2]\norder = 9223372036854775807\n[outputs]\ncoordinates = [\"x1\"]\n",
            "ssm.order",
            7,
        ),
        (
            "[ssm]\norder = 5\n[outputs]\ncoordinates = [\"x1\"]\n[forcing]\nepsilon = 0.01\nomega_range = [1.8, 2.2]\npoints = 1000000000\n",
            "forcing.points",
            12,
        ),
        (
            "[ssm]\norder = 5\n[outputs]\ncoordinates = [\"x1\"]\n[outputs.transient]\nrho0 = [0.1]\nt_end = 100\nsamples = 10000000000\n",
            "outputs.transient.samples",
            12,
        ),
        (
            "[ssm]\norder = 5\n[outputs]\ncoordinates = [\"x1\"]\n[outputs.transient]\nrho0 = [0.1]\nt_end = 1e9\n",
            "outputs.transient.t_end",
            11,
        ),
        (
            "[ssm]\nmaster_pairs = [1, 2, 3]\norder = 5\n[outputs]\ncoordinates = [\"x1\"]\n[outputs.invariance_error]\nradii = [0.1]\norders = [5]\nn_alpha = 1000\nn_theta = 1000\n",
            "outputs.invariance_error.n_theta",
            14,
        ),
        (
            "[ssm]\norder = 5\n[outputs]\ncoordinates = [\"x1\"]\n[forcing]\nepsilon = 0.01\nomega_range = [1.8, 2.2]\n[validate.steady_state]\nepsilon = 0.01\nomega = [2.0]\nmax_periods = 1000000000000\n",
            "validate.steady_state.max_periods",
            15,
        ),
    ];
    for (rest, key, line) in cases {
        let (at, msg) = scene_error(&oscillator(rest));
        assert!(msg.starts_with(key), "expected {key}: {msg}");
        assert!(
            msg.contains("needs about") && msg.contains("this run allows"),
            "{msg}"
        );
        assert_eq!(at, line, "{msg}");
    }
}

#[test]
fn a_transient_tolerance_of_10_is_refused() {
    let (line, msg) = scene_error(&oscillator(
        "[ssm]\norder = 5\n[outputs]\ncoordinates = [\"x1\"]\n[outputs.transient]\nrho0 = [0.1]\nt_end = 10\nrtol = 10\n",
    ));
    assert_eq!(line, 12, "{msg}");
    assert!(
        msg.starts_with("outputs.transient.rtol: must be below 1e-2"),
        "{msg}"
    );
}

#[test]
fn an_accuracy_target_outside_0_1_is_refused() {
    let (line, msg) = scene_error(&oscillator(
        "[ssm]\ntolerance = 5\n[outputs]\ncoordinates = [\"x1\"]\n",
    ));
    assert_eq!(line, 6, "{msg}");
    assert!(msg.starts_with("ssm.tolerance"), "{msg}");
}

/// Power 0, a power of u32::MAX and two powers whose u32 sum wraps around to
/// a small degree are refused before any storage is sized from them.
#[test]
fn impossible_exponents_in_plugin_polynomials_are_typed_errors() {
    let with_factors = |factors: Vec<VarPower>| {
        let mut m = cubic_map_model();
        m.nonlinearity.terms[0].factors = factors.into_iter().collect();
        System::from_model("test", m)
    };
    match with_factors(vec![
        VarPower { var: 0, power: 0 },
        VarPower { var: 1, power: 2 },
    ]) {
        Err(ModelError::ZeroPower { eq: 0, var: 0, .. }) => {}
        other => panic!("power 0: {other:?}"),
    }
    match with_factors(vec![VarPower {
        var: 0,
        power: u32::MAX,
    }]) {
        Err(ModelError::HighDegree { degree, .. }) => assert_eq!(degree, u64::from(u32::MAX)),
        other => panic!("power u32::MAX: {other:?}"),
    }
    // 2^31 + 2^31 + 2 wraps to 2 in u32 arithmetic
    let wrap = vec![
        VarPower {
            var: 0,
            power: 1 << 31,
        },
        VarPower {
            var: 1,
            power: 1 << 31,
        },
        VarPower { var: 2, power: 2 },
    ];
    match with_factors(wrap) {
        Err(ModelError::HighDegree { degree, .. }) => assert_eq!(degree, (1u64 << 32) + 2),
        other => panic!("wrapping powers: {other:?}"),
    }
    let limit = u32::try_from(MAX_DEGREE).expect("small");
    assert!(with_factors(vec![VarPower {
        var: 0,
        power: limit
    }])
    .is_ok());
    // an equation index out of range is refused before the layout permutes it
    let mut m = cubic_map_model();
    m.nonlinearity.terms[0].eq = 99;
    assert!(matches!(
        System::from_model("test", m),
        Err(ModelError::Index { index: 99, .. })
    ));
}

/// `omega2 = omega1` makes the master eigenvalue repeat outside the master
/// subspace (a 1:1 resonance at order 1 that the checks of eq. 57 skip).
#[test]
fn a_repeated_master_eigenvalue_is_warned_about() {
    let text = "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"none\"\nomega2 = 2.0\nzeta2 = 0.01\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x1\"]\n";
    let warnings = match run_scene_text(text) {
        Ok(r) => r.warnings,
        // the SSM itself may then fail on the resonance; the warning is what
        // tells the user why, so it must be in the spectral stage's output
        Err(e) => panic!("{e}"),
    };
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("is repeated by eigenvalue") && w.contains("add that mode's pair")),
        "{warnings:?}"
    );
}

/// The Fig. 5 scene of the unconstrained oscillator, with the non-autonomous
/// order left to the engine: at O(11) every curve meets the 1 % target
/// (reference: the independent harmonic-balance run of the issue found the
/// leading-order peak 3 / 8 / 14 % high and 0.02-0.18 % off with the
/// O(eps |p|^6) terms), and the leading-order-only O(3) curves are flagged.
#[test]
fn fig5_curves_carry_error_estimates_against_the_accuracy_target() {
    let text = std::fs::read_to_string(repo_root().join("zoo/spatial_oscillator_none_fig5.toml"))
        .expect("zoo scene");
    let auto = text.replace("nonautonomous_order = 0\n", "");
    assert_ne!(auto, text, "the zoo scene fixes the leading order");
    let r = run_scene_text(&auto).expect("runs");
    let frc = r.frc.expect("FRC");
    for c in &frc.curves {
        let CurveDetails::OnePair {
            error_estimate,
            nonautonomous_order,
            ..
        } = c.details
        else {
            panic!("one pair")
        };
        if c.order == 11 {
            assert!(
                error_estimate <= 0.01 && !c.untrusted,
                "O(11), eps = {}: estimate {error_estimate} (k = {nonautonomous_order})",
                c.epsilon
            );
            assert!(
                nonautonomous_order > 0,
                "the leading order alone is 3-14 % off"
            );
        }
        if c.order == 3 {
            assert!(c.untrusted, "O(3), eps = {}: {error_estimate}", c.epsilon);
        }
    }
    assert!(
        r.warnings
            .iter()
            .any(|w| w.starts_with("O(3), eps = 0.03: the estimated error")),
        "{:?}",
        r.warnings
    );
    // the leading-order curve alone, as the scene once ran: its estimate must
    // see the 14 % error at eps = 0.03 (at least 5 %)
    let fixed = text.replace("orders = [3, 5, 7, 9, 11]", "orders = [11]");
    let r0 = run_scene_text(&fixed).expect("runs");
    let c = r0
        .frc
        .expect("FRC")
        .curves
        .into_iter()
        .find(|c| c.epsilon == 0.03)
        .expect("curve");
    let CurveDetails::OnePair { error_estimate, .. } = c.details else {
        panic!("one pair")
    };
    assert!(error_estimate > 0.05 && c.untrusted, "{error_estimate}");
}

/// The error estimate against an independent reference: the first-order
/// harmonic balance of `x'' + 2 zeta x' + x + x^3 = eps cos(Omega t)`, whose
/// peak is `Omega^2 = 1 + 3/4 A^2`, `2 zeta Omega A = eps`. With zeta = 0.002
/// and eps = 1.24e-3 the peak amplitude is A = 0.3; the balance neglects terms
/// of relative size about `(3/4 A^2)^2 / 32 = 1.4e-4` plus the third harmonic
/// (absent from the first-harmonic amplitude compared here), so `HB_ERROR =
/// 1e-3` bounds the reference's own error. At every order the estimate must
/// not be optimistic (true error <= estimate + HB_ERROR) nor vacuous (at most
/// twice the true error, or 2 HB_ERROR when that is larger; measured 1.1-1.5).
#[test]
fn the_error_estimate_brackets_the_error_against_harmonic_balance() {
    const HB_ERROR: f64 = 1e-3;
    let (zeta, eps) = (0.002f64, 1.24e-3f64);
    let mut a = eps / (2.0 * zeta);
    for _ in 0..200 {
        a = eps / (2.0 * zeta * (1.0 + 0.75 * a * a).sqrt());
    }
    for order in [3, 5, 7] {
        let text = format!(
            "[model]\nplugin = \"duffing\"\n[model.params]\nzeta = {zeta}\n[ssm]\norder = {order}\n[outputs]\ncoordinates = [\"x\"]\n[forcing]\nepsilon = {eps}\nomega_range = [0.95, 1.1]\npoints = 400\nrho_max = 1.0\nnonautonomous_order = 0\n"
        );
        let frc = run_scene_text(&text).expect("runs").frc.expect("FRC");
        let peak = frc.rows.iter().map(|r| r.h1[0]).fold(0.0, f64::max);
        let error = (peak - a).abs() / a;
        let CurveDetails::OnePair { error_estimate, .. } = frc.curves[0].details else {
            panic!("one pair")
        };
        eprintln!("O({order}): peak {peak:.6} against {a:.6}: error {error:.2e}, estimate {error_estimate:.2e}");
        assert!(error <= error_estimate + HB_ERROR, "O({order}): optimistic");
        assert!(
            error_estimate <= 2.0 * error.max(HB_ERROR),
            "O({order}): vacuous"
        );
    }
}
