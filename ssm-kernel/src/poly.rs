//! Multi-indices and truncated power series in the reduced coordinates, and the
//! order-by-order composition `F(W(p))` of a sparse polynomial `F` with a
//! power series `W`.
//!
//! Reduced coordinates are ordered `p = (p1, conj p1, ..., pm, conj pm)`; a
//! multi-index `k` in `nvar = 2m` variables stands for the monomial
//! `p^k = prod_i p_i^{k_i}`.
//!
//! The composition is computed the way the parametrization method needs it:
//! at order `k`, the order-`k` coefficients of every monomial of `F` evaluated
//! on `W` are formed from coefficients of orders `< k` only (`F` starts at
//! degree 2), so `W` can be solved order by order. Each monomial of `F` is a
//! node of a trie, `P = Q * z_v`, and its coefficient at multi-index `k` is the
//! Cauchy product `[P]_k = sum_{a + b = k} [Q]_a [z_v]_b` over the precomputed
//! splits of `k`. The cost is the number of trie nodes (at most the number of
//! factors in the terms of `F`) times the number of splits; it never depends on
//! `N^degree`.
//!
//! # References
//! S. Jain, G. Haller, *How to compute invariant manifolds and their reduced
//! dynamics in high-dimensional finite element models*, Nonlinear Dyn. 107
//! (2022), Sect. 3 (order-by-order composition of multivariate polynomials).

use ssm_api::PolyVector;

use crate::C64;

/// All multi-indices in `nvar` variables of total order `0..=max_order`, graded
/// (order 0 first, then order 1, ...), reverse-lexicographic within an order.
#[derive(Debug, Clone)]
pub struct MultiIndexSet {
    nvar: usize,
    max_order: usize,
    exps: Vec<u16>,
    order_start: Vec<usize>,
    /// `C(n, m)` at `n * (nvar + 1) + m`, for `n <= max_order + nvar`: the
    /// counts that rank a multi-index ([`Self::index`]).
    choose: Vec<usize>,
    conj: Vec<usize>,
    split_start: Vec<usize>,
    splits: Vec<(u32, u32)>,
    lower: Vec<u32>,
}

impl MultiIndexSet {
    /// Enumerates the multi-indices and their splits. `nvar` must be even
    /// (conjugate pairs) for [`Self::conj`] to be meaningful.
    pub fn new(nvar: usize, max_order: usize) -> Self {
        Self::build(nvar, max_order, false).expect("not cancellable")
    }

    /// [`Self::new`] that stops when the work running on this thread is asked
    /// to ([`crate::cancel`]): `None` then. The split table of a high order
    /// over several pairs takes seconds to enumerate (at O(31) over two
    /// pairs, a sixth of the SSM), so a long computation builds its set with
    /// this one.
    pub fn cancellable(nvar: usize, max_order: usize) -> Option<Self> {
        Self::build(nvar, max_order, true)
    }

    fn build(nvar: usize, max_order: usize, cancellable: bool) -> Option<Self> {
        let mut exps: Vec<u16> = Vec::new();
        let mut order_start = vec![0];
        let mut cur = vec![0u16; nvar];
        for k in 0..=max_order {
            compositions(k, nvar, &mut cur, 0, &mut exps);
            order_start.push(exps.len() / nvar.max(1));
        }
        if nvar == 0 {
            order_start = vec![0, 1];
        }
        let cols = nvar + 1;
        let rows = max_order + nvar + 1;
        let mut choose = vec![0usize; rows * cols];
        for n in 0..rows {
            choose[n * cols] = 1;
            for m in 1..cols.min(n + 1) {
                let above = if m < n { choose[(n - 1) * cols + m] } else { 0 };
                choose[n * cols + m] = choose[(n - 1) * cols + m - 1].saturating_add(above);
            }
        }
        let mut set = Self {
            nvar,
            max_order,
            exps,
            order_start,
            choose,
            conj: Vec::new(),
            split_start: Vec::new(),
            splits: Vec::new(),
            lower: Vec::new(),
        };
        let len = set.order_start[set.order_start.len() - 1];
        let mut e = vec![0u16; nvar];
        set.conj = (0..len)
            .map(|i| {
                e.copy_from_slice(set.exponents(i));
                for pair in e.chunks_mut(2) {
                    if pair.len() == 2 {
                        pair.swap(0, 1);
                    }
                }
                set.rank(&e)
            })
            .collect();
        set.build_splits(cancellable)?;
        set.build_lower(cancellable)?;
        Some(set)
    }

