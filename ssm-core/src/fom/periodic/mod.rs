//! Periodic orbits of the full forced system `B z' = A z + F(z) + eps Fext(z,
//! Omega t)` by harmonic balance with alternating frequency-time (AFT)
//! evaluation of the nonlinearity.
//!
//! # Formulation
//! An orbit of period `m T`, `T = 2 pi / Omega` (`m = 1` for the main
//! response, `m = 2` after a period doubling), is written in the angle
//! `psi = Omega t / m` as the truncated real Fourier series
//!
//! `z(psi) = c_0 + sum_{k=1}^{H} (c_k^c cos k psi + c_k^s sin k psi)`,
//!
//! and the Galerkin projection of the equation on the same `2H + 1`
//! functions gives the residual
//!
//! `R(c, Omega) = (Omega / m) (I ⊗ B)(D ⊗ I) c - P f(Z(c), psi) = 0`,
//!
//! with `D` the derivative in the Fourier basis (`(cos k)' = -k sin k`), `Z`
//! the values of `z` at `M` equally spaced angles, `f = A z + F(z) + eps
//! Fext(z, m psi)` evaluated there (the time domain), and `P` the discrete
//! Fourier projection back. `F` and `Fext` are polynomial (plugins are, and
//! a recast makes any model so), so `M > (d + 1) H + m k_f` samples, `d` the
//! largest degree and `k_f` the highest forcing harmonic, make `P` exact: the
//! only error is the truncation at `H` harmonics, which falls exponentially in
//! `H` for the analytic orbits of polynomial systems. Forcing harmonics above
//! `H` are part of that truncation: the projection drops them.
//!
//! Why harmonic balance rather than collocation or shooting:
//! - the model is a DAE of index up to 3 (multipliers of configuration
//!   constraints) or 1 (recast auxiliaries). The algebraic rows of `B z' = f`
//!   simply have no `Omega` term in `R`; there is no consistent initial value
//!   to find, no continuity condition to drop for algebraic variables, and no
//!   order reduction of collocation at index 3;
//! - the Jacobian is exact and sparse: a slot `(i, j)` of `DF` or `DFext` is a
//!   dense `(2H+1)^2` block of products of Fourier coefficients of
//!   `J_ij(psi)` (eq. `galerkin_block`), a slot of `A` alone is diagonal,
//!   and `B` couples `cos k` with `sin k`. One symbolic sparse LU of the
//!   bordered Jacobian serves the whole continuation;
//! - the Floquet exponents follow from the same Jacobian (Hill's method,
//!   [`floquet`]).
//!
//! Unknowns are scaled: `u = (c / a, Omega / w)`, `a` an amplitude scale and
//! `w` the width of the frequency range, so the arclength weighs amplitude and
//! frequency alike.
//!
//! # References
//! A. Cardona, T. Coune, A. Lerusse, M. Geradin, A multiharmonic method for
//! non-linear vibration analysis, Int. J. Numer. Meth. Eng. 37 (1994)
//! 1593-1608 (AFT); T. M. Cameron, J. H. Griffin, An alternating
//! frequency/time domain method for calculating the steady-state response of
//! nonlinear dynamic systems, J. Appl. Mech. 56 (1989) 149-154; M. Krack,
//! J. Gross, *Harmonic Balance for Nonlinear Vibration Problems*, Springer
//! (2019), Chs. 2-4 (convergence, Hill's method); G. von Groll, D. J. Ewins,
//! The harmonic balance method with arc-length continuation in rotor/stator
//! contact problems, J. Sound Vib. 241 (2001) 223-233.

pub(crate) mod amplitude;
mod branch;
mod doubling;
pub mod floquet;
pub mod frc;
mod gauge;
pub mod monodromy;
mod multipliers;
mod problem;
pub(crate) mod runs;
pub(crate) mod seed;

use faer::sparse::{SparseColMat, SymbolicSparseColMat};

