//! Shared catalogue of test problems with known answers, used by the
//! integration tests and the benchmarks, and helpers to find the built plugin
//! libraries and the `ssm-engine` binary.
//!
//! Plugins are `cdylib`s: build them first (`cargo build --release --workspace`);
//! the tests look for them next to the test executable's profile directory.

use std::path::{Path, PathBuf};

use num_complex::Complex64 as C64;
use ssm_core::model::plugin::Plugin;
use ssm_core::model::system::System;
use ssm_core::spectrum::Normalization;
use ssm_core::spectrum::{self, Method, Spectrum, SpectrumOptions};
use ssm_core::ssm::{self as ssm_mod, SsmExpansion, SsmOptions};

mod forced;
pub use forced::{
    duffing_fold, duffing_orbits, forced_duffing, linear_steady_state, parametric_pump,
    parametric_pump_reference,
};

/// `target/<profile>` of the running test or bench executable.
pub fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    let deps = exe.parent().expect("executable directory");
    if deps.file_name().is_some_and(|n| n == "deps") {
        deps.parent().expect("profile directory").to_owned()
    } else {
        deps.to_owned()
    }
}

/// Path of the built library of the plugin crate `crate_name` (dashes or underscores).
pub fn plugin_path(crate_name: &str) -> PathBuf {
    let file = format!("lib{}.so", crate_name.replace('-', "_"));
    let path = profile_dir().join(&file);
    assert!(
        path.exists(),
        "{} not found: build the plugins first with `cargo build --release --workspace`",
        path.display()
    );
    path
}

/// Path of the built `ssm-engine` binary.
pub fn engine_binary() -> PathBuf {
    let path = profile_dir().join("ssm-engine");
    assert!(
        path.exists(),
        "{} not found: build it first with `cargo build --release --workspace`",
        path.display()
    );
    path
}

/// The repository root.
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ is inside the repository")
        .to_owned()
}

/// Loads plugin `crate_name` through its real `.so` and builds `model` with
/// the TOML parameter text `params`.
pub fn system(crate_name: &str, model: &str, params: &str) -> System {
    let plugin = Plugin::load(&plugin_path(crate_name)).expect("plugin loads");
    let m = plugin.build_model(model, params).expect("model builds");
    System::from_model(plugin.name(), m).expect("model is valid")
}

/// Plugin `crate_name`'s `model` with parameters `params` as the plugin
/// gives it (expressions, equilibrium) and validated: reducers that
/// project the model itself need both.
pub fn model_and_system(crate_name: &str, model: &str, params: &str) -> (ssm_api::Model, System) {
    let plugin = Plugin::load(&plugin_path(crate_name)).expect("plugin loads");
    let m = plugin.build_model(model, params).expect("model builds");
    let sys = System::from_model(plugin.name(), m.clone()).expect("model is valid");
    (m, sys)
}

/// A registry with the repository's model plugins.
pub fn registry() -> ssm_core::model::plugin::Registry {
    ssm_core::model::plugin::Registry::discover(&[
        plugin_path("spatial-oscillator"),
        plugin_path("oscillator-chain"),
        plugin_path("duffing"),
        plugin_path("pendulum"),
        plugin_path("divider"),
        plugin_path("matrix-model"),
        plugin_path("shaw-pierre"),
        plugin_path("nar-identifier"),
        plugin_path("ssm-fixture-modal-truncation"),
        plugin_path("ssm-fixture-api-1-0"),
    ])
    .expect("plugins load")
}

/// Runs the scene text `text` (as `test.toml`) with [`registry`].
pub fn run_scene_text(
    text: &str,
) -> Result<ssm_engine::pipeline::JobResult, ssm_engine::pipeline::JobError> {
    let scene =
        ssm_engine::scene::SceneFile::parse(std::path::Path::new("test.toml"), text.to_owned())?;
    ssm_engine::job::run(&scene, &mut registry(), &ssm_engine::pipeline::Quiet)
}

/// The line and `key: message` of the scene error `text` must produce.
pub fn scene_error(text: &str) -> (usize, String) {
    use ssm_engine::pipeline::JobError;
    use ssm_engine::scene::SceneError;
    match run_scene_text(text) {
        Err(JobError::Scene(SceneError::Parse { line, message, .. })) => (line, message),
        Err(JobError::Scene(SceneError::Invalid {
            line, key, message, ..
        })) => (line, format!("{key}: {message}")),
        Err(e) => panic!("expected a scene error, got: {e}"),
        Ok(_) => panic!("expected a scene error, the scene ran"),
    }
}

