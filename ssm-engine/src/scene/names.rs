//! Lists of names in a scene (outputs, data columns): each name once.

use super::{SceneError, SceneFile};

impl SceneFile {
    /// Refuses a list that names one output (or data column) twice: each
    /// entry is computed and written, so a repeated name only multiplies
    /// the work.
    pub(super) fn check_unique_names(&self) -> Result<(), SceneError> {
        let sc = &self.scene;
        let lists = [
            (Some(&sc.outputs.coordinates), "outputs.coordinates"),
            (
                sc.validate.as_ref().and_then(|v| v.outputs.as_ref()),
                "validate.outputs",
            ),
            (
                sc.simulate.as_ref().and_then(|v| v.outputs.as_ref()),
                "simulate.outputs",
            ),
            (
                sc.pod.as_ref().and_then(|v| v.outputs.as_ref()),
                "pod.outputs",
            ),
            (
                sc.reference.as_ref().and_then(|v| v.outputs.as_ref()),
                "reference.outputs",
            ),
            (
                sc.data.as_ref().and_then(|v| v.columns.as_ref()),
                "data.columns",
            ),
        ];
        for (names, key) in lists.into_iter().filter_map(|(n, k)| Some((n?, k))) {
            let mut seen = std::collections::HashSet::new();
            if let Some(dup) = names.get_ref().iter().find(|n| !seen.insert(n.as_str())) {
                return Err(self.invalid(
                    names.span(),
                    key,
                    format!("names '{dup}' more than once: give each name once"),
                ));
            }
        }
        Ok(())
    }
}