use crate::fom::problem::DaeProblem;
use crate::model::system::System;
use crate::spectrum::dense::FiniteStructure;
use gauge::Gauge;
use ssm_kernel::continuation::sparse::SparseBordered;

pub use amplitude::{reference_amplitude, reference_amplitude_resumable, AmplitudeSettings};
pub use floquet::{Floquet, FloquetError};
pub use frc::{
    reference_frc, reference_frc_resumable, ReferenceBranch, ReferenceError, ReferenceEvent,
    ReferenceOrbit, ReferenceSettings,
};
pub use problem::Parameter;
pub use runs::Runs;
pub use seed::Seed;

/// Why a harmonic-balance discretization cannot be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HarmonicBalanceError {
    /// A forcing harmonic that is not an integer multiple of the orbit's
    /// base frequency.
    #[error("forcing harmonic {multiple} x Omega is not periodic with period {period_multiple} T: harmonic balance needs integer multiples")]
    NonIntegerHarmonic {
        /// The harmonic's multiple of `Omega`.
        multiple: f64,
        /// Period multiple `m`.
        period_multiple: usize,
    },
    /// The sparse symbolic analysis failed.
    #[error("symbolic LU of the harmonic-balance Jacobian failed: {0}")]
    Symbolic(String),
}

/// Where one slot `(i, j)` of the system's Jacobian pattern goes in the
/// harmonic-balance Jacobian.
#[derive(Debug, Clone)]
enum SlotPlan {
    /// A slot of `DF` or `DFext`: a dense block; `first[q]` is the position of
    /// row `i K` in column `j K + q` (rows `i K .. i K + K` follow it).
    Dense { slot: usize, first: Vec<usize> },
    /// A slot of `A` and `B` only: `diag[q]` is the position of `(i K + q,
    /// j K + q)`, `partner[q]` that of the `cos k <-> sin k` coupling of `B`.
    Linear {
        slot: usize,
        diag: Vec<usize>,
        partner: Vec<usize>,
    },
}

/// The harmonic-balance discretization of one system at one forcing
/// amplitude, harmonic count and period multiple: the continuation problem
/// in `(c / a, Omega / w)`.
pub struct HarmonicBalance<'a> {
    prob: DaeProblem<'a>,
    n: usize,
    harmonics: usize,
    multiple: usize,
    samples: usize,
    /// `cos(k psi_s)`, `sin(k psi_s)` for `k = 0..=2H`, row-major `s * (2H+1) + k`.
    cos: Vec<f64>,
    sin: Vec<f64>,
    plans: Vec<SlotPlan>,
    /// The Jacobian `[R_c a, R_Omega w]` (`N(2H+1) x N(2H+1) + 1`) and its
    /// bordered solves.
    solver: SparseBordered,
    /// Amplitude scale `a`.
    pub amplitude_scale: f64,
    /// Frequency scale `w`.
    pub frequency_scale: f64,
    /// The continuation parameter (the last unknown).
    pub parameter: Parameter,
    /// Forcing-amplitude scale (the last unknown is `eps / scale` when the
    /// parameter is the amplitude).
    pub epsilon_scale: f64,
    /// The Hill pencil's nilpotent structure, found at the first orbit.
    hill_structure: Option<FiniteStructure>,
    /// The recast's gauge conditions (rows `aux K`).
    gauges: Vec<Gauge>,
    /// A branch of period `2T` ends where the norm of its odd harmonics
    /// (scaled) falls below this: it has rejoined the period-`T` branch.
    pub odd_floor: Option<f64>,
    /// Floquet multipliers at each orbit (stability, folds as multipliers,
    /// period doublings, Neimark-Sacker); without them a branch has its
    /// folds in the parameter only and an empty stability column.
    pub stability: bool,
}