    /// Whether a cancellable build should stop at multi-index `idx` (asked
    /// every 256 indices).
    fn stop(cancellable: bool, idx: usize) -> bool {
        cancellable && idx.is_multiple_of(256) && crate::cancel::requested()
    }

    fn build_splits(&mut self, cancellable: bool) -> Option<()> {
        let nvar = self.nvar;
        let mut split_start = Vec::with_capacity(self.len() + 1);
        // sized exactly (the pairs `0 <= a <= m` less the two trivial ones),
        // so the table, the largest array of an SSM, never grows by doubling
        // past what the cost gate counted
        let count: usize = (0..self.len())
            .map(|idx| {
                let m = self.exponents(idx);
                if m.iter().map(|&x| x as usize).sum::<usize>() < 2 {
                    0
                } else {
                    m.iter().map(|&x| x as usize + 1).product::<usize>() - 2
                }
            })
            .sum();
        let mut splits = Vec::with_capacity(count);
        let mut a = vec![0u16; nvar];
        let mut b = vec![0u16; nvar];
        for idx in 0..self.len() {
            if Self::stop(cancellable, idx) {
                return None;
            }
            split_start.push(splits.len());
            let m = self.exponents(idx).to_vec();
            let k: usize = m.iter().map(|&x| x as usize).sum();
            if k < 2 {
                continue;
            }
            // mixed-radix counter over 0 <= a <= m componentwise
            a.iter_mut().for_each(|x| *x = 0);
            loop {
                let ka: usize = a.iter().map(|&x| x as usize).sum();
                if ka >= 1 && ka < k {
                    for v in 0..nvar {
                        b[v] = m[v] - a[v];
                    }
                    splits.push((self.rank(&a) as u32, self.rank(&b) as u32));
                }
                let mut v = 0;
                while v < nvar {
                    if a[v] < m[v] {
                        a[v] += 1;
                        break;
                    }
                    a[v] = 0;
                    v += 1;
                }
                if v == nvar {
                    break;
                }
            }
        }
        split_start.push(splits.len());
        self.split_start = split_start;
        self.splits = splits;
        Some(())
    }

    fn build_lower(&mut self, cancellable: bool) -> Option<()> {
        let mut lower = vec![u32::MAX; self.len() * self.nvar];
        let mut e = vec![0u16; self.nvar];
        for idx in 0..self.len() {
            if Self::stop(cancellable, idx) {
                return None;
            }
            for v in 0..self.nvar {
                e.copy_from_slice(self.exponents(idx));
                if e[v] > 0 {
                    e[v] -= 1;
                    lower[idx * self.nvar + v] = self.rank(&e) as u32;
                }
            }
        }
        self.lower = lower;
        Some(())
    }

    /// Index of `k - e_v` (`None` when `k_v = 0`).
    pub fn lower(&self, idx: usize, v: usize) -> Option<usize> {
        let l = self.lower[idx * self.nvar + v];
        (l != u32::MAX).then_some(l as usize)
    }

    /// Number of variables.
    pub fn nvar(&self) -> usize {
        self.nvar
    }

    /// Highest order enumerated.
    pub fn max_order(&self) -> usize {
        self.max_order
    }

    /// Number of multi-indices.
    pub fn len(&self) -> usize {
        self.conj.len()
    }

    /// True when the set is empty (never: order 0 is always there).
    pub fn is_empty(&self) -> bool {
        self.conj.is_empty()
    }

    /// Exponents of multi-index `idx`.
    pub fn exponents(&self, idx: usize) -> &[u16] {
        &self.exps[idx * self.nvar..(idx + 1) * self.nvar]
    }

