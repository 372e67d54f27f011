//! The NAR identifier (plugin `nar-identifier`) on data the engine makes with
//! `[simulate]` from the modified Shaw-Pierre oscillator of Szalai, Ehrhardt &
//! Haller (2017), Sect. 9a: two decaying signals of `v1 = x1'` from the
//! initial conditions (9.2), 8000 samples at `T = 0.8`.
//!
//! References: the closed-form spectrum of (9.1) (Sect. 9a), the closed-form
//! small-amplitude backbone of (9.1), and the engine's model-based SSM
//! backbone of (9.1) computed from the equations of motion (an independent
//! route: a flow's SSM, not a map fitted to data).

use std::path::{Path, PathBuf};

use serde_json::Value;
use ssm_tests::{diagnostic as diag, run_scene_text, shaw_pierre_data, tmp_dir};

const C: f64 = 0.003;
const KAPPA: f64 = 0.5;

/// The identification scene on `files` with the reducer parameters `params`,
/// backbone of pair `pair` up to `rho_max` at `orders`.
fn identify(files: &[PathBuf], params: &str, order: usize, rho_max: f64) -> (Value, String) {
    identify_pair(files, params, order, rho_max, 1)
}

/// [`identify`] with the backbone of master pair `pair` (pairs ordered by
/// decay rate, slowest first).
fn identify_pair(
    files: &[PathBuf],
    params: &str,
    order: usize,
    rho_max: f64,
    pair: usize,
) -> (Value, String) {
    let r = identify_run(files, params, order, rho_max, pair);
    let summary: Value = serde_json::from_slice(r.outputs.get("summary.json").unwrap()).unwrap();
    let backbone = String::from_utf8(r.outputs.get("backbone.csv").unwrap().to_vec()).unwrap();
    (summary, backbone)
}

/// The identification run itself (every output file).
fn identify_run(
    files: &[PathBuf],
    params: &str,
    order: usize,
    rho_max: f64,
    pair: usize,
) -> ssm_engine::pipeline::JobResult {
    let list: Vec<String> = files.iter().map(|f| format!("{:?}", f)).collect();
    let scene = format!(
        "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n[reduce.params]\n{params}\n\
         [data]\nfiles = [{}]\n[ssm]\nmaster_pairs = [{pair}]\norder = {order}\n\
         [outputs]\ncoordinates = [\"x1_dot\"]\n[outputs.backbone]\nrho_max = {rho_max}\npoints = 41\norders = [{order}]\n",
        list.join(", ")
    );
    run_scene_text(&scene).expect("identification runs")
}

/// The noise-free signals of (9.2), made once for every test of this file.
fn clean_data() -> &'static [PathBuf] {
    static DATA: std::sync::OnceLock<Vec<PathBuf>> = std::sync::OnceLock::new();
    DATA.get_or_init(|| shaw_pierre_data(&tmp_dir("nar-clean"), 0.0, 1))
}

/// `(amplitude of the output, omega)` rows of `order` in a backbone.csv.
fn curve(csv: &str, order: usize) -> Vec<(f64, f64)> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let (io, iw, ia) = (
        head.iter().position(|h| *h == "order").unwrap(),
        head.iter().position(|h| *h == "omega").unwrap(),
        head.iter().position(|h| *h == "x1_dot").unwrap(),
    );
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[io].parse::<usize>().unwrap() == order)
        .map(|f| (f[ia].parse().unwrap(), f[iw].parse().unwrap()))
        .collect()
}

/// `omega` of `curve` at amplitude `amp` (linear interpolation).
fn omega_at(curve: &[(f64, f64)], amp: f64) -> Option<f64> {
    curve
        .windows(2)
        .find(|w| w[0].0 <= amp && amp <= w[1].0 && w[1].0 > w[0].0)
        .map(|w| w[0].1 + (w[1].1 - w[0].1) * (amp - w[0].0) / (w[1].0 - w[0].0))
}