impl<'a> HarmonicBalance<'a> {
    /// The discretization of `sys` forced at amplitude `epsilon` with `H =
    /// harmonics` harmonics of `Omega / multiple`.
    pub fn new(
        sys: &'a System,
        epsilon: f64,
        harmonics: usize,
        multiple: usize,
    ) -> Result<Self, HarmonicBalanceError> {
        let multiple = multiple.max(1);
        // with omega = 1, DaeProblem's forcing at t = m psi is cos(k m psi)
        let prob = DaeProblem::new(sys, epsilon, 1.0);
        let n = sys.n_states();
        let h = harmonics;
        let kk = 2 * h + 1;
        let mut k_f = 0usize;
        if epsilon != 0.0 {
            for hm in &sys.forcing {
                let km = hm.multiple * multiple as f64;
                if (km - km.round()).abs() > 1e-9 || km < 0.0 {
                    return Err(HarmonicBalanceError::NonIntegerHarmonic {
                        multiple: hm.multiple,
                        period_multiple: multiple,
                    });
                }
                let km = km.round() as usize;
                k_f = k_f.max(km);
            }
        }
        let degree = |p: &ssm_api::PolyVector| {
            p.terms
                .iter()
                .map(|t| t.factors.iter().map(|f| f.power as usize).sum::<usize>())
                .max()
                .unwrap_or(1)
        };
        let mut d = degree(&sys.nonlinearity).max(1);
        if epsilon != 0.0 {
            for hm in &sys.forcing {
                d = d.max(degree(&hm.cos)).max(degree(&hm.sin));
            }
        }
        let samples = ((d + 1) * h + k_f + 1).max(4 * h + 2);
        let mut cos = vec![0.0; samples * (2 * h + 1)];
        let mut sin = vec![0.0; samples * (2 * h + 1)];
        for s in 0..samples {
            let psi = 2.0 * std::f64::consts::PI * s as f64 / samples as f64;
            for k in 0..=2 * h {
                let (si, co) = (k as f64 * psi).sin_cos();
                cos[s * (2 * h + 1) + k] = co;
                sin[s * (2 * h + 1) + k] = si;
            }
        }
        // which slots vary along the orbit
        let sp = prob.pattern().clone();
        let slot_of = |row: usize, col: usize| -> usize {
            let start = sp.col_ptr()[col];
            let rows = &sp.row_idx()[start..sp.col_ptr()[col + 1]];
            start + rows.binary_search(&row).expect("slot in the union pattern")
        };
        let mut varying = vec![false; sp.row_idx().len()];
        let mut polys = vec![&sys.nonlinearity];
        if epsilon != 0.0 {
            for hm in &sys.forcing {
                polys.push(&hm.cos);
                polys.push(&hm.sin);
            }
        }
        for p in polys {
            for t in p.terms.iter() {
                for f in t.factors.iter() {
                    varying[slot_of(t.eq as usize, f.var as usize)] = true;
                }
            }
        }
        let nu = n * kk;
        // (slot, row, column) of the system's pattern
        let slots: Vec<(usize, usize, usize)> = (0..n)
            .flat_map(|j| (sp.col_ptr()[j]..sp.col_ptr()[j + 1]).map(move |s| (s, j)))
            .map(|(s, j)| (s, sp.row_idx()[s], j))
            .collect();
        let mut cells: Vec<(usize, usize)> = Vec::new();
        for &(s, i, j) in &slots {
            for q in 0..kk {
                if varying[s] {
                    cells.extend((0..kk).map(|p| (j * kk + q, i * kk + p)));
                } else {
                    cells.push((j * kk + q, i * kk + q));
                    if q > 0 {
                        cells.push((j * kk + q, i * kk + partner(q)));
                    }
                }
            }
        }
        let mut gauges = Gauge::of(sys);
        for g in &gauges {
            for j in g.states() {
                cells.extend((0..kk).map(|q| (j * kk + q, g.aux * kk)));
            }
        }
        cells.extend((0..nu).map(|r| (nu, r)));
        cells.sort_unstable();
        cells.dedup();
        let pattern = column_pattern(nu, nu + 1, &cells);
        let pos = |row: usize, col: usize| -> usize {
            let start = pattern.col_ptr()[col];
            let rows = &pattern.row_idx()[start..pattern.col_ptr()[col + 1]];
            start + rows.binary_search(&row).expect("cell in the pattern")
        };
        let mut plans = Vec::with_capacity(varying.len());
        for &(s, i, j) in &slots {
            {
                plans.push(if varying[s] {
                    SlotPlan::Dense {
                        slot: s,
                        first: (0..kk).map(|q| pos(i * kk, j * kk + q)).collect(),
                    }
                } else {
                    SlotPlan::Linear {
                        slot: s,
                        diag: (0..kk).map(|q| pos(i * kk + q, j * kk + q)).collect(),
                        partner: (0..kk)
                            .map(|q| {
                                if q == 0 {
                                    usize::MAX
                                } else {
                                    pos(i * kk + partner(q), j * kk + q)
                                }
                            })
                            .collect(),
                    }
                });
            }
        }
        for g in &mut gauges {
            let row = g.aux * kk;
            g.row_positions = (0..=nu)
                .filter_map(|col| {
                    let start = pattern.col_ptr()[col];
                    let rows = &pattern.row_idx()[start..pattern.col_ptr()[col + 1]];
                    rows.binary_search(&row).ok().map(|p| start + p)
                })
                .collect();
            g.columns = g
                .states()
                .into_iter()
                .map(|j| (j, (0..kk).map(|q| pos(row, j * kk + q)).collect()))
                .collect();
        }
        Ok(Self {
            prob,
            n,
            harmonics: h,
            multiple,
            samples,
            cos,
            sin,
            plans,
            solver: SparseBordered::new(pattern),
            amplitude_scale: 1.0,
            frequency_scale: 1.0,
            parameter: Parameter::Frequency,
            epsilon_scale: 1.0,
            hill_structure: None,
            gauges,
            odd_floor: None,
            stability: true,
        })
    }

