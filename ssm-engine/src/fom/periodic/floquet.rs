//! Floquet exponents and multipliers of a harmonic-balance orbit by Hill's
//! method.
//!
//! A perturbation `e^(mu t) p(psi)` of the orbit, `p` periodic, satisfies
//! `B (mu p + (Omega/m) p_psi) = J(psi) p`, whose Galerkin projection on the
//! orbit's `2H + 1` Fourier functions is the generalized eigenproblem
//!
//! `-R_c P = mu (I ⊗ B) P`,
//!
//! with `R_c` the harmonic-balance Jacobian ([`super::HarmonicBalance`]). Its
//! finite eigenvalues approximate each Floquet exponent `mu` together with its
//! copies `mu + i k Omega / m`; the infinite ones are the algebraic rows
//! (constraints and recast auxiliaries), removed exactly by the dense pencil
//! path ([`crate::spectrum::dense::finite_eigenvalues`]), which handles their
//! index-3 nilpotent structure. One copy of each exponent is kept: the one in
//! the strip `-Omega/(2m) <= Im mu < Omega/(2m)` (the copies nearest the
//! centre are the most accurate ones, Krack & Gross Sect. 4.2), and the
//! multipliers are `exp(mu m T)`. A real negative multiplier has its exponent
//! on the strip's edge, so the edge is half-open, with a tolerance.
//!
//! This path is dense in `N (2H + 1)` and limited to
//! [`MAX_HILL_COEFFICIENTS`] coefficients; larger orbits get their
//! multipliers from the monodromy matrix ([`super::monodromy`]).
//!
//! # References
//! M. Krack, J. Gross, *Harmonic Balance for Nonlinear Vibration Problems*,
//! Springer (2019), Sect. 4.2 (Hill's method and the choice of exponents);
//! G. W. Hill, On the part of the motion of the lunar perigee which is a
//! function of the mean motions of the sun and moon, Acta Math. 8 (1886);
//! B. Deconinck, J. N. Kutz, Computing spectra of linear operators using the
//! Floquet-Fourier-Hill method, J. Comput. Phys. 219 (2006) 296-321.

use super::HarmonicBalance;
use crate::spectrum::dense::{finite_eigenvalues_with, FiniteStructure};
use crate::C64;

/// Largest `N (2H + 1)` for which the dense Hill eigenproblem is solved;
/// above it the multipliers come from the monodromy matrix
/// ([`super::monodromy`]) up to its own limit.
pub const MAX_HILL_COEFFICIENTS: usize = 1500;

/// Why no Floquet multipliers were computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FloquetError {
    /// The dense Hill eigenproblem and the monodromy matrix are too large.
    #[error("Floquet multipliers: {coefficients} Fourier coefficients exceed the dense Hill limit {limit}, and the states the monodromy limit")]
    TooLarge {
        /// `N (2H + 1)`.
        coefficients: usize,
        /// [`MAX_HILL_COEFFICIENTS`].
        limit: usize,
    },
    /// The eigenvalue computation failed.
    #[error("Floquet multipliers: the Hill eigenproblem failed: {0}")]
    Spectrum(String),
}

/// Floquet exponents and multipliers of an orbit.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Floquet {
    /// One exponent per finite mode, in the central strip.
    pub exponents: Vec<C64>,
    /// `exp(mu m T)`.
    pub multipliers: Vec<C64>,
    /// Number of multipliers outside the unit circle (by more than
    /// [`UNIT_CIRCLE_TOL`]).
    pub unstable: usize,
}

/// A multiplier counts as outside the unit circle when `|rho| > 1 + tol`.
pub const UNIT_CIRCLE_TOL: f64 = 1e-7;

impl Floquet {
    /// No multiplier outside the unit circle.
    pub fn stable(&self) -> bool {
        self.unstable == 0
    }

    /// Largest `|rho|`.
    pub fn max_modulus(&self) -> f64 {
        self.multipliers
            .iter()
            .map(|r| r.norm())
            .fold(0.0, f64::max)
    }

