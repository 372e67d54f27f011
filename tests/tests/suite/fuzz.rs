//! Property tests over hostile input (issue "Trustworthy under any input"):
//! scenes mutated from the zoo and plugin model data mutated from real
//! plugins. Every case runs in a forked process with a time limit, so a panic,
//! an abort (out of memory, stack overflow) or a hang fails the property, not
//! the test binary. The property: the run ends in `Ok` or a typed error, and
//! an `Ok` run writes no NaN or infinity into a CSV file. The other input
//! surfaces are in `fuzz_inputs.rs` (reference, POD, data files, model
//! folders, plugin parameters), `fuzz_checkpoints.rs` (resumed checkpoints)
//! and `fuzz_outputs.rs` (output directories).
//!
//! The number of cases is proptest's `PROPTEST_CASES` (default below), the
//! seed fixed unless `PROPTEST_RNG_SEED` is set (so CI is reproducible and a
//! longer local run, e.g. `PROPTEST_CASES=3000 PROPTEST_RNG_SEED=7`, explores
//! further); the
//! estimated work of a run is capped at a few seconds through
//! `SSM_TIME_LIMIT_MINUTES`, so CI time stays bounded. Failing inputs that
//! proptest shrinks are not persisted (`failure_persistence: None`: CI runs a
//! clean clone); each failure found is kept as a named regression test in
//! `robustness.rs` or `limits.rs`.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use ssm_api::{ExprOp, Model};
use ssm_core::model::plugin::Plugin;
use ssm_core::model::system::System;
use ssm_core::spectrum::Normalization;
use ssm_core::spectrum::{self, Method};
use ssm_core::ssm as ssm_mod;
use ssm_tests::{plugin_path, repo_root, run_scene_text};

/// The seed when `PROPTEST_RNG_SEED` is not set.
const SEED: u64 = 20_261_123;
/// Cases per property when `PROPTEST_CASES` is not set.
const CASES: u32 = 256;
/// Milliseconds a single case may take (forked) before it counts as a hang:
/// twice the slowest legitimate case. That is a chain scaled to 41,000
/// pendulums (409,995 states), built and its spectrum computed before an
/// order it cannot afford is refused: 12.7 s alone on the 2-core CI
/// machine, two thirds of it the kernel zeroing fresh pages, and 15.2 s
/// beside the suite's other tests (where the order could fit no model, it is
/// now refused before the build:
/// `cost_gate::an_order_that_fits_no_model_is_refused_before_the_model_is_built`).
const CASE_TIMEOUT_MS: u32 = 30_000;
/// The work budget of one run in minutes (the engine refuses larger requests).
pub(crate) const WORK_MINUTES: &str = "0.05";

fn config() -> Config {
    config_with(CASES)
}

/// The shared configuration with `cases` cases unless `PROPTEST_CASES` is set.
pub(crate) fn config_with(cases: u32) -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(cases);
    // a fixed seed keeps CI reproducible; PROPTEST_RNG_SEED explores others
    let rng_seed = if std::env::var_os("PROPTEST_RNG_SEED").is_some() {
        Config::default().rng_seed
    } else {
        RngSeed::Fixed(SEED)
    };
    Config {
        cases,
        rng_seed,
        fork: true,
        timeout: CASE_TIMEOUT_MS,
        failure_persistence: None,
        ..Config::default()
    }
}

/// Numbers a hostile user types.
pub(crate) const HOSTILE_NUMBERS: [&str; 16] = [
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "0.0",
    "1e300",
    "1e-300",
    "-1e-300",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "3",
    "1000000",
    "0.5",
    "1e-9",
];

/// Lists a hostile user types.
const HOSTILE_LISTS: [&str; 8] = [
    "[]",
    "[nan]",
    "[0, 0]",
    "[1e300, -1e300]",
    "[1, 2, 3, 4, 5, 6, 7]",
    "[0.9, 1.1]",
    "[-1]",
    "[1.1, 0.9]",
];