/// The model-based backbone of (9.1), pair 1, in the amplitude of `x1'`.
fn model_backbone(order: usize, rho_max: f64) -> (Vec<(f64, f64)>, Option<f64>) {
    let scene = format!(
        "[model]\nplugin = \"shaw-pierre\"\n[ssm]\nmaster_pairs = [1]\norder = {order}\n\
         [outputs]\ncoordinates = [\"x1_dot\"]\n[outputs.backbone]\nrho_max = {rho_max}\npoints = 201\norders = [{order}]\n"
    );
    let r = run_scene_text(&scene).unwrap();
    let csv = String::from_utf8(r.outputs.get("backbone.csv").unwrap().to_vec()).unwrap();
    let summary: Value = serde_json::from_slice(r.outputs.get("summary.json").unwrap()).unwrap();
    let trusted = summary["accuracy"]["answers"][0]["trusted_up_to_rho"].as_f64();
    (curve(&csv, order), trusted)
}

/// Reference: Sect. 9a, `omega_1 = sqrt(k0)`, `omega_2 = sqrt(3 k0)`,
/// `zeta_1 = c / (2 sqrt(k0))`, `zeta_2 = sqrt(3) c / (2 sqrt(k0))`.
/// Noise-free data, 2 nu = 4, order 9 (truncated SVD at 1e-14), residuals
/// weighted by `1/|xi|^2` (delay vectors below 1e-5 of the largest left out):
/// frequencies to 1e-10 relative (measured 4.0e-11, 6.2e-11), damping ratios
/// to 5e-7 (measured 9.0e-9, 3.3e-7). A damping ratio of 1.5e-3 turns a multiplier
/// error `d` into `d / (zeta omega T) ~ 800 d` of itself, so the damping
/// needs the linear part 1000 times better than the frequency does. What
/// limits it is the map's truncation at the data's largest amplitude
/// (x1 = 1.15, where kappa x1^2 / k0 = 0.67), which grows like `|xi|^10`:
/// with the weighting `1/|xi|` the same fit is at least 5 times worse in
/// damping (measured 3e-6, 1.2e-5), and at order 5 the frequencies are at
/// least 10 times worse (checked below).
#[test]
fn shaw_pierre_linear_figures_from_noise_free_data() {
    let files = clean_data();
    let exact_w = [1.0, 3f64.sqrt()];
    let exact_z = [C / 2.0, 3f64.sqrt() * C / 2.0];
    let errors = |params: &str, order: usize| {
        let (s, _) = identify(files, params, order, 0.1);
        let w = diag(&s, "frequencies");
        let z = diag(&s, "damping_ratios");
        assert_eq!(w.len(), 2, "two pairs identified: {w:?}");
        let ew: Vec<f64> = (0..2)
            .map(|l| ((w[l] - exact_w[l]) / exact_w[l]).abs())
            .collect();
        let ez: Vec<f64> = (0..2)
            .map(|l| ((z[l] - exact_z[l]) / exact_z[l]).abs())
            .collect();
        let q = diag(&s, "spectral_quotients");
        (ew, ez, q)
    };
    let settings = |power: u32| {
        format!("nu = 2\norder = 9\nweighting = \"relative\"\nweight_power = {power}\nfloor = 1e-5\nrcond = 1e-14")
    };
    let (ew, ez, q) = errors(&settings(2), 9);
    eprintln!("frequencies {ew:?}, damping ratios {ez:?}");
    assert!(ew.iter().all(|e| *e < 1e-10), "frequencies: {ew:?}");
    assert!(ez.iter().all(|e| *e < 5e-7), "damping ratios: {ez:?}");
    // eq. (5.10): sigma(E_1) = Int[3 zeta_2 omega_2... ] = 3, sigma(E_2) = 0
    assert_eq!(q, vec![3.0, 0.0]);
    let (_, ez1, _) = errors(&settings(1), 9);
    assert!(
        (0..2).all(|l| ez1[l] > 5.0 * ez[l]),
        "weighting 1/|xi|: {ez1:?} against 1/|xi|^2: {ez:?}"
    );
    let (ew5, _, _) = errors("nu = 2\norder = 5", 5);
    assert!((0..2).all(|l| ew5[l] > 10.0 * ew[l]), "{ew5:?}");
}

