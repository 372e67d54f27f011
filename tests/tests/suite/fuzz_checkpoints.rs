//! Property tests over `--resume` checkpoints: the checkpoint of the 1:2
//! parametric pump edited (numbers, words, flags, lines, a cut) and resumed
//! ends in a typed error or in a consistent branch (finite orbits, stable
//! exactly where their largest multiplier is inside the unit circle). The
//! cases run forked with the time limit and seed of `fuzz.rs`.

use proptest::prelude::*;
use ssm_core::fom::periodic::{reference_frc_resumable, ReferenceBranch, Runs};
use ssm_engine::output::checkpoint::Checkpoint;

use crate::fuzz::config_with;
use crate::fuzz_inputs::{case_dir, CASES};

/// One edit of a checkpoint line (JSON).
#[derive(Debug, Clone)]
enum RecordEdit {
    /// The `k`-th number of a line replaced.
    Number { line: usize, k: usize, value: usize },
    /// The `k`-th string value of a line replaced.
    Word { line: usize, k: usize, value: usize },
    /// `true` and `false` swapped on a line.
    Flip { line: usize },
    /// A line deleted, duplicated or moved.
    Lines { line: usize, kind: usize, to: usize },
    /// The file cut at a byte.
    Truncate { at: usize },
}

fn record_edit() -> impl Strategy<Value = RecordEdit> {
    prop_oneof![
        5 => (any::<usize>(), any::<usize>(), any::<usize>())
            .prop_map(|(line, k, value)| RecordEdit::Number { line, k, value }),
        2 => (any::<usize>(), any::<usize>(), any::<usize>())
            .prop_map(|(line, k, value)| RecordEdit::Word { line, k, value }),
        1 => any::<usize>().prop_map(|line| RecordEdit::Flip { line }),
        2 => (any::<usize>(), any::<usize>(), any::<usize>())
            .prop_map(|(line, kind, to)| RecordEdit::Lines { line, kind, to }),
        1 => any::<usize>().prop_map(|at| RecordEdit::Truncate { at }),
    ]
}

/// Numbers a hostile checkpoint holds (JSON: no NaN literal).
const HOSTILE_JSON_NUMBERS: [&str; 10] = [
    "-1",
    "0",
    "3",
    "1e300",
    "1e999",
    "0.5",
    "-0.0",
    "4294967296",
    "1e-300",
    "2",
];
const HOSTILE_WORDS: [&str; 7] = [
    "Fold",
    "BranchPoint",
    "PeriodDoubling",
    "Bogus",
    "",
    "Stop",
    "Step",
];

fn apply_record_edit(text: &str, e: &RecordEdit) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    if lines.is_empty() {
        return text.to_owned();
    }
    let n = lines.len().max(1);
    // byte ranges of the numbers (or quoted words) of a line
    let spans = |l: &str, words: bool| -> Vec<(usize, usize)> {
        let b = l.as_bytes();
        let mut out = Vec::new();
        let mut i = 0;
        while i < b.len() {
            if words && b[i] == b'"' {
                let end = l[i + 1..].find('"').map_or(b.len(), |j| i + 1 + j);
                // a value, not a key: followed by something other than ':'
                if l[end.min(b.len())..].get(1..2) != Some(":") {
                    out.push((i + 1, end));
                }
                i = end + 1;
            } else if !words
                && (b[i].is_ascii_digit() || b[i] == b'-')
                && (i == 0 || b"[:,".contains(&b[i - 1]))
            {
                let start = i;
                while i < b.len() && !b",]}".contains(&b[i]) {
                    i += 1;
                }
                out.push((start, i));
            } else {
                i += 1;
            }
        }
        out
    };
    match *e {
        RecordEdit::Number { line, k, value } | RecordEdit::Word { line, k, value } => {
            let words = matches!(e, RecordEdit::Word { .. });
            let l = &mut lines[line % n];
            let s = spans(l, words);
            if !s.is_empty() {
                let (a, b) = s[k % s.len()];
                let v = if words {
                    HOSTILE_WORDS[value % HOSTILE_WORDS.len()]
                } else {
                    HOSTILE_JSON_NUMBERS[value % HOSTILE_JSON_NUMBERS.len()]
                };
                l.replace_range(a..b, v);
            }
        }
        RecordEdit::Flip { line } => {
            let l = &mut lines[line % n];
            *l = l
                .replace("true", "t#")
                .replace("false", "true")
                .replace("t#", "false");
        }
        RecordEdit::Lines { line, kind, to } => {
            let i = line % n;
            match kind % 3 {
                0 => {
                    lines.remove(i);
                }
                1 => {
                    let l = lines[i].clone();
                    lines.insert(i, l);
                }
                _ => {
                    let l = lines.remove(i);
                    lines.insert(to % n.max(1).min(lines.len() + 1), l);
                }
            }
        }
        RecordEdit::Truncate { at } => {
            let mut cut = at % text.len().max(1);
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_owned();
        }
    }
    lines.join("\n") + "\n"
}

