//! Forced response of several master pairs (internal resonance): fixed points
//! of the rotating-frame reduced dynamics traced by the shared continuation
//! core in `Omega`, with stability, saddle-node, branch-point and Hopf
//! detection, and branch switching at branch points.
//!
//! With `p_{2j} = q_j e^{i r_j Omega t}` (ratios `r` of eq. 16) the normal-form
//! reduced dynamics with forcing `eps s_j` on the externally resonant pairs are
//! autonomous:
//!
//! `q_j' = sum_k c_{j,k} q^k - i r_j Omega q_j + eps s_j`,
//!
//! where `q^k` is a monomial in `q_l` and `conj q_l`. Fixed points are the zeros
//! of `F(y, Omega)`, `y = (Re q_1, Im q_1, ...)`, in Cartesian form so that
//! branches through `q_j = 0` (the `rho_1 = 0` main branch of a 1:2 resonance)
//! are regular. They are continued by the shared core
//! ([`ssm_kernel::continuation`]: local parametrization, step control, events
//! located along the chord), with this module's test functions between
//! consecutive points: `det F_y` (it changes sign at folds, which the core
//! reports from the tangent's `Omega` component, and at branch points),
//! `det [F_y F_Omega; t^T]` with the unit tangent `t` (branch point), and the
//! number of eigenvalues of `F_y` in the right half-plane (Hopf, where it
//! changes in a step without a fold or a determinant's sign change). The
//! Jacobian is by central differences (the dynamics are a handful of
//! polynomial equations). At a
//! branch point the second direction of the two-dimensional null space of
//! `[F_y F_Omega]` (SVD) starts the other branch.
//!
//! # References
//! H. Dankowicz, F. Schilder, *Recipes for Continuation*, SIAM (2013),
//! Chs. 3, 10 (pseudo-arclength, branch points, test functions);
//! Y. A. Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed., Springer
//! (2004), Sect. 10.2; M. Li, S. Jain, G. Haller, Nonlinear Dyn. 110 (2022),
//! Sect. 4 (rotating-frame reduced dynamics on SSMs).

use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;

use crate::C64;
use ssm_kernel::continuation::{
    self as core, correct, local_parameter, solve_at_parameter, BifurcationKind, EventKind,
    Monitor, Problem, ProblemFailure, Stop, Test,
};

/// One term `coeff * q^exponents` of the equation of pair `pair`; exponents
/// over `(q_1, conj q_1, q_2, conj q_2, ...)`.
#[derive(Debug, Clone, PartialEq)]
pub struct PolarTerm {
    /// 0-based pair.
    pub pair: usize,
    /// Exponents.
    pub exponents: Vec<u16>,
    /// Coefficient.
    pub coeff: C64,
}

/// The rotating-frame reduced dynamics of `m` pairs.
#[derive(Debug, Clone)]
pub struct RotatingFrame {
    /// Autonomous terms (linear ones included).
    pub terms: Vec<PolarTerm>,
    /// Ratios `r_j`.
    pub ratios: Vec<f64>,
    /// Forcing `eps s_j` per pair.
    pub force: Vec<C64>,
}

/// Why continuation stopped short.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContinuationError {
    /// Newton did not converge at the start.
    #[error("no fixed point found at Omega = {omega} to start the continuation")]
    Start {
        /// Start frequency.
        omega: f64,
    },
}

/// A point of a continued branch.
#[derive(Debug, Clone, PartialEq)]
pub struct BranchPoint {
    /// `q_j`.
    pub q: Vec<C64>,
    /// Forcing frequency.
    pub omega: f64,
    /// All eigenvalues of `F_y` in the open left half-plane.
    pub stable: bool,
}

/// A located bifurcation on a continued branch.
#[derive(Debug, Clone, PartialEq)]
pub struct Located {
    /// Fold, branch point or Hopf.
    pub kind: BifurcationKind,
    /// The point.
    pub at: BranchPoint,
    /// Tangent there (for branch switching).
    tangent: Vec<f64>,
}

/// One continued branch and what was found on it.
#[derive(Debug, Clone)]
pub struct Branch {
    /// Points in order.
    pub points: Vec<BranchPoint>,
    /// Located bifurcations.
    pub located: Vec<Located>,
    /// The branch was stopped where a pair amplitude passed
    /// [`Settings::max_amplitude`].
    pub reached_max_amplitude: bool,
    /// The branch came back to its start: a closed loop (an isola, or the
    /// loop of a secondary branch through two branch points and its mirror
    /// image under a symmetry of the reduced dynamics).
    pub closed: bool,
}

