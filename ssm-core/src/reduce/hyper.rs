//! The reduced polynomial of a POD model evaluated through the lift, and
//! its hyper-reduction by the discrete empirical interpolation method.
//!
//! The Galerkin projection `V^T F(V y)` ([`super::galerkin`]) expanded in
//! the reduced states is dense: with POD modes that mix every coordinate, a
//! bilinear constraint becomes `r (r + 1) / 2` monomials per reduced
//! equation and a cubic force `O(r^3)`. Evaluated through the lift instead,
//!
//! ```text
//! z_S = V_S y,   f_S = F_S(z_S),   F_r(y) = P f_S,
//! ```
//!
//! a step costs what the rows `S` of the full polynomial and their variables
//! cost: the lift of the variables those rows use (`r` per variable), the
//! full model's own sparse terms, and the projection `P` (`nr` per row).
//! With every row of `F` and `P = V^T` this is exactly the projected model
//! (to round-off).
//!
//! The hyper-reduction samples the internal forces, the momentum-row terms
//! free of multipliers, by DEIM: the force snapshots `F_int(z_k)` of the
//! training run give orthonormal modes `U_f` (`n_f x m`, an SVD), the greedy
//! DEIM selection picks `m` rows `S` (Chaturantabut & Sorensen 2010,
//! Algorithm 1), and
//!
//! ```text
//! V^T F_int(z) ~ V_F^T U_f (S^T U_f)^{-1} S^T F_int(z)      (eq. 2.2 there)
//! ```
//!
//! needs the `m` sampled rows only. The constraint rows and the reaction
//! terms `C_q^T mu` are kept exactly (lifted, not sampled): an interpolated
//! reaction would no longer be the transpose of the reduced constraint
//! Jacobian, and the iteration matrix of the index-3 DAE relies on it.
//! The error control is the training error of the reduced force,
//! `max_k |V_F^T (F_k - D F_k)|` over the snapshots (`D` the DEIM
//! interpolation) relative to the peak of the reduced internal force, and
//! `m` is the smallest sample meeting the tolerance; where the nonlinear
//! part cancels the linear one the whole internal force is sampled instead
//! ([`deim`]); with every force row sampled the interpolation is the
//! identity and the model is exact.
//!
//! # References
//! S. Chaturantabut, D. C. Sorensen, *Nonlinear model reduction via discrete
//! empirical interpolation*, SIAM J. Sci. Comput. 32 (2010) 2737-2764,
//! eq. (2.2), Algorithm 1, Lemma 3.2; M. Stadlmayr, W. Witteveen, W. Steiner,
//! *A generalized constraint reduction method for reduced order MBS models*,
//! Multibody Syst. Dyn. (2017), eq. (14) (the lifted evaluation the paper
//! names the method's bottleneck).

use std::collections::HashMap;
use std::time::Instant;

use faer::Mat;
use ssm_api::PolyVector;

use crate::fom::lifted::{LiftedPoly, Placed};

/// Singular values of the force snapshots below this fraction of the
/// largest count as zero (no DEIM mode is made of them).
const RANK_TOL: f64 = 1e-13;

/// Most force snapshots used for the DEIM training (evenly spread).
const MAX_SNAPSHOTS: usize = 400;

/// Whether the term of `full` is a constraint or reaction term of the
/// canonical layout `(q, q', mu)` with `n` coordinates: in a constraint row,
/// or with a multiplier (or a later state) among its variables.
fn is_constraint_term(full: &PolyVector, term: usize, n: usize) -> bool {
    let t = &full.terms[term];
    t.eq as usize >= 2 * n || t.factors.iter().any(|f| f.var as usize >= 2 * n)
}

/// Whether the term has degree two or more: constants and linear terms of a
/// model's polynomial go into the projected model's constant and linear
/// part ([`super::galerkin::project_mechanical`]), not into its nonlinearity.
fn nonlinear(full: &PolyVector, term: usize) -> bool {
    full.terms[term]
        .factors
        .iter()
        .map(|f| f.power)
        .sum::<u32>()
        >= 2
}

