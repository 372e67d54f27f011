//! The three-stage Radau IIA stepper (order 5) for `B z' = f(t, z)` with a
//! singular `B`, after RADAU5 (Hairer & Wanner II, Sect. IV.8).
//!
//! With stage increments `Z = (Z_1, Z_2, Z_3)`, `Z_i = Y_i - z_n`, the
//! collocation equations are `(I ⊗ B) Z = h (A_R ⊗ I) F(Z)`. Writing
//! `A_R^{-1} = T diag(gamma, [[alpha, -beta], [beta, alpha]]) T^{-1}` and
//! `W = (T^{-1} ⊗ I) Z`, each simplified Newton step solves one real system
//! with `(gamma/h) B - J` and one complex system with `((alpha + i beta)/h) B - J`
//! (eq. (8.19) of Sect. IV.8). The error estimate is eq. (8.20) with the mass
//! matrix, `err = ((gamma/h) B - J)^{-1} (f(z_n) + B (e_1 Z_1 + e_2 Z_2 + e_3 Z_3)/h)`,
//! measured in a norm whose index-2 and index-3 components are scaled by `h`
//! and `h^2` (Sect. VII.8). The collocation polynomial gives the dense output.
//!
//! # References
//! E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed.,
//! Springer (1996), Sects. IV.8 and VII.8; the RADAU5 code of the same authors
//! (constants `T`, `T^{-1}`, step-size and Newton controls).

use faer::sparse::SparseColMat;
use faer::{Mat, Par};

use super::{DaeProblem, SimError};
use crate::C64;
use ssm_kernel::sparse_lu::SparseLu;
use ssm_kernel::stepper::{StepStats, Stepper};

const SQ6: f64 = 2.449_489_742_783_178;
/// Collocation nodes.
const C1: f64 = (4.0 - SQ6) / 10.0;
const C2: f64 = (4.0 + SQ6) / 10.0;

/// The Radau IIA matrix `A_R` (three stages, order 5; Hairer & Wanner II,
/// Table IV.5.6).
pub(crate) const RADAU_A: [[f64; 3]; 3] = [
    [
        (88.0 - 7.0 * SQ6) / 360.0,
        (296.0 - 169.0 * SQ6) / 1800.0,
        (-2.0 + 3.0 * SQ6) / 225.0,
    ],
    [
        (296.0 + 169.0 * SQ6) / 1800.0,
        (88.0 + 7.0 * SQ6) / 360.0,
        (-2.0 - 3.0 * SQ6) / 225.0,
    ],
    [(16.0 - SQ6) / 36.0, (16.0 + SQ6) / 36.0, 1.0 / 9.0],
];

/// The Radau IIA nodes `c`.
pub(crate) const RADAU_C: [f64; 3] = [C1, C2, 1.0];
const C1M1: f64 = C1 - 1.0;
const C2M1: f64 = C2 - 1.0;
const C1MC2: f64 = C1 - C2;
/// Error-estimate weights `e_i` (eq. (8.20)).
const DD1: f64 = -(13.0 + 7.0 * SQ6) / 3.0;
const DD2: f64 = (-13.0 + 7.0 * SQ6) / 3.0;
const DD3: f64 = -1.0 / 3.0;
/// `T` and `T^{-1}` of RADAU5.
const T: [[f64; 3]; 3] = [
    [
        9.123_239_487_089_294e-2,
        -0.141_255_295_020_954_2,
        -3.002_919_410_514_742_4e-2,
    ],
    [
        0.241_717_932_707_107,
        0.204_129_352_293_799_9,
        0.382_942_112_757_261_9,
    ],
    [0.966_048_182_615_093, 1.0, 0.0],
];
const TI: [[f64; 3]; 3] = [
    [
        4.325_579_890_063_155,
        0.339_199_251_815_809_9,
        0.541_770_539_935_874_9,
    ],
    [
        -4.178_718_591_551_905,
        -0.327_682_820_761_062_4,
        0.476_623_554_500_550_5,
    ],
    [
        -0.502_872_634_945_786_9,
        2.571_926_949_855_605,
        -0.596_039_204_828_224_9,
    ],
];