/// A fresh scratch directory for test outputs.
pub fn tmp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ssm-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// The files beside the output directory `out` whose names start with
/// `<out name>.<kind>` (`reference-partial`: the reference's journals,
/// `reference-checkpoint`: its checkpoints), sorted.
pub fn files_beside(out: &Path, kind: &str) -> Vec<PathBuf> {
    let name = out
        .file_name()
        .expect("name")
        .to_string_lossy()
        .into_owned();
    let mut found: Vec<_> = std::fs::read_dir(out.parent().expect("parent"))
        .expect("parent")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .is_some_and(|f| f.to_string_lossy().starts_with(&format!("{name}.{kind}")))
        })
        .collect();
    found.sort();
    found
}

/// Checks `summary` (a `summary.json` file) against the engine's JSON
/// Schema, `docs/summary.schema.json`, with the Python package `jsonschema`
/// (`tests/scripts/validate_summary.py`); panics with every violation.
pub fn assert_summary_valid(summary: &Path) {
    let root = repo_root();
    let o = std::process::Command::new("python3")
        .arg(root.join("tests/scripts/validate_summary.py"))
        .arg(root.join("docs/summary.schema.json"))
        .arg(summary)
        .output()
        .expect(
            "python3 runs the schema check: install python3 and the packages of \
             tests/requirements.txt (`python3 -m pip install -r tests/requirements.txt`)",
        );
    assert!(
        o.status.success(),
        "{} does not follow docs/summary.schema.json:\n{}{}",
        summary.display(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// [`assert_summary_valid`] for the `summary.json` of an in-process run
/// (`name` names its scratch file).
pub fn assert_job_summary_valid(job: &ssm_engine::pipeline::JobResult, name: &str) {
    let dir = tmp_dir(&format!("summary-{name}"));
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let file = dir.join("summary.json");
    std::fs::write(
        &file,
        job.outputs.get("summary.json").expect("summary.json"),
    )
    .expect("written");
    assert_summary_valid(&file);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs the zoo scene `scene` through the binary (with `args` before it, e.g.
/// `["report"]`); returns its summary (checked against the schema) and
/// output directory.
pub fn run_zoo_with(args: &[&str], scene: &str) -> (serde_json::Value, PathBuf) {
    let out = tmp_dir(scene);
    let args: Vec<&std::ffi::OsStr> = args.iter().map(std::ffi::OsStr::new).collect();
    let s = run_binary(&args, &repo_root().join("zoo").join(scene), &out);
    (s, out)
}

/// Runs the binary on the scene file `scene` into `out` (with `args` before
/// it, e.g. `--plugin` and a library); returns its summary, checked against
/// the schema.
pub fn run_binary(args: &[&std::ffi::OsStr], scene: &Path, out: &Path) -> serde_json::Value {
    let o = std::process::Command::new(engine_binary())
        .args(args)
        .arg(scene)
        .arg("--out")
        .arg(out)
        .env("CI", "1")
        .output()
        .expect("ssm-engine runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_summary_valid(&out.join("summary.json"));
    serde_json::from_slice(&std::fs::read(out.join("summary.json")).expect("summary"))
        .expect("summary is JSON")
}

/// Runs a zoo scene through the binary; returns its summary and output directory.
pub fn run_zoo_in(scene: &str) -> (serde_json::Value, PathBuf) {
    run_zoo_with(&[], scene)
}

/// Runs a zoo scene through the binary and returns its summary.
pub fn run_zoo(scene: &str) -> serde_json::Value {
    let (s, out) = run_zoo_in(scene);
    let _ = std::fs::remove_dir_all(&out);
    s
}

/// Published eigenvalues of the spatial oscillator, Li, Jain & Haller (2023):
/// eq. (26) (unconstrained, three pairs) and eq. (27) (cubic or spherical
/// constraint, two finite pairs). Printed to 4-5 significant digits; only the
/// positive-imaginary member of each pair is listed.
pub fn oscillator_published_eigenvalues(constraint: &str) -> Vec<C64> {
    let mut ev = vec![C64::new(-0.02, 1.9999), C64::new(-0.15, 2.9962)];
    if constraint == "none" {
        ev.push(C64::new(-0.25, 4.9937));
    }
    ev
}

/// Closed-form spectrum of the `oscillator-chain` plugin (fixed-fixed chain of
/// `n` unit masses, springs `k`, Rayleigh damping `C = alpha M + beta K`):
/// `omega_j = 2 sqrt(k) sin(j pi / (2 (n + 1)))`, `2 zeta_j omega_j = alpha + beta omega_j^2`,
/// `lambda_j = -zeta_j omega_j + i omega_j sqrt(1 - zeta_j^2)` (positive-imaginary members, slowest first).
pub fn chain_eigenvalues(n: usize, k: f64, alpha: f64, beta: f64, count: usize) -> Vec<C64> {
    (1..=count)
        .map(|j| {
            let w =
                2.0 * k.sqrt() * (j as f64 * std::f64::consts::PI / (2.0 * (n as f64 + 1.0))).sin();
            let zeta = (alpha + beta * w * w) / (2.0 * w);
            C64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt())
        })
        .collect()
}

/// The `oscillator-chain` plugin with `n` masses (other parameters default)
/// and its `modes` finite eigenvalues nearest 0 from the sparse path.
pub fn chain_with_sparse_spectrum(n: usize, modes: usize) -> (System, Spectrum) {
    let sys = system("oscillator-chain", "chain", &format!("n = {n}"));
    let sp = spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &spectrum_options(Some(Method::Sparse), modes),
    )
    .expect("chain spectrum");
    (sys, sp)
}

/// The eigenvalues in the upper half plane (one of each pair), slowest
/// frequency first.
pub fn upper_half(eigenvalues: &[C64]) -> Vec<C64> {
    let mut upper: Vec<C64> = eigenvalues.iter().copied().filter(|l| l.im > 0.0).collect();
    upper.sort_by(|x, y| x.im.total_cmp(&y.im));
    upper
}

/// Default parameters of the `oscillator-chain` plugin `(k, alpha, beta)`.
pub const CHAIN_DEFAULTS: (f64, f64, f64) = (1.0, 1e-5, 1e-3);

/// Spectrum options with unit normalization and shift 0 (`method: None` = automatic).
pub fn spectrum_options(method: Option<Method>, modes: usize) -> SpectrumOptions {
    SpectrumOptions {
        method,
        modes,
        shift: 0.0,
        normalization: Normalization::Unit,
        velocities: None,
    }
}

/// The three variants of the spatial oscillator (Li, Jain & Haller 2023, eqs. 23-25).
pub const OSCILLATOR_CONSTRAINTS: [&str; 3] = ["none", "cubic", "spherical"];

/// The spatial oscillator with `constraint` (paper defaults otherwise), loaded
/// through its `.so`, and its automatically computed finite spectrum.
pub fn oscillator_with_spectrum(constraint: &str) -> (System, Spectrum) {
    let sys = system(
        "spatial-oscillator",
        "",
        &format!("constraint = \"{constraint}\""),
    );
    let sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &spectrum_options(None, 0))
        .expect("oscillator spectrum");
    (sys, sp)
}

/// Autonomous SSM of `pairs` to `order` (resonance tolerance 0.02), with the
/// master modes scaled by `normalization`.
pub fn ssm_of(
    sys: &System,
    sp: &Spectrum,
    pairs: &[usize],
    order: usize,
    normalization: Normalization,
) -> SsmExpansion {
    let masters = spectrum::master_modes(sys, sp, pairs, normalization).expect("master modes");
    let others = ssm_mod::non_master(&sp.eigenvalues, &masters);
    ssm_mod::compute(
        sys,
        &masters,
        &others,
        &SsmOptions {
            order,
            resonance_tol: 0.02,
        },
    )
    .expect("SSM computation")
}

/// Printed polar reduced dynamics of the spatial oscillator's slowest SSM at
/// O(13), Li, Jain & Haller (2023), eqs. (28) (unconstrained), (29) (cubic)
/// and (30) (spherical): `([a1, a3, ..., a13], [b0, b2, ..., b12])` with
/// `rho' = sum a_{2j+1} rho^{2j+1}`, `theta' = sum b_{2j} rho^{2j}`, as printed
/// (4 significant digits).
pub fn oscillator_published_polar(constraint: &str) -> ([&'static str; 7], [&'static str; 7]) {
    match constraint {
        "none" => (
            [
                "-0.02", "-0.2387", "1.08", "-4.408", "27.75", "-71.08", "50.58",
            ],
            [
                "2.0", "-1.206", "-0.3417", "-4.035", "-23.49", "121.5", "-1370",
            ],
        ),
        "cubic" => (
            [
                "-0.02", "-0.02188", "0.02972", "-1.029", "5.913", "-27.97", "214.2",
            ],
            [
                "2.0", "0.8168", "-8.958", "3.485", "-66.98", "-7.963", "-882.8",
            ],
        ),
        "spherical" => (
            [
                "-0.02", "-0.05085", "0.2779", "-1.945", "5.725", "26.99", "1068.0",
            ],
            [
                "2.0", "4.421", "-3.666", "-88.02", "1341.0", "-12060.0", "55620.0",
            ],
        ),
        other => panic!("no published polar form for constraint {other}"),
    }
}

/// A real 4-dimensional polynomial map `z_{k+1} = A z_k + F(z_k)` with two
/// rotation-contraction blocks, `mu_1 = 0.95 e^{0.3 i}` (slow) and
/// `mu_2 = 0.7 e^{1.1 i}`, and quadratic and cubic couplings (sampling period
/// 0.1). Used against Theorem 6.3 of Szalai, Ehrhardt & Haller (2017).
pub fn cubic_map() -> System {
    System::from_model("catalogue", cubic_map_model()).expect("valid map model")
}

/// The plugin data of [`cubic_map`], for tests that corrupt it.
pub fn cubic_map_model() -> ssm_api::Model {
    use ssm_api::reexports::abi_stable::std_types::{ROption, RString, RVec};
    use ssm_api::{
        Model, MotionKind, Output, PolyVector, SparseMatrix, StateInfo, StateKind, TimeKind, Weight,
    };
    let mut a = SparseMatrix::zeros(4, 4);
    for (blk, (r, th)) in [(0.95f64, 0.3f64), (0.7, 1.1)].into_iter().enumerate() {
        let (c, s) = (r * th.cos(), r * th.sin());
        let o = 2 * blk;
        a.push(o, o, c);
        a.push(o, o + 1, -s);
        a.push(o + 1, o, s);
        a.push(o + 1, o + 1, c);
    }
    let mut f = PolyVector::zeros(4, 4);
    f.push(0, 0.3, &[(0, 2)]);
    f.push(0, 0.2, &[(0, 1), (2, 1)]);
    f.push(0, -0.5, &[(0, 3)]);
    f.push(0, 0.1, &[(1, 1), (3, 2)]);
    f.push(1, -0.4, &[(0, 1), (1, 1)]);
    f.push(1, 0.7, &[(1, 3)]);
    f.push(1, 0.15, &[(0, 2), (1, 1)]);
    f.push(2, 0.25, &[(0, 2)]);
    f.push(2, -0.3, &[(1, 2), (2, 1)]);
    f.push(3, 0.35, &[(0, 1), (1, 1)]);
    f.push(3, 0.2, &[(3, 3)]);
    let states: RVec<StateInfo> = (1..=4)
        .map(|i| StateInfo {
            name: RString::from(format!("z{i}")),
            kind: StateKind::Other,
            motion: MotionKind::Unspecified,
        })
        .collect();
    let outputs: RVec<Output> = (0..4)
        .map(|i| Output {
            name: RString::from(format!("z{}", i + 1)),
            weights: vec![Weight {
                state: i,
                value: 1.0,
            }]
            .into(),
        })
        .collect();
    Model {
        name: "cubic-map".into(),
        a,
        b: SparseMatrix::diagonal(&[1.0; 4]),
        nonlinearity: f,
        forcing: RVec::new(),
        states,
        outputs,
        time: TimeKind::Map { period: 0.1 },
        mechanical: ROption::RNone,
        expressions: ssm_api::ExprVector::zeros(4, 4),
        equilibrium: RVec::new(),
    }
}

/// The spectrum of a map, sorted by `ln |mu|` (slowest first).
pub fn map_spectrum(sys: &System) -> Spectrum {
    let mut sp = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &spectrum_options(None, 0))
        .expect("map spectrum");
    spectrum::sort_multipliers(&mut sp.eigenvalues);
    sp
}

/// Two oscillators with an exact 1:2 resonance, `lambda_2 = 2 lambda_1`
/// (`omega_2 = 2 omega_1`, equal damping ratios `zeta`), coupled by the
/// quadratic terms `x1^2` (in the second equation) and `x1 x2` (in the first)
/// and with cubic self-stiffening.
pub fn one_to_two_resonant(zeta: f64) -> System {
    one_to_two_forced(zeta, 0.0)
}

/// [`one_to_two_resonant`] with the load `f cos(Omega t)` on `x2` (scaled by
/// the forcing amplitude `eps`): near `Omega = 2` the coupling `x1 x2` pumps
/// `x1` parametrically (a Mathieu tongue for `0.5 |x2| > 4 zeta`), so the
/// response can be of period `2T` (a frequency divider).
pub fn one_to_two_forced(zeta: f64, f: f64) -> System {
    use ssm_api::{PolyVector, SparseMatrix};
    use ssm_plugin_kit::MechanicalSystem;
    let mut m = MechanicalSystem::new("one-to-two", &["x1", "x2"]);
    if f != 0.0 {
        m.forcing = forced::cosine_load(2, 1, f);
    }
    let (w1, w2) = (1.0f64, 2.0f64);
    m.mass = SparseMatrix::diagonal(&[1.0, 1.0]);
    m.damping = SparseMatrix::diagonal(&[2.0 * zeta * w1, 2.0 * zeta * w2]);
    m.stiffness = SparseMatrix::diagonal(&[w1 * w1, w2 * w2]);
    let mut f = PolyVector::zeros(2, 4);
    f.push(0, 0.5, &[(0, 1), (1, 1)]);
    f.push(1, 0.25, &[(0, 2)]);
    f.push(0, 0.3, &[(0, 3)]);
    f.push(1, 0.2, &[(1, 3)]);
    m.internal_force = f;
    let model = m.into_model().expect("valid mechanical model");
    System::from_model("catalogue", model).expect("valid model")
}

/// Model `model` of the `pendulum` plugin (parameters `params`, TOML) through its
/// `.so` and the recast, with the finite spectrum of its physical pencil (no
/// spurious recast modes); the chain uses the sparse path (8 modes).
pub fn pendulum_with_spectrum(model: &str, params: &str) -> (System, Spectrum) {
    let sys = system("pendulum", model, params);
    let method = (model == "chain").then_some(Method::Sparse);
    let (a, b) = sys.spectral_pencil();
    let sp = spectrum::compute(a, b, &spectrum_options(method, 8)).expect("pendulum spectrum");
    (sys, sp)
}

/// Two masses tied by the linear constraint `x1 - x2 = 0` (masses 1 and 2,
/// springs 3 and 5, dampers 0.1 and 0.2): an index-3 DAE whose motion is the
/// damped oscillator `3 x'' + 0.3 x' + 8 x = 0`. Returns the system and the
/// closed-form solution [`LinearConstrained`] from `x(0) = x0`, `x'(0) = 0`.
pub fn linear_constrained_oscillator(x0: f64) -> (System, LinearConstrained) {
    use ssm_api::{PolyVector, SparseMatrix};
    use ssm_plugin_kit::{Constraints, MechanicalSystem};
    let mut m = MechanicalSystem::new("linear-constrained", &["x1", "x2"]);
    m.mass = SparseMatrix::diagonal(&[1.0, 2.0]);
    m.damping = SparseMatrix::diagonal(&[0.1, 0.2]);
    m.stiffness = SparseMatrix::diagonal(&[3.0, 5.0]);
    let mut g = PolyVector::zeros(1, 2);
    g.push(0, 1.0, &[(0, 1)]);
    g.push(0, -1.0, &[(1, 1)]);
    m.constraints = Some(Constraints::polynomial(g));
    let model = m.into_model().expect("valid mechanical model");
    let sys = System::from_model("catalogue", model).expect("valid model");
    let zeta_w: f64 = 0.3 / (2.0 * 3.0);
    let wd = (8.0 / 3.0 - zeta_w * zeta_w).sqrt();
    (
        sys,
        LinearConstrained {
            x0,
            decay: zeta_w,
            wd,
        },
    )
}

/// Closed-form motion of [`linear_constrained_oscillator`]:
/// `x(t) = x0 e^{-d t} (cos wd t + (d / wd) sin wd t)`, and the multiplier
/// `mu = -(m1 x'' + c1 x' + k1 x)` of the first mass's equation.
#[derive(Debug, Clone, Copy)]
pub struct LinearConstrained {
    /// Initial displacement.
    pub x0: f64,
    /// Decay rate `d`.
    pub decay: f64,
    /// Damped frequency `wd`.
    pub wd: f64,
}

impl LinearConstrained {
    /// `(x, x', mu)` at time `t`.
    pub fn at(&self, t: f64) -> (f64, f64, f64) {
        let (d, wd) = (self.decay, self.wd);
        let e = (-d * t).exp();
        let (s, c) = (wd * t).sin_cos();
        let x = self.x0 * e * (c + d / wd * s);
        let v = -self.x0 * e * (d * d / wd + wd) * s;
        let a = -0.3 / 3.0 * v - 8.0 / 3.0 * x;
        (x, v, -(a + 0.1 * v + 3.0 * x))
    }
}

/// Frequency of the conservative pendulum `phi'' + sin(phi) = 0` at amplitude
/// `a`: `pi / (2 K(sin(a/2)))` with the complete elliptic integral of the first
/// kind, `K(k) = pi / (2 AGM(1, sqrt(1 - k^2)))`, i.e. `AGM(1, cos(a/2))`.
pub fn conservative_frequency(a: f64) -> f64 {
    let (mut x, mut y) = (1.0f64, (a / 2.0).cos());
    // quadratic convergence: 64 steps are far more than enough; stop at round-off
    for _ in 0..64 {
        if (x - y).abs() <= 4.0 * f64::EPSILON * x {
            break;
        }
        (x, y) = (0.5 * (x + y), (x * y).sqrt());
    }
    x
}

/// The decaying signals of `x1'` of the modified Shaw-Pierre oscillator
/// (Szalai, Ehrhardt & Haller 2017, Sect. 9a) from the initial conditions
/// (9.2), 8000 samples at `T = 0.8`, with additive noise `noise` (relative to
/// each signal's peak, seeded), written by `[simulate]` into `dir`; returns
/// the two files. Integrated at `rtol = 1e-13`, `atol = 1e-16`, near the
/// floor of double precision, so that the tolerances stay below 1e-10 of
/// even the tail at 1e-5 of the peak: noise-free data for the linear figures.
pub fn shaw_pierre_data(dir: &Path, noise: f64, seed: u64) -> Vec<PathBuf> {
    let x1 = 2.0 / 3f64.sqrt();
    let scene = format!(
        "[model]\nplugin = \"shaw-pierre\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x1\"]\n\
         [simulate]\nperiod = 0.8\nsamples = 8000\noutputs = [\"x1_dot\"]\nnoise = {noise}\nseed = {seed}\n\
         rtol = 1e-13\natol = 1e-16\n\
         [[simulate.run]]\nx0 = {{ x1 = {x1}, x2 = {x1} }}\n\
         [[simulate.run]]\nx0 = {{ x1 = {}, x2 = {} }}\n",
        -2.0 / 3.0,
        2.0 / 3.0
    );
    let r = run_scene_text(&scene).expect("data scene runs");
    r.outputs.write(dir).expect("data written");
    vec![dir.join("simulation_1.csv"), dir.join("simulation_2.csv")]
}

/// The decaying signals of `x1'` of the chain of three cubic oscillators
/// (plugin `oscillator-chain`, `n = 3`, defaults otherwise), one started on
/// each linear mode shape `sin(j k pi / 4)` with amplitude 0.5, 8000 samples
/// at `T = 0.8`: data whose delay embedding needs `2 nu = 6`.
pub fn chain3_data(dir: &Path) -> Vec<PathBuf> {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let mut scene = String::from(
        "[model]\nplugin = \"oscillator-chain\"\n[model.params]\nn = 3\n[ssm]\norder = 3\n\
         [outputs]\ncoordinates = [\"x1\"]\n[simulate]\nperiod = 0.8\nsamples = 8000\noutputs = [\"x1_dot\"]\n",
    );
    for shape in [[s, 1.0, s], [1.0, 0.0, -1.0], [s, -1.0, s]] {
        scene.push_str(&format!(
            "[[simulate.run]]\nx0 = {{ x1 = {}, x2 = {}, x3 = {} }}\n",
            0.5 * shape[0],
            0.5 * shape[1],
            0.5 * shape[2]
        ));
    }
    let r = run_scene_text(&scene).expect("chain data scene runs");
    r.outputs.write(dir).expect("data written");
    (1..=3)
        .map(|k| dir.join(format!("simulation_{k}.csv")))
        .collect()
}

/// Runs the zoo's data scene `scene` (a `[simulate]` section with `runs`
/// runs) in-process and writes its files into `dir`; returns the
/// `simulation_<k>.csv` files, so tests use the zoo's own data (its summary
/// checked against the schema).
pub fn zoo_data(scene: &str, dir: &Path, runs: usize) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(repo_root().join("zoo").join(scene))
        .unwrap_or_else(|e| panic!("zoo/{scene}: {e}"));
    let r = run_scene_text(&text).unwrap_or_else(|e| panic!("zoo/{scene}: {e}"));
    r.outputs.write(dir).expect("data written");
    assert_summary_valid(&dir.join("summary.json"));
    (1..=runs)
        .map(|k| dir.join(format!("simulation_{k}.csv")))
        .collect()
}

/// The three noisy decaying signals of the quarter-span velocity of the
/// clamped-clamped beam (plugin `divider`, model `beam`), one started on the
/// SSM of each of the first three mode pairs, as `zoo/beam_data.toml` makes
/// them, written into `dir`; returns the three files.
pub fn beam_data(dir: &Path) -> Vec<PathBuf> {
    zoo_data("beam_data.toml", dir, 3)
}

/// Reducer diagnostic `name` of a run's `summary.json` (`reduction.diagnostics`)
/// as numbers (a scalar gives one).
pub fn diagnostic(summary: &serde_json::Value, name: &str) -> Vec<f64> {
    match &summary["reduction"]["diagnostics"][name] {
        serde_json::Value::Array(a) => a.iter().map(|v| v.as_f64().unwrap()).collect(),
        v => vec![v.as_f64().unwrap_or_else(|| panic!("{name}: {v}"))],
    }
}

/// An HHT run (`alpha = -0.1`, fixed steps `h`) of `sys` from rest at the
/// origin over `[0, t_end]`, forced with `eps`, `Omega`: the crank drive's
/// training and check runs.
pub fn hht_from_rest(
    sys: &System,
    eps: f64,
    omega: f64,
    t_end: f64,
    h: f64,
) -> ssm_core::fom::hht::HhtSolution {
    use ssm_core::fom::hht::{integrate, HhtOptions};
    let p = ssm_core::fom::DaeProblem::new(sys, eps, omega);
    let z0 = vec![0.0; sys.states.len()];
    integrate(&p, &z0, 0.0, t_end, &HhtOptions::new(-0.1, h)).expect("HHT run")
}

/// Largest deviation over a run of the lifted positions `U q_r` of a POD
/// reduced run from the full ones, relative to the largest full position
/// (the reduced run interpolated at the full run's step ends).
pub fn pod_coordinate_error(
    full: &ssm_core::fom::hht::HhtSolution,
    reduced: &ssm_core::fom::hht::HhtSolution,
    u: faer::MatRef<'_, f64>,
) -> f64 {
    let (n, r) = (u.nrows(), u.ncols());
    let (mut err, mut peak) = (0.0f64, 0.0f64);
    for (&t, z) in full.times.iter().zip(&full.states) {
        let y = reduced.at(t, r);
        for (i, zi) in z[..n].iter().enumerate() {
            let lifted: f64 = (0..r).map(|j| u[(i, j)] * y[j]).sum();
            err = err.max((lifted - zi).abs());
            peak = peak.max(zi.abs());
        }
    }
    err / peak
}

/// The text of an SVG document: its text elements in order, joined by
/// single spaces (so that a legend label wrapped over several lines reads
/// as one).
pub fn svg_text(svg: &str) -> String {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| t.split_once('>').map(|(_, rest)| rest))
        .filter_map(|rest| rest.split("</text>").next())
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The largest deviation of `b` from `a` (time-major outputs, one row per
/// time), each output's relative to its peak in `a`: computed here, apart
/// from the engine's own error figures.
pub fn peak_relative_deviation(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    let outputs = a.first().map_or(0, Vec::len);
    (0..outputs)
        .map(|o| {
            let peak = a.iter().map(|r| r[o].abs()).fold(0.0, f64::max);
            a.iter()
                .zip(b)
                .map(|(x, y)| (x[o] - y[o]).abs())
                .fold(0.0, f64::max)
                / peak
        })
        .fold(0.0, f64::max)
}