/// `V^T F(V y)` evaluated through the lift, every row of `F` kept: the
/// projected polynomial's nonlinear part exactly. `v_rows[i]` is row `i` of `V`
/// (`(reduced state, weight)`), `n_reduced` its columns.
pub fn lifted_exact(full: &PolyVector, v_rows: &[Vec<(u32, f64)>], n_reduced: usize) -> LiftedPoly {
    let mut local_row: HashMap<u32, usize> = HashMap::new();
    let mut rows = Vec::new();
    let mut placed = Vec::new();
    for (k, t) in full.terms.iter().enumerate() {
        if v_rows[t.eq as usize].is_empty() || !nonlinear(full, k) {
            continue;
        }
        let row = *local_row.entry(t.eq).or_insert_with(|| {
            rows.push((t.eq, v_rows[t.eq as usize].clone()));
            rows.len() - 1
        });
        placed.push(Placed { term: k, row });
    }
    LiftedPoly::assemble(full, &placed, rows, v_rows, n_reduced)
}

/// How many rows the DEIM samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sample {
    /// The fewest rows whose training error is at most this.
    Tolerance(f64),
    /// This many rows (all force rows when it reaches their number).
    Points(usize),
}

/// What the DEIM training found.
#[derive(Debug, Clone, PartialEq)]
pub struct HyperInfo {
    /// Full rows carrying internal forces (the candidates).
    pub force_rows: usize,
    /// The sampled full rows, in the order DEIM picked them.
    pub sampled: Vec<usize>,
    /// `true` when every force row is sampled (the identity: exact).
    pub all_rows: bool,
    /// Singular values of the force snapshots.
    pub singular_values: Vec<f64>,
    /// Training error of the reduced internal force (see the module).
    pub training_error: f64,
    /// Snapshots used.
    pub snapshots: usize,
    /// Seconds of the training.
    pub seconds: f64,
    /// `true` when the sampled rows carry the whole internal force, its
    /// linear part included (see [`deim`]).
    pub total: bool,
}

/// Why a hyper-reduction could not be trained.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HyperError {
    /// The sample size or tolerance is unusable.
    #[error("hyper-reduction: {0}")]
    Sample(String),
    /// The SVD of the force snapshots failed.
    #[error("hyper-reduction: the SVD of the force snapshots did not converge")]
    Svd,
}

/// A hyper-reduced polynomial: constraint rows and reactions lifted exactly,
/// the internal forces interpolated at DEIM rows.
#[derive(Debug, Clone)]
pub struct Hyper {
    /// The polynomial to evaluate.
    pub lifted: LiftedPoly,
    /// The training's figures.
    pub info: HyperInfo,
    /// Where the sampled rows carry the whole internal force
    /// ([`HyperInfo::total`]): the entries `(p, q, value)` to subtract from
    /// the reduced model's linear part `A_r`, the projection `V_F^T A_F V`
    /// of the sampled rows' linear part now evaluated at the DEIM rows
    /// (empty otherwise).
    pub linear_removed: Vec<(usize, usize, f64)>,
}

