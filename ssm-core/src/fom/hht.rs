//! The Hilber-Hughes-Taylor (HHT-alpha) method for index-3 multibody DAEs
//! `M q'' = Q(q, q', t) - G(q)^T mu`, `0 = g(q)`: the integrator of MSC Adams
//! and FreeDyn, used by Stadlmayr, Witteveen & Steiner (2017) for the full
//! and the POD-reduced models.
//!
//! # Method
//! With `f(z, t)` the force of the momentum rows, `A z + F(z) + eps Fext`
//! less the damping `C q'` that the first-order form (eqs. (4)-(5) of Li,
//! Jain & Haller 2023) keeps in `B` (so `f` holds the elastic, damping,
//! external and constraint forces; `z = (q, q', mu)`), one step solves for the new
//! accelerations `a` and multipliers `mu` (Negrut et al. 2007, eqs. (7)-(9)):
//!
//! - `M a_{n+1} - (1 + alpha) f(z_{n+1}, t_{n+1}) + alpha f(z_n, t_n) = 0`,
//! - `g(q_{n+1}) / (beta h^2) = 0`,
//! - `q_{n+1} = q_n + h q'_n + h^2/2 ((1 - 2 beta) a_n + 2 beta a_{n+1})`,
//!   `q'_{n+1} = q'_n + h ((1 - gamma) a_n + gamma a_{n+1})`,
//!
//! with `alpha` in `[-1/3, 0]`, `gamma = (1 - 2 alpha) / 2`,
//! `beta = (1 - alpha)^2 / 4`: second order, unconditionally stable on
//! linear problems, with spectral radius `(1 + alpha) / (1 - alpha)` at
//! infinite frequency (`alpha = 0`: the trapezoidal Newmark method, no
//! numerical damping). The constraint rows are divided by `beta h^2`, so the
//! iteration matrix
//! `[M - (1 + alpha)(beta h^2 f_q + gamma h f_q'), -(1 + alpha) f_mu; G, 0]`
//! keeps entries of order one as `h -> 0` (the scaling of the paper and of
//! Negrut et al.; unscaled, its condition grows like `h^-2`). Newton uses
//! the analytic sparse Jacobian of the polynomial model on one symbolic LU
//! for the run; a step whose Newton iteration fails is halved. Steps are
//! fixed (growing back after five converged ones), or controlled by the
//! local error of the positions, `(beta - 1/6) h^2 (a_{n+1} - a_n)`.
//!
//! A recast model's auxiliaries `w` (Li, Jain & Haller 2023, Sect. 4.2:
//! `u_s = sin a`, `u_c = 1 - cos a`, ...) are unknowns of the same Newton
//! iteration, moved with the positions (`w = w_pred + beta h^2 w_hat`, the
//! prediction along their last rate, so their columns scale like the
//! positions'): a differential auxiliary `B_w w' = f_w(z)` by the trapezoidal
//! rule, `B_w (w_{n+1} - w_n) = h/2 (f_w(z_{n+1}) + f_w(z_n))` (second order,
//! free of the HHT shift, which only the second-order rows need), an
//! algebraic one exactly; both rows are divided by `beta h^2` like the
//! constraints.
//!
//! Consistent starts come from [`consistent_initial`]
//! (positions, velocities and multipliers); the first accelerations from
//! `M a_0 = f(z_0, t_0)`.
//!
//! # References
//! H. M. Hilber, T. J. R. Hughes, R. L. Taylor, *Improved numerical
//! dissipation for time integration algorithms in structural dynamics*,
//! Earthq. Eng. Struct. Dyn. 5 (1977) 283-292; D. Negrut, R. Rampalli,
//! G. Ottarsson, A. Sajdak, *On an implementation of the Hilber-Hughes-Taylor
//! method in the context of index 3 differential-algebraic equations of
//! multibody dynamics*, J. Comput. Nonlinear Dyn. 2 (2007) 73-85;
//! M. Stadlmayr, W. Witteveen, W. Steiner, Multibody Syst. Dyn. (2017).

