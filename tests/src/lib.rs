//! Shared catalogue of test problems with known answers, used by the
//! integration tests and the benchmarks, and helpers to find the built plugin
//! libraries and the `ssm-engine` binary.
//!
//! Plugins are `cdylib`s: build them first (`cargo build --release --workspace`);
//! the tests look for them next to the test executable's profile directory.

use std::path::PathBuf;

use num_complex::Complex64 as C64;
use ssm_engine::plugin::Plugin;
use ssm_engine::scene::Normalization;
use ssm_engine::spectrum::{self, Method, Spectrum, SpectrumOptions};
use ssm_engine::system::System;

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

/// Default parameters of the `oscillator-chain` plugin `(k, alpha, beta)`.
pub const CHAIN_DEFAULTS: (f64, f64, f64) = (1.0, 1e-5, 1e-3);

/// Spectrum options with unit normalization and shift 0 (`method: None` = automatic).
pub fn spectrum_options(method: Option<Method>, modes: usize) -> SpectrumOptions {
    SpectrumOptions {
        method,
        modes,
        shift: 0.0,
        normalization: Normalization::Unit,
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