    /// Total order `|k|` of multi-index `idx`.
    pub fn order(&self, idx: usize) -> usize {
        // order_start is short; a linear scan is cheaper than storing orders
        self.order_start.partition_point(|&s| s <= idx) - 1
    }

    /// Indices of the multi-indices of order `k`.
    pub fn of_order(&self, k: usize) -> std::ops::Range<usize> {
        self.order_start[k]..self.order_start[k + 1]
    }

    /// Index of the multi-index with exponents `e`, if enumerated.
    pub fn index(&self, e: &[u16]) -> Option<usize> {
        let order: usize = e.iter().map(|&x| x as usize).sum();
        (e.len() == self.nvar && order <= self.max_order).then(|| self.rank(e))
    }

    /// The index of `e` (of `nvar` entries, order at most `max_order`) by
    /// counting: graded, then descending in the first exponent, the second,
    /// ...; the multi-indices of order `r` in `v` variables whose first
    /// exponent exceeds `x` number `C(r - x - 1 + v - 1, v - 1)` (the
    /// compositions of `r - x - 1` into `v` parts, by the hockey-stick
    /// identity).
    fn rank(&self, e: &[u16]) -> usize {
        let nvar = self.nvar;
        let Some(last) = nvar.checked_sub(1) else {
            return 0;
        };
        let mut r: usize = e.iter().map(|&x| x as usize).sum();
        let mut idx = self.order_start[r];
        for (pos, &x) in e[..last].iter().enumerate() {
            let x = x as usize;
            let parts = nvar - pos;
            if x < r {
                idx += self.choose[(r - x - 1 + parts - 1) * (nvar + 1) + parts - 1];
            }
            r -= x;
        }
        idx
    }

    /// Index of the conjugate multi-index (exponents of `p_i` and `conj p_i` swapped).
    pub fn conj(&self, idx: usize) -> usize {
        self.conj[idx]
    }

    /// All splits `(a, b)` with `a + b = k`, `|a| >= 1`, `|b| >= 1`.
    pub fn splits(&self, idx: usize) -> &[(u32, u32)] {
        &self.splits[self.split_start[idx]..self.split_start[idx + 1]]
    }

    /// `p^k` at the point `p`.
    pub fn monomial(&self, idx: usize, p: &[C64]) -> C64 {
        let mut v = C64::new(1.0, 0.0);
        for (x, &e) in p.iter().zip(self.exponents(idx)) {
            if e > 0 {
                v *= x.powu(e as u32);
            }
        }
        v
    }

    /// `d(p^k)/dp . r = sum_v k_v p^{k - e_v} r_v`: the monomial `idx`
    /// differentiated along the reduced vector field `r`, from the monomials
    /// `mono` of `p` (the multi-index `k` of `[DW(p) R(p)]`).
    pub fn derivative_along(&self, idx: usize, mono: &[C64], r: &[C64]) -> C64 {
        let mut s = C64::new(0.0, 0.0);
        for (v, &ev) in self.exponents(idx).iter().enumerate() {
            if ev > 0 {
                let low = self.lower(idx, v).expect("k_v > 0");
                s += mono[low] * r[v] * f64::from(ev);
            }
        }
        s
    }

    /// All monomials `p^k` up to order `max` at the point `p`, by the recursion
    /// `p^k = p^{k - e_v} p_v` (one multiplication each).
    pub fn monomials(&self, p: &[C64], max: usize) -> Vec<C64> {
        let end = self.order_start[max.min(self.max_order) + 1];
        let mut out = vec![C64::new(0.0, 0.0); end];
        out[0] = C64::new(1.0, 0.0);
        for idx in 1..end {
            let v = self
                .exponents(idx)
                .iter()
                .position(|&x| x > 0)
                .expect("order >= 1");
            out[idx] = out[self.lower(idx, v).expect("k_v > 0")] * p[v];
        }
        out
    }
}

fn compositions(k: usize, nvar: usize, cur: &mut Vec<u16>, pos: usize, out: &mut Vec<u16>) {
    if nvar == 0 {
        return;
    }
    if pos == nvar - 1 {
        cur[pos] = k as u16;
        out.extend_from_slice(cur);
        return;
    }
    for e in (0..=k).rev() {
        cur[pos] = e as u16;
        compositions(k - e, nvar, cur, pos + 1, out);
    }
    cur[pos] = 0;
}

