//! Models from files: the plugin `matrix-model` reading a model folder, and
//! `ssm-engine export` writing one (issue "Models from files").
//!
//! References: the plugin that made the model (round trip, to 1e-12), closed
//! forms for models the tests write from formulas (two-DOF eigenvalues, the
//! Duffing normal-form coefficient), and the file and line each bad file must
//! name.

use std::path::Path;
use std::process::Command;

use num_complex::Complex64 as C64;
use ssm_core::model::plugin::Plugin;
use ssm_core::model::system::System;
use ssm_core::spectrum::Normalization;
use ssm_core::spectrum::{self, Method, Spectrum};
use ssm_core::ssm::analysis::polar;
use ssm_core::ssm::SsmExpansion;
use ssm_tests::{engine_binary, plugin_path, repo_root, spectrum_options, ssm_of, system, tmp_dir};

/// The model of the folder `dir`, built by the plugin `matrix-model`.
fn from_files(dir: &Path, extra: &str) -> Result<System, String> {
    let plugin = Plugin::load(&plugin_path("matrix-model")).expect("plugin loads");
    let params = format!("dir = {:?}\n{extra}", dir.display().to_string());
    let m = plugin.build_model("", &params).map_err(|e| e.to_string())?;
    System::from_model(plugin.name(), m).map_err(|e| e.to_string())
}

/// Writes `files` (name, text) into a fresh folder.
fn folder(name: &str, files: &[(&str, String)]) -> std::path::PathBuf {
    let dir = tmp_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    for (f, text) in files {
        std::fs::write(dir.join(f), text).unwrap();
    }
    dir
}

fn spectrum_of(sys: &System, method: Option<Method>, modes: usize) -> Spectrum {
    spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &spectrum_options(method, modes),
    )
    .expect("spectrum")
}

/// Largest relative difference of the eigenvalues, of the reduced dynamics
/// and of the SSM coefficients of the two systems' SSMs.
fn compare(
    a: &System,
    b: &System,
    method: Option<Method>,
    modes: usize,
    pairs: &[usize],
    order: usize,
) {
    let (sa, sb) = (spectrum_of(a, method, modes), spectrum_of(b, method, modes));
    assert_eq!(sa.eigenvalues.len(), sb.eigenvalues.len());
    for (x, y) in sa.eigenvalues.iter().zip(&sb.eigenvalues) {
        assert!(
            (x - y).norm() <= 1e-12 * x.norm(),
            "eigenvalue {x} against {y}"
        );
    }
    let (wa, wb): (SsmExpansion, SsmExpansion) = (
        ssm_of(a, &sa, pairs, order, Normalization::Unit),
        ssm_of(b, &sb, pairs, order, Normalization::Unit),
    );
    assert_eq!(wa.r.len(), wb.r.len());
    let r_scale = wa.r.iter().map(|t| t.coeff.norm()).fold(0.0, f64::max);
    for (x, y) in wa.r.iter().zip(&wb.r) {
        assert_eq!((x.coord, x.index), (y.coord, y.index));
        assert!(
            (x.coeff - y.coeff).norm() <= 1e-12 * r_scale.max(x.coeff.norm()),
            "reduced dynamics {:?}: {} against {}",
            wa.set.exponents(x.index),
            x.coeff,
            y.coeff
        );
    }
    assert_eq!(wa.w.len(), wb.w.len());
    for (k, (x, y)) in wa.w.iter().zip(&wb.w).enumerate() {
        let scale = x.iter().map(|c| c.norm()).fold(0.0, f64::max);
        let diff = x
            .iter()
            .zip(y)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        assert!(
            diff <= 1e-12 * scale.max(1e-300),
            "W at {:?}: difference {diff:e} of {scale:e}",
            wa.set.exponents(k)
        );
    }
}

