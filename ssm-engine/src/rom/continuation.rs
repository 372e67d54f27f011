//! Forced response of several master pairs (internal resonance): fixed points
//! of the rotating-frame reduced dynamics traced by pseudo-arclength
//! continuation in `Omega`, with stability, saddle-node, branch-point and Hopf
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
//! are regular. Continuation: tangent predictor, Newton corrector on
//! `[F; t . (u - u_pred)]`, step control by Newton iterations. Test functions
//! between consecutive points: `det F_y` (saddle-node when the tangent's
//! `Omega` component also changes sign, otherwise a branch point),
//! `det [F_y F_Omega; t^T]` (branch point), and the number of eigenvalues of
//! `F_y` in the right half-plane without a change of `det F_y` (Hopf). Each is
//! located by bisection along the arc, re-corrected at every step. At a branch
//! point the second direction of the two-dimensional null space of
//! `[F_y F_Omega]` (SVD) starts the other branch.
//!
//! # References
//! H. Dankowicz, F. Schilder, *Recipes for Continuation*, SIAM (2013),
//! Chs. 3, 10 (pseudo-arclength, branch points, test functions);
//! Y. A. Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed., Springer
//! (2004), Sect. 10.2; M. Li, S. Jain, G. Haller, Nonlinear Dyn. 110 (2022),
//! Sect. 4 (rotating-frame reduced dynamics on SSMs).

use faer::linalg::solvers::Solve;
use faer::Mat;

use crate::rom::frc::BifurcationKind;
use crate::C64;

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
    /// Saddle-node, branch point or Hopf.
    pub kind: LocatedKind,
    /// The point.
    pub at: BranchPoint,
    /// Tangent there (for branch switching).
    tangent: Vec<f64>,
}