/// The DEIM hyper-reduction of `V^T F(V y)` for the canonical mechanical
/// layout with `n` coordinates, trained on the full states `snapshots`
/// (shifted like `F`); `linear` is the full model's linear part `A`.
///
/// What is sampled: the nonlinear internal force `F_nl`, or the whole
/// internal force `A_F z + F_nl(z)` (the force rows' linear part off the
/// multipliers included), whichever meets `sample` with fewer rows (then
/// with the smaller training error). The whole force wins where the
/// nonlinear part cancels the linear one, as in absolute nodal coordinates,
/// where a rigid rotation of an element makes large coordinates and no
/// force, or in a von Karman beam's membrane response: an interpolation
/// error relative to the cancelling parts is then an error far larger
/// relative to the force they leave, while the whole force is zero at the
/// sampled rows under rigid motion, hence zero after the interpolation. Its
/// linear part then leaves the reduced `A` ([`Hyper::linear_removed`]).
/// Either way the training error is that of the reduced internal force,
/// `max_k |V_F^T (F_k - D F_k)|` of the sampled `F` relative to
/// `max_k |V_F^T (A_F z_k + F_nl(z_k))|`.
pub fn deim(
    full: &PolyVector,
    linear: &ssm_api::SparseMatrix,
    v_rows: &[Vec<(u32, f64)>],
    n_reduced: usize,
    n: usize,
    snapshots: &[Vec<f64>],
    sample: Sample,
) -> Result<Hyper, HyperError> {
    let clock = Instant::now();
    match sample {
        Sample::Tolerance(t) if !(t > 0.0 && t < 1.0) => {
            return Err(HyperError::Sample(format!(
                "the tolerance {t} must lie in (0, 1)"
            )))
        }
        Sample::Points(0) => {
            return Err(HyperError::Sample(
                "the sample must have at least one row".into(),
            ))
        }
        _ => {}
    }
    let force_terms: Vec<usize> = (0..full.terms.len())
        .filter(|&k| nonlinear(full, k) && !is_constraint_term(full, k, n))
        .filter(|&k| !v_rows[full.terms[k].eq as usize].is_empty())
        .collect();
    let mut force_rows: Vec<u32> = force_terms.iter().map(|&k| full.terms[k].eq).collect();
    force_rows.sort_unstable();
    force_rows.dedup();
    let nf = force_rows.len();
    let stride = snapshots.len().div_ceil(MAX_SNAPSHOTS).max(1);
    let picks: Vec<&Vec<f64>> = snapshots.iter().step_by(stride).collect();
    // F_int at the snapshots, rows = force rows
    let row_of: HashMap<u32, usize> = force_rows
        .iter()
        .enumerate()
        .map(|(i, &r)| (r, i))
        .collect();
    // the force rows' linear part off the multipliers, as degree-one terms
    // appended to the polynomial (the model's own ones kept in place)
    let mut aug = full.clone();
    let mut linear_terms: Vec<usize> = (0..full.terms.len())
        .filter(|&k| !nonlinear(full, k) && !is_constraint_term(full, k, n))
        .filter(|&k| full.terms[k].factors.len() == 1 && row_of.contains_key(&full.terms[k].eq))
        .collect();
    for (i, k, value) in linear.iter() {
        if value != 0.0 && k < 2 * n && row_of.contains_key(&(i as u32)) {
            aug.push(i, value, &[(k, 1)]);
            linear_terms.push(aug.terms.len() - 1);
        }
    }
    let g_nl = snapshot_matrix(&aug, &force_terms, &row_of, &picks);
    let g_lin = snapshot_matrix(&aug, &linear_terms, &row_of, &picks);
    // V_F (nf x nr) and the reduced force snapshots V_F^T g
    let vf = Mat::from_fn(nf, n_reduced, |i, j| {
        v_rows[force_rows[i] as usize]
            .iter()
            .find(|e| e.0 as usize == j)
            .map_or(0.0, |e| e.1)
    });
    let g_total = &g_nl + &g_lin;
    // the error of either variant is the error of the reduced internal
    // force, V_F^T (F - D F) of what is sampled, against its peak
    let peak = column_peak(&(vf.transpose() * &g_total));
    let nl = select(&g_nl, &vf, peak, sample, picks.len());
    let whole =
        (!linear_terms.is_empty()).then(|| select(&g_total, &vf, peak, sample, picks.len()));
    let rows_of = |c: &Option<(usize, Mat<f64>, f64)>| c.as_ref().map_or((nf, 0.0), |x| (x.0, x.2));
    let (total, selection) = match (nl, whole) {
        (Ok(a), Some(Ok(b))) => {
            // the fewer rows, then the smaller error
            let ((ma, ea), (mb, eb)) = (rows_of(&a.chosen), rows_of(&b.chosen));
            if mb < ma || (mb == ma && eb < ea) {
                (true, b)
            } else {
                (false, a)
            }
        }
        (Err(_), Some(Ok(b))) => (true, b),
        (a, _) => (false, a?),
    };
    let Selection {
        values,
        points,
        chosen,
    } = selection;
    let sampled_terms = if total {
        [force_terms.clone(), linear_terms.clone()].concat()
    } else {
        force_terms.clone()
    };
    let mut local_row: HashMap<u32, usize> = HashMap::new();
    let mut rows = Vec::new();
    let mut placed = Vec::new();
    for (k, t) in aug.terms.iter().enumerate() {
        if nonlinear(&aug, k) && is_constraint_term(&aug, k, n) && !v_rows[t.eq as usize].is_empty()
        {
            let row = *local_row.entry(t.eq).or_insert_with(|| {
                rows.push((t.eq, v_rows[t.eq as usize].clone()));
                rows.len() - 1
            });
            placed.push(Placed { term: k, row });
        }
    }
    let (sampled, all_rows, training_error) = match chosen {
        Some((m, p, err)) => {
            // the sampled rows, projected by the columns of P
            let mut deim_row: HashMap<u32, usize> = HashMap::new();
            for (i, &pt) in points[..m].iter().enumerate() {
                let full_row = force_rows[pt];
                let weights: Vec<(u32, f64)> = (0..n_reduced)
                    .filter(|&j| p[(j, i)] != 0.0)
                    .map(|j| (j as u32, p[(j, i)]))
                    .collect();
                rows.push((full_row, weights));
                deim_row.insert(full_row, rows.len() - 1);
            }
            for &k in &sampled_terms {
                if let Some(&row) = deim_row.get(&aug.terms[k].eq) {
                    placed.push(Placed { term: k, row });
                }
            }
            let sampled = points[..m]
                .iter()
                .map(|&i| force_rows[i] as usize)
                .collect();
            (sampled, false, err)
        }
        None => {
            let mut exact_row: HashMap<u32, usize> = HashMap::new();
            for &r in &force_rows {
                rows.push((r, v_rows[r as usize].clone()));
                exact_row.insert(r, rows.len() - 1);
            }
            for &k in &force_terms {
                placed.push(Placed {
                    term: k,
                    row: exact_row[&full.terms[k].eq],
                });
            }
            (force_rows.iter().map(|&r| r as usize).collect(), true, 0.0)
        }
    };
    // every row sampled: the plain projection, its linear part in A_r
    let total = total && !all_rows;
    let linear_removed = if total {
        projected_linear(&aug, &linear_terms, v_rows, n_reduced)
    } else {
        Vec::new()
    };
    let lifted = LiftedPoly::assemble(&aug, &placed, rows, v_rows, n_reduced);
    Ok(Hyper {
        linear_removed,
        lifted,
        info: HyperInfo {
            force_rows: nf,
            sampled,
            all_rows,
            singular_values: values,
            training_error,
            snapshots: picks.len(),
            seconds: clock.elapsed().as_secs_f64(),
            total,
        },
    })
}

