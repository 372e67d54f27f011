//! Reference branches started from predicted orbits (`start = "ssm"`): a
//! seed is one period of an orbit predicted by another method (the SSM's
//! forced response lifted by `W`), projected on the Fourier basis, corrected
//! by Newton at its frequency and continued in both directions.
//!
//! A branch traced from rest at the low end of the range misses every branch
//! that is not connected to it inside the range: isolas, and upper branches
//! cut by the range's ends. A seed on each of the reduced model's branches
//! reaches them. A seed whose corrected orbit lies on a branch already traced
//! (within `SAME_BRANCH` of its polyline in scaled unknowns) adds nothing
//! and is dropped.
//!
//! # References
//! M. Krack, J. Gross, *Harmonic Balance for Nonlinear Vibration Problems*,
//! Springer (2019), Sect. 4.3 (initial guesses, isolated branches);
//! G. Haller, S. Ponsioen, Nonlinear normal modes and spectral submanifolds,
//! Nonlinear Dyn. 86 (2016) 1493-1534 (the SSM's periodic orbits as
//! predictions of the full system's).

use crate::model::system::System;
use ssm_kernel::continuation::{self, dot, solve_at_parameter, Point, Settings, Stop};

pub use super::branch::Seed;
use super::branch::{
    classify, drop_rejoining_step, orbits_at, Reader, ReferenceBranch, ReferenceError,
    ReferenceSettings,
};
use super::runs::Runs;
use super::{HarmonicBalance, OrbitInfo};

/// Largest distance (scaled unknowns: amplitudes by the amplitude scale,
/// frequency by the range width) from a corrected seed to a traced branch's
/// polyline at which the seed counts as lying on that branch. The chords of
/// a branch traced with steps up to `h` and tangent turns up to 0.1 rad stay
/// within `h / 80` of the arc, so `0.05` holds for the default steps, while
/// distinct orbits at one frequency differ by much more outside the
/// immediate neighbourhood of a fold or branch point (where they meet).
pub(crate) const SAME_BRANCH: f64 = 0.05;

/// A traced branch's polyline in scaled unknowns, with its period multiple.
#[derive(Debug, Clone)]
pub(super) struct Path {
    pub multiple: usize,
    pub points: Vec<Vec<f64>>,
}

impl Path {
    /// The polyline of a traced branch.
    pub fn of(multiple: usize, points: &[Point<OrbitInfo>]) -> Self {
        Path {
            multiple,
            points: points.iter().map(|p| p.u.clone()).collect(),
        }
    }

    /// The distance from `u` to the polyline.
    fn distance(&self, u: &[f64]) -> f64 {
        match self.points.as_slice() {
            [] => f64::INFINITY,
            [only] => continuation::segment_distance(only, only, u),
            pts => pts
                .windows(2)
                .map(|w| continuation::segment_distance(&w[0], &w[1], u))
                .fold(f64::INFINITY, f64::min),
        }
    }
}

/// What a seed gave.
pub(super) enum Seeded {
    /// A new branch, its polyline, and its period doublings.
    Branch(Box<ReferenceBranch>, Path, Vec<Point<OrbitInfo>>),
    /// The seed lies on a branch traced already.
    Known,
    /// Why the seed could not start a branch (a note for the user).
    Dropped(String),
}