    /// The test function of real multipliers crossing the unit circle
    /// (folds and branch points through `+1`, period doublings through
    /// `-1`): `(-1)^k`, `k` the number of real multipliers outside the
    /// circle, times the smallest `|ln |rho||` among the real multipliers.
    /// It is continuous and vanishes where a real multiplier is on the
    /// circle; two real multipliers merging into a complex pair change `k` by
    /// 0 or 2, not its sign, and multipliers deep inside the circle (which
    /// the monodromy path drops below a threshold) do not enter it.
    pub fn real_crossing_test(&self) -> f64 {
        let mut sign = 1.0;
        let mut near = f64::INFINITY;
        for r in self.multipliers.iter().filter(|r| is_real(r)) {
            let l = r.norm().ln();
            if l > 0.0 {
                sign = -sign;
            }
            near = near.min(l.abs());
        }
        if near.is_finite() {
            sign * near
        } else {
            1.0
        }
    }

    /// Number of complex (non-real) multipliers outside the unit circle:
    /// its changes are Neimark-Sacker bifurcations.
    pub fn complex_unstable(&self) -> usize {
        self.multipliers
            .iter()
            .filter(|r| !is_real(r) && r.norm() > 1.0 + UNIT_CIRCLE_TOL)
            .count()
    }

    /// Why these data cannot be one analysis (as read back from a file):
    /// multipliers that are not finite, exponents not one per multiplier, or
    /// an unstable count other than the multipliers outside the circle.
    pub fn inconsistency(&self) -> Option<String> {
        if self.exponents.len() != self.multipliers.len() {
            return Some(format!(
                "{} exponents for {} multipliers",
                self.exponents.len(),
                self.multipliers.len()
            ));
        }
        if self
            .multipliers
            .iter()
            .chain(&self.exponents)
            .any(|r| !(r.re.is_finite() && r.im.is_finite()))
        {
            return Some("a multiplier or exponent is not finite".into());
        }
        let outside = self
            .multipliers
            .iter()
            .filter(|r| r.norm() > 1.0 + UNIT_CIRCLE_TOL)
            .count();
        (outside != self.unstable).then(|| {
            format!(
                "{} unstable multipliers stated, {outside} of its multipliers are outside the unit circle",
                self.unstable
            )
        })
    }

    /// The real (`real = true`) or complex multiplier nearest the unit
    /// circle.
    pub fn critical(&self, real: bool) -> Option<C64> {
        self.multipliers
            .iter()
            .filter(|r| is_real(r) == real)
            .min_by(|a, b| (a.norm() - 1.0).abs().total_cmp(&(b.norm() - 1.0).abs()))
            .copied()
    }
}

/// Multipliers above this modulus enter [`Floquet::distance`]: their
/// partners in another computation are above the monodromy's
/// [`super::monodromy::DOMINANT_FLOOR`] unless the two differ by more than
/// `1e-2`, which the distance then shows.
pub const CHECK_FLOOR: f64 = 1e-2;

impl Floquet {
    /// The largest distance from a multiplier above [`CHECK_FLOOR`] of either
    /// set to the nearest multiplier of the other: the disagreement of two
    /// computations of the same orbit's multipliers (0 when neither has one
    /// above the floor).
    pub fn distance(&self, other: &Floquet) -> f64 {
        let one_way = |a: &[C64], b: &[C64]| {
            a.iter()
                .filter(|x| x.norm() > CHECK_FLOOR)
                .map(|x| {
                    b.iter()
                        .map(|y| (x - y).norm())
                        .fold(f64::INFINITY, f64::min)
                })
                .fold(0.0, f64::max)
        };
        one_way(&self.multipliers, &other.multipliers)
            .max(one_way(&other.multipliers, &self.multipliers))
    }
}

/// A branch's multipliers computed again at its orbit whose largest
/// multiplier is nearest the unit circle, by the monodromy map with twice
/// its default steps: independent of Hill's method where that gave them
/// (the difference is then Hill's truncation error), and their Richardson
/// partner where the monodromy map gave them (the error falls as `h^5`, so
/// the difference is the default steps' error to 3 %).
#[derive(Debug, Clone, PartialEq)]
pub struct MultiplierCheck {
    /// The checked orbit's frequency.
    pub omega: f64,
    /// Its forcing amplitude.
    pub epsilon: f64,
    /// Steps per period of the check.
    pub steps: usize,
    /// [`Floquet::distance`] of the branch's multipliers from the check's.
    pub difference: f64,
    /// Orbits of the branch whose largest multiplier is within `difference`
    /// of the unit circle: their stable flag is not vouched for.
    pub uncertain_orbits: usize,
}

