//! Regression corpus of issue 38, section 3: every size a scene or a
//! reducer's parameters derive (explicit orders, the harmonic table of the
//! multi-pair forced response, the NAR regression, lists of outputs) is
//! costed before anything is allocated, against the memory the process may
//! really use (`ulimit -v`, cgroups), and refused as a typed error at the key
//! that drives it. The address-space cases run the engine binary in a child
//! under `ulimit -v`: without the gate they abort on an allocation (or run
//! for minutes, stopped by `timeout`), with it they exit with the scene error.
//! The `[pod]` study, the engine's `pod` reducer and `[simulate]` are costed
//! by the same gate before their runs start.

use std::path::{Path, PathBuf};
use std::process::Command;

use ssm_tests::{engine_binary, repo_root, run_scene_text, scene_error, tmp_dir};

/// Runs the engine on `scene` (written to a scratch file) under
/// `ulimit -v kib` with `env`, stopped after 120 s; returns its exit code
/// (None: killed by a signal) and stderr.
fn run_limited(name: &str, scene: &str, kib: u64, env: &[(&str, &str)]) -> (Option<i32>, String) {
    let dir = tmp_dir(name);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).expect("scene written");
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!(
            "ulimit -v {kib}; exec timeout 120 \"$0\" \"$1\" --out \"$2\""
        ))
        .arg(engine_binary())
        .arg(&path)
        .arg(dir.join("out"))
        .env("CI", "1");
    for (k, v) in env {
        cmd.env(k, v);
    }
    let o = cmd.output().expect("sh runs");
    let _ = std::fs::remove_dir_all(&dir);
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A zoo scene's text up to (not including) `cut`, with `from` replaced by `to`.
fn zoo_scene(name: &str, cut: Option<&str>, from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(repo_root().join("zoo").join(name)).expect("zoo scene");
    let text = cut.map_or(text.as_str(), |c| {
        &text[..text.find(c).expect("cut marker")]
    });
    assert!(text.contains(from), "{from} in {name}");
    text.replacen(from, to, 1)
}

fn assert_refused(code: Option<i32>, err: &str, line: usize, key: &str, also: &str) {
    assert_eq!(
        code,
        Some(1),
        "a typed refusal, not an abort or a timeout: {err}"
    );
    assert!(
        err.contains(&format!("scene.toml:{line}: `{key}`")) && err.contains(also),
        "{err}"
    );
}

/// `[ssm] order = 400` on the 6-state spatial oscillator: the series product
/// table alone is `8 C(404, 4)` bytes = 8.7 GB (the number of split pairs of
/// all multi-indices in 2 variables up to order 400), more than a 4 GB
/// address space holds; it ran 50 s and aborted.
#[test]
fn an_explicit_order_beyond_the_address_space_is_refused() {
    let scene = zoo_scene(
        "spatial_oscillator_cubic.toml",
        Some("# Full-system validation"),
        "order = 13",
        "order = 400",
    );
    let (code, err) = run_limited("order400", &scene, 4_000_000, &[]);
    assert_refused(
        code,
        &err,
        17,
        "ssm.order",
        "address-space limit (ulimit -v)",
    );
}

/// The chain of Fig. 13 scaled to 41,000 pendulums (409,995 states) with
/// `order = 13000000000000` (a fuzz case): the order cannot fit even the
/// smallest model of one master pair (2 states: 8e25 multi-indices), so it
/// is refused before the model is built, where it had the chain assembled
/// and its spectrum computed (12.7 s on the CI machine) before the same
/// refusal. The message names the lower bound it used (the zoo scene itself,
/// at order 13, runs in `scenes`).
#[test]
fn an_order_that_fits_no_model_is_refused_before_the_model_is_built() {
    let scene = zoo_scene(
        "pendulum_chain_fig13.toml",
        None,
        "order = 13",
        "order = 13000000000000",
    )
    .replacen("n = 41", "n = 41000", 1);
    let (line, message) = scene_error(&scene);
    assert_eq!(line, 21, "{message}");
    assert!(
        message.starts_with("ssm.order: ")
            && message.contains("even of the smallest model (2 states)"),
        "{message}"
    );
}

