//! The least-squares fit of the NAR model (7.1): the coefficients `K` that
//! minimize `Err = sum_p M_p^{-1} sum_k |K psi(xi_k^p) - xi_{k+1}^p|^2`,
//! the weighted residual behind (7.2).
//!
//! The paper writes the minimizer through the normal matrix, `K = Q P^{-1}`
//! (7.2). Forming `P = Psi^T Psi` squares the condition number of the
//! regression, which for monomials of order 5 on decaying signals is already
//! large, so the fit here is orthogonal: the weighted, column-equilibrated
//! regression matrix is bordered by the right-hand side, `[Psi | b] = Q R`
//! (Householder QR, faer), and the small triangle `R11` is decomposed by SVD,
//! `R11 = U S V^T`; then
//! `x = sum_i f_i (u_i^T c / s_i) v_i`, `c = R[..N, N]`,
//! with filter factors `f_i = s_i^2 / (s_i^2 + (lambda s_1)^2)` (ridge, Tikhonov)
//! and `f_i = 0` for `s_i <= rcond s_1` (truncated SVD). The residual follows
//! from the same factors, `|Psi x - b|^2 = |R11 x - c|^2 + R[N, N]^2`.
//!
//! Only the last delay coordinate is fitted: the others of `xi_{k+1}` are
//! coordinates of `xi_k` (`F_i(xi) = xi_{i+1}`, `i < 2 nu`), which the fit of
//! (7.2) reproduces exactly, so they are set exactly instead.
//!
//! # References
//! R. Szalai, D. Ehrhardt, G. Haller, Proc. R. Soc. A 473 (2017) 20160759,
//! Sect. 7, eqs. (7.1)-(7.2); G. H. Golub, C. F. Van Loan, *Matrix
//! Computations*, 4th ed., Sects. 5.3 (least squares by QR) and 6.1
//! (regularization by SVD filtering).

use faer::Mat;

use crate::embedding::{MonomialBasis, Series};

/// Largest condition number of the equilibrated regression accepted without
/// regularization: beyond it, the coefficients carry less than four
/// significant digits even for exact data.
pub const MAX_CONDITION: f64 = 1e12;

/// Largest `rcond` accepted. `rcond` drops the singular values of the
/// equilibrated regression below that fraction of the largest, as the noise
/// level of the data would blur them; a fraction of 10 % drops directions
/// determined to one digit even with noise of 10 % of the signal, beyond
/// which no map is identified from the data at all.
pub const RCOND_MAX: f64 = 0.1;

/// The residual a regularization may leave beyond the data's own (see
/// [`FitError::Regularized`]), as a fraction of the signal: a misfit of one part in
/// a million moves the identified multipliers by about as much (first-order
/// perturbation of the companion matrix), below the decay per sample of
/// any damping the identification reports (`zeta omega T` of 1e-4 and up).
pub const EXCESS_FLOOR: f64 = 1e-6;

/// How the least-squares problem is regularized.
#[derive(Debug, Clone, Copy)]
pub struct FitSettings {
    /// Embedding dimension `2 nu`.
    pub dim: usize,
    /// Tikhonov parameter relative to the largest singular value (0: none).
    pub ridge: f64,
    /// Singular values below `rcond` times the largest are dropped (0: none).
    pub rcond: f64,
    /// Relative weighting: each row is divided by `(|xi_k| / scale)^p`
    /// with this exponent `p` (0: the uniform weighting of (7.2); 1: the
    /// residual relative to the delay vector). The truncation error of an
    /// order-r map grows like `|xi|^(r+1)` while the linear part acts like
    /// `|xi|`, so `p > 1` lets the small-amplitude tail of decaying data pin
    /// the linear part (multipliers, damping) against the truncation.
    pub weight_power: f64,
    /// Delay vectors with `|xi_k| < floor * scale` are left out (below the
    /// noise they carry no information, and errors in the regressors bias
    /// the fit towards zero).
    pub floor: f64,
}