    /// Numeric sparse factorizations made.
    pub fn factorizations(&self) -> usize {
        self.solver.factorizations
    }

    /// Number of states `N`.
    pub fn n_states(&self) -> usize {
        self.n
    }

    /// Harmonics `H`.
    pub fn harmonics(&self) -> usize {
        self.harmonics
    }

    /// Period multiple `m`.
    pub fn period_multiple(&self) -> usize {
        self.multiple
    }

    /// Time samples per period of the AFT.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Number of Fourier coefficients `N (2H + 1)`.
    pub fn n_coefficients(&self) -> usize {
        self.n * (2 * self.harmonics + 1)
    }

    /// The forcing amplitude.
    pub fn epsilon(&self) -> f64 {
        self.prob.epsilon
    }

    /// The system.
    pub fn system(&self) -> &'a System {
        self.prob.sys
    }

    fn kk(&self) -> usize {
        2 * self.harmonics + 1
    }

    /// `z` at sample `s` from coefficients `c` (state-major, `K` per state).
    fn z_at(&self, c: &[f64], s: usize, out: &mut [f64]) {
        let kk = self.kk();
        let (co, si) = (&self.cos[s * kk..], &self.sin[s * kk..]);
        for (i, o) in out.iter_mut().enumerate() {
            let ci = &c[i * kk..(i + 1) * kk];
            let mut v = ci[0];
            for k in 1..=self.harmonics {
                v += ci[2 * k - 1] * co[k] + ci[2 * k] * si[k];
            }
            *o = v;
        }
    }

    /// The orbit's state at angle `psi = Omega t / m`.
    pub fn state_at(&self, c: &[f64], psi: f64) -> Vec<f64> {
        let kk = self.kk();
        let trig: Vec<(f64, f64)> = (1..=self.harmonics)
            .map(|k| (k as f64 * psi).sin_cos())
            .collect();
        (0..self.n)
            .map(|i| {
                let ci = &c[i * kk..(i + 1) * kk];
                (1..=self.harmonics)
                    .zip(&trig)
                    .fold(ci[0], |v, (k, &(s, co))| {
                        v + ci[2 * k - 1] * co + ci[2 * k] * s
                    })
            })
            .collect()
    }

    /// `(I ⊗ B)(D ⊗ I) c`, the Fourier coefficients of `B z_psi`.
    fn b_derivative(&self, c: &[f64]) -> Vec<f64> {
        let kk = self.kk();
        let mut dc = vec![0.0; c.len()];
        for i in 0..self.n {
            for k in 1..=self.harmonics {
                dc[i * kk + 2 * k - 1] = k as f64 * c[i * kk + 2 * k];
                dc[i * kk + 2 * k] = -(k as f64) * c[i * kk + 2 * k - 1];
            }
        }
        let mut out = vec![0.0; c.len()];
        let b = self.prob.sys.b.as_ref();
        for j in 0..self.n {
            for (i, v) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
                for q in 0..kk {
                    out[i * kk + q] += v * dc[j * kk + q];
                }
            }
        }
        out
    }

    /// `R(c, Omega)` in physical units.
    pub(crate) fn residual_physical(&self, c: &[f64], omega: f64) -> Vec<f64> {
        let kk = self.kk();
        let (n, m) = (self.n, self.samples);
        let mut r = self.b_derivative(c);
        let w = omega / self.multiple as f64;
        r.iter_mut().for_each(|v| *v *= w);
        self.project_into(c, -1.0, &mut r, |t, z, f| self.prob.rhs(t, z, f));
        if !self.gauges.is_empty() {
            // one synthesis of the state per sample for all gauges
            let mut z = vec![0.0; n];
            let mut sums = vec![0.0; self.gauges.len()];
            for s in 0..m {
                self.z_at(c, s, &mut z);
                for (g, sum) in self.gauges.iter().zip(&mut sums) {
                    *sum += g.defect(&z);
                }
            }
            let inv = 1.0 / m as f64;
            for (g, sum) in self.gauges.iter().zip(&sums) {
                r[g.aux * kk] = sum * inv;
            }
        }
        r
    }

    /// `P Fext(Z(c), m psi)`: the Fourier coefficients of the forcing per
    /// unit amplitude on the orbit (`R` is affine in `eps`, `R_eps = -P
    /// Fext`).
    fn forcing_projection(&self, c: &[f64]) -> Vec<f64> {
        let mut r = vec![0.0; c.len()];
        self.project_into(c, 1.0, &mut r, |t, z, f| self.prob.forcing_rhs(t, z, f));
        r
    }

    /// `r += weight P f(Z(c), m psi)`: the discrete Fourier projection of the
    /// time-domain function `eval(t, z, out)` (at the forcing phase `t = m
    /// psi`) on the orbit's samples.
    fn project_into(
        &self,
        c: &[f64],
        weight: f64,
        r: &mut [f64],
        eval: impl Fn(f64, &[f64], &mut [f64]),
    ) {
        let kk = self.kk();
        let m = self.samples;
        let mut z = vec![0.0; self.n];
        let mut f = vec![0.0; self.n];
        let inv = weight / m as f64;
        for s in 0..m {
            self.z_at(c, s, &mut z);
            eval(self.multiple as f64 * self.psi(s), &z, &mut f);
            let (co, si) = (&self.cos[s * kk..], &self.sin[s * kk..]);
            for (i, fi) in f.iter().enumerate() {
                let ri = &mut r[i * kk..(i + 1) * kk];
                ri[0] += inv * fi;
                for k in 1..=self.harmonics {
                    ri[2 * k - 1] += 2.0 * inv * fi * co[k];
                    ri[2 * k] += 2.0 * inv * fi * si[k];
                }
            }
        }
    }

    /// Sets the forcing amplitude (the parameter of an amplitude
    /// continuation). The forcing's terms are prepared only for a
    /// discretization made with `epsilon != 0`.
    pub(crate) fn set_epsilon(&mut self, epsilon: f64) {
        self.prob.epsilon = epsilon;
    }

    fn psi(&self, s: usize) -> f64 {
        2.0 * std::f64::consts::PI * s as f64 / self.samples as f64
    }

    /// Values of the Jacobian `[R_c a, R_Omega w]` in the pattern's order.
    fn jacobian_values(&self, c: &[f64], omega: f64) -> Vec<f64> {
        let kk = self.kk();
        let h = self.harmonics;
        let nu = self.n_coefficients();
        let pattern = self.solver.pattern();
        let mut vals = vec![0.0; pattern.row_idx().len()];
        let nslots = self.prob.pattern().row_idx().len();
        // Fourier coefficients of each slot of J(psi) up to 2H
        let mut jac = vec![0.0; nslots];
        let mut coef = vec![0.0; nslots * (4 * h + 1)];
        let mut z = vec![0.0; self.n];
        let m = self.samples;
        let inv = 1.0 / m as f64;
        let dense: Vec<usize> = self
            .plans
            .iter()
            .filter_map(|p| match p {
                SlotPlan::Dense { slot, .. } => Some(*slot),
                SlotPlan::Linear { .. } => None,
            })
            .collect();
        let mut constant = vec![0.0; nslots];
        for s in 0..m {
            self.z_at(c, s, &mut z);
            self.prob
                .jacobian(self.multiple as f64 * self.psi(s), &z, &mut jac);
            if s == 0 {
                constant.copy_from_slice(&jac);
            }
            let (co, si) = (&self.cos[s * kk..], &self.sin[s * kk..]);
            for &sl in &dense {
                let cs = &mut coef[sl * (4 * h + 1)..(sl + 1) * (4 * h + 1)];
                let v = jac[sl];
                cs[0] += inv * v;
                for k in 1..=2 * h {
                    cs[2 * k - 1] += 2.0 * inv * v * co[k];
                    cs[2 * k] += 2.0 * inv * v * si[k];
                }
            }
        }
        let b = self.prob.b_values();
        let wm = omega / self.multiple as f64;
        let a = self.amplitude_scale;
        let mut block = vec![0.0; kk * kk];
        for plan in &self.plans {
            match plan {
                SlotPlan::Dense { slot, first } => {
                    let cs = &coef[slot * (4 * h + 1)..(slot + 1) * (4 * h + 1)];
                    galerkin_block(cs, h, &mut block);
                    for q in 0..kk {
                        for p in 0..kk {
                            vals[first[q] + p] = -block[p * kk + q] * a;
                        }
                        if q > 0 {
                            let d = derivative_entry(q);
                            vals[first[q] + partner(q)] += wm * b[*slot] * d * a;
                        }
                    }
                }
                SlotPlan::Linear {
                    slot,
                    diag,
                    partner: pp,
                } => {
                    for q in 0..kk {
                        vals[diag[q]] = -constant[*slot] * a;
                        if q > 0 {
                            vals[pp[q]] = wm * b[*slot] * derivative_entry(q) * a;
                        }
                    }
                }
            }
        }
        // the parameter's column: R_Omega w, or R_eps s = -P Fext s
        let col_ptr = pattern.col_ptr();
        let rows = pattern.row_idx();
        let (r_par, pscale) = match self.parameter {
            Parameter::Frequency => (
                self.b_derivative(c),
                self.frequency_scale / self.multiple as f64,
            ),
            Parameter::Amplitude { .. } => (self.forcing_projection(c), -self.epsilon_scale),
        };
        for p in col_ptr[nu]..col_ptr[nu + 1] {
            vals[p] = r_par[rows[p]] * pscale;
        }
        self.gauge_rows(c, &mut vals);
        vals
    }

    /// Writes the gauge conditions' rows (scaled by the amplitude scale)
    /// over the auxiliaries' mean rows.
    fn gauge_rows(&self, c: &[f64], vals: &mut [f64]) {
        let kk = self.kk();
        let m = self.samples;
        let inv = 1.0 / m as f64;
        if self.gauges.is_empty() {
            return;
        }
        let mut z = vec![0.0; self.n];
        for g in &self.gauges {
            for &p in &g.row_positions {
                vals[p] = 0.0;
            }
        }
        // one synthesis of the state per sample for all gauges (each writes
        // its own row)
        for s in 0..m {
            self.z_at(c, s, &mut z);
            let (co, si) = (&self.cos[s * kk..], &self.sin[s * kk..]);
            for g in &self.gauges {
                for ((_, d), (_, pos)) in g.gradient(&z).into_iter().zip(&g.columns) {
                    let d = d * inv * self.amplitude_scale;
                    vals[pos[0]] += d;
                    for k in 1..=self.harmonics {
                        vals[pos[2 * k - 1]] += d * co[k];
                        vals[pos[2 * k]] += d * si[k];
                    }
                }
            }
        }
    }

    /// `R_c` (unscaled, `N(2H+1)` square) as a sparse matrix: Hill's method
    /// needs it.
    pub(crate) fn jacobian_physical(&self, c: &[f64], omega: f64) -> SparseColMat<usize, f64> {
        let nu = self.n_coefficients();
        let saved = self.amplitude_scale;
        let vals = self.jacobian_values(c, omega);
        let pattern = self.solver.pattern();
        let col_ptr = pattern.col_ptr();
        let rows = pattern.row_idx();
        let mut trip = Vec::with_capacity(vals.len());
        for col in 0..nu {
            for p in col_ptr[col]..col_ptr[col + 1] {
                if rows[p] < nu {
                    trip.push(faer::sparse::Triplet::new(rows[p], col, vals[p] / saved));
                }
            }
        }
        SparseColMat::try_new_from_triplets(nu, nu, &trip).expect("indices come from the pattern")
    }

    /// `I ⊗ B` in the coefficient ordering, without the gauge rows (which are
    /// algebraic).
    pub(crate) fn mass_blocks(&self) -> SparseColMat<usize, f64> {
        let kk = self.kk();
        let nu = self.n_coefficients();
        let b = self.prob.sys.b.as_ref();
        let mut trip = Vec::new();
        let gauged = |row: usize| self.gauges.iter().any(|g| g.aux * kk == row);
        for j in 0..self.n {
            for (i, v) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
                for q in 0..kk {
                    if !gauged(i * kk + q) {
                        trip.push(faer::sparse::Triplet::new(i * kk + q, j * kk + q, *v));
                    }
                }
            }
        }
        SparseColMat::try_new_from_triplets(nu, nu, &trip).expect("indices are in range")
    }

    /// Physical coefficients and frequency from scaled unknowns (the fixed
    /// frequency when the parameter is the amplitude).
    pub fn unscale(&self, u: &[f64]) -> (Vec<f64>, f64) {
        let nu = self.n_coefficients();
        let c = u[..nu].iter().map(|v| v * self.amplitude_scale).collect();
        match self.parameter {
            Parameter::Frequency => (c, u[nu] * self.frequency_scale),
            Parameter::Amplitude { omega } => (c, omega),
        }
    }

    /// Scaled unknowns from physical coefficients and the parameter's value
    /// (the frequency, or the forcing amplitude when the parameter is the
    /// amplitude).
    pub fn scale(&self, c: &[f64], parameter: f64) -> Vec<f64> {
        let mut u: Vec<f64> = c.iter().map(|v| v / self.amplitude_scale).collect();
        u.push(match self.parameter {
            Parameter::Frequency => parameter / self.frequency_scale,
            Parameter::Amplitude { .. } => parameter / self.epsilon_scale,
        });
        u
    }
}