/// Three master pairs with `n_alpha = n_theta = 40`: `40^2 40^3` = 1.0e8
/// points of 160 bytes, 16.4 GB, accepted against `MemAvailable` and
/// aborted under an 8 GB address-space limit.
#[test]
fn the_invariance_error_is_refused_under_an_address_space_limit() {
    let scene = "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"none\"\n\
        [ssm]\nmaster_pairs = [1, 2, 3]\norder = 3\n[outputs]\ncoordinates = [\"x1\"]\n\
        [outputs.invariance_error]\nradii = [0.1]\norders = [3]\nn_alpha = 40\nn_theta = 40\n";
    let (code, err) = run_limited("invariance40", scene, 8_000_000, &[]);
    assert_refused(
        code,
        &err,
        14,
        "outputs.invariance_error.n_theta",
        "address-space limit (ulimit -v)",
    );
}

/// The pendulum slider's two pairs at resonance ratios `[1, 1e9]`: the
/// harmonic table has `2 * 7 * 1e9 + 1` slots sampled at 64 phases, 14 TB of
/// complex numbers (it aborted allocating 160 GB in 0.1 s).
#[test]
fn resonance_ratios_are_costed_with_the_harmonic_table() {
    let scene = "[model]\nplugin = \"pendulum\"\nname = \"slider\"\n[ssm]\nmaster_pairs = [1, 2]\norder = 7\n\
        [outputs]\ncoordinates = [\"x1\"]\n[forcing]\nepsilon = [0.08]\nomega_range = [1.8, 1.9]\n\
        resonance = [1.0, 1e9]\n";
    let (line, msg) = scene_error(scene);
    assert_eq!(line, 12, "{msg}");
    assert!(
        msg.starts_with("forcing.resonance: forced response curves at resonance ratios [1, 1000000000] (14000000001 harmonics"),
        "{msg}"
    );
    assert!(msg.contains("needs about"), "{msg}");
}

/// A decaying signal of `x1_dot` with `samples` samples, written to `dir`.
fn decaying_signal(dir: &Path, samples: usize) -> PathBuf {
    std::fs::create_dir_all(dir).expect("scratch dir");
    let mut text = String::from("t,x1_dot\n");
    for k in 0..samples {
        let t = 0.05 * k as f64;
        text.push_str(&format!("{t},{}\n", (-0.01 * t).exp() * (1.3 * t).sin()));
    }
    let path = dir.join("signal.csv");
    std::fs::write(&path, text).expect("signal written");
    path
}

fn nar_scene(params: &str, file: &Path) -> String {
    format!(
        "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n[reduce.params]\n{params}\n\
         [data]\nfiles = [{file:?}]\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x1_dot\"]\n"
    )
}

/// The NAR identifier at `nu = 16, order = 25` (each accepted on its own):
/// the unknowns are counted as `C(57, 25) - 1` before the monomial basis is
/// built (it filled 8 GB in 10 s building 9.9e15 monomials).
#[test]
fn the_nar_unknowns_are_counted_before_the_basis_is_built() {
    let dir = tmp_dir("nar-huge");
    let file = decaying_signal(&dir, 400);
    let err = match run_scene_text(&nar_scene("nu = 16\norder = 25", &file)) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("nu = 16, order = 25 ran"),
    };
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        err.contains("nu = 16, order = 25") && err.contains("9.929e15 unknowns (at most 5000)"),
        "{err}"
    );
}

/// `nu = 2, order = 12` on 60 000 samples: a regression of 60 000 rows by
/// `C(16, 12) - 1 = 1819` unknowns, 0.98 GB with its factors, below the
/// identifier's 2 GB cap but beyond a 1 GB address space: refused by the
/// plugin with the limit it read, not aborted.
#[test]
fn the_nar_regression_is_refused_under_an_address_space_limit() {
    let dir = tmp_dir("nar-ulimit");
    let file = decaying_signal(&dir, 60_000);
    let (code, err) = run_limited(
        "nar-ulimit-run",
        &nar_scene("nu = 2\norder = 12", &file),
        1_000_000,
        &[],
    );
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(code, Some(1), "a typed refusal, not an abort: {err}");
    assert!(
        err.contains("nu = 2, order = 12: the regression would have 59996 rows by 1819 unknowns")
            && err.contains("address-space limit (ulimit -v)"),
        "{err}"
    );
}

