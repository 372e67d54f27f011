//! The factorizations of `sigma B - A` the homological solves go through:
//! an LU (of the equilibrated matrix where band solves run), or the real
//! form's `L B L^T` of a symmetric condensed pencil.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::Lu;
use ssm_kernel::sparse_sym::ComplexSymFactor;

use crate::C64;

/// A sparse LU of `M = sigma B - A`, or of `D_r M D_c` with the diagonal
/// equilibration `scale = (D_r, D_c)` (each row, then each column, scaled
/// to a largest entry between 1/2 and 1 by a power of two, so that scaling
/// rounds nothing): where band solves run (finite-element models whose rows
/// differ in scale by orders of magnitude) the pivots of the equilibrated
/// matrix keep an unrefined solve's componentwise backward error small, and
/// a refined solve needs fewer sweeps.
///
/// # References
/// N. J. Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed.,
/// SIAM (2002), Sect. 9.8 (scaling and equilibration); E. Anderson et al.,
/// *LAPACK Users' Guide*, 3rd ed., SIAM (1999) (`xGEEQU`).
///
/// Where the velocities of a mechanical model are eliminated
/// ([`condense`](crate::model::condense)), the LU is of the condensed `S(sigma)`, half the size.
pub(in crate::ssm) struct Factor {
    pub(super) lu: Kernel,
    pub(super) scale: Option<(Vec<f64>, Vec<f64>)>,
    /// The value factorized (what [`Condensed`](crate::model::condense::Condensed) expands with).
    pub(super) sigma: C64,
    /// Heap the LU holds (0 where the allocator does not count).
    pub(super) bytes: usize,
}

/// The factorization of a [`Factor`]: an LU, or where the condensed pencil
/// is symmetric and its factors are dear, the `L B L^T` of its real form
/// ([`ssm_kernel::sparse_sym`]: a few times fewer entries, fewer flops).
pub(super) enum Kernel {
    Lu(Box<Lu<usize, C64>>),
    Symmetric(ComplexSymFactor),
}

/// The power of two nearest below `1 / m` (`1` for a zero or non-finite
/// `m`).
fn inverse_power_of_two(m: f64) -> f64 {
    if m > 0.0 && m.is_finite() {
        (-m.log2().ceil()).exp2()
    } else {
        1.0
    }
}

/// Scales `vals` (the values of `pattern`) to `D_r M D_c` and returns `(D_r,
/// D_c)` (see [`Factor`]).
pub(super) fn equilibrate_in_place(
    pattern: faer::sparse::SymbolicSparseColMatRef<'_, usize>,
    vals: &mut [C64],
) -> (Vec<f64>, Vec<f64>) {
    let n = pattern.nrows();
    let mut row_max = vec![0.0f64; n];
    for j in 0..pattern.ncols() {
        for k in pattern.col_range(j) {
            let i = pattern.row_idx()[k];
            row_max[i] = row_max[i].max(vals[k].norm());
        }
    }
    let row: Vec<f64> = row_max.into_iter().map(inverse_power_of_two).collect();
    let mut col = vec![1.0f64; pattern.ncols()];
    for (j, cj) in col.iter_mut().enumerate() {
        let mut m = 0.0f64;
        for k in pattern.col_range(j) {
            vals[k] *= row[pattern.row_idx()[k]];
            m = m.max(vals[k].norm());
        }
        *cj = inverse_power_of_two(m);
        for k in pattern.col_range(j) {
            vals[k] *= *cj;
        }
    }
    (row, col)
}

/// `x` overwritten by the factorized matrix's inverse applied to it.
pub(super) fn kernel_solve(lu: &Kernel, mut x: Vec<C64>) -> Vec<C64> {
    match lu {
        Kernel::Lu(lu) => {
            let n = x.len();
            let mut m = faer::MatMut::from_column_major_slice_mut(&mut x, n, 1);
            lu.solve_in_place(m.as_mut());
        }
        Kernel::Symmetric(f) => f.solve_in_place(&mut x),
    }
    x
}

/// Scales the values `vals` of the symmetric `pattern` to `D S D` and
/// returns `D`: powers of two near `m_i^(-1/2)`, `m_i` the largest entry of
/// row `i`, so that `|(D S D)_ij| <= 1` and scaling rounds nothing (the
/// symmetric counterpart of [`equilibrate_in_place`]).
pub(super) fn symmetric_equilibrate(
    pattern: faer::sparse::SymbolicSparseColMatRef<'_, usize>,
    vals: &mut [C64],
) -> Vec<f64> {
    let n = pattern.nrows();
    let mut row_max = vec![0.0f64; n];
    for j in 0..pattern.ncols() {
        for k in pattern.col_range(j) {
            let i = pattern.row_idx()[k];
            row_max[i] = row_max[i].max(vals[k].norm());
        }
    }
    let d: Vec<f64> = row_max
        .into_iter()
        .map(|m| inverse_power_of_two(m.sqrt()))
        .collect();
    for j in 0..pattern.ncols() {
        for k in pattern.col_range(j) {
            vals[k] *= d[pattern.row_idx()[k]] * d[j];
        }
    }
    d
}
