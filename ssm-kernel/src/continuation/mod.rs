//! Continuation of the zeros of `F(u) = 0`,
//! `F: R^(n+1) -> R^n`, the continuation parameter being the last unknown.
//!
//! One core for every continued problem: the problem gives its residual, a
//! factorization of the bordered Jacobian `[F_u(u); e_k^T]` (dense or sparse,
//! its choice) and its test functions; the core does the rest.
//!
//! The branch is parametrized locally by the unknown `k` of the largest
//! tangent component (Rheinboldt's local parametrization, as in PITCON):
//! near a fold in the parameter that is an amplitude, elsewhere mostly the
//! parameter. Unlike Keller's pseudo-arclength row `t^T`, the border `e_k^T`
//! is sparse, so a sparse problem factors `F_u` with column `k` removed and
//! keeps the fill of its own Jacobian (a dense border row makes the
//! structure of `J^T J`, and so the symbolic LU with partial pivoting, dense).
//!
//! - Predictor: `u_pred = u + h t` with the unit tangent `t`, the solution of
//!   `[F_u(u); e_k^T] t = e_(n+1)`, normalized (its orientation follows the
//!   previous tangent, so the branch passes folds without turning back).
//! - Corrector: Newton on `[F(u); u_k - u_pred,k] = 0`, with a fresh
//!   factorization at each iterate.
//! - Step control: the step halves when the corrector fails or the tangent
//!   turns by more than [`Settings::max_turn`] (so that two events never share
//!   a step), and grows by 1.3 up to `h_max` after a straight, fast step.
//! - Events: folds in the parameter (the parameter component of the tangent
//!   changes sign) and the problem's test functions, either signed values
//!   (an event where the sign changes) or counts (an event where the count
//!   changes: unstable Floquet multipliers or eigenvalues). Each event is
//!   located along the arc by bisection of the arclength in `[0, h]`, every
//!   trial point corrected onto the branch.
//! - Stops: the parameter leaves its range, the problem's own bound (e.g. an
//!   amplitude up to which a model is trusted), the branch closes on itself,
//!   the step falls below `h_min`, or `max_steps`.
//!
//! # References
//! W. C. Rheinboldt, J. V. Burkardt, A locally parameterized continuation
//! process, ACM Trans. Math. Softw. 9 (1983) 215-235;
//! H. B. Keller, Numerical solution of bifurcation and nonlinear eigenvalue
//! problems, in *Applications of Bifurcation Theory*, Academic Press (1977);
//! E. L. Allgower, K. Georg, *Introduction to Numerical Continuation
//! Methods*, SIAM (2003), Chs. 2, 8; H. Dankowicz, F. Schilder, *Recipes for
//! Continuation*, SIAM (2013), Chs. 3, 10; W. Govaerts, *Numerical Methods
//! for Bifurcations of Dynamical Equilibria*, SIAM (2000), Ch. 3.

/// A failure of the problem (its residual, factorization or tests), in words.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ProblemFailure(pub String);

/// One test function at a point.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Test {
    /// A signed value: an event where the sign changes.
    Sign(f64),
    /// A count: an event where it changes.
    Count(usize),
}

impl Test {
    fn differs(self, other: Test) -> bool {
        match (self, other) {
            (Test::Sign(a), Test::Sign(b)) => (a > 0.0) != (b > 0.0),
            (Test::Count(a), Test::Count(b)) => a != b,
            _ => true,
        }
    }
}

/// What a problem reports at a corrected point.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Monitor<I> {
    /// Test functions, in a fixed order.
    pub tests: Vec<Test>,
    /// The problem's data at the point (stability, multipliers, ...).
    pub info: I,
}