/// An output named twice is a scene error at its list (100 000 times it ran
/// past a minute on the 2-state Duffing).
#[test]
fn a_repeated_output_name_is_refused_at_its_list() {
    let names = vec!["\"x\""; 100_000].join(", ");
    let scene = format!(
        "[model]\nplugin = \"duffing\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x\"]\n\
         [forcing]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\n[reference]\nepsilon = 0.01\noutputs = [{names}]\n"
    );
    let (line, msg) = scene_error(&scene);
    assert_eq!(line, 12, "{msg}");
    assert!(
        msg.starts_with("reference.outputs: names 'x' more than once"),
        "{msg}"
    );
    let (line, msg) = scene_error(
        "[model]\nplugin = \"duffing\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x\", \"x\"]\n",
    );
    assert_eq!(
        (line, msg.starts_with("outputs.coordinates")),
        (6, true),
        "{msg}"
    );
}

/// A `[reference]` refused for its number of steps names the key that sets
/// it, at its line: `step` when a small step makes the branches long,
/// `max_steps` when that caps them (before, both named `reference.harmonics`
/// at line 1). A time limit of 0.06 s makes any reference too long.
#[test]
fn reference_refusals_name_the_key_that_drives_the_cost() {
    let base =
        "[model]\nplugin = \"duffing\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x\"]\n\
        [forcing]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\n[reference]\nepsilon = 0.01\n";
    let env = [("SSM_TIME_LIMIT_MINUTES", "0.001")];
    let cases = [
        ("step = 1e-3\nmax_steps = 100000\n", 12, "reference.step"),
        (
            "step = 1e-4\nmax_steps = 20000\n",
            13,
            "reference.max_steps",
        ),
        ("harmonics = 40\n", 12, "reference.harmonics"),
    ];
    for (rest, line, key) in cases {
        let (code, err) = run_limited("reference-key", &format!("{base}{rest}"), 8_000_000, &env);
        assert_refused(code, &err, line, key, "needs about");
    }
}

/// A huge number from the scene is echoed as `1e300`, not as its 301 digits
/// (`{}` of an f64 never uses an exponent).
#[test]
fn huge_numbers_are_echoed_in_exponent_form() {
    let base =
        "[model]\nplugin = \"duffing\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x\"]\n";
    let cases = [
        ("[ssm]\ntolerance = 1e300\n", "ssm.tolerance", "found 1e300"),
        (
            "[forcing]\nepsilon = 0.01\nomega_range = [0.9, 1.1]\n[reference]\nepsilon = 0.01\ntol = -1e300\n",
            "reference.tol",
            "found -1e300",
        ),
    ];
    for (rest, key, echo) in cases {
        let text = if rest.starts_with("[ssm]") {
            base.replace("[ssm]\n", rest)
        } else {
            format!("{base}{rest}")
        };
        let (_, msg) = scene_error(&text);
        assert!(msg.starts_with(key) && msg.ends_with(echo), "{msg}");
    }
}

/// The line of the first `needle` in `text` (1-based).
fn line_of(text: &str, needle: &str) -> usize {
    text[..text.find(needle).expect("needle in scene")]
        .lines()
        .count()
        + 1
}

/// `[pod] step = 1e-9` on the zoo's chain (405 states, three runs of 30):
/// 3e10 HHT steps a run, days of work and terabytes of stored states,
/// refused at `pod.step` before the training run starts (it ran for hours
/// filling memory with snapshots).
#[test]
fn a_pod_step_of_days_is_refused_at_pod_step() {
    let scene = zoo_scene(
        "pendulum_chain_pod.toml",
        None,
        "step = 0.01",
        "step = 1e-9",
    );
    let (line, msg) = scene_error(&scene);
    assert_eq!(line, line_of(&scene, "step = 1e-9"), "{msg}");
    assert!(
        msg.starts_with("pod.step: the [pod] study (3 full-model HHT run(s)")
            && msg.contains("days")
            && msg.contains("lengthen the step"),
        "{msg}"
    );
}