/// A [`MultiplierCheck::difference`] above this is a warning: the
/// multipliers are uncertain to more than the tolerance on located
/// bifurcations (1e-3), and stability near the unit circle with them.
pub const CHECK_WARNING: f64 = 1e-3;

/// Real up to the accuracy of the exponents: Hill's method returns the
/// exponent of a real negative multiplier on the strip's edge with an
/// imaginary part off by about 1e-9 relative (measured on the spatial
/// oscillator), so `1e-6` separates them from genuine complex pairs, which
/// are only this close to the real axis just before two of them collide
/// (where counting both as real changes no sign of the test function).
fn is_real(r: &C64) -> bool {
    r.im.abs() <= 1e-6 * r.norm().max(1.0)
}

/// Hill's method at the orbit `c` at `omega`.
pub fn floquet(hb: &HarmonicBalance<'_>, c: &[f64], omega: f64) -> Result<Floquet, FloquetError> {
    floquet_with(hb, c, omega, &mut None)
}

/// [`floquet`] reusing the structure of the Hill pencil's nilpotent part
/// found at an earlier orbit of the same discretization (set on the first
/// call).
pub fn floquet_with(
    hb: &HarmonicBalance<'_>,
    c: &[f64],
    omega: f64,
    structure: &mut Option<FiniteStructure>,
) -> Result<Floquet, FloquetError> {
    let nu = hb.n_coefficients();
    if nu > MAX_HILL_COEFFICIENTS {
        return super::monodromy::floquet_by_monodromy(hb, c, omega, None);
    }
    let m = hb.period_multiple() as f64;
    let wb = omega / m;
    let rc = hb.jacobian_physical(c, omega);
    let neg: Vec<faer::sparse::Triplet<usize, usize, f64>> = (0..nu)
        .flat_map(|j| {
            rc.as_ref()
                .row_idx_of_col(j)
                .zip(rc.as_ref().val_of_col(j))
                .map(move |(i, v)| faer::sparse::Triplet::new(i, j, -v))
                .collect::<Vec<_>>()
        })
        .collect();
    let a = faer::sparse::SparseColMat::try_new_from_triplets(nu, nu, &neg)
        .map_err(|e| FloquetError::Spectrum(format!("{e:?}")))?;
    let b = hb.mass_blocks();
    // shifts that are no exponent: odd fractions of Omega/m
    let mut last = String::new();
    let mut all = None;
    for shift in [0.3371 * wb, -0.2713 * wb, 1.4171 * wb] {
        match finite_eigenvalues_with(a.as_ref(), b.as_ref(), shift, structure) {
            Ok(v) => {
                all = Some(v);
                break;
            }
            Err(e) => last = e.to_string(),
        }
    }
    let all = all.ok_or(FloquetError::Spectrum(last))?;
    let kk = 2 * hb.harmonics() + 1;
    let wanted = (all.len() as f64 / kk as f64).round() as usize;
    let edge = 1e-6 * wb;
    let mut exps: Vec<C64> = all
        .iter()
        .filter(|l| l.im >= -0.5 * wb - edge && l.im < 0.5 * wb - edge)
        .copied()
        .collect();
    if exps.len() != wanted {
        // the strip holds a copy too many or too few (inaccurate high
        // copies): keep the `wanted` nearest the real axis
        let mut sorted = all.clone();
        sorted.sort_by(|x, y| x.im.abs().total_cmp(&y.im.abs()));
        exps = sorted.into_iter().take(wanted).collect();
    }
    let period = 2.0 * std::f64::consts::PI * m / omega;
    let multipliers: Vec<C64> = exps.iter().map(|mu| (mu * period).exp()).collect();
    let unstable = multipliers
        .iter()
        .filter(|r| r.norm() > 1.0 + UNIT_CIRCLE_TOL)
        .count();
    Ok(Floquet {
        exponents: exps,
        multipliers,
        unstable,
    })
}