/// A continued problem.
pub trait Problem {
    /// Data attached to each point.
    type Info: Clone;
    /// Number of unknowns `n + 1`, the parameter last.
    fn dim(&self) -> usize;
    /// `F(u)`, `n` values.
    fn residual(&mut self, u: &[f64]) -> Result<Vec<f64>, ProblemFailure>;
    /// Factorizes `[F_u(u); e_k^T]` for the following [`Problem::solve`]s.
    fn factor(&mut self, u: &[f64], k: usize) -> Result<(), ProblemFailure>;
    /// Solves with the last factorization, in place (`n + 1` values).
    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), ProblemFailure>;
    /// Test functions and data at a corrected point with unit tangent `t`.
    /// It must leave the factorization made for the tangent in place: the
    /// next step's corrector starts with it.
    fn monitor(&mut self, u: &[f64], t: &[f64]) -> Result<Monitor<Self::Info>, ProblemFailure>;
    /// True where the branch must stop although the parameter is in range
    /// (the problem's own bound), on the step from the accepted point
    /// `_last` to the accepted point `_next`.
    fn beyond(&self, _last: &[f64], _next: &[f64]) -> bool {
        false
    }
}

/// Settings of a continuation run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The branch stops when the parameter leaves this range.
    pub range: (f64, f64),
    /// First step.
    pub h0: f64,
    /// Largest step.
    pub h_max: f64,
    /// Smallest step before giving up.
    pub h_min: f64,
    /// Largest number of continuation steps.
    pub max_steps: usize,
    /// Largest angle (radians) between consecutive tangents.
    pub max_turn: f64,
    /// Newton tolerance on the update, relative to `1 + |u|`.
    pub tol: f64,
    /// Largest number of corrector iterations.
    pub max_newton: usize,
}

impl Settings {
    /// Defaults for a parameter range and a largest step.
    pub fn new(range: (f64, f64), h_max: f64) -> Self {
        Self {
            range,
            h0: h_max,
            h_max,
            h_min: h_max * 1e-6,
            max_steps: 10_000,
            max_turn: 0.1,
            tol: 1e-10,
            max_newton: 16,
        }
    }
}

/// A corrected point of a branch.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Point<I> {
    /// The unknowns, the parameter last.
    pub u: Vec<f64>,
    /// The unit tangent.
    pub tangent: Vec<f64>,
    /// The problem's test functions and data.
    pub monitor: Monitor<I>,
}

impl<I> Point<I> {
    /// The parameter.
    pub fn parameter(&self) -> f64 {
        self.u[self.u.len() - 1]
    }
}

/// What a continued branch passes, in one vocabulary for every continued
/// problem: the reduced model's forced responses (equilibria of the polar
/// or rotating-frame dynamics) and the full system's periodic orbits. The
/// core itself sees only an [`EventKind`]; each problem names it.
///
/// # References
/// Y. A. Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed.,
/// Springer (2004), Ch. 3-5 and 10.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BifurcationKind {
    /// Fold (saddle-node): the branch turns in the parameter; a real
    /// eigenvalue of an equilibrium crosses 0, or a Floquet multiplier of an
    /// orbit passes `+1`.
    Fold,
    /// Hopf: a complex pair of eigenvalues of an equilibrium crosses the
    /// imaginary axis.
    Hopf,
    /// Branch point: a real eigenvalue crosses 0 (a multiplier passes `+1`)
    /// where the branch does not turn.
    BranchPoint,
    /// Period doubling: a multiplier passes `-1`.
    PeriodDoubling,
    /// Neimark-Sacker: a complex pair of multipliers leaves the unit circle.
    NeimarkSacker,
}

impl BifurcationKind {
    /// `SN`, `HB`, `BP`, `PD` or `NS`, as in the summary and the CSV files.
    pub fn label(self) -> &'static str {
        match self {
            Self::Fold => "SN",
            Self::Hopf => "HB",
            Self::BranchPoint => "BP",
            Self::PeriodDoubling => "PD",
            Self::NeimarkSacker => "NS",
        }
    }
}

/// What the core located on a branch: a fold in the parameter or a sign
/// change of one of the problem's test functions (which the problem names
/// with a [`BifurcationKind`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum EventKind {
    /// A fold in the parameter.
    Fold,
    /// A change of the problem's test function of this index.
    Test(usize),
}

/// A located event.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Event<I> {
    /// What changed.
    pub kind: EventKind,
    /// Index of the branch point after which it lies.
    pub after: usize,
    /// The located point.
    pub at: Point<I>,
}

