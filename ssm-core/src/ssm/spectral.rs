//! What an SSM needs of the spectrum, computed once per run: the finite
//! spectrum of the pencil with the spec's options (falling back to the
//! sparse path where the dense one fails on a stiff pencil, widened on the
//! sparse path until it covers the resonances up to the expansion order),
//! the master modes, and the non-resonance checks, with the warnings a user
//! must see.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//! systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 3.2
//! (eqs. 53-58: the spectral quotients and non-resonance conditions).

use std::time::Instant;

use super::Dynamics;
use crate::model::system::System;
use crate::spec::{SpectrumSpec, SsmSpec};
use crate::spectrum::{
    self, check_resonances, MasterMode, Method, ResonanceReport, Spectrum, SpectrumError,
    SpectrumOptions,
};
use crate::C64;

/// What the spectral stage found.
#[derive(Debug, Clone)]
pub struct Spectral {
    /// The finite spectrum (multipliers sorted for maps).
    pub spectrum: Spectrum,
    /// The master modes.
    pub masters: Vec<MasterMode>,
    /// Spectral quotients and (near) resonances.
    pub resonances: ResonanceReport,
    /// Finite modes of the model: counted, or from its mechanical structure
    /// when only part of the spectrum was computed.
    pub n_finite: usize,
    /// Warnings (fallbacks, unexpected mode counts, resonances).
    pub warnings: Vec<String>,
    /// Seconds for spectrum and master modes.
    pub spectrum_s: f64,
    /// Seconds for the resonance checks.
    pub resonance_s: f64,
}

/// The spectral stage of the SSM `ssm` (its master pairs, scaling and
/// resonance tolerance) with the solver of `spec` on `system`, the
/// resonance checks up to `order`. A master pair beyond the spectrum is
/// [`SpectrumError::PairOutOfRange`].
pub fn spectral(
    ssm: &SsmSpec,
    spec: &SpectrumSpec,
    system: &System,
    order: usize,
) -> Result<Spectral, SpectrumError> {
    let t_spec = Instant::now();
    let mut warnings = Vec::new();
    let pairs = &ssm.master_pairs;
    let max_pair = pairs.iter().copied().max().unwrap_or(1);
    let opts = SpectrumOptions {
        method: spec.method,
        modes: spec.modes.unwrap_or(2 * max_pair + 10).max(2 * max_pair),
        shift: spec.shift,
        normalization: ssm.normalization,
        velocities: system.velocities(),
    };
    let dynamics = Dynamics::from(system.time);
    let (pencil_a, pencil_b) = system.spectral_pencil();
    let mut spectrum = compute_with_fallback(pencil_a, pencil_b, &opts, &mut warnings)?;
    if let Dynamics::Map { .. } = dynamics {
        spectrum::sort_multipliers(&mut spectrum.eigenvalues);
    }
    let coverage = match (spectrum.complete, dynamics) {
        (false, Dynamics::Flow) => {
            let automatic = spec.modes.is_none();
            let (widened, coverage) = cover_resonances(
                pencil_a,
                pencil_b,
                &opts,
                spectrum,
                (pairs, order, ssm.resonance_tol),
                automatic,
            )?;
            spectrum = widened;
            coverage
        }
        _ => None,
    };
    let n_original = system.n_states() - system.n_auxiliary();
    let mechanical_layout = system
        .mechanical
        .as_ref()
        .filter(|m| n_original == 2 * m.n_dof + m.n_constraints);
    if let (true, Some(mech)) = (spectrum.complete, mechanical_layout) {
        let expected = 2 * (mech.n_dof - mech.n_constraints.min(mech.n_dof));
        if spectrum.eigenvalues.len() != expected {
            warnings.push(format!(
                "found {} finite eigenvalues where a mechanical system with {} dofs and {} constraints has {expected}: check that M is non-singular and G0 has full rank",
                spectrum.eigenvalues.len(),
                mech.n_dof,
                mech.n_constraints
            ));
        }
    }
    let n_finite = match (mechanical_layout, spectrum.complete) {
        (Some(m), false) => 2 * (m.n_dof - m.n_constraints.min(m.n_dof)),
        _ => spectrum.eigenvalues.len(),
    };
    // a sparse path that found every finite mode of a mechanical model has
    // the whole spectrum
    if mechanical_layout.is_some() && spectrum.eigenvalues.len() >= n_finite {
        spectrum.complete = true;
    }
    let masters = spectrum::master_modes(system, &spectrum, pairs, opts.normalization)?;
    let spectrum_s = t_spec.elapsed().as_secs_f64();
    let master_indices: Vec<usize> = masters.iter().map(|m| m.index).collect();
    warnings.extend(repeated_masters(
        &spectrum.eigenvalues,
        &masters,
        ssm.resonance_tol,
    ));
    let rates = match dynamics {
        Dynamics::Flow => spectrum.eigenvalues.clone(),
        Dynamics::Map { period } => spectrum::multipliers_to_rates(&spectrum.eigenvalues, period),
    };
    let t_res = Instant::now();
    let resonances = check_resonances(
        &rates,
        &master_indices,
        order,
        ssm.resonance_tol,
        spectrum.complete,
    );
    let resonance_s = t_res.elapsed().as_secs_f64();
    warnings.extend(resonances.warnings.iter().cloned());
    if !spectrum.complete {
        warnings.push(coverage_warning(&spectrum, coverage.as_ref(), &opts, order));
    }
    Ok(Spectral {
        spectrum,
        masters,
        resonances,
        n_finite,
        warnings,
        spectrum_s,
        resonance_s,
    })
}

