//! Property tests over every input surface beyond the scene keys and plugin
//! model data of `fuzz.rs`: `[reference]` and its `--resume` checkpoints,
//! `[pod]` and the `pod` reducer, `[simulate]`, `[data]` CSV files for the
//! NAR identifier, the files of a `matrix-model` folder (Matrix Market,
//! `.coo`, `outputs.csv`), the parameters of the divider, beam and
//! crank-drive plugins. Resumed checkpoints are fuzzed in
//! `fuzz_checkpoints.rs`, the output directory in `fuzz_outputs.rs`.
//!
//! The property is the one of `fuzz.rs`: every case runs in a forked
//! process with a time limit and ends in a typed error, or in finite results
//! that pass the output checks (no NaN or infinity in a CSV file; a resumed
//! reference's orbits finite, and stable exactly where their largest
//! multiplier is inside the unit circle). `SSM_FUZZ_VERBOSE=1` prints what
//! each scene case ended in. Cases per target
//! default to [`CASES`] (a fixed seed, so CI is reproducible);
//! `PROPTEST_CASES` and `PROPTEST_RNG_SEED` explore further.

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use ssm_tests::{plugin_path, run_scene_text};

use crate::fuzz::{
    apply_scene_edit, assert_finite_outputs, config_with, format_keys, scene_edit, HOSTILE_NUMBERS,
    HOSTILE_OTHER, WORK_MINUTES,
};

/// Cases per target when `PROPTEST_CASES` is not set: these runs integrate
/// and continue, so fewer than the scene target's.
pub(crate) const CASES: u32 = 32;

/// A scene text read from a file at `dir/scene.toml` (so relative paths in
/// it resolve there), run with the test registry under the fuzz work budget.
fn run_in(dir: &Path, text: &str) -> Result<ssm_engine::pipeline::JobResult, String> {
    std::env::set_var("SSM_TIME_LIMIT_MINUTES", WORK_MINUTES);
    let result = ssm_engine::scene::SceneFile::parse(&dir.join("scene.toml"), text.to_owned())
        .map_err(|e| e.to_string())
        .and_then(|scene| {
            ssm_engine::job::run(
                &scene,
                &mut ssm_tests::registry(),
                &ssm_engine::pipeline::Quiet,
            )
            .map_err(|e| e.to_string())
        });
    if std::env::var_os("SSM_FUZZ_VERBOSE").is_some() {
        match &result {
            Ok(r) => eprintln!("fuzz case: ok, {} warnings", r.warnings.len()),
            Err(e) => eprintln!(
                "fuzz case: error: {}",
                e.lines()
                    .next()
                    .unwrap_or("")
                    .chars()
                    .take(120)
                    .collect::<String>()
            ),
        }
    }
    result
}

/// A fresh directory for one forked case.
pub(crate) fn case_dir(target: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ssm-fuzz-{target}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("case directory");
    d
}

/// Scene edits restricted to the keys of the tables named (hostile values
/// for keys the scene has and for keys it could have), or any edit.
fn edit_scene(text: &str, tables: &[&str], edits: &[crate::fuzz::SceneEdit]) -> String {
    let all = format_keys();
    let mut keys: Vec<(String, String)> = all
        .iter()
        .filter(|(t, _)| tables.iter().any(|x| t == x))
        .cloned()
        .collect();
    if keys.is_empty() {
        keys = all;
    }
    edits
        .iter()
        .fold(text.to_owned(), |t, e| apply_scene_edit(&t, e, &keys))
}

/// The Duffing oscillator's forced response, reduced and full (harmonic
/// balance with 3 harmonics, Floquet multipliers, folds).
const REFERENCE_SCENE: &str = "[model]\nplugin = \"duffing\"\n[model.params]\nzeta = 0.02\n\
[ssm]\nmaster_pairs = [1]\norder = 5\n[outputs]\ncoordinates = [\"x\"]\n\
[forcing]\nepsilon = [0.01]\nomega_range = [0.9, 1.15]\n\
[reference]\nepsilon = [0.01]\nharmonics = 3\nstep = 0.5\n";