use faer::prelude::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::Mat;

use super::problem::square_pattern;
use super::{consistent_initial, DaeProblem, SimError};

/// Settings of an HHT run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HhtOptions {
    /// `alpha` in `[-1/3, 0]` (0: no numerical damping).
    pub alpha: f64,
    /// Step size `h`: fixed (halved where Newton fails), or the first and
    /// largest step with [`HhtOptions::local_error`].
    pub step: f64,
    /// Step-size control on the positions' local error, `(rtol, atol)`:
    /// `(beta - 1/6) h^2 |a_{n+1} - a_n|` (the leading term of the Newmark
    /// position formula's truncation error, Negrut et al. 2007, Sect. 4) kept
    /// below `atol + rtol |q|`; `None`: fixed steps.
    pub local_error: Option<(f64, f64)>,
    /// Newton stops when every correction is below `tol (1 + |value|)`.
    pub tol: f64,
    /// Newton iterations per attempt.
    pub max_newton: usize,
}

impl HhtOptions {
    /// `alpha` and `step` with Newton at `1e-10`, 8 iterations.
    pub fn new(alpha: f64, step: f64) -> Self {
        Self {
            alpha,
            step,
            local_error: None,
            tol: 1e-10,
            max_newton: 8,
        }
    }

    /// [`HhtOptions::new`] with step-size control at `(rtol, atol)`, `step`
    /// the first and largest step.
    pub fn adaptive(alpha: f64, step: f64, rtol: f64, atol: f64) -> Self {
        Self {
            local_error: Some((rtol, atol)),
            ..Self::new(alpha, step)
        }
    }

    /// `(gamma, beta)` of `alpha`.
    pub fn newmark(&self) -> (f64, f64) {
        (0.5 - self.alpha, 0.25 * (1.0 - self.alpha).powi(2))
    }

    fn check(&self) -> Result<(), SimError> {
        if !(-1.0 / 3.0..=0.0).contains(&self.alpha) {
            return Err(SimError::Settings(format!(
                "HHT alpha = {} must lie in [-1/3, 0]",
                self.alpha
            )));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(SimError::Settings(format!(
                "HHT step {} must be positive",
                self.step
            )));
        }
        if let Some((rtol, atol)) = self.local_error {
            if !(rtol > 0.0 && rtol < 1.0 && atol > 0.0 && atol.is_finite()) {
                return Err(SimError::Settings(format!(
                    "HHT tolerances must satisfy 0 < rtol < 1 and atol > 0 (rtol = {rtol}, atol = {atol})"
                )));
            }
        }
        if !(self.tol.is_finite() && self.tol > 0.0) || self.max_newton == 0 {
            return Err(SimError::Settings(
                "HHT Newton tolerance must be positive and iterations at least 1".into(),
            ));
        }
        Ok(())
    }
}

/// Counters of an HHT run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HhtStats {
    /// Steps taken.
    pub steps: usize,
    /// Step attempts whose Newton iteration failed (then halved).
    pub rejected: usize,
    /// Newton iterations.
    pub newton: usize,
    /// Numeric LU factorizations of the iteration matrix.
    pub factorizations: usize,
}

/// The states of an HHT run at its step ends.
#[derive(Debug, Clone, PartialEq)]
pub struct HhtSolution {
    /// Step end times, from `t0`.
    pub times: Vec<f64>,
    /// The full state `z = (q, q', mu)` at each time.
    pub states: Vec<Vec<f64>>,
    /// The accelerations `a` at each time.
    pub accelerations: Vec<Vec<f64>>,
    /// Counters.
    pub stats: HhtStats,
}

impl HhtSolution {
    /// The state at `t` inside the run: `q` and `q'` by cubic Hermite
    /// interpolation from `(q, q')` and `(q', a)` at the step ends (error
    /// `O(h^4)`, below the method's `O(h^2)`), `mu` linearly.
    pub fn at(&self, t: f64, n_dof: usize) -> Vec<f64> {
        let k = match self.times.partition_point(|&s| s <= t) {
            0 => 0,
            k if k >= self.times.len() => self.times.len().saturating_sub(2),
            k => k - 1,
        };
        if self.times.len() < 2 {
            return self.states[0].clone();
        }
        hermite(
            t,
            (self.times[k], &self.states[k], &self.accelerations[k]),
            (
                self.times[k + 1],
                &self.states[k + 1],
                &self.accelerations[k + 1],
            ),
            n_dof,
        )
    }
}