/// The most modes the sparse path computes on its own to cover the
/// resonance checks (the Krylov basis holds about twice as many vectors).
const MAX_AUTOMATIC_MODES: usize = 160;

/// The most numbers the Krylov basis of an automatic widening may hold
/// (2^27: 1 GiB).
const KRYLOV_BASIS_MAX: usize = 1 << 27;

/// Which eigenvalues a partial spectrum holds for the resonance checks.
#[derive(Debug, Clone, Copy)]
struct Coverage {
    /// Every eigenvalue with `|lambda| <= radius` was computed.
    radius: f64,
    /// Resonances up to the expansion order involve `|lambda| <= needed`:
    /// `order max |lambda_master|` with the resonance tolerance.
    needed: f64,
}

/// The spectrum of the pencil by `opts`; without a method asked for, a
/// dense path defeated by a stiff pencil falls back to the sparse path (with
/// a warning); asked for explicitly, the error says whether the sparse path
/// would have worked.
fn compute_with_fallback(
    pencil_a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    pencil_b: faer::sparse::SparseColMatRef<'_, usize, f64>,
    opts: &SpectrumOptions,
    warnings: &mut Vec<String>,
) -> Result<Spectrum, SpectrumError> {
    match spectrum::compute(pencil_a, pencil_b, opts) {
        // a stiff pencil (e.g. light pendulums on a heavy slider) can defeat the
        // dense path's rank decisions; the sparse path needs only the slow modes
        Err(e @ (SpectrumError::SingularPencil { .. } | SpectrumError::NoConvergence { .. }))
            if opts.method.is_none() =>
        {
            let sparse = SpectrumOptions {
                method: Some(Method::Sparse),
                ..opts.clone()
            };
            let sp = spectrum::compute(pencil_a, pencil_b, &sparse).map_err(|_| e.clone())?;
            warnings.push(format!(
                "dense spectrum failed ({e}); the sparse path was used instead (set [spectrum] method = \"sparse\" to skip the attempt)"
            ));
            Ok(sp)
        }
        // asked for explicitly: say whether the sparse path would have worked
        Err(e @ (SpectrumError::SingularPencil { .. } | SpectrumError::NoConvergence { .. })) => {
            let sparse = SpectrumOptions {
                method: Some(Method::Sparse),
                ..opts.clone()
            };
            Err(match spectrum::compute(pencil_a, pencil_b, &sparse) {
                Ok(_) => SpectrumError::DenseTooStiff {
                    detail: match &e {
                        SpectrumError::SingularPencil { detail } => detail.clone(),
                        other => other.to_string(),
                    },
                },
                Err(_) => e,
            })
        }
        r => r,
    }
}

/// What an incomplete (sparse) spectrum covers against what the checks up
/// to `order` need, for the warnings.
fn coverage_warning(
    spectrum: &Spectrum,
    coverage: Option<&Coverage>,
    opts: &SpectrumOptions,
    order: usize,
) -> String {
    match coverage {
        Some(c) if c.radius >= c.needed => format!(
            "sparse path: the {} finite modes with |lambda - sigma| <= {:.4e} (sigma = {}) were computed; they hold every eigenvalue that the non-resonance conditions of eq. (53) up to order {order} can involve (|lambda| <= {:.4e}); the real-part conditions of eq. (57) and the spectral quotients count only them",
            spectrum.eigenvalues.len(),
            c.radius + opts.shift.abs(),
            opts.shift,
            c.needed
        ),
        Some(c) => format!(
            "sparse path: the {} finite modes computed hold the eigenvalues with |lambda| <= {:.4e} only, but the non-resonance conditions of eq. (53) up to order {order} can involve |lambda| up to {:.4e}: the resonance checks and spectral quotients are incomplete; raise [spectrum] modes (or leave it out to let the engine choose) or set method = \"dense\"",
            spectrum.eigenvalues.len(),
            c.radius,
            c.needed
        ),
        None => format!(
            "sparse path: {} finite modes nearest sigma = {} were computed; resonance checks and spectral quotients cover only those",
            spectrum.eigenvalues.len(),
            opts.shift
        ),
    }
}

