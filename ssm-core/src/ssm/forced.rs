//! The periodic SSM of a harmonically forced flow at leading order in `eps`
//! (eqs. 19-20 and 60).
//!
//! With `Fext(z, phi) = sum_h cos_h cos(kappa_h phi) + sin_h sin(kappa_h phi)`,
//! each harmonic is `F_h e^{i kappa_h phi} + c.c.` with `F_h = (cos_h(0) - i sin_h(0)) / 2`.
//! Inserting `W_eps = W(p) + eps X0(phi)`, `R_eps = R(p) + eps S0(phi)` with
//! `X0 = sum_h x_h e^{i kappa_h phi} + c.c.`, `S0 = sum_h s_h e^{i kappa_h phi} + c.c.`
//! into eq. (60) and collecting `eps p^0 e^{i kappa_h phi}` gives
//!
//! `(i kappa_h Omega B - A) x_h + B V s_h = F_h`,
//!
//! the homological equation of `ssm::homological` at `Lambda = i kappa_h Omega`.
//! Normal-form style: `s_h` has a component on the master coordinate `p_j`
//! exactly when the harmonic is externally resonant with it, `kappa_h = r_j`
//! for the resonance ratio vector `r` of eq. (16) (`lambda_j ~ i r_j Omega`);
//! those components are `s_{h,j} = u_j^* F_h` and the rest of the response
//! goes into `x_h`, closed by `u_j^* B x_h = 0`. In the rotating frame
//! `p_j = q_j e^{i r_j Omega t}` the reduced dynamics are then autonomous.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), eqs. (16), (19)-(20),
//! (59)-(61); M. Li, S. Jain, G. Haller, *Nonlinear analysis of forced mechanical
//! systems with internal resonance using spectral submanifolds, Part I*,
//! Nonlinear Dyn. 110 (2022), Sect. 3.

use ssm_api::PolyVector;

use super::homological::{horner, series_accept, Homological, HomologicalError, Solution};
use super::reduced_modes;
use crate::model::system::System;
use crate::spectrum::MasterMode;
use crate::C64;
use ssm_kernel::chebyshev::{self, Table};

/// Why the forced SSM could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ForcedError {
    /// The model has no forcing.
    #[error("the model defines no external forcing (Fext); a forced response needs one")]
    NoForcing,
    /// The resonance ratios do not match the master pairs.
    #[error("{found} resonance ratios for {pairs} master pairs")]
    Ratios {
        /// Ratios given.
        found: usize,
        /// Master pairs.
        pairs: usize,
    },
    /// Higher-order non-autonomous terms need state-independent forcing.
    #[error("the forcing depends on the state; higher-order non-autonomous terms need a state-independent Fext")]
    StateDependentForcing,
    /// A harmonic's homological equation failed.
    #[error("harmonic {harmonic} at Omega = {}: {source}", ssm_kernel::number::short(.omega))]
    Solve {
        /// 1-based harmonic.
        harmonic: usize,
        /// Forcing frequency.
        omega: f64,
        /// Cause.
        source: HomologicalError,
    },
}

/// One forcing harmonic's leading-order terms at one `Omega`.
#[derive(Debug, Clone)]
pub struct ForcedHarmonic {
    /// `kappa_h`: frequency as a multiple of `Omega`.
    pub multiple: f64,
    /// `x_h`: coefficient of `e^{i kappa_h phi}` in `X0` (`N` states).
    pub x: Vec<C64>,
    /// `s_h`: coefficient of `e^{i kappa_h phi}` in `S0`, per reduced coordinate
    /// (`p1, conj p1, p2, ...`); zero where not externally resonant.
    pub s: Vec<C64>,
}

/// `X0`, `S0` at one forcing frequency.
#[derive(Debug, Clone)]
pub struct ForcedTerms {
    /// Forcing frequency `Omega`.
    pub omega: f64,
    /// One entry per forcing harmonic.
    pub harmonics: Vec<ForcedHarmonic>,
}

impl ForcedTerms {
    /// The scalar output `sum w_s X0_s` at phase `phi` (real).
    pub fn output_at(&self, weights: &[(usize, f64)], phi: f64) -> f64 {
        self.harmonics
            .iter()
            .map(|h| {
                let c: C64 = weights.iter().map(|&(s, w)| h.x[s] * w).sum();
                2.0 * (c * C64::from_polar(1.0, h.multiple * phi)).re
            })
            .sum()
    }

