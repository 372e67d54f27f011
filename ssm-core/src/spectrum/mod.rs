//! Finite spectrum of the linear pencil `A v = lambda B v` (eq. 6), with `B`
//! possibly singular (constraint modes, recast auxiliaries), master modes with
//! right and left eigenvectors, spectral quotients and non-resonance checks.
//!
//! Only finite eigenvalues count: the `3 n_c` infinite eigenvalues of a
//! constrained mechanical system (eq. 87) are constraint modes, never master
//! modes, and never enter resonance checks (Remark 1).
//!
//! Two paths, chosen automatically ([`DENSE_LIMIT`]) or by the scene:
//! - [`dense`]: shift-invert of the whole pencil and a dense eigensolver, all finite eigenvalues;
//! - [`sparse`]: shift-invert Krylov-Schur on `(A - sigma B)^{-1} B` with a sparse
//!   LU, only the requested modes nearest `sigma`, no dense `N x N` storage.
//!
//! Master modes are then polished by inverse iteration with a complex sparse LU
//! of `A - lambda B` (right vector) and its adjoint (left vector), and scaled by
//! a [`Normalization`].
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), eqs. (6)-(7), (53)-(58),
//! Appendix D.

pub mod dense;
mod krylov;
pub mod modes;
mod normalization;
pub(crate) mod resonance;
pub mod sparse;

use crate::C64;

pub use modes::{master_modes, MasterMode};
pub use normalization::Normalization;
pub use resonance::{check_resonances, ResonanceReport, SpectralQuotients};
pub use ssm_kernel::sparse_lu::SolveCounts;

/// Largest number of states for which `auto` uses the dense path.
pub const DENSE_LIMIT: usize = 100;

/// Why a spectrum could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectrumError {
    /// The dense eigenvalue iteration did not converge.
    #[error("dense eigenvalue iteration did not converge for the {n}x{n} pencil (A, B)")]
    NoConvergence {
        /// Pencil size.
        n: usize,
    },
    /// The pencil is singular (`det(lambda B - A) = 0` for all lambda): e.g.
    /// redundant constraints or a state that appears nowhere.
    #[error("the pencil (A, B) is singular: {detail}. The model has no well-defined dynamics: look for redundant constraints (the constraint Jacobian G0 must have full row rank), a mass matrix that is singular in a direction no constraint fixes, or a state that appears in no equation; changing [spectrum] shift cannot help")]
    SingularPencil {
        /// What was observed.
        detail: String,
    },
    /// `A - sigma B` is singular at the chosen shift (and regular elsewhere:
    /// the shift is an eigenvalue). [`compute`] names a shift that works.
    #[error("A - sigma B is singular at sigma = {shift} ({detail}): the shift is an eigenvalue of the model{}", match suggestion { Some(s) => format!("; set [spectrum] shift = {s:.6}, where A - sigma B is regular"), None => String::new() })]
    SingularShift {
        /// The shift.
        shift: f64,
        /// Factorization detail.
        detail: String,
        /// A shift at which `A - sigma B` was found regular.
        suggestion: Option<f64>,
    },
    /// The dense path failed where the sparse path succeeds (a stiff pencil).
    #[error("the dense path failed on this pencil ({detail}), while the sparse path computes its spectrum: the pencil is too stiff for the dense path's rank decisions, not singular; set [spectrum] method = \"sparse\" or \"auto\"")]
    DenseTooStiff {
        /// The dense path's error.
        detail: String,
    },
    /// The Krylov iteration found fewer modes than requested.
    #[error("sparse eigen-solver converged on {found} of {requested} modes; raise [spectrum] modes or choose a shift closer to the wanted modes")]
    NotConverged {
        /// Modes found.
        found: usize,
        /// Modes requested.
        requested: usize,
    },
    /// Fewer complex mode pairs than the master pairs ask for.
    #[error("master pair {pair} requested, but only {available} underdamped mode pairs were found{hint}")]
    PairOutOfRange {
        /// 1-based pair asked for.
        pair: usize,
        /// Pairs available.
        available: usize,
        /// What to do.
        hint: String,
    },
    /// Mass normalization needs a mechanical model.
    #[error("normalization = \"mass\" needs a model with a mass matrix (built with the mechanical builder); use \"unit\"")]
    NoMassMatrix,
    /// Inverse iteration produced a non-finite or zero vector.
    #[error("eigenvector of lambda = {:.6e} {:+.6e}i could not be computed ({detail}); the model's entries may span more magnitudes than double precision resolves (rescale its units)", lambda.re, lambda.im)]
    Eigenvector {
        /// Eigenvalue.
        lambda: C64,
        /// What happened.
        detail: String,
    },
}

