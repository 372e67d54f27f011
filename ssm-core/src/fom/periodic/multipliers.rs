//! Floquet multipliers of a periodic orbit, whichever method computed them
//! (Hill's method, [`super::floquet`]; the monodromy matrix,
//! [`super::monodromy`]): the result, its errors, the check of one method
//! against the other, and the tolerances on the unit circle.

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
    /// `UNIT_CIRCLE_TOL`).
    pub unstable: usize,
}

/// A multiplier counts as outside the unit circle when `|rho| > 1 + tol`.
pub(crate) const UNIT_CIRCLE_TOL: f64 = 1e-7;

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
    pub(crate) fn real_crossing_test(&self) -> f64 {
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
    pub(crate) fn complex_unstable(&self) -> usize {
        self.multipliers
            .iter()
            .filter(|r| !is_real(r) && r.norm() > 1.0 + UNIT_CIRCLE_TOL)
            .count()
    }

    /// Why these data cannot be one analysis (as read back from a file):
    /// multipliers that are not finite, exponents not one per multiplier, or
    /// an unstable count other than the multipliers outside the circle.
    pub(crate) fn inconsistency(&self) -> Option<String> {
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
pub(crate) const CHECK_FLOOR: f64 = 1e-2;

impl Floquet {
    /// The largest distance from a multiplier above `CHECK_FLOOR` of either
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
pub(crate) const CHECK_WARNING: f64 = 1e-3;

/// Real up to the accuracy of the exponents: Hill's method returns the
/// exponent of a real negative multiplier on the strip's edge with an
/// imaginary part off by about 1e-9 relative (measured on the spatial
/// oscillator), so `1e-6` separates them from genuine complex pairs, which
/// are only this close to the real axis just before two of them collide
/// (where counting both as real changes no sign of the test function).
fn is_real(r: &C64) -> bool {
    r.im.abs() <= 1e-6 * r.norm().max(1.0)
}