/// The branch through `seed`, numbered `number`, continued both ways from
/// its corrected orbit until it leaves the range, closes (an isola), or
/// rejoins the period-`T` branch (a seed of period `2T`); `template` gives
/// the harmonics and scales.
#[allow(clippy::too_many_arguments)]
pub(super) fn seeded_branch(
    sys: &System,
    settings: &ReferenceSettings,
    template: &HarmonicBalance<'_>,
    seed: &Seed,
    cs: &Settings,
    number: usize,
    known: &[Path],
    runs: &mut Runs<'_>,
) -> Result<Seeded, ReferenceError> {
    let m = seed.period_multiple.max(1);
    let mut hb = HarmonicBalance::new(sys, settings.epsilon, m * template.harmonics(), m)?;
    hb.amplitude_scale = template.amplitude_scale;
    hb.frequency_scale = template.frequency_scale;
    hb.stability = template.stability;
    let (lo, hi) = (cs.range.0, cs.range.1);
    let w = seed.omega / hb.frequency_scale;
    // a seed outside the range has no branch to start inside it
    if !(w >= lo && w <= hi) {
        return Ok(Seeded::Known);
    }
    let c = match seed.coefficients(hb.n_states(), hb.harmonics()) {
        Ok(c) => c,
        Err(e) => return Ok(Seeded::Dropped(format!("{}: {e}", seed.origin))),
    };
    let guess = hb.scale(&c, seed.omega);
    let u0 = match solve_at_parameter(&mut hb, guess, cs) {
        Ok(u) => u,
        Err(e) => {
            return Ok(Seeded::Dropped(format!(
                "{} at Omega = {:.6}: Newton from the prediction failed ({e})",
                seed.origin, seed.omega
            )))
        }
    };
    let nu = hb.n_coefficients();
    let kk = 2 * hb.harmonics() + 1;
    let odd_norm = |u: &[f64]| -> f64 {
        (0..nu)
            .filter(|p| {
                let q = p % kk;
                q > 0 && q.div_ceil(2) % m != 0
            })
            .map(|p| u[p] * u[p])
            .sum::<f64>()
            .sqrt()
    };
    if m > 1 {
        let odd = odd_norm(&u0);
        if odd < 1e-6 * (1.0 + dot(&u0[..nu], &u0[..nu]).sqrt()) {
            return Ok(Seeded::Dropped(format!(
                "{} at Omega = {:.6}: the corrected orbit has period T, not {m}T",
                seed.origin, seed.omega
            )));
        }
        hb.odd_floor = Some(0.25 * odd);
    }
    // an orbit of period m T shifted by j T is the same orbit: the seed may
    // lie on any of a traced branch's m copies
    let copies: Vec<Vec<f64>> = (0..m).map(|j| shifted(&u0, kk, j, m)).collect();
    if known
        .iter()
        .any(|p| p.multiple == m && copies.iter().any(|u| p.distance(u) <= SAME_BRANCH))
    {
        return Ok(Seeded::Known);
    }
    let reader = Reader::of(&hb, settings.epsilon, &settings.outputs);
    let mut up = vec![0.0; nu + 1];
    up[nu] = 1.0;
    let mut forward = runs.trace(&mut hb, u0.clone(), &up, cs, &reader, number, true)?;
    drop_rejoining_step(&mut forward);
    let backward = if forward.stop == Stop::Closed || forward.stop == Stop::Interrupted {
        None
    } else {
        up[nu] = -1.0;
        // the seed's own orbit was shown with the forward half
        Some(runs.trace(&mut hb, u0, &up, cs, &reader, number, false)?)
    };
    let (mut orbits, mut events, mut doublings) = classify(&forward, &reader, number);
    let mut points = forward.points;
    let mut stop = forward.stop;
    if let Some(mut b) = backward {
        drop_rejoining_step(&mut b);
        let (o, e, d) = classify(&b, &reader, number);
        orbits = o.into_iter().skip(1).rev().chain(orbits).collect();
        events = e.into_iter().rev().chain(events).collect();
        doublings.extend(d);
        points = b.points.into_iter().skip(1).rev().chain(points).collect();
        if b.stop != Stop::Range && b.stop != Stop::Bound {
            stop = b.stop;
        }
    }
    let at = orbits_at(&mut hb, &points, &settings.points_at, cs, &reader, number);
    Ok(Seeded::Branch(
        Box::new(ReferenceBranch::traced(
            &mut hb, &points, orbits, events, stop, at,
        )),
        Path::of(m, &points),
        if m == 1 { doublings } else { Vec::new() },
    ))
}

/// The unknowns `u` (Fourier coefficients of an orbit of period `m T`, `K =
/// 2H + 1` per state, the parameter last) of the same orbit shifted in time
/// by `j T`: the angle `psi = Omega t / m` advances by `a = 2 pi j / m`, and
/// harmonic `k` rotates, `(c, s) -> (c cos ka + s sin ka, s cos ka - c sin
/// ka)`.
fn shifted(u: &[f64], kk: usize, j: usize, m: usize) -> Vec<f64> {
    let mut out = u.to_vec();
    let a = 2.0 * std::f64::consts::PI * j as f64 / m as f64;
    let n = (u.len() - 1) / kk;
    for i in 0..n {
        for k in 1..=(kk - 1) / 2 {
            let (sn, cs) = (k as f64 * a).sin_cos();
            let (c, s) = (u[i * kk + 2 * k - 1], u[i * kk + 2 * k]);
            out[i * kk + 2 * k - 1] = c * cs + s * sn;
            out[i * kk + 2 * k] = s * cs - c * sn;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::shifted;

    /// Reference: the series evaluated directly at the shifted angle. The
    /// coefficients shifted by `j T` give `z(psi + 2 pi j / m)` at every
    /// angle (1e-14), and `m` shifts by `T` are the identity.
    #[test]
    fn shifted_coefficients_are_the_orbit_later_by_whole_periods() {
        let (h, m) = (3usize, 3usize);
        let kk = 2 * h + 1;
        let u: Vec<f64> = (0..2 * kk + 1).map(|p| (p as f64 * 0.7).sin()).collect();
        let eval = |u: &[f64], i: usize, psi: f64| {
            (1..=h).fold(u[i * kk], |v, k| {
                let (s, c) = (k as f64 * psi).sin_cos();
                v + u[i * kk + 2 * k - 1] * c + u[i * kk + 2 * k] * s
            })
        };
        for j in 0..m {
            let v = shifted(&u, kk, j, m);
            for q in 0..16 {
                let psi = 0.4 * q as f64;
                let later = psi + 2.0 * std::f64::consts::PI * j as f64 / m as f64;
                for i in 0..2 {
                    assert!((eval(&v, i, psi) - eval(&u, i, later)).abs() < 1e-14);
                }
            }
            assert_eq!(v[2 * kk], u[2 * kk], "the parameter is kept");
        }
        let mut w = u.clone();
        for _ in 0..m {
            w = shifted(&w, kk, 1, m);
        }
        assert!(w.iter().zip(&u).all(|(a, b)| (a - b).abs() < 1e-14));
    }
}
