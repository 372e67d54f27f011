//! The backbone curves of the first master pair (`[outputs.backbone]`): the
//! instantaneous frequency `omega(rho)` of the polar form of the reduced
//! dynamics against the amplitude `rho`, with the amplitudes of the outputs
//! read off `W`, one curve per expansion order, each point with the
//! estimate of its error (the modal defect of the invariance equation on
//! the circle of radius `rho`). When the model was identified from `[data]`
//! signals, the backbones read off those signals (zero crossings and the
//! Hilbert transform) near the SSM's frequency are drawn beside them.
//!
//! No key of `summary.json` of its own (older than the registry): its
//! estimates are the `backbone` entries of `accuracy.answers`; files
//! `backbone.csv`, `backbone.svg` and `data_backbone.csv`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 3.3
//! and Fig. 5; G. Haller, S. Ponsioen, *Nonlinear normal modes and spectral
//! submanifolds*, Nonlinear Dyn. 86 (2016), Sect. 6; M. Feldman, J. Sound
//! Vib. 208 (1997) 475-489 (backbones of free decays by the Hilbert
//! transform).

mod write;

use schemars::JsonSchema;
use serde::Serialize;

use super::{untrusted_warning, Analysis, Answers, Beside, Context, Needs, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::compare::instantaneous::{data_backbones, near_frequency, DataBackbone};
use ssm_core::rom::accuracy::AnswerEstimate;
use ssm_core::rom::autonomous::{backbone, BackboneCurve, ResultError};
use ssm_core::spec::{BackboneSpec, SpecError};

/// The backbone as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Backbone;

/// Backbone curves, those of the `[data]` signals, and the accuracy target
/// their estimates were held to.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct Backbones {
    /// The accuracy target (`[ssm] tolerance`, relative).
    pub tolerance: f64,
    /// One curve per expansion order.
    pub curves: Vec<BackboneCurve>,
    /// The backbones of the `[data]` signals of the first output whose
    /// frequency is within 25 % of the SSM's at `rho = 0`.
    pub data: Vec<DataBackbone>,
}

impl Analysis for Backbone {
    const NAME: &'static str = "backbone";
    const OWN_TABLE: Option<&'static str> = Some("outputs.backbone");
    type Spec = BackboneSpec;
    type Output = Backbones;
    type Error = ResultError;

    fn check(spec: &BackboneSpec, needs: &Needs) -> Result<(), SpecError> {
        spec.check(needs.pairs, needs.max_order)
    }

    fn orders(spec: &BackboneSpec) -> Vec<usize> {
        spec.orders.clone().unwrap_or_default()
    }

    /// `points` evaluations of the polar form and of `W` at each order.
    fn work(spec: &BackboneSpec, sizes: &Sizes<'_>) -> Work {
        let points = spec.points as f64;
        let orders = spec.orders.as_ref().map_or(1, Vec::len) as f64;
        let coords = sizes.outputs as f64;
        Work {
            ops: points * orders * 4.0 * sizes.multi_indices * (coords + 1.0),
            bytes: points * orders * 8.0 * (coords + 6.0),
            key: "outputs.backbone.points",
            what: format!("a backbone of {points:.1e} points"),
            advice: "lower the number of points",
        }
    }

    fn run(spec: &BackboneSpec, cx: &Context<'_>) -> Result<Backbones, ResultError> {
        let curves = backbone(
            cx.ssm,
            cx.system,
            &cx.masters[0],
            spec,
            cx.outputs,
            cx.tolerance,
        )?;
        let data = match (cx.signals, curves.first()) {
            (Some(sig), Some(first)) => {
                let all = signal_backbones(sig, cx.outputs.first().map(|o| o.name.as_str()));
                let omega0 = first.points.first().map_or(0.0, |p| p.omega);
                near_frequency(all, omega0, 0.25)
            }
            _ => Vec::new(),
        };
        Ok(Backbones {
            tolerance: cx.tolerance,
            curves,
            data,
        })
    }

    fn estimates(output: &Backbones) -> Vec<AnswerEstimate> {
        output
            .curves
            .iter()
            .map(|c| AnswerEstimate {
                answer: "backbone",
                order: c.order,
                epsilon: None,
                estimate: c.error_estimate,
                untrusted: c.untrusted,
                trusted_up_to: c.trusted_up_to,
            })
            .collect()
    }

    fn warnings(output: &Backbones) -> Vec<String> {
        output
            .curves
            .iter()
            .filter(|c| c.untrusted)
            .map(|c| {
                untrusted_warning(
                    &format!("backbone O({})", c.order),
                    c.error_estimate,
                    output.tolerance,
                    c.trusted_up_to,
                    "lower [outputs.backbone] rho_max or raise the expansion order",
                )
            })
            .collect()
    }

    /// Nothing: its estimates are in `accuracy.answers`.
    fn summarize(_output: &Backbones, _answers: &mut Answers) {}

    fn files(
        output: &Backbones,
        outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        let mut files = vec![
            (
                "backbone.csv".to_owned(),
                write::backbone_csv(&output.curves, outputs).into_bytes(),
            ),
            (
                "backbone.svg".to_owned(),
                write::backbone_svg(&output.curves, &output.data, outputs)?.into_bytes(),
            ),
        ];
        if !output.data.is_empty() {
            files.push((
                "data_backbone.csv".to_owned(),
                write::data_backbone_csv(&output.data).into_bytes(),
            ));
        }
        Ok(files)
    }
}

/// The zero-crossing and Hilbert backbones of each `[data]` signal of the
/// observable `name` (the backbone's first output), when the data have it.
fn signal_backbones(sig: &ssm_api::Signals, name: Option<&str>) -> Vec<DataBackbone> {
    let Some(j) = name.and_then(|n| sig.names.iter().position(|c| c.as_str() == n)) else {
        return Vec::new();
    };
    let series: Vec<(String, Vec<f64>)> = (0..sig.trajectories.len())
        .map(|k| {
            let y = (0..sig.n_samples(k)).map(|i| sig.sample(k, i)[j]).collect();
            (sig.trajectories[k].source.to_string(), y)
        })
        .collect();
    data_backbones(&series, sig.period)
}