/// The cubic-constrained spatial oscillator with a short POD study (one
/// truncation, one unseen load) and the same model through the `pod`
/// reducer.
const POD_SCENE: &str =
    "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"cubic\"\n\
[outputs]\ncoordinates = [\"x1\"]\n\
[pod]\nenergy = [1e-4]\nstep = 0.02\n\
[pod.train]\nepsilon = 0.05\nomega = 2.0\nt_end = 4.0\n\
[[pod.test]]\nepsilon = 0.05\nomega = 1.9\nt_end = 4.0\n";

const POD_REDUCER_SCENE: &str = "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"cubic\"\n\
[reduce]\nreducer = \"pod\"\n[reduce.params]\nstep = 0.02\nt_end = 4.0\nepsilon = 0.05\nomega = 2.0\n\
[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs]\ncoordinates = [\"x1\"]\n\
[outputs.backbone]\nrho_max = 0.1\npoints = 11\norders = [3]\n";

/// Sampled runs of the cubic-constrained spatial oscillator.
const SIMULATE_SCENE: &str =
    "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"cubic\"\n\
[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs]\ncoordinates = [\"x1\"]\n\
[simulate]\nperiod = 0.5\nsamples = 200\noutputs = [\"x1_dot\"]\nnoise = 0.01\nseed = 3\n\
[[simulate.run]]\nx0 = { x1 = 0.1 }\n\
[[simulate.run]]\nrho0 = [0.1]\ntheta0 = [0.5]\n";