/// Anything else.
pub(crate) const HOSTILE_OTHER: [&str; 6] =
    ["\"\"", "\"dense\"", "{}", "true", "\"x\"", "{ scale = -1 }"];

/// A hostile value of the same kind as `old` three times in four, else of
/// any kind.
pub(crate) fn hostile_value(old: &str, pick: usize) -> &'static str {
    let old = old.trim();
    let same: &[&str] = if old.starts_with('[') {
        &HOSTILE_LISTS
    } else if old.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+' || c == '.') {
        &HOSTILE_NUMBERS
    } else {
        &HOSTILE_OTHER
    };
    let any = [&HOSTILE_NUMBERS[..], &HOSTILE_LISTS[..], &HOSTILE_OTHER[..]].concat();
    if pick.is_multiple_of(4) {
        any[(pick / 4) % any.len()]
    } else {
        same[(pick / 4) % same.len()]
    }
}

/// Floating-point values for model data.
const HOSTILE_F64: [f64; 12] = [
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    0.0,
    -1.0,
    1e300,
    1e-300,
    f64::MIN_POSITIVE,
    f64::MAX,
    1.0,
    0.5,
    -2.0,
];

const BASE_SCENES: [&str; 5] = [
    "spatial_oscillator_cubic",
    "spatial_oscillator_none",
    "pendulum_simple_fig7_c0.1",
    "pendulum_slider_fig11",
    "pendulum_chain_fig13",
];

/// Every `[table] key` the scene format knows, read from its one source.
pub(crate) fn format_keys() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(repo_root().join("ssm-engine/src/scene/format.toml"))
        .expect("format.toml");
    let mut table = String::new();
    let mut keys = Vec::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with('[') {
            table = line.trim_matches(|c| c == '[' || c == ']').to_owned();
        } else if let Some((k, _)) = line.split_once('=') {
            if !line.starts_with('#') {
                keys.push((table.clone(), k.trim().to_owned()));
            }
        }
    }
    keys
}

/// One edit of a scene's text; the numbers pick lines, keys and values.
#[derive(Debug, Clone)]
pub(crate) enum SceneEdit {
    /// Replace the value of the `line`-th `key = value` line.
    Value { line: usize, value: usize },
    /// Delete a line.
    Delete { line: usize },
    /// Duplicate a line.
    Duplicate { line: usize },
    /// Add a known key with a hostile value under its table.
    Insert { key: usize, value: usize },
    /// Cut the text at a byte.
    Truncate { at: usize },
    /// Scale the number (or each number of the list) of the `line`-th
    /// numeric `key = value` line by one of [`SCALES`], keeping its type: a
    /// well-formed scene whose sizes and tolerances a user got wrong, which
    /// reaches the numerics where a syntax error would stop at the parser.
    Scale { line: usize, factor: usize },
}

/// Factors of [`SceneEdit::Scale`]: zero, tiny and huge, sign flips, and
/// the near misses of a plausible value.
pub(crate) const SCALES: [f64; 12] = [
    0.0, 1e-12, 1e-3, 0.1, 0.5, 0.9, 1.1, 2.0, 10.0, 1e3, 1e12, -1.0,
];

/// `value` (a TOML number or list of numbers) times `factor`, integers kept
/// integers; `None` when it is not numeric.
fn scaled(value: &str, factor: f64) -> Option<String> {
    let one = |v: &str| -> Option<String> {
        let v = v.trim();
        if let Ok(i) = v.parse::<i64>() {
            return Some(format!("{}", (i as f64 * factor).round() as i64));
        }
        let x = v.parse::<f64>().ok()?;
        Some(format!("{:e}", x * factor))
    };
    let value = value.trim();
    if let Some(inner) = value.strip_prefix('[').and_then(|v| v.strip_suffix(']')) {
        let items: Option<Vec<String>> = inner
            .split(',')
            .filter(|v| !v.trim().is_empty())
            .map(one)
            .collect();
        return items.map(|i| format!("[{}]", i.join(", ")));
    }
    one(value)
}