    /// Total forcing `eps * S0` coefficient on reduced coordinate `j` at ratio
    /// `r_j` (the sum over harmonics resonant with it).
    pub fn resonant_forcing(&self, coord: usize) -> C64 {
        self.harmonics.iter().map(|h| h.s[coord]).sum()
    }
}

/// The harmonics' coefficients of a few scalar outputs of `X0` at one
/// forcing frequency: `c_{h,o} = sum_s w_{o,s} x_{h,s}`.
#[derive(Debug, Clone)]
pub(crate) struct OutputCoefficients {
    multiples: Vec<f64>,
    n_outputs: usize,
    /// Harmonic-major: `c[h * n_outputs + o]`.
    c: Vec<C64>,
}

impl OutputCoefficients {
    /// Output `o` of `X0` at phase `phi` (real), as [`ForcedTerms::output_at`].
    pub fn value(&self, o: usize, phi: f64) -> f64 {
        let turns: Vec<C64> = self
            .multiples
            .iter()
            .map(|&kappa| C64::from_polar(1.0, kappa * phi))
            .collect();
        self.value_turned(o, &turns)
    }

    /// Output `o` of `X0` where harmonic `h` has turned to `turns[h] = e^{i
    /// kappa_h phi}` (for many outputs or points at the same phases).
    pub(crate) fn value_turned(&self, o: usize, turns: &[C64]) -> f64 {
        turns
            .iter()
            .enumerate()
            .map(|(h, t)| 2.0 * (self.c[h * self.n_outputs + o] * t).re)
            .sum()
    }
}

/// Largest relative interpolation error of [`ForcedSsm::tabulate_outputs`]
/// accepted; beyond it every frequency is solved exactly. Four orders below
/// the 1 % accuracy figures of a forced response, and above the rounding
/// error of the bordered solves of large stiff models (measured 7e-8 for the
/// 14,402-state divider, 2e-11 for its 146 states).
pub(crate) const OUTPUT_TABLE_TOLERANCE: f64 = 1e-6;

/// Largest relative error estimate of [`ForcedSsm::tabulate_outputs`] at
/// which the table is still used (with a warning above
/// [`OUTPUT_TABLE_TOLERANCE`]): the interpolant has converged to the noise of
/// the solves themselves (ill-conditioned `Lambda B - A`, e.g. a very fine
/// mesh), and solving every point would be no more accurate. Beyond it the
/// table did not converge (a non-master eigenvalue near `i Omega`).
pub(crate) const OUTPUT_TABLE_ACCEPT: f64 = 1e-2;

/// The warning for a table of [`ForcedSsm::tabulate_outputs`] over `range`
/// with error estimate `error`, if any.
pub(crate) fn table_warning(error: f64, range: (f64, f64)) -> Option<String> {
    if error <= OUTPUT_TABLE_TOLERANCE {
        None
    } else if error <= OUTPUT_TABLE_ACCEPT {
        Some(format!(
            "X0 over [{}, {}] is interpolated in Omega to {error:.1e} (relative), the accuracy of the sparse solves themselves: Lambda B - A is ill-conditioned (a very fine mesh or a stiff model)",
            range.0, range.1
        ))
    } else {
        Some(format!(
            "X0 could not be interpolated in Omega over [{}, {}] (estimated error {error:.1e}): either a non-master eigenvalue is near i Omega, or the sparse solves of this model have lost that much precision (an ill-conditioned pencil: compare the eigenvalues with a coarser mesh); the outputs are solved at every point instead, one sparse solve of the full system per point",
            range.0, range.1
        ))
    }
}

/// Most Chebyshev nodes (exact solves) spent on an output table.
const OUTPUT_TABLE_MAX_NODES: usize = 129;

/// Value of a forcing polynomial at the origin (its constant terms).
fn at_origin(p: &PolyVector, n: usize) -> Vec<f64> {
    let mut v = vec![0.0; n];
    for t in p.terms.iter().filter(|t| t.factors.is_empty()) {
        v[t.eq as usize] += t.coeff;
    }
    v
}

/// The whole `X0`, `S0` over the band `center +- half_width` as Taylor
/// series in `t = (Omega - center) / half_width`: per harmonic the term
/// lists of `x` and of the resonant coordinates' `s`, and the floor their
/// refined solves reached.
struct X0Series {
    center: f64,
    half_width: f64,
    harmonics: Vec<HarmonicSeries>,
}

/// One harmonic's terms of `x` and of `s` on the resonant coordinates, and
/// their floor.
type HarmonicSeries = (Vec<Vec<C64>>, Vec<Vec<C64>>, f64);

