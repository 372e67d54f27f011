//! The full-system comparisons as analyses of the registry's full-system
//! phase (`ssm_engine::analyses::{validation, reference, report}`): they
//! run once, after the order is chosen, in the plan's order, each reading
//! the results of those before it; they keep their tables, their keys of
//! `summary.json` and their files.

use std::path::Path;
use std::sync::Mutex;

use ssm_engine::analyses::{self, Phase};
use ssm_engine::pipeline::Progress;
use ssm_engine::scene::SceneFile;

/// The Duffing oscillator's forced response at two amplitudes, with the
/// order chosen by the run (at least 5: the forcing's orders); at
/// `eps = 0.002` its peak (about `eps / (2 zeta) = 0.1`) lies below the
/// amplitude of the first fold, so that the curve has no jump.
const DUFFING: &str = "[model]\nplugin = \"duffing\"\n[ssm]\ntolerance = 1e-3\n\
[outputs]\ncoordinates = [\"x\"]\n\
[forcing]\nepsilon = [0.002, 0.01]\nomega_range = [0.9, 1.3]\npoints = 60\norders = [5]\n";

/// The comparisons of every kind.
const COMPARISONS: &str =
    "[validate.steady_state]\nepsilon = 0.01\nomega_range = [1.0, 1.2]\npoints = 3\n\
[reference]\nepsilon = [0.002]\nharmonics = 5\n\
[report]\norders = [3, 5]\n";

/// Stages seen by a progress display.
#[derive(Default)]
struct Stages(Mutex<Vec<String>>);

impl Progress for Stages {
    fn stage(&self, name: &str) {
        self.0.lock().expect("stages").push(name.to_owned());
    }
}

/// Checks: the comparisons run once each, after the last SSM the run tried,
/// in the order validation, reference, report; `accuracy.measured` lists
/// the forced response's errors against the steady states (Radau IIA,
/// `[validate]`, at `eps = 0.01`) and then against the harmonic balance
/// (`[reference]`, at `eps = 0.002`), two independent full-system methods
/// that each find the O(5) curve within 2 % of the full system (the
/// measure compares amplitudes at equal frequencies, so a fold shifted by
/// a fraction of a percent in frequency reads as a large error: the
/// harmonic balance runs where the curve has none); the reference started also
/// from the forced response (its range and start taken from `[forcing]`)
/// and is drawn on `frc.svg` rather than a plot of its own; the report read
/// both (its rows measure the forced response).
#[test]
fn the_comparisons_run_once_in_plan_order_and_read_earlier_results() {
    let text = format!("{DUFFING}{COMPARISONS}");
    let scene = SceneFile::parse(Path::new("comparisons.toml"), text).expect("scene");
    let stages = Stages::default();
    let job = ssm_engine::job::run(&scene, &mut ssm_tests::registry(), &stages).expect("runs");
    ssm_tests::assert_job_summary_valid(&job, "full-system-phase");
    let stages = stages.0.into_inner().expect("stages");
    let last_ssm = stages
        .iter()
        .rposition(|s| s.starts_with("SSM to order"))
        .expect("an SSM");
    let at = |name: &str| {
        let found: Vec<usize> = stages
            .iter()
            .enumerate()
            .filter(|(_, s)| s.starts_with(name))
            .map(|(k, _)| k)
            .collect();
        assert_eq!(found.len(), 1, "{name}: {stages:?}");
        found[0]
    };
    let (v, r, p) = (
        at("full-system validation"),
        at("full-system reference"),
        at("speed-against-error report"),
    );
    assert!(last_ssm < v && v < r && r < p, "{stages:?}");

    let summary: serde_json::Value =
        serde_json::from_slice(job.outputs.get("summary.json").expect("summary")).expect("json");
    let measured = summary["accuracy"]["measured"]
        .as_array()
        .expect("measured");
    let against: Vec<&str> = measured
        .iter()
        .map(|m| m["against"].as_str().expect("against"))
        .collect();
    let first_hb = against
        .iter()
        .position(|a| *a == "harmonic_balance")
        .expect("errors against the reference");
    assert!(first_hb > 0, "{against:?}");
    assert!(against[..first_hb].iter().all(|a| *a == "steady_state"));
    assert!(against[first_hb..].iter().all(|a| *a == "harmonic_balance"));
    for m in measured {
        let e = m["relative_error"].as_f64().expect("an error");
        assert!(e < 0.02, "{m}");
    }
    assert!(job.outputs.get("reference_frc.csv").is_some());
    assert!(job.outputs.get("reference_frc.svg").is_none());
    let frc_svg = std::str::from_utf8(job.outputs.get("frc.svg").expect("frc.svg")).unwrap();
    assert!(
        ssm_tests::svg_text(frc_svg).contains("full system (harmonic balance, H = 5), eps = 0.002")
    );
    let rows = summary["report"]["rows"].as_array().expect("rows");
    assert_eq!(rows.len(), 2);
    assert!(
        rows.iter().all(|r| r["frc_error"].as_f64().is_some()),
        "{rows:?}"
    );
    for (name, key) in [
        ("validation", "validation"),
        ("reference", "reference"),
        ("report", "report"),
    ] {
        assert!(summary[key].is_object(), "{name}");
        assert_eq!(
            analyses::find(name).expect("registered").phase(),
            Phase::FullSystem
        );
    }
    assert!(summary.get("analyses").is_none());
}

/// `[analysis.<name>]` of a comparison is refused at its line, naming the
/// comparison's own table.
#[test]
fn the_comparisons_are_asked_for_with_their_own_tables() {
    for (name, own) in [
        ("validation", "validate"),
        ("reference", "reference"),
        ("report", "report"),
    ] {
        let text = format!("{DUFFING}[analysis.{name}]\nepsilon = [0.01]\n");
        let (line, msg) = ssm_tests::scene_error(&text);
        assert_eq!(line, 1 + DUFFING.lines().count(), "{msg}");
        assert!(
            msg.contains(&format!("analysis.{name}")) && msg.contains(&format!("[{own}]")),
            "{msg}"
        );
    }
}