/// The momentum, constraint and auxiliary rows of a mechanical model as HHT
/// sees them.
struct Layout {
    n: usize,
    n_c: usize,
    /// Per auxiliary row (rows `2n + n_c ..`): differential (`B` has entries
    /// in it) or algebraic.
    differential: Vec<bool>,
}

/// Checks that `p` is the first-order form of the mechanical builder (Li,
/// Jain & Haller 2023, eqs. (4)-(5)) in canonical order: momentum rows
/// `0..n`, `C_B x' + M v' = A_m z + F_m(z)`; kinematic rows `n..2n`,
/// `E x' = E v`; constraint rows `2n .. 2n + n_c`, `0 = g(x, w)` (no `B`);
/// and the rows of a recast's auxiliaries `w` after them, differential
/// (`B_w w' = f_w(z)`, `B` only in auxiliary columns) or algebraic.
fn layout(p: &DaeProblem) -> Result<Layout, SimError> {
    let sys = p.sys;
    let not = |why: String| {
        Err(SimError::Settings(format!(
            "HHT integrates second-order mechanical models (M x'' = f(x, x', mu, t), 0 = g(x)); {why}"
        )))
    };
    let Some(mech) = sys.mechanical.as_ref() else {
        return not("this model declares no mechanical structure".into());
    };
    let (n, n_c) = (mech.n_dof, mech.n_constraints);
    let big_n = sys.n_states();
    let first_aux = 2 * n + n_c;
    if big_n < first_aux {
        return not(format!(
            "{big_n} states, fewer than 2 n + n_c = {first_aux}"
        ));
    }
    let entries = |m: faer::sparse::SparseColMatRef<'_, usize, f64>| {
        let mut e: Vec<(usize, usize, f64)> = (0..m.ncols())
            .flat_map(|j| {
                m.row_idx_of_col(j)
                    .zip(m.val_of_col(j))
                    .map(move |(i, v)| (i, j, *v))
            })
            .collect();
        e.sort_by_key(|x| (x.0, x.1));
        e
    };
    let (b, a) = (entries(sys.b.as_ref()), entries(sys.a.as_ref()));
    let misplaced = |&&(i, j, _): &&(usize, usize, f64)| {
        if i >= first_aux || j >= first_aux {
            // an auxiliary's own rate, and nothing else, in its rows
            i < first_aux || j < first_aux
        } else {
            j >= 2 * n || i >= 2 * n || (i >= n && j >= n)
        }
    };
    if let Some(&(i, j, _)) = b.iter().find(misplaced) {
        return not(format!(
            "B has an entry at ({i}, {j}) outside [[C, M, 0], [E, 0, 0], [0, 0, 0], [0, 0, B_w]]"
        ));
    }
    // kinematic rows: E x' = E v, the same E on both sides
    let kin_b: Vec<(usize, usize, f64)> = b
        .iter()
        .filter(|e| (n..2 * n).contains(&e.0))
        .copied()
        .collect();
    let kin_a: Vec<(usize, usize, f64)> = a
        .iter()
        .filter(|e| (n..2 * n).contains(&e.0))
        .map(|&(i, j, v)| (i, j.wrapping_sub(n), v))
        .collect();
    if kin_b != kin_a {
        return not("rows n..2n are not E x' = E v".into());
    }
    if let Some(t) = sys
        .nonlinearity
        .terms
        .iter()
        .find(|t| (n..2 * n).contains(&(t.eq as usize)))
    {
        return not(format!("the kinematic row {} has a nonlinear term", t.eq));
    }
    let mut differential = vec![false; big_n - first_aux];
    for &(i, _, _) in &b {
        if i >= first_aux {
            differential[i - first_aux] = true;
        }
    }
    Ok(Layout {
        n,
        n_c,
        differential,
    })
}

