//! The NAR identifier (plugin `nar-identifier`) on data the engine simulates
//! from its own models through the zoo's scenes: the clamped-clamped beam
//! (the stand-in for the experiment of Szalai, Ehrhardt & Haller 2017, Sect.
//! 9b) and the spatial oscillator with its cubic path constraint (a DAE).
//!
//! Reference: the engine's model-based SSM backbones of the same models,
//! computed from their equations of motion at O(13) (an independent route: a
//! flow's SSM, not a map fitted to samples).
//!
//! Tolerance, point by point, is what the data and the two expansions leave
//! open: a one-step map perturbed by a relative `eps` (the regression's
//! relative residual, uniform weighting: noise and the map's truncation)
//! moves a multiplier's argument by up to `eps` rad, so the frequency by
//! `eps / (omega T)`; plus the error estimates of the identified and of the
//! model-based backbone. Compared where the identified backbone's own
//! estimate is below 1 %, over the amplitudes the data cover.

use std::path::PathBuf;

use serde_json::Value;
use ssm_engine::pipeline::JobResult;
use ssm_tests::{beam_data, diagnostic, repo_root, run_scene_text, tmp_dir, zoo_data};

/// `(amplitude, omega, error_estimate)` rows of a backbone.csv (one order)
/// in the output `output`.
fn curve_with_estimate(r: &JobResult, output: &str) -> Vec<(f64, f64, f64)> {
    let csv = String::from_utf8(r.outputs.get("backbone.csv").unwrap().to_vec()).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (iw, ia, ie) = (col("omega"), col(output), col("error_estimate"));
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .map(|f| {
            (
                f[ia].parse().unwrap(),
                f[iw].parse().unwrap(),
                f[ie].parse().unwrap(),
            )
        })
        .collect()
}

/// The zoo identification scene `zoo` on `files`, with the O(7) backbone of
/// master pair `pair` up to `rho_max`.
fn identify(zoo: &str, files: &[PathBuf], pair: i64, rho_max: f64) -> JobResult {
    let text = std::fs::read_to_string(repo_root().join("zoo").join(zoo)).unwrap();
    let mut scene: toml::Table = toml::from_str(&text).unwrap();
    scene["data"]["files"] = toml::Value::Array(
        files
            .iter()
            .map(|f| toml::Value::String(f.display().to_string()))
            .collect(),
    );
    scene["ssm"]["master_pairs"] = toml::Value::Array(vec![toml::Value::Integer(pair)]);
    scene["outputs"]["backbone"] =
        toml::from_str::<toml::Table>(&format!("rho_max = {rho_max:?}\npoints = 61\norders = [7]"))
            .unwrap()
            .into();
    let r = run_scene_text(&toml::to_string(&scene).unwrap()).expect("identification runs");
    ssm_tests::assert_job_summary_valid(&r, &format!("identify-{zoo}-{pair}"));
    r
}

/// What [`compare`] found.
#[derive(Debug)]
struct Comparison {
    /// Points compared.
    compared: usize,
    /// The largest relative frequency gap.
    worst: f64,
    /// The largest `|omega_ref / omega_ref(0) - 1| / tolerance` compared: how
    /// far the backbone bends beyond what the test tolerates.
    bend: f64,
}

/// Compares the identified backbone `id` with the model-based `reference`
/// in `output` over the amplitudes `window`, wherever the identified
/// estimate is below 1 %; panics at the first gap beyond the tolerance of
/// the module's header, naming `what`.
fn compare(
    id: &JobResult,
    reference: &JobResult,
    output: &str,
    window: (f64, f64),
    what: &str,
) -> Comparison {
    let identified = curve_with_estimate(id, output);
    let reference = curve_with_estimate(reference, output);
    let summary: Value = serde_json::from_slice(id.outputs.get("summary.json").unwrap()).unwrap();
    let eps = diagnostic(&summary, "relative_residual")[0];
    let period = diagnostic(&summary, "map_period")[0];
    let omega0 = reference[0].1;
    let fit_tolerance = eps / (omega0 * period);
    let mut c = Comparison {
        compared: 0,
        worst: 0.0,
        bend: 0.0,
    };
    for &(amp, omega, estimate) in &identified {
        if !(window.0..=window.1).contains(&amp) || estimate > 1e-2 {
            continue;
        }
        let k = reference
            .windows(2)
            .position(|w| w[0].0 <= amp && amp <= w[1].0)
            .unwrap_or_else(|| panic!("{what}: the model-based backbone does not reach {amp}"));
        let (a0, w0, e0) = reference[k];
        let (a1, w1, e1) = reference[k + 1];
        let omega_ref = w0 + (w1 - w0) * (amp - a0) / (a1 - a0);
        let gap = (omega - omega_ref).abs() / omega_ref;
        let tolerance = fit_tolerance + estimate + e0.max(e1);
        assert!(
            gap <= tolerance,
            "{what}, amplitude {amp:.3}: gap {gap:.2e} beyond {tolerance:.2e}"
        );
        c.compared += 1;
        c.worst = c.worst.max(gap);
        c.bend = c.bend.max((omega_ref / omega0 - 1.0).abs() / tolerance);
    }
    eprintln!("{what}: {c:?}, fit tolerance {fit_tolerance:.2e}");
    c
}