/// Reference: the backbone of the same identified map (order 7, relative
/// weighting) at O(17), used where it has converged: where its own error
/// estimate is below a tenth of the error measured. The error estimate of a
/// map's backbone (the invariance residual of (5.8), `B W(R(p)) - A W(p) -
/// F(W(p))`, projected on the master pair and read in `log mu`) must never
/// understate the truncation error of orders 3, 5 and 7 and overstate it at
/// most 50-fold (measured: 2.9-3.4, 18-34 and 4.3-5.9 fold; O(9) is too
/// close to the reference to be measured against it).
#[test]
fn map_backbone_error_estimate_tracks_the_truncation_error() {
    let list: Vec<String> = clean_data().iter().map(|f| format!("{f:?}")).collect();
    let scene = format!(
        "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n[reduce.params]\n\
         nu = 2\norder = 7\nweighting = \"relative\"\nfloor = 1e-5\n\
         [data]\nfiles = [{}]\n[ssm]\nmaster_pairs = [1]\norder = 17\n\
         [outputs]\ncoordinates = [\"x1_dot\"]\n[outputs.backbone]\nrho_max = 0.6\npoints = 13\norders = [3, 5, 7, 17]\n",
        list.join(", ")
    );
    let r = run_scene_text(&scene).expect("identification runs");
    let csv = String::from_utf8(r.outputs.get("backbone.csv").unwrap().to_vec()).unwrap();
    // (order, omega, error_estimate) per row, rows of one order in rho order
    let rows: Vec<(usize, f64, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let estimate = f[f.len() - 1].parse().expect("maps have error estimates");
            (f[0].parse().unwrap(), f[2].parse().unwrap(), estimate)
        })
        .collect();
    let of = |order: usize| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.0 == order)
            .map(|r| (r.1, r.2))
            .collect()
    };
    let reference = of(17);
    assert_eq!(reference.len(), 13);
    for order in [3, 5, 7] {
        let mut compared = 0;
        for ((omega, estimate), (omega_ref, estimate_ref)) in of(order).into_iter().zip(&reference)
        {
            let truth = (omega - omega_ref).abs() / omega_ref;
            if truth < 1e-9 || *estimate_ref > 0.1 * truth {
                continue;
            }
            compared += 1;
            let ratio = estimate / truth;
            assert!(
                (1.0..=50.0).contains(&ratio),
                "O({order}): estimate {estimate:.2e} against {truth:.2e}"
            );
        }
        assert!(compared >= 4, "O({order}): {compared} points compared");
    }
}

/// Reference: the engine's model-based SSM backbone of (9.1) (pair 1, O(7),
/// amplitude of x1'), over the amplitudes where its own error estimate meets
/// 1 %: the backbone of the identified map (2 nu = 4, order 5 and 7) agrees
/// within 1 % of the frequency at order 5 (measured 3.8e-3) and 3e-3 at
/// order 7 (measured 2.0e-3), and the order-7 fit is closer than the
/// order-5 one. At small amplitude both follow the closed form of Sect. 9a,
/// `omega = omega_d + 3 kappa A^2 / 16` (A the amplitude of x1, which equals
/// that of x1' to leading order), at A <= 0.1 (the shift measured from the
/// identified map's own linear frequency): to 5 % of the shift at order 5
/// (measured 4.4 %) and 1 % at order 7; the map's truncation at the data's
/// largest amplitudes biases its cubic term, less at higher order.
#[test]
fn shaw_pierre_backbone_from_data_matches_the_model_based_one() {
    let files = clean_data();
    let (model, trusted) = model_backbone(7, 0.8);
    let rho_ok = trusted.unwrap_or(0.8);
    let amp_max = model
        .iter()
        .enumerate()
        .filter(|(k, _)| (*k as f64) * 0.8 / 200.0 <= rho_ok)
        .map(|(_, p)| p.0)
        .fold(0.0, f64::max);
    assert!(amp_max > 0.5, "model-based backbone trusted to {amp_max}");
    let mut worst_by_order = Vec::new();
    for (order, closed_tol, gap_tol) in [(5usize, 0.05, 1e-2), (7, 0.01, 3e-3)] {
        let params = format!("nu = 2\norder = {order}\nweighting = \"relative\"\nfloor = 1e-8");
        let (_, csv) = identify(files, &params, order, 0.8);
        let id = curve(&csv, order);
        let mut worst = 0.0f64;
        let mut compared = 0;
        for &(amp, w) in id.iter().filter(|p| p.0 > 0.0 && p.0 <= amp_max) {
            let wm = omega_at(&model, amp).unwrap();
            worst = worst.max(((w - wm) / wm).abs());
            compared += 1;
        }
        eprintln!("order {order}: worst relative gap {worst:.2e} over {compared} points");
        assert!(compared >= 5, "order {order}: {compared} points compared");
        assert!(worst < gap_tol, "order {order}: worst relative gap {worst}");
        // the small-amplitude closed form, from the identified linear frequency
        let w_d = id[0].1;
        assert!((w_d - (1.0 - C * C / 4.0).sqrt()).abs() < 1e-4, "{w_d}");
        let small = id.iter().filter(|p| p.0 > 0.0 && p.0 <= 0.1).count();
        assert!(small >= 3, "order {order}: {small} points at A <= 0.1");
        for &(amp, w) in id.iter().filter(|p| p.0 > 0.0 && p.0 <= 0.1) {
            let shift = w - w_d;
            let closed = 3.0 * KAPPA * amp * amp / 16.0;
            assert!(
                ((shift - closed) / closed).abs() < closed_tol,
                "order {order}, A = {amp}: shift {shift} against {closed}"
            );
        }
        worst_by_order.push(worst);
    }
    assert!(
        worst_by_order[1] < worst_by_order[0],
        "order 7 ({}) is not closer than order 5 ({})",
        worst_by_order[1],
        worst_by_order[0]
    );
}