/// One node of the monomial trie: `P = parent * z_var` (or `z_var` at a root).
#[derive(Debug, Clone, Copy)]
struct Node {
    parent: Option<usize>,
    var: usize,
    /// Root node of `var` (itself for a root).
    leaf: usize,
}

/// The monomials of a sparse polynomial vector `F(z)`, composed with a power
/// series `z = W(p)` order by order.
#[derive(Debug, Clone)]
pub struct Composition {
    nodes: Vec<Node>,
    /// `values[node][idx]`: coefficient of `p^idx` in the monomial evaluated on `W`.
    values: Vec<Vec<C64>>,
    /// Root node of each variable that occurs in `F`.
    leaves: Vec<(usize, usize)>,
    /// `(eq, coeff, node)` per term of `F`.
    terms: Vec<(usize, f64, usize)>,
}

/// The trie of the monomials of `f` (a node per distinct prefix of a
/// monomial's sorted factors, powers repeated, and a root per variable, the
/// factor its children multiply by) and the `(eq, coeff, node)` of each
/// term.
#[allow(clippy::type_complexity)]
fn trie(f: &PolyVector) -> (Vec<Node>, Vec<(usize, f64, usize)>) {
    let mut nodes: Vec<Node> = Vec::new();
    // the root of each variable, and each node's children (few: the
    // variables that follow it in some monomial), found without hashing
    let mut roots = vec![usize::MAX; f.n_vars as usize];
    let mut children: Vec<Vec<(usize, usize)>> = Vec::new();
    let mut terms = Vec::with_capacity(f.terms.len());
    let mut vars: Vec<usize> = Vec::new();
    for t in f.terms.iter() {
        vars.clear();
        for vp in t.factors.iter() {
            vars.extend(std::iter::repeat_n(vp.var as usize, vp.power as usize));
        }
        vars.sort_unstable();
        let mut node: Option<usize> = None;
        for &v in &vars {
            if roots[v] == usize::MAX {
                roots[v] = nodes.len();
                nodes.push(Node {
                    parent: None,
                    var: v,
                    leaf: nodes.len(),
                });
                children.push(Vec::new());
            }
            let leaf = roots[v];
            let next = match node {
                None => leaf,
                Some(parent) => match children[parent].iter().find(|c| c.0 == v) {
                    Some(&(_, c)) => c,
                    None => {
                        let id = nodes.len();
                        nodes.push(Node {
                            parent: Some(parent),
                            var: v,
                            leaf,
                        });
                        children.push(Vec::new());
                        children[parent].push((v, id));
                        id
                    }
                },
            };
            node = Some(next);
        }
        if let Some(node) = node {
            terms.push((t.eq as usize, t.coeff, node));
        }
    }
    (nodes, terms)
}

