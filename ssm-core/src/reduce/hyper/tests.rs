//! Unit tests of the lifted evaluation and the DEIM training.

use super::*;
use crate::fom::lifted::PreparedLifted;

/// A cubic polynomial in 6 full states (`n = 2` coordinates, velocities,
/// two multipliers) with force terms in rows 0 and 1, reaction terms
/// `q mu` and a constraint row, and a `V` (6 x 4) that mixes them.
/// `V` by its rows: `(reduced state, weight)`.
type Rows = Vec<Vec<(u32, f64)>>;

fn sample() -> (PolyVector, Rows, Mat<f64>) {
    let mut f = PolyVector::zeros(6, 6);
    f.push(0, 1.5, &[(0, 3)]);
    f.push(0, -0.7, &[(0, 1), (1, 1)]);
    f.push(1, 0.4, &[(1, 2), (2, 1)]);
    f.push(1, 2.0, &[(0, 2)]);
    f.push(0, 0.3, &[(0, 1), (4, 1)]);
    f.push(1, -0.2, &[(1, 1), (5, 1)]);
    f.push(4, 1.1, &[(0, 1), (1, 1)]);
    f.push(5, 0.9, &[(1, 2)]);
    f.push(0, 5.0, &[(1, 1)]); // linear: left to the projection's A
    let v = Mat::from_fn(6, 4, |i, j| match (i, j) {
        (0 | 1, 0) => 0.6 + 0.1 * i as f64,
        (0 | 1, 1) => -0.4 + 0.3 * i as f64,
        (2 | 3, 2) => 0.8 - 0.2 * i as f64,
        (4, 3) => 1.0,
        (5, 3) => -0.5,
        _ => 0.0,
    });
    let rows = (0..6)
        .map(|i| {
            (0..4)
                .filter(|&j| v[(i, j)] != 0.0)
                .map(|j| (j as u32, v[(i, j)]))
                .collect()
        })
        .collect();
    (f, rows, v)
}

/// `V^T F_nl(V y)` by lifting every state and evaluating every term of
/// degree two or more.
fn direct(f: &PolyVector, v: &Mat<f64>, y: &[f64]) -> Vec<f64> {
    let z: Vec<f64> = (0..v.nrows())
        .map(|i| (0..v.ncols()).map(|j| v[(i, j)] * y[j]).sum())
        .collect();
    let mut full = vec![0.0; v.nrows()];
    for t in f.terms.iter() {
        if t.factors.iter().map(|x| x.power).sum::<u32>() >= 2 {
            full[t.eq as usize] += t
                .factors
                .iter()
                .fold(t.coeff, |a, x| a * z[x.var as usize].powi(x.power as i32));
        }
    }
    (0..v.ncols())
        .map(|j| (0..v.nrows()).map(|i| v[(i, j)] * full[i]).sum())
        .collect()
}

fn eval(lp: &LiftedPoly, y: &[f64]) -> Vec<f64> {
    let (prep, _) = PreparedLifted::new(lp);
    let mut out = vec![0.0; lp.n_reduced()];
    prep.eval_into(y, 1.0, &mut out);
    out
}

fn none(n: usize) -> ssm_api::SparseMatrix {
    ssm_api::SparseMatrix::zeros(n, n)
}