/// The largest `|value|` of the second column of a `[data]` CSV.
fn peak(file: &PathBuf) -> f64 {
    std::fs::read_to_string(file)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse::<f64>().unwrap().abs())
        .fold(0.0, f64::max)
}

/// Identified by `zoo/beam_nar.toml` (2 nu = 6, r = 3 as in the paper,
/// every second sample, floor 1 %, ridge 1e-8; the backbone of each pair in
/// turn) from the three noisy signals of `zoo/beam_data.toml` (0.1 % noise,
/// one started on the SSM of each of the first three pairs), compared over
/// 10 % to 50 % of each signal's peak. Measured gaps: 7.3e-4, 1.7e-4 and
/// 7.4e-5 of the frequency (pairs 1 to 3) against tolerances of 1.4e-2,
/// 4.5e-3 and 2.2e-3; the backbone of pair 1 bends by 5 % there, more than
/// three times its tolerance, so a wrong curvature is caught.
#[test]
fn beam_backbones_from_noisy_data_match_the_model_based_ones() {
    let files = beam_data(&tmp_dir("nar-beam"));
    for (pair, file) in (1..=3).zip(&files) {
        let p = peak(file);
        let id = identify("beam_nar.toml", &files, pair, 200.0);
        let model = run_scene_text(&format!(
            "[model]\nplugin = \"divider\"\nname = \"beam\"\n[model.params]\nn = 8\nalpha = 3.0\n\
             [ssm]\nmaster_pairs = [{pair}]\norder = 13\n[outputs]\ncoordinates = [\"w_quarter_dot\"]\n\
             [outputs.backbone]\nrho_max = 200\npoints = 201\norders = [13]\n"
        ))
        .expect("model-based backbone runs");
        let c = compare(
            &id,
            &model,
            "w_quarter_dot",
            (0.1 * p, 0.5 * p),
            &format!("beam pair {pair}"),
        );
        assert!(c.compared >= 10, "pair {pair}: {c:?}");
        if pair == 1 {
            assert!(c.bend > 3.0, "pair 1 bends too little to test: {c:?}");
        }
    }
}

/// Identified by `zoo/spatial_oscillator_nar.toml` (2 nu = 2, r = 7) from the
/// noise-free signal of `zoo/spatial_oscillator_data.toml` (x1 of the
/// oscillator with the cubic constraint, an index-3 DAE, started on the SSM
/// of the slow pair), compared over 10 % to 100 % of the signal's peak.
/// The backbone hardens by 0.9 % and then softens by 1.2 % there: its
/// non-monotone shape comes from the constraint. Measured on 42 points:
/// worst gap 1.8e-3 of the frequency near the peak, where the identified
/// backbone's own estimate approaches 1 % (the fit alone leaves 1.75e-4); the
/// bend reaches 31 times the tolerance.
#[test]
fn constrained_oscillator_backbone_from_data_matches_the_model_based_one() {
    let files = zoo_data("spatial_oscillator_data.toml", &tmp_dir("nar-spatial"), 1);
    let p = peak(&files[0]);
    let id = identify("spatial_oscillator_nar.toml", &files, 1, 0.2);
    let model = run_scene_text(
        "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"cubic\"\n\
         [ssm]\nmaster_pairs = [1]\norder = 13\nnormalization = { scale = 0.8306 }\n\
         [outputs]\ncoordinates = [\"x1\"]\n[outputs.backbone]\nrho_max = 0.4\npoints = 161\norders = [13]\n",
    )
    .expect("model-based backbone runs");
    let c = compare(&id, &model, "x1", (0.1 * p, p), "spatial oscillator");
    assert!(c.compared >= 15, "{c:?}");
    assert!(c.bend > 3.0, "the backbone bends too little to test: {c:?}");
}

/// Identified by `zoo/pendulum_chain_nar.toml` (2 nu = 2, r = 5) from the
/// signal of the slider of `zoo/pendulum_chain_data.toml` (the chain of 40
/// pendulums, 405 states, started on the O(13) SSM of the slowest pair),
/// compared over 10 % to 90 % of the signal's peak, where the backbone
/// stiffens by 0.8 %. Measured on 53 points: worst gap 4.9e-4 of the
/// frequency against a tolerance of 5.0e-4 (nearly all of it the fit's: the
/// regression leaves a relative residual of 2.5e-4 on these noise-free
/// data); the bend is 13 times the tolerance.
#[test]
fn pendulum_chain_backbone_from_data_matches_the_model_based_one() {
    let files = zoo_data("pendulum_chain_data.toml", &tmp_dir("nar-chain"), 1);
    let p = peak(&files[0]);
    let id = identify("pendulum_chain_nar.toml", &files, 1, 1.0);
    let model = run_scene_text(
        "[model]\nplugin = \"pendulum\"\nname = \"chain\"\n[spectrum]\nmethod = \"sparse\"\nmodes = 8\n\
         [ssm]\nmaster_pairs = [1]\norder = 13\n\
         [outputs]\ncoordinates = [\"x1\"]\n[outputs.backbone]\nrho_max = 30\npoints = 121\norders = [13]\n",
    )
    .expect("model-based backbone runs");
    let c = compare(&id, &model, "x1", (0.1 * p, 0.9 * p), "pendulum chain");
    assert!(c.compared >= 15, "{c:?}");
    assert!(c.bend > 3.0, "the backbone bends too little to test: {c:?}");
}