impl Composition {
    /// Builds the trie of the monomials of `f`, with series storage for
    /// `n_index` multi-indices.
    pub fn new(f: &PolyVector, n_index: usize) -> Self {
        let (nodes, terms) = trie(f);
        let leaves = nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.parent.is_none())
            .map(|(i, n)| (i, n.var))
            .collect();
        let values = vec![vec![C64::new(0.0, 0.0); n_index]; nodes.len()];
        Self {
            nodes,
            values,
            leaves,
            terms,
        }
    }

    /// The trie nodes [`Composition::new`] makes for `f` (each holds one
    /// series of the multi-indices), without their series: what a cost
    /// gate reads before the composition is allocated.
    pub fn nodes_of(f: &PolyVector) -> usize {
        trie(f).0.len()
    }

    /// Number of distinct monomials (trie nodes).
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Copies the coefficients of `W` at the multi-indices `range` into the
    /// leaves (`w[idx]` is the state vector of coefficient `idx`).
    pub fn load_leaves(&mut self, w: &[Vec<C64>], range: std::ops::Range<usize>) {
        for &(node, var) in &self.leaves {
            let vals = &mut self.values[node];
            for idx in range.clone() {
                vals[idx] = w[idx][var];
            }
        }
    }

    /// Computes the coefficients of every non-leaf monomial at the multi-indices
    /// of order `k`. The leaves must hold all orders `< k`. Work that is
    /// cancelled ([`crate::cancel`]) stops between two monomials, leaving the
    /// order incomplete: the caller asks [`crate::cancel::requested`] next.
    pub fn advance(&mut self, set: &MultiIndexSet, k: usize) {
        for node in 0..self.nodes.len() {
            if crate::cancel::requested() {
                return;
            }
            let Node { parent, leaf, .. } = self.nodes[node];
            let Some(q) = parent else { continue };
            for idx in set.of_order(k) {
                let mut s = C64::new(0.0, 0.0);
                for &(a, b) in set.splits(idx) {
                    let qa = self.values[q][a as usize];
                    if qa.re != 0.0 || qa.im != 0.0 {
                        s += qa * self.values[leaf][b as usize];
                    }
                }
                self.values[node][idx] = s;
            }
        }
    }

    /// Adds `[F(W)]_idx` into `out` (a state vector).
    pub fn accumulate(&self, idx: usize, out: &mut [C64]) {
        for &(eq, coeff, node) in &self.terms {
            let v = self.values[node][idx];
            if v.re != 0.0 || v.im != 0.0 {
                out[eq] += v * coeff;
            }
        }
    }
}

/// Evaluates a sparse polynomial vector at a real or complex point.
pub fn eval_poly(f: &PolyVector, z: &[C64], out: &mut [C64]) {
    for t in f.terms.iter() {
        let mut v = C64::new(t.coeff, 0.0);
        for vp in t.factors.iter() {
            let x = z[vp.var as usize];
            // the powers of mechanical nonlinearities (1 to 3) multiplied
            // out as `powu`'s squaring does (the same bits, no call)
            v *= match vp.power {
                1 => x,
                2 => x * x,
                3 => x * (x * x),
                p => x.powu(p),
            };
        }
        out[t.eq as usize] += v;
    }
}

