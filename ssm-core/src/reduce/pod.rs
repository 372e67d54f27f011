//! Proper orthogonal decomposition of velocity snapshots per coordinate kind
//! and the generalized constraint reduction of Stadlmayr, Witteveen &
//! Steiner (2017): the numerics of the `pod` reducer.
//!
//! - POD (Sect. 3.2): the SVD `X' = Phi Sigma W^T` of the velocity snapshots
//!   of one kind of coordinates (translational, rotational, flexible); the
//!   proper orthogonal values (POVs) `sigma_k`, the modes (POMs) `Phi`,
//!   truncated by a drop of the normalized POVs by some decades or by the
//!   signal energy `sum sigma_k^2` left out.
//! - The global projection `U` (eq. 7), block diagonal over the kinds, and
//!   the modified Galerkin projection `q ~ U q_r + R_q0` with
//!   `R_q0 = q0 - U U^T q0` (eq. 8), likewise for the velocities (eq. 9).
//! - The generalized constraint reduction (Sect. 3.4): the SVD of the
//!   projected constraint Jacobian `C_q U = L B R^T`, its independent left
//!   singular vectors `L^i` (singular values above a rank tolerance), and the
//!   reduced constraints `C_l = (L^i)^T C` (eqs. 12-13).
//!
//! # References
//! M. Stadlmayr, W. Witteveen, W. Steiner, *A generalized constraint reduction
//! method for reduced order MBS models*, Multibody Syst. Dyn. (2017), eqs.
//! (2)-(14).

use faer::{Mat, MatRef};

/// Why a POD or constraint reduction could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PodError {
    /// No snapshots or no coordinates.
    #[error(
        "POD of '{kind}': the snapshot matrix is empty ({rows} coordinates x {cols} snapshots)"
    )]
    Empty {
        /// Coordinate kind.
        kind: String,
        /// Coordinates.
        rows: usize,
        /// Snapshots.
        cols: usize,
    },
    /// A snapshot is NaN or infinite.
    #[error("POD of '{kind}': snapshot {snapshot} of coordinate {coordinate} is not finite")]
    NotFinite {
        /// Coordinate kind.
        kind: String,
        /// Coordinate (row).
        coordinate: usize,
        /// Snapshot (column).
        snapshot: usize,
    },
    /// The SVD did not converge.
    #[error("{what}: the SVD did not converge")]
    Svd {
        /// Which decomposition.
        what: String,
    },
    /// A truncation setting is out of range.
    #[error("POD truncation: {0}")]
    Truncation(String),
}

/// How many POMs of a kind are kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Truncation {
    /// Keep the POVs down to the first drop of the normalized POVs
    /// `sigma_k / sigma_1` by at least `decades` powers of ten from one to the
    /// next (the paper's rule); all nonzero ones when there is no such drop.
    Drop {
        /// Powers of ten.
        decades: f64,
    },
    /// Keep the fewest POMs whose POVs carry `1 - fraction` of the signal
    /// energy `sum sigma_k^2` (the energy left out is at most `fraction`).
    Energy {
        /// Energy fraction left out, in `(0, 1)`.
        fraction: f64,
    },
}

/// The POD of one kind of coordinates.
#[derive(Debug, Clone)]
pub struct PodBasis {
    /// Proper orthogonal values, descending (as many as `min(rows, cols)`).
    pub values: Vec<f64>,
    /// The kept POMs, one per column (`rows x kept`).
    pub modes: Mat<f64>,
}

impl PodBasis {
    /// Number of POMs kept.
    pub fn kept(&self) -> usize {
        self.modes.ncols()
    }
}

/// POD of the snapshots `x` (`coordinates x snapshots`, velocities) of the
/// coordinate kind `kind`, truncated by `rule`. Exactly zero POVs are never
/// kept; a kind without motion keeps no POM.
pub fn pod(x: MatRef<'_, f64>, kind: &str, rule: Truncation) -> Result<PodBasis, PodError> {
    let (rows, cols) = x.shape();
    if rows == 0 || cols == 0 {
        return Err(PodError::Empty {
            kind: kind.into(),
            rows,
            cols,
        });
    }
    for j in 0..cols {
        for i in 0..rows {
            if !x[(i, j)].is_finite() {
                return Err(PodError::NotFinite {
                    kind: kind.into(),
                    coordinate: i,
                    snapshot: j,
                });
            }
        }
    }
    match rule {
        Truncation::Drop { decades } if !(decades.is_finite() && decades > 0.0) => {
            return Err(PodError::Truncation(format!(
                "a drop of {decades} decades must be positive"
            )))
        }
        Truncation::Energy { fraction } if !(fraction > 0.0 && fraction < 1.0) => {
            return Err(PodError::Truncation(format!(
                "the energy fraction left out, {fraction}, must lie in (0, 1)"
            )))
        }
        _ => {}
    }
    let svd = x.thin_svd().map_err(|_| PodError::Svd {
        what: format!("POD of '{kind}'"),
    })?;
    let values: Vec<f64> = svd.S().column_vector().iter().copied().collect();
    let kept = kept_count(&values, rule);
    let u = svd.U();
    let modes = Mat::from_fn(rows, kept, |i, j| u[(i, j)]);
    Ok(PodBasis { values, modes })
}

/// How many of the descending `values` `rule` keeps.
fn kept_count(values: &[f64], rule: Truncation) -> usize {
    let first = values.first().copied().unwrap_or(0.0);
    if first == 0.0 {
        return 0;
    }
    let nonzero = values.iter().take_while(|&&v| v > 0.0).count();
    match rule {
        Truncation::Drop { decades } => {
            let factor = 10f64.powf(decades);
            (1..nonzero)
                .find(|&k| values[k - 1] > factor * values[k])
                .unwrap_or(nonzero)
        }
        Truncation::Energy { fraction } => {
            let total: f64 = values.iter().map(|v| v * v).sum();
            let mut left = total;
            let mut k = 0;
            while k < nonzero && left > fraction * total {
                left -= values[k] * values[k];
                k += 1;
            }
            k.max(1)
        }
    }
}

