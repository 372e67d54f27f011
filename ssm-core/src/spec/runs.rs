//! The specs of the sections that are not answers read off the reduced
//! model: the SSM and spectrum settings, the full-system reference, the
//! report, the sampled runs and the POD study. Like the answers' specs of
//! this module, each serializes to and from JSON, a field left out
//! takes the default documented on it (the scene's default), and unknown
//! fields are refused.

use super::ValidationStart;
use crate::spectrum::{Method, Normalization};
use serde::{Deserialize, Serialize};

/// The SSM (`[ssm]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SsmSpec {
    /// 1-based master mode pairs, slowest first (default `[1]`).
    #[serde(default = "SsmSpec::default_master_pairs")]
    pub master_pairs: Vec<usize>,
    /// Expansion order (`None`: the lowest odd order from 3 up to
    /// [`SsmSpec::AUTO_MAX_ORDER`], and the machine's limits, whose answers
    /// meet `tolerance`).
    #[serde(default)]
    pub order: Option<usize>,
    /// Eigenvector scaling (default unit 2-norm).
    #[serde(default)]
    pub normalization: Normalization,
    /// Relative distance below which a combination of eigenvalues counts as
    /// a (near) resonance (default 0.02).
    #[serde(default = "SsmSpec::default_resonance_tol")]
    pub resonance_tol: f64,
    /// Accuracy target: the relative error an answer may have before it is
    /// flagged (default 0.01).
    #[serde(default = "SsmSpec::default_tolerance")]
    pub tolerance: f64,
}

impl SsmSpec {
    /// The highest expansion order the engine chooses by itself: beyond it,
    /// on a model whose answers still miss the accuracy target, the
    /// expansion is usually outside its convergence radius.
    pub const AUTO_MAX_ORDER: usize = 15;
    /// `resonance_tol` when none is asked for.
    pub const DEFAULT_RESONANCE_TOL: f64 = 0.02;
    /// `tolerance` when none is asked for.
    pub const DEFAULT_TOLERANCE: f64 = 0.01;

    fn default_master_pairs() -> Vec<usize> {
        vec![1]
    }
    fn default_resonance_tol() -> f64 {
        Self::DEFAULT_RESONANCE_TOL
    }
    fn default_tolerance() -> f64 {
        Self::DEFAULT_TOLERANCE
    }

    /// The highest order any answer may use: `order`, or
    /// [`Self::AUTO_MAX_ORDER`].
    pub fn max_order(&self) -> usize {
        self.order.unwrap_or(Self::AUTO_MAX_ORDER)
    }
}

impl Default for SsmSpec {
    fn default() -> Self {
        Self {
            master_pairs: Self::default_master_pairs(),
            order: None,
            normalization: Normalization::Unit,
            resonance_tol: Self::DEFAULT_RESONANCE_TOL,
            tolerance: Self::DEFAULT_TOLERANCE,
        }
    }
}

/// The eigensolver (`[spectrum]`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpectrumSpec {
    /// Solver (`None`: dense up to [`crate::spectrum::DENSE_LIMIT`]
    /// states, sparse above).
    #[serde(default)]
    pub method: Option<Method>,
    /// Finite eigenvalues computed on the sparse path (`None`: the master
    /// modes plus 10, widened to cover the resonance checks).
    #[serde(default)]
    pub modes: Option<usize>,
    /// Real shift of the sparse path (default 0: the modes nearest the origin).
    #[serde(default)]
    pub shift: f64,
}

/// Where the branches of the full-system reference start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceStart {
    /// One branch from rest at `Omega_min`.
    Rest,
    /// Also a branch from the peak of each branch of the reduced model's
    /// forced response, lifted by `W`.
    Ssm,
}

/// The full system's forced response by harmonic balance and continuation
/// (`[reference]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Forcing amplitudes, one branch each.
    pub epsilon: Vec<f64>,
    /// `[Omega_min, Omega_max]` (`None`: the forced response's).
    #[serde(default)]
    pub omega_range: Option<[f64; 2]>,
    /// Harmonics `H` of the orbits (default 9).
    #[serde(default = "ReferenceSpec::default_harmonics")]
    pub harmonics: usize,
    /// Largest scaled arclength step (default 0.5).
    #[serde(default = "ReferenceSpec::default_step")]
    pub step: f64,
    /// Newton tolerance, relative update (default 1e-10).
    #[serde(default = "ReferenceSpec::default_tol")]
    pub tol: f64,
    /// Most continuation steps per branch (default 5000).
    #[serde(default = "ReferenceSpec::default_max_steps")]
    pub max_steps: usize,
    /// Switch to the branch of period `2T` at each period doubling (default true).
    #[serde(default = "yes")]
    pub period_doubling: bool,
    /// Floquet multipliers of every orbit (default true).
    #[serde(default = "yes")]
    pub stability: bool,
    /// Outputs whose amplitudes are written (`None`: the plan's coordinates).
    #[serde(default)]
    pub outputs: Option<Vec<String>>,
    /// Where branches start (`None`: also from the reduced model's forced
    /// response when the plan has one, else from rest).
    #[serde(default)]
    pub start: Option<ReferenceStart>,
    /// Frequencies of amplitude responses (continuation in `eps` at fixed
    /// `Omega`), one branch each (default none).
    #[serde(default)]
    pub amplitude_at: Vec<f64>,
    /// `[eps_min, eps_max]` of the amplitude responses (`None`: `[0, the
    /// largest epsilon]`).
    #[serde(default)]
    pub amplitude_range: Option<[f64; 2]>,
}