/// Noise of 0.1 %, 1 % and 5 % of the signals' largest value (seeded): the
/// identification (uniform weighting, delay vectors below ten times the
/// noise left out, ridge 1e-8, order 5) stays stable; the first pair's
/// linear frequency is within 1e-3 of the closed form at 0.1 % noise and
/// within 50 % at 5 %; the backbone's gap to the model-based one is
/// reported (measured 6e-4, 3.3e-2, 6.8e-2), below 1 % at 0.1 % noise, and
/// grows with the noise no faster than its square (the order of the bias
/// that noise in the regressors gives a least-squares fit).
#[test]
fn shaw_pierre_backbone_degrades_smoothly_with_noise() {
    let (model, _) = model_backbone(7, 0.5);
    let mut gaps = Vec::new();
    for (level, seed) in [(0.001, 11u64), (0.01, 12), (0.05, 13)] {
        let dir = tmp_dir(&format!("nar-noise-{seed}"));
        let files = shaw_pierre_data(&dir, level, seed);
        let params = format!("nu = 2\norder = 5\nfloor = {}\nridge = 1e-8", 10.0 * level);
        let (mut s, mut csv) = identify(&files, &params, 5, 0.5);
        let w = diag(&s, "frequencies");
        // noise adds damping, most to the first mode, which may then no
        // longer be the slowest pair: take the pair near omega_1
        let mu = &s["master_modes"][0]["lambda"];
        let w_master = mu["im"].as_f64().unwrap().atan2(mu["re"].as_f64().unwrap()) / 0.8;
        if (w_master - 1.0).abs() > 0.3 {
            (s, csv) = identify_pair(&files, &params, 5, 0.5, 2);
        }
        let tol = if level < 0.005 { 1e-3 } else { 0.5 };
        assert!(
            (w[0] - 1.0).abs() < tol,
            "noise {level}: omega_1 = {}",
            w[0]
        );
        let id = curve(&csv, 5);
        let mut worst = 0.0f64;
        let mut compared = 0;
        for &(amp, w) in id.iter().filter(|p| p.0 > 0.0 && p.0 <= 0.4) {
            let wm = omega_at(&model, amp).unwrap();
            worst = worst.max(((w - wm) / wm).abs());
            compared += 1;
        }
        assert!(compared >= 5, "noise {level}: {compared} points compared");
        assert!(worst.is_finite());
        eprintln!(
            "noise {level}: backbone gap {worst:.3e}, residual {:?}",
            diag(&s, "relative_residual")
        );
        gaps.push(worst);
    }
    assert!(gaps[0] < 0.01, "{gaps:?}");
    // errors in the regressors bias a least-squares fit by O(sigma^2): the
    // gap grows, but no faster than the square of the noise level
    let levels = [0.001f64, 0.01, 0.05];
    for k in 1..gaps.len() {
        let bound = 1.2 * (levels[k] / levels[k - 1]).powi(2);
        assert!(
            gaps[k] > gaps[k - 1] && gaps[k] < bound * gaps[k - 1],
            "{gaps:?}"
        );
    }
}