/// The leading-order periodic SSM of one system and master set, evaluated at
/// any forcing frequency; one symbolic LU serves every frequency.
pub struct ForcedSsm<'a> {
    /// The bordered solver (its series solves serve the non-autonomous
    /// expansions directly).
    pub(super) solver: Homological<'a>,
    forcing: Vec<(f64, Vec<C64>, Vec<usize>)>,
    n_coords: usize,
    lambda: Vec<C64>,
    coord_ratios: Vec<f64>,
    outputs: Vec<Vec<(usize, f64)>>,
    table: Option<Table>,
    /// The whole `X0`, `S0` of the output table's series, where they were
    /// accepted ([`ForcedSsm::at_series`]).
    x0_series: Option<X0Series>,
    /// The frequency whose factorization preconditions the solves of
    /// [`ForcedSsm::at`] (see [`ForcedSsm::anchor_at`]).
    anchor: Option<f64>,
}

impl<'a> ForcedSsm<'a> {
    /// Prepares the forcing amplitudes `F_h` and the resonant sets for master
    /// modes `masters` with external resonance ratios `ratios` (one per master
    /// pair, eq. 16).
    pub fn new(
        sys: &'a System,
        masters: &[MasterMode],
        ratios: &[f64],
    ) -> Result<Self, ForcedError> {
        if sys.forcing.is_empty() {
            return Err(ForcedError::NoForcing);
        }
        if ratios.len() != masters.len() {
            return Err(ForcedError::Ratios {
                found: ratios.len(),
                pairs: masters.len(),
            });
        }
        let n = sys.n_states();
        let (lambda, right, left) = reduced_modes(masters);
        let solver = Homological::new(
            sys.a.as_ref(),
            sys.b.as_ref(),
            sys.velocities(),
            &lambda,
            &right,
            &left,
        );
        let forcing = sys
            .forcing
            .iter()
            .map(|h| {
                let c = at_origin(&h.cos, n);
                let s = at_origin(&h.sin, n);
                let f: Vec<C64> = c
                    .iter()
                    .zip(&s)
                    .map(|(&c, &s)| C64::new(0.5 * c, -0.5 * s))
                    .collect();
                // e^{i kappa phi} resonates with p_j when kappa = r_j (never with conj p_j)
                let set: Vec<usize> = ratios
                    .iter()
                    .enumerate()
                    .filter(|(_, &r)| (r - h.multiple).abs() <= 1e-12 * r.abs().max(1.0))
                    .map(|(pair, _)| 2 * pair)
                    .collect();
                (h.multiple, f, set)
            })
            .collect();
        let coord_ratios = ratios.iter().flat_map(|&r| [r, -r]).collect();
        Ok(Self {
            solver,
            forcing,
            n_coords: lambda.len(),
            lambda,
            coord_ratios,
            outputs: Vec::new(),
            table: None,
            x0_series: None,
            anchor: None,
        })
    }

    /// Master eigenvalues per reduced coordinate (`lambda_1, conj lambda_1, ...`).
    pub(crate) fn lambda(&self) -> &[C64] {
        &self.lambda
    }

    /// Resonance ratio per reduced coordinate (`r_j` for `p_j`, `-r_j` for its conjugate).
    pub(crate) fn coord_ratios(&self) -> &[f64] {
        &self.coord_ratios
    }

    /// Number of forcing harmonics.
    pub(crate) fn n_harmonics(&self) -> usize {
        self.forcing.len()
    }

    /// `(kappa_h, F_h)` of harmonic `h`.
    pub(crate) fn harmonic(&self, h: usize) -> (f64, &[C64]) {
        (self.forcing[h].0, &self.forcing[h].1)
    }

    /// One bordered solve (see [`Homological::solve`]).
    pub(crate) fn solve(
        &mut self,
        big: C64,
        set: &[usize],
        rhs: &[C64],
    ) -> Result<(Vec<C64>, Vec<C64>), HomologicalError> {
        self.solver.solve(big, set, rhs)
    }

    /// Bordered solves at every value of `bigs` through the factorization at
    /// the nearby `anchor` (see [`Homological::solve_band`]).
    pub(crate) fn solve_band(
        &mut self,
        bigs: &[C64],
        anchor: C64,
        set: &[usize],
        rhss: &[&[C64]],
    ) -> Result<Vec<Solution>, HomologicalError> {
        self.solver.solve_band(bigs, anchor, set, rhss)
    }

