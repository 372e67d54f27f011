//! What the pattern of `Lambda B - A` costs, known before any numeric
//! factorization: the fill of a symbolic Cholesky analysis decides whether
//! band solves iterate ([`iterates`]) and what the factors will hold
//! ([`lu_bytes_estimate`]).

use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};

use crate::model::condense;

/// Nonzeros a column of the Cholesky factor of the symmetrized pattern (AMD
/// order) must reach for [`Homological::solve_band`] to iterate rather
/// than factorize anew: below it (chains, small models) a factorization
/// costs a few triangular solves, and the iteration's tens of solves do
/// not pay.
pub(super) const NEAR_FILL: f64 = 40.0;

/// Whether a pattern factorizes dearly enough for [`Homological::solve_band`]
/// to iterate: the fill of the symbolic Cholesky factor of `P + P^T` in
/// approximate minimum degree order, per column, is at least [`NEAR_FILL`]
/// (deterministic, unlike a timing: the same model gives the same digits).
pub(super) fn iterates(p: faer::sparse::SymbolicSparseColMatRef<'_, usize>) -> bool {
    let n = p.nrows();
    let pattern = (0..n).flat_map(|j| p.row_idx_of_col(j).map(move |i| (i, j)));
    cholesky_entries(n, pattern).is_some_and(|len| len as f64 / n as f64 >= NEAR_FILL)
}

/// Entries of the symbolic Cholesky factor of `P + P^T` in approximate
/// minimum degree order, for the `n x n` pattern `P` of the `(row, column)`
/// pairs given; `None` for an empty or invalid pattern.
fn cholesky_entries(n: usize, pattern: impl Iterator<Item = (usize, usize)>) -> Option<usize> {
    use faer::sparse::linalg::cholesky::{
        factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering,
    };
    let upper = upper_of_symmetrized(n, pattern)?;
    factorize_symbolic_cholesky(
        upper.as_ref(),
        faer::Side::Upper,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .ok()
    .map(|chol| chol.len_val())
}

/// The upper triangle of `P + P^T` for the `n x n` pattern `P` of the
/// `(row, column)` pairs given (rows sorted, each entry once): a counting
/// pass and a fill by column, then a sort of each column, so that the
/// pattern of a finite-element pencil (millions of pairs, `A`'s and `B`'s
/// overlapping) is built without a global sort of triplets. `None` for an
/// empty pattern or an index out of range.
fn upper_of_symmetrized(
    n: usize,
    pattern: impl Iterator<Item = (usize, usize)>,
) -> Option<SymbolicSparseColMat<usize>> {
    if n == 0 {
        return None;
    }
    let pairs: Vec<(usize, usize)> = pattern.map(|(i, j)| (i.min(j), i.max(j))).collect();
    if pairs.iter().any(|&(_, j)| j >= n) {
        return None;
    }
    let mut start = vec![0usize; n + 1];
    for &(_, j) in &pairs {
        start[j + 1] += 1;
    }
    for j in 0..n {
        start[j + 1] += start[j];
    }
    let mut next = start.clone();
    let mut rows = vec![0usize; pairs.len()];
    for &(i, j) in &pairs {
        rows[next[j]] = i;
        next[j] += 1;
    }
    drop(pairs);
    // each column sorted and its repeats dropped, compacted in place
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0);
    let mut kept = 0;
    for j in 0..n {
        let (lo, hi) = (start[j], start[j + 1]);
        rows[lo..hi].sort_unstable();
        let mut last = usize::MAX;
        for k in lo..hi {
            let i = rows[k];
            if i != last {
                rows[kept] = i;
                kept += 1;
                last = i;
            }
        }
        col_ptr.push(kept);
    }
    rows.truncate(kept);
    Some(SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows))
}

/// Heap the sparse factorizations of `Lambda B - A` are estimated to hold
/// ([`lu_bytes_estimate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FactorBytes {
    /// One complex factorization of the pencil as the homological solves
    /// make it (of its condensation, where the velocities are eliminated:
    /// the real form's `L B L^T` where that is symmetric and dear).
    pub each: f64,
    /// One complex LU of the same matrix (what the sparse spectrum's
    /// shift-invert and inverse iteration factorize).
    pub lu: f64,
    /// Held once for all of them: the real LU of the mass matrix where the
    /// velocities are eliminated, 0 otherwise.
    pub shared: f64,
}