/// Why a branch ended.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Stop {
    /// The parameter left its range.
    Range,
    /// The problem's own bound ([`Problem::beyond`]).
    Bound,
    /// The branch came back to its start.
    Closed,
    /// `max_steps` reached.
    MaxSteps,
    /// The step fell below `h_min`; the last failure.
    StepTooSmall {
        /// Parameter reached.
        parameter: f64,
        /// The corrector's last failure.
        cause: String,
    },
    /// The observer asked to stop, or the work was cancelled
    /// ([`crate::cancel`]).
    Interrupted,
}

/// A continued branch.
#[derive(Debug, Clone, PartialEq)]
pub struct Branch<I> {
    /// Points in order.
    pub points: Vec<Point<I>>,
    /// Located events in order.
    pub events: Vec<Event<I>>,
    /// Why it ended.
    pub stop: Stop,
}

/// Why a continuation could not start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContinuationError {
    /// The start point is not a zero of `F`.
    #[error("continuation: no solution near the start at parameter {parameter}: {cause}")]
    Start {
        /// Start parameter.
        parameter: f64,
        /// The corrector's failure.
        cause: String,
    },
    /// The problem failed at the start (tangent or test functions).
    #[error("continuation: the problem failed at the start point: {0}")]
    Problem(#[from] ProblemFailure),
}

/// The Euclidean inner product `a . b` of two vectors of equal length.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// The Euclidean distance of `a` and `b`.
pub fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// The index of the largest component of `t`: the local parameter.
pub fn local_parameter(t: &[f64]) -> usize {
    t.iter()
        .enumerate()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map_or(0, |(i, _)| i)
}

/// Newton on `[F(u); u_k - anchor_k] = 0` from `u`, as a chord iteration:
/// the Jacobian is factored at the first iterate (unless `factored`: the
/// problem already holds a factorization with local parameter `k` near `u`,
/// the last accepted point's) and again only where an update shrank by less
/// than a factor 4 (one sparse LU is the cost of a step on large problems; a
/// corrector from a good predictor contracts fast with the first
/// factorization). Returns the point and the number of iterations.
pub fn correct<P: Problem>(
    p: &mut P,
    mut u: Vec<f64>,
    anchor: &[f64],
    k: usize,
    s: &Settings,
    factored: bool,
) -> Result<(Vec<f64>, usize), ProblemFailure> {
    let mut refactor = !factored;
    let mut last = f64::INFINITY;
    for it in 1..=s.max_newton {
        let mut rhs = p.residual(&u)?;
        rhs.push(u[k] - anchor[k]);
        rhs.iter_mut().for_each(|v| *v = -*v);
        if refactor {
            p.factor(&u, k)?;
            refactor = false;
        }
        p.solve(&mut rhs)?;
        if !rhs.iter().all(|v| v.is_finite()) {
            return Err(ProblemFailure("the Newton update is not finite".into()));
        }
        u.iter_mut().zip(&rhs).for_each(|(a, d)| *a += d);
        let step = norm(&rhs);
        if step <= s.tol * (1.0 + norm(&u)) {
            return Ok((u, it));
        }
        if step > 0.25 * last {
            refactor = true;
        }
        last = step;
    }
    Err(ProblemFailure(format!(
        "Newton did not converge in {} iterations",
        s.max_newton
    )))
}

/// The unit tangent at `u`, oriented along `prev`.
pub fn tangent<P: Problem>(p: &mut P, u: &[f64], prev: &[f64]) -> Result<Vec<f64>, ProblemFailure> {
    p.factor(u, local_parameter(prev))?;
    let mut t = vec![0.0; u.len()];
    t[u.len() - 1] = 1.0;
    p.solve(&mut t)?;
    let n = norm(&t);
    if !n.is_finite() || n == 0.0 {
        return Err(ProblemFailure(
            "the tangent is not finite: the bordered Jacobian is singular".into(),
        ));
    }
    if dot(&t, prev) < 0.0 {
        t.iter_mut().for_each(|v| *v = -*v / n);
    } else {
        t.iter_mut().for_each(|v| *v /= n);
    }
    Ok(t)
}