/// The fitted last row of the sampling map and what the regression says of it.
#[derive(Debug, Clone)]
pub struct Fit {
    /// Coefficient of each monomial of the basis, in the data's units.
    pub coefficients: Vec<f64>,
    /// Singular values of the weighted, equilibrated regression matrix.
    pub singular_values: Vec<f64>,
    /// Their ratio, largest over smallest.
    pub condition: f64,
    /// Singular values used (all, unless `rcond` truncated some).
    pub rank: usize,
    /// `|Psi x - b| / |b|` (weighted).
    pub relative_residual: f64,
    /// The same of the unregularized least-squares solution: what no
    /// map of this order explains in these data (their noise and the
    /// truncation of the map), the data's own noise level.
    pub data_residual: f64,
    /// Regression rows.
    pub rows: usize,
    /// Scale of the data (largest `|y|`).
    pub scale: f64,
}

/// Why the regression cannot be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    /// A signal has too few samples for one delay vector and its successor.
    #[error("{file}: {samples} samples after skip/decimate; at least {needed} are needed for one delay vector of dimension {dim} and its successor")]
    ShortSignal {
        /// File.
        file: String,
        /// Samples kept.
        samples: usize,
        /// Samples needed.
        needed: usize,
        /// Embedding dimension.
        dim: usize,
    },
    /// Fewer regression rows than unknowns.
    #[error("{rows} regression rows (delay vectors over all signals, above the floor) for {unknowns} unknowns; give longer or more signals, lower floor, or lower order/nu")]
    Underdetermined {
        /// Rows.
        rows: usize,
        /// Unknowns.
        unknowns: usize,
    },
    /// The signals are identically zero.
    #[error("every signal is zero: there is nothing to fit")]
    ZeroData,
    /// The regression matrix is numerically rank deficient.
    #[error("rank-deficient regression: condition number {condition:.2e} (singular values fall to {smallest:.2e} of the largest); the monomials of order {order} are nearly dependent on these data. Lower order or nu, add signals that leave the SSM, or regularize with ridge (e.g. 1e-8) or rcond (e.g. 1e-10)")]
    RankDeficient {
        /// Condition number.
        condition: f64,
        /// Smallest singular value relative to the largest.
        smallest: f64,
        /// Polynomial order.
        order: usize,
    },
    /// The data's scale puts the highest-order coefficients outside double
    /// precision (they scale as `scale^(1 - r)`).
    #[error("the signals' largest value {scale:e} makes the order-{order} coefficients scale like {scale:e}^{} (outside double precision); give the signals in units that put them near 1 (e.g. mm/s instead of km/s)", 1i64 - *order as i64)]
    Scale {
        /// Largest `|y|`.
        scale: f64,
        /// Polynomial order.
        order: usize,
    },
    /// Truncation kept fewer singular directions than the linear part of
    /// the map has coefficients.
    #[error("rcond = {rcond:e} keeps {rank} of {unknowns} singular values, fewer than the {needed} coefficients of the map's linear part (2 nu): its multipliers and damping ratios would be a projection, not a fit; lower rcond (e.g. 1e-10) or use ridge")]
    RankTooLow {
        /// The truncation.
        rcond: f64,
        /// Singular values kept.
        rank: usize,
        /// Unknowns.
        unknowns: usize,
        /// The linear coefficients.
        needed: usize,
    },
    /// The regularization left unexplained a part of the data that the
    /// least-squares fit explains.
    #[error("the regularized fit leaves {residual:.2e} of the data unexplained (relative residual), the least-squares fit {data:.2e}: the regularization removed {excess:.2e} of the signal, above the data's own misfit (their noise level) and above {floor:e}, so the identified linear part (multipliers, damping ratios) cannot be trusted; lower {setting}")]
    Regularized {
        /// The regularized fit's relative residual.
        residual: f64,
        /// The unregularized fit's.
        data: f64,
        /// The part removed by the regularization.
        excess: f64,
        /// [`EXCESS_FLOOR`].
        floor: f64,
        /// `ridge`, `rcond` or both.
        setting: &'static str,
    },
    /// The factorization produced non-finite numbers.
    #[error(
        "the least-squares solution is not finite (SVD did not converge or the data overflow)"
    )]
    NotFinite,
}

