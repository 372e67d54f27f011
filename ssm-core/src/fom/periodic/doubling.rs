//! Switching to the branch of period `2T` at a period doubling.
//!
//! At a period doubling a Floquet multiplier passes `-1`: the linearization
//! has a solution `p(t)` with `p(t + T) = -p(t)`, a series in the odd
//! harmonics of `Omega / 2`. Written with period `2T` (harmonics of `Omega /
//! 2`, the orbit's own in the even ones), the period-`T` branch lies in the
//! subspace of even harmonics, and the period doubling is a symmetric
//! (pitchfork) branch point of this formulation: `R_c` is singular with its
//! null vector `v` in the odd harmonics, while the time shift `t -> t + T`
//! maps the new branch's two halves onto each other. So the new branch starts
//! at `u_PD + delta v`, corrected with the largest component of `v` fixed,
//! and is traced in one direction until its odd part vanishes again (it
//! rejoins the period-`T` branch at the next period doubling) or it leaves the
//! frequency range. `v` is found by inverse iteration with `R_c` at the
//! located point, where it is singular to the location's accuracy.
//!
//! # References
//! Y. A. Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed.,
//! Springer (2004), Sect. 10.3 (branch switching at period doubling);
//! E. J. Doedel, H. B. Keller, J. P. Kernevez, Numerical analysis and control
//! of bifurcation problems (II), Int. J. Bifurc. Chaos 1 (1991) 745-772.

use crate::model::system::System;
use ssm_kernel::continuation::{correct, local_parameter, Point, Problem, Settings};

use super::branch::{
    classify, drop_rejoining_step, orbits_at, Reader, ReferenceBranch, ReferenceError,
    ReferenceSettings,
};
use super::runs::Runs;
use super::seed::Path;
use super::{HarmonicBalance, OrbitInfo};

/// The branch of period `2T` from the period doubling `pd` of the
/// period-`T` branch of `hb1`, numbered `number`.
pub(super) fn doubled_branch(
    sys: &System,
    settings: &ReferenceSettings,
    hb1: &HarmonicBalance<'_>,
    pd: &Point<OrbitInfo>,
    cs: &Settings,
    number: usize,
    runs: &mut Runs<'_>,
) -> Result<(ReferenceBranch, Path), ReferenceError> {
    let h1 = hb1.harmonics();
    let mut hb = HarmonicBalance::new(sys, settings.epsilon, 2 * h1, 2)?;
    hb.amplitude_scale = hb1.amplitude_scale;
    hb.frequency_scale = hb1.frequency_scale;
    hb.stability = hb1.stability;
    let n = hb.n_states();
    let (k1, k2) = (2 * h1 + 1, 4 * h1 + 1);
    let nu = n * k2;
    // the period-T orbit in the harmonics of Omega/2: harmonic k -> 2k
    let mut u = vec![0.0; nu + 1];
    for i in 0..n {
        u[i * k2] = pd.u[i * k1];
        for k in 1..=h1 {
            u[i * k2 + 4 * k - 1] = pd.u[i * k1 + 2 * k - 1];
            u[i * k2 + 4 * k] = pd.u[i * k1 + 2 * k];
        }
    }
    u[nu] = pd.u[n * k1];
    let odd = |q: usize| q > 0 && q.div_ceil(2) % 2 == 1;
    // inverse iteration for the null vector of R_c in the odd harmonics
    hb.factor(&u, nu).map_err(|e| fail(&u, &hb, e.0))?;
    let mut v: Vec<f64> = (0..=nu)
        .map(|p| {
            if p < nu && odd(p % k2) {
                crate::spectrum::sparse::pseudo_random(p)
            } else {
                0.0
            }
        })
        .collect();
    for _ in 0..4 {
        v[nu] = 0.0;
        hb.solve(&mut v).map_err(|e| fail(&u, &hb, e.0))?;
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(fail(&u, &hb, "no null vector in the odd harmonics".into()));
        }
        v.iter_mut().for_each(|x| *x /= norm);
    }
    v[nu] = 0.0;
    // a step along v onto the new branch, its largest component held
    let delta = 0.1 * cs.h_max;
    let start: Vec<f64> = u.iter().zip(&v).map(|(a, b)| a + delta * b).collect();
    let (u0, _) = correct(
        &mut hb,
        start.clone(),
        &start,
        local_parameter(&v),
        cs,
        false,
    )
    .map_err(|e| fail(&u, &hb, e.0))?;
    let odd_norm = |w: &[f64]| -> f64 {
        (0..nu)
            .filter(|p| odd(p % k2))
            .map(|p| w[p] * w[p])
            .sum::<f64>()
            .sqrt()
    };
    hb.odd_floor = Some(0.25 * odd_norm(&u0));
    let t0: Vec<f64> = u0.iter().zip(&u).map(|(a, b)| a - b).collect();
    let reader = Reader::of(&hb, settings.epsilon, &settings.outputs);
    let mut branch = runs.trace(&mut hb, u0, &t0, cs, &reader, number, true)?;
    drop_rejoining_step(&mut branch);
    let at = orbits_at(
        &mut hb,
        &branch.points,
        &settings.points_at,
        cs,
        &reader,
        number,
    );
    let (orbits, events, _) = classify(&branch, &reader, number);
    let path = Path::of(2, &branch.points);
    Ok((
        ReferenceBranch::traced(&mut hb, &branch.points, orbits, events, branch.stop, at),
        path,
    ))
}

fn fail(u: &[f64], hb: &HarmonicBalance<'_>, cause: String) -> ReferenceError {
    ReferenceError::Settings(format!(
        "switching to the period-2T branch at Omega = {:.6}: {cause}",
        u[u.len() - 1] * hb.frequency_scale
    ))
}