pub(crate) fn scene_edit() -> impl Strategy<Value = SceneEdit> {
    prop_oneof![
        4 => (any::<usize>(), any::<usize>()).prop_map(|(line, value)| SceneEdit::Value { line, value }),
        1 => any::<usize>().prop_map(|line| SceneEdit::Delete { line }),
        1 => any::<usize>().prop_map(|line| SceneEdit::Duplicate { line }),
        3 => (any::<usize>(), any::<usize>()).prop_map(|(key, value)| SceneEdit::Insert { key, value }),
        1 => any::<usize>().prop_map(|at| SceneEdit::Truncate { at }),
        5 => (any::<usize>(), any::<usize>()).prop_map(|(line, factor)| SceneEdit::Scale { line, factor }),
    ]
}

pub(crate) fn apply_scene_edit(text: &str, edit: &SceneEdit, keys: &[(String, String)]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let n = lines.len().max(1);
    match *edit {
        SceneEdit::Value { line, value } => {
            let assignments: Vec<usize> = (0..lines.len())
                .filter(|&i| !lines[i].trim_start().starts_with('#') && lines[i].contains('='))
                .collect();
            if let Some(&i) = assignments.get(line % assignments.len().max(1)) {
                let (key, old) = lines[i].split_once('=').unwrap_or(("", ""));
                lines[i] = format!("{key}= {}", hostile_value(old, value));
            }
        }
        SceneEdit::Delete { line } => {
            if !lines.is_empty() {
                lines.remove(line % n);
            }
        }
        SceneEdit::Duplicate { line } => {
            if !lines.is_empty() {
                let l = lines[line % n].clone();
                lines.insert(line % n, l);
            }
        }
        SceneEdit::Insert { key, value } => {
            // under the table's header when the scene has it (a second
            // header would only be a duplicate-table error), replacing the
            // key's value when the table has it
            let (table, k) = &keys[key % keys.len()];
            let header = format!("[{table}]");
            let line = format!("{k} = {}", hostile_value("0", value));
            match lines.iter().position(|l| l.trim() == header) {
                Some(h) => {
                    let end = (h + 1..lines.len())
                        .find(|&i| lines[i].trim_start().starts_with('['))
                        .unwrap_or(lines.len());
                    let existing = (h + 1..end)
                        .find(|&i| lines[i].split_once('=').is_some_and(|(x, _)| x.trim() == k));
                    match existing {
                        Some(i) => {
                            let old = lines[i].split_once('=').map_or("", |(_, v)| v).to_owned();
                            lines[i] = format!("{k} = {}", hostile_value(&old, value));
                        }
                        None => lines.insert(h + 1, line),
                    }
                }
                None => {
                    lines.push(header);
                    lines.push(line);
                }
            }
        }
        SceneEdit::Scale { line, factor } => {
            let factor = SCALES[factor % SCALES.len()];
            let numeric: Vec<(usize, String)> = (0..lines.len())
                .filter(|&i| !lines[i].trim_start().starts_with('#'))
                .filter_map(|i| {
                    let (key, old) = lines[i].split_once('=')?;
                    Some((i, format!("{key}= {}", scaled(old, factor)?)))
                })
                .collect();
            if let Some((i, new)) = numeric.get(line % numeric.len().max(1)) {
                lines[*i] = new.clone();
            }
        }
        SceneEdit::Truncate { at } => {
            let mut cut = at % text.len().max(1);
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_owned();
        }
    }
    lines.join("\n") + "\n"
}