/// The kind of a row of the iteration matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Row {
    /// `M a - (1 + alpha) f(z_{n+1}) + alpha f(z_n)`.
    Momentum,
    /// `g(z_{n+1}) / (beta h^2)`: a constraint or an algebraic auxiliary.
    Algebraic,
    /// `(B_w (w_{n+1} - w_n) - h/2 (f_w(z_{n+1}) + f_w(z_n))) / (beta h^2)`.
    Differential,
}

/// One contribution to the iteration matrix: `coef(row, col) * J[src]`
/// (and `coef_b(row, col) * B[src]`) into slot `dst`.
#[derive(Debug, Clone, Copy)]
struct Scatter {
    src: usize,
    dst: usize,
    /// 0: a position column, 1: a velocity column, 2: a multiplier column,
    /// 3: an auxiliary column.
    col: u8,
    row: Row,
}

/// The sparse iteration matrix on the unknowns `(a, mu)` and its LU.
struct Iteration {
    pattern: SymbolicSparseColMat<usize>,
    scatter: Vec<Scatter>,
    symbolic: SymbolicLu<usize>,
    lu: Option<Lu<usize, f64>>,
}

impl Iteration {
    fn new(p: &DaeProblem, l: &Layout) -> Result<Self, SimError> {
        let (n, n_c) = (l.n, l.n_c);
        let size = p.n() - n;
        let src = p.pattern().as_ref();
        let mut entries: Vec<(usize, usize, usize, u8, Row)> = Vec::new();
        for c in 0..src.ncols() {
            let (col, kind) = if c < n {
                (c, 0)
            } else if c < 2 * n {
                (c - n, 1)
            } else if c < 2 * n + n_c {
                (c - n, 2)
            } else {
                (c - n, 3)
            };
            for k in src.col_ptr()[c]..src.col_ptr()[c + 1] {
                // momentum rows keep their index, constraint and auxiliary
                // rows follow them, the kinematic rows are the Newmark formulas
                let r = src.row_idx()[k];
                let row = if r < n {
                    Row::Momentum
                } else if r < 2 * n {
                    continue;
                } else if r < 2 * n + n_c || !l.differential[r - 2 * n - n_c] {
                    Row::Algebraic
                } else {
                    Row::Differential
                };
                entries.push((col, if r < n { r } else { r - n }, k, kind, row));
            }
        }
        let mut cells: Vec<(usize, usize)> = entries.iter().map(|e| (e.0, e.1)).collect();
        // the diagonal, so that a row the Jacobian leaves empty is reported
        // as singular rather than as a bad pattern
        cells.extend((0..size).map(|i| (i, i)));
        cells.sort_unstable();
        cells.dedup();
        let pattern = square_pattern(size, &cells);
        let scatter = entries
            .iter()
            .map(|&(c, r, k, col, row)| Scatter {
                src: k,
                dst: cells.binary_search(&(c, r)).expect("cell listed"),
                col,
                row,
            })
            .collect();
        let symbolic =
            SymbolicLu::try_new(pattern.as_ref()).map_err(|e| SimError::SingularIteration {
                t: 0.0,
                h: 0.0,
                detail: format!("symbolic LU of the HHT iteration matrix failed: {e:?}"),
            })?;
        Ok(Self {
            pattern,
            scatter,
            symbolic,
            lu: None,
        })
    }