/// Widens a sparse spectrum until it holds every eigenvalue that the
/// non-resonance conditions of eq. (53) up to `order` can involve
/// (`lambda_j = <m, lambda_M>` with `|m| <= order` needs `|lambda_j| <=
/// order max |lambda_M|`, widened by the resonance tolerance `tol`; the
/// real-part conditions of eq. (57) reach up to the absolute spectral
/// quotient, which only the whole spectrum knows), doubling the modes, at most
/// [`MAX_AUTOMATIC_MODES`], half the states and a basis of
/// [`KRYLOV_BASIS_MAX`] numbers; only when `automatic` (the scene named no
/// count).
/// The shift-invert iteration finds the eigenvalues nearest `sigma`, so
/// the computed set is the whole disk `|lambda - sigma| <= max |lambda_i -
/// sigma|` and covers `|lambda| <=` that radius minus `|sigma|`.
fn cover_resonances(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    b: faer::sparse::SparseColMatRef<'_, usize, f64>,
    opts: &SpectrumOptions,
    mut found: Spectrum,
    (pairs, order, tol): (&[usize], usize, f64),
    automatic: bool,
) -> Result<(Spectrum, Option<Coverage>), SpectrumError> {
    let n = a.nrows();
    let mut modes = opts.modes;
    loop {
        let starts = spectrum::pair_starts(&found.eigenvalues);
        let Some(master_abs) = pairs
            .iter()
            .map(|&p| starts.get(p - 1).map(|&i| found.eigenvalues[i].norm()))
            .collect::<Option<Vec<f64>>>()
        else {
            // a missing master pair is reported by the master-mode stage
            return Ok((found, None));
        };
        let needed = order as f64 * master_abs.iter().copied().fold(0.0, f64::max) * (1.0 + tol);
        let radius = found
            .eigenvalues
            .iter()
            .map(|l| (l - opts.shift).norm())
            .fold(0.0, f64::max)
            - opts.shift.abs();
        let coverage = Coverage { radius, needed };
        // the Krylov basis holds about 2 modes + 8 vectors of n numbers:
        // at most KRYLOV_BASIS_MAX of them
        let by_memory = (KRYLOV_BASIS_MAX / n.max(1)).saturating_sub(8) / 2;
        let next = (2 * modes)
            .min(MAX_AUTOMATIC_MODES)
            .min(n / 2)
            .min(by_memory);
        if radius >= needed || !automatic || next <= modes {
            return Ok((found, Some(coverage)));
        }
        modes = next;
        let wider = SpectrumOptions {
            modes,
            method: Some(Method::Sparse),
            ..opts.clone()
        };
        found = spectrum::compute(a, b, &wider)?;
    }
}

/// A warning for each master eigenvalue that is repeated (to within the
/// relative `tol`) elsewhere in the spectrum: a 1:1 resonance at order 1,
/// which the checks of eq. (57) (orders 2 and up) do not see. Outside the
/// master subspace it leaves the SSM without a unique spectral subspace;
/// inside it, the master eigenvectors are one arbitrary basis of the
/// eigenspace.
fn repeated_masters(eigenvalues: &[C64], masters: &[MasterMode], tol: f64) -> Vec<String> {
    let mut warnings = Vec::new();
    for (k, m) in masters.iter().enumerate() {
        for (j, &ev) in eigenvalues.iter().enumerate() {
            let distance = (ev - m.lambda).norm() / m.lambda.norm().max(f64::MIN_POSITIVE);
            if j == m.index || distance > tol {
                continue;
            }
            match masters.iter().position(|o| o.index == j) {
                Some(o) if o > k => warnings.push(format!(
                    "master pairs {} and {} share the eigenvalue {:.6} (relative distance {distance:.1e}): their modes are one arbitrary basis of a repeated eigenspace, and the reduced dynamics keep the 1:1 coupling",
                    m.pair, masters[o].pair, m.lambda
                )),
                Some(_) => {}
                None => warnings.push(format!(
                    "master pair {}: lambda = {:.6} is repeated by eigenvalue {} = {ev:.6} outside the master subspace (relative distance {distance:.1e}): the SSM is not unique there; add that mode's pair to [ssm] master_pairs",
                    m.pair,
                    m.lambda,
                    j + 1
                )),
            }
        }
    }
    warnings
}
