//! The result set of a run is replaced as a whole (`OutputSet::write`):
//! stale files of an earlier scene disappear, planted links are never
//! followed, a directory that is not a result set is never replaced, a failure
//! while writing keeps the old set, and concurrent writers leave one complete
//! set. Reference: the guarantees stated in `ssm-engine/src/output/files.rs`.

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

use ssm_engine::output::{OutputSet, MARKER};
use ssm_tests::tmp_dir;

fn set(tag: &str, names: &[&str]) -> OutputSet {
    let mut s = OutputSet::default();
    for n in names {
        s.add(n, format!("{tag}:{n}"));
    }
    s
}

/// File name -> contents of `dir` (the marker left out).
fn contents(dir: &Path) -> BTreeMap<String, String> {
    fs::read_dir(dir)
        .expect("output directory")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n != MARKER)
        .map(|n| {
            let c = fs::read_to_string(dir.join(&n)).unwrap_or_default();
            (n, c)
        })
        .collect()
}

/// Entries of `parent` other than `keep` (left-over staging directories).
fn leftovers(parent: &Path, keep: &[&str]) -> Vec<String> {
    fs::read_dir(parent)
        .expect("parent")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| !keep.contains(&n.as_str()))
        .collect()
}

#[test]
fn stale_files_of_an_earlier_scene_are_gone() {
    let root = tmp_dir("outputs-stale");
    let out = root.join("out");
    set("A", &["summary.json", "frc.csv"]).write(&out).unwrap();
    set("B", &["summary.json", "spectrum.csv"])
        .write(&out)
        .unwrap();
    let c = contents(&out);
    assert_eq!(
        c.keys().collect::<Vec<_>>(),
        ["spectrum.csv", "summary.json"],
        "{c:?}"
    );
    assert!(c.values().all(|v| v.starts_with("B:")));
    assert!(out.join(MARKER).is_file());
    assert_eq!(leftovers(&root, &["out"]), Vec::<String>::new());
}

#[cfg(unix)]
#[test]
fn planted_links_are_never_followed() {
    let root = tmp_dir("outputs-links");
    let out = root.join("out");
    fs::create_dir_all(&root).unwrap();
    let victim = root.join("victim.txt");
    fs::write(&victim, "precious").unwrap();
    set("A", &["summary.json"]).write(&out).unwrap();
    // links at the old fixed temporary names and at a result name
    for name in [".summary.json.tmp", ".frc.csv.tmp", "frc.csv"] {
        std::os::unix::fs::symlink(&victim, out.join(name)).unwrap();
    }
    set("B", &["summary.json", "frc.csv"]).write(&out).unwrap();
    assert_eq!(fs::read_to_string(&victim).unwrap(), "precious");
    let c = contents(&out);
    assert_eq!(c.len(), 2, "{c:?}");
    assert!(c.values().all(|v| v.starts_with("B:")));
    assert!(!fs::symlink_metadata(out.join("frc.csv"))
        .unwrap()
        .file_type()
        .is_symlink());
    // --out itself a link: refused, the target untouched
    let elsewhere = root.join("elsewhere");
    fs::create_dir(&elsewhere).unwrap();
    fs::write(elsewhere.join("notes.txt"), "mine").unwrap();
    let link = root.join("linked-out");
    std::os::unix::fs::symlink(&elsewhere, &link).unwrap();
    let e = set("C", &["summary.json"]).write(&link).unwrap_err();
    assert!(e.to_string().contains("symbolic link"), "{e}");
    assert_eq!(contents(&elsewhere).len(), 1);
}

#[test]
fn a_directory_that_is_not_a_result_set_is_not_replaced() {
    let root = tmp_dir("outputs-foreign");
    let out = root.join("thesis");
    fs::create_dir_all(&out).unwrap();
    fs::write(out.join("chapter1.tex"), "text").unwrap();
    let e = set("A", &["summary.json"]).write(&out).unwrap_err();
    assert!(e.to_string().contains("no ssm-engine result set"), "{e}");
    assert_eq!(
        fs::read_to_string(out.join("chapter1.tex")).unwrap(),
        "text"
    );
    assert_eq!(leftovers(&root, &["thesis"]), Vec::<String>::new());
}