/// The uninterrupted checkpoint of the 1:2 parametric pump (computed once
/// per test process: proptest runs the cases of a forked test in one child).
fn pump_checkpoint() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| {
        let dir = case_dir("checkpoint-whole");
        let sys = ssm_tests::parametric_pump(0.01, 0.01, 1.0, 0.5, 0.005);
        let settings = ssm_tests::parametric_pump_reference(vec![2.0]);
        let whole = Checkpoint::fresh(&dir.join("out"), "pump", "scene text");
        reference_frc_resumable(&sys, &settings, &mut Runs::new(&whole, |_| true))
            .expect("the pump's reference");
        let path = whole.written().expect("checkpoint written");
        drop(whole);
        let text = std::fs::read_to_string(&path).expect("checkpoint");
        let _ = std::fs::remove_dir_all(&dir);
        text
    })
}

/// A resumed branch (and the branches it holds) is finite and stable
/// exactly where its largest multiplier says so.
fn assert_consistent(b: &ReferenceBranch) {
    for o in &b.orbits {
        assert!(
            o.omega.is_finite() && o.epsilon.is_finite() && o.tail.is_finite(),
            "{o:?}"
        );
        assert!(o.linf.iter().all(|v| v.is_finite()), "{o:?}");
        if let (Some(stable), Some(m)) = (o.stable, o.max_multiplier) {
            assert!(m.is_finite(), "{o:?}");
            if m < 1.0 - 1e-6 {
                assert!(
                    stable,
                    "an orbit with multipliers inside the circle is unstable: {o:?}"
                );
            }
            if m > 1.0 + 1e-3 {
                assert!(
                    !stable,
                    "an orbit with a multiplier outside the circle is stable: {o:?}"
                );
            }
        }
    }
    for d in b.doubled.iter().chain(&b.seeded) {
        assert_consistent(d);
    }
}

proptest! {
    #![proptest_config(config_with(CASES))]

    /// The checkpoint of the 1:2 parametric pump (two continuation runs,
    /// period doublings, the 2T branch) edited up to three times and
    /// resumed: refused with a typed error, or a consistent branch.
    #[test]
    fn corrupted_checkpoints_resume_to_an_error_or_a_consistent_branch(
        edits in prop::collection::vec(record_edit(), 1..4),
    ) {
        let dir = case_dir("checkpoint");
        let path = Checkpoint::default_path(&dir.join("out"));
        let sys = ssm_tests::parametric_pump(0.01, 0.01, 1.0, 0.5, 0.005);
        let settings = ssm_tests::parametric_pump_reference(vec![2.0]);
        let text = pump_checkpoint();
        // the run's end removed, as a stop leaves it, so that resuming reads
        // the records instead of finding the run complete
        let body: String = text
            .lines()
            .filter(|l| !l.starts_with("{\"End\""))
            .map(|l| format!("{l}\n"))
            .collect();
        let edited = edits.iter().fold(body, |t, e| apply_record_edit(&t, e));
        std::fs::write(&path, edited).expect("edited checkpoint");
        if let Ok(ck) = Checkpoint::resume(&path, "pump", "scene text") {
            if let Ok(b) = reference_frc_resumable(&sys, &settings, &mut Runs::new(&ck, |_| true)) {
                assert_consistent(&b);
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
