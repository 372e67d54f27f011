//! Regression corpus of hostile inputs (issue "Trustworthy under any input"):
//! each case ends in its typed error or a correct answer, never a panic, a
//! hang or a silently empty result.

use std::process::{Command, Stdio};

use ssm_engine::pipeline::JobError;
use ssm_engine::rom::forced_response::FrcError;
use ssm_tests::{engine_binary, run_scene_text, scene_error};

fn duffing_frc(zeta: &str, epsilon: &str) -> String {
    format!(
        r#"[model]
plugin = "duffing"
[model.params]
zeta = {zeta}
[ssm]
master_pairs = [1]
order = 5
[outputs]
coordinates = ["x"]
[forcing]
epsilon = {epsilon}
omega_range = [0.9, 1.1]
"#
    )
}

#[test]
fn forcing_epsilon_may_be_a_number_or_a_list() {
    let one = run_scene_text(&duffing_frc("0.01", "0.01")).expect("a number");
    let list = run_scene_text(&duffing_frc("0.01", "[0.01]")).expect("a list");
    let (a, b) = (one.frc.expect("FRC"), list.frc.expect("FRC"));
    assert_eq!(a.rows, b.rows, "epsilon = 0.01 and [0.01] differ");
    assert!(!a.rows.is_empty());
}

#[test]
fn steady_state_epsilon_may_be_a_list_of_one_but_not_of_two() {
    let base = |eps: &str| {
        format!(
            "{}[validate.steady_state]\nepsilon = {eps}\nomega = [1.0]\nmax_periods = 3\n",
            duffing_frc("0.01", "0.01")
        )
    };
    let ok = ssm_engine::scene::SceneFile::parse(std::path::Path::new("test.toml"), base("[0.01]"))
        .expect("a list of one is accepted");
    assert_eq!(
        *ok.scene
            .validate
            .as_ref()
            .and_then(|v| v.steady_state.as_ref())
            .expect("steady state")
            .epsilon
            .get_ref(),
        0.01
    );
    let (line, msg) = scene_error(&base("[0.01, 0.02]"));
    assert_eq!(line, 14, "{msg}");
    assert!(msg.contains("one steady-state epsilon"), "{msg}");
}

/// Very light damping puts the default amplitude bound far above the peak;
/// the amplitude grid then misses every fixed point. That must not be an empty
/// FRC written with exit 0.
#[test]
fn an_frc_without_points_is_an_error_that_names_rho_max() {
    match run_scene_text(&duffing_frc("1e-7", "0.01")) {
        Err(JobError::Frc(FrcError::Empty { order, rho_max, .. })) => {
            assert_eq!(order, 5);
            assert!(rho_max > 1e4, "{rho_max}");
        }
        Err(e) => panic!("expected FrcError::Empty, got {e}"),
        Ok(r) => panic!(
            "expected an error, got {} FRC points",
            r.frc.map_or(0, |f| f.rows.len())
        ),
    }
    // with rho_max above the response in range the same scene answers, and
    // its peak (at Omega = 1.1, on the resonant branch of the hardening
    // oscillator) is the one-harmonic balance of x'' + x + x^3 = eps cos(Omega t),
    // zeta -> 0: 3/4 a^3 + (1 - Omega^2) a = eps. Tolerance 1 %: the balance
    // neglects the third harmonic, of relative size about a^2/32 = 1 % here;
    // the SSM is taken at O(13), where O(9) to O(13) changes the peak by 0.3 %.
    let text = duffing_frc("1e-7", "0.01").replace("order = 5", "order = 13") + "rho_max = 0.5\n";
    let frc = run_scene_text(&text)
        .expect("rho_max given")
        .frc
        .expect("FRC");
    let peak = frc
        .rows
        .iter()
        .max_by(|a, b| a.h1[0].total_cmp(&b.h1[0]))
        .expect("points");
    assert!((peak.omega - 1.1).abs() < 1e-9, "peak at {}", peak.omega);
    let hb = |a: f64| 0.75 * a.powi(3) + (1.0 - 1.21) * a - 0.01;
    let (mut lo, mut hi) = (0.3, 1.0);
    for _ in 0..100 {
        let m = 0.5 * (lo + hi);
        if hb(lo) * hb(m) <= 0.0 {
            hi = m;
        } else {
            lo = m;
        }
    }
    let rel = (peak.h1[0] - lo).abs() / lo;
    assert!(
        rel < 0.01,
        "peak {} against harmonic balance {lo}: {rel:.2e}",
        peak.h1[0]
    );
}

/// `ssm-engine plugins | head -1`: the reader goes away; the listing ends
/// quietly instead of panicking on the broken pipe.
#[test]
fn plugin_listing_into_a_closed_pipe_does_not_panic() {
    let mut child = Command::new(engine_binary())
        .arg("plugins")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("engine starts");
    drop(child.stdout.take());
    let o = child.wait_with_output().expect("engine ends");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(o.status.success(), "exit {:?}: {err}", o.status);
}