    /// Factorizes the matrix for step `h` from the Jacobian values `jac`.
    fn factorize(
        &mut self,
        p: &DaeProblem,
        jac: &[f64],
        h: f64,
        o: &HhtOptions,
        t: f64,
    ) -> Result<(), SimError> {
        let (gamma, beta) = o.newmark();
        let w = 1.0 + o.alpha;
        // unknowns (a, mu, w_hat) with dq/da = beta h^2, dv/da = gamma h
        // and w = w_pred + beta h^2 w_hat (auxiliaries move with the
        // positions). Momentum rows: d/d(unknown) of
        // M a - (1 + alpha) (A z + F(z) - C_B v); B's mass and damping blocks
        // share the Jacobian's slots
        let bh2 = beta * h * h;
        let momentum_j = [-w * bh2, -w * gamma * h, -w, -w * bh2];
        let momentum_b = [w * gamma * h, 1.0, 0.0, 0.0];
        let algebraic = [1.0, gamma / (beta * h), 1.0 / bh2, 1.0];
        let differential_j = [-0.5 * h, -0.5 * gamma / beta, -0.5 / (beta * h), -0.5 * h];
        let differential_b = [0.0, 0.0, 0.0, 1.0];
        let b = p.b_values();
        let mut vals = vec![0.0; self.pattern.row_idx().len()];
        for s in &self.scatter {
            let k = s.col as usize;
            vals[s.dst] += match s.row {
                Row::Momentum => momentum_j[k] * jac[s.src] + momentum_b[k] * b[s.src],
                Row::Algebraic => algebraic[k] * jac[s.src],
                Row::Differential => differential_j[k] * jac[s.src] + differential_b[k] * b[s.src],
            };
        }
        let m = SparseColMat::new(self.pattern.clone(), vals);
        let lu = Lu::try_new_with_symbolic(self.symbolic.clone(), m.as_ref()).map_err(|e| {
            SimError::SingularIteration {
                t,
                h,
                detail: format!("LU of the HHT iteration matrix failed: {e:?}"),
            }
        })?;
        self.lu = Some(lu);
        Ok(())
    }

    fn solve(&self, rhs: &mut [f64]) {
        let lu = self.lu.as_ref().expect("factorized before solving");
        let mut x = Mat::<f64>::from_fn(rhs.len(), 1, |i, _| rhs[i]);
        lu.solve_in_place(x.as_mut());
        for (i, r) in rhs.iter_mut().enumerate() {
            *r = x[(i, 0)];
        }
    }
}

/// The state at `t` between the step ends `(t0, z0, a0)` and `(t1, z1, a1)`:
/// `q` and `q'` by cubic Hermite interpolation from `(q, q')` and `(q', a)`
/// (error `O(h^4)`, below the method's `O(h^2)`), `mu` linearly.
pub fn hermite(
    t: f64,
    (t0, z0, a0): (f64, &[f64], &[f64]),
    (t1, z1, a1): (f64, &[f64], &[f64]),
    n_dof: usize,
) -> Vec<f64> {
    let h = t1 - t0;
    let s = (t - t0) / h;
    let (h00, h10, h01, h11) = (
        (1.0 + 2.0 * s) * (1.0 - s).powi(2),
        s * (1.0 - s).powi(2),
        s * s * (3.0 - 2.0 * s),
        s * s * (s - 1.0),
    );
    let mut out = z0.to_vec();
    for i in 0..n_dof {
        let (v0, v1) = (z0[n_dof + i], z1[n_dof + i]);
        out[i] = h00 * z0[i] + h * h10 * v0 + h01 * z1[i] + h * h11 * v1;
        out[n_dof + i] = h00 * v0 + h * h10 * a0[i] + h01 * v1 + h * h11 * a1[i];
    }
    for i in 2 * n_dof..out.len() {
        out[i] = (1.0 - s) * z0[i] + s * z1[i];
    }
    out
}

/// Most steps of one run (the same budget as Radau's default).
const MAX_STEPS: usize = 2_000_000;

/// Integrates `p` from the start `guess` (made consistent first) over
/// `[t0, t_end]` with HHT-alpha and keeps every step end (memory grows with
/// the steps: [`integrate_with`] streams them instead).
pub fn integrate(
    p: &DaeProblem,
    guess: &[f64],
    t0: f64,
    t_end: f64,
    o: &HhtOptions,
) -> Result<HhtSolution, SimError> {
    let mut sol = HhtSolution {
        times: Vec::new(),
        states: Vec::new(),
        accelerations: Vec::new(),
        stats: HhtStats::default(),
    };
    sol.stats = integrate_with(p, guess, t0, t_end, o, |t, z, a| {
        sol.times.push(t);
        sol.states.push(z.to_vec());
        sol.accelerations.push(a.to_vec());
    })?;
    Ok(sol)
}