/// Eigenvalues of `A_R^{-1}`: `gamma` (real) and `alpha +- i beta`.
fn radau_eigenvalues() -> (f64, f64, f64) {
    let c81 = 81f64.cbrt();
    let c9 = 9f64.cbrt();
    let u1 = (6.0 + c81 - c9) / 30.0;
    let alph = (12.0 - c81 + c9) / 60.0;
    let beta = (c81 + c9) * 3f64.sqrt() / 60.0;
    let cno = alph * alph + beta * beta;
    (1.0 / u1, alph / cno, beta / cno)
}

/// Settings of the integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadauOptions {
    /// Relative tolerance of the local error.
    pub rtol: f64,
    /// Absolute tolerance of the local error.
    pub atol: f64,
    /// First step (default: `1e-3 (t_end - t0)` bounded by `h_max`).
    pub h0: Option<f64>,
    /// Largest step.
    pub h_max: f64,
    /// Steps at most (accepted and rejected).
    pub max_steps: usize,
    /// A fixed step size without error control (for convergence studies).
    pub fixed_step: Option<f64>,
}

impl Default for RadauOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-8,
            atol: 1e-10,
            h0: None,
            h_max: f64::INFINITY,
            max_steps: 2_000_000,
            fixed_step: None,
        }
    }
}

/// Work counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RadauStats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps (error test or Newton failure).
    pub rejected: usize,
    /// Jacobian evaluations.
    pub jacobians: usize,
    /// Pairs of numeric LU factorizations (real and complex).
    pub factorizations: usize,
    /// Newton iterations.
    pub newton: usize,
    /// Right-hand side evaluations.
    pub rhs: usize,
}

const NIT: usize = 7;
const SAFE: f64 = 0.9;
const FACL: f64 = 5.0;
const FACR: f64 = 0.125;
const THET: f64 = 0.001;
const QUOT1: f64 = 1.0;
const QUOT2: f64 = 1.2;
const UROUND: f64 = 1e-16;

/// A Radau IIA integration in progress.
pub struct Radau<'p, 'a> {
    p: &'p DaeProblem<'a>,
    opts: RadauOptions,
    rtol: f64,
    atol: f64,
    fnewt: f64,
    gamma: f64,
    alpha: f64,
    beta: f64,
    t: f64,
    y: Vec<f64>,
    f0: Vec<f64>,
    h: f64,
    h_old: f64,
    /// Dense-output coefficients of the last accepted step.
    cont: [Vec<f64>; 3],
    first: bool,
    reject: bool,
    theta: f64,
    faccon: f64,
    h_acc: f64,
    err_acc: f64,
    jac: Vec<f64>,
    jac_current: bool,
    need_jac: bool,
    need_lu: bool,
    /// The LUs of the real and the complex iteration matrix, on one thread
    /// each (the matrices are `3N` at most a few thousand: threads inside
    /// one factorization cost more than they give; callers run independent
    /// integrations in parallel instead).
    lu_real: SparseLu<f64>,
    lu_cplx: SparseLu<C64>,
    /// Why the last step was rejected (reported when steps collapse).
    last_cause: &'static str,
    /// Newton iterations of the last converged stage solve.
    last_newton: usize,
    /// Work counters.
    pub stats: RadauStats,
}

