//! The reduced transient (`[outputs.transient]`): the reduced dynamics on
//! the SSM integrated from given polar amplitudes and phases of the master
//! pairs and lifted by `W` to the model's outputs, with the estimate of its
//! error (the modal defect of the invariance equation along the trajectory,
//! and for several pairs the change from two orders lower).
//!
//! Its results keep the key `rom_steps` of `summary.json` (older than the
//! registry) and its estimate the entry `transient` of `accuracy.answers`;
//! file `rom_trajectory.csv`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 3.3
//! (the reduced dynamics) and Figs. 10 and 22 (transients on the SSM).

mod write;

use schemars::JsonSchema;
use serde::Serialize;

use super::{untrusted_warning, Analysis, Answers, Beside, Context, Needs, Sizes, Work};
use crate::plot::PlotError;
use ssm_core::rom::accuracy::AnswerEstimate;
use ssm_core::rom::autonomous::{transient, LiftedTransient, ResultError};
use ssm_core::spec::{SpecError, TransientSpec};
use ssm_core::ssm::Dynamics;

/// The reduced transient as an analysis of the registry.
#[derive(Debug, Clone, Copy)]
pub struct Transient;

/// A reduced transient and the accuracy target its estimate was held to.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct ReducedTransient {
    /// The accuracy target (`[ssm] tolerance`, relative).
    pub tolerance: f64,
    /// The transient, lifted to the outputs of `[outputs] coordinates`.
    #[serde(flatten)]
    pub transient: LiftedTransient,
}

impl Analysis for Transient {
    const NAME: &'static str = "transient";
    const OWN_TABLE: Option<&'static str> = Some("outputs.transient");
    type Spec = TransientSpec;
    type Output = ReducedTransient;
    type Error = ResultError;

    fn check(spec: &TransientSpec, needs: &Needs) -> Result<(), SpecError> {
        spec.check(needs.pairs, needs.max_order)
    }

    fn orders(spec: &TransientSpec) -> Vec<usize> {
        spec.order.into_iter().collect()
    }

    /// The reduced integration (`steps` of a 7-stage pair on the reduced
    /// vector field, at most 1e3 multi-indices a stage) and the lift of the
    /// stored samples to the outputs; a map stores every step.
    fn work(spec: &TransientSpec, sizes: &Sizes<'_>) -> Work {
        let periods = spec.t_end * sizes.periods_per_time;
        let (n, stored) = match sizes.dynamics {
            Dynamics::Map { .. } => (periods, periods.max(spec.samples as f64)),
            Dynamics::Flow => (periods * sizes.steps_per_period, spec.samples as f64),
        };
        let (nvar, coords) = (2.0 * sizes.pairs.max(1) as f64, sizes.outputs as f64);
        let (key, what) = if n * 1e3 > stored {
            (
                "outputs.transient.t_end",
                format!("a reduced transient over {periods:.1e} periods"),
            )
        } else {
            (
                "outputs.transient.samples",
                format!("a reduced transient of {:.1e} samples", spec.samples as f64),
            )
        };
        Work {
            ops: n * 7.0 * 4.0 * sizes.multi_indices.min(1e3) * nvar
                + stored * 4.0 * sizes.multi_indices * coords,
            bytes: stored * (16.0 * nvar + 8.0 * coords + 96.0),
            key,
            what,
            advice: "shorten the transient or take fewer samples",
        }
    }

    fn run(spec: &TransientSpec, cx: &Context<'_>) -> Result<ReducedTransient, ResultError> {
        let t = transient(
            cx.ssm,
            cx.system,
            cx.masters,
            spec,
            cx.outputs,
            cx.tolerance,
        )?;
        Ok(ReducedTransient {
            tolerance: cx.tolerance,
            transient: t,
        })
    }

    fn estimates(output: &ReducedTransient) -> Vec<AnswerEstimate> {
        let t = &output.transient;
        vec![AnswerEstimate {
            answer: "transient",
            order: t.order,
            epsilon: None,
            estimate: t.error_estimate,
            untrusted: t.untrusted,
            trusted_up_to: None,
        }]
    }

    fn warnings(output: &ReducedTransient) -> Vec<String> {
        let t = &output.transient;
        if !t.untrusted {
            return Vec::new();
        }
        vec![untrusted_warning(
            &format!("transient O({})", t.order),
            t.error_estimate,
            output.tolerance,
            None,
            "start nearer the equilibrium (rho0), shorten t_end or raise the expansion order",
        )]
    }

    fn summarize(output: &ReducedTransient, answers: &mut Answers) {
        answers.rom_steps = Some(output.transient.steps);
    }

    fn files(
        output: &ReducedTransient,
        outputs: &[String],
        _beside: &Beside<'_>,
    ) -> Result<Vec<(String, Vec<u8>)>, PlotError> {
        Ok(vec![(
            "rom_trajectory.csv".into(),
            write::transient_csv(&output.transient, outputs).into(),
        )])
    }
}