/// Two coordinates without constraints (states `q0, q1, v0, v1`), the
/// linear force `-k q0 (1, 2)` in the momentum rows 2, 3 and the
/// nonlinear one `k q1^2 (1, 2)`: on the "rigid" states `q0 = q1^2` the
/// whole force is zero while its parts are of size `k`, as
/// for an element of absolute nodal coordinates turning rigidly.
/// Trained on states near that curve, DEIM samples the whole force, takes
/// its projected linear part out of `A_r`, and gives exactly zero at a
/// rigid state with one row; with every row it is the plain projection.
#[test]
fn deim_samples_the_whole_force_where_its_parts_cancel() {
    let k = 1e4;
    let mut a = none(4);
    a.push(2, 0, -k);
    a.push(3, 0, -2.0 * k);
    let mut f = PolyVector::zeros(4, 4);
    f.push(2, k, &[(1, 2)]);
    f.push(3, 2.0 * k, &[(1, 2)]);
    let rows: Rows = (0..4).map(|i| vec![(i as u32, 1.0)]).collect();
    let snaps: Vec<Vec<f64>> = (0..30)
        .map(|j| {
            let s = 0.1 * j as f64 - 1.5;
            vec![s * s + 1e-4 * (3.0 * s).sin(), s, 0.0, 0.0]
        })
        .collect();
    let h = deim(&f, &a, &rows, 4, 2, &snaps, Sample::Points(1)).expect("trains");
    assert!(h.info.total && !h.info.all_rows, "{:?}", h.info);
    let mut removed = [0.0; 16];
    for &(p, q, v) in &h.linear_removed {
        removed[4 * p + q] += v;
    }
    assert_eq!(removed[2 * 4], -k);
    assert_eq!(removed[3 * 4], -2.0 * k);
    assert_eq!(removed.iter().filter(|v| **v != 0.0).count(), 2);
    // A_r - removed is zero: the reduced force is the lifted one alone
    for y in [[4.0, 2.0, 0.3, -0.1], [0.25, -0.5, 0.0, 1.0]] {
        let got = eval(&h.lifted, &y);
        for g in &got {
            assert!(g.abs() < 1e-12 * k, "{got:?}");
        }
    }
    let all = deim(&f, &a, &rows, 4, 2, &snaps, Sample::Points(2)).expect("trains");
    assert!(all.info.all_rows && !all.info.total && all.linear_removed.is_empty());
    // without the linear part nothing cancels: the nonlinear force alone
    let plain = deim(&f, &none(4), &rows, 4, 2, &snaps, Sample::Points(1)).expect("trains");
    assert!(!plain.info.total && plain.linear_removed.is_empty());
}

#[test]
fn lifted_exact_is_the_projection_and_its_jacobian_the_derivative() {
    let (f, rows, v) = sample();
    let lp = lifted_exact(&f, &rows, 4);
    let y = [0.3, -0.2, 0.5, 1.2];
    let (got, want) = (eval(&lp, &y), direct(&f, &v, &y));
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-14 * (1.0 + w.abs()), "{got:?} {want:?}");
    }
    // the Jacobian against central differences (cubic: h^2 error)
    let (prep, cells) = PreparedLifted::new(&lp);
    let mut vals = vec![0.0; cells.len()];
    prep.jac_into(&y, 1.0, &mut vals, |p, q| {
        cells.iter().position(|&c| c == (q, p)).expect("cell")
    });
    let h = 1e-5;
    for q in 0..4 {
        let mut yp = y;
        let mut ym = y;
        yp[q] += h;
        ym[q] -= h;
        let (fp, fm) = (direct(&f, &v, &yp), direct(&f, &v, &ym));
        for p in 0..4 {
            let fd = (fp[p] - fm[p]) / (2.0 * h);
            let an = cells
                .iter()
                .position(|&c| c == (q, p))
                .map_or(0.0, |k| vals[k]);
            assert!((fd - an).abs() < 1e-8, "d{p}/d{q}: {an} vs {fd}");
        }
    }
}