/// 10 000 Jacobian samples of the 5-pendulum chain over 101 snapshots: the
/// stacked projected constraint Jacobian has up to `101 x 10^4` columns
/// (the reduced coordinates bounded by the snapshots), minutes of SVD,
/// refused under a one-minute limit at `pod.jacobian_samples`, not at the
/// step that the full runs (101 steps) do not need changed.
#[test]
fn pod_jacobian_samples_that_drive_the_cost_are_named() {
    let scene = "[model]\nplugin = \"pendulum\"\nname = \"chain\"\n[outputs]\ncoordinates = [\"x1\"]\n\
        [pod]\nstep = 0.01\nrank_tol = 1e-2\njacobian_samples = 10000\n[pod.train]\nepsilon = 0.6\nomega = 2.0\nt_end = 1.0\n";
    let env = [("SSM_TIME_LIMIT_MINUTES", "1")];
    let (code, err) = run_limited("pod-samples", scene, 8_000_000, &env);
    assert_refused(
        code,
        &err,
        9,
        "pod.jacobian_samples",
        "lower jacobian_samples",
    );
}

/// The engine's `pod` reducer with `step = 1e-9` over `t_end = 30`: its
/// training run is refused at the step's own line inside `[reduce.params]`.
#[test]
fn the_pod_reducer_training_run_is_costed() {
    let scene = "[model]\nplugin = \"pendulum\"\nname = \"chain\"\n[reduce]\nreducer = \"pod\"\n\
        [reduce.params]\nt_end = 30.0\nstep = 1e-9\nrank_tol = 1e-2\n[ssm]\norder = 3\n\
        [outputs]\ncoordinates = [\"x1\"]\n";
    let (line, msg) = scene_error(scene);
    assert_eq!(line, 8, "{msg}");
    assert!(
        msg.starts_with("reduce.params.step: the pod reducer's training run")
            && msg.contains("days"),
        "{msg}"
    );
}

/// `[simulate]` is costed from the master mode's frequency: runs of
/// `1999 x 1e6` time units are some 3e8 periods of the oscillator, refused
/// at `simulate.period` (in a child under `timeout`: without the gate it
/// integrates for days); `1e12` samples at `simulate.samples`.
#[test]
fn simulate_runs_are_costed_at_their_keys() {
    let scene = zoo_scene(
        "spatial_oscillator_data.toml",
        None,
        "period = 0.2",
        "period = 1e6",
    );
    let (code, err) = run_limited("simulate-period", &scene, 8_000_000, &[]);
    let line = line_of(&scene, "period = 1e6");
    assert_refused(code, &err, line, "simulate.period", "2000 samples over");
    let scene = zoo_scene(
        "spatial_oscillator_data.toml",
        None,
        "samples = 2000",
        "samples = 1000000000000",
    );
    let (line, msg) = scene_error(&scene);
    assert_eq!(line, line_of(&scene, "samples = 1000000000000"), "{msg}");
    assert!(msg.starts_with("simulate.samples"), "{msg}");
}

/// Two million samples a run, each at least a step of the full model: the
/// samples drive the cost and are named under a 0.6 s limit.
#[test]
fn simulate_samples_that_drive_the_cost_are_named() {
    let scene = zoo_scene(
        "spatial_oscillator_data.toml",
        None,
        "period = 0.2\nsamples = 2000",
        "period = 1e-3\nsamples = 2000000",
    );
    let env = [("SSM_TIME_LIMIT_MINUTES", "0.01")];
    let (code, err) = run_limited("simulate-samples", &scene, 8_000_000, &env);
    let line = line_of(&scene, "samples = 2000000");
    assert_refused(code, &err, line, "simulate.samples", "take fewer samples");
}