impl Branch {
    /// The branch of the frame scaled by [`RotatingFrame::scaled`] with `a`,
    /// in the original amplitudes (`q = a q_scaled`).
    pub fn unscaled(mut self, a: f64) -> Branch {
        let back = |p: &mut BranchPoint| p.q.iter_mut().for_each(|q| *q *= a);
        self.points.iter_mut().for_each(back);
        self.located.iter_mut().for_each(|l| back(&mut l.at));
        self
    }
}

/// Largest angle (radians) between the tangents of two consecutive steps
/// before the step is halved.
const MAX_TURN: f64 = 0.1;

/// Settings of the continuation.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// `[Omega_min, Omega_max]`: the branch stops when it leaves this range.
    pub omega_range: (f64, f64),
    /// Initial and largest arclength step.
    pub h_max: f64,
    /// Smallest step before giving up.
    pub h_min: f64,
    /// Largest number of steps.
    pub max_steps: usize,
    /// The branch stops where some `|q_j|` exceeds this (the amplitude up to
    /// which the expansion is trusted, `[forcing] rho_max`).
    pub max_amplitude: Option<f64>,
}

impl RotatingFrame {
    fn m(&self) -> usize {
        self.ratios.len()
    }

    /// The same dynamics in the amplitude `q / a`: each term of degree `d`
    /// is multiplied by `a^(d - 1)` and the forcing divided by `a`. Continuing
    /// in the scaled frame makes the arclength (and so the step control and
    /// the number of steps) independent of the amplitude unit, which for a
    /// unit-normalized eigenvector grows with the number of degrees of
    /// freedom.
    pub fn scaled(&self, a: f64) -> RotatingFrame {
        RotatingFrame {
            terms: self
                .terms
                .iter()
                .map(|t| {
                    let degree: i32 = t.exponents.iter().map(|&e| i32::from(e)).sum();
                    PolarTerm {
                        coeff: t.coeff * a.powi(degree - 1),
                        ..t.clone()
                    }
                })
                .collect(),
            ratios: self.ratios.clone(),
            force: self.force.iter().map(|f| f / a).collect(),
        }
    }

    /// `F(y, Omega)`.
    pub fn rhs(&self, y: &[f64], omega: f64) -> Vec<f64> {
        let m = self.m();
        let q: Vec<C64> = (0..m).map(|j| C64::new(y[2 * j], y[2 * j + 1])).collect();
        let mut z: Vec<C64> = Vec::with_capacity(2 * m);
        for qj in &q {
            z.push(*qj);
            z.push(qj.conj());
        }
        let mut f: Vec<C64> = (0..m)
            .map(|j| self.force[j] - C64::new(0.0, self.ratios[j] * omega) * q[j])
            .collect();
        for t in &self.terms {
            let mut v = t.coeff;
            for (zi, &e) in z.iter().zip(&t.exponents) {
                if e > 0 {
                    v *= zi.powu(u32::from(e));
                }
            }
            f[t.pair] += v;
        }
        f.iter().flat_map(|c| [c.re, c.im]).collect()
    }

    /// `[F_y | F_Omega]` by central differences (`2m x (2m + 1)`).
    fn jacobian(&self, y: &[f64], omega: f64) -> Mat<f64> {
        let n = y.len();
        let mut j = Mat::<f64>::zeros(n, n + 1);
        for c in 0..=n {
            let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
            let (mut wp, mut wm) = (omega, omega);
            let h;
            if c < n {
                h = 1e-7 * (1.0 + y[c].abs());
                yp[c] += h;
                ym[c] -= h;
            } else {
                h = 1e-7 * (1.0 + omega.abs());
                wp += h;
                wm -= h;
            }
            let (fp, fm) = (self.rhs(&yp, wp), self.rhs(&ym, wm));
            for r in 0..n {
                j[(r, c)] = (fp[r] - fm[r]) / (2.0 * h);
            }
        }
        j
    }

    /// `(det F_y, det [F_y F_Omega; t^T], eigenvalues of F_y in the right
    /// half-plane, stable)`.
    fn tests(&self, u: &[f64], t: &[f64]) -> (f64, f64, usize, bool) {
        let n = u.len() - 1;
        let j = self.jacobian(&u[..n], u[n]);
        let fy = j.subcols(0, n).to_owned();
        let det = fy.determinant();
        let aug = Mat::<f64>::from_fn(n + 1, n + 1, |r, c| if r < n { j[(r, c)] } else { t[c] });
        let bp = aug.determinant();
        let ev = fy.eigenvalues().unwrap_or_default();
        let unstable = ev.iter().filter(|l| l.re > 0.0).count();
        (det, bp, unstable, unstable == 0 && !ev.is_empty())
    }