#[test]
fn deim_with_every_force_row_is_exact_and_reactions_stay_exact() {
    let (f, rows, v) = sample();
    let snaps: Vec<Vec<f64>> = (0..20)
        .map(|k| {
            let t = k as f64 * 0.3;
            vec![t.sin(), (1.3 * t).cos(), 0.1 * t, 0.2, 0.5 * t.cos(), -0.1]
        })
        .collect();
    let all = deim(&f, &none(6), &rows, 4, 2, &snaps, Sample::Points(2)).expect("trains");
    assert!(all.info.all_rows && all.info.force_rows == 2);
    let y = [0.3, -0.2, 0.5, 1.2];
    let (got, want) = (eval(&all.lifted, &y), direct(&f, &v, &y));
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-14 * (1.0 + w.abs()));
    }
    // one row: the force is interpolated, the multiplier rows (reduced
    // equation 3: the constraint rows 4, 5) are not touched
    let one = deim(&f, &none(6), &rows, 4, 2, &snaps, Sample::Points(1)).expect("trains");
    assert_eq!(one.info.sampled.len(), 1);
    let got = eval(&one.lifted, &y);
    assert!((got[3] - want[3]).abs() < 1e-14 * (1.0 + want[3].abs()));
    assert!(
        (0..2).any(|p| (got[p] - want[p]).abs() > 1e-6),
        "one row cannot carry two independent rows"
    );
}

#[test]
fn deim_interpolates_a_force_in_the_span_of_its_modes_exactly() {
    // three force rows, every snapshot (and the test state) with row 2 =
    // row 0 + row 1 at z = (a, b, .): a two-mode force, two points exact
    let mut f = PolyVector::zeros(3, 3);
    f.push(0, 1.0, &[(0, 2)]);
    f.push(1, 1.0, &[(1, 2)]);
    f.push(2, 1.0, &[(0, 2)]);
    f.push(2, 1.0, &[(1, 2)]);
    let rows: Vec<Vec<(u32, f64)>> = (0..3)
        .map(|i| vec![(0, 0.5 + 0.1 * i as f64), (1, (i as f64) - 1.0)])
        .collect();
    let snaps: Vec<Vec<f64>> = (0..10)
        .map(|k| vec![(k as f64).sin(), (0.7 * k as f64).cos(), 0.0])
        .collect();
    // n = 3 here: a first-order model without constraints or velocities
    let h = deim(&f, &none(6), &rows, 2, 3, &snaps, Sample::Tolerance(1e-12)).expect("trains");
    assert_eq!(h.info.sampled.len(), 2, "{:?}", h.info);
    assert!(!h.info.all_rows && h.info.training_error < 1e-12);
    let v = Mat::from_fn(3, 2, |i, j| rows[i][j].1);
    let y = [0.4, -1.3];
    let (got, want) = (eval(&h.lifted, &y), direct(&f, &v, &y));
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-12 * (1.0 + w.abs()), "{got:?} {want:?}");
    }
    assert!(matches!(
        deim(&f, &none(6), &rows, 2, 3, &snaps, Sample::Tolerance(0.0)),
        Err(HyperError::Sample(_))
    ));
    assert!(matches!(
        deim(&f, &none(6), &rows, 2, 3, &snaps, Sample::Points(0)),
        Err(HyperError::Sample(_))
    ));
}

#[test]
fn a_model_without_internal_forces_samples_every_row_of_none() {
    // only reaction and constraint terms (a rigid natural-coordinate
    // model): nothing to sample, the lifted model is exact
    let (mut f, rows, v) = sample();
    f.terms = f
        .terms
        .iter()
        .filter(|t| t.eq >= 4 || t.factors.iter().any(|x| x.var >= 4))
        .cloned()
        .collect();
    let snaps = vec![vec![0.1; 6]; 5];
    for s in [Sample::Tolerance(1e-3), Sample::Points(3)] {
        let h = deim(&f, &none(6), &rows, 4, 2, &snaps, s).expect("trains");
        assert_eq!((h.info.force_rows, h.info.sampled.len()), (0, 0));
        assert!(h.info.all_rows);
        let y = [0.3, -0.2, 0.5, 1.2];
        let (got, want) = (eval(&h.lifted, &y), direct(&f, &v, &y));
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 1e-14 * (1.0 + w.abs()));
        }
    }
    // a zero snapshot set: no mode, every row
    let zero = vec![vec![0.0; 6]; 5];
    let (g, _, _) = sample();
    let h = deim(&g, &none(6), &rows, 4, 2, &zero, Sample::Tolerance(1e-3)).expect("trains");
    assert!(h.info.all_rows && h.info.sampled.len() == 2);
}