/// Times and frequencies from the scene in integration errors print in
/// exponent form (`{}` wrote `t_end = 1e300` as 301 digits).
#[test]
fn integration_errors_echo_huge_times_in_exponent_form() {
    use ssm_core::fom::SimError;
    let e = SimError::TooManySteps {
        t: 2.5,
        steps: 10,
        t_end: 1e300,
    };
    assert!(
        e.to_string().contains("t = 2.5 before t_end = 1e300:"),
        "{e}"
    );
    let e = SimError::Inconsistent {
        t: -1e300,
        detail: "x".into(),
    };
    assert!(e.to_string().contains("at t = -1e300: x"), "{e}");
}

/// faer's x86 matrix kernels give every thread that runs a large product a
/// buffer of twice the L3 cache (960 MiB of address space where the CPU
/// reports 480 MiB). Under an address-space limit that cannot hold one per
/// thread, the 24-state pendulum chain of Fig. 13 aborted on its first
/// large product ("memory allocation of 1006632960 bytes failed", exit by
/// signal 6, at 700 MB). The engine now reserves the buffers before its
/// memory gate reads the room (`ssm_kernel::workspace`): where they do not
/// fit, the run is refused with the reason and what to change; with one
/// pool thread and room for its two buffers, it runs. Where the buffers are
/// small (an L3 below 256 MiB), the run must simply complete under the same
/// limit.
#[test]
fn an_address_space_limit_below_the_kernels_buffers_is_refused_not_aborted() {
    let per_thread = ssm_kernel::workspace::reserve().per_thread;
    let scene = std::fs::read_to_string(repo_root().join("zoo").join("pendulum_chain_fig13.toml"))
        .expect("zoo scene");
    // room for two buffers and the run, not for three
    let kib = (700e6 + 2.2 * per_thread) as u64 / 1024;
    let (code, err) = run_limited("kernel-buffers", &scene, kib, &[("RAYON_NUM_THREADS", "2")]);
    if per_thread >= 256.0 * 1024.0 * 1024.0 {
        assert_eq!(code, Some(1), "a typed refusal, not an abort: {err}");
        assert!(
            err.contains("scene.toml:")
                && err.contains("cannot hold the")
                && err.contains("for 3 thread(s)")
                && err.contains("raise ulimit -v by at least")
                && err.contains("RAYON_NUM_THREADS=1"),
            "{err}"
        );
    } else {
        assert_eq!(code, Some(0), "small buffers fit: {err}");
    }
    let (code, err) = run_limited(
        "kernel-buffers-1",
        &scene,
        kib,
        &[("RAYON_NUM_THREADS", "1")],
    );
    assert_eq!(code, Some(0), "two buffers fit: {err}");
}

/// The sparse spectrum is costed before it runs: on the ANCF cantilever of
/// 64 elements (514 states), 200 modes make an Arnoldi basis of 408
/// vectors whose orthogonalization alone is `6 N m^2` = 5e8 operations,
/// refused at `spectrum.modes` under a 0.6 s limit, while 6 modes (a basis
/// of 20) pass that gate.
#[test]
fn the_sparse_spectrum_is_costed_at_its_modes() {
    let scene = |modes: usize| {
        format!(
            "[model]\nplugin = \"crank-drive\"\nname = \"ancf-beam\"\n[model.params]\nelements = 64\n\
             [spectrum]\nmethod = \"sparse\"\nmodes = {modes}\n[ssm]\norder = 3\n\
             [outputs]\ncoordinates = [\"w_tip\"]\n"
        )
    };
    let env = [("SSM_TIME_LIMIT_MINUTES", "0.01")];
    let (code, err) = run_limited("sparse-modes", &scene(200), 8_000_000, &env);
    assert_refused(
        code,
        &err,
        8,
        "spectrum.modes",
        "the sparse spectrum of 514 states",
    );
    let (_, err) = run_limited("sparse-modes-few", &scene(6), 8_000_000, &env);
    assert!(!err.contains("`spectrum.modes`"), "{err}");
}