/// Reference: the divider plugin itself. `ssm-engine export` writes its model
/// (146 states, a revolute joint, quadratic and cubic von Karman forces); read
/// back, the spectrum, the 4-D SSM's reduced dynamics and its coefficients at
/// O(5) agree to 1e-12 (rounding only: the files carry every digit).
#[test]
fn divider_exported_and_read_back_gives_the_same_spectrum_and_ssm() {
    let dir = tmp_dir("export-divider");
    let export = |scene: &str| {
        let o = Command::new(engine_binary())
            .arg("export")
            .arg(scene)
            .arg(&dir)
            .current_dir(repo_root())
            .output()
            .expect("ssm-engine runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    // an earlier export in the folder (with g3.coo) is replaced as a whole
    export("zoo/spatial_oscillator_cubic.toml");
    assert!(dir.join("g3.coo").exists());
    export("zoo/divider_frc.toml");
    assert!(
        !dir.join("g3.coo").exists(),
        "a file of the earlier export stayed"
    );
    let original = system("divider", "", "");
    let read = from_files(&dir, "").expect("the exported folder builds");
    assert_eq!(original.n_states(), read.n_states());
    for name in ["w_hori_mid", "w_vert_mid"] {
        assert!(read.outputs.iter().any(|o| o.name == name), "output {name}");
    }
    compare(&original, &read, Some(Method::Sparse), 20, &[1, 2], 5);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Reference: the spatial oscillator plugin with its cubic constraint (eq. 24,
/// `g3.coo`); spectrum, the slow SSM at O(9) and its coefficients to 1e-12.
#[test]
fn spatial_oscillator_with_cubic_constraint_round_trips() {
    let original = system("spatial-oscillator", "", "constraint = \"cubic\"");
    let plugin = Plugin::load(&plugin_path("spatial-oscillator")).unwrap();
    let model = plugin.build_model("", "constraint = \"cubic\"").unwrap();
    let (files, notes) = ssm_plugin_kit::files_from_model(&model).unwrap();
    assert!(notes.is_empty(), "{notes:?}");
    let encoded = files.encode("test").unwrap();
    assert!(encoded.iter().any(|(n, _)| *n == "g3.coo"));
    let texts: Vec<(&str, String)> = encoded
        .into_iter()
        .map(|(n, c)| (n, String::from_utf8(c).unwrap()))
        .collect();
    let dir = folder("export-oscillator", &texts);
    let read = from_files(&dir, "").unwrap();
    compare(&original, &read, None, 0, &[1], 9);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Reference (closed form): two masses between three springs, written by the
/// test as files (`M` symmetric coordinate, `K` symmetric array, Rayleigh
/// damping from the scene parameters). The undamped `omega^2` solve
/// `m1 m2 w^4 - (m1 (k2 + k3) + m2 (k1 + k2)) w^2 + (k1 + k2)(k2 + k3) - k2^2 = 0`;
/// Rayleigh damping keeps the modes, so each pair is
/// `lambda = -d/2 +- i sqrt(w^2 - d^2/4)` with `d = alpha + beta w^2`.
#[test]
fn two_dof_model_written_from_formulas_has_the_closed_form_eigenvalues() {
    let (m1, m2, k1, k2, k3) = (1.5f64, 0.75f64, 2.0f64, 3.0f64, 5.0f64);
    let (alpha, beta) = (0.02f64, 0.003f64);
    let dir = folder(
        "two-dof",
        &[
            (
                "M.mtx",
                format!(
                    "%%MatrixMarket matrix coordinate real symmetric\n% masses\n2 2 2\n1 1 {m1}\n2 2 {m2}\n"
                ),
            ),
            (
                "K.mtx",
                // column-major lower triangle: K11, K21, K22
                format!(
                    "%%MatrixMarket matrix array real symmetric\n2 2\n{}\n{}\n{}\n",
                    k1 + k2,
                    -k2,
                    k2 + k3
                ),
            ),
        ],
    );
    let sys = from_files(&dir, &format!("rayleigh = [{alpha}, {beta}]")).unwrap();
    let sp = spectrum_of(&sys, None, 0);
    let (a, b, c) = (
        m1 * m2,
        -(m1 * (k2 + k3) + m2 * (k1 + k2)),
        (k1 + k2) * (k2 + k3) - k2 * k2,
    );
    let disc = (b * b - 4.0 * a * c).sqrt();
    let mut w2 = [(-b - disc) / (2.0 * a), (-b + disc) / (2.0 * a)];
    w2.sort_by(f64::total_cmp);
    let found = ssm_tests::upper_half(&sp.eigenvalues);
    assert_eq!(found.len(), 2, "{:?}", sp.eigenvalues);
    for (l, w2) in found.iter().zip(w2) {
        let d = alpha + beta * w2;
        let expected = C64::new(-d / 2.0, (w2 - d * d / 4.0).sqrt());
        assert!(
            (l - expected).norm() < 1e-12 * expected.norm(),
            "{l} against {expected}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Reference (closed form, as in `tests/ssm_autonomous.rs`): the Duffing
/// oscillator `x'' + 2 zeta w x' + w^2 x + kappa x^3 = 0` written as files
/// (`f3.coo` holds `1 1 1 1 kappa`) has the cubic normal-form coefficient
/// `theta' = w_d + 3 kappa rho^2 / (2 w_d (1 + w^2))` under unit normalization,
/// and no cubic damping.
#[test]
fn duffing_written_as_files_has_the_closed_form_cubic_coefficient() {
    let (zeta, w, kappa) = (0.02f64, 1.7f64, -0.6f64);
    let dir = folder(
        "duffing-files",
        &[
            (
                "M.mtx",
                "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1\n".into(),
            ),
            (
                "K.mtx",
                format!("%%MatrixMarket matrix array real general\n1 1\n{}\n", w * w),
            ),
            (
                "C.mtx",
                format!(
                    "%%MatrixMarket matrix array real general\n1 1\n{}\n",
                    2.0 * zeta * w
                ),
            ),
            ("f3.coo", format!("% the cubic spring\n1 1 1 1 {kappa}\n")),
            (
                "fext.mtx",
                "%%MatrixMarket matrix array real general\n1 1\n1\n".into(),
            ),
            ("outputs.csv", "name,dof\ndisplacement,1\n".into()),
        ],
    );
    let sys = from_files(&dir, "").unwrap();
    assert!(sys.outputs.iter().any(|o| o.name == "displacement"));
    assert_eq!(sys.forcing.len(), 1);
    let sp = spectrum_of(&sys, None, 0);
    let p = polar(&ssm_of(&sys, &sp, &[1], 3, Normalization::Unit)).unwrap();
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let expected = 3.0 * kappa / (2.0 * wd * (1.0 + w * w));
    assert!(
        (p.c[1] - C64::new(0.0, expected)).norm() < 1e-12 * expected.abs(),
        "{:?}",
        p.c
    );
    assert!((p.c[0] - C64::new(-zeta * w, wd)).norm() < 1e-12 * w);
    let _ = std::fs::remove_dir_all(&dir);
}

const M2: &str = "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n2 2 2.0\n";
const K2: &str =
    "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 4.0\n2 1 -1.0\n2 2 3.0\n";

/// A bad folder: what is wrong, the files replacing the good ones, the
/// scene parameters, and the pieces the error must contain.
type BadCase = (
    &'static str,
    Vec<(&'static str, String)>,
    &'static str,
    Vec<&'static str>,
);

/// Each bad folder must give an error that names the file, the line where
/// there is one, and the problem (the list: wrong sizes, a
/// non-symmetric matrix declared symmetric, indices out of range, non-finite
/// values, a missing required file, a malformed line, a singular `M` without
/// constraints; and the other ways a folder can be wrong).
#[test]
fn each_bad_file_is_named_with_its_line_and_problem() {
    let k3 = "%%MatrixMarket matrix coordinate real general\n3 3 1\n1 1 1.0\n";
    let cases: Vec<BadCase> = vec![
        ("wrong size", vec![("K.mtx", k3.into())], "", vec!["K.mtx", "is 3x3, but M.mtx is 2x2"]),
        (
            "declared symmetric, not symmetric",
            vec![(
                "M.mtx",
                "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 1.0\n1 2 0.5\n2 2 1.0\n".into(),
            )],
            "",
            vec!["M.mtx, line 4", "above the diagonal", "declare it general"],
        ),
        (
            "index out of range",
            vec![("f2.coo", "% quadratic\n1 3 1 2.0\n".into())],
            "",
            vec!["f2.coo, line 2", "variable index 3 is outside 1..=2"],
        ),
        (
            "non-finite value",
            vec![(
                "K.mtx",
                "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 4.0\n2 2 nan\n".into(),
            )],
            "",
            vec!["K.mtx, line 4", "value 'nan' is not finite"],
        ),
        (
            "malformed line",
            vec![("f3.coo", "1 1 1 2.0\n".into())],
            "",
            vec!["f3.coo, line 1", "expected 'i j k l value' (5 fields)"],
        ),
        (
            "singular M without constraints",
            vec![("M.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1.0\n".into())],
            "",
            vec!["M.mtx", "1 have no mass", "infinite", "G.mtx"],
        ),
        (
            "massless degree of freedom",
            vec![(
                "M.mtx",
                "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n1 2 0.5\n".into(),
            )],
            "",
            vec!["M.mtx", "degree of freedom 2 has no mass", "infinite"],
        ),
        (
            "negative mass",
            vec![(
                "M.mtx",
                "%%MatrixMarket matrix coordinate real general\n2 2 2\n1 1 1.0\n2 2 -2.0\n".into(),
            )],
            "",
            vec!["M.mtx", "M(2, 2) = -2", "positive definite"],
        ),
        (
            "non-symmetric mass matrix declared general",
            vec![(
                "M.mtx",
                "%%MatrixMarket matrix coordinate real general\n2 2 4\n1 1 1.0\n2 2 1.0\n1 2 0.5\n2 1 -0.5\n".into(),
            )],
            "",
            vec!["M.mtx", "M(2, 1) = -0.5 but M(1, 2) = 0.5", "must be symmetric"],
        ),
        (
            "fewer entries than declared",
            vec![("K.mtx", K2.replace("2 2 3\n", "2 2 4\n"))],
            "",
            vec!["K.mtx", "declares 4 entries, the file has 3"],
        ),
        (
            "more entries than declared",
            vec![("K.mtx", K2.replace("2 2 3\n", "2 2 2\n"))],
            "",
            vec!["K.mtx, line 5", "more entries than the 2"],
        ),
        (
            "bad header",
            vec![("M.mtx", "%%MatrixMarket matrix coordinate complex general\n2 2 0\n".into())],
            "",
            vec!["M.mtx, line 1", "complex"],
        ),
        (
            "output dof out of range",
            vec![("outputs.csv", "name,dof\ntip,3\n".into())],
            "",
            vec!["outputs.csv, line 2", "dof 3 is outside 1..=2"],
        ),
        (
            "output named like a state",
            vec![("outputs.csv", "x2,1\n".into())],
            "",
            vec!["outputs.csv", "'x2' is the name of a state"],
        ),
        (
            "constraint terms without G0",
            vec![("g2.coo", "1 1 2 1.0\n".into())],
            "",
            vec!["g2.coo", "need the linear part G.mtx"],
        ),
        (
            "load of the wrong size",
            vec![("fext.mtx", "%%MatrixMarket matrix array real general\n3 1\n1\n0\n0\n".into())],
            "",
            vec!["fext.mtx", "the load shape must be 2x1"],
        ),
        (
            "damping twice",
            vec![("C.mtx", M2.into())],
            "rayleigh = [0.0, 0.01]",
            vec!["rayleigh", "keep one"],
        ),
        (
            "constraint without linear part",
            vec![
                ("G.mtx", "%%MatrixMarket matrix coordinate real general\n2 2 1\n1 1 1.0\n".into()),
                ("g2.coo", "2 1 2 1.0\n".into()),
            ],
            "",
            vec!["G.mtx", "row 2 is empty", "rank deficient"],
        ),
        (
            "more constraints than degrees of freedom",
            vec![(
                "G.mtx",
                "%%MatrixMarket matrix coordinate real general\n3 2 3\n1 1 1.0\n2 2 1.0\n3 1 1.0\n".into(),
            )],
            "",
            vec!["G.mtx", "is 3x2", "1 <= n_c <= n"],
        ),
        ("Rayleigh with one value", vec![], "rayleigh = [0.1]", vec!["rayleigh", "a list of 2 numbers"]),
    ];
    for (what, files, params, expected) in cases {
        let mut all: Vec<(&str, String)> = vec![("M.mtx", M2.into()), ("K.mtx", K2.into())];
        for (name, text) in files {
            all.retain(|(n, _)| *n != name);
            all.push((name, text));
        }
        let dir = folder("bad-files", &all);
        let e = from_files(&dir, params).expect_err(what);
        for piece in expected {
            assert!(e.contains(piece), "{what}: '{piece}' not in: {e}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    let dir = folder("missing", &[("M.mtx", M2.into())]);
    let e = from_files(&dir, "").unwrap_err();
    assert!(e.contains("K.mtx: required file missing"), "{e}");
    let e = from_files(&dir.join("nowhere"), "").unwrap_err();
    assert!(e.contains("is not a folder"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene next to its model folder runs from any working directory (the
/// relative `dir` is read from the scene's folder), and a wrong `dir` is a
/// scene error at its line.
#[test]
fn scene_reads_the_folder_relative_to_itself() {
    let root = tmp_dir("scene-files");
    std::fs::create_dir_all(root.join("model")).unwrap();
    for (name, text) in [("M.mtx", M2), ("K.mtx", K2)] {
        std::fs::write(root.join("model").join(name), text).unwrap();
    }
    std::fs::write(root.join("model/f3.coo"), "1 1 1 1 0.5\n2 2 2 2 0.5\n").unwrap();
    let scene = "[model]\nplugin = \"matrix-model\"\n[model.params]\ndir = \"model\"\nrayleigh = [0.0, 0.01]\n\n[ssm]\nmaster_pairs = [1]\norder = 5\n";
    std::fs::write(root.join("s.toml"), scene).unwrap();
    let run = |scene_file: &str| {
        Command::new(engine_binary())
            .arg(root.join(scene_file))
            .arg("--out")
            .arg(root.join("out"))
            .current_dir(std::env::temp_dir())
            .env("CI", "1")
            .output()
            .unwrap()
    };
    let o = run("s.toml");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(root.join("out/summary.json").exists());
    std::fs::write(
        root.join("bad.toml"),
        scene.replace("\"model\"", "\"modle\""),
    )
    .unwrap();
    let o = run("bad.toml");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("bad.toml:4:") && err.contains("model.params.dir") && err.contains("modle"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&root);
}

/// Reference: the oscillator-chain plugin at 10^5 masses (2 x 10^5 states)
/// and the chain's closed-form spectrum (`ssm_tests::chain_eigenvalues`).
/// Written as files (about 30 MB), read back streaming, the sparse spectrum's
/// slowest pairs match the closed form to 1e-9 and the O(3) SSM of the
/// slowest pair matches the plugin's to 1e-12. Reading time is printed
/// (`--nocapture`); `cargo bench -p ssm-benches --bench model_files` times it.
#[test]
fn chain_of_100000_masses_from_files_through_the_sparse_path() {
    let n = 100_000;
    let params = format!("n = {n}");
    let original = system("oscillator-chain", "", &params);
    let model = Plugin::load(&plugin_path("oscillator-chain"))
        .unwrap()
        .build_model("", &params)
        .unwrap();
    let (files, _) = ssm_plugin_kit::files_from_model(&model).unwrap();
    let dir = tmp_dir("chain-files");
    std::fs::create_dir_all(&dir).unwrap();
    for (name, contents) in files.encode("test").unwrap() {
        std::fs::write(dir.join(name), contents).unwrap();
    }
    let t0 = std::time::Instant::now();
    let read = from_files(&dir, "").unwrap();
    println!(
        "read {n} degrees of freedom from files in {:.2} s",
        t0.elapsed().as_secs_f64()
    );
    let sp = spectrum_of(&read, Some(Method::Sparse), 6);
    let (k, alpha, beta) = ssm_tests::CHAIN_DEFAULTS;
    let exact = ssm_tests::chain_eigenvalues(n, k, alpha, beta, 3);
    let found = ssm_tests::upper_half(&sp.eigenvalues);
    assert!(found.len() >= exact.len(), "{found:?}");
    for (l, e) in found.iter().zip(&exact) {
        assert!((l - e).norm() < 1e-9 * e.norm(), "{l} against {e}");
    }
    let so = spectrum_of(&original, Some(Method::Sparse), 6);
    let (wa, wb) = (
        ssm_of(&original, &so, &[1], 3, Normalization::Unit),
        ssm_of(&read, &sp, &[1], 3, Normalization::Unit),
    );
    assert_eq!(wa.r.len(), wb.r.len());
    for (x, y) in wa.r.iter().zip(&wb.r) {
        assert!((x.coeff - y.coeff).norm() <= 1e-12 * x.coeff.norm().max(1e-300));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The README's "Bring your own model" example, run as a newcomer would: the
/// Python script (numpy and scipy only; `.ci/run` installs them; without them
/// the test fails and says how to install them) writes the clamped-clamped beam, the scene next to it runs. The
/// reference is the closed-form first bending frequency of a clamped-clamped
/// beam, `4.730041^2 / L^2 sqrt(E I / (rho A))` (Blevins, *Formulas for
/// natural frequency and mode shape*, table 8-1): consistent-mass Hermite
/// elements bound it from above (Rayleigh-Ritz) and converge as `h^4`, so 8
/// elements must lie above it by less than 1e-4 (measured: 8.4e-5). The
/// Rayleigh pair is `-beta w^2 / 2 +- i w_d`.
///
/// Backbone reference: the single-mode Galerkin projection on the exact
/// clamped-clamped mode `phi` gives the Duffing equation
/// `rho A |phi|^2 q'' + E I |phi''|^2 q + E A / (2 L) |phi'|^2^2 q^3 = 0`, so
/// `omega = omega_0 + c a^2` in the midpoint amplitude `a` with
/// `c = 3 gamma / (8 omega_0 phi(L/2)^2)`, `gamma = E A |phi'|^4 / (2 L rho A
/// |phi|^2)` (integrals by Simpson's rule on the analytic mode shape). With
/// a cubic force only, the O(3) SSM backbone coefficient is that projection on
/// the FE mode, so at amplitudes up to 0.05 mm the engine's `(omega -
/// omega_0) / a^2` must match `c` to 1e-3 (FE mode error and the `O(a^2)`
/// terms of the amplitude map; measured 3.6e-4).
#[test]
fn readme_python_beam_example_runs() {
    let python = Command::new("python3")
        .args(["-c", "import numpy, scipy"])
        .output();
    assert!(
        python.is_ok_and(|o| o.status.success()),
        "this test runs the Python model example of docs/models.md, which needs python3 \
         with numpy and scipy: install them with `python3 -m pip install numpy scipy`"
    );
    let root = tmp_dir("python-beam");
    std::fs::create_dir_all(&root).unwrap();
    let files = repo_root().join("zoo/files");
    std::fs::copy(files.join("beam.toml"), root.join("beam.toml")).unwrap();
    let o = Command::new("python3")
        .arg(files.join("write_beam.py"))
        .arg(root.join("beam"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new(engine_binary())
        .arg(root.join("beam.toml"))
        .arg("--out")
        .arg(root.join("out"))
        .env("CI", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("out/summary.json")).unwrap()).unwrap();
    let (l, e, i, rho_a, beta) = (500.0f64, 70e6f64, 10.0f64 / 12.0, 2700e-9 * 10.0, 2e-5f64);
    let w = (4.730_040_745f64 / l).powi(2) * (e * i / rho_a).sqrt();
    let l1 = &s["spectrum"][0];
    let (re, im) = (l1["re"].as_f64().unwrap(), l1["im"].as_f64().unwrap());
    let w_fe = (re * re + im * im).sqrt();
    let rel = (w_fe - w) / w;
    eprintln!("beam: first bending frequency {w_fe} against {w} ({rel:.2e})");
    assert!(
        rel > 0.0 && rel < 1e-4,
        "first bending frequency {w_fe} against {w}"
    );
    assert!(
        (re + beta * w_fe * w_fe / 2.0).abs() < 1e-9 * w_fe,
        "Rayleigh damping {re}"
    );
    let csv = std::fs::read_to_string(root.join("out/backbone.csv")).unwrap();
    let c = galerkin_backbone_coefficient(l, e, i, rho_a, 10.0);
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|r| r.split(',').map(|x| x.parse().unwrap()).collect())
        .filter(|v: &Vec<f64>| v[0] == 3.0)
        .collect();
    let w0 = rows[0][2];
    let mut checked = 0;
    for v in rows.iter().filter(|v| v[3] > 0.0 && v[3] <= 0.05) {
        let coefficient = (v[2] - w0) / (v[3] * v[3]);
        eprintln!("beam: backbone coefficient {coefficient} against {c}");
        assert!(
            (coefficient / c - 1.0).abs() < 1e-3,
            "backbone {coefficient} against {c}"
        );
        checked += 1;
    }
    assert!(checked >= 3, "{checked} backbone rows checked");
    let _ = std::fs::remove_dir_all(&root);
}

/// The single-mode Galerkin backbone coefficient of a clamped-clamped beam
/// with immovable ends (length `l`, modulus `e`, moment of inertia `i`, mass
/// per length `rho_a`, section area `area`): `omega = omega_0 + c a^2` in the
/// midpoint amplitude `a` (see `readme_python_beam_example_runs`).
fn galerkin_backbone_coefficient(l: f64, e: f64, i: f64, rho_a: f64, area: f64) -> f64 {
    let bl = 4.730_040_745f64;
    let b = bl / l;
    let s = (bl.cosh() - bl.cos()) / (bl.sinh() - bl.sin());
    let phi = |x: f64| (b * x).cosh() - (b * x).cos() - s * ((b * x).sinh() - (b * x).sin());
    let dphi = |x: f64| b * ((b * x).sinh() + (b * x).sin() - s * ((b * x).cosh() - (b * x).cos()));
    let simpson = |f: &dyn Fn(f64) -> f64| {
        let n = 4000;
        let h = l / n as f64;
        let inner: f64 = (1..n)
            .map(|k| if k % 2 == 1 { 4.0 } else { 2.0 } * f(k as f64 * h))
            .sum();
        h / 3.0 * (f(0.0) + f(l) + inner)
    };
    let phi2 = simpson(&|x| phi(x) * phi(x));
    let dphi2 = simpson(&|x| dphi(x) * dphi(x));
    let w0 = b * b * (e * i / rho_a).sqrt();
    let gamma = e * area / (2.0 * l) * dphi2 * dphi2 / (rho_a * phi2);
    3.0 * gamma / (8.0 * w0 * phi(l / 2.0).powi(2))
}

/// Export never replaces a folder that is not an earlier export or result
/// set (a user's own files there stay untouched), and refuses a model the
/// files cannot hold with the reason.
#[test]
fn export_refuses_a_foreign_folder_and_a_non_polynomial_model() {
    let dir = tmp_dir("export-foreign");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    let export = |scene: &str, to: &Path| {
        Command::new(engine_binary())
            .arg("export")
            .arg(scene)
            .arg(to)
            .current_dir(repo_root())
            .output()
            .unwrap()
    };
    let o = export("zoo/spatial_oscillator_cubic.toml", &dir);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("not replaced"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.join("notes.txt")).unwrap(),
        "mine"
    );
    assert!(!dir.join("M.mtx").exists());
    let o = export("zoo/pendulum_simple_fig7_c0.1.toml", &dir.join("pendulum"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("non-polynomial terms"),
        "{err}"
    );
    assert!(!dir.join("pendulum").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