    /// Whether band solves iterate through one factorization (the model's
    /// factors are dear).
    pub(crate) fn iterative(&mut self) -> bool {
        self.solver.iterative()
    }

    /// Whether the model's forcing is constant in the state (what the
    /// higher-order non-autonomous terms need).
    pub(crate) fn forcing_is_constant(&self, sys: &System) -> bool {
        sys.forcing.iter().all(|h| {
            h.cos
                .terms
                .iter()
                .chain(h.sin.terms.iter())
                .all(|t| t.factors.is_empty())
        })
    }

    /// Forgets the factorization at `anchor`, unless it is the one of
    /// [`ForcedSsm::anchor_at`] (`i kappa_h Omega` at the band's middle, kept
    /// for [`ForcedSsm::at`], the X0 table and the multi-index 0 of every
    /// later expansion).
    pub(crate) fn release_anchor(&mut self, anchor: C64) {
        let pinned = self.anchor.is_some_and(|c| {
            self.forcing
                .iter()
                .any(|(multiple, _, _)| C64::new(0.0, multiple * c) == anchor)
        });
        if !pinned {
            self.solver.release_anchor(anchor);
        }
    }

    /// Forgets the factorizations at the anchor of [`ForcedSsm::anchor_at`]
    /// (kept for the output table and the leading order), the anchor
    /// itself kept: a later solve there factorizes it again (counted). For
    /// the expansions of higher order, whose multi-index 0 takes the output
    /// table's series and whose other multi-indices have anchors of their
    /// own: their factors then do not sit beside it.
    pub fn drop_anchor_factors(&mut self) {
        if let Some(c) = self.anchor {
            for (multiple, _, _) in &self.forcing {
                self.solver.release_anchor(C64::new(0.0, multiple * c));
            }
        }
    }

    /// Solves [`ForcedSsm::at`] through one factorization at `omega` (the
    /// middle of a frequency band) for every frequency
    /// (`Homological::solve_band`), instead of a factorization per
    /// frequency.
    pub fn anchor_at(&mut self, omega: f64) {
        self.anchor = Some(omega);
    }

    /// The factorizations and solves spent so far.
    pub fn counts(&self) -> super::SolveCounts {
        self.solver.stats.counts()
    }

    /// The most heap the sparse factors held at once (see
    /// [`super::SolveStats::factor_bytes`]).
    pub fn factor_bytes(&self) -> Option<usize> {
        self.solver.stats.factor_bytes
    }

    /// Forgets cached numeric factorizations.
    pub(crate) fn clear(&mut self) {
        self.solver.clear_numeric();
    }

    /// `X0`, `S0` at forcing frequency `omega`.
    pub fn at(&mut self, omega: f64) -> Result<ForcedTerms, ForcedError> {
        let mut harmonics = Vec::with_capacity(self.forcing.len());
        for (k, (multiple, f, set)) in self.forcing.iter().enumerate() {
            let big = C64::new(0.0, multiple * omega);
            let solved = match self.anchor {
                Some(c) => self
                    .solver
                    .solve_band(&[big], C64::new(0.0, multiple * c), set, &[f])
                    .map(|mut v| v.pop().expect("one value")),
                None => self.solver.solve(big, set, f),
            };
            let (x, r) = solved.map_err(|source| ForcedError::Solve {
                harmonic: k + 1,
                omega,
                source,
            })?;
            let mut s = vec![C64::new(0.0, 0.0); self.n_coords];
            for (&j, v) in set.iter().zip(r) {
                s[j] = v;
            }
            harmonics.push(ForcedHarmonic {
                multiple: *multiple,
                x,
                s,
            });
        }
        self.solver.clear_numeric();
        Ok(ForcedTerms { omega, harmonics })
    }

    /// Output coefficients at `omega` from a direct solve.
    fn solve_outputs(&mut self, omega: f64) -> Result<Vec<C64>, ForcedError> {
        let terms = self.at(omega)?;
        let outputs = &self.outputs;
        Ok(terms
            .harmonics
            .iter()
            .flat_map(|h| {
                outputs
                    .iter()
                    .map(|w| w.iter().map(|&(s, v)| h.x[s] * v).sum::<C64>())
            })
            .collect())
    }

