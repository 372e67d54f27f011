//! The velocities of a mechanical pencil eliminated: `sigma B - A` solved
//! through a matrix of half the size.
//!
//! A mechanical model's first-order form in the canonical layout `z = (x,
//! x', mu, rest)` (velocities `V = n .. 2n`, the other states `K`) has
//!
//! ```text
//! B = [ B_KK    E M ]      A = [ A_KK  0 ]
//!     [ M E^T   0   ],         [ 0     M ],
//! ```
//!
//! with `M` the mass matrix and `E` the embedding of the `n` displacements
//! among `K` (the displacement rows: `B_KK` holds the damping, `A_KK` the
//! stiffness and the constraint Jacobians). The velocity rows of
//! `(sigma B - A) z = h` give `y = sigma E^T x - M^{-1} h_V`; substituted
//! into the other rows (the `M M^{-1}` cancels):
//!
//! `S(sigma) x = h_K + sigma E h_V`, `S(sigma) = sigma B_KK - A_KK + sigma^2
//! E M E^T`,
//!
//! which for an unconstrained model is the quadratic pencil `sigma^2 M +
//! sigma C + K` of the second-order equations. `S` has `N - n` rows, and a
//! sparse LU of it holds about a quarter of the entries of one of `sigma B -
//! A` (the first-order graph doubles every vertex of the second-order one),
//! for about an eighth of the work; `M` is factorized once, in real
//! arithmetic, for every `sigma`. The structure is recognized from the
//! matrices' values, entry by entry: a model that only resembles it (any
//! other entry in the blocks that must vanish, or velocity couplings unlike
//! `M`) keeps the solve of the whole pencil.
//!
//! # References
//! F. Tisseur, K. Meerbergen, *The quadratic eigenvalue problem*, SIAM Rev.
//! 43 (2001) 235-286, Sect. 3.4 (linearizations and their Schur
//! complements); S. Jain, G. Haller, Nonlinear Dyn. 107 (2022), Sect. 3.2
//! (the first-order form of second-order finite-element models).

use std::ops::Range;

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{
    SparseColMat, SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef, Triplet,
};
use faer::Mat;
use ssm_kernel::sparse_sym::SpdFactor;

use crate::C64;

/// The condensed pencil `S(sigma) = sigma B_KK - A_KK + sigma^2 E M E^T`
/// of a mechanical model and the factor of its mass matrix (see the module).
pub(crate) struct Condensed {
    /// Velocities `start .. start + n` of the full state (their displacements
    /// are `0 .. n`).
    start: usize,
    /// Displacements (and velocities).
    n: usize,
    /// Size of the full pencil.
    full: usize,
    /// Pattern of `S` (`full - n` square, columns sorted).
    pub(crate) symbolic: SymbolicSparseColMat<usize>,
    a_val: Vec<f64>,
    b_val: Vec<f64>,
    m_val: Vec<f64>,
    /// `M` itself, for the refinement of its solves.
    m: SparseColMat<usize, f64>,
    /// Factor of `D M D`, `D` = [`Condensed::mass_scale`].
    mass: MassFactor,
    /// Powers of two near `|M_ii|^(-1/2)`: a finite-element mass matrix
    /// couples displacements and slopes whose entries differ by the square
    /// of the element size, and its LU's solves are componentwise accurate
    /// only once the diagonal is brought near one.
    mass_scale: Vec<f64>,
    /// Heap the LU of `M` holds (0 where the allocator does not count).
    pub(crate) mass_bytes: usize,
}

/// The factor of the scaled mass matrix: Cholesky where it is symmetric
/// positive definite (in minimum-degree order it holds a fraction of an
/// LU's entries, and solves on one thread), an LU otherwise.
enum MassFactor {
    Cholesky(SpdFactor),
    Lu(Lu<usize, f64>),
}

impl MassFactor {
    fn new(scaled: &SparseColMat<usize, f64>) -> Option<Self> {
        if symmetric(scaled.symbolic(), &[scaled.val()]) {
            if let Some(f) = SpdFactor::factor(scaled.as_ref()) {
                return Some(Self::Cholesky(f));
            }
        }
        let sym = SymbolicLu::try_new(scaled.symbolic()).ok()?;
        Lu::try_new_with_symbolic(sym, scaled.as_ref())
            .ok()
            .map(Self::Lu)
    }