impl<'p, 'a> Radau<'p, 'a> {
    /// Starts at `(t0, z0)`; `z0` must be consistent ([`super::consistent_initial`]).
    pub fn new(
        p: &'p DaeProblem<'a>,
        t0: f64,
        z0: &[f64],
        t_end: f64,
        opts: RadauOptions,
    ) -> Result<Self, SimError> {
        if !(opts.rtol > 0.0 && opts.atol > 0.0 && opts.rtol < 1.0) {
            return Err(SimError::Settings(format!(
                "tolerances must satisfy 0 < rtol < 1 and atol > 0 (rtol = {}, atol = {})",
                opts.rtol, opts.atol
            )));
        }
        if z0.len() != p.n() {
            return Err(SimError::Settings(format!(
                "initial state has {} entries, the system {}",
                z0.len(),
                p.n()
            )));
        }
        if let Some(i) = z0.iter().position(|v| !v.is_finite()) {
            return Err(SimError::NonFinite {
                t: t0,
                state: p.state_name(i).to_owned(),
            });
        }
        let analyze_fail = |e: faer::sparse::FaerError| SimError::SingularIteration {
            t: t0,
            h: 0.0,
            detail: format!("symbolic LU of the iteration matrix failed: {e:?}"),
        };
        let lu_real = SparseLu::analyze(p.pattern().as_ref(), Par::Seq).map_err(analyze_fail)?;
        let lu_cplx = SparseLu::analyze(p.pattern().as_ref(), Par::Seq).map_err(analyze_fail)?;
        // RADAU5's tolerance transformation: the order-3 error estimate is
        // compared with 0.1 rtol^(2/3)
        let quot = opts.atol / opts.rtol;
        let rtol = 0.1 * opts.rtol.powf(2.0 / 3.0);
        let atol = rtol * quot;
        let fnewt = (10.0 * UROUND / rtol).max(0.03f64.min(rtol.sqrt()));
        let (gamma, alpha, beta) = radau_eigenvalues();
        let span = (t_end - t0).abs().max(1e-12);
        let h = match opts.fixed_step {
            Some(h) if h > 0.0 => h,
            Some(h) => {
                return Err(SimError::Settings(format!(
                    "fixed step must be positive, got {h}"
                )))
            }
            None => opts.h0.unwrap_or(1e-3 * span).min(opts.h_max).min(span),
        };
        let n = p.n();
        let mut s = Self {
            p,
            opts,
            rtol,
            atol,
            fnewt: if opts.fixed_step.is_some() {
                1e-3 * fnewt
            } else {
                fnewt
            },
            gamma,
            alpha,
            beta,
            t: t0,
            y: z0.to_vec(),
            f0: vec![0.0; n],
            h,
            h_old: h,
            cont: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            first: true,
            reject: false,
            theta: 1.0,
            faccon: 1.0,
            h_acc: h,
            err_acc: 1e-2,
            jac: vec![0.0; p.b_values().len()],
            jac_current: false,
            need_jac: true,
            need_lu: true,
            lu_real,
            lu_cplx,
            last_cause: "",
            last_newton: 0,
            stats: RadauStats::default(),
        };
        s.eval(t0, z0)?;
        Ok(s)
    }

    /// Current time.
    pub fn t(&self) -> f64 {
        self.t
    }

    /// Current state.
    pub fn z(&self) -> &[f64] {
        &self.y
    }

    /// `f0 = f(t, z)`, the derivative at the step start used by the error estimate.
    fn eval(&mut self, t: f64, z: &[f64]) -> Result<(), SimError> {
        let mut out = std::mem::take(&mut self.f0);
        self.p.rhs(t, z, &mut out);
        self.stats.rhs += 1;
        self.f0 = out;
        if let Some(i) = self.f0.iter().position(|v| !v.is_finite()) {
            return Err(SimError::NonFinite {
                t,
                state: self.p.state_name(i).to_owned(),
            });
        }
        Ok(())
    }