/// Which solver produced a spectrum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Dense eigensolver.
    Dense,
    /// Sparse shift-invert Krylov-Schur.
    Sparse,
}

impl Method {
    /// Lower-case name for reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Dense => "dense",
            Self::Sparse => "sparse",
        }
    }
}

/// Finite eigenvalues, sorted by real part descending (slowest first), complex
/// conjugate pairs adjacent with the positive imaginary part first.
#[derive(Debug, Clone)]
pub struct Spectrum {
    /// Finite eigenvalues in order.
    pub eigenvalues: Vec<C64>,
    /// True when every finite eigenvalue of the pencil is listed (dense path).
    pub complete: bool,
    /// Solver used.
    pub method: Method,
    /// The factorizations of the shifted pencil (sparse: symbolic and
    /// numeric; dense: numeric only) and the solves with them (one per
    /// right-hand side).
    pub work: SolveCounts,
}

/// What a structural dynamicist reads off one finite eigenvalue `lambda`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModalFigures {
    /// The eigenvalue.
    pub lambda: C64,
    /// `|lambda|`, the undamped natural frequency of an underdamped pair.
    pub abs: f64,
    /// `|Im lambda|`, the damped frequency.
    pub frequency: f64,
    /// `-Re lambda / |lambda|` (0 at `lambda = 0`).
    pub damping_ratio: f64,
}

impl Spectrum {
    /// [`ModalFigures`] of every eigenvalue, in order.
    pub fn modal_figures(&self) -> Vec<ModalFigures> {
        self.eigenvalues
            .iter()
            .map(|&lambda| {
                let abs = lambda.norm();
                ModalFigures {
                    lambda,
                    abs,
                    frequency: lambda.im.abs(),
                    damping_ratio: if abs > 0.0 { -lambda.re / abs } else { 0.0 },
                }
            })
            .collect()
    }
}

/// Options for [`compute`].
#[derive(Debug, Clone)]
pub struct SpectrumOptions {
    /// Force a path (`None`: dense up to [`DENSE_LIMIT`] states).
    pub method: Option<Method>,
    /// Number of finite eigenvalues wanted on the sparse path.
    pub modes: usize,
    /// Shift of the sparse path.
    pub shift: f64,
    /// Eigenvector scaling of master modes.
    pub normalization: Normalization,
    /// The velocities of a mechanical model ([`System::velocities`]): where
    /// the pencil has their structure, the sparse path factorizes the
    /// condensed pencil, half the size. `None` factorizes `A - sigma B`.
    ///
    /// [`System::velocities`]: crate::model::system::System::velocities
    pub velocities: Option<std::ops::Range<usize>>,
}

/// Computes the finite spectrum of `(A, B)`.
pub fn compute(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    b: faer::sparse::SparseColMatRef<'_, usize, f64>,
    opts: &SpectrumOptions,
) -> Result<Spectrum, SpectrumError> {
    let n = a.nrows();
    let method = opts.method.unwrap_or(if n <= DENSE_LIMIT {
        Method::Dense
    } else {
        Method::Sparse
    });
    let found = match method {
        // one dense LU of A - sigma B, solved for the n columns of B
        Method::Dense => dense::finite_eigenvalues(a, b, opts.shift).map(|v| {
            let work = SolveCounts {
                factorizations: 1,
                solves: a.nrows(),
                ..SolveCounts::default()
            };
            (v, work)
        }),
        Method::Sparse => {
            sparse::eigenvalues_near_shift(a, b, opts.velocities.clone(), opts.shift, opts.modes)
        }
    };
    let (mut eigenvalues, work) = match found {
        Err(SpectrumError::SingularShift { shift, detail, .. }) => {
            return Err(diagnose_singular_shift(a, b, shift, detail))
        }
        other => other?,
    };
    sort_spectrum(&mut eigenvalues);
    Ok(Spectrum {
        eigenvalues,
        complete: method == Method::Dense,
        method,
        work,
    })
}

