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
    anchor_for, band_anchors, resonant_set, rotating_frame, shift, sub_index, NaHarmonic,
    NonAutonomous, Rhs,
};
use crate::model::system::System;
use crate::ssm::forced::{ForcedError, ForcedSsm};
use crate::ssm::homological::{horner, series_accept, Homological, HomologicalError, SeriesRun};
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

    /// [`NonAutonomous::rotating_frame_coefficients`] of the expansion at
    /// `omega` (in the band), from the reduced coefficients' series alone.
    pub fn rotating_frame_coefficients_at(&self, omega: f64) -> (Vec<C64>, Vec<C64>) {
        let t = (omega - self.center) / self.half_width;
        let s: Vec<Vec<C64>> = self.harmonics[0]
            .s
            .iter()
            .map(|terms| horner(terms, t))
            .collect();
        rotating_frame(&self.set, self.order, &|i, c| s[i][c])
    }

    /// The output `sum_s weights_s x_{k,s}` of the first harmonic's
    /// coefficient of each multi-index `k` at `omega` (in the band): a
    /// polynomial in `omega` per multi-index, without the states.
    pub fn outputs_at(&self, omega: f64, weights: &[(usize, f64)]) -> Vec<C64> {
        let t = (omega - self.center) / self.half_width;
        self.harmonics[0]
            .x
            .iter()
            .map(|terms| {
                terms.iter().rev().fold(C64::new(0.0, 0.0), |acc, xm| {
                    acc * t + weights.iter().map(|&(s, w)| xm[s] * w).sum::<C64>()
                })
            })
            .collect()
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
    ///
    /// An order's systems read only the lower orders: their right-hand
    /// sides are built (every system and term apart) while the order's
    /// factorizations are made, where those are symmetric `L B L^T`s that
    /// may run beside other work ([`Homological::factors_concurrent`]);
    /// then the series run side by side, each checked at every point as
    /// soon as it is done.
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
        let concurrent = self.solver.factors_concurrent()?;
        let slope = C64::new(0.0, multiple * half_width);
        for k in 0..=set.max_order() {
            let done = set.of_order(k).start;
            let indices: Vec<usize> = set.of_order(k).collect();
            let big_of =
                |idx: usize| C64::new(0.0, multiple * center) + shift_of(set.exponents(idx));
            let needed: Vec<C64> = indices
                .iter()
                .filter_map(|&idx| anchor_for(anchors, big_of(idx)))
                .collect();
            // multi-index 0 of the first harmonic solves what the output
            // table's series solved: its terms, rescaled to this band, are
            // taken (and checked at the nodes below)
            let reused = (k == 0 && indices.len() == 1)
                .then(|| self.x0_terms(h, center, half_width))
                .flatten()
                .filter(|_| {
                    resonant_set(coord_ratio, multiple, set.exponents(0)) == self.forcing_set(h)
                });
            let built = {
                let (xs, ss) = (&xs, &ss);
                let build = || order_rhs(cx, &indices, done, xs, ss, (k == 0).then_some(f), nvar);
                if reused.is_some() {
                    Vec::new()
                } else if concurrent {
                    let solver = &mut self.solver;
                    let (factored, built) =
                        rayon::join(|| solver.prefactor_anchors(&needed), build);
                    factored?;
                    built
                } else {
                    self.solver.prefactor_anchors(&needed)?;
                    build()
                }
            };
            let mut jobs = Vec::with_capacity(indices.len());
            for (&idx, (rhs, known)) in indices.iter().zip(built) {
                let set_res = resonant_set(coord_ratio, multiple, set.exponents(idx));
                let big = big_of(idx);
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
            // series through different factorizations (or through one with
            // one border) read the solver alone: one per core; a slot whose
            // border two resonant sets share is re-bordered before each
            let shared = jobs.iter().all(|a| {
                jobs.iter()
                    .all(|b| a.slot != b.slot || a.set_res == b.set_res)
            });
            let mut solved: Vec<Solved> = Vec::with_capacity(jobs.len());
            if let Some((w, r, floor)) = reused {
                let rhs = vec![f.to_vec()];
                let big = big_of(0);
                let set_res = self.forcing_set(h).to_vec();
                let series = Line {
                    big,
                    slope,
                    set: &set_res,
                    rhs: &rhs,
                };
                if !series.accepted(&self.solver, ts, &w, &r, floor) {
                    return Ok(None);
                }
                jobs.push(Job {
                    idx: 0,
                    set_res,
                    rhs,
                    known: Vec::new(),
                    big,
                    at: big,
                    slot: usize::MAX,
                });
                solved.push((w, r));
            } else {
                // a series, and its terms where it converged and every
                // frequency asked for is accepted
                let run_one = |solver: &Homological, j: &Job, slot: usize| {
                    let mut run =
                        solver.series_at(slot, j.big, slope, &j.set_res, &j.rhs, &j.known);
                    let line = Line {
                        big: j.big,
                        slope,
                        set: &j.set_res,
                        rhs: &j.rhs,
                    };
                    let terms = run.take().and_then(|(series, floor)| {
                        let (w, r): Solved = series.into_iter().unzip();
                        line.accepted(solver, ts, &w, &r, floor).then_some((w, r))
                    });
                    (run, terms)
                };
                let runs: Vec<(SeriesRun, Option<Solved>)> = if shared {
                    let solver = &self.solver;
                    jobs.par_iter()
                        .map(|j| run_one(solver, j, j.slot))
                        .collect()
                } else {
                    let mut runs = Vec::with_capacity(jobs.len());
                    for j in &jobs {
                        let slot = self
                            .solver
                            .series_anchor(j.at, &j.set_res)?
                            .expect("factorized above");
                        runs.push(run_one(&self.solver, j, slot));
                    }
                    runs
                };
                let mut missed = false;
                for (run, terms) in runs {
                    self.solver.series_counted(run);
                    match terms {
                        Some(t) => solved.push(t),
                        None => missed = true,
                    }
                }
                if missed {
                    return Ok(None);
                }
            }
            for (job, (w, r)) in jobs.into_iter().zip(solved) {
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

/// A series' terms of `x` and of `s` on its resonant set.
type Solved = (Vec<Vec<C64>>, Vec<Vec<C64>>);

/// One multi-index's bordered system along `Lambda(t) = big + slope t`:
/// its resonant set and right-hand side's Taylor coefficients.
struct Line<'a> {
    big: C64,
    slope: C64,
    set: &'a [usize],
    rhs: &'a [Vec<C64>],
}

impl Line<'_> {
    /// Whether the series `w`, `r` (its refined solves' floor `floor`)
    /// solves the system at every point of `ts` to the backward error of
    /// `series_accept` (the points are independent: one per core).
    fn accepted(
        &self,
        solver: &Homological,
        ts: &[f64],
        w: &[Vec<C64>],
        r: &[Vec<C64>],
        floor: f64,
    ) -> bool {
        !ts.par_iter().any(|&t| {
            let (wt, rt, bt) = (horner(w, t), horner(r, t), horner(self.rhs, t));
            let error = solver.backward_error(self.big + self.slope * t, self.set, &wt, &rt, &bt);
            error.is_nan() || error > series_accept(floor)
        })
    }
}

/// The right-hand sides' Taylor coefficients of the systems `indices` (one
/// order; the lower orders' multi-indices `..done`) from the lower orders'
/// series `xs`, `ss`, with `M^{-1} rhs_V` where known (see
/// [`Rhs::rhs_known`]), each of the lower series' degree; `forcing` at
/// order 0. Every system and term is built apart, one per core.
#[allow(clippy::type_complexity)]
fn order_rhs(
    cx: &Rhs,
    indices: &[usize],
    done: usize,
    xs: &[Vec<Vec<C64>>],
    ss: &[Vec<Vec<C64>>],
    forcing: Option<&[C64]>,
    nvar: usize,
) -> Vec<(Vec<Vec<C64>>, Vec<Option<Vec<C64>>>)> {
    let set = &cx.set;
    let zeros = vec![C64::new(0.0, 0.0); nvar];
    let empty: &[C64] = &[];
    let terms = if forcing.is_some() {
        1
    } else {
        (0..done).map(|j| xs[j].len()).max().unwrap_or(1)
    };
    let systems: Vec<(Vec<u16>, Vec<(usize, usize)>)> = indices
        .iter()
        .map(|&idx| {
            let e = set.exponents(idx).to_vec();
            // the lower multi-indices j with e - j in the set, and e - j
            let below = (0..done)
                .filter_map(|j| sub_index(set, &e, set.exponents(j)).map(|t| (j, t)))
                .collect();
            (e, below)
        })
        .collect();
    let flat: Vec<(Vec<C64>, Option<Vec<C64>>)> = (0..systems.len() * terms)
        .into_par_iter()
        .map(|i| {
            let ((e, below), m) = (&systems[i / terms], i % terms);
            let x: Vec<&[C64]> = (0..done)
                .map(|j| xs[j].get(m).map_or(empty, Vec::as_slice))
                .collect();
            let s: Vec<&[C64]> = (0..done)
                .map(|j| ss[j].get(m).map_or(zeros.as_slice(), Vec::as_slice))
                .collect();
            cx.rhs_known(e, done, below, &x, &s, forcing.filter(|_| m == 0))
        })
        .collect();
    let mut flat = flat.into_iter();
    systems
        .iter()
        .map(|_| flat.by_ref().take(terms).unzip())
        .collect()
}