    /// The dense output at `t` inside the last accepted step `[t - h, t]`.
    pub fn dense(&self, t: f64, out: &mut [f64]) {
        let s = (t - self.t) / self.h_old;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.y[i]
                + s * (self.cont[0][i]
                    + (s - C2M1) * (self.cont[1][i] + (s - C1M1) * self.cont[2][i]));
        }
    }

    fn factorize(&mut self) -> Result<(), SimError> {
        let bv = self.p.b_values();
        let fac1 = self.gamma / self.h;
        let sig = C64::new(self.alpha / self.h, self.beta / self.h);
        let real: Vec<f64> = bv
            .iter()
            .zip(&self.jac)
            .map(|(b, j)| fac1 * b - j)
            .collect();
        let cplx: Vec<C64> = bv.iter().zip(&self.jac).map(|(b, j)| sig * b - j).collect();
        let fail = |e: String| SimError::SingularIteration {
            t: self.t,
            h: self.h,
            detail: e,
        };
        let m = SparseColMat::new(self.p.pattern().clone(), real);
        self.lu_real
            .factor(m.as_ref())
            .map_err(|e| fail(format!("LU of (gamma/h) B - J failed: {e:?}")))?;
        let mc = SparseColMat::new(self.p.pattern().clone(), cplx);
        self.lu_cplx
            .factor(mc.as_ref())
            .map_err(|e| fail(format!("LU of ((alpha + i beta)/h) B - J failed: {e:?}")))?;
        self.stats.factorizations += 1;
        Ok(())
    }

    fn solve_real(&mut self, rhs: &mut [f64]) -> Result<(), SimError> {
        let mut x = Mat::<f64>::from_fn(rhs.len(), 1, |i, _| rhs[i]);
        self.lu_real.solve_in_place(x.as_mut());
        for (i, r) in rhs.iter_mut().enumerate() {
            *r = x[(i, 0)];
        }
        self.check_solution(rhs.iter().copied())
    }

    fn solve_cplx(&mut self, re: &mut [f64], im: &mut [f64]) -> Result<(), SimError> {
        let mut x = Mat::<C64>::from_fn(re.len(), 1, |i, _| C64::new(re[i], im[i]));
        self.lu_cplx.solve_in_place(x.as_mut());
        for i in 0..re.len() {
            re[i] = x[(i, 0)].re;
            im[i] = x[(i, 0)].im;
        }
        self.check_solution(re.iter().chain(im.iter()).copied())
    }

    fn check_solution(&self, mut vals: impl Iterator<Item = f64>) -> Result<(), SimError> {
        if vals.all(f64::is_finite) {
            Ok(())
        } else {
            Err(SimError::SingularIteration {
                t: self.t,
                h: self.h,
                detail: "the solve produced non-finite values: (gamma/h) B - J is singular, \
                         so the pencil (A, B) is singular or the constraints are redundant \
                         at this state"
                    .into(),
            })
        }
    }

    fn scale(&self) -> Vec<f64> {
        let idx = self.p.index();
        self.y
            .iter()
            .zip(idx)
            .map(|(y, &k)| {
                let s = self.atol + self.rtol * y.abs();
                match k {
                    2 => s / self.h,
                    3 => s / (self.h * self.h),
                    _ => s,
                }
            })
            .collect()
    }

    /// Takes one accepted step, never beyond `t_end`.
    pub fn step(&mut self, t_end: f64) -> Result<(), SimError> {
        if ssm_kernel::cancel::requested() {
            return Err(SimError::Interrupted { t: self.t });
        }
        let h_min = 1e-13 * self.t.abs().max(1.0);
        loop {
            if self.stats.accepted + self.stats.rejected >= self.opts.max_steps {
                return Err(SimError::TooManySteps {
                    t: self.t,
                    steps: self.stats.accepted + self.stats.rejected,
                    t_end,
                });
            }
            if self.opts.fixed_step.is_none() {
                let remaining = t_end - self.t;
                if self.h > remaining {
                    self.h = remaining;
                    self.need_lu = true;
                }
            }
            if self.h < h_min {
                return Err(SimError::StepCollapse {
                    t: self.t,
                    h: self.h,
                    cause: format!(
                        "{} (the solution may blow up or leave the region where the model holds; \
                         a consistent initial state and a looser tolerance may help)",
                        if self.last_cause.is_empty() {
                            "the step reached the floor"
                        } else {
                            self.last_cause
                        }
                    ),
                });
            }
            if self.need_jac {
                let y = self.y.clone();
                self.p.jacobian(self.t, &y, &mut self.jac);
                self.stats.jacobians += 1;
                self.jac_current = true;
                self.need_jac = false;
                self.need_lu = true;
            }
            if self.need_lu {
                self.factorize()?;
                self.need_lu = false;
            }
            let scal = self.scale();
            match self.newton(&scal)? {
                Newton::Converged(z) => {
                    if self.finish_step(z, &scal, t_end)? {
                        return Ok(());
                    }
                }
                Newton::Diverged { factor } => {
                    if self.opts.fixed_step.is_some() {
                        return Err(SimError::StepCollapse {
                            t: self.t,
                            h: self.h,
                            cause: "Newton iteration did not converge with the fixed step".into(),
                        });
                    }
                    self.stats.rejected += 1;
                    self.last_cause = "the Newton iteration of the stage equations diverges";
                    self.h *= factor;
                    self.reject = true;
                    self.need_lu = true;
                    if !self.jac_current {
                        self.need_jac = true;
                    }
                }
            }
        }
    }

    fn newton(&mut self, scal: &[f64]) -> Result<Newton, SimError> {
        let n = self.p.n();
        let h = self.h;
        let mut z = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        if !self.first {
            let c3q = h / self.h_old;
            let (c1q, c2q) = (C1 * c3q, C2 * c3q);
            let [z1, z2, z3] = &mut z;
            for (i, ((a, b), c)) in z1
                .iter_mut()
                .zip(z2.iter_mut())
                .zip(z3.iter_mut())
                .enumerate()
            {
                let ext = |cq: f64| {
                    cq * (self.cont[0][i]
                        + (cq - C2M1) * (self.cont[1][i] + (cq - C1M1) * self.cont[2][i]))
                };
                *a = ext(c1q);
                *b = ext(c2q);
                *c = ext(c3q);
            }
        }
        let mut w = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        for i in 0..n {
            for r in 0..3 {
                w[r][i] = TI[r][0] * z[0][i] + TI[r][1] * z[1][i] + TI[r][2] * z[2][i];
            }
        }
        self.faccon = self.faccon.max(UROUND).powf(0.8);
        let fac1 = self.gamma / h;
        let (alphn, betan) = (self.alpha / h, self.beta / h);
        let mut f = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut yi = vec![0.0; n];
        let mut bw = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut dynold = 0.0f64;
        let mut thqold = 0.0f64;
        let mut newt = 0usize;
        // fixed steps (convergence studies) solve the stages to near round-off
        let nit = if self.opts.fixed_step.is_some() {
            40
        } else {
            NIT
        };
        loop {
            if newt >= nit {
                return Ok(Newton::Diverged { factor: 0.5 });
            }
            for (s, c) in [C1, C2, 1.0].into_iter().enumerate() {
                for i in 0..n {
                    yi[i] = self.y[i] + z[s][i];
                }
                self.p.rhs(self.t + c * h, &yi, &mut f[s]);
                self.stats.rhs += 1;
            }
            if f.iter().flatten().any(|v| !v.is_finite()) {
                return Ok(Newton::Diverged { factor: 0.5 });
            }
            for r in 0..3 {
                self.p.b_mul(&w[r], &mut bw[r]);
            }
            let mut r1 = vec![0.0; n];
            let mut r2 = vec![0.0; n];
            let mut r3 = vec![0.0; n];
            for i in 0..n {
                let tf = |r: usize| TI[r][0] * f[0][i] + TI[r][1] * f[1][i] + TI[r][2] * f[2][i];
                r1[i] = tf(0) - fac1 * bw[0][i];
                r2[i] = tf(1) - (alphn * bw[1][i] - betan * bw[2][i]);
                r3[i] = tf(2) - (betan * bw[1][i] + alphn * bw[2][i]);
            }
            self.solve_real(&mut r1)?;
            self.solve_cplx(&mut r2, &mut r3)?;
            self.stats.newton += 1;
            let dyno = ((0..n)
                .map(|i| (r1[i] * r1[i] + r2[i] * r2[i] + r3[i] * r3[i]) / (scal[i] * scal[i]))
                .sum::<f64>()
                / (3 * n) as f64)
                .sqrt();
            if newt >= 1 {
                let thq = dyno / dynold;
                self.theta = if newt == 1 {
                    thq
                } else {
                    (thq * thqold).sqrt()
                };
                thqold = thq;
                if self.theta < 0.99 {
                    self.faccon = self.theta / (1.0 - self.theta);
                    let dyth = self.faccon * dyno * self.theta.powi(NIT as i32 - 1 - newt as i32)
                        / self.fnewt;
                    if dyth >= 1.0 && self.opts.fixed_step.is_none() {
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        let factor =
                            0.8 * qnewt.powf(-1.0 / (4.0 + NIT as f64 - 1.0 - newt as f64));
                        return Ok(Newton::Diverged { factor });
                    }
                } else {
                    return Ok(Newton::Diverged { factor: 0.5 });
                }
            }
            dynold = dyno.max(UROUND);
            for i in 0..n {
                w[0][i] += r1[i];
                w[1][i] += r2[i];
                w[2][i] += r3[i];
                for (s, zs) in z.iter_mut().enumerate() {
                    zs[i] = T[s][0] * w[0][i] + T[s][1] * w[1][i] + T[s][2] * w[2][i];
                }
            }
            newt += 1;
            let converged = if self.opts.fixed_step.is_some() {
                newt >= 2 && dyno <= self.fnewt
            } else {
                self.faccon * dyno <= self.fnewt
            };
            if converged {
                self.last_newton = newt;
                return Ok(Newton::Converged(z));
            }
        }
    }
}

