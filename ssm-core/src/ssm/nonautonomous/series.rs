//! The non-autonomous expansion over a band of forcing frequencies as one
//! Taylor series in `Omega` per multi-index.
//!
//! With `Omega = center + half_width t`, the equation of multi-index `k`
//! (module docs of `nonautonomous`) is the bordered system along
//! `Lambda(t) = i kappa center + k . lambda + i kappa half_width t`, and its
//! right-hand side is linear in the lower multi-indices' `x_j`, `s_j` with
//! coefficients that do not depend on `Omega` (the forcing `F_h` enters at
//! `k = 0` alone, as a constant). So if every lower coefficient is a
//! polynomial in `t`, the right-hand side is one of the same degree, built
//! term by term with the same formula, and the solution is a Taylor series
//! in `t` whose coefficients follow from one factorization (module `series`
//! of `homological`): a band costs one factorization per distinct imaginary
//! part of `k . lambda` and a few dozen solves per multi-index, whatever the
//! number of frequencies, and any frequency of the band is then a
//! polynomial evaluation. Each multi-index's series is accepted only where
//! its value at every frequency asked for solves that frequency's bordered
//! system to a componentwise backward error of 1e-12, or ten times the
//! floor its coefficients' refined solves reached (with the
//! right-hand side evaluated from the lower series, as a direct solve at that
//! frequency would see it); otherwise the caller solves frequency by
//! frequency.
//!
//! # References
//! Z. Bai, Appl. Numer. Math. 43 (2002) 9-44 (moment matching through one
//! factorization); M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023),
//! eq. (60).

use super::{
    anchor_for, band_anchors, resonant_set, shift, sub_index, NaHarmonic, NonAutonomous, Rhs,
};
use crate::model::system::System;
use crate::ssm::forced::{ForcedError, ForcedSsm};
use crate::ssm::homological::{horner, series_accept, HomologicalError, SeriesRun};
use crate::ssm::SsmExpansion;
use crate::C64;
use rayon::prelude::*;
use ssm_kernel::poly::MultiIndexSet;

/// One multi-index's system of an order: its resonant set, right-hand
/// side series, value at the band's middle, anchor and the anchor's slot.
struct Job {
    idx: usize,
    set_res: Vec<usize>,
    rhs: Vec<Vec<C64>>,
    /// `M^{-1} rhs_V` per term where known without a solve.
    known: Vec<Option<Vec<C64>>>,
    big: C64,
    at: C64,
    slot: usize,
}

/// One harmonic's series: `x[idx][m]`, `s[idx][m]`, the coefficient of `t^m`.
#[derive(Debug, Clone)]
struct SeriesHarmonic {
    multiple: f64,
    x: Vec<Vec<Vec<C64>>>,
    s: Vec<Vec<Vec<C64>>>,
}

/// The non-autonomous part of the periodic SSM to order `order` in `p` over
/// the band `center +- half_width`, as Taylor series in `t = (Omega -
/// center) / half_width` (module docs).
#[derive(Debug, Clone)]
pub struct NaSeries {
    /// Middle of the band.
    pub center: f64,
    /// Half its width.
    pub half_width: f64,
    /// Highest order in `p`.
    pub order: usize,
    /// Multi-indices up to `order`.
    pub set: MultiIndexSet,
    harmonics: Vec<SeriesHarmonic>,
}

impl NaSeries {
    /// The longest series (terms of one multi-index).
    pub fn terms(&self) -> usize {
        self.harmonics
            .iter()
            .flat_map(|h| h.x.iter().map(Vec::len))
            .max()
            .unwrap_or(0)
    }

    /// Whether `omega` lies in the band.
    pub fn contains(&self, omega: f64) -> bool {
        (omega - self.center).abs() <= self.half_width * (1.0 + 1e-12)
    }

    /// The expansion at `omega` (in the band: [`NaSeries::contains`]).
    pub fn at(&self, omega: f64) -> NonAutonomous {
        let t = (omega - self.center) / self.half_width;
        NonAutonomous {
            omega,
            order: self.order,
            set: self.set.clone(),
            harmonics: self
                .harmonics
                .iter()
                .map(|h| NaHarmonic {
                    multiple: h.multiple,
                    x: h.x.iter().map(|terms| horner(terms, t)).collect(),
                    s: h.s.iter().map(|terms| horner(terms, t)).collect(),
                })
                .collect(),
        }
    }
}

