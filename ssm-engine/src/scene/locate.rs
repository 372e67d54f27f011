//! Where a key is written in a scene: the front end's half of a plan error
//! (the plan names keys, the scene knows their lines).

use std::ops::Range;

use toml::de::{DeTable, DeValue};

use super::SceneFile;

impl SceneFile {
    /// The span of the value at the key path `path` (`reference.step`,
    /// `simulate.run[2].x0`: `[n]` picks the n-th element, 1-based), or,
    /// when the path is not written (a default), of the nearest table on
    /// it that is (its header line); the start of the file without one.
    pub fn locate(&self, path: &str) -> Range<usize> {
        let Ok(root) = DeTable::parse(&self.text) else {
            return 0..0;
        };
        let mut table = root.get_ref();
        let mut found = 0..0;
        for part in path.split('.') {
            let (name, index) = match part.split_once('[') {
                Some((n, rest)) => (n, rest.trim_end_matches(']').parse::<usize>().ok()),
                None => (part, None),
            };
            let Some(value) = table.get(name) else {
                break;
            };
            found = value.span();
            let value = match (value.get_ref(), index) {
                (DeValue::Array(items), Some(k)) => {
                    match items.get(k.saturating_sub(1)).filter(|_| k > 0) {
                        Some(item) => {
                            found = item.span();
                            item.get_ref()
                        }
                        None => break,
                    }
                }
                (v, _) => v,
            };
            match value {
                DeValue::Table(t) => table = t,
                _ => break,
            }
        }
        found
    }
}