/// A model export (the marker, no `summary.json`) is not replaced by a
/// run's result set, nor a result set by an export: each only by its own
/// kind (before: an export folder, which may be a model folder another scene
/// reads, was replaced by any run).
#[test]
fn an_export_and_a_result_set_do_not_replace_each_other() {
    let root = tmp_dir("outputs-kinds");
    let (export, results) = (root.join("export"), root.join("results"));
    set("E", &["M.mtx", "K.mtx"]).write(&export).unwrap();
    set("R", &["summary.json", "frc.csv"])
        .write(&results)
        .unwrap();
    let e = set("R", &["summary.json"]).write(&export).unwrap_err();
    assert!(e.to_string().contains("holds a model export"), "{e}");
    let e = set("E", &["M.mtx"]).write(&results).unwrap_err();
    assert!(e.to_string().contains("holds a run's result set"), "{e}");
    assert_eq!(contents(&export)["K.mtx"], "E:K.mtx");
    assert_eq!(contents(&results)["frc.csv"], "R:frc.csv");
    // each by its own kind
    set("E2", &["M.mtx"]).write(&export).unwrap();
    set("R2", &["summary.json"]).write(&results).unwrap();
    assert_eq!(contents(&export)["M.mtx"], "E2:M.mtx");
    assert_eq!(contents(&results)["summary.json"], "R2:summary.json");
    let _ = fs::remove_dir_all(&root);
}

#[test]
fn a_failure_while_writing_keeps_the_old_set() {
    let root = tmp_dir("outputs-failure");
    let out = root.join("out");
    set("A", &["summary.json", "frc.csv"]).write(&out).unwrap();
    // the third file cannot be created (name longer than the file system allows)
    let long = "x".repeat(300);
    let e = set("B", &["summary.json", "spectrum.csv", &long])
        .write(&out)
        .unwrap_err();
    assert!(e.to_string().contains("cannot write"), "{e}");
    let c = contents(&out);
    assert_eq!(c.keys().collect::<Vec<_>>(), ["frc.csv", "summary.json"]);
    assert!(c.values().all(|v| v.starts_with("A:")));
    assert_eq!(leftovers(&root, &["out"]), Vec::<String>::new());
}

#[test]
fn concurrent_writers_leave_one_complete_set() {
    let root = tmp_dir("outputs-concurrent");
    let out = root.join("out");
    let writers: Vec<_> = [
        ("A", ["summary.json", "frc.csv"]),
        ("B", ["summary.json", "backbone.csv"]),
    ]
    .into_iter()
    .map(|(tag, names)| {
        let out = out.clone();
        std::thread::spawn(move || {
            for _ in 0..50 {
                set(tag, &names).write(&out).expect("every write succeeds");
            }
        })
    })
    .collect();
    for w in writers {
        w.join().expect("writer");
    }
    let c = contents(&out);
    assert_eq!(c.len(), 2, "{c:?}");
    let tag = &c["summary.json"][..2];
    assert!(c.values().all(|v| v.starts_with(tag)), "mixed sets: {c:?}");
    assert_eq!(leftovers(&root, &["out"]), Vec::<String>::new());
}

/// The SVG plotter (`plot::line_plot`): title, axis labels, legend
/// entries, curves and markers are drawn, on linear and log-log axes.
#[test]
fn svg_plots_have_axes_legend_and_curves() {
    let curves = vec![
        ssm_engine::plot::Curve {
            label: "O(3)".into(),
            points: (0..10).map(|i| (i as f64, (i * i) as f64)).collect(),
            ..ssm_engine::plot::Curve::default()
        },
        ssm_engine::plot::Curve {
            label: "O(5)".into(),
            points: vec![(1.0, 2.0), (f64::NAN, 1.0), (3.0, 4.0)],
            dashed: true,
            markers: vec![(3.0, 4.0)],
            color: Some(0),
            full: false,
        },
    ];
    let svg = ssm_engine::plot::line_plot(
        "backbone",
        "amplitude x1",
        "omega",
        &curves,
        ssm_engine::plot::Scale::Linear,
    )
    .unwrap();
    assert!(svg.starts_with("<svg"));
    for text in [
        "backbone",
        "amplitude x1",
        "omega",
        "O(3)",
        "O(5)",
        "polyline",
    ] {
        assert!(svg.contains(text), "missing {text}");
    }
    let log = ssm_engine::plot::line_plot(
        "error",
        "radius",
        "error",
        &curves,
        ssm_engine::plot::Scale::LogLog,
    )
    .unwrap();
    assert!(log.contains("polyline"));
    assert!(svg.contains("<circle"), "bifurcation marker");
}

/// The text elements of an SVG document: `(x, text)`.
fn svg_texts(svg: &str) -> Vec<(f64, String)> {
    svg.split("<text ")
        .skip(1)
        .filter_map(|t| {
            let x = t.split("x=\"").nth(1)?.split('"').next()?.parse().ok()?;
            let text = t.split('>').nth(1)?.split('<').next()?.trim().to_owned();
            Some((x, text))
        })
        .collect()
}