    /// Tabulates the outputs `weights` of `X0` over `[a, b]` for
    /// `ForcedSsm::outputs_at`: each `c_{h,o}(Omega)` is analytic there
    /// unless a non-master eigenvalue sits at `i kappa_h Omega` (the master
    /// resonances are removed by the bordering of eq. 60), so Chebyshev
    /// interpolation converges geometrically and a few dozen sparse solves
    /// serve every point of a curve. Returns the table's relative error
    /// estimate; when it exceeds `OUTPUT_TABLE_ACCEPT` the table is
    /// dropped and every frequency is solved exactly.
    ///
    /// # Errors
    /// A failed solve at a node.
    pub fn tabulate_outputs(
        &mut self,
        a: f64,
        b: f64,
        weights: &[&[(usize, f64)]],
    ) -> Result<f64, ForcedError> {
        self.tabulate_outputs_within(a, b, (a, b), weights)
    }

    /// [`ForcedSsm::tabulate_outputs`] with the outputs' Taylor series (where
    /// band solves run) expanded over `band`, which holds `[a, b]` and has
    /// its middle: the band of the non-autonomous table's nodes, whose
    /// multi-index 0 then takes the same series;
    /// over `[a, b]` where the series does not converge over `band`.
    ///
    /// # Errors
    /// A failed solve at a node.
    pub fn tabulate_outputs_within(
        &mut self,
        a: f64,
        b: f64,
        band: (f64, f64),
        weights: &[&[(usize, f64)]],
    ) -> Result<f64, ForcedError> {
        self.outputs = weights.iter().map(|w| w.to_vec()).collect();
        self.table = None;
        self.x0_series = None;
        let wide = band.0 <= a && band.1 >= b && band != (a, b);
        let series = if !self.solver.iterative() {
            None
        } else if let Some(s) = wide
            .then(|| self.output_series(band.0, band.1))
            .transpose()?
            .flatten()
        {
            Some(s)
        } else {
            self.output_series(a, b)?
        };
        let table = match series {
            // the outputs' Taylor series in Omega, tabulated
            Some((center, half_width, terms)) => chebyshev::adaptive(
                a,
                b,
                OUTPUT_TABLE_TOLERANCE,
                OUTPUT_TABLE_MAX_NODES,
                |omega| {
                    let t = (omega - center) / half_width;
                    Ok::<_, ForcedError>(horner(&terms, t))
                },
            )?,
            None => chebyshev::adaptive(
                a,
                b,
                OUTPUT_TABLE_TOLERANCE,
                OUTPUT_TABLE_MAX_NODES,
                |omega| self.solve_outputs(omega),
            )?,
        };
        let error = table.error;
        if error <= OUTPUT_TABLE_ACCEPT {
            self.table = Some(table);
        }
        Ok(error)
    }

    /// The outputs of `X0` over `[a, b]` as Taylor series in `t = (Omega -
    /// center) / half_width` (module `series` of `homological`: one
    /// factorization at the middle per harmonic), each term's output
    /// coefficients harmonic-major as [`ForcedSsm::solve_outputs`] gives
    /// them; `None` when a harmonic's series does not converge or its value
    /// at either end or the middle misses the componentwise backward error
    /// of `series_accept`.
    #[allow(clippy::type_complexity)]
    fn output_series(
        &mut self,
        a: f64,
        b: f64,
    ) -> Result<Option<(f64, f64, Vec<Vec<C64>>)>, ForcedError> {
        let (center, half_width) = (0.5 * (a + b), 0.5 * (b - a));
        if !(half_width > 0.0 && half_width.is_finite()) {
            return Ok(None);
        }
        let mut terms: Vec<Vec<C64>> = Vec::new();
        let mut whole = X0Series {
            center,
            half_width,
            harmonics: Vec::with_capacity(self.forcing.len()),
        };
        for (k, (multiple, f, set)) in self.forcing.iter().enumerate() {
            let anchor = C64::new(0.0, multiple * center);
            let slope = C64::new(0.0, multiple * half_width);
            let zero = C64::new(0.0, 0.0);
            let solved = self
                .solver
                .solve_series(anchor, zero, slope, set, std::slice::from_ref(f))
                .map_err(|source| ForcedError::Solve {
                    harmonic: k + 1,
                    omega: center,
                    source,
                })?;
            let Some((series, floor)) = solved else {
                return Ok(None);
            };
            let (w, r): (Vec<Vec<C64>>, Vec<Vec<C64>>) = series.into_iter().unzip();
            for t in [-1.0, 0.0, 1.0] {
                let (wt, rt) = (horner(&w, t), horner(&r, t));
                let error = self
                    .solver
                    .backward_error(anchor + slope * t, set, &wt, &rt, f);
                if error.is_nan() || error > series_accept(floor) {
                    return Ok(None);
                }
            }
            if terms.len() < w.len() {
                terms.resize(w.len(), Vec::new());
            }
            for (m, xm) in w.iter().enumerate() {
                let row = &mut terms[m];
                row.resize(k * self.outputs.len(), zero);
                row.extend(
                    self.outputs
                        .iter()
                        .map(|o| o.iter().map(|&(s, v)| xm[s] * v).sum::<C64>()),
                );
            }
            whole.harmonics.push((w, r, floor));
        }
        self.x0_series = Some(whole);
        let width = self.forcing.len() * self.outputs.len();
        terms
            .iter_mut()
            .for_each(|row| row.resize(width, C64::new(0.0, 0.0)));
        Ok(Some((center, half_width, terms)))
    }