fn point_at<P: Problem>(
    p: &mut P,
    u: Vec<f64>,
    prev: &[f64],
) -> Result<Point<P::Info>, ProblemFailure> {
    let t = tangent(p, &u, prev)?;
    let monitor = p.monitor(&u, &t)?;
    Ok(Point {
        u,
        tangent: t,
        monitor,
    })
}

/// Solves `F(u) = 0` with the parameter fixed at the last entry of `guess`.
pub fn solve_at_parameter<P: Problem>(
    p: &mut P,
    guess: Vec<f64>,
    s: &Settings,
) -> Result<Vec<f64>, ContinuationError> {
    let anchor = guess.clone();
    let k = guess.len() - 1;
    correct(p, guess, &anchor, k, s, false)
        .map(|(u, _)| u)
        .map_err(|e| ContinuationError::Start {
            parameter: anchor[anchor.len() - 1],
            cause: e.0,
        })
}

/// The point between `from` and `to` (consecutive points of a branch) where
/// `kind` changes: trial points `from + sigma (to - from)`, `sigma` in
/// `[0, 1]`, corrected in the hyperplane of the chord's largest component
/// (which the arc crosses once between two points of a step, also when a
/// fold lies between them); `sigma` by regula falsi with the Illinois
/// modification on the continuous value (the tangent's parameter component
/// for folds, a signed test function), by bisection for counts.
fn locate<P: Problem>(
    p: &mut P,
    from: &Point<P::Info>,
    to: &Point<P::Info>,
    kind: EventKind,
    s: &Settings,
) -> Option<Point<P::Info>> {
    let k = from.u.len() - 1;
    let chord: Vec<f64> = to.u.iter().zip(&from.u).map(|(a, b)| a - b).collect();
    let k_chord = local_parameter(&chord);
    let h = 1.0;
    // the continuous value, or +-1 for counts (+1 where equal to `from`)
    let value = |a: &Point<P::Info>| -> (f64, bool) {
        match kind {
            EventKind::Fold => (a.tangent[k], true),
            EventKind::Test(i) => match (from.monitor.tests[i], a.monitor.tests[i]) {
                (Test::Sign(_), Test::Sign(v)) => (v, true),
                (f, v) => (if f.differs(v) { -1.0 } else { 1.0 }, false),
            },
        }
    };
    // a fold needs the tangent only; the problem's tests need its monitor
    let needs_monitor = kind != EventKind::Fold;
    let at = |p: &mut P, sigma: f64| -> Option<Point<P::Info>> {
        let pred: Vec<f64> = from
            .u
            .iter()
            .zip(&chord)
            .map(|(a, b)| a + sigma * b)
            .collect();
        let (u, _) = correct(p, pred.clone(), &pred, k_chord, s, false).ok()?;
        let tangent = tangent(p, &u, &from.tangent).ok()?;
        let monitor = if needs_monitor {
            p.monitor(&u, &tangent).ok()?
        } else {
            from.monitor.clone()
        };
        Some(Point {
            u,
            tangent,
            monitor,
        })
    };
    let (f_from, continuous) = value(from);
    let (mut lo, mut hi) = (0.0, h);
    let (mut f_lo, mut f_hi) = (f_from, if continuous { f64::NAN } else { -1.0 });
    let mut best = to.clone();
    if continuous {
        f_hi = value(&best).0;
        if (f_hi > 0.0) == (f_lo > 0.0) {
            return Some(best);
        }
    }
    let mut side = 0i8;
    for _ in 0..60 {
        let mid = if continuous && f_lo != f_hi {
            (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        } else {
            0.5 * (lo + hi)
        };
        let mid = mid.clamp(lo + 1e-3 * (hi - lo), hi - 1e-3 * (hi - lo));
        let Some(pt) = at(p, mid) else { break };
        let (f, _) = value(&pt);
        if continuous && f == 0.0 {
            best = pt;
            break;
        }
        if (f > 0.0) == (f_lo > 0.0) {
            lo = mid;
            f_lo = f;
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            hi = mid;
            f_hi = f;
            best = pt;
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
        if hi - lo <= 1e-10 * h {
            break;
        }
    }
    if !needs_monitor {
        best.monitor = p.monitor(&best.u, &best.tangent).ok()?;
    }
    Some(best)
}

/// Continues the branch through the solution `u0` in the direction `t0`,
/// calling `observe` with each accepted point (and its events); the
/// observer returns `false` to stop.
pub fn continue_branch<P, O>(
    p: &mut P,
    u0: Vec<f64>,
    t0: &[f64],
    s: &Settings,
    observe: O,
) -> Result<Branch<P::Info>, ContinuationError>
where
    P: Problem,
    O: FnMut(&Step<'_, P::Info>) -> bool,
{
    let first = start_point(p, u0, t0)?;
    Ok(continue_from(p, first, s, observe))
}

/// The start point of a branch through the solution `u0` in the direction
/// `t0`: its tangent and monitor, the only part of a continuation that can
/// fail (so that a caller keeping a record of its runs can withdraw one
/// that cannot start).
pub fn start_point<P: Problem>(
    p: &mut P,
    u0: Vec<f64>,
    t0: &[f64],
) -> Result<Point<P::Info>, ContinuationError> {
    Ok(point_at(p, u0, t0)?)
}

/// [`continue_branch`] from its [`start_point`] `first`.
pub fn continue_from<P, O>(
    p: &mut P,
    first: Point<P::Info>,
    s: &Settings,
    mut observe: O,
) -> Branch<P::Info>
where
    P: Problem,
    O: FnMut(&Step<'_, P::Info>) -> bool,
{
    let trace = Trace {
        points: vec![first],
        events: Vec::new(),
        h: s.h0.min(s.h_max),
        steps: 0,
    };
    let start = Step {
        point: &trace.points[0],
        events: &[],
        h: trace.h,
        steps: 0,
    };
    if !observe(&start) {
        return Branch {
            points: trace.points,
            events: trace.events,
            stop: Stop::Interrupted,
        };
    }
    resume_branch(p, trace, s, observe)
}

/// Continues a traced branch from its last point with the trace's step size
/// and step count (a branch resumed from a checkpoint), calling `observe`
/// with each new accepted point; a trace whose last step ended the branch
/// (range, bound, closed) ends there.
pub fn resume_branch<P, O>(
    p: &mut P,
    trace: Trace<P::Info>,
    s: &Settings,
    mut observe: O,
) -> Branch<P::Info>
where
    P: Problem,
    O: FnMut(&Step<'_, P::Info>) -> bool,
{
    let k = trace.points[0].u.len() - 1;
    let Trace {
        mut points,
        mut events,
        mut h,
        mut steps,
    } = trace;
    if let Some(stop) = stop_after(p, &points, s) {
        return Branch {
            points,
            events,
            stop,
        };
    }
    // the local parameter of the factorization the problem holds at the
    // last accepted point, if it holds one
    let mut held: Option<usize> = None;
    let stop = loop {
        if steps >= s.max_steps {
            break Stop::MaxSteps;
        }
        if crate::cancel::requested() {
            break Stop::Interrupted;
        }
        steps += 1;
        let last = points.last().expect("a branch has its start");
        let pred: Vec<f64> = last
            .u
            .iter()
            .zip(&last.tangent)
            .map(|(a, b)| a + h * b)
            .collect();
        let k_local = local_parameter(&last.tangent);
        // the corrector's chord is the Jacobian at the last point: the
        // tangent's factorization when it was made with the same local
        // parameter and nothing factored since (a resumed run factors it
        // here, so that it computes the same bits); half the LUs of a step
        let factored = held == Some(k_local) || p.factor(&last.u, k_local).is_ok();
        held = None;
        // correct, then the tangent; the problem's monitor only where the
        // tangent turned little enough for the step to be kept
        let step = correct(p, pred.clone(), &pred, k_local, s, factored)
            .and_then(|(u, it)| tangent(p, &u, &last.tangent).map(|t| (u, t, it)))
            .and_then(|(u, t, it)| {
                let turn = dot(&t, &last.tangent).clamp(-1.0, 1.0).acos();
                if turn > s.max_turn && h > s.h_min * 2.0 {
                    return Ok(None);
                }
                let monitor = p.monitor(&u, &t)?;
                let next = Point {
                    u,
                    tangent: t,
                    monitor,
                };
                Ok(Some((next, it, turn)))
            });
        let (next, iters, turn) = match step {
            Ok(Some(v)) => v,
            Ok(None) => {
                h *= 0.5;
                continue;
            }
            Err(e) => {
                h *= 0.5;
                if h < s.h_min {
                    break Stop::StepTooSmall {
                        parameter: last.u[k],
                        cause: e.0,
                    };
                }
                continue;
            }
        };
        let last = last.clone();
        let found = crossed(&last, &next);
        // the tangent at `next` was factored with `k_local`; locating an
        // event factors elsewhere
        if found.is_empty() {
            held = Some(k_local);
        }
        let after = points.len() - 1;
        let new_events: Vec<Event<P::Info>> = found
            .into_iter()
            .filter_map(|kind| locate(p, &last, &next, kind, s).map(|at| Event { kind, after, at }))
            .collect();
        events.extend(new_events.iter().cloned());
        points.push(next);
        if turn < 0.25 * s.max_turn && iters <= 5 {
            h = (1.3 * h).min(s.h_max);
        }
        let accepted = Step {
            point: points.last().expect("just pushed"),
            events: &new_events,
            h,
            steps,
        };
        if !observe(&accepted) {
            break Stop::Interrupted;
        }
        if let Some(stop) = stop_after(p, &points, s) {
            break stop;
        }
    };
    Branch {
        points,
        events,
        stop,
    }
}

/// What changes on the step from `last` to `next` (points of one branch):
/// a fold where the parameter's tangent component changes sign, each test
/// function that changes.
pub fn crossed<I>(last: &Point<I>, next: &Point<I>) -> Vec<EventKind> {
    let k = next.u.len() - 1;
    let mut found = Vec::new();
    if (next.tangent[k] > 0.0) != (last.tangent[k] > 0.0) {
        found.push(EventKind::Fold);
    }
    for (i, (a, b)) in last
        .monitor
        .tests
        .iter()
        .zip(&next.monitor.tests)
        .enumerate()
    {
        if a.differs(*b) {
            found.push(EventKind::Test(i));
        }
    }
    found
}

/// Whether the branch ends with its last step: the parameter left its
/// range, the problem's own bound, or the branch came back through its
/// start.
fn stop_after<P: Problem>(p: &P, points: &[Point<P::Info>], s: &Settings) -> Option<Stop> {
    let [.., last, next] = points else {
        return None;
    };
    let k = next.u.len() - 1;
    if next.u[k] < s.range.0 || next.u[k] > s.range.1 {
        return Some(Stop::Range);
    }
    if p.beyond(&last.u, &next.u) {
        return Some(Stop::Bound);
    }
    let start = &points[0];
    if points.len() > 10
        && passes_through(&last.u, &next.u, &start.u, 0.1 * s.h_max)
        && dot(&next.tangent, &start.tangent) > 0.5
    {
        return Some(Stop::Closed);
    }
    None
}

/// True when the segment from `a` to `b` passes within `tol` of `p`.
fn passes_through(a: &[f64], b: &[f64], p: &[f64], tol: f64) -> bool {
    segment_distance(a, b, p) <= tol
}

/// The Euclidean distance from `p` to the segment from `a` to `b`.
pub fn segment_distance(a: &[f64], b: &[f64], p: &[f64]) -> f64 {
    let ab: Vec<f64> = b.iter().zip(a).map(|(x, y)| x - y).collect();
    let ap: Vec<f64> = p.iter().zip(a).map(|(x, y)| x - y).collect();
    let len2 = dot(&ab, &ab);
    let s = if len2 > 0.0 {
        (dot(&ap, &ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let d2: f64 = ap.iter().zip(&ab).map(|(x, y)| (x - s * y).powi(2)).sum();
    d2.sqrt()
}

mod ledger;
pub mod sparse;

pub use ledger::{Ledger, NoLedger, Step, Trace};

#[cfg(test)]
mod tests;