/// [`integrate`] without keeping the run: `on_step(t, z, a)` sees the
/// consistent start and then every step end, in order; returns the counters.
pub fn integrate_with(
    p: &DaeProblem,
    guess: &[f64],
    t0: f64,
    t_end: f64,
    o: &HhtOptions,
    mut on_step: impl FnMut(f64, &[f64], &[f64]),
) -> Result<HhtStats, SimError> {
    o.check()?;
    if !(t0.is_finite() && t_end.is_finite() && t_end > t0) {
        return Err(SimError::Settings(format!(
            "HHT interval [{t0}, {t_end}] is empty or not finite"
        )));
    }
    let l = layout(p)?;
    let (n, big_n) = (l.n, p.n());
    let z0 = consistent_initial(p, t0, guess)?.z;
    let mut it = Iteration::new(p, &l)?;
    let mut jac = vec![0.0; p.b_values().len()];
    let mut f_old = vec![0.0; big_n];
    let mut bz = vec![0.0; big_n];
    let mut acc = vec![0.0; big_n];
    p.rhs(t0, &z0, &mut f_old);
    momentum_force(p, &z0, &mut f_old, &mut bz, &mut acc, n);
    let a0 = initial_accelerations(p, &l, &f_old, t0)?;
    let (gamma, beta) = o.newmark();
    let w = 1.0 + o.alpha;
    let mut stats = HhtStats::default();
    on_step(t0, &z0, &a0);
    let (mut t, mut z, mut a) = (t0, z0, a0);
    let mut h = o.step;
    // the step size the iteration matrix was factored for; NaN: refactor
    // (a new step size, or a Jacobian gone stale along the motion)
    let mut h_factored = f64::NAN;
    let mut good = 0;
    let mut f_new = vec![0.0; big_n];
    // auxiliaries: predicted along their last rate, corrected with the
    // positions (w = w_pred + beta h^2 w_hat)
    let first_aux = 2 * n + l.n_c;
    let mut w_rate = vec![0.0; big_n - first_aux];
    let mut bw = vec![0.0; big_n];
    while t < t_end {
        if stats.steps >= MAX_STEPS {
            return Err(SimError::TooManySteps {
                t,
                steps: stats.steps,
                t_end,
            });
        }
        // the last step takes up what the sum of the steps leaves (no
        // sliver of round-off as a step of its own)
        let t1 = if t_end - t <= h * (1.0 + 1e-8) {
            t_end
        } else {
            t + h
        };
        let hs = t1 - t;
        // unknowns (a_{n+1}, mu_{n+1}, w_hat) from the predictor (a_n, mu_n, 0)
        let mut u: Vec<f64> = a
            .iter()
            .chain(&z[2 * n..first_aux])
            .copied()
            .chain(std::iter::repeat_n(0.0, big_n - first_aux))
            .collect();
        let w_pred: Vec<f64> = (first_aux..big_n)
            .map(|i| z[i] + hs * w_rate[i - first_aux])
            .collect();
        let step = Newmark {
            n,
            n_c: l.n_c,
            h: hs,
            gamma,
            beta,
            w_pred: &w_pred,
        };
        let mut z1 = z.clone();
        let mut converged = false;
        let mut fresh = false;
        let mut iterations = 0;
        let mut last_size = f64::INFINITY;
        for k in 0..o.max_newton {
            iterations = k + 1;
            step.state(&z, &a, &u, &mut z1);
            p.rhs(t1, &z1, &mut f_new);
            if let Some(i) = f_new.iter().position(|v| !v.is_finite()) {
                return Err(SimError::NonFinite {
                    t: t1,
                    state: p.state_name(i.min(big_n - 1)).to_owned(),
                });
            }
            momentum_force(p, &z1, &mut f_new, &mut bz, &mut acc, n);
            acc.iter_mut().for_each(|v| *v = 0.0);
            acc[n..2 * n].copy_from_slice(&u[..n]);
            p.b_mul(&acc, &mut bz);
            // B_w (w_{n+1} - w_n) of the differential auxiliaries (none
            // without a recast: no product)
            if first_aux < big_n {
                acc.iter_mut().for_each(|v| *v = 0.0);
                for i in first_aux..big_n {
                    acc[i] = z1[i] - z[i];
                }
                p.b_mul(&acc, &mut bw);
            }
            // residual: momentum rows, then the scaled constraint and
            // auxiliary rows
            let bh2 = beta * hs * hs;
            let mut r: Vec<f64> = (0..n)
                .map(|i| -(bz[i] - w * f_new[i] + o.alpha * f_old[i]))
                .chain((2 * n..big_n).map(|i| {
                    if i >= first_aux && l.differential[i - first_aux] {
                        -(bw[i] - 0.5 * hs * (f_new[i] + f_old[i])) / bh2
                    } else {
                        -f_new[i] / bh2
                    }
                }))
                .collect();
            if k == 0 && hs != h_factored {
                p.jacobian(t1, &z1, &mut jac);
                it.factorize(p, &jac, hs, o, t1)?;
                stats.factorizations += 1;
                h_factored = hs;
                fresh = true;
            }
            it.solve(&mut r);
            stats.newton += 1;
            let mut small = true;
            let mut finite = true;
            for (ui, di) in u.iter_mut().zip(&r) {
                if !di.is_finite() {
                    finite = false;
                    break;
                }
                *ui += di;
                small &= di.abs() <= o.tol * (1.0 + ui.abs());
            }
            let size = r.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            // at the round-off floor of the scaled system (the corrections
            // stop shrinking, small steps with large multipliers), accept
            // once they no longer move the step's states: `beta h^2 da`,
            // `gamma h da` in q and q', `gamma h dmu`, `beta h^2 dw_hat`
            let stalled = finite && k > 0 && size > 0.5 * last_size && {
                let (bh2, gh) = (beta * hs * hs, gamma * hs);
                (0..r.len()).all(|i| {
                    let (impact, scale) = if i < n {
                        (
                            gh * r[i].abs(),
                            (1.0 + z1[i].abs()).min(1.0 + z1[n + i].abs()),
                        )
                    } else if i < n + l.n_c {
                        (gh * r[i].abs(), 1.0 + u[i].abs())
                    } else {
                        (bh2 * r[i].abs(), 1.0 + z1[i + n].abs())
                    };
                    impact <= o.tol * scale
                })
            };
            last_size = size;
            if finite && (small || stalled) {
                step.state(&z, &a, &u, &mut z1);
                converged = true;
                break;
            }
        }
        // the next attempt or step refactors: at once after a failure or a
        // slow convergence with an old matrix, at half the step after a
        // failure with a fresh one
        if !converged || iterations > 3 {
            h_factored = f64::NAN;
        }
        if !converged && !fresh {
            continue;
        }
        if !converged {
            stats.rejected += 1;
            good = 0;
            h = 0.5 * hs;
            if h < o.step * 1e-8 {
                return Err(SimError::StepCollapse {
                    t,
                    h,
                    cause: "the HHT Newton iteration does not converge (the motion may leave the model's range, or the step is far too large)".into(),
                });
            }
            continue;
        }
        if let Some((rtol, atol)) = o.local_error {
            let c = (beta - 1.0 / 6.0) * hs * hs;
            let err = (0..n)
                .map(|i| {
                    let scale = atol + rtol * z[i].abs().max(z1[i].abs());
                    (c * (u[i] - a[i])).abs() / scale
                })
                .fold(0.0, f64::max);
            // the error is O(h^3): the classic controller with safety 0.9
            let factor = (0.9 * err.max(1e-10).powf(-1.0 / 3.0)).clamp(0.2, 2.0);
            if err > 1.0 {
                stats.rejected += 1;
                h = hs * factor.min(0.9);
                continue;
            }
            // a growth below 20 % keeps the factored matrix
            h = if (1.0..1.2).contains(&factor) {
                hs
            } else {
                (hs * factor).min(o.step)
            };
        }
        for (k, rate) in w_rate.iter_mut().enumerate() {
            *rate = (z1[first_aux + k] - z[first_aux + k]) / hs;
        }
        t = t1;
        p.rhs(t, &z1, &mut f_old);
        momentum_force(p, &z1, &mut f_old, &mut bz, &mut acc, n);
        a.copy_from_slice(&u[..n]);
        z = z1;
        on_step(t, &z, &a);
        stats.steps += 1;
        good += 1;
        if o.local_error.is_none() && h < o.step && good >= 5 {
            h = (2.0 * h).min(o.step);
            good = 0;
        }
    }
    Ok(stats)
}