/// The defects a paper's reader sees, gone from the engine's plots: the
/// legend stands in its own column right of the axes (every legend text
/// starts beyond the plotting area, x >= 550 of 800), never over a curve;
/// a full-system curve is drawn first, pale (opacity 0.4) and thick (5 px),
/// with the reduced curve 1 px wide over it, so the two stay apart where
/// they coincide; reduced curves alone narrow by a pixel each, so a curve
/// over an earlier one leaves its edges visible; an axis through zero
/// labels its tick `0` where round-off puts it at `-5.6e-17` (a cosine
/// sampled over whole periods has such a mean).
#[test]
fn svg_plots_keep_legend_full_system_and_zero_apart() {
    use ssm_engine::plot::{line_plot, Curve, Scale};
    let t: Vec<f64> = (0..=400).map(|k| k as f64 * 0.05).collect();
    let wave = |a: f64| {
        t.iter()
            .map(|&t| (t, a * (t * 3.0).cos()))
            .collect::<Vec<_>>()
    };
    let curves = vec![
        Curve {
            label: "x1 full system".into(),
            points: wave(1.0),
            full: true,
            color: Some(0),
            ..Curve::default()
        },
        Curve {
            label: "x1 SSM O(5), a label long enough to be wrapped in the legend column".into(),
            points: wave(0.999),
            color: Some(0),
            ..Curve::default()
        },
    ];
    let svg = line_plot("validation", "t", "output", &curves, Scale::Linear).unwrap();
    let texts = svg_texts(&svg);
    for label in ["x1 full system", "x1 SSM O(5), a label long enough to"] {
        let (x, _) = texts
            .iter()
            .find(|(_, t)| t == label)
            .unwrap_or_else(|| panic!("no legend text {label:?} in {texts:?}"));
        assert!(*x >= 550.0, "{label} at x = {x}");
    }
    assert!(texts
        .iter()
        .any(|(_, t)| t == "be wrapped in the legend column"));
    assert!(
        !texts.iter().any(|(_, t)| t.contains("e-1")),
        "a round-off tick label: {texts:?}"
    );
    assert!(texts.iter().any(|(_, t)| t == "0"));
    // the full system's polyline first, pale and thick; the reduced one over it
    // the data's polylines (401 points; the mesh and the legend's samples
    // are polylines of two points)
    let curves_of = |svg: &str| -> Vec<String> {
        svg.split("<polyline")
            .skip(1)
            .filter(|l| l.split("/>").next().unwrap_or("").matches(',').count() > 100)
            .map(|l| l.chars().take(200).collect())
            .collect()
    };
    let lines = curves_of(&svg);
    assert!(lines[0].contains("opacity=\"0.4\"") && lines[0].contains("stroke-width=\"5\""));
    assert!(
        lines[1].contains("stroke-width=\"1\""),
        "{}",
        &lines[1][..200]
    );
    // reduced curves alone: 3, 2 and 1 px
    let alone: Vec<Curve> = (0..3)
        .map(|k| Curve {
            label: format!("O({})", 2 * k + 3),
            points: wave(1.0),
            ..Curve::default()
        })
        .collect();
    let svg = line_plot("backbone", "rho", "omega", &alone, Scale::Linear).unwrap();
    let widths: Vec<String> = curves_of(&svg)
        .iter()
        .filter_map(|l| {
            l.split("stroke-width=\"")
                .nth(1)?
                .split('"')
                .next()
                .map(str::to_owned)
        })
        .collect();
    assert_eq!(widths, ["3", "2", "1"]);
}

/// `backbone.svg` draws the part of a backbone beyond its accuracy target
/// differently, not just with a legend word: the Duffing oscillator's O(3)
/// backbone to `rho = 1.2` leaves the 1 % target (its estimate passes it
/// near `rho = 0.5`), so the curve is solid up to `trusted_up_to` and dashed
/// (many two-point segments) beyond, in the same colour, with a legend
/// entry of its own; to `rho = 0.2` it stays within the target and has no
/// such entry.
#[test]
fn backbone_svg_draws_the_untrusted_part_dashed() {
    let svg_of = |rho_max: f64| -> String {
        let text = format!(
            "[model]\nplugin = \"duffing\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x\"]\n\
             [outputs.backbone]\nrho_max = {rho_max}\npoints = 61\n"
        );
        let job = ssm_tests::run_scene_text(&text).expect("the Duffing scene runs");
        String::from_utf8(
            job.outputs
                .get("backbone.svg")
                .expect("backbone.svg")
                .to_vec(),
        )
        .expect("utf-8")
    };
    let dashes = |svg: &str| {
        svg.split("<polyline")
            .skip(1)
            .filter(|l| l.split("/>").next().unwrap_or("").matches(',').count() == 2)
            .count()
    };
    let far = svg_of(1.2);
    let text = ssm_tests::svg_text(&far);
    assert!(
        text.contains("O(3) beyond the accuracy target"),
        "no legend entry for the untrusted part: {text}"
    );
    let near = svg_of(0.2);
    assert!(
        !ssm_tests::svg_text(&near).contains("beyond the accuracy"),
        "a trusted backbone has no untrusted part"
    );
    // the dashes: many two-point segments beyond the legend samples
    assert!(
        dashes(&far) > dashes(&near) + 10,
        "{} against {} two-point segments",
        dashes(&far),
        dashes(&near)
    );
}