/// A run that succeeded wrote finite numbers only.
pub(crate) fn assert_finite_outputs(result: &ssm_engine::pipeline::JobResult) {
    for (name, bytes) in &result.outputs.files {
        if !name.ends_with(".csv") {
            continue;
        }
        let text = String::from_utf8_lossy(bytes);
        for line in text.lines().skip(1) {
            for field in line.split(',') {
                let v = field.trim().parse::<f64>();
                assert!(
                    v.map_or(true, f64::is_finite),
                    "{name} holds {field}: {line}"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(config())]

    /// Zoo scenes with up to three hostile edits end in a typed error or a
    /// finite answer.
    #[test]
    fn mutated_scenes_end_in_a_typed_error_or_a_finite_answer(
        base in 0..BASE_SCENES.len(),
        edits in prop::collection::vec(scene_edit(), 1..4),
    ) {
        std::env::set_var("SSM_TIME_LIMIT_MINUTES", WORK_MINUTES);
        let path = repo_root().join("zoo").join(format!("{}.toml", BASE_SCENES[base]));
        let keys = format_keys();
        let mut text = std::fs::read_to_string(path).expect("zoo scene");
        for e in &edits {
            text = apply_scene_edit(&text, e, &keys);
        }
        if let Ok(result) = run_scene_text(&text) {
            assert_finite_outputs(&result);
        }
    }
}

/// One edit of a model's data.
#[derive(Debug, Clone)]
struct ModelEdit {
    what: u8,
    index: u32,
    raw: u32,
    value: usize,
}

fn model_edit() -> impl Strategy<Value = ModelEdit> {
    (0u8..14, any::<u32>(), any::<u32>(), 0..HOSTILE_F64.len()).prop_map(
        |(what, index, raw, value)| ModelEdit {
            what,
            index,
            raw,
            value,
        },
    )
}

/// A hostile `u32`: mostly near the valid range, sometimes anything.
fn near(raw: u32, size: usize) -> u32 {
    if raw.is_multiple_of(4) {
        raw
    } else {
        raw % (size as u32 + 3)
    }
}

fn apply_model_edit(m: &mut Model, e: &ModelEdit) {
    let n = m.states.len();
    let x = HOSTILE_F64[e.value];
    let pick = |len: usize| (e.index as usize) % len.max(1);
    match e.what {
        0 if !m.a.entries.is_empty() => {
            let i = pick(m.a.entries.len());
            m.a.entries[i].row = near(e.raw, n);
        }
        1 if !m.a.entries.is_empty() => {
            let i = pick(m.a.entries.len());
            m.a.entries[i].value = x;
        }
        2 if !m.b.entries.is_empty() => {
            let i = pick(m.b.entries.len());
            m.b.entries[i].col = near(e.raw, n);
        }
        3 => m.a.nrows = near(e.raw, n),
        4 if !m.nonlinearity.terms.is_empty() => {
            let i = pick(m.nonlinearity.terms.len());
            m.nonlinearity.terms[i].coeff = x;
        }
        5 if !m.nonlinearity.terms.is_empty() => {
            let i = pick(m.nonlinearity.terms.len());
            if let Some(f) = m.nonlinearity.terms[i].factors.first_mut() {
                f.power = if e.raw.is_multiple_of(3) {
                    e.raw
                } else {
                    e.raw % 70
                };
            }
        }
        6 if !m.nonlinearity.terms.is_empty() => {
            let i = pick(m.nonlinearity.terms.len());
            if let Some(f) = m.nonlinearity.terms[i].factors.first_mut() {
                f.var = near(e.raw, n);
            }
        }
        7 if !m.states.is_empty() => {
            let i = pick(m.states.len());
            m.states.remove(i);
        }
        8 if !m.outputs.is_empty() => {
            let i = pick(m.outputs.len());
            if let Some(w) = m.outputs[i].weights.first_mut() {
                w.state = near(e.raw, n);
                w.value = x;
            }
        }
        9 => m.equilibrium = vec![x; (e.raw % 4) as usize + n.saturating_sub(1)].into(),
        10 if !m.expressions.nodes.is_empty() => {
            let len = m.expressions.nodes.len();
            let node = &mut m.expressions.nodes[pick(len)];
            node.a = near(e.raw, len);
            node.value = x;
        }
        11 if !m.expressions.nodes.is_empty() => {
            let i = pick(m.expressions.nodes.len());
            let ops = [
                ExprOp::Ln,
                ExprOp::Recip,
                ExprOp::Sqrt,
                ExprOp::Powi,
                ExprOp::Var,
            ];
            m.expressions.nodes[i].op = ops[(e.raw as usize) % ops.len()];
        }
        12 => {
            if let ssm_api::reexports::abi_stable::std_types::ROption::RSome(info) =
                &mut m.mechanical
            {
                info.n_dof = near(e.raw, n);
                if e.raw.is_multiple_of(2) {
                    info.n_constraints = near(e.raw / 2, n);
                }
            }
        }
        13 if !m.forcing.is_empty() => {
            let i = pick(m.forcing.len());
            m.forcing[i].multiple = x;
        }
        _ => {}
    }
}

/// The models to corrupt: a map, a Duffing oscillator, the constrained
/// spatial oscillator (polynomial constraint) and the slider pendulum
/// (expressions, equilibrium).
fn base_model(i: usize) -> Model {
    let from = |lib: &str, name: &str, params: &str| {
        Plugin::load(&plugin_path(lib))
            .expect("plugin loads")
            .build_model(name, params)
            .expect("model builds")
    };
    match i {
        0 => ssm_tests::cubic_map_model(),
        1 => from("duffing", "", ""),
        2 => from("spatial-oscillator", "", "constraint = \"cubic\""),
        _ => from("pendulum", "slider", ""),
    }
}

/// Up to the SSM at order 3: validation, spectrum (both paths), master modes.
/// What each stage returns must be finite: a corrupted model that gets
/// through validation gets a finite spectrum, finite master modes and a
/// finite expansion, or a typed error.
fn analyse(model: Model) {
    let finite = |z: &num_complex::Complex64| z.re.is_finite() && z.im.is_finite();
    let Ok(sys) = System::from_model("fuzz", model) else {
        return;
    };
    for method in [Method::Dense, Method::Sparse] {
        let opts = ssm_tests::spectrum_options(Some(method), 4);
        let Ok(sp) = spectrum::compute(sys.a.as_ref(), sys.b.as_ref(), &opts) else {
            continue;
        };
        assert!(
            sp.eigenvalues.iter().all(finite),
            "{method:?}: {:?}",
            sp.eigenvalues
        );
        let Ok(masters) = spectrum::master_modes(&sys, &sp, &[1], Normalization::Unit) else {
            continue;
        };
        for m in &masters {
            assert!(finite(&m.lambda) && m.right.iter().all(finite) && m.left.iter().all(finite));
        }
        let others = ssm_mod::non_master(&sp.eigenvalues, &masters);
        let options = ssm_mod::SsmOptions {
            order: 3,
            resonance_tol: 1e-6,
        };
        if let Ok(e) = ssm_mod::compute(&sys, &masters, &others, &options) {
            assert!(
                e.w.iter().flatten().all(finite),
                "{method:?}: a W coefficient is not finite"
            );
            assert!(
                e.r.iter().all(|t| finite(&t.coeff)),
                "{method:?}: an R term is not finite"
            );
        }
    }
}

proptest! {
    #![proptest_config(config())]

    /// Plugin model data with up to four corrupted fields is refused with a
    /// typed error or analysed to finite results; nothing panics, aborts or
    /// hangs.
    #[test]
    fn corrupted_model_data_is_refused_or_analysed(
        base in 0usize..4,
        edits in prop::collection::vec(model_edit(), 1..5),
    ) {
        let mut m = base_model(base);
        for e in &edits {
            apply_model_edit(&mut m, e);
        }
        analyse(m);
    }
}