/// [`eval_poly`] at several points at once: `outs[k] += f(zs[k])` with one
/// pass over the terms for all of them (the points' values side by side,
/// so that a term's factors are read once), the same bits as a call per
/// point. Every point has `f`'s variables, every output its equations.
///
/// # Panics
/// If `outs` and `zs` differ in length.
pub fn eval_poly_many(f: &PolyVector, zs: &[&[C64]], outs: &mut [Vec<C64>]) {
    assert_eq!(zs.len(), outs.len(), "eval_poly_many: one output per point");
    let k = zs.len();
    let (Some(first), Some(out0)) = (zs.first(), outs.first()) else {
        return;
    };
    let (n, m) = (first.len(), out0.len());
    let zero = C64::new(0.0, 0.0);
    // point-minor: z[var * k + point], o[eq * k + point]
    let mut z = vec![zero; n * k];
    for (p, zp) in zs.iter().enumerate() {
        for (v, x) in zp.iter().enumerate() {
            z[v * k + p] = *x;
        }
    }
    let mut o = vec![zero; m * k];
    for (p, op) in outs.iter().enumerate() {
        for (e, x) in op.iter().enumerate() {
            o[e * k + p] = *x;
        }
    }
    let mut v = vec![zero; k];
    for t in f.terms.iter() {
        v.iter_mut().for_each(|x| *x = C64::new(t.coeff, 0.0));
        for vp in t.factors.iter() {
            let at = vp.var as usize * k;
            let xs = &z[at..at + k];
            // as eval_poly multiplies them out
            match vp.power {
                1 => v.iter_mut().zip(xs).for_each(|(a, &x)| *a *= x),
                2 => v.iter_mut().zip(xs).for_each(|(a, &x)| *a *= x * x),
                3 => v.iter_mut().zip(xs).for_each(|(a, &x)| *a *= x * (x * x)),
                pw => v.iter_mut().zip(xs).for_each(|(a, &x)| *a *= x.powu(pw)),
            }
        }
        let at = t.eq as usize * k;
        for (a, b) in o[at..at + k].iter_mut().zip(&v) {
            *a += b;
        }
    }
    for (p, op) in outs.iter_mut().enumerate() {
        for (e, x) in op.iter_mut().enumerate() {
            *x = o[e * k + p];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_composition_has_a_node_per_prefix_of_a_sorted_monomial_and_per_variable() {
        use ssm_api::{PolyTerm, VarPower};
        use std::collections::BTreeSet;
        let monomials: [&[(u32, u32)]; 6] = [
            &[(1, 1), (0, 2)],
            &[(0, 1), (1, 1)],
            &[(0, 3)],
            &[(2, 1), (1, 1)],
            &[(0, 1), (1, 1)],
            &[(3, 2)],
        ];
        let f = PolyVector {
            n_eq: 2,
            n_vars: 4,
            terms: monomials
                .iter()
                .enumerate()
                .map(|(k, m)| PolyTerm {
                    eq: (k % 2) as u32,
                    coeff: 1.0 + k as f64,
                    factors: m
                        .iter()
                        .map(|&(var, power)| VarPower { var, power })
                        .collect::<Vec<_>>()
                        .into(),
                })
                .collect::<Vec<_>>()
                .into(),
        };
        // every prefix of each monomial's variables, sorted with repeats,
        // and every variable alone (the factor a node multiplies by)
        let mut prefixes = BTreeSet::new();
        for m in monomials {
            let mut vars: Vec<u32> = m
                .iter()
                .flat_map(|&(v, p)| std::iter::repeat_n(v, p as usize))
                .collect();
            vars.sort_unstable();
            for k in 1..=vars.len() {
                prefixes.insert(vars[..k].to_vec());
            }
            prefixes.extend(vars.iter().map(|&v| vec![v]));
        }
        assert_eq!(prefixes.len(), 10);
        assert_eq!(Composition::nodes_of(&f), prefixes.len());
        assert_eq!(Composition::new(&f, 3).n_nodes(), prefixes.len());
    }

    #[test]
    fn many_points_at_once_give_the_bits_of_one_at_a_time() {
        use ssm_api::{PolyTerm, VarPower};
        let term = |eq: u32, coeff: f64, f: &[(u32, u32)]| PolyTerm {
            eq,
            coeff,
            factors: f
                .iter()
                .map(|&(var, power)| VarPower { var, power })
                .collect::<Vec<_>>()
                .into(),
        };
        let f = PolyVector {
            n_eq: 3,
            n_vars: 3,
            terms: vec![
                term(0, 1.5, &[(0, 2), (1, 1)]),
                term(2, -0.7, &[(2, 3)]),
                term(1, 2.0, &[(0, 1), (1, 4)]),
                term(0, 0.3, &[]),
                term(2, 1e-3, &[(1, 5), (2, 1)]),
            ]
            .into(),
        };
        let points: Vec<Vec<C64>> = (0..5)
            .map(|p| {
                (0..3)
                    .map(|v| C64::new(0.3 * p as f64 - 0.1 * v as f64, 0.7 - 0.2 * v as f64))
                    .collect()
            })
            .collect();
        let refs: Vec<&[C64]> = points.iter().map(Vec::as_slice).collect();
        let mut many = vec![vec![C64::new(0.25, -1.0); 3]; 5];
        eval_poly_many(&f, &refs, &mut many);
        for (z, got) in points.iter().zip(&many) {
            let mut one = vec![C64::new(0.25, -1.0); 3];
            eval_poly(&f, z, &mut one);
            assert_eq!(&one, got);
        }
    }

    fn binom(n: usize, k: usize) -> usize {
        (0..k).fold(1, |acc, i| acc * (n - i) / (i + 1))
    }

    #[test]
    fn a_cancellable_set_stops_when_asked_and_equals_the_plain_one_otherwise() {
        let plain = MultiIndexSet::new(4, 9);
        let built = MultiIndexSet::cancellable(4, 9).expect("no flag: not interrupted");
        assert_eq!(built.exps, plain.exps);
        assert_eq!(built.splits, plain.splits);
        assert_eq!(built.lower, plain.lower);
        let flag = crate::cancel::Flag::new();
        flag.raise();
        crate::cancel::within(Some(&flag), || {
            assert!(MultiIndexSet::cancellable(4, 9).is_none());
            assert_eq!(MultiIndexSet::new(4, 9).splits, plain.splits);
        });
    }

    #[test]
    fn counts_match_binomials() {
        for (nvar, order) in [(2, 35), (4, 13), (6, 5)] {
            let s = MultiIndexSet::new(nvar, order);
            assert_eq!(s.len(), binom(order + nvar, nvar));
            for k in 0..=order {
                assert_eq!(s.of_order(k).len(), binom(k + nvar - 1, nvar - 1));
                for idx in s.of_order(k) {
                    assert_eq!(s.order(idx), k);
                    assert_eq!(s.conj(s.conj(idx)), idx);
                    // the counting rank is the enumeration's position
                    assert_eq!(s.index(s.exponents(idx)), Some(idx));
                }
            }
            let mut beyond = vec![0u16; nvar];
            beyond[nvar - 1] = order as u16 + 1;
            assert_eq!(s.index(&beyond), None);
            assert_eq!(s.index(&beyond[1..]), None);
        }
        let empty = MultiIndexSet::new(0, 3);
        assert_eq!(empty.index(&[]), Some(0));
    }

    #[test]
    fn splits_cover_all_factorizations() {
        let s = MultiIndexSet::new(4, 6);
        for idx in s.of_order(5) {
            let m = s.exponents(idx);
            let expected: usize = m.iter().map(|&e| e as usize + 1).product::<usize>() - 2;
            assert_eq!(s.splits(idx).len(), expected);
            for &(a, b) in s.splits(idx) {
                let sum: Vec<u16> = s
                    .exponents(a as usize)
                    .iter()
                    .zip(s.exponents(b as usize))
                    .map(|(x, y)| x + y)
                    .collect();
                assert_eq!(sum, m);
            }
        }
    }

    /// Reference: direct evaluation. `F(W(p))` from the order-by-order
    /// composition must equal `F` evaluated at `W(p)` up to the truncation
    /// order, which we check with a polynomial `W` of degree 1 (then `F(W)` is
    /// a polynomial of degree `deg F` and the truncated series is exact).
    #[test]
    fn composition_matches_direct_evaluation() {
        let mut f = PolyVector::zeros(2, 3);
        f.push(0, 1.5, &[(0, 2), (1, 1)]);
        f.push(1, -0.7, &[(2, 3)]);
        f.push(0, 0.3, &[(1, 2)]);
        f.push(1, 2.0, &[(0, 1), (1, 1), (2, 2)]);
        let set = MultiIndexSet::new(2, 4);
        let n = 3;
        let mut w = vec![vec![C64::new(0.0, 0.0); n]; set.len()];
        let lin = [
            [C64::new(0.3, 0.1), C64::new(-0.2, 0.5), C64::new(0.7, -0.4)],
            [
                C64::new(0.3, -0.1),
                C64::new(-0.2, -0.5),
                C64::new(0.7, 0.4),
            ],
        ];
        for (i, idx) in set.of_order(1).enumerate() {
            w[idx] = lin[i].to_vec();
        }
        let mut comp = Composition::new(&f, set.len());
        let mut series = vec![vec![C64::new(0.0, 0.0); 2]; set.len()];
        for k in 2..=4 {
            comp.load_leaves(&w, set.of_order(k - 1));
            comp.advance(&set, k);
            for idx in set.of_order(k) {
                comp.accumulate(idx, &mut series[idx]);
            }
        }
        let p = [C64::new(0.4, 0.3), C64::new(0.4, -0.3)];
        let z: Vec<C64> = (0..n)
            .map(|s| lin[0][s] * p[0] + lin[1][s] * p[1])
            .collect();
        let mut direct = vec![C64::new(0.0, 0.0); 2];
        eval_poly(&f, &z, &mut direct);
        let mono = set.monomials(&p, 4);
        for eq in 0..2 {
            let s: C64 = (0..set.len()).map(|i| series[i][eq] * mono[i]).sum();
            assert!((s - direct[eq]).norm() < 1e-14, "{s} vs {}", direct[eq]);
        }
    }
}
