//! What a forced response computation returns: the curves' points, their
//! bifurcations and error figures, and why a curve could not be produced.
//! Shared by the one-pair path ([`crate::rom::forced_one_pair`]) and the
//! continuation of several pairs ([`crate::rom::forced_multi`]); the entry
//! point is [`crate::rom::forced_response::forced_response`].

use crate::ssm::analysis::PolarError;
use crate::ssm::forced::ForcedError;
use crate::C64;

/// Why an FRC could not be produced.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrcError {
    /// The periodic SSM failed.
    #[error("forced SSM: {0}")]
    Forced(#[from] ForcedError),
    /// No polar form.
    #[error("FRC: {0}")]
    Polar(#[from] PolarError),
    /// What the FRC path does not cover.
    #[error("FRC: {0}")]
    Unsupported(String),
    /// A curve has no point in the frequency range.
    #[error("FRC O({order}), eps = {}: no response found in the frequency range with amplitudes up to rho_max = {rho_max:e}; every forcing frequency has one, so the amplitude grid missed them: set [forcing] rho_max near the expected peak amplitude (or raise points)", ssm_kernel::number::short(.epsilon))]
    Empty {
        /// Expansion order.
        order: usize,
        /// Forcing amplitude.
        epsilon: f64,
        /// Largest amplitude searched.
        rho_max: f64,
    },
    /// The continuation could not start.
    #[error("FRC: {0}")]
    Continuation(#[from] crate::rom::continuation::ContinuationError),
    /// The spec asks for what cannot be computed.
    #[error("FRC: {0}")]
    Spec(#[from] crate::spec::SpecError),
}

/// One point of a forced response curve.
#[derive(Debug, Clone, PartialEq)]
pub struct FrcRow {
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Forcing frequency.
    pub omega: f64,
    /// Branch number (points of one branch are consecutive, in arc order).
    pub branch: usize,
    /// Stability.
    pub stable: bool,
    /// Polar amplitude `|p|` of the fixed point (all pairs).
    pub rho: f64,
    /// The fixed point `q_j` of each pair in the rotating frame, `p_j(t) =
    /// q_j e^{i r_j Omega t}`: the reduced coordinates at `t = 0`.
    pub q: Vec<C64>,
    /// `|q_j|` of each pair.
    pub pair_amplitudes: Vec<f64>,
    /// Largest `|output|` over the response period, per output.
    pub linf: Vec<f64>,
    /// Amplitude of the first harmonic of each output.
    pub h1: Vec<f64>,
}

impl FrcRow {
    /// The amplitude an FRC is drawn with: the first output's, or `|q_1|`.
    pub fn plotted(&self) -> f64 {
        self.linf
            .first()
            .copied()
            .unwrap_or_else(|| self.pair_amplitudes.first().copied().unwrap_or(self.rho))
    }
}

/// A bifurcation (or branch point) located on a forced response curve.
#[derive(Debug, Clone, PartialEq)]
pub struct FrcBifurcation {
    /// `"SN"`, `"HB"`, `"BP"`, ...
    pub kind: &'static str,
    /// Forcing frequency.
    pub omega: f64,
    /// Branch it lies on.
    pub branch: usize,
    /// `|q_j|` of each pair there.
    pub rho: Vec<f64>,
    /// Drawn amplitude of the nearest computed point of its branch.
    pub plotted: Option<f64>,
}

/// What is known of one curve beyond its points.
#[derive(Debug, Clone, PartialEq)]
pub enum CurveDetails {
    /// One pair: fixed points on an amplitude grid, with error figures.
    OnePair {
        /// Largest polar amplitude on the curve.
        rho_peak: f64,
        /// Eq. (41) at `rho_peak`.
        invariance_error_at_peak: Option<f64>,
        /// Largest eq. (60) residual along the peak's periodic orbit.
        residual_eq60_at_peak: Option<f64>,
        /// Estimated relative error of the response amplitude: the largest
        /// resonant part `|u^* r|` of that residual over the resonant load
        /// `eps |u^* Fext|` (NaN or infinite when the expansion diverged).
        error_estimate: f64,
        /// Order of the non-autonomous terms used.
        nonautonomous_order: usize,
    },
    /// Several pairs: continuation (the shared core) with branch switching.
    Continuation {
        /// Branches switched to at branch points.
        branch_switches: usize,
        /// Continuation steps over all branches.
        continuation_steps: usize,
        /// Estimated relative error of the response: the largest over the
        /// branches' peaks of the distance to the curve two orders lower
        /// (an upper estimate while the expansion converges; infinite where
        /// the lower order has no branch, NaN below O(3)). The truncation of
        /// the non-autonomous terms at leading order is not in this figure.
        error_estimate: f64,
    },
}

/// One forced response curve: an expansion order and a forcing amplitude.
#[derive(Debug, Clone, PartialEq)]
pub struct FrcCurve {
    /// Expansion order.
    pub order: usize,
    /// Forcing amplitude.
    pub epsilon: f64,
    /// Points written (inside the frequency range).
    pub points: usize,
    /// Branches.
    pub branches: usize,
    /// Bifurcations inside the frequency range.
    pub bifurcations: Vec<FrcBifurcation>,
    /// Method-specific figures.
    pub details: CurveDetails,
    /// The curve's error estimate exceeds the accuracy target.
    pub untrusted: bool,
}

impl FrcCurve {
    /// The curve's estimated relative error (NaN or infinite when the
    /// expansion diverged).
    pub fn error_estimate(&self) -> f64 {
        match self.details {
            CurveDetails::OnePair { error_estimate, .. }
            | CurveDetails::Continuation { error_estimate, .. } => error_estimate,
        }
    }
}

/// Everything `[forcing]` produced.
#[derive(Debug, Clone, PartialEq)]
pub struct ForcedResponse {
    /// Names of the outputs of `linf` and `h1`.
    pub outputs: Vec<String>,
    /// All points, curve after curve.
    pub rows: Vec<FrcRow>,
    /// The curves, in the order of `rows`.
    pub curves: Vec<FrcCurve>,
    /// External resonance ratios `r_j` (eq. 16).
    pub resonance: Vec<f64>,
    /// Largest polar amplitude searched (one pair).
    pub rho_max: Option<f64>,
    /// Resonant forcing `u_j^* Fext` on each master pair.
    pub forcing_on_master: Vec<C64>,
    /// Terms left out or other caveats.
    pub warnings: Vec<String>,
    /// The sparse linear algebra with the full system's matrices: the
    /// leading-order terms at each frequency solved or tabulated, the
    /// non-autonomous terms at their nodes.
    pub linear: crate::ssm::SolveCounts,
    /// The most heap its sparse factors held at once, in bytes, as the
    /// allocator counted it (`None` where it does not count).
    pub factor_bytes: Option<usize>,
}