/// Bad data end in typed errors naming the file (and line) and the problem:
/// NaN and Inf values, non-uniform sampling and a missing column (the
/// engine's [data] reader), a signal shorter than one delay vector and its
/// successor, fewer rows than unknowns, a rank-deficient regression, an
/// unstable identified map, two observables where one is needed, too many
/// unknowns, a regression too large to hold, and settings out of range.
#[test]
fn bad_data_gives_clear_errors() {
    let dir = tmp_dir("nar-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let run = |name: &str, text: &str, params: &str, columns: &str| -> String {
        let f = dir.join(name);
        std::fs::write(&f, text).unwrap();
        let scene = format!(
            "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n[reduce.params]\n{params}\n\
             [data]\nfiles = [{:?}]\n{columns}\n[ssm]\norder = 3\n",
            f
        );
        match run_scene_text(&scene) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("{name}: the scene ran"),
        }
    };
    let decay = |n: usize, a: f64| -> String {
        let mut s = String::from("t,v\n");
        for k in 0..n {
            let t = k as f64 * 0.5;
            s.push_str(&format!(
                "{t},{}\n",
                a * (-0.05 * t).exp() * (1.3 * t).cos()
                    + 0.1 * a * a * (-0.1 * t).exp() * (2.6 * t).sin()
            ));
        }
        s
    };
    let mut text = decay(50, 1.0);
    text = text.replacen("\n1,", "\n1,NaN\n#", 1);
    let e = run("nan.csv", &text.replace("#", ""), "nu = 1", "");
    assert!(e.contains("nan.csv") && e.contains("line 4"), "{e}");
    let e = run("inf.csv", "t,v\n0,1\n0.5,inf\n1,0.2\n", "nu = 1", "");
    assert!(
        e.contains("inf.csv, line 3") && e.contains("not finite"),
        "{e}"
    );
    let e = run(
        "nonuniform.csv",
        "t,v\n0,1\n0.5,0.5\n1.1,0.2\n1.5,0.1\n",
        "nu = 1",
        "",
    );
    assert!(e.contains("nonuniform.csv") && e.contains("uniform"), "{e}");
    let e = run("column.csv", &decay(50, 1.0), "nu = 1", "columns = [\"w\"]");
    assert!(
        e.contains("column.csv") && e.contains("no column 'w'"),
        "{e}"
    );
    let e = run("short.csv", &decay(4, 1.0), "nu = 2", "");
    assert!(e.contains("short.csv") && e.contains("at least 5"), "{e}");
    let e = run("few.csv", &decay(30, 1.0), "nu = 2\norder = 3", "");
    assert!(
        e.contains("regression rows") && e.contains("34 unknowns"),
        "{e}"
    );
    let e = run(
        "constant.csv",
        &"t,v\n"
            .chars()
            .chain((0..100).flat_map(|k| {
                format!("{},0.3\n", k as f64 * 0.5)
                    .chars()
                    .collect::<Vec<_>>()
            }))
            .collect::<String>(),
        "nu = 1\norder = 3",
        "",
    );
    assert!(e.contains("rank-deficient") && e.contains("ridge"), "{e}");
    let mut grow = String::from("t,v\n");
    for k in 0..200 {
        let t = k as f64 * 0.5;
        grow.push_str(&format!(
            "{t},{}\n",
            1e-3 * (0.02 * t).exp() * (1.3 * t).cos()
        ));
    }
    let e = run("growing.csv", &grow, "nu = 1\norder = 1", "");
    assert!(
        e.contains("unstable identified map") && e.contains("|mu|"),
        "{e}"
    );
    let e = run(
        "two.csv",
        "t,a,b\n0,1,2\n0.5,0.5,1\n1,0.2,0.4\n",
        "nu = 1",
        "",
    );
    assert!(
        e.contains("one scalar observable") && e.contains("a, b"),
        "{e}"
    );
    // too many unknowns, and a regression too large to hold
    let e = run("big.csv", &decay(8000, 1.0), "nu = 16\norder = 3", "");
    assert!(e.contains("unknowns") && e.contains("at most 5000"), "{e}");
    let e = run("big2.csv", &decay(250_000, 1.0), "nu = 4\norder = 5", "");
    assert!(e.contains("GB") && e.contains("decimate"), "{e}");
    // settings out of range name the setting
    for (params, key) in [
        ("nu = 0", "nu"),
        ("order = 26", "order"),
        ("floor = 1.5", "floor"),
        ("ridge = -1e-3", "ridge"),
        ("rcond = nan", "rcond"),
        ("weight_power = 0", "weight_power"),
        ("weight_power = 5", "weight_power"),
        ("decimate = 0", "decimate"),
    ] {
        let e = run("settings.csv", &decay(200, 1.0), params, "");
        assert!(
            e.contains(key) && (e.contains("must be") || e.contains("finite")),
            "{params}: {e}"
        );
    }
}