/// The `nrows x ncols` pattern of the cells `(col, row)`, sorted and
/// without repeats.
fn column_pattern(
    nrows: usize,
    ncols: usize,
    cells: &[(usize, usize)],
) -> SymbolicSparseColMat<usize> {
    let mut col_ptr = vec![0usize; ncols + 1];
    for &(c, _) in cells {
        col_ptr[c + 1] += 1;
    }
    for j in 0..ncols {
        col_ptr[j + 1] += col_ptr[j];
    }
    let row_idx: Vec<usize> = cells.iter().map(|&(_, r)| r).collect();
    SymbolicSparseColMat::new_checked(nrows, ncols, col_ptr, None, row_idx)
}

/// The other function of a harmonic's pair: `cos k <-> sin k`.
fn partner(q: usize) -> usize {
    if q % 2 == 1 {
        q + 1
    } else {
        q - 1
    }
}

/// `D[partner(q)][q]`: the derivative maps `c_k^s` to `k` on `cos k` and
/// `c_k^c` to `-k` on `sin k`.
fn derivative_entry(q: usize) -> f64 {
    let k = q.div_ceil(2) as f64;
    if q.is_multiple_of(2) {
        k
    } else {
        -k
    }
}

/// The Galerkin block `G[p][q] = <phi_p, J phi_q> / <phi_p, phi_p>` of a
/// slot whose Fourier coefficients up to `2H` are `cs = (j_0, j_1^c, j_1^s,
/// ...)`, from the product-to-sum identities (`C(d) = <cos d psi J>`,
/// `S(d) = <sin d psi J>`):
///
/// `G[ck][cl] = C(k-l) + C(k+l)`, `G[ck][sl] = S(k+l) - S(k-l)`,
/// `G[sk][cl] = S(k+l) + S(k-l)`, `G[sk][sl] = C(k-l) - C(k+l)`,
/// `G[0][cl] = C(l)`, `G[0][sl] = S(l)`, `G[ck][0] = 2 C(k)`,
/// `G[sk][0] = 2 S(k)`, `G[0][0] = C(0)`; row-major in `out`.
pub(crate) fn galerkin_block(cs: &[f64], h: usize, out: &mut [f64]) {
    let kk = 2 * h + 1;
    let cc = |d: i64| -> f64 {
        let a = d.unsigned_abs() as usize;
        if a == 0 {
            cs[0]
        } else {
            0.5 * cs[2 * a - 1]
        }
    };
    let ss = |d: i64| -> f64 {
        let a = d.unsigned_abs() as usize;
        if a == 0 {
            0.0
        } else {
            0.5 * d.signum() as f64 * cs[2 * a]
        }
    };
    out[0] = cc(0);
    for l in 1..=h as i64 {
        let (cl, sl) = (2 * l as usize - 1, 2 * l as usize);
        out[cl] = cc(l);
        out[sl] = ss(l);
        out[cl * kk] = 2.0 * cc(l);
        out[sl * kk] = 2.0 * ss(l);
    }
    for k in 1..=h as i64 {
        let (ck, sk) = (2 * k as usize - 1, 2 * k as usize);
        for l in 1..=h as i64 {
            let (cl, sl) = (2 * l as usize - 1, 2 * l as usize);
            out[ck * kk + cl] = cc(k - l) + cc(k + l);
            out[ck * kk + sl] = ss(k + l) - ss(k - l);
            out[sk * kk + cl] = ss(k + l) + ss(k - l);
            out[sk * kk + sl] = cc(k - l) - cc(k + l);
        }
    }
}

/// Information at a point of a harmonic-balance branch.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OrbitInfo {
    /// Floquet analysis, when computed.
    pub floquet: Option<Floquet>,
}

#[cfg(test)]
mod tests;
