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

pub use super::multipliers::{Floquet, FloquetError, MultiplierCheck, MAX_HILL_COEFFICIENTS};
pub(crate) use super::multipliers::{CHECK_WARNING, UNIT_CIRCLE_TOL};

use super::HarmonicBalance;
use crate::spectrum::dense::{finite_eigenvalues_with, FiniteStructure};
use crate::C64;

/// Hill's method at the orbit `c` at `omega`.
pub fn floquet(hb: &HarmonicBalance<'_>, c: &[f64], omega: f64) -> Result<Floquet, FloquetError> {
    floquet_with(hb, c, omega, &mut None)
}

/// [`floquet`] reusing the structure of the Hill pencil's nilpotent part
/// found at an earlier orbit of the same discretization (set on the first
/// call).
pub(crate) fn floquet_with(
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
