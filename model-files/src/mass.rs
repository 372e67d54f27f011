//! Whether a matrix can be a mass matrix: checked on the entries as a
//! folder is read, so the message names the file.

use ssm_api::{SparseMatrix, SYMMETRY_TOLERANCE};

use crate::mtx::summed;

/// What makes `M` singular or not a mass matrix, checked on its entries: a
/// degree of freedom whose row or column is empty (no inertia), a diagonal
/// entry that is not positive, or an entry pair `M(i, j) != M(j, i)` (beyond
/// [`SYMMETRY_TOLERANCE`] of the largest entry: the kinetic energy
/// `x'^T M x' / 2` has a symmetric `M`; the builder checks the same, here
/// the message names the file). Positive definiteness is not
/// checked beyond the diagonal (a constrained model's `M` may be singular).
/// `None` when no such defect shows.
pub fn mass_defect(m: &SparseMatrix, constrained: bool) -> Option<String> {
    let n = m.nrows as usize;
    let hint = if constrained {
        "a massless degree of freedom that a constraint fixes belongs out of the model \
         (eliminate it); give every other one mass"
    } else {
        "the model has no constraints (no G.mtx), so M must be non-singular: give every \
         degree of freedom mass, or write the relation that fixes a massless one as a \
         constraint in G.mtx"
    };
    if m.entries.len() < n {
        // checked before any O(n) memory: a declared size far beyond the entries
        return Some(format!(
            "M is singular: it has {} entries for {n} degrees of freedom, so at least {} \
             have no mass; each massless degree of freedom turns a pair of the pencil's \
             eigenvalues infinite (a mode without inertia); {hint}",
            m.entries.len(),
            n - m.entries.len()
        ));
    }
    let mut row = vec![false; n];
    let mut col = vec![false; n];
    let mut diag = vec![0.0; n];
    for (i, j, v) in summed(m).into_iter().filter(|e| e.2 != 0.0) {
        row[i] = true;
        col[j] = true;
        if i == j {
            diag[i] = v;
        }
    }
    if let Some(i) = (0..n).find(|&i| !row[i] || !col[i]) {
        return Some(format!(
            "M is singular: degree of freedom {} has no mass (its row or column is empty); \
             each massless degree of freedom turns a pair of the pencil's eigenvalues \
             infinite (a mode without inertia), and the model is no longer an ODE; {hint}",
            i + 1
        ));
    }
    if let Some(i) = (0..n).find(|&i| diag[i] <= 0.0) {
        return Some(format!(
            "M({0}, {0}) = {1}: a mass matrix must be positive definite, so its diagonal \
             must be positive; {hint}",
            i + 1,
            diag[i]
        ));
    }
    asymmetry(m)
}

/// The message naming the first entry pair of `m` that is not symmetric
/// ([`SparseMatrix::asymmetry`] at [`SYMMETRY_TOLERANCE`]).
fn asymmetry(m: &SparseMatrix) -> Option<String> {
    let (i, j, v, w) = m.asymmetry(SYMMETRY_TOLERANCE)?;
    Some(format!(
        "M({}, {}) = {v} but M({}, {}) = {w}: a mass matrix must be symmetric (the \
         kinetic energy x'^T M x' / 2 holds only its symmetric part); the entries \
         differ by {:.3e}, above {SYMMETRY_TOLERANCE:e} of the largest entry; write both \
         entries equal (or declare the file symmetric and give the lower triangle)",
        i + 1,
        j + 1,
        j + 1,
        i + 1,
        (v - w).abs()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matrix(entries: &[(usize, usize, f64)]) -> SparseMatrix {
        let mut m = SparseMatrix::zeros(2, 2);
        for &(i, j, v) in entries {
            m.push(i, j, v);
        }
        m
    }

    /// An asymmetry at rounding level (1e-14 of the largest entry) is
    /// accepted; one of 1e-8 is refused naming both entries.
    #[test]
    fn mass_asymmetry_beyond_rounding_is_refused() {
        let base = [(0, 0, 2.0), (1, 1, 1.0), (0, 1, 0.3)];
        let with = |v: f64| {
            let mut e = base.to_vec();
            e.push((1, 0, v));
            matrix(&e)
        };
        assert_eq!(mass_defect(&with(0.3 + 2e-14), false), None);
        let e = mass_defect(&with(0.3 + 2e-8), false).expect("refused");
        assert!(e.contains("M(2, 1) = 0.30000002 but M(1, 2) = 0.3"), "{e}");
        assert!(e.contains("must be symmetric"), "{e}");
    }
}