/// The force snapshots: the `terms` of `poly` at the states `picks`,
/// summed per force row (`row_of`: full row -> snapshot row).
fn snapshot_matrix(
    poly: &PolyVector,
    terms: &[usize],
    row_of: &HashMap<u32, usize>,
    picks: &[&Vec<f64>],
) -> Mat<f64> {
    let mut g = Mat::<f64>::zeros(row_of.len(), picks.len());
    for (s, z) in picks.iter().enumerate() {
        for &k in terms {
            let t = &poly.terms[k];
            let v = t.factors.iter().fold(t.coeff, |acc, f| {
                acc * z[f.var as usize].powi(f.power as i32)
            });
            g[(row_of[&t.eq], s)] += v;
        }
    }
    g
}

/// A DEIM training of one sampled force: its singular values, the greedy
/// points, and the chosen sample `(m, P, training error)` (`None`: every
/// row).
struct Selection {
    values: Vec<f64>,
    points: Vec<usize>,
    chosen: Option<(usize, Mat<f64>, f64)>,
}

/// The DEIM of the force snapshots `g` (force rows x snapshots) for the
/// projection `V_F`: the training error of `m` points is
/// `max_k |V_F^T (g_k - U_m (S^T U_m)^{-1} S^T g_k)| / peak`, and `sample`
/// picks `m`.
fn select(
    g: &Mat<f64>,
    vf: &Mat<f64>,
    peak: f64,
    sample: Sample,
    snapshots: usize,
) -> Result<Selection, HyperError> {
    let nf = g.nrows();
    let reduced = vf.transpose() * g;
    let (values, modes) = if nf == 0 || g.ncols() == 0 {
        (Vec::new(), Mat::zeros(nf, 0))
    } else {
        let svd = g.thin_svd().map_err(|_| HyperError::Svd)?;
        let values: Vec<f64> = svd.S().column_vector().iter().copied().collect();
        let largest = values.first().copied().unwrap_or(0.0);
        let rank = values
            .iter()
            .take_while(|&&v| v > RANK_TOL * largest && v > 0.0)
            .count();
        let u = svd.U();
        (values, Mat::from_fn(nf, rank, |i, j| u[(i, j)]))
    };
    let rank = modes.ncols();
    let points = greedy_points(&modes);
    // the DEIM of m points: P = V_F^T U_m (S^T U_m)^{-1}, its training error
    let trial = |m: usize| -> Option<(Mat<f64>, f64)> {
        let um = modes.subcols(0, m);
        let stu = Mat::from_fn(m, m, |i, j| um[(points[i], j)]);
        let lu = stu.partial_piv_lu();
        // (S^T U)^{-1} as the solve of its transpose: P^T = (S^T U)^{-T} U^T V_F
        let ut_vf = um.transpose() * vf;
        let pt = faer::linalg::solvers::Solve::solve_transpose(&lu, &ut_vf);
        if pt
            .col_iter()
            .flat_map(|c| c.iter().copied().collect::<Vec<_>>())
            .any(|v| !v.is_finite())
        {
            return None;
        }
        let sampled = Mat::from_fn(m, g.ncols(), |i, s| g[(points[i], s)]);
        let approx = pt.transpose() * &sampled;
        let err = column_peak(&(&reduced - &approx)) / peak.max(f64::MIN_POSITIVE);
        Some((pt.transpose().to_owned(), err))
    };
    let chosen: Option<(usize, Mat<f64>, f64)> = match sample {
        Sample::Points(m) if m >= nf => None,
        Sample::Points(m) if m > rank => {
            return Err(HyperError::Sample(format!(
                "{m} rows need {m} force modes, the {snapshots} training snapshots give {rank} of the {nf} force rows: sample at most {rank}, or all {nf}"
            )))
        }
        Sample::Points(m) => trial(m).map(|(p, e)| (m, p, e)),
        Sample::Tolerance(tol) => {
            // the smallest sample meeting tol, by doubling then bisection
            // (the training error falls with the sample, Lemma 3.2's bound
            // with the neglected singular values; a few trials, not one per m)
            let top = rank.min(nf.saturating_sub(1));
            let meets = |m: usize| trial(m).filter(|(_, e)| *e <= tol);
            let mut hi = 1;
            while hi < top && meets(hi).is_none() {
                hi = (2 * hi).min(top);
            }
            // no force mode short of every row (no force rows, or forces
            // that vanish on the run): every row
            match (top > 0).then(|| meets(hi)).flatten() {
                None => None,
                Some(found) => {
                    let (mut lo, mut best) = (hi / 2, (hi, found));
                    let mut up = hi;
                    while up - lo > 1 {
                        let mid = (lo + up) / 2;
                        match meets(mid) {
                            Some(f) => {
                                up = mid;
                                best = (mid, f);
                            }
                            None => lo = mid,
                        }
                    }
                    Some((best.0, (best.1).0, (best.1).1))
                }
            }
        }
    };
    Ok(Selection {
        values,
        points,
        chosen,
    })
}