impl Stepper for Radau<'_, '_> {
    type Scalar = f64;
    type Error = SimError;

    fn t(&self) -> f64 {
        self.t
    }

    fn state(&self) -> &[f64] {
        &self.y
    }

    fn step(&mut self, t_end: f64) -> Result<(), SimError> {
        Radau::step(self, t_end)
    }

    fn dense(&self, t: f64, out: &mut [f64]) {
        Radau::dense(self, t, out);
    }

    fn stats(&self) -> StepStats {
        let s = self.stats;
        StepStats {
            accepted: s.accepted,
            rejected: s.rejected,
            newton: s.newton,
            factorizations: s.factorizations,
            rhs: s.rhs,
        }
    }
}

impl Radau<'_, '_> {
    /// Error test of a converged step; on acceptance advances the state and the
    /// dense output and returns `true`, otherwise shrinks `h` and returns `false`.
    fn finish_step(
        &mut self,
        z: [Vec<f64>; 3],
        scal: &[f64],
        t_end: f64,
    ) -> Result<bool, SimError> {
        let n = self.p.n();
        let h = self.h;
        let accept_fixed = self.opts.fixed_step.is_some();
        let mut err_norm = 0.0;
        if !accept_fixed {
            let f2: Vec<f64> = (0..n)
                .map(|i| (DD1 * z[0][i] + DD2 * z[1][i] + DD3 * z[2][i]) / h)
                .collect();
            let mut bf2 = vec![0.0; n];
            self.p.b_mul(&f2, &mut bf2);
            let mut cont: Vec<f64> = (0..n).map(|i| bf2[i] + self.f0[i]).collect();
            self.solve_real(&mut cont)?;
            err_norm = rms(&cont, scal).max(1e-10);
            if err_norm >= 1.0 && (self.first || self.reject) {
                let y1: Vec<f64> = (0..n).map(|i| self.y[i] + cont[i]).collect();
                let mut f1 = vec![0.0; n];
                self.p.rhs(self.t, &y1, &mut f1);
                self.stats.rhs += 1;
                let mut c2: Vec<f64> = (0..n).map(|i| f1[i] + bf2[i]).collect();
                self.solve_real(&mut c2)?;
                err_norm = rms(&c2, scal).max(1e-10);
                if !err_norm.is_finite() {
                    err_norm = 1e10;
                }
            }
        }
        let fac = SAFE.min(SAFE * (1.0 + 2.0 * NIT as f64) / (self.last_newton + 2 * NIT) as f64);
        let mut quot = FACR.max(FACL.min(err_norm.powf(0.25) / fac));
        let mut h_new = h / quot;
        if err_norm < 1.0 || accept_fixed {
            if !self.first && !accept_fixed {
                // predictive controller of Gustafsson
                let facgus =
                    (self.h_acc / h) * (err_norm * err_norm / self.err_acc).powf(0.25) / SAFE;
                let facgus = FACR.max(FACL.min(facgus));
                quot = quot.max(facgus);
                h_new = h / quot;
            }
            self.h_acc = h;
            self.err_acc = err_norm.max(1e-2);
            self.first = false;
            self.stats.accepted += 1;
            let [za, zb, zc] = &z;
            for (i, ((&z1, &z2), &z3)) in za.iter().zip(zb).zip(zc).enumerate() {
                self.y[i] += z3;
                self.cont[0][i] = (z2 - z3) / C2M1;
                let ak = (z1 - z2) / C1MC2;
                let acont3 = (ak - z1 / C1) / C2;
                self.cont[1][i] = (ak - self.cont[0][i]) / C1M1;
                self.cont[2][i] = self.cont[1][i] - acont3;
            }
            self.t += h;
            self.h_old = h;
            if let Some(i) = self.y.iter().position(|v| !v.is_finite()) {
                return Err(SimError::NonFinite {
                    t: self.t,
                    state: self.p.state_name(i).to_owned(),
                });
            }
            let y = std::mem::take(&mut self.y);
            let res = self.eval(self.t, &y);
            self.y = y;
            res?;
            if accept_fixed {
                self.need_jac = true;
                self.need_lu = true;
                return Ok(true);
            }
            h_new = h_new.min(self.opts.h_max);
            if self.reject {
                h_new = h_new.min(h);
            }
            self.reject = false;
            let qt = h_new / h;
            let keep = self.theta <= THET && (QUOT1..=QUOT2).contains(&qt) && self.t + h < t_end;
            if !keep {
                self.h = h_new;
                self.need_lu = true;
            }
            // the Jacobian was taken at the previous step start; keep it only
            // while the Newton contraction is fast
            self.need_jac = self.theta > THET;
            self.jac_current = false;
            Ok(true)
        } else {
            self.reject = true;
            self.stats.rejected += 1;
            self.last_cause = "the local error test keeps failing";
            self.h = if self.first { 0.1 * h } else { h_new };
            self.need_lu = true;
            if !self.jac_current {
                self.need_jac = true;
            }
            Ok(false)
        }
    }
}