/// The Newmark formulas of one step.
struct Newmark<'a> {
    n: usize,
    n_c: usize,
    h: f64,
    gamma: f64,
    beta: f64,
    /// Predicted auxiliaries.
    w_pred: &'a [f64],
}

impl Newmark<'_> {
    /// `z1 = (q, q', mu, w)` from the step start `(z, a)` and the unknowns
    /// `u = (a_{n+1}, mu_{n+1}, w_hat)`.
    fn state(&self, z: &[f64], a: &[f64], u: &[f64], z1: &mut [f64]) {
        let (n, h, gamma, beta) = (self.n, self.h, self.gamma, self.beta);
        for i in 0..n {
            let (q, v, a0, a1) = (z[i], z[n + i], a[i], u[i]);
            z1[i] = q + h * v + 0.5 * h * h * ((1.0 - 2.0 * beta) * a0 + 2.0 * beta * a1);
            z1[n + i] = v + h * ((1.0 - gamma) * a0 + gamma * a1);
        }
        let first_aux = 2 * n + self.n_c;
        z1[2 * n..first_aux].copy_from_slice(&u[n..n + self.n_c]);
        for (k, wp) in self.w_pred.iter().enumerate() {
            z1[first_aux + k] = wp + beta * h * h * u[n + self.n_c + k];
        }
    }
}