    /// `X0`, `S0` at `omega` from the Taylor series of
    /// [`ForcedSsm::tabulate_outputs`] (a polynomial evaluation in place of
    /// a band solve), where `omega` lies in its band and the value solves
    /// each harmonic's bordered system there to the backward error the
    /// series was accepted with (`series_accept`); `None` otherwise.
    pub fn at_series(&self, omega: f64) -> Option<ForcedTerms> {
        let x0 = self.x0_series.as_ref()?;
        let t = (omega - x0.center) / x0.half_width;
        if t.is_nan() || t.abs() > 1.0 + 1e-12 {
            return None;
        }
        let mut harmonics = Vec::with_capacity(self.forcing.len());
        for ((multiple, f, set), (w, r, floor)) in self.forcing.iter().zip(&x0.harmonics) {
            let (x, rt) = (horner(w, t), horner(r, t));
            let big = C64::new(0.0, multiple * omega);
            let error = self.solver.backward_error(big, set, &x, &rt, f);
            if error.is_nan() || error > series_accept(*floor) {
                return None;
            }
            let mut s = vec![C64::new(0.0, 0.0); self.n_coords];
            for (&j, v) in set.iter().zip(rt) {
                s[j] = v;
            }
            harmonics.push(ForcedHarmonic {
                multiple: *multiple,
                x,
                s,
            });
        }
        Some(ForcedTerms { omega, harmonics })
    }

    /// The terms of harmonic `h`'s `X0` and `S0` (resonant coordinates) as
    /// a Taylor series in `t = (Omega - center) / half_width`, with their
    /// floor: the output table's series, whose band has the same middle and
    /// holds this one, rescaled (`a_m (half_width / h_0)^m` for its half
    /// width `h_0`, exact); `None` without such a series.
    #[allow(clippy::type_complexity)]
    pub(crate) fn x0_terms(
        &self,
        h: usize,
        center: f64,
        half_width: f64,
    ) -> Option<(Vec<Vec<C64>>, Vec<Vec<C64>>, f64)> {
        let x0 = self.x0_series.as_ref()?;
        let same_middle = (x0.center - center).abs() <= 1e-12 * center.abs().max(x0.half_width);
        if !(same_middle && half_width > 0.0 && half_width <= x0.half_width) {
            return None;
        }
        let (w, r, floor) = x0.harmonics.get(h)?;
        let ratio = half_width / x0.half_width;
        let scaled = |terms: &[Vec<C64>]| -> Vec<Vec<C64>> {
            let mut f = 1.0;
            terms
                .iter()
                .map(|t| {
                    let v = t.iter().map(|c| c * f).collect();
                    f *= ratio;
                    v
                })
                .collect()
        };
        Some((scaled(w), scaled(r), *floor))
    }

    /// The forcing set (resonant coordinates) of harmonic `h`.
    pub(crate) fn forcing_set(&self, h: usize) -> &[usize] {
        &self.forcing[h].2
    }

    /// The outputs of [`ForcedSsm::tabulate_outputs`] at `omega`:
    /// interpolated inside the table's range, solved exactly elsewhere or
    /// without a table.
    ///
    /// # Errors
    /// A failed solve.
    pub(crate) fn outputs_at(&mut self, omega: f64) -> Result<OutputCoefficients, ForcedError> {
        let inside = self.table.as_ref().filter(|t| t.contains(omega));
        let c = match inside {
            Some(t) => t.at(omega),
            None => self.solve_outputs(omega)?,
        };
        Ok(OutputCoefficients {
            multiples: self.forcing.iter().map(|f| f.0).collect(),
            n_outputs: self.outputs.len(),
            c,
        })
    }
}