/// The global projection `U` (`n x r`, eq. 7): the kept POMs of each kind
/// placed on that kind's coordinates (`groups[g].0`, indices into `0..n`),
/// kinds side by side.
pub fn global_projection(n: usize, groups: &[(&[usize], &PodBasis)]) -> Mat<f64> {
    let r: usize = groups.iter().map(|g| g.1.kept()).sum();
    let mut u = Mat::<f64>::zeros(n, r);
    let mut col = 0;
    for (coords, basis) in groups {
        for k in 0..basis.kept() {
            for (row, &c) in coords.iter().enumerate() {
                u[(c, col)] = basis.modes[(row, k)];
            }
            col += 1;
        }
    }
    u
}

/// The residual term `R = q0 - U U^T q0` of the modified Galerkin projection
/// (eqs. 8-9): what `U` cannot represent of the initial values, kept so that
/// `U q_r(0) + R = q0` holds exactly.
pub fn residual_term(u: MatRef<'_, f64>, q0: &[f64]) -> Vec<f64> {
    let coef: Vec<f64> = (0..u.ncols())
        .map(|j| (0..u.nrows()).map(|i| u[(i, j)] * q0[i]).sum())
        .collect();
    (0..u.nrows())
        .map(|i| q0[i] - (0..u.ncols()).map(|j| u[(i, j)] * coef[j]).sum::<f64>())
        .collect()
}

/// The generalized constraint reduction of a projected constraint Jacobian.
#[derive(Debug, Clone)]
pub struct ConstraintReduction {
    /// Singular values of `C_q U`, descending.
    pub singular_values: Vec<f64>,
    /// The independent left singular vectors `L^i` (`m x l`): the reduced
    /// constraints are `C_l = (L^i)^T C`.
    pub basis: Mat<f64>,
}

impl ConstraintReduction {
    /// Number of constraints removed, `m - l`.
    pub fn removed(&self) -> usize {
        self.basis.nrows() - self.basis.ncols()
    }

    /// `(L^i)^T c`: the reduced constraint values (or one column of the
    /// reduced Jacobian) from the original ones.
    pub fn reduce(&self, c: &[f64]) -> Vec<f64> {
        (0..self.basis.ncols())
            .map(|j| {
                (0..self.basis.nrows())
                    .map(|i| self.basis[(i, j)] * c[i])
                    .sum()
            })
            .collect()
    }
}

/// The SVD of the projected constraint Jacobian `cq_u = C_q U` (`m x r`) and
/// its independent left singular vectors: those whose singular value exceeds
/// `rank_tol` times the largest (and is not zero). A Jacobian that vanishes
/// on the subspace keeps no constraint.
pub fn reduce_constraints(
    cq_u: MatRef<'_, f64>,
    rank_tol: f64,
) -> Result<ConstraintReduction, PodError> {
    if !(rank_tol.is_finite() && rank_tol > 0.0 && rank_tol < 1.0) {
        return Err(PodError::Truncation(format!(
            "the constraint rank tolerance {rank_tol} must lie in (0, 1)"
        )));
    }
    let m = cq_u.nrows();
    if m == 0 || cq_u.ncols() == 0 {
        return Ok(ConstraintReduction {
            singular_values: Vec::new(),
            basis: Mat::zeros(m, 0),
        });
    }
    let svd = cq_u.svd().map_err(|_| PodError::Svd {
        what: "constraint reduction".into(),
    })?;
    let s: Vec<f64> = svd.S().column_vector().iter().copied().collect();
    let largest = s.first().copied().unwrap_or(0.0);
    let l = s
        .iter()
        .take_while(|&&v| v > 0.0 && v > rank_tol * largest)
        .count();
    let u = svd.U();
    Ok(ConstraintReduction {
        singular_values: s,
        basis: Mat::from_fn(m, l, |i, j| u[(i, j)]),
    })
}

/// The constraints that the earlier reduction of Stadlmayr, Witteveen &
/// Steiner (2015), the paper's reference \[27\], removes: those whose row of
/// the projected Jacobian `C_q U` vanishes (norm at most `rank_tol` times
/// the largest singular value), i.e. constraints that act along directions
/// the subspace never moves in. They are a subset of what
/// [`reduce_constraints`] removes (a zero row is a zero singular value's
/// left singular vector); constraints whose directions tumble with the
/// motion never vanish, however redundant they are (the paper's Sect. 4.1).
///
/// # References
/// D. Stadlmayr, W. Witteveen, W. Steiner, *Reduction of physical and
/// constraint DOF of redundant formulated multibody systems*, J. Comput.
/// Nonlinear Dyn. 11(3), 031010 (2015); M. Stadlmayr, W. Witteveen,
/// W. Steiner (2017), Sects. 3.3-3.4.
pub fn vanishing_constraints(cq_u: MatRef<'_, f64>, rank_tol: f64) -> Vec<usize> {
    let largest = cq_u
        .singular_values()
        .ok()
        .and_then(|s| s.first().copied())
        .unwrap_or(0.0);
    (0..cq_u.nrows())
        .filter(|&i| {
            let row: f64 = (0..cq_u.ncols()).map(|j| cq_u[(i, j)].powi(2)).sum();
            row.sqrt() <= rank_tol * largest
        })
        .collect()
}