    fn point(&self, u: &[f64], stable: bool) -> BranchPoint {
        let n = u.len() - 1;
        BranchPoint {
            q: (0..n / 2)
                .map(|j| C64::new(u[2 * j], u[2 * j + 1]))
                .collect(),
            omega: u[n],
            stable,
        }
    }

    fn core_settings(s: &Settings) -> core::Settings {
        core::Settings {
            h_min: s.h_min,
            max_steps: s.max_steps,
            max_turn: MAX_TURN,
            tol: 1e-13,
            ..core::Settings::new(s.omega_range, s.h_max)
        }
    }

    /// Continues the branch through `(u0, t0)` in the direction `t0`.
    pub fn continue_branch(&self, u0: Vec<f64>, t0: Vec<f64>, s: &Settings) -> Branch {
        let mut p = FrameProblem {
            frame: self,
            lu: None,
            max_amplitude: s.max_amplitude,
        };
        let Ok(branch) = core::continue_branch(&mut p, u0, &t0, &Self::core_settings(s), |_| true)
        else {
            return Branch {
                points: Vec::new(),
                located: Vec::new(),
                reached_max_amplitude: false,
                closed: false,
            };
        };
        let step_has = |after: usize, kind: EventKind| {
            branch
                .events
                .iter()
                .any(|e| e.after == after && e.kind == kind)
        };
        let mut located = Vec::new();
        for e in &branch.events {
            let kind = match e.kind {
                // the tangent's Omega component also turns where a branch
                // crosses a symmetric (pitchfork) branch point: that is the
                // branch point the augmented determinant reports
                EventKind::Fold if step_has(e.after, EventKind::Test(1)) => continue,
                EventKind::Fold => BifurcationKind::Fold,
                EventKind::Test(1) => BifurcationKind::BranchPoint,
                // det F_y alone: a fold (reported by the tangent) or a
                // branch point (reported by the augmented determinant)
                EventKind::Test(0) => continue,
                EventKind::Test(_) => {
                    let real = step_has(e.after, EventKind::Fold)
                        || step_has(e.after, EventKind::Test(0))
                        || step_has(e.after, EventKind::Test(1));
                    if real {
                        continue;
                    }
                    BifurcationKind::Hopf
                }
            };
            located.push(Located {
                kind,
                at: self.point(&e.at.u, e.at.monitor.info),
                tangent: e.at.tangent.clone(),
            });
        }
        Branch {
            points: branch
                .points
                .iter()
                .map(|pt| self.point(&pt.u, pt.monitor.info))
                .collect(),
            located,
            reached_max_amplitude: branch.stop == Stop::Bound,
            closed: branch.stop == Stop::Closed,
        }
    }

    /// The branch through the fixed point found at `omega_start` (from the
    /// linear response), continued towards increasing `Omega`.
    pub fn start(
        &self,
        omega_start: f64,
        guess: Vec<f64>,
        s: &Settings,
    ) -> Result<Branch, ContinuationError> {
        let mut p = FrameProblem {
            frame: self,
            lu: None,
            max_amplitude: s.max_amplitude,
        };
        let mut u = guess;
        u.push(omega_start);
        let n = u.len() - 1;
        let cs = core::Settings {
            max_newton: 50,
            ..Self::core_settings(s)
        };
        let u = solve_at_parameter(&mut p, u, &cs)
            .map_err(|_| ContinuationError::Start { omega: omega_start })?;
        let mut t0 = vec![0.0; n + 1];
        t0[n] = 1.0;
        Ok(self.continue_branch(u, t0, s))
    }

    /// The point of this frame's branch nearest `point` of the branch of
    /// `other` (the same dynamics truncated differently): the corrector from
    /// `point` with the largest component of `other`'s unit tangent there
    /// held (the null vector of `other`'s `[F_y F_Omega]`, regular at
    /// folds). `None` when the corrector does not converge: this frame has
    /// no branch near `point`.
    pub(crate) fn nearest_point(
        &self,
        other: &RotatingFrame,
        point: &BranchPoint,
    ) -> Option<BranchPoint> {
        let n = point.q.len() * 2;
        let mut u: Vec<f64> = point.q.iter().flat_map(|q| [q.re, q.im]).collect();
        let j = other.jacobian(&u, point.omega);
        let svd = j.svd().ok()?;
        let v = svd.V();
        let t: Vec<f64> = (0..=n).map(|r| v[(r, n)]).collect();
        u.push(point.omega);
        let mut p = FrameProblem {
            frame: self,
            lu: None,
            max_amplitude: None,
        };
        let cs = core::Settings {
            tol: 1e-13,
            ..core::Settings::new((f64::NEG_INFINITY, f64::INFINITY), 1.0)
        };
        let (w, _) = correct(&mut p, u.clone(), &u, local_parameter(&t), &cs, false).ok()?;
        let stable = self.tests(&w, &t).3;
        Some(self.point(&w, stable))
    }