fn rms(v: &[f64], scal: &[f64]) -> f64 {
    (v.iter()
        .zip(scal)
        .map(|(x, s)| (x / s) * (x / s))
        .sum::<f64>()
        / v.len().max(1) as f64)
        .sqrt()
}

enum Newton {
    Converged([Vec<f64>; 3]),
    Diverged { factor: f64 },
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    }

    /// `T^{-1} A_R^{-1} T = diag(gamma, [[alpha, -beta], [beta, alpha]])`,
    /// checked as `A_R (T Lambda T^{-1}) = I`.
    #[test]
    fn transformation_diagonalizes_the_inverse_radau_matrix() {
        let (g, a, b) = radau_eigenvalues();
        let lambda = [[g, 0.0, 0.0], [0.0, a, -b], [0.0, b, a]];
        let prod = mul(&RADAU_A, &mul(&mul(&T, &lambda), &TI));
        let id = mul(&T, &TI);
        for i in 0..3 {
            for j in 0..3 {
                let e = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (prod[i][j] - e).abs() < 1e-14,
                    "A T L T^-1 [{i}][{j}] = {}",
                    prod[i][j]
                );
                assert!(
                    (id[i][j] - e).abs() < 1e-15,
                    "T T^-1 [{i}][{j}] = {}",
                    id[i][j]
                );
            }
        }
        // the nodes are the last row sums (stiff accuracy: c_3 = 1, b = last row)
        let ar = RADAU_A;
        for (row, c) in ar.iter().zip([C1, C2, 1.0]) {
            assert!((row.iter().sum::<f64>() - c).abs() < 1e-15);
        }
    }
}
