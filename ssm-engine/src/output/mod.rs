//! The output layer: writers that turn the typed results of a run into files
//! (`summary.json`, CSV tables, SVG plots) and compute nothing, and the
//! [`OutputSet`] that holds them in memory until they are written to the
//! output directory.

pub mod checkpoint;
mod files;
pub mod identified;
pub mod ssm;
pub mod summary;

use crate::plot::PlotError;
pub use files::{check_not_input, InputInOutput, OutputError, OutputSet, MARKER};
use ssm_core::spectrum::ModalFigures;
use summary::{pod_only_summary_json, summary_json, Summary, Timing};

use ssm_core::compare::pod::PodStudy;
use ssm_core::model::plugin::PluginOrigin;
use ssm_core::model::system::System;

/// `spectrum.csv`: one finite eigenvalue a row with its frequency, damping
/// ratio and master-pair membership (`(pair, index)` of each master).
pub(crate) fn spectrum_csv(modal: &[ModalFigures], master_indices: &[(usize, usize)]) -> String {
    let mut s = String::from("index,re,im,abs,frequency,damping_ratio,master_pair\n");
    for (k, m) in modal.iter().enumerate() {
        let master = master_indices
            .iter()
            .find(|(_, i)| k == *i || k == *i + 1)
            .map_or(String::new(), |(p, _)| p.to_string());
        s.push_str(&format!(
            "{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{}\n",
            k + 1,
            m.lambda.re,
            m.lambda.im,
            m.abs,
            m.frequency,
            m.damping_ratio,
            master
        ));
    }
    s
}

/// The typed results of a run, as the output layer receives them.
pub(crate) struct Products<'a> {
    /// The finite spectrum's frequencies and damping ratios.
    pub modal: &'a [ModalFigures],
    /// Everything `summary.json` reports (also the FRC, validation and report).
    pub summary: Summary<'a>,
}

/// Every file of a run: `summary.json`, `spectrum.csv`, and the files of each
/// answer present.
pub(crate) fn result_files(p: &Products<'_>) -> Result<OutputSet, PlotError> {
    let s = &p.summary;
    let mut out = OutputSet::default();
    if let Some(study) = s.pod {
        pod_files(&mut out, &s.system.name, study)?;
    }
    if let Some(r) = s.reduction.filter(|r| r.signals.is_some()) {
        out.add("identified.json", identified::identified_json(r, s.system));
    }
    let pair_index: Vec<(usize, usize)> = s.masters.iter().map(|m| (m.pair, m.index)).collect();
    out.add("spectrum.csv", spectrum_csv(p.modal, &pair_index));
    out.add("summary.json", summary_json(s));
    Ok(out)
}

/// The files of a `[pod]` study.
fn pod_files(out: &mut OutputSet, model: &str, study: &PodStudy) -> Result<(), PlotError> {
    for (name, contents) in crate::analyses::pod::files(model, study)? {
        out.add(&name, contents);
    }
    Ok(())
}

/// Every file of a `[pod]` scene that asks for no SSM answer.
pub(crate) fn pod_only_files(
    system: &System,
    plugins: &[PluginOrigin],
    study: Option<&PodStudy>,
    warnings: &[String],
    timing: Timing,
) -> Result<OutputSet, PlotError> {
    let mut out = OutputSet::default();
    if let Some(study) = study {
        pod_files(&mut out, &system.name, study)?;
    }
    out.add(
        "summary.json",
        pod_only_summary_json(system, plugins, study, warnings, timing),
    );
    Ok(out)
}