/// Fits the last delay coordinate: `y_{k + 2 nu} ~ sum_m a_m xi_k^m`.
pub fn fit(series: &Series, basis: &MonomialBasis, set: &FitSettings) -> Result<Fit, FitError> {
    let dim = set.dim;
    for (p, v) in series.values.iter().enumerate() {
        if v.len() < dim + 1 {
            return Err(FitError::ShortSignal {
                file: series.sources[p].clone(),
                samples: v.len(),
                needed: dim + 1,
                dim,
            });
        }
    }
    let n = basis.len();
    let scale = series.scale();
    if scale == 0.0 {
        return Err(FitError::ZeroData);
    }
    let order = (0..n).map(|k| basis.degree(k)).max().unwrap_or(1) as usize;
    if !(scale.powi(1 - order as i32).is_normal() && scale.is_normal()) {
        return Err(FitError::Scale { scale, order });
    }
    // the delay vectors kept (above the floor), per trajectory
    let delay = |v: &[f64], k: usize, xi: &mut [f64]| {
        for (j, x) in xi.iter_mut().enumerate() {
            *x = v[k + j] / scale;
        }
        xi.iter().map(|x| x * x).sum::<f64>().sqrt()
    };
    let mut xi = vec![0.0; dim];
    let kept: Vec<Vec<usize>> = series
        .values
        .iter()
        .enumerate()
        .map(|(p, v)| {
            (0..series.rows(p, dim))
                .filter(|&k| {
                    let norm = delay(v, k, &mut xi);
                    norm > 0.0 && norm >= set.floor
                })
                .collect()
        })
        .collect();
    let rows: usize = kept.iter().map(Vec::len).sum();
    if rows < n + 1 {
        return Err(FitError::Underdetermined { rows, unknowns: n });
    }
    // [Psi | b], rows weighted by M_p^{-1/2} as in (7.2), data scaled to O(1)
    let mut aug = Mat::<f64>::zeros(rows, n + 1);
    let mut psi = vec![0.0; n];
    let mut r = 0;
    for (v, ks) in series.values.iter().zip(&kept) {
        let w_p = 1.0 / (ks.len().max(1) as f64).sqrt();
        for &k in ks {
            let norm = delay(v, k, &mut xi);
            basis.eval(&xi, &mut psi);
            let w = w_p / norm.powf(set.weight_power);
            for (j, &val) in psi.iter().enumerate() {
                aug[(r, j)] = w * val;
            }
            aug[(r, n)] = w * v[k + dim] / scale;
            r += 1;
        }
    }
    // column equilibration: the conditioning reported is that of the
    // best-scaled problem, not of the monomials' units
    let mut col_norm = vec![0.0; n];
    for (j, cn) in col_norm.iter_mut().enumerate() {
        *cn = aug.col(j).norm_l2();
        if *cn == 0.0 {
            return Err(FitError::RankDeficient {
                condition: f64::INFINITY,
                smallest: 0.0,
                order: basis
                    .exponents
                    .iter()
                    .map(|e| e.iter().sum::<u32>())
                    .max()
                    .unwrap_or(0) as usize,
            });
        }
        let inv = 1.0 / *cn;
        aug.col_mut(j).iter_mut().for_each(|x| *x *= inv);
    }
    // Householder QR in place: the regression is the largest array of the
    // identification, so it is neither copied nor split into Q and R
    let rfac = qr_triangle(aug);
    let r11 = rfac.get(..n, ..n).to_owned();
    let c: Vec<f64> = (0..n).map(|i| rfac[(i, n)]).collect();
    let r_tail = rfac[(n, n)].abs();
    let svd = r11.svd().map_err(|_| FitError::NotFinite)?;
    let s: Vec<f64> = svd.S().column_vector().iter().copied().collect();
    let (u, vmat) = (svd.U(), svd.V());
    let s_max = s.first().copied().unwrap_or(0.0);
    if !(s_max.is_finite() && s_max > 0.0) {
        return Err(FitError::NotFinite);
    }
    let s_min = s.last().copied().unwrap_or(0.0);
    let condition = s_max / s_min;
    if set.ridge == 0.0 && set.rcond == 0.0 && (condition.is_nan() || condition > MAX_CONDITION) {
        return Err(FitError::RankDeficient {
            condition,
            smallest: s_min / s_max,
            order,
        });
    }
    let lambda2 = (set.ridge * s_max).powi(2);
    let mut x = vec![0.0; n];
    let mut rank = 0;
    for (i, &si) in s.iter().enumerate() {
        if si <= set.rcond * s_max || si == 0.0 {
            continue;
        }
        rank += 1;
        let uc: f64 = (0..n).map(|k| u[(k, i)] * c[k]).sum();
        let coef = uc * si / (si * si + lambda2);
        for (k, xk) in x.iter_mut().enumerate() {
            *xk += coef * vmat[(k, i)];
        }
    }
    let mut res2 = r_tail * r_tail;
    for (i, ci) in c.iter().enumerate() {
        let rx: f64 = (i..n).map(|k| r11[(i, k)] * x[k]).sum();
        res2 += (rx - ci).powi(2);
    }
    let b2 = c.iter().map(|v| v * v).sum::<f64>() + r_tail * r_tail;
    if set.rcond > 0.0 && rank < dim {
        return Err(FitError::RankTooLow {
            rcond: set.rcond,
            rank,
            unknowns: n,
            needed: dim,
        });
    }
    // the discrepancy principle (Morozov; Hansen, Rank-Deficient and
    // Discrete Ill-Posed Problems (1998), Sect. 7.2): a regularization is
    // sound while the misfit it adds stays at the data's noise level. The
    // data's own level, noise and the map's truncation together, is the
    // residual of the unregularized least squares, |R[N, N]| / |b|; the
    // misfit the filter factors add is |R11 x - c| / |b|. Above both it and
    // EXCESS_FLOOR (noise-free data) the fit discards signal, first the
    // slow decay that the damping ratios are read from.
    let b = b2.max(f64::MIN_POSITIVE).sqrt();
    let (residual, data) = (res2.sqrt() / b, r_tail / b);
    let excess = (res2 - r_tail * r_tail).max(0.0).sqrt() / b;
    if excess > data.max(EXCESS_FLOOR) {
        return Err(FitError::Regularized {
            residual,
            data,
            excess,
            floor: EXCESS_FLOOR,
            setting: match (set.ridge > 0.0, set.rcond > 0.0) {
                (true, true) => "ridge and rcond",
                (true, false) => "ridge",
                _ => "rcond",
            },
        });
    }
    let coefficients: Vec<f64> = (0..n)
        .map(|j| x[j] / col_norm[j] * scale.powi(1 - basis.degree(j) as i32))
        .collect();
    if coefficients.iter().any(|v| !v.is_finite()) {
        return Err(FitError::NotFinite);
    }
    Ok(Fit {
        coefficients,
        singular_values: s,
        condition,
        rank,
        relative_residual: residual,
        data_residual: data,
        rows,
        scale,
    })
}

