//! The full system's amplitude response at a fixed forcing frequency: the
//! harmonic-balance orbits traced in the forcing amplitude `eps` by the
//! shared continuation core, with Floquet stability and the located folds
//! (jumps as the load grows or shrinks), period doublings, Neimark-Sacker and
//! branch points.
//!
//! The branch starts at the low end of the amplitude range: from rest when
//! it is `eps = 0` (the equilibrium is the orbit there), else from the linear
//! response, corrected by Newton. The residual is affine in `eps`, `R =
//! R_0(c) - eps P Fext(Z(c), psi)`, so the parameter's Jacobian column is the
//! projected forcing itself. The coefficients are scaled by the largest
//! coefficient of the linear response at the top of the range, the forcing
//! amplitude by the range's width.
//!
//! # References
//! M. Krack, J. Gross, *Harmonic Balance for Nonlinear Vibration Problems*,
//! Springer (2019), Sect. 4.2 (continuation in any parameter); A. H. Nayfeh,
//! D. T. Mook, *Nonlinear Oscillations*, Wiley (1979), Sect. 4.1.4 (the
//! amplitude response of the Duffing oscillator and its jumps).

use crate::model::system::{OutputMap, System};
use ssm_kernel::continuation::{solve_at_parameter, NoLedger, Settings};

use super::branch::{classify, orbits_at, Reader, ReferenceBranch, ReferenceError, ReferenceOrbit};
use super::frc::check_flow;
use super::runs::Runs;
use super::{HarmonicBalance, Parameter};

/// Settings of a reference amplitude response.
#[derive(Debug, Clone, PartialEq)]
pub struct AmplitudeSettings {
    /// The fixed forcing frequency `Omega`.
    pub omega: f64,
    /// `[eps_min, eps_max]`, `eps_min >= 0`; the branch starts at `eps_min`.
    pub epsilon_range: (f64, f64),
    /// Harmonics `H`.
    pub harmonics: usize,
    /// Largest arclength step in scaled unknowns (amplitude by the linear
    /// response at `eps_max`, the forcing amplitude by the range's width).
    pub step: f64,
    /// Newton tolerance (relative update).
    pub tol: f64,
    /// Largest number of continuation steps.
    pub max_steps: usize,
    /// Outputs whose amplitudes are reported.
    pub outputs: Vec<OutputMap>,
    /// Forcing amplitudes at which the orbits of the branch are also solved
    /// exactly (every crossing of the branch).
    pub points_at: Vec<f64>,
    /// Floquet multipliers at each orbit: stability and the bifurcations
    /// they locate.
    pub stability: bool,
}

/// The reference amplitude response of `sys` at the frequency of
/// `settings`, numbered `number`; `observe` sees each orbit as it is
/// accepted and returns `false` to stop. Period doublings are located and
/// noted; the branch of period `2T` is switched to only in `Omega`
/// ([`super::reference_frc`]).
pub fn reference_amplitude<O>(
    sys: &System,
    settings: &AmplitudeSettings,
    number: usize,
    observe: O,
) -> Result<ReferenceBranch, ReferenceError>
where
    O: FnMut(&ReferenceOrbit) -> bool,
{
    reference_amplitude_resumable(sys, settings, number, &mut Runs::new(&NoLedger, observe))
}

/// [`reference_amplitude`] with its continuation run kept in (and,
/// resuming a stopped computation, restored from) the ledger of `runs`.
pub fn reference_amplitude_resumable(
    sys: &System,
    settings: &AmplitudeSettings,
    number: usize,
    runs: &mut Runs<'_>,
) -> Result<ReferenceBranch, ReferenceError> {
    let (lo, hi) = settings.epsilon_range;
    let omega = settings.omega;
    if !(omega.is_finite() && omega > 0.0) {
        return Err(ReferenceError::Settings(format!(
            "the frequency {omega} of an amplitude response must be finite and positive",
            omega = ssm_kernel::number::short(omega)
        )));
    }
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
        return Err(ReferenceError::Settings(format!(
            "epsilon_range [{lo}, {hi}] must be finite, non-negative and increasing"
        )));
    }
    check_flow(sys, settings.harmonics)?;
    // prepared at eps_max > 0, so that the forcing's terms are in it
    let mut hb = HarmonicBalance::new(sys, hi, settings.harmonics, 1)?;
    hb.parameter = Parameter::Amplitude { omega };
    hb.epsilon_scale = hi - lo;
    hb.stability = settings.stability;
    let nu = hb.n_coefficients();
    let cs = Settings {
        tol: settings.tol,
        max_steps: settings.max_steps,
        ..Settings::new((lo / (hi - lo), hi / (hi - lo)), settings.step)
    };
    // one Newton step from rest at eps_max is the linear response there; its
    // largest coefficient is the amplitude scale
    let lin = Settings {
        max_newton: 1,
        tol: f64::INFINITY,
        ..cs
    };
    let rest = hb.scale(&vec![0.0; nu], hi);
    let top = solve_at_parameter(&mut hb, rest, &lin)?;
    let (c_top, _) = hb.unscale(&top);
    let scale = c_top.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return Err(ReferenceError::Settings(format!(
            "the linear response at Omega = {omega}, eps = {hi} is {scale}: no forcing reaches the model", omega = ssm_kernel::number::short(omega)
        )));
    }
    hb.amplitude_scale = scale;
    // the linear response at eps_min (rest at eps_min = 0), then Newton
    let guess: Vec<f64> = c_top.iter().map(|v| v * lo / hi).collect();
    let guess = hb.scale(&guess, lo);
    let u0 = solve_at_parameter(&mut hb, guess, &cs)?;
    let mut t0 = vec![0.0; nu + 1];
    t0[nu] = 1.0;
    let reader = Reader::of(&hb, lo, &settings.outputs);
    let branch = runs.trace(&mut hb, u0, &t0, &cs, &reader, number, true)?;
    let at = orbits_at(
        &mut hb,
        &branch.points,
        &settings.points_at,
        &cs,
        &reader,
        number,
    );
    let (orbits, events, doublings) = classify(&branch, &reader, number);
    let notes = doublings
        .iter()
        .map(|pd| {
            format!(
                "period doubling at Omega = {omega}, eps = {:e}: the branch of period 2T is traced only in a continuation in Omega",
                pd.parameter() * hb.epsilon_scale, omega = ssm_kernel::number::short(omega)
            )
        })
        .collect();
    Ok(ReferenceBranch {
        notes,
        ..ReferenceBranch::traced(&mut hb, &branch.points, orbits, events, branch.stop, at)
    })
}