    /// The other branch through a located branch point, in both directions.
    pub fn switch(&self, at: &Located, s: &Settings) -> Vec<Branch> {
        let n = at.at.q.len() * 2;
        let mut u: Vec<f64> = at.at.q.iter().flat_map(|c| [c.re, c.im]).collect();
        u.push(at.at.omega);
        let j = self.jacobian(&u[..n], u[n]);
        let Ok(svd) = j.svd() else {
            return Vec::new();
        };
        let v = svd.V();
        // the two right singular vectors of the smallest singular values span
        // the null space; take the one most orthogonal to the branch tangent
        let cols = v.ncols();
        let cand: Vec<Vec<f64>> = (cols.saturating_sub(2)..cols)
            .map(|c| (0..=n).map(|r| v[(r, c)]).collect())
            .collect();
        let mut d = cand
            .iter()
            .min_by(|a, b| {
                dot(a, &at.tangent)
                    .abs()
                    .total_cmp(&dot(b, &at.tangent).abs())
            })
            .cloned()
            .unwrap_or_default();
        // remove the tangent component and normalize
        let p = dot(&d, &at.tangent);
        d.iter_mut().zip(&at.tangent).for_each(|(x, t)| *x -= p * t);
        let nd = dot(&d, &d).sqrt();
        d.iter_mut().for_each(|x| *x /= nd);
        let mut problem = FrameProblem {
            frame: self,
            lu: None,
            max_amplitude: s.max_amplitude,
        };
        let cs = Self::core_settings(s);
        let mut out = Vec::new();
        for sign in [1.0, -1.0] {
            let dir: Vec<f64> = d.iter().map(|x| sign * x).collect();
            let start: Vec<f64> = u
                .iter()
                .zip(&dir)
                .map(|(a, b)| a + 0.5 * s.h_max * b)
                .collect();
            if let Ok((u1, _)) = correct(
                &mut problem,
                start.clone(),
                &start,
                local_parameter(&dir),
                &cs,
                false,
            ) {
                let branch = self.continue_branch(u1, dir, s);
                let closed = branch.closed;
                out.push(branch);
                if closed {
                    // the loop came back through the branch point: the other
                    // direction would trace it again
                    break;
                }
            }
        }
        out
    }
}

/// The rotating-frame dynamics as a continuation problem of the shared core:
/// dense, with the finite-difference Jacobian.
struct FrameProblem<'a> {
    frame: &'a RotatingFrame,
    lu: Option<PartialPivLu<f64>>,
    max_amplitude: Option<f64>,
}

impl Problem for FrameProblem<'_> {
    /// Stable.
    type Info = bool;

    fn dim(&self) -> usize {
        2 * self.frame.m() + 1
    }

    fn residual(&mut self, u: &[f64]) -> Result<Vec<f64>, ProblemFailure> {
        let n = u.len() - 1;
        let r = self.frame.rhs(&u[..n], u[n]);
        if r.iter().all(|v| v.is_finite()) {
            Ok(r)
        } else {
            Err(ProblemFailure("the reduced dynamics are not finite".into()))
        }
    }

    fn factor(&mut self, u: &[f64], k: usize) -> Result<(), ProblemFailure> {
        let n = u.len() - 1;
        let j = self.frame.jacobian(&u[..n], u[n]);
        let a = Mat::<f64>::from_fn(n + 1, n + 1, |r, c| {
            if r < n {
                j[(r, c)]
            } else {
                f64::from(u8::from(c == k))
            }
        });
        self.lu = Some(a.partial_piv_lu());
        Ok(())
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), ProblemFailure> {
        let lu = self
            .lu
            .as_ref()
            .ok_or_else(|| ProblemFailure("solve before factor".into()))?;
        let b = Mat::<f64>::from_fn(rhs.len(), 1, |i, _| rhs[i]);
        let x = lu.solve(&b);
        for (i, r) in rhs.iter_mut().enumerate() {
            *r = x[(i, 0)];
        }
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(ProblemFailure("singular bordered Jacobian".into()))
        }
    }

    fn monitor(&mut self, u: &[f64], t: &[f64]) -> Result<Monitor<bool>, ProblemFailure> {
        let (det, bp, unstable, stable) = self.frame.tests(u, t);
        Ok(Monitor {
            tests: vec![Test::Sign(det), Test::Sign(bp), Test::Count(unstable)],
            info: stable,
        })
    }

    fn beyond(&self, _last: &[f64], u: &[f64]) -> bool {
        let n = u.len() - 1;
        self.max_amplitude
            .is_some_and(|r| (0..n / 2).any(|j| u[2 * j].hypot(u[2 * j + 1]) > r))
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