/// Tells a shift that happens to be an eigenvalue from a singular pencil
/// (`det(lambda B - A) = 0` for every `lambda`: a singular mass matrix in a
/// direction no constraint fixes, redundant constraints, a state in no
/// equation). `A - sigma B` is probed at two more shifts, apart from `shift`
/// by irrational multiples of `1 + |shift|`: a regular pencil has finitely many
/// eigenvalues and is regular at both with probability one, while a singular
/// pencil is singular at every shift, so advice to change the shift would
/// send the user in a circle.
fn diagnose_singular_shift(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    b: faer::sparse::SparseColMatRef<'_, usize, f64>,
    shift: f64,
    detail: String,
) -> SpectrumError {
    let scale = 1.0 + shift.abs();
    let probes = [shift - 0.739_085_133 * scale, shift + 1.324_717_957 * scale];
    match probes.into_iter().find(|&s| sparse::is_regular_at(a, b, s)) {
        Some(s) => SpectrumError::SingularShift {
            shift,
            detail,
            suggestion: Some(s),
        },
        None => SpectrumError::SingularPencil {
            detail: format!(
                "A - sigma B is singular at sigma = {shift} and at the probes {:.4} and {:.4} ({detail}), so at every shift",
                probes[0], probes[1]
            ),
        },
    }
}

/// Relative size below which an imaginary part counts as zero (real eigenvalue).
const REAL_TOL: f64 = 1e-10;

/// True when `l` is (numerically) real.
pub(crate) fn is_real(l: C64) -> bool {
    l.im.abs() <= REAL_TOL * l.norm().max(f64::MIN_POSITIVE)
}

/// Sorts by real part descending; a conjugate pair is kept together with the
/// positive imaginary part first, pairs with equal real parts by increasing
/// frequency. Conjugate partners are made exact conjugates of each other.
pub(crate) fn sort_spectrum(ev: &mut Vec<C64>) {
    // keep one representative per pair (Im >= 0), then rebuild the partners
    let mut reps: Vec<C64> = Vec::with_capacity(ev.len());
    let mut negatives: Vec<C64> = Vec::new();
    for &l in ev.iter() {
        if is_real(l) {
            reps.push(C64::new(l.re, 0.0));
        } else if l.im > 0.0 {
            reps.push(l);
        } else {
            negatives.push(l);
        }
    }
    // a negative-imaginary eigenvalue whose partner is missing (sparse path at
    // the edge of the computed set) brings its partner in
    for l in negatives {
        let partner = l.conj();
        let tol = 1e-8 * l.norm();
        if !reps.iter().any(|r| (r - partner).norm() <= tol) {
            reps.push(partner);
        }
    }
    reps.sort_by(|x, y| {
        y.re.total_cmp(&x.re)
            .then(x.im.abs().total_cmp(&y.im.abs()))
    });
    ev.clear();
    for r in reps {
        ev.push(r);
        if r.im != 0.0 {
            ev.push(r.conj());
        }
    }
}

/// Sorts the multipliers of a map like `sort_spectrum` sorts eigenvalues
/// of a flow: by `ln |mu|` descending (slowest decay first), pairs adjacent.
pub fn sort_multipliers(ev: &mut Vec<C64>) {
    let mut logs: Vec<C64> = ev.iter().map(|m| m.ln()).collect();
    sort_spectrum(&mut logs);
    *ev = logs.iter().map(|l| l.exp()).collect();
    // exact conjugate partners after the round trip
    for i in 1..ev.len() {
        if ev[i - 1].im > 0.0 && logs[i] == logs[i - 1].conj() {
            ev[i] = ev[i - 1].conj();
        }
    }
}

/// Flow eigenvalues `ln(mu) / T` of map multipliers.
pub fn multipliers_to_rates(mu: &[C64], period: f64) -> Vec<C64> {
    mu.iter().map(|m| m.ln() / period).collect()
}

/// Indices (into a sorted spectrum) of the first eigenvalue of each complex
/// conjugate pair, in order: pair `p` (1-based) is `pairs[p - 1]`.
pub fn pair_starts(ev: &[C64]) -> Vec<usize> {
    ev.iter()
        .enumerate()
        .filter(|(_, l)| l.im > 0.0)
        .map(|(i, _)| i)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorting_puts_slow_first_and_pairs_adjacent() {
        let mut ev = vec![
            C64::new(-0.15, -2.9962),
            C64::new(-0.02, -1.9999),
            C64::new(-0.5, 0.0),
            C64::new(-0.15, 2.9962),
            C64::new(-0.02, 1.9999),
        ];
        sort_spectrum(&mut ev);
        assert_eq!(ev[0], C64::new(-0.02, 1.9999));
        assert_eq!(ev[1], C64::new(-0.02, -1.9999));
        assert_eq!(ev[2], C64::new(-0.15, 2.9962));
        assert_eq!(ev[3], C64::new(-0.15, -2.9962));
        assert_eq!(ev[4], C64::new(-0.5, 0.0));
        assert_eq!(pair_starts(&ev), vec![0, 2]);
    }
}