    fn solve_in_place(&self, x: faer::MatMut<'_, f64>) {
        match self {
            Self::Cholesky(f) => f.solve_in_place(x),
            Self::Lu(lu) => lu.solve_in_place(x),
        }
    }
}

/// The parts [`split`] finds.
struct Split {
    /// Pattern of `S`.
    symbolic: SymbolicSparseColMat<usize>,
    /// Values of `A_KK`, `B_KK` and `E M E^T` on it.
    vals: [Vec<f64>; 3],
    /// `M`.
    mass: SparseColMat<usize, f64>,
}

/// The index in `S` of full index `j` outside the velocities.
fn kept(j: usize, v: &Range<usize>) -> usize {
    if j < v.start {
        j
    } else {
        j - v.len()
    }
}

/// The pattern of `S` and its values split into the parts of `B_KK`,
/// `A_KK` and `E M E^T`, and `M` itself (`n x n`), when `(A, B)` has the
/// structure of the module with velocities `v` (their displacements `0 ..
/// n`); `None` otherwise.
fn split(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    v: &Range<usize>,
) -> Option<Split> {
    let (full, n) = (a.nrows(), v.len());
    if n == 0 || v.start < n || v.end > full || b.nrows() != full {
        return None;
    }
    let inv = |j: usize| v.contains(&j);
    // M = A_VV, and A's velocity rows and columns hold nothing else
    let mut mass = Vec::new();
    let mut s_entries: Vec<Vec<(usize, f64, f64, f64)>> = vec![Vec::new(); full - n];
    for j in 0..full {
        for (i, &x) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            match (inv(i), inv(j)) {
                (true, true) => mass.push((i - v.start, j - v.start, x)),
                (false, false) => s_entries[kept(j, v)].push((kept(i, v), x, 0.0, 0.0)),
                _ if x == 0.0 => {}
                _ => return None,
            }
        }
    }
    mass.sort_unstable_by_key(|&(i, j, _)| (j, i));
    // B_VV = 0, B_KV = E M (nothing in the other rows), B_VK = M E^T
    let mut upper = Vec::new();
    let mut lower = Vec::new();
    for j in 0..full {
        for (i, &x) in b.row_idx_of_col(j).zip(b.val_of_col(j)) {
            match (inv(i), inv(j)) {
                (true, true) if x != 0.0 => return None,
                (true, true) => {}
                (false, true) if i < n => upper.push((i, j - v.start, x)),
                (true, false) if j < n => lower.push((i - v.start, j, x)),
                (false, false) => s_entries[kept(j, v)].push((kept(i, v), 0.0, x, 0.0)),
                _ if x == 0.0 => {}
                _ => return None,
            }
        }
    }
    let scale = mass.iter().fold(0.0f64, |m, e| m.max(e.2.abs()));
    let copies = scale > 0.0
        && scale.is_finite()
        && same(&mut upper, &mass, scale)
        && same(&mut lower, &mass, scale);
    if !copies {
        return None;
    }
    for &(i, j, x) in &mass {
        s_entries[j].push((i, 0.0, 0.0, x));
    }
    let mut col_ptr = Vec::with_capacity(full - n + 1);
    let mut row_idx = Vec::new();
    let mut vals: [Vec<f64>; 3] = [Vec::new(), Vec::new(), Vec::new()];
    col_ptr.push(0);
    for mut col in s_entries {
        col.sort_unstable_by_key(|e| e.0);
        let mut last = usize::MAX;
        for (i, av, bv, mv) in col {
            if i == last {
                for (v, x) in vals.iter_mut().zip([av, bv, mv]) {
                    *v.last_mut().expect("an entry was pushed") += x;
                }
            } else {
                row_idx.push(i);
                for (v, x) in vals.iter_mut().zip([av, bv, mv]) {
                    v.push(x);
                }
                last = i;
            }
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic = SymbolicSparseColMat::new_checked(full - n, full - n, col_ptr, None, row_idx);
    let triplets: Vec<_> = mass
        .iter()
        .map(|&(i, j, x)| Triplet::new(i, j, x))
        .collect();
    let m = SparseColMat::try_new_from_triplets(n, n, &triplets).ok()?;
    Some(Split {
        symbolic,
        vals,
        mass: m,
    })
}

/// Whether the entries `e` (any order; sorted here) equal those of `m`
/// (sorted by column, then row) up to [`ROUNDING`] of `scale`, an entry
/// missing from either counting as zero: a plugin that assembles the mass
/// matrix from elements and copies it into three blocks may sum the
/// duplicates of each copy in another order.
fn same(e: &mut [(usize, usize, f64)], m: &[(usize, usize, f64)], scale: f64) -> bool {
    e.sort_unstable_by_key(|&(i, j, _)| (j, i));
    let tol = ROUNDING * scale;
    let (mut p, mut q) = (0, 0);
    while p < e.len() || q < m.len() {
        let key = |t: &(usize, usize, f64)| (t.1, t.0);
        let (x, y) = match (e.get(p), m.get(q)) {
            (Some(a), Some(b)) if key(a) == key(b) => {
                p += 1;
                q += 1;
                (a.2, b.2)
            }
            (Some(a), Some(b)) if key(a) < key(b) => {
                p += 1;
                (a.2, 0.0)
            }
            (Some(a), None) => {
                p += 1;
                (a.2, 0.0)
            }
            (_, Some(b)) => {
                q += 1;
                (0.0, b.2)
            }
            (None, None) => unreachable!("the loop's condition"),
        };
        if (x - y).abs() > tol || !x.is_finite() {
            return false;
        }
    }
    true
}

/// Relative difference (of the largest mass entry) up to which two copies
/// of the mass matrix count as the same: the rounding of sums of a few
/// hundred element contributions.
const ROUNDING: f64 = 1e-13;

impl Condensed {
    /// The condensation of `(A, B)` with velocities `v` (displacements `0 ..
    /// v.len()`), when the pencil has the structure of the module and its
    /// mass matrix factorizes; `None` otherwise (the whole pencil is then
    /// solved).
    pub(crate) fn detect(
        a: SparseColMatRef<'_, usize, f64>,
        b: SparseColMatRef<'_, usize, f64>,
        v: Range<usize>,
    ) -> Option<Self> {
        let Split {
            symbolic,
            vals: [a_val, b_val, m_val],
            mass: m,
        } = split(a, b, &v)?;
        let mass_scale: Vec<f64> = (0..v.len())
            .map(|j| {
                let d = m
                    .row_idx_of_col(j)
                    .zip(m.val_of_col(j))
                    .find(|&(i, _)| i == j)
                    .map_or(0.0, |(_, &x)| x.abs());
                if d > 0.0 && d.is_finite() {
                    (-(d.log2() / 2.0).round()).exp2()
                } else {
                    1.0
                }
            })
            .collect();
        let pattern = m.symbolic();
        let mut vals = m.val().to_vec();
        for j in 0..v.len() {
            for k in pattern.col_range(j) {
                vals[k] *= mass_scale[pattern.row_idx()[k]] * mass_scale[j];
            }
        }
        let scaled = SparseColMat::new(pattern.to_owned().ok()?, vals);
        let (mass, bytes) = ssm_kernel::heap::held(|| MassFactor::new(&scaled));
        let mass = mass?;
        let out = Self {
            start: v.start,
            n: v.len(),
            full: a.nrows(),
            symbolic,
            a_val,
            b_val,
            m_val,
            m,
            mass,
            mass_scale,
            mass_bytes: bytes.unwrap_or(0),
        };
        // a singular M factorizes without error but solves to non-finite
        // values
        let probe: Vec<C64> = (0..out.n)
            .map(|i| C64::new(1.0 + (i % 7) as f64, 0.0))
            .collect();
        out.mass_solve(&probe)
            .iter()
            .all(|x| x.re.is_finite() && x.im.is_finite())
            .then_some(out)
    }

    /// Whether `S(sigma)` is symmetric (`S^T = S`, complex symmetric at a
    /// complex `sigma`) for every `sigma`: its pattern is, and each of the
    /// stiffness, damping and mass parts to rounding, `|X_ij - X_ji| <=
    /// 1e-12 sqrt(m_i m_j)` with `m_i` the largest `|X_ik|` of row `i` (an
    /// assembled finite-element model's parts are sums of symmetric element
    /// matrices, equal across the diagonal to a few roundings).
    pub(crate) fn is_symmetric(&self) -> bool {
        symmetric(
            self.symbolic.as_ref(),
            &[&self.a_val, &self.b_val, &self.m_val],
        )
    }

    /// The values of `S(sigma)` on [`Condensed::symbolic`].
    pub(crate) fn values(&self, sigma: C64) -> Vec<C64> {
        let s2 = sigma * sigma;
        self.a_val
            .iter()
            .zip(&self.b_val)
            .zip(&self.m_val)
            .map(|((&a, &b), &m)| sigma * b - a + s2 * m)
            .collect()
    }

    /// The number `n` of displacements (and of velocities).
    pub(crate) fn displacements(&self) -> usize {
        self.n
    }

    /// The right-hand side `h_K + sigma E h_V` of the condensed system.
    pub(crate) fn reduce(&self, sigma: C64, h: &[C64]) -> Vec<C64> {
        let v = self.start..self.start + self.n;
        let mut out: Vec<C64> = h[..v.start].iter().chain(&h[v.end..]).copied().collect();
        for (o, &hv) in out.iter_mut().zip(&h[v]) {
            *o += sigma * hv;
        }
        out
    }

    /// The full solution `z = (x, sigma E^T x - M^{-1} h_V)` (velocities in
    /// place) from the condensed one `x`; `mass_part`, where given, is
    /// `M^{-1} h_V` (`n` values), known to the caller without a solve.
    pub(crate) fn expand(
        &self,
        sigma: C64,
        x: &[C64],
        h: &[C64],
        mass_part: Option<&[C64]>,
    ) -> Vec<C64> {
        let v = self.start..self.start + self.n;
        let hv = &h[v.clone()];
        let mut z = Vec::with_capacity(self.full);
        z.extend_from_slice(&x[..v.start]);
        z.extend(x[..self.n].iter().map(|&xi| sigma * xi));
        z.extend_from_slice(&x[v.start..]);
        if let Some(u) = mass_part.filter(|u| u.len() == self.n) {
            for (zv, u) in z[v].iter_mut().zip(u) {
                *zv -= u;
            }
        } else if hv.iter().any(|c| c.re != 0.0 || c.im != 0.0) {
            for (zv, u) in z[v].iter_mut().zip(self.mass_solve(hv)) {
                *zv -= u;
            }
        }
        z
    }

    /// `M^{-1} h` through the LU of the scaled `D M D`, with one step of
    /// iterative refinement (one step in working precision makes a solve
    /// componentwise backward stable: Skeel 1980).
    fn mass_solve(&self, h: &[C64]) -> Vec<C64> {
        let d = &self.mass_scale;
        let solve = |r: &[C64]| -> Vec<C64> {
            let mut x = Mat::<f64>::from_fn(self.n, 2, |i, k| {
                d[i] * if k == 0 { r[i].re } else { r[i].im }
            });
            self.mass.solve_in_place(x.as_mut());
            (0..self.n)
                .map(|i| C64::new(x[(i, 0)], x[(i, 1)]) * d[i])
                .collect()
        };
        let mut u = solve(h);
        let mut r = h.to_vec();
        for (j, uj) in u.iter().enumerate() {
            for (i, m) in self.m.row_idx_of_col(j).zip(self.m.val_of_col(j)) {
                r[i] -= uj * m;
            }
        }
        u.iter_mut().zip(solve(&r)).for_each(|(a, b)| *a += b);
        u
    }
}

/// Whether the pattern `p` is symmetric and each of `parts` (values on it)
/// is to rounding (see [`Condensed::is_symmetric`]).
fn symmetric(p: SymbolicSparseColMatRef<'_, usize>, parts: &[&[f64]]) -> bool {
    let n = p.nrows();
    // the position of (j, i) for each entry (i, j)
    let mut mirror = vec![usize::MAX; p.row_idx().len()];
    let mut next: Vec<usize> = (0..n).map(|j| p.col_range(j).start).collect();
    for j in 0..n {
        for k in p.col_range(j) {
            let i = p.row_idx()[k];
            // the entries (j, i') of column i in row order meet j in
            // column order: the transpose's walk
            let m = next[i];
            if m >= p.col_range(i).end || p.row_idx()[m] != j {
                return false;
            }
            mirror[k] = m;
            next[i] += 1;
        }
    }
    if (0..n).any(|i| next[i] != p.col_range(i).end) {
        return false;
    }
    parts.iter().all(|x| {
        let mut row = vec![0.0f64; n];
        for j in 0..n {
            for k in p.col_range(j) {
                let i = p.row_idx()[k];
                row[i] = row[i].max(x[k].abs());
            }
        }
        (0..n).all(|j| {
            p.col_range(j).all(|k| {
                let i = p.row_idx()[k];
                (x[k] - x[mirror[k]]).abs() <= 1e-12 * (row[i] * row[j]).sqrt()
            })
        })
    })
}

/// The patterns of the condensed pencil of `(A, B)` with velocities `v` and
/// of its mass matrix, when the structure holds; for the estimates made
/// before a run.
/// and whether the condensed pencil is symmetric ([`Condensed::is_symmetric`]).
pub(crate) fn patterns(
    a: SparseColMatRef<'_, usize, f64>,
    b: SparseColMatRef<'_, usize, f64>,
    v: Range<usize>,
) -> Option<(
    SymbolicSparseColMat<usize>,
    SymbolicSparseColMat<usize>,
    bool,
)> {
    let parts = split(a, b, &v)?;
    let [a_val, b_val, m_val] = &parts.vals;
    let sym = symmetric(parts.symbolic.as_ref(), &[a_val, b_val, m_val]);
    Some((parts.symbolic, parts.mass.symbolic().to_owned().ok()?, sym))
}

/// The shift-invert operator `(A - sigma B)^{-1} B` of a mechanical pencil
/// through `S(sigma)`, without a solve with the mass matrix: for `y = B z`,
/// `y_V = M z_x`, so the velocities of `w = (A - sigma B)^{-1} y` are `w_V =
/// sigma w_x + z_x`, and `S(sigma) w_K = -(y_K + sigma E y_V)` (the module's
/// elimination with `h = -y`). Its adjoint, `(A - sigma B)^{-H} B^T`, is the
/// same with `S(sigma)^H`, `B^T` and `conj(sigma)`, since `(B^T u)_V = M^T
/// u_x`. Krylov iterations and inverse iteration on the spectrum apply it
/// through an LU of `S`, half the size of `A - sigma B`.
pub(crate) struct ShiftInvert {
    /// The velocities (their displacements `0 .. v.len()`).
    v: Range<usize>,
    symbolic: SymbolicSparseColMat<usize>,
    /// Values of `A_KK`, `B_KK` and `E M E^T` on `symbolic`.
    vals: [Vec<f64>; 3],
}

impl ShiftInvert {
    /// The operator of `(A, B)` with velocities `v`, when the pencil has the
    /// structure of the module and its mass matrix factorizes to finite
    /// solves ([`Condensed::detect`]): with a singular `M` the first-order
    /// pencil is singular at every shift while `S` need not be, and the
    /// whole pencil's factorization then says so.
    pub(crate) fn detect(
        a: SparseColMatRef<'_, usize, f64>,
        b: SparseColMatRef<'_, usize, f64>,
        v: Range<usize>,
    ) -> Option<Self> {
        let c = Condensed::detect(a, b, v)?;
        Some(Self {
            v: c.start..c.start + c.n,
            symbolic: c.symbolic,
            vals: [c.a_val, c.b_val, c.m_val],
        })
    }

    /// Whether `S(sigma)` is symmetric at every `sigma` (as
    /// [`Condensed::is_symmetric`]).
    pub(crate) fn is_symmetric(&self) -> bool {
        let [a, b, m] = &self.vals;
        symmetric(self.symbolic.as_ref(), &[a, b, m])
    }

    /// `S(sigma)` for a real shift.
    pub(crate) fn real(&self, sigma: f64) -> SparseColMat<usize, f64> {
        let [a, b, m] = &self.vals;
        let vals = (0..a.len())
            .map(|k| sigma * b[k] - a[k] + sigma * sigma * m[k])
            .collect();
        SparseColMat::new(self.symbolic.clone(), vals)
    }

    /// `S(sigma)` for a complex shift.
    pub(crate) fn complex(&self, sigma: C64) -> SparseColMat<usize, C64> {
        let [a, b, m] = &self.vals;
        let vals = (0..a.len())
            .map(|k| sigma * b[k] - a[k] + sigma * sigma * m[k])
            .collect();
        SparseColMat::new(self.symbolic.clone(), vals)
    }

    /// The condensed right-hand side `-(y_K + s E y_V)` of `y = B z` (or
    /// `B^T u`, with `s = conj(sigma)`).
    pub(crate) fn rhs<T>(&self, y: &[T], s: T) -> Vec<T>
    where
        T: Copy + std::ops::Add<Output = T> + std::ops::Mul<Output = T> + std::ops::Neg<Output = T>,
    {
        let v = &self.v;
        let mut out: Vec<T> = y[..v.start]
            .iter()
            .chain(&y[v.end..])
            .map(|&x| -x)
            .collect();
        for (o, &yv) in out.iter_mut().zip(&y[v.clone()]) {
            *o = *o + -(s * yv);
        }
        out
    }

    /// `w` from the condensed solution `x` and the vector `z` the operator
    /// was applied to: `w_V = s x_disp + z_x`.
    pub(crate) fn expand<T>(&self, x: &[T], z: &[T], s: T) -> Vec<T>
    where
        T: Copy + std::ops::Add<Output = T> + std::ops::Mul<Output = T>,
    {
        let v = &self.v;
        let mut w = Vec::with_capacity(x.len() + v.len());
        w.extend_from_slice(&x[..v.start]);
        w.extend((0..v.len()).map(|k| s * x[k] + z[k]));
        w.extend_from_slice(&x[v.start..]);
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-dof mechanical system with a constraint: `B z' = A z` with `z =
    /// (x1, x2, v1, v2, mu)`.
    fn pencil(
        extra: Option<(usize, usize, f64)>,
    ) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
        pencil_with_mass(extra, [[2.0, 0.5], [0.5, 1.0]])
    }

    fn pencil_with_mass(
        extra: Option<(usize, usize, f64)>,
        m: [[f64; 2]; 2],
    ) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
        let k = [[3.0, -1.0], [-1.0, 2.0]];
        let c = [[0.1, 0.0], [0.0, 0.2]];
        let g = [1.0, -2.0];
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for i in 0..2 {
            for j in 0..2 {
                a.push(Triplet::new(i, j, -k[i][j]));
                a.push(Triplet::new(2 + i, 2 + j, m[i][j]));
                b.push(Triplet::new(i, j, c[i][j]));
                b.push(Triplet::new(i, 2 + j, m[i][j]));
                b.push(Triplet::new(2 + i, j, m[i][j]));
            }
            a.push(Triplet::new(4, i, g[i]));
            a.push(Triplet::new(i, 4, -g[i]));
        }
        if let Some((i, j, x)) = extra {
            b.push(Triplet::new(i, j, x));
        }
        (
            SparseColMat::try_new_from_triplets(5, 5, &a).unwrap(),
            SparseColMat::try_new_from_triplets(5, 5, &b).unwrap(),
        )
    }

    #[test]
    fn the_condensed_solve_solves_the_whole_pencil() {
        let (a, b) = pencil(None);
        let c = Condensed::detect(a.as_ref(), b.as_ref(), 2..4).expect("mechanical");
        let sigma = C64::new(-0.3, 1.7);
        let h: Vec<C64> = (0..5)
            .map(|i| C64::new(1.0 + i as f64, 0.5 - i as f64))
            .collect();
        // S x = reduce(h), through a dense solve of S
        let s = c.values(sigma);
        let ns = c.symbolic.nrows();
        let mut dense = Mat::<C64>::zeros(ns, ns);
        for j in 0..ns {
            for (p, i) in c.symbolic.row_idx_of_col(j).enumerate() {
                dense[(i, j)] = s[c.symbolic.col_ptr()[j] + p];
            }
        }
        let rhs = c.reduce(sigma, &h);
        let x = dense
            .partial_piv_lu()
            .solve(Mat::from_fn(ns, 1, |i, _| rhs[i]));
        let x: Vec<C64> = (0..ns).map(|i| x[(i, 0)]).collect();
        let z = c.expand(sigma, &x, &h, None);
        // the residual of (sigma B - A) z = h
        let (ad, bd) = (a.to_dense(), b.to_dense());
        for i in 0..5 {
            let r: C64 = (0..5)
                .map(|j| (sigma * bd[(i, j)] - ad[(i, j)]) * z[j])
                .sum::<C64>()
                - h[i];
            assert!(r.norm() < 1e-13, "row {i}: residual {r}");
        }
    }

    #[test]
    fn a_pencil_unlike_the_mechanical_one_is_not_condensed() {
        let (a, b) = pencil(Some((2, 3, 1e-3)));
        assert!(Condensed::detect(a.as_ref(), b.as_ref(), 2..4).is_none());
        let (a, b) = pencil(Some((4, 2, 1.0)));
        assert!(Condensed::detect(a.as_ref(), b.as_ref(), 2..4).is_none());
        let (a, b) = pencil(Some((0, 3, 0.1)));
        assert!(Condensed::detect(a.as_ref(), b.as_ref(), 2..4).is_none());
        let (a, b) = pencil(None);
        assert!(Condensed::detect(a.as_ref(), b.as_ref(), 1..3).is_none());
    }

    /// A dense solve of `m x = y`.
    fn dense_solve(m: &Mat<C64>, y: &[C64]) -> Vec<C64> {
        let x = m
            .partial_piv_lu()
            .solve(Mat::from_fn(y.len(), 1, |i, _| y[i]));
        (0..y.len()).map(|i| x[(i, 0)]).collect()
    }

    /// The condensed shift-invert and its adjoint against dense solves of the
    /// whole pencil: `(A - sigma B)^{-1} B z` and `(A - sigma B)^{-H} B^T u`
    /// to 1e-13, at a real and a complex shift.
    #[test]
    fn the_condensed_shift_invert_is_the_whole_pencils() {
        let (a, b) = pencil(None);
        let op = ShiftInvert::detect(a.as_ref(), b.as_ref(), 2..4).expect("mechanical");
        let (ad, bd) = (a.to_dense(), b.to_dense());
        let z: Vec<C64> = (0..5)
            .map(|i| C64::new(0.3 + i as f64, 1.0 - 0.7 * i as f64))
            .collect();
        for sigma in [C64::new(0.7, 0.0), C64::new(-0.2, 1.3)] {
            let s = op.complex(sigma);
            let ns = s.nrows();
            let mut sd = Mat::<C64>::zeros(ns, ns);
            for j in 0..ns {
                for (i, v) in s.row_idx_of_col(j).zip(s.val_of_col(j)) {
                    sd[(i, j)] = *v;
                }
            }
            let whole =
                Mat::<C64>::from_fn(5, 5, |i, j| C64::new(ad[(i, j)], 0.0) - sigma * bd[(i, j)]);
            for adjoint in [false, true] {
                let (y, shift, mat, lhs) = if adjoint {
                    let y: Vec<C64> = (0..5)
                        .map(|j| (0..5).map(|i| bd[(i, j)] * z[i]).sum())
                        .collect();
                    (
                        y,
                        sigma.conj(),
                        sd.adjoint().to_owned(),
                        whole.adjoint().to_owned(),
                    )
                } else {
                    let y: Vec<C64> = (0..5)
                        .map(|i| (0..5).map(|j| bd[(i, j)] * z[j]).sum())
                        .collect();
                    (y, sigma, sd.clone(), whole.clone())
                };
                let x = dense_solve(&mat, &op.rhs(&y, shift));
                let w = op.expand(&x, &z, shift);
                let reference = dense_solve(&lhs, &y);
                for (p, q) in w.iter().zip(&reference) {
                    assert!(
                        (p - q).norm() < 1e-13 * q.norm().max(1.0),
                        "{p} against {q}"
                    );
                }
            }
        }
        // the real shift's matrix is the complex one's
        let (sr, sc) = (op.real(0.7), op.complex(C64::new(0.7, 0.0)));
        for (x, y) in sr.val().iter().zip(sc.val()) {
            assert_eq!(C64::new(*x, 0.0), *y);
        }
    }

    /// A singular mass matrix makes the first-order pencil singular at every
    /// shift (its velocity null vectors), while `S` may not be: such a
    /// pencil is not condensed, so that its factorization reports it.
    #[test]
    fn a_singular_mass_matrix_is_not_condensed() {
        let (a, b) = pencil_with_mass(None, [[1.0, 1.0], [1.0, 1.0]]);
        assert!(ShiftInvert::detect(a.as_ref(), b.as_ref(), 2..4).is_none());
        let (a, b) = pencil_with_mass(None, [[1.0, 1.0 - 1e-9], [1.0 - 1e-9, 1.0]]);
        assert!(ShiftInvert::detect(a.as_ref(), b.as_ref(), 2..4).is_some());
    }
}