/// Turns `f = A z + F(z) + eps Fext` (already in `f`) into the force of
/// `M q'' = f` on the momentum rows `0..n`: subtracts the damping `C_B q'`
/// that the first-order form keeps in `B` (`bz`, `acc`: scratch).
fn momentum_force(
    p: &DaeProblem,
    z: &[f64],
    f: &mut [f64],
    bz: &mut [f64],
    acc: &mut [f64],
    n: usize,
) {
    acc.iter_mut().for_each(|v| *v = 0.0);
    acc[..n].copy_from_slice(&z[n..2 * n]);
    p.b_mul(acc, bz);
    for i in 0..n {
        f[i] -= bz[i];
    }
}

/// `a_0` from `M a_0 = f(z_0, t_0)` (the momentum rows of `f`, from
/// [`momentum_force`]).
fn initial_accelerations(
    p: &DaeProblem,
    l: &Layout,
    f: &[f64],
    t: f64,
) -> Result<Vec<f64>, SimError> {
    let n = l.n;
    let b = p.sys.b.as_ref();
    let mut triplets = Vec::new();
    for j in n..2 * n {
        for (i, v) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
            if i < n {
                triplets.push(faer::sparse::Triplet::new(i, j - n, *v));
            }
        }
    }
    let singular = |detail: String| SimError::SingularIteration { t, h: 0.0, detail };
    let m = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| singular(format!("mass matrix: {e:?}")))?;
    let lu = m
        .sp_lu()
        .map_err(|e| singular(format!("LU of the mass matrix failed: {e:?}")))?;
    let mut x = Mat::<f64>::from_fn(n, 1, |i, _| f[i]);
    lu.solve_in_place(x.as_mut());
    let a: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
    if a.iter().all(|v| v.is_finite()) {
        Ok(a)
    } else {
        Err(singular("the mass matrix is singular".into()))
    }
}