/// The triangle `R` (square, of the column count) of the Householder QR of
/// `a`, factored in place with faer's blocked algorithm (in parallel for
/// large problems).
fn qr_triangle(mut a: Mat<f64>) -> Mat<f64> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::qr::no_pivoting::factor;
    let (m, n) = a.shape();
    // below some 1e9 flops the threads' synchronization costs more than
    // the second core gains
    let par = if (m as f64) * (n as f64).powi(2) < 5e8 {
        faer::Par::Seq
    } else {
        faer::get_global_parallelism()
    };
    let block = factor::recommended_block_size::<f64>(m, n);
    let mut householder = Mat::<f64>::zeros(block, m.min(n));
    let scratch = factor::qr_in_place_scratch::<f64>(m, n, block, par, Default::default());
    factor::qr_in_place(
        a.as_mut(),
        householder.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    );
    Mat::from_fn(n, n, |i, j| if i <= j { a[(i, j)] } else { 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform weighting, no floor, no ridge, 2 nu = 2, truncation `rcond`.
    fn plain(rcond: f64) -> FitSettings {
        FitSettings {
            dim: 2,
            ridge: 0.0,
            rcond,
            weight_power: 0.0,
            floor: 0.0,
        }
    }

    fn series(values: Vec<Vec<f64>>) -> Series {
        Series {
            sources: (0..values.len()).map(|p| format!("s{p}.csv")).collect(),
            values,
            period: 1.0,
        }
    }

    /// Data generated by a known quadratic recurrence are fitted exactly
    /// (reference: the recurrence's coefficients, 1e-9 relative).
    #[test]
    fn recovers_a_known_recurrence() {
        // y_{k+2} = 1.6 y_{k+1} - 0.9 y_k + 0.3 y_k y_{k+1} - 0.2 y_k^2
        let exact = |a: f64, b: f64| 1.6 * b - 0.9 * a + 0.3 * a * b - 0.2 * a * a;
        let mk = |y0: f64, y1: f64| {
            let mut v = vec![y0, y1];
            for k in 0..400 {
                let next = exact(v[k], v[k + 1]);
                v.push(next);
            }
            v
        };
        let s = series(vec![mk(0.3, 0.1), mk(-0.2, 0.25)]);
        let basis = MonomialBasis::new(2, 2);
        let f = fit(&s, &basis, &plain(0.0)).unwrap();
        let want = |e: &[u32]| match e {
            [1, 0] => -0.9,
            [0, 1] => 1.6,
            [1, 1] => 0.3,
            [2, 0] => -0.2,
            _ => 0.0,
        };
        for (k, e) in basis.exponents.iter().enumerate() {
            assert!(
                (f.coefficients[k] - want(e)).abs() < 1e-9,
                "{e:?}: {} vs {}",
                f.coefficients[k],
                want(e)
            );
        }
        assert!(f.relative_residual < 1e-12);
    }

    /// A signal that obeys a linear recurrence leaves the quadratic monomials
    /// dependent on the linear ones only if it is degenerate; a constant
    /// signal makes the regression exactly rank deficient and is refused.
    #[test]
    fn refuses_a_rank_deficient_regression() {
        let s = series(vec![vec![0.5; 200]]);
        let basis = MonomialBasis::new(2, 3);
        let e = fit(&s, &basis, &plain(0.0)).unwrap_err();
        assert!(matches!(e, FitError::RankDeficient { .. }), "{e}");
        // with truncation they keep one singular value, fewer than the two
        // coefficients of the linear part: refused, not a projection
        let e = fit(&s, &basis, &plain(1e-10)).unwrap_err();
        assert!(
            matches!(
                e,
                FitError::RankTooLow {
                    rank: 1,
                    needed: 2,
                    ..
                }
            ),
            "{e}"
        );
    }

    /// A regularization that leaves part of exactly fitted data unexplained
    /// (ridge 0.3 on the recurrence of `recovers_a_known_recurrence`, whose
    /// least-squares residual is at rounding level) is refused naming ridge;
    /// a light one (1e-12) is kept.
    #[test]
    fn refuses_a_regularization_that_discards_signal() {
        let exact = |a: f64, b: f64| 1.6 * b - 0.9 * a + 0.3 * a * b;
        let mut v = vec![0.3, 0.1];
        for k in 0..400 {
            let next = exact(v[k], v[k + 1]);
            v.push(next);
        }
        let s = series(vec![v]);
        let basis = MonomialBasis::new(2, 2);
        let ridge = |r: f64| FitSettings {
            ridge: r,
            ..plain(0.0)
        };
        let e = fit(&s, &basis, &ridge(0.3)).unwrap_err();
        assert!(
            matches!(
                e,
                FitError::Regularized {
                    setting: "ridge",
                    ..
                }
            ),
            "{e}"
        );
        let f = fit(&s, &basis, &ridge(1e-12)).unwrap();
        assert!(
            f.relative_residual < EXCESS_FLOOR,
            "{}",
            f.relative_residual
        );
    }

    /// Signals of scale 1e-150 or 1e150 put order-5 coefficients (scale^-4)
    /// outside double precision: refused with the units advice, never
    /// returned as infinite or silently zero coefficients.
    #[test]
    fn refuses_data_whose_scale_overflows_the_coefficients() {
        for scale in [1e-150, 1e150] {
            let v: Vec<f64> = (0..300)
                .map(|k| scale * (-0.01 * k as f64).exp() * (0.9 * k as f64).cos())
                .collect();
            let e = fit(&series(vec![v]), &MonomialBasis::new(2, 5), &plain(0.0)).unwrap_err();
            assert!(matches!(e, FitError::Scale { order: 5, .. }), "{e}");
            assert!(e.to_string().contains("units"), "{e}");
        }
    }
}