/// Heap the sparse LUs of `Lambda B - A` are estimated to hold, before any
/// factorization: [`LU_BYTES_PER_ENTRY`] per entry of the symbolic Cholesky
/// factor of the symmetrized pattern (AMD order) of the matrix factorized,
/// the pencil or, where a mechanical model's `velocities` are eliminated
/// (`Homological::new`), its condensation, with half as much for the real LU
/// of the mass matrix. `None` for an empty pattern.
pub fn lu_bytes_estimate(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    velocities: Option<std::ops::Range<usize>>,
) -> Option<FactorBytes> {
    let entries = |p: faer::sparse::SymbolicSparseColMatRef<'_, usize>| {
        let pattern = (0..p.ncols()).flat_map(move |j| p.row_idx_of_col(j).map(move |i| (i, j)));
        cholesky_entries(p.nrows(), pattern)
    };
    let n = a.nrows();
    let pattern = [a, b]
        .into_iter()
        .flat_map(|m| (0..m.ncols()).flat_map(move |j| m.row_idx_of_col(j).map(move |i| (i, j))));
    let whole = cholesky_entries(n, pattern)?;
    if let Some((s, m, symmetric)) = velocities.and_then(|v| condense::patterns(a, b, v)) {
        // the kernel `Homological` chooses: the real form's L B L^T where
        // the condensed pencil is symmetric and the factors dear
        let dear = whole as f64 / n as f64 >= NEAR_FILL;
        let per_entry = if symmetric && dear {
            SYM_BYTES_PER_ENTRY
        } else {
            LU_BYTES_PER_ENTRY
        };
        let condensed = entries(s.as_ref())? as f64;
        return Some(FactorBytes {
            each: per_entry * condensed,
            lu: LU_BYTES_PER_ENTRY * condensed,
            shared: 0.5 * LU_BYTES_PER_ENTRY * entries(m.as_ref())? as f64,
        });
    }
    Some(FactorBytes {
        each: LU_BYTES_PER_ENTRY * whole as f64,
        lu: LU_BYTES_PER_ENTRY * whole as f64,
        shared: 0.0,
    })
}

/// Heap of the `L B L^T` of a symmetric condensed pencil's real form
/// ([`ssm_kernel::sparse_sym`]) per entry of the symbolic Cholesky factor
/// of the condensed pattern (AMD order): the real form's factor holds four
/// reals for each of its entries. Measured with the counting allocator on
/// the simply supported plates: 64 and 34 bytes an entry at 16 x 16 and 90
/// x 90 elements (the small mesh's supernodes are padded the most); rounded
/// up, as [`LU_BYTES_PER_ENTRY`], so that the gate errs towards refusing.
pub const SYM_BYTES_PER_ENTRY: f64 = 80.0;

/// Heap of faer's complex supernodal LU (partial pivoting, COLAMD order)
/// per entry of the symbolic Cholesky factor of the symmetrized pattern in
/// AMD order. Measured with the counting allocator on the clamped plates:
/// 73, 70 and 95 bytes an entry at 16 x 16, 32 x 32 and 64 x 64 elements
/// (2,948 to 48,644 states; the spread is mostly the spare capacity of the
/// factor's growing arrays); the value is rounded up so that the gate errs
/// towards refusing (the suite's `plate` tests assert it bounds the measured
/// factors).
pub const LU_BYTES_PER_ENTRY: f64 = 128.0;

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::linalg::cholesky::{
        factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering,
    };
    use faer::sparse::{SparseColMat, Triplet};

    /// The Cholesky entries of the column-filled pattern against those of
    /// faer's own assembly of `P + P^T` from triplets (an independent
    /// construction), on an unsymmetric pattern with repeats.
    #[test]
    fn the_symmetrized_pattern_matches_faers_assembly() {
        let n = 300;
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as usize
        };
        let mut pairs: Vec<(usize, usize)> = (0..n).map(|i| (i, i)).collect();
        for _ in 0..2000 {
            let j = next() % n;
            let i = (j + next() % 9).min(n - 1);
            pairs.push((i, j));
            pairs.push((i, j));
        }
        let triplets: Vec<_> = pairs
            .iter()
            .flat_map(|&(i, j)| [Triplet::new(i, j, 1.0f64), Triplet::new(j, i, 1.0)])
            .collect();
        let sym = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).unwrap();
        let reference = factorize_symbolic_cholesky(
            sym.symbolic(),
            faer::Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .unwrap()
        .len_val();
        let upper = upper_of_symmetrized(n, pairs.iter().copied()).unwrap();
        let dup_free = (0..n).all(|j| {
            let r: Vec<usize> = upper.row_idx_of_col(j).collect();
            r.windows(2).all(|w| w[0] < w[1]) && r.iter().all(|&i| i <= j)
        });
        assert!(dup_free, "sorted, once each, upper");
        assert_eq!(cholesky_entries(n, pairs.iter().copied()), Some(reference));
        assert!(upper_of_symmetrized(n, [(0, n)].into_iter()).is_none());
        assert!(upper_of_symmetrized(0, std::iter::empty()).is_none());
    }
}