fn yes() -> bool {
    true
}

impl ReferenceSpec {
    /// Harmonics when none are asked for.
    pub const DEFAULT_HARMONICS: usize = 9;
    /// Step when none is asked for.
    pub const DEFAULT_STEP: f64 = 0.5;
    /// Newton tolerance when none is asked for.
    pub const DEFAULT_TOL: f64 = 1e-10;
    /// Steps per branch when none are asked for.
    pub const DEFAULT_MAX_STEPS: usize = 5000;

    fn default_harmonics() -> usize {
        Self::DEFAULT_HARMONICS
    }
    fn default_step() -> f64 {
        Self::DEFAULT_STEP
    }
    fn default_tol() -> f64 {
        Self::DEFAULT_TOL
    }
    fn default_max_steps() -> usize {
        Self::DEFAULT_MAX_STEPS
    }

    /// Branches at the amplitudes `epsilon`, everything else at its default.
    pub fn new(epsilon: Vec<f64>) -> Self {
        Self {
            epsilon,
            omega_range: None,
            harmonics: Self::DEFAULT_HARMONICS,
            step: Self::DEFAULT_STEP,
            tol: Self::DEFAULT_TOL,
            max_steps: Self::DEFAULT_MAX_STEPS,
            period_doubling: true,
            stability: true,
            outputs: None,
            start: None,
            amplitude_at: Vec::new(),
            amplitude_range: None,
        }
    }

    /// Whether branches also start from the reduced model's forced
    /// response (`forced`: the plan has one).
    pub fn from_ssm(&self, forced: bool) -> bool {
        self.start.map_or(forced, |s| s == ReferenceStart::Ssm)
    }

    /// The frequency range: this spec's, else the forced response's.
    pub fn omega_range(&self, forcing: Option<[f64; 2]>) -> Option<(f64, f64)> {
        self.omega_range.or(forcing).map(|[a, b]| (a, b))
    }

    /// The amplitude responses' range: `amplitude_range`, else `[0, the
    /// largest epsilon]`.
    pub fn amplitude_range(&self) -> (f64, f64) {
        match self.amplitude_range {
            Some([a, b]) => (a, b),
            None => (0.0, self.epsilon.iter().copied().fold(0.0, f64::max)),
        }
    }
}

/// The speed-against-error report (`[report]`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSpec {
    /// Expansion orders, one row each (`None`: the odd orders from 3 up to
    /// the SSM's order, which is always included).
    #[serde(default)]
    pub orders: Option<Vec<usize>>,
}

impl ReportSpec {
    /// The orders of the report on an SSM of order `max`.
    pub fn orders_up_to(&self, max: usize) -> Vec<usize> {
        self.orders.clone().unwrap_or_else(|| {
            let mut o: Vec<usize> = (3..=max).filter(|k| k % 2 == 1).collect();
            if o.last() != Some(&max) {
                o.push(max);
            }
            o
        })
    }
}

/// Sampled full-system runs (`[simulate]`), the input of data-driven
/// reducers: one run per start, sampled at `t = 0, T, ..., (samples - 1) T`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulateSpec {
    /// Sampling period `T`.
    pub period: f64,
    /// Samples per run.
    pub samples: usize,
    /// Outputs sampled (`None`: the plan's coordinates).
    #[serde(default)]
    pub outputs: Option<Vec<String>>,
    /// Additive Gaussian noise, relative to each output's largest value
    /// over its run (default 0).
    #[serde(default)]
    pub noise: f64,
    /// Seed of the noise (default 1).
    #[serde(default = "SimulateSpec::default_seed")]
    pub seed: u64,
    /// Relative tolerance of the integrator (default 1e-10).
    #[serde(default = "SimulateSpec::default_rtol")]
    pub rtol: f64,
    /// Absolute tolerance of the integrator (default 1e-12).
    #[serde(default = "SimulateSpec::default_atol")]
    pub atol: f64,
    /// HHT-alpha at this `alpha` instead of Radau IIA (`None`: Radau).
    #[serde(default)]
    pub hht_alpha: Option<f64>,
    /// Where each run starts: on the SSM or at given displacements and
    /// velocities.
    pub runs: Vec<ValidationStart>,
}