/// Kind of a located point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LocatedKind {
    /// A fold or Hopf point.
    Bifurcation(BifurcationKind),
    /// A branch point.
    BranchPoint,
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

    /// Newton at fixed `Omega`.
    fn solve_at(&self, mut y: Vec<f64>, omega: f64) -> Option<Vec<f64>> {
        let n = y.len();
        for _ in 0..50 {
            let f = self.rhs(&y, omega);
            let norm = f.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm < 1e-13 {
                return Some(y);
            }
            let j = self.jacobian(&y, omega);
            let fy = j.subcols(0, n).to_owned();
            let rhs = Mat::<f64>::from_fn(n, 1, |i, _| -f[i]);
            let dy = fy.partial_piv_lu().solve(&rhs);
            for i in 0..n {
                y[i] += dy[(i, 0)];
            }
            if !y.iter().all(|v| v.is_finite()) {
                return None;
            }
        }
        None
    }

    /// Corrector: Newton on `[F(u); t . (u - u_pred)] = 0`.
    fn correct(&self, pred: &[f64], t: &[f64]) -> Option<(Vec<f64>, usize)> {
        let n = pred.len() - 1;
        let mut u = pred.to_vec();
        for it in 0..12 {
            let f = self.rhs(&u[..n], u[n]);
            let g: f64 = t
                .iter()
                .zip(u.iter().zip(pred))
                .map(|(ti, (a, b))| ti * (a - b))
                .sum();
            let norm = f.iter().map(|v| v * v).sum::<f64>().sqrt() + g.abs();
            if norm < 1e-12 {
                return Some((u, it));
            }
            let j = self.jacobian(&u[..n], u[n]);
            let a = Mat::<f64>::from_fn(n + 1, n + 1, |r, c| if r < n { j[(r, c)] } else { t[c] });
            let rhs = Mat::<f64>::from_fn(n + 1, 1, |r, _| if r < n { -f[r] } else { -g });
            let du = a.partial_piv_lu().solve(&rhs);
            for i in 0..=n {
                u[i] += du[(i, 0)];
            }
            if !u.iter().all(|v| v.is_finite()) {
                return None;
            }
        }
        None
    }

    /// Unit tangent with the orientation of `prev`.
    fn tangent(&self, u: &[f64], prev: &[f64]) -> Vec<f64> {
        let n = u.len() - 1;
        let j = self.jacobian(&u[..n], u[n]);
        let a = Mat::<f64>::from_fn(n + 1, n + 1, |r, c| if r < n { j[(r, c)] } else { prev[c] });
        let rhs = Mat::<f64>::from_fn(n + 1, 1, |r, _| if r < n { 0.0 } else { 1.0 });
        let t = a.partial_piv_lu().solve(&rhs);
        let norm = (0..=n).map(|i| t[(i, 0)].powi(2)).sum::<f64>().sqrt();
        (0..=n).map(|i| t[(i, 0)] / norm).collect()
    }

    /// `(det F_y, det [F_y F_Omega; t^T], unstable eigenvalue count, stable)`.
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

    fn point(&self, u: &[f64], t: &[f64]) -> BranchPoint {
        let n = u.len() - 1;
        BranchPoint {
            q: (0..n / 2)
                .map(|j| C64::new(u[2 * j], u[2 * j + 1]))
                .collect(),
            omega: u[n],
            stable: self.tests(u, t).3,
        }
    }

    /// Bisection along the arc from `(u0, t0)` over `[0, h]` for a sign change
    /// of `test`.
    fn locate(
        &self,
        u0: &[f64],
        t0: &[f64],
        h: f64,
        test: &dyn Fn(&[f64], &[f64]) -> f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let at = |s: f64| -> Option<(Vec<f64>, Vec<f64>)> {
            let pred: Vec<f64> = u0.iter().zip(t0).map(|(a, b)| a + s * b).collect();
            let (u, _) = self.correct(&pred, t0)?;
            let t = self.tangent(&u, t0);
            Some((u, t))
        };
        let f0 = test(u0, t0);
        let (mut lo, mut hi) = (0.0, h);
        for _ in 0..50 {
            let mid = 0.5 * (lo + hi);
            match at(mid) {
                Some((u, t)) if (test(&u, &t) > 0.0) == (f0 > 0.0) => lo = mid,
                Some(_) => hi = mid,
                None => break,
            }
        }
        at(0.5 * (lo + hi)).unwrap_or_else(|| (u0.to_vec(), t0.to_vec()))
    }

    /// Continues the branch through `(u0, t0)` in the direction `t0`.
    pub fn continue_branch(&self, u0: Vec<f64>, t0: Vec<f64>, s: &Settings) -> Branch {
        let mut u = u0;
        let mut t = self.tangent(&u, &t0);
        let mut h = s.h_max;
        let mut points = vec![self.point(&u, &t)];
        let mut located = Vec::new();
        let (mut det, mut bp, mut unst, _) = self.tests(&u, &t);
        let (u_first, t_first) = (u.clone(), t.clone());
        let mut reached_max_amplitude = false;
        let mut closed = false;
        for step in 0..s.max_steps {
            let pred: Vec<f64> = u.iter().zip(&t).map(|(a, b)| a + h * b).collect();
            let Some((un, iters)) = self.correct(&pred, &t) else {
                h *= 0.5;
                if h < s.h_min {
                    break;
                }
                continue;
            };
            let tn = self.tangent(&un, &t);
            let (detn, bpn, unstn, _) = self.tests(&un, &tn);
            let n = un.len() - 1;
            if bp * bpn < 0.0 {
                let (ul, tl) = self.locate(&u, &t, h, &|a, b| self.tests(a, b).1);
                located.push(Located {
                    kind: LocatedKind::BranchPoint,
                    at: self.point(&ul, &tl),
                    tangent: tl,
                });
            } else if det * detn < 0.0 {
                let (ul, tl) = self.locate(&u, &t, h, &|a, b| self.tests(a, b).0);
                located.push(Located {
                    kind: LocatedKind::Bifurcation(BifurcationKind::SaddleNode),
                    at: self.point(&ul, &tl),
                    tangent: tl,
                });
            } else if unst != unstn {
                // a complex pair crossed: locate where the smallest |Re| of a pair vanishes
                let hopf = |a: &[f64], _: &[f64]| -> f64 {
                    let j = self.jacobian(&a[..n], a[n]);
                    let ev = j.subcols(0, n).to_owned().eigenvalues().unwrap_or_default();
                    let count = ev.iter().filter(|l| l.re > 0.0).count();
                    if count == unst {
                        1.0
                    } else {
                        -1.0
                    }
                };
                let (ul, tl) = self.locate(&u, &t, h, &hopf);
                located.push(Located {
                    kind: LocatedKind::Bifurcation(BifurcationKind::Hopf),
                    at: self.point(&ul, &tl),
                    tangent: tl,
                });
            }
            let u_prev = std::mem::replace(&mut u, un);
            let t_prev = std::mem::replace(&mut t, tn);
            det = detn;
            bp = bpn;
            unst = unstn;
            points.push(self.point(&u, &t));
            if u[n] < s.omega_range.0 || u[n] > s.omega_range.1 {
                break;
            }
            if let Some(r) = s.max_amplitude {
                if (0..n / 2).any(|j| u[2 * j].hypot(u[2 * j + 1]) > r) {
                    reached_max_amplitude = true;
                    break;
                }
            }
            // a closed branch (isola, or the loop of a secondary branch) is done
            // when its last step passes its start in the starting direction
            if step > 10
                && passes_through(&u_prev, &u, &u_first, 0.1 * s.h_max)
                && dot(&t, &t_first) > 0.5
            {
                closed = true;
                break;
            }
            // step control: shrink where the branch turns (so that two
            // bifurcations never share a step), grow where it is straight and
            // the corrector converged fast
            let turn = dot(&t, &t_prev).clamp(-1.0, 1.0).acos();
            if turn > MAX_TURN {
                h = (0.5 * h).max(s.h_min);
            } else if iters <= 3 && turn < 0.25 * MAX_TURN {
                h = (h * 1.3).min(s.h_max);
            }
        }
        Branch {
            points,
            located,
            reached_max_amplitude,
            closed,
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
        let y = self
            .solve_at(guess, omega_start)
            .ok_or(ContinuationError::Start { omega: omega_start })?;
        let n = y.len();
        let mut u = y;
        u.push(omega_start);
        let mut t0 = vec![0.0; n + 1];
        t0[n] = 1.0;
        Ok(self.continue_branch(u, t0, s))
    }

    /// The point of this frame's branch nearest `point` of the branch of
    /// `other` (the same dynamics truncated differently): the corrector from
    /// `point` in the hyperplane normal to `other`'s branch there, whose
    /// unit tangent is the null vector of `other`'s `[F_y F_Omega]` (regular
    /// at folds). `None` when the corrector does not converge: this frame has
    /// no branch near `point`.
    pub fn nearest_point(&self, other: &RotatingFrame, point: &BranchPoint) -> Option<BranchPoint> {
        let n = point.q.len() * 2;
        let mut u: Vec<f64> = point.q.iter().flat_map(|q| [q.re, q.im]).collect();
        let j = other.jacobian(&u, point.omega);
        let svd = j.svd().ok()?;
        let v = svd.V();
        let t: Vec<f64> = (0..=n).map(|r| v[(r, n)]).collect();
        u.push(point.omega);
        let (w, _) = self.correct(&u, &t)?;
        Some(self.point(&w, &t))
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
        let mut out = Vec::new();
        for sign in [1.0, -1.0] {
            let dir: Vec<f64> = d.iter().map(|x| sign * x).collect();
            let start: Vec<f64> = u
                .iter()
                .zip(&dir)
                .map(|(a, b)| a + 0.5 * s.h_max * b)
                .collect();
            if let Some((u1, _)) = self.correct(&start, &dir) {
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

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// True when the segment from `a` to `b` passes within `tol` of `p`.
fn passes_through(a: &[f64], b: &[f64], p: &[f64], tol: f64) -> bool {
    let ab: Vec<f64> = b.iter().zip(a).map(|(x, y)| x - y).collect();
    let ap: Vec<f64> = p.iter().zip(a).map(|(x, y)| x - y).collect();
    let len2 = dot(&ab, &ab);
    let s = if len2 > 0.0 {
        (dot(&ap, &ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d2: f64 = ap.iter().zip(&ab).map(|(x, y)| (x - s * y).powi(2)).sum();
    d2.sqrt() <= tol
}