/// `V^T L V` of the degree-one `terms` `L` of `poly`, as `(p, q, value)`.
fn projected_linear(
    poly: &PolyVector,
    terms: &[usize],
    v_rows: &[Vec<(u32, f64)>],
    n_reduced: usize,
) -> Vec<(usize, usize, f64)> {
    let mut dense = vec![0.0; n_reduced * n_reduced];
    for &k in terms {
        let t = &poly.terms[k];
        let var = t.factors[0].var as usize;
        for &(p, wp) in &v_rows[t.eq as usize] {
            for &(q, wq) in &v_rows[var] {
                dense[p as usize * n_reduced + q as usize] += wp * t.coeff * wq;
            }
        }
    }
    dense
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(k, &v)| (k / n_reduced, k % n_reduced, v))
        .collect()
}

/// The largest column norm of `m`.
fn column_peak(m: &Mat<f64>) -> f64 {
    m.col_iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .fold(0.0, f64::max)
}

/// The greedy DEIM points of the orthonormal modes `u` (Chaturantabut &
/// Sorensen 2010, Algorithm 1): the first where the first mode is largest,
/// each next where the next mode's interpolation error at the points chosen
/// so far is largest. Nested: the first `m` points serve `m` modes.
fn greedy_points(u: &Mat<f64>) -> Vec<usize> {
    let (nf, m) = (u.nrows(), u.ncols());
    let mut points: Vec<usize> = Vec::with_capacity(m);
    for l in 0..m {
        let residual: Vec<f64> = if l == 0 {
            (0..nf).map(|i| u[(i, 0)]).collect()
        } else {
            let a = Mat::from_fn(l, l, |i, j| u[(points[i], j)]);
            let b = Mat::from_fn(l, 1, |i, _| u[(points[i], l)]);
            let c = faer::linalg::solvers::Solve::solve(&a.partial_piv_lu(), &b);
            (0..nf)
                .map(|i| u[(i, l)] - (0..l).map(|j| u[(i, j)] * c[(j, 0)]).sum::<f64>())
                .collect()
        };
        let best = (0..nf)
            .filter(|i| !points.contains(i))
            .max_by(|&a, &b| residual[a].abs().total_cmp(&residual[b].abs()))
            .expect("fewer points than rows");
        points.push(best);
    }
    points
}

#[cfg(test)]
mod tests;
