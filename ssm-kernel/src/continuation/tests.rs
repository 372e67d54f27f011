//! The core on problems with closed-form branches.

use super::*;
use faer::linalg::solvers::Solve;
use faer::Mat;

/// `x^2 + lambda^2 = r^2` (a circle: folds at `lambda = +-r`), with the
/// test function `x` (changes sign at the folds too, at `x = 0`) and the
/// count of `x < 0`.
struct Circle {
    r: f64,
    lu: Option<faer::linalg::solvers::PartialPivLu<f64>>,
}

impl Problem for Circle {
    type Info = ();
    fn dim(&self) -> usize {
        2
    }
    fn residual(&mut self, u: &[f64]) -> Result<Vec<f64>, ProblemFailure> {
        Ok(vec![u[0] * u[0] + u[1] * u[1] - self.r * self.r])
    }
    fn factor(&mut self, u: &[f64], k: usize) -> Result<(), ProblemFailure> {
        let m = Mat::<f64>::from_fn(2, 2, |i, j| {
            if i == 0 {
                2.0 * u[j]
            } else {
                f64::from(u8::from(j == k))
            }
        });
        self.lu = Some(m.partial_piv_lu());
        Ok(())
    }
    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), ProblemFailure> {
        let lu = self.lu.as_ref().expect("factored");
        let b = Mat::<f64>::from_fn(2, 1, |i, _| rhs[i]);
        let x = lu.solve(&b);
        rhs[0] = x[(0, 0)];
        rhs[1] = x[(1, 0)];
        Ok(())
    }
    fn monitor(&mut self, u: &[f64], _t: &[f64]) -> Result<Monitor<()>, ProblemFailure> {
        Ok(Monitor {
            tests: vec![Test::Sign(u[0]), Test::Count(usize::from(u[0] < 0.0))],
            info: (),
        })
    }
}

/// Reference: the circle's folds are at `(x, lambda) = (0, +-r)`; the
/// located points must be there to the corrector tolerance, and every point
/// on the circle to 1e-10.
#[test]
fn circle_folds_are_located_and_the_loop_closes() {
    let r = 2.0;
    let mut p = Circle { r, lu: None };
    let s = Settings::new((-10.0, 10.0), 0.2);
    let u0 = solve_at_parameter(&mut p, vec![1.5, 0.5], &s).expect("start");
    assert!((u0[0] - (r * r - 0.25f64).sqrt()).abs() < 1e-12);
    let mut seen = 0;
    let b = continue_branch(&mut p, u0, &[0.0, 1.0], &s, |_| {
        seen += 1;
        true
    })
    .expect("continues");
    assert_eq!(b.stop, Stop::Closed);
    assert_eq!(seen, b.points.len());
    for pt in &b.points {
        assert!((pt.u[0].hypot(pt.u[1]) - r).abs() < 1e-10);
    }
    let folds: Vec<&Event<()>> = b
        .events
        .iter()
        .filter(|e| e.kind == EventKind::Fold)
        .collect();
    assert_eq!(folds.len(), 2, "{:?}", b.events);
    let mut lambdas: Vec<f64> = folds.iter().map(|e| e.at.parameter()).collect();
    lambdas.sort_by(f64::total_cmp);
    assert!((lambdas[0] + r).abs() < 1e-8, "{lambdas:?}");
    assert!((lambdas[1] - r).abs() < 1e-8, "{lambdas:?}");
    // the sign and count tests change at the same two points
    for i in [0, 1] {
        let at: Vec<f64> = b
            .events
            .iter()
            .filter(|e| e.kind == EventKind::Test(i))
            .map(|e| e.at.u[0])
            .collect();
        assert_eq!(at.len(), 2);
        assert!(
            at.iter().all(|x| x.abs() < 1e-8),
            "test {i}: {at:?} {:?}",
            b.events
                .iter()
                .map(|e| (e.kind, e.at.u.clone(), e.after))
                .collect::<Vec<_>>()
        );
    }
}

/// The observer's `false` stops the branch where it is.
#[test]
fn observer_interrupts() {
    let mut p = Circle { r: 1.0, lu: None };
    let s = Settings::new((-10.0, 10.0), 0.1);
    let u0 = solve_at_parameter(&mut p, vec![1.0, 0.0], &s).expect("start");
    let mut n = 0;
    let b = continue_branch(&mut p, u0, &[0.0, 1.0], &s, |_| {
        n += 1;
        n < 4
    })
    .expect("continues");
    assert_eq!(b.stop, Stop::Interrupted);
    assert_eq!(b.points.len(), 4);
}

/// No solution near the start: a typed error, not a panic.
#[test]
fn no_start_is_an_error() {
    let mut p = Circle { r: 1.0, lu: None };
    let s = Settings::new((-10.0, 10.0), 0.1);
    let e = solve_at_parameter(&mut p, vec![0.5, 3.0], &s).unwrap_err();
    assert!(matches!(e, ContinuationError::Start { .. }), "{e}");
}

/// Reference: the uninterrupted continuation around the circle. A run
/// stopped after 7 points and resumed from what its observer saw (the
/// points, the events of each step, the step size and count) gives the same
/// branch, point for point and bit for bit, with the same events and stop;
/// the resumed observer sees only the new points.
#[test]
fn a_resumed_branch_is_the_uninterrupted_branch() {
    let s = Settings::new((-10.0, 10.0), 0.2);
    let mut p = Circle { r: 2.0, lu: None };
    let u0 = solve_at_parameter(&mut p, vec![1.5, 0.5], &s).expect("start");
    let whole = continue_branch(&mut p, u0.clone(), &[0.0, 1.0], &s, |_| true).expect("whole");
    assert!(whole.points.len() > 20 && whole.events.len() >= 2);
    let mut kept: Option<Trace<()>> = None;
    let stopped = continue_branch(&mut p, u0, &[0.0, 1.0], &s, |step| {
        let t = kept.get_or_insert_with(|| Trace {
            points: Vec::new(),
            events: Vec::new(),
            h: 0.0,
            steps: 0,
        });
        t.points.push(step.point.clone());
        t.events.extend(step.events.iter().cloned());
        t.h = step.h;
        t.steps = step.steps;
        t.points.len() < 7
    })
    .expect("stopped");
    assert_eq!(stopped.stop, Stop::Interrupted);
    let mut fresh = Circle { r: 2.0, lu: None };
    let mut seen = 0;
    let resumed = resume_branch(&mut fresh, kept.expect("kept"), &s, |_| {
        seen += 1;
        true
    });
    assert_eq!(resumed, whole);
    assert_eq!(seen, whole.points.len() - 7);
}