proptest! {
    #![proptest_config(config_with(CASES))]

    /// `[reference]` and `[forcing]` keys with hostile values (and the
    /// scene's other lines deleted, duplicated or cut).
    #[test]
    fn mutated_reference_scenes_end_in_a_typed_error_or_a_finite_answer(
        edits in prop::collection::vec(scene_edit(), 1..4),
    ) {
        let dir = case_dir("reference");
        let text = edit_scene(REFERENCE_SCENE, &["reference", "forcing"], &edits);
        if let Ok(result) = run_in(&dir, &text) {
            assert_finite_outputs(&result);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `[pod]`, `[pod.train]`, `[[pod.test]]` and the `pod` reducer's
    /// parameters with hostile values.
    #[test]
    fn mutated_pod_scenes_end_in_a_typed_error_or_a_finite_answer(
        reducer in any::<bool>(),
        edits in prop::collection::vec(scene_edit(), 1..4),
    ) {
        let dir = case_dir("pod");
        let (base, tables): (&str, &[&str]) = if reducer {
            (POD_REDUCER_SCENE, &["reduce.params", "reduce"])
        } else {
            (POD_SCENE, &["pod", "pod.train", "pod.test"])
        };
        let mut text = edit_scene(base, tables, &edits);
        if reducer {
            // the reducer's parameters are the plugin's, not the format's:
            // hostile values for the ones the base scene sets
            for (k, e) in edits.iter().enumerate() {
                if let crate::fuzz::SceneEdit::Value { value, .. } = e {
                    let key = ["step", "t_end", "epsilon", "omega"][k % 4];
                    text = text.replacen(
                        &format!("\n{key} = "),
                        &format!("\n{key} = {}\nx_{key} = ", HOSTILE_NUMBERS[value % HOSTILE_NUMBERS.len()]),
                        1,
                    );
                }
            }
        }
        if let Ok(result) = run_in(&dir, &text) {
            assert_finite_outputs(&result);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// `[simulate]` and `[[simulate.run]]` with hostile values.
    #[test]
    fn mutated_simulate_scenes_end_in_a_typed_error_or_a_finite_answer(
        edits in prop::collection::vec(scene_edit(), 1..4),
    ) {
        let dir = case_dir("simulate");
        let text = edit_scene(SIMULATE_SCENE, &["simulate", "simulate.run"], &edits);
        if let Ok(result) = run_in(&dir, &text) {
            assert_finite_outputs(&result);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The base scenes the targets mutate run as they are, to finite outputs
/// (so the mutations start from a working scene, not from an error).
#[test]
fn the_fuzz_base_scenes_run() {
    for (name, text) in [
        ("reference", REFERENCE_SCENE),
        ("pod", POD_SCENE),
        ("pod reducer", POD_REDUCER_SCENE),
        ("simulate", SIMULATE_SCENE),
    ] {
        let r = run_scene_text(text).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_finite_outputs(&r);
    }
    let dir = ssm_tests::tmp_dir("fuzz-bases");
    write_model_folder(&dir.join("model"));
    write_data(&dir.join("data"));
    for text in [MODEL_FOLDER_SCENE, DATA_SCENE] {
        let scene = ssm_engine::scene::SceneFile::parse(&dir.join("scene.toml"), text.to_owned())
            .expect("scene");
        let r = ssm_engine::job::run(
            &scene,
            &mut ssm_tests::registry(),
            &ssm_engine::pipeline::Quiet,
        )
        .unwrap_or_else(|e| panic!("{text}: {e}"));
        assert_finite_outputs(&r);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// One edit of a text file, or of what stands at its path.
#[derive(Debug, Clone)]
enum FileEdit {
    /// Replace the `token`-th whitespace- or comma-separated token of a line.
    Token {
        line: usize,
        token: usize,
        value: usize,
    },
    /// Delete a line.
    Delete { line: usize },
    /// Duplicate a line.
    Duplicate { line: usize },
    /// Cut the file at a byte.
    Truncate { at: usize },
    /// A word of a Matrix Market header replaced.
    Header { word: usize },
    /// A byte-order mark in front, CRLF line ends, or NUL and control bytes
    /// appended.
    Encoding { kind: usize },
    /// Something else at the path: nothing, an empty file, a directory, a
    /// link to `/dev/zero` or `/dev/null`.
    Replace { kind: usize },
}

fn file_edit() -> impl Strategy<Value = FileEdit> {
    prop_oneof![
        5 => (any::<usize>(), any::<usize>(), any::<usize>())
            .prop_map(|(line, token, value)| FileEdit::Token { line, token, value }),
        1 => any::<usize>().prop_map(|line| FileEdit::Delete { line }),
        1 => any::<usize>().prop_map(|line| FileEdit::Duplicate { line }),
        1 => any::<usize>().prop_map(|at| FileEdit::Truncate { at }),
        1 => any::<usize>().prop_map(|word| FileEdit::Header { word }),
        1 => any::<usize>().prop_map(|kind| FileEdit::Encoding { kind }),
        1 => any::<usize>().prop_map(|kind| FileEdit::Replace { kind }),
    ]
}

/// Tokens a hostile file holds.
const HOSTILE_TOKENS: [&str; 14] = [
    "nan",
    "inf",
    "-1",
    "0",
    "1e300",
    "1e-300",
    "99999999999",
    "x",
    "",
    "-0",
    "1.5",
    "3",
    "2",
    "\"1\"",
];

/// Applies `edit` to the file at `path` (which holds `text`).
fn apply_file_edit(path: &Path, edit: &FileEdit) {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let n = lines.len().max(1);
    if lines.is_empty() && !matches!(edit, FileEdit::Replace { .. } | FileEdit::Encoding { .. }) {
        return;
    }
    let new = match *edit {
        FileEdit::Token { line, token, value } => {
            if let Some(l) = lines.get_mut(line % n) {
                let mut tokens: Vec<String> = l.split([' ', ',']).map(str::to_owned).collect();
                let k = token % tokens.len();
                tokens[k] = HOSTILE_TOKENS[value % HOSTILE_TOKENS.len()].to_owned();
                *l = tokens.join(if l.contains(',') { "," } else { " " });
            }
            lines.join("\n") + "\n"
        }
        FileEdit::Delete { line } => {
            if !lines.is_empty() {
                lines.remove(line % n);
            }
            lines.join("\n") + "\n"
        }
        FileEdit::Duplicate { line } => {
            if !lines.is_empty() {
                let l = lines[line % n].clone();
                lines.insert(line % n, l);
            }
            lines.join("\n") + "\n"
        }
        FileEdit::Truncate { at } => {
            let mut cut = at % text.len().max(1);
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            text[..cut].to_owned()
        }
        FileEdit::Header { word } => {
            let swaps = [
                ("coordinate", "array"),
                ("array", "coordinate"),
                ("real", "complex"),
                ("real", "pattern"),
                ("real", "integer"),
                ("symmetric", "general"),
                ("general", "symmetric"),
                ("general", "skew-symmetric"),
                ("general", "hermitian"),
                ("%%MatrixMarket", "%%MatrixMarkt"),
            ];
            let (a, b) = swaps[word % swaps.len()];
            text.replacen(a, b, 1)
        }
        FileEdit::Encoding { kind } => match kind % 3 {
            0 => format!("\u{feff}{text}"),
            1 => text.replace('\n', "\r\n"),
            _ => format!("{text}\0\u{1}\u{1b}[31mgarbage\n"),
        },
        FileEdit::Replace { kind } => {
            let _ = std::fs::remove_file(path);
            match kind % 5 {
                0 => {}
                1 => std::fs::write(path, "").expect("empty file"),
                2 => std::fs::create_dir(path).expect("directory"),
                3 => std::os::unix::fs::symlink("/dev/zero", path).expect("link"),
                _ => std::os::unix::fs::symlink("/dev/null", path).expect("link"),
            }
            return;
        }
    };
    std::fs::write(path, new).expect("edited file");
}

/// A two-mass oscillator with a cubic spring, as a `matrix-model` folder.
fn write_model_folder(dir: &Path) {
    let files = [
        (
            "M.mtx",
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1.0\n2 2 1.0\n",
        ),
        (
            "K.mtx",
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n1 1 2.0\n2 1 -1.0\n2 2 2.0\n",
        ),
        (
            "C.mtx",
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 0.02\n2 2 0.02\n",
        ),
        ("f3.coo", "% f_1 += 0.5 x1^3\n1 1 1 1 0.5\n2 2 2 2 0.2\n"),
        (
            "fext.mtx",
            "%%MatrixMarket matrix array real general\n2 1\n1.0\n0.0\n",
        ),
        ("outputs.csv", "name,dof\nx_a,1\nx_b,2,0.5\n"),
    ];
    std::fs::create_dir_all(dir).expect("model folder");
    for (name, text) in files {
        std::fs::write(dir.join(name), text).expect("model file");
    }
}

/// The `matrix-model` folder `model` beside the scene, reduced and forced.
const MODEL_FOLDER_SCENE: &str =
    "[model]\nplugin = \"matrix-model\"\n[model.params]\ndir = \"model\"\n\
[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs]\ncoordinates = [\"x_a\"]\n\
[outputs.backbone]\nrho_max = 0.2\npoints = 11\norders = [3]\n\
[forcing]\nepsilon = [0.01]\nomega_range = [0.9, 1.1]\n";

/// The NAR identifier on `data/simulation_1.csv` beside the scene.
const DATA_SCENE: &str = "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n\
[reduce.params]\nnu = 2\norder = 3\n[data]\nfiles = [\"data/simulation_1.csv\"]\n\
[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs]\ncoordinates = [\"x1_dot\"]\n\
[outputs.backbone]\nrho_max = 0.5\npoints = 11\norders = [3]\n";

const MODEL_FILES: [&str; 6] = [
    "M.mtx",
    "K.mtx",
    "C.mtx",
    "f3.coo",
    "fext.mtx",
    "outputs.csv",
];

/// The shortest data the NAR identifier fits at order 3: 600 samples of
/// `x1'` of the Shaw-Pierre oscillator from one start, written by `[simulate]`.
fn write_data(dir: &Path) -> PathBuf {
    let scene =
        "[model]\nplugin = \"shaw-pierre\"\n[ssm]\norder = 3\n[outputs]\ncoordinates = [\"x1\"]\n\
        [simulate]\nperiod = 0.8\nsamples = 600\noutputs = [\"x1_dot\"]\n\
        [[simulate.run]]\nx0 = { x1 = 1.0, x2 = 1.0 }\n";
    let r = run_scene_text(scene).expect("data scene runs");
    r.outputs.write(dir).expect("data written");
    dir.join("simulation_1.csv")
}

proptest! {
    #![proptest_config(config_with(CASES))]

    /// The files of a `matrix-model` folder edited up to three times.
    #[test]
    fn mutated_model_folders_end_in_a_typed_error_or_a_finite_answer(
        edits in prop::collection::vec((0..MODEL_FILES.len(), file_edit()), 1..4),
    ) {
        let dir = case_dir("model-folder");
        let model = dir.join("model");
        write_model_folder(&model);
        for (file, edit) in &edits {
            apply_file_edit(&model.join(MODEL_FILES[*file]), edit);
        }
        let text = MODEL_FOLDER_SCENE;
        if let Ok(result) = run_in(&dir, text) {
            assert_finite_outputs(&result);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A `[data]` CSV file edited up to three times, identified by `nar`.
    #[test]
    fn mutated_data_files_end_in_a_typed_error_or_a_finite_answer(
        edits in prop::collection::vec(file_edit(), 1..4),
    ) {
        let dir = case_dir("data");
        let file = write_data(&dir.join("data"));
        for edit in &edits {
            apply_file_edit(&file, edit);
        }
        let text = DATA_SCENE;
        if let Ok(result) = run_in(&dir, text) {
            assert_finite_outputs(&result);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The divider's, the beam's and the crank drive's parameters with
    /// hostile values: refused, or a model whose O(3) SSM and backbone (or,
    /// for the crank drive, a short POD run) are finite.
    #[test]
    fn hostile_plugin_parameters_end_in_a_typed_error_or_a_finite_answer(
        model in 0usize..3,
        params in prop::collection::vec((any::<usize>(), any::<usize>()), 1..4),
    ) {
        let dir = case_dir("params");
        let (lib, name) = [("divider", "divider"), ("divider", "beam"), ("crank-drive", "")][model];
        let plugin = ssm_core::model::plugin::Plugin::load(&plugin_path(lib)).expect("plugin loads");
        let info = plugin.models().expect("listing");
        let spec = info
            .iter()
            .find(|m| name.is_empty() || m.name.as_str() == name)
            .expect("model listed");
        let mut table = String::new();
        for (p, v) in &params {
            let param = &spec.params[p % spec.params.len()];
            let value = if v % 3 == 0 {
                HOSTILE_OTHER[v / 3 % HOSTILE_OTHER.len()]
            } else {
                HOSTILE_NUMBERS[v / 3 % HOSTILE_NUMBERS.len()]
            };
            table.push_str(&format!("{} = {value}\n", param.name));
        }
        let path = plugin_path(lib);
        let head = format!("[model]\nplugin = \"{}\"\n", path.display());
        let model_line = if name.is_empty() { String::new() } else { format!("name = \"{name}\"\n") };
        let analysis = if lib == "crank-drive" {
            "[pod]\nstep = 1e-3\n[pod.train]\nepsilon = 1.0\nt_end = 0.05\n"
        } else {
            "[ssm]\nmaster_pairs = [1]\norder = 3\n[outputs.backbone]\nrho_max = 0.01\npoints = 5\norders = [3]\n"
        };
        let text = format!("{head}{model_line}[model.params]\n{table}{analysis}");
        if let Ok(result) = run_in(&dir, &text) {
            assert_finite_outputs(&result);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