impl ForcedSsm<'_> {
    /// The expansion of [`ForcedSsm::expansion`] over the band around
    /// `center` that holds every frequency of `omegas`, as Taylor series in
    /// `Omega` (module docs), checked at each of `omegas`. `None` when a
    /// series does not converge over the band (a pencil eigenvalue near it)
    /// or misses the check at one of `omegas`; the factorizations spent are
    /// counted either way.
    ///
    /// # Errors
    /// A factorization failed; the forcing depends on the state.
    pub fn expansion_series(
        &mut self,
        ssm: &SsmExpansion,
        sys: &System,
        omegas: &[f64],
        order: usize,
        center: f64,
    ) -> Result<Option<NaSeries>, ForcedError> {
        let order = order.min(ssm.order);
        if order > 0 && !self.forcing_is_constant(sys) {
            return Err(ForcedError::StateDependentForcing);
        }
        let half_width = omegas
            .iter()
            .fold(0.0f64, |m, &w| m.max((w - center).abs()));
        if omegas.is_empty() || !(half_width > 0.0 && half_width.is_finite()) {
            return Ok(None);
        }
        let cx = Rhs::new(ssm, sys, order);
        let set = &cx.set;
        let lambda = self.lambda().to_vec();
        let coord_ratio = self.coord_ratios().to_vec();
        let shift_of = |e: &[u16]| shift(&lambda, e);
        let ts: Vec<f64> = omegas.iter().map(|w| (w - center) / half_width).collect();
        let mut harmonics = Vec::with_capacity(self.n_harmonics());
        for h in 0..self.n_harmonics() {
            let (multiple, f) = self.harmonic(h);
            let f = f.to_vec();
            // at each multi-index's own value at the center (damping
            // included): every coefficient's solve is then one refined solve
            let anchors = band_anchors(set, &|e| C64::new(0.0, multiple * center) + shift_of(e));
            let solved =
                self.harmonic_series(&cx, &coord_ratio, h, &f, &anchors, center, half_width, &ts);
            for &(at, _) in &anchors {
                self.release_anchor(at);
            }
            let Some((x, s)) = solved.map_err(|source| ForcedError::Solve {
                harmonic: h + 1,
                omega: center,
                source,
            })?
            else {
                return Ok(None);
            };
            harmonics.push(SeriesHarmonic { multiple, x, s });
        }
        Ok(Some(NaSeries {
            center,
            half_width,
            order,
            set: cx.set.clone(),
            harmonics,
        }))
    }

    /// One harmonic's series, multi-index by multi-index (`None`: not
    /// converged or not accepted at a check point `ts`).
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn harmonic_series(
        &mut self,
        cx: &Rhs,
        coord_ratio: &[f64],
        h: usize,
        f: &[C64],
        anchors: &[(C64, usize)],
        center: f64,
        half_width: f64,
        ts: &[f64],
    ) -> Result<Option<(Vec<Vec<Vec<C64>>>, Vec<Vec<Vec<C64>>>)>, HomologicalError> {
        let set = &cx.set;
        let (multiple, _) = self.harmonic(h);
        let nvar = set.nvar();
        let zero = C64::new(0.0, 0.0);
        let lambda = self.lambda().to_vec();
        let shift_of = |e: &[u16]| shift(&lambda, e);
        let mut xs: Vec<Vec<Vec<C64>>> = vec![Vec::new(); set.len()];
        let mut ss: Vec<Vec<Vec<C64>>> = vec![Vec::new(); set.len()];
        let empty: &[C64] = &[];
        let zeros = vec![zero; nvar];
        for k in 0..=set.max_order() {
            let done = set.of_order(k).start;
            // the order's systems: their right-hand sides come from the
            // lower orders alone
            let mut jobs = Vec::new();
            // the order's factorizations first, side by side
            let needed: Vec<C64> = set
                .of_order(k)
                .filter_map(|idx| {
                    let big = C64::new(0.0, multiple * center) + shift_of(set.exponents(idx));
                    anchor_for(anchors, big)
                })
                .collect();
            self.solver.prefactor_anchors(&needed)?;
            for idx in set.of_order(k) {
                let e = set.exponents(idx).to_vec();
                let shift = shift_of(&e);
                let set_res = resonant_set(coord_ratio, multiple, &e);
                let below: Vec<(usize, usize)> = (0..done)
                    .filter_map(|j| sub_index(set, &e, set.exponents(j)).map(|t| (j, t)))
                    .collect();
                // the right-hand side's Taylor coefficients, of the lower
                // series' degree
                let terms = if k == 0 {
                    1
                } else {
                    (0..done).map(|j| xs[j].len()).max().unwrap_or(1)
                };
                let (rhs, known): (Vec<Vec<C64>>, Vec<Option<Vec<C64>>>) = (0..terms)
                    .map(|m| {
                        let x: Vec<&[C64]> = (0..done)
                            .map(|j| xs[j].get(m).map_or(empty, Vec::as_slice))
                            .collect();
                        let s: Vec<&[C64]> = (0..done)
                            .map(|j| ss[j].get(m).map_or(zeros.as_slice(), Vec::as_slice))
                            .collect();
                        let forcing = (k == 0 && m == 0).then_some(f);
                        cx.rhs_known(&e, done, &below, &x, &s, forcing)
                    })
                    .unzip();
                let big = C64::new(0.0, multiple * center) + shift;
                let at = anchor_for(anchors, big).expect("every multi-index has its anchor");
                let Some(slot) = self.solver.series_anchor(at, &set_res)? else {
                    return Ok(None);
                };
                jobs.push(Job {
                    idx,
                    set_res,
                    rhs,
                    known,
                    big,
                    at,
                    slot,
                });
            }
            let slope = C64::new(0.0, multiple * half_width);
            // series through different factorizations (or through one with
            // one border) read the solver alone: one per core; a slot whose
            // border two resonant sets share is re-bordered before each
            let shared = jobs.iter().all(|a| {
                jobs.iter()
                    .all(|b| a.slot != b.slot || a.set_res == b.set_res)
            });
            // multi-index 0 of the first harmonic solves what the output
            // table's series solved: its terms, rescaled to this band, are
            // taken (and checked at the nodes below)
            let reused = (k == 0 && jobs.len() == 1)
                .then(|| self.x0_terms(h, center, half_width))
                .flatten()
                .filter(|_| jobs[0].rhs.len() == 1 && jobs[0].set_res == self.forcing_set(h));
            let runs: Vec<SeriesRun> = if reused.is_some() {
                Vec::new()
            } else if shared {
                let solver = &self.solver;
                jobs.par_iter()
                    .map(|j| solver.series_at(j.slot, j.big, slope, &j.set_res, &j.rhs, &j.known))
                    .collect()
            } else {
                let mut runs = Vec::with_capacity(jobs.len());
                for j in &jobs {
                    let slot = self
                        .solver
                        .series_anchor(j.at, &j.set_res)?
                        .expect("factorized above");
                    runs.push(
                        self.solver
                            .series_at(slot, j.big, slope, &j.set_res, &j.rhs, &j.known),
                    );
                }
                runs
            };
            let mut solved = Vec::with_capacity(jobs.len());
            solved.extend(reused);
            for run in runs {
                let Some((series, floor)) = self.solver.series_counted(run) else {
                    return Ok(None);
                };
                let (w, r): (Vec<Vec<C64>>, Vec<Vec<C64>>) = series.into_iter().unzip();
                solved.push((w, r, floor));
            }
            // every frequency asked for: its value solves its system (the
            // checks are independent: one per core)
            let solver = &self.solver;
            let missed = (0..jobs.len() * ts.len()).into_par_iter().any(|i| {
                let (job, (w, r, floor)) = (&jobs[i / ts.len()], &solved[i / ts.len()]);
                let t = ts[i % ts.len()];
                let (wt, rt, bt) = (horner(w, t), horner(r, t), horner(&job.rhs, t));
                let error = solver.backward_error(job.big + slope * t, &job.set_res, &wt, &rt, &bt);
                error.is_nan() || error > series_accept(*floor)
            });
            if missed {
                return Ok(None);
            }
            for (job, (w, r, _)) in jobs.into_iter().zip(solved) {
                let set_res = &job.set_res;
                ss[job.idx] = r
                    .into_iter()
                    .map(|rv| {
                        let mut full = vec![zero; nvar];
                        for (&c, v) in set_res.iter().zip(rv) {
                            full[c] = v;
                        }
                        full
                    })
                    .collect();
                xs[job.idx] = w;
            }
            for &(at, _) in anchors.iter().filter(|(_, l)| *l == k) {
                self.release_anchor(at);
            }
        }
        Ok(Some((xs, ss)))
    }
}