impl SimulateSpec {
    /// Relative tolerance when none is asked for.
    pub const DEFAULT_RTOL: f64 = 1e-10;
    /// Absolute tolerance when none is asked for.
    pub const DEFAULT_ATOL: f64 = 1e-12;

    fn default_seed() -> u64 {
        1
    }
    fn default_rtol() -> f64 {
        Self::DEFAULT_RTOL
    }
    fn default_atol() -> f64 {
        Self::DEFAULT_ATOL
    }
}

/// How POD truncates, one reduced model per value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum PodTruncations {
    /// Energy fractions left out.
    Energy(Vec<f64>),
    /// Drops of the normalized POVs in decades.
    Drop(Vec<f64>),
}

impl Default for PodTruncations {
    fn default() -> Self {
        Self::Drop(vec![6.0])
    }
}

impl PodTruncations {
    /// Reduced models asked for.
    pub fn len(&self) -> usize {
        match self {
            Self::Energy(v) | Self::Drop(v) => v.len(),
        }
    }

    /// Whether none is asked for.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One run of the POD study: a harmonic load `eps Fext(Omega t)` (or none),
/// possibly switched in steps, from rest or from given displacements and
/// velocities.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PodRunSpec {
    /// Forcing amplitude (default 0: a free run).
    #[serde(default)]
    pub epsilon: f64,
    /// Forcing frequency (default 0).
    #[serde(default)]
    pub omega: f64,
    /// Length of the run.
    pub t_end: f64,
    /// Given displacements and velocities `(state name, value)`, the others
    /// zero (default: rest).
    #[serde(default)]
    pub start: Vec<(String, f64)>,
    /// A piecewise-constant load in time, steps `(t_k, a_k)` with rising
    /// `t_k`: from `t_k` on the load is `a_k eps Fext(Omega t)`, before the
    /// first step there is none (default: no steps, `eps Fext` throughout).
    #[serde(default)]
    pub steps: Vec<(f64, f64)>,
}

/// POD with generalized constraint reduction of the model, from a training
/// run, compared with the full model on the training and test loads
/// (`[pod]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PodSpec {
    /// Truncations (default: one model at a drop of 6 decades).
    #[serde(default)]
    pub truncations: PodTruncations,
    /// Relative singular-value threshold of the constraint reduction
    /// (default 1e-8).
    #[serde(default = "PodSpec::default_rank_tol")]
    pub rank_tol: f64,
    /// Snapshots at which the projected constraint Jacobian is stacked
    /// (default 64).
    #[serde(default = "PodSpec::default_jacobian_samples")]
    pub jacobian_samples: usize,
    /// Training tolerances of DEIM hyper-reductions: one more model per
    /// truncation and tolerance (default: none).
    #[serde(default)]
    pub hyper: Vec<f64>,
    /// Fixed HHT step of every run.
    pub step: f64,
    /// HHT `alpha` in `[-1/3, 0]` (default -0.1).
    #[serde(default = "PodSpec::default_hht_alpha")]
    pub hht_alpha: f64,
    /// Outputs compared (`None`: the plan's coordinates).
    #[serde(default)]
    pub outputs: Option<Vec<String>>,
    /// Master pair sets of SSM reduced models run on the same loads.
    #[serde(default)]
    pub ssm_pairs: Vec<Vec<usize>>,
    /// Expansion order of those SSM models (`None`: the SSM's `order`, else 5).
    #[serde(default)]
    pub ssm_order: Option<usize>,
    /// The training run.
    pub train: PodRunSpec,
    /// Loads the reduced models were not trained on.
    #[serde(default)]
    pub tests: Vec<PodRunSpec>,
}

impl PodSpec {
    /// `rank_tol` when none is asked for.
    pub const DEFAULT_RANK_TOL: f64 = 1e-8;
    /// `jacobian_samples` when none are asked for.
    pub const DEFAULT_JACOBIAN_SAMPLES: usize = 64;
    /// `hht_alpha` when none is asked for.
    pub const DEFAULT_HHT_ALPHA: f64 = -0.1;

    fn default_rank_tol() -> f64 {
        Self::DEFAULT_RANK_TOL
    }
    fn default_jacobian_samples() -> usize {
        Self::DEFAULT_JACOBIAN_SAMPLES
    }
    fn default_hht_alpha() -> f64 {
        Self::DEFAULT_HHT_ALPHA
    }

    /// The expansion order of the SSM models, with the SSM's `order`.
    pub fn ssm_order(&self, order: Option<usize>) -> usize {
        self.ssm_order.or(order).unwrap_or(5)
    }
}