/// The two zoo scenes as the README runs them, through the binary: the data
/// scene writes the signals where the identification scene reads them
/// (`../out/shaw_pierre_data` from `zoo/`, here inside a scratch copy), and
/// the identified first pair has the closed-form frequency of Sect. 9a,
/// `omega_1 = sqrt(k0) = 1`, to 1e-5 with `sigma(E_1) = 3`; the map written
/// to `identified.json` predicts the data one step ahead.
#[test]
fn zoo_scenes_identify_the_first_pair() {
    let root = tmp_dir("nar-zoo");
    let zoo = root.join("zoo");
    std::fs::create_dir_all(&zoo).unwrap();
    let repo = ssm_tests::repo_root();
    let run = |scene: &Path, out: &Path| {
        let o = std::process::Command::new(ssm_tests::engine_binary())
            .arg(scene)
            .arg("--out")
            .arg(out)
            .env("CI", "1")
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        ssm_tests::assert_summary_valid(&out.join("summary.json"));
    };
    run(
        &repo.join("zoo/shaw_pierre_data.toml"),
        &root.join("out/shaw_pierre_data"),
    );
    let nar = zoo.join("shaw_pierre_nar.toml");
    std::fs::copy(repo.join("zoo/shaw_pierre_nar.toml"), &nar).unwrap();
    run(&nar, &root.join("out/nar"));
    let s: Value =
        serde_json::from_slice(&std::fs::read(root.join("out/nar/summary.json")).unwrap()).unwrap();
    let w = diag(&s, "frequencies");
    assert!((w[0] - 1.0).abs() < 1e-5, "{w:?}");
    assert_eq!(diag(&s, "spectral_quotients")[0], 3.0);
    assert!(root.join("out/nar/backbone.svg").exists());
    // identified.json holds the fitted map: its one-step predictions of the
    // first signal match the next samples to 1e-4 of the signal's peak
    let id: Value =
        serde_json::from_slice(&std::fs::read(root.join("out/nar/identified.json")).unwrap())
            .unwrap();
    assert_eq!(id["map_period"].as_f64(), Some(0.8));
    let states: Vec<String> = id["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_owned())
        .collect();
    assert_eq!(states.len(), 4);
    let last_row: Vec<f64> = id["linear_part"][3]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let y: Vec<f64> = std::fs::read_to_string(root.join("out/shaw_pierre_data/simulation_1.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse().unwrap())
        .collect();
    let peak = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut worst = 0.0f64;
    for k in (0..y.len() - 4).step_by(97) {
        let xi = &y[k..k + 4];
        let mut next: f64 = (0..4).map(|j| last_row[j] * xi[j]).sum();
        for t in id["nonlinear_terms"].as_array().unwrap() {
            assert_eq!(t["equation"].as_str(), Some(states[3].as_str()));
            let mut m = t["coefficient"].as_f64().unwrap();
            for (name, p) in t["monomial"].as_object().unwrap() {
                let j = states.iter().position(|s| s == name).unwrap();
                m *= xi[j].powi(p.as_i64().unwrap() as i32);
            }
            next += m;
        }
        worst = worst.max((next - y[k + 4]).abs() / peak);
    }
    assert!(
        worst < 1e-4,
        "one-step prediction error {worst:.2e} of the peak"
    );
}

/// Fig. 4's independent backbones: the zero-crossing and Hilbert backbones
/// read off the first decaying signal (`data_backbone.csv`, drawn into
/// `backbone.svg`) agree with the engine's model-based O(7) SSM backbone of
/// (9.1) within 7e-3 of the frequency at amplitudes 0.05 to 0.3 of x1'
/// (measured 4.7e-3; above, the second mode's decaying remainder in a signal
/// started in the linear modal subspace makes them oscillate by up to 2 %).
/// The second signal's points near omega_2 are left out of the overlay.
#[test]
fn data_backbones_match_the_model_based_one() {
    let files = clean_data();
    let (model, _) = model_backbone(7, 0.5);
    let r = identify_run(files, "nu = 2\norder = 5", 5, 0.5, 1);
    let csv = String::from_utf8(r.outputs.get("data_backbone.csv").unwrap().to_vec()).unwrap();
    let mut checked = [0usize; 2];
    let mut worst = 0.0f64;
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (amp, w): (f64, f64) = (f[2].parse().unwrap(), f[3].parse().unwrap());
        assert!((w - 1.0).abs() < 0.25, "{line}: a point far from omega_1");
        if f[1].ends_with("simulation_1.csv") && (0.05..=0.3).contains(&amp) {
            let wm = omega_at(&model, amp).unwrap();
            worst = worst.max(((w - wm) / wm).abs());
            assert!(((w - wm) / wm).abs() < 7e-3, "{line}: model {wm}");
            checked[usize::from(f[0] == "hilbert")] += 1;
        }
    }
    eprintln!("data backbones: worst relative gap {worst:.2e}");
    assert!(checked[0] > 100 && checked[1] > 100, "{checked:?}");
    let svg = String::from_utf8(r.outputs.get("backbone.svg").unwrap().to_vec()).unwrap();
    assert!(svg.contains("zero crossings of simulation_1.csv") && svg.contains("hilbert of"));
}

/// Issue 38: `rcond = 0.999999` on the noise-free data kept one singular
/// value, left 69 % of the data unexplained and reported damping ratios
/// 0.64 and 0.30 (true 0.0015, 0.0026) with success. Now `rcond` beyond
/// 0.1 (the plugin's `RCOND_MAX`) is refused at the setting, and a
/// truncation (rcond = 0.1) or a ridge (0.5) inside the range that
/// discards signal is refused naming its setting: the relative residual of
/// the regularized fit must stay within the least-squares fit's (the data's
/// noise level, here the map's truncation) or 1e-6 (light truncations,
/// rcond = 1e-14, still fit: `shaw_pierre_linear_figures_from_noise_free_data`).
#[test]
fn a_regularization_that_discards_the_signal_is_refused() {
    let files = clean_data();
    let base = "nu = 2\norder = 7\nweighting = \"relative\"\nfloor = 1e-5";
    let list: Vec<String> = files.iter().map(|f| format!("{f:?}")).collect();
    let run = |extra: &str| {
        let scene = format!(
            "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n[reduce.params]\n{base}\n{extra}\n\
             [data]\nfiles = [{}]\n[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs]\ncoordinates = [\"x1_dot\"]\n",
            list.join(", ")
        );
        run_scene_text(&scene)
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let e = run("rcond = 0.999999").unwrap_err();
    assert!(
        e.contains("rcond") && e.contains("must be in [0, 0.1]"),
        "{e}"
    );
    let e = run("rcond = 0.1").unwrap_err();
    assert!(
        e.contains("rcond") && (e.contains("linear part") || e.contains("unexplained")),
        "{e}"
    );
    let e = run("ridge = 0.5").unwrap_err();
    assert!(
        e.contains("unexplained") && e.contains("lower ridge"),
        "{e}"
    );
}
