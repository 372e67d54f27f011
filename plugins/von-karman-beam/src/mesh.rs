//! A straight beam of equal [`Element`]s: numbering of its free unknowns,
//! assembly of mass, stiffness and the polynomial internal force into the
//! global sparse arrays of a model, and point evaluation of the transverse
//! displacement (for point loads and outputs).

use ssm_api::{PolyVector, SparseMatrix};

use crate::element::{hermite, Element, LocalTerm, Section};

/// Boundary condition at a beam end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    /// No condition: `u`, `w`, `phi` are unknowns.
    Free,
    /// `u = w = phi = 0`: the three unknowns are removed.
    Clamped,
    /// `u = w = 0` (axially restrained hinge): only `phi` remains.
    Pinned,
}

impl Support {
    fn removes(self, dof: usize) -> bool {
        match self {
            Support::Free => false,
            Support::Clamped => true,
            Support::Pinned => dof < 2,
        }
    }
}

/// Names of the three nodal unknowns.
pub const DOF_NAMES: [&str; 3] = ["u", "w", "phi"];

/// A straight beam from `x = 0` (start) to `x = length` (end), cut into
/// `elements` equal elements.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mesh {
    /// Beam length.
    pub length: f64,
    /// Section and material.
    pub section: Section,
    /// Number of elements (at least 1).
    pub elements: usize,
    /// Condition at `x = 0`.
    pub start: Support,
    /// Condition at `x = length`.
    pub end: Support,
}

/// Global indices of the unknowns `(u, w, phi)` of every node (`None` where a
/// support removes it); node `k` sits at `x = k length / elements`.
#[derive(Clone, Debug, PartialEq)]
pub struct Numbering {
    /// One entry per node, `elements + 1` in all.
    pub nodes: Vec<[Option<usize>; 3]>,
}

impl Numbering {
    /// Number of unknowns numbered.
    pub fn len(&self) -> usize {
        self.nodes.iter().flatten().flatten().count()
    }

    /// True when no unknown is left (every node supported).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `(global index, name)` of each unknown, named `<prefix><node>_<u|w|phi>`.
    pub fn names(&self, prefix: &str) -> Vec<(usize, String)> {
        let mut out = Vec::with_capacity(self.len());
        for (node, dofs) in self.nodes.iter().enumerate() {
            for (d, idx) in dofs.iter().enumerate() {
                if let Some(i) = idx {
                    out.push((*i, format!("{prefix}{node}_{}", DOF_NAMES[d])));
                }
            }
        }
        out
    }

    /// Global index of unknown `dof` (0 = u, 1 = w, 2 = phi) of `node`.
    pub fn get(&self, node: usize, dof: usize) -> Option<usize> {
        self.nodes.get(node).and_then(|d| d[dof])
    }
}

impl Mesh {
    /// The (common) element of the mesh.
    pub fn element(&self) -> Element {
        Element {
            length: self.length / self.elements as f64,
            section: self.section,
        }
    }

    /// Numbers the unknowns node by node (`u, w, phi`), starting at `first`.
    pub fn number(&self, first: usize) -> Numbering {
        let last = self.elements;
        let mut next = first;
        let nodes = (0..=last)
            .map(|k| {
                let mut dofs = [None; 3];
                for (d, slot) in dofs.iter_mut().enumerate() {
                    let removed =
                        (k == 0 && self.start.removes(d)) || (k == last && self.end.removes(d));
                    if !removed {
                        *slot = Some(next);
                        next += 1;
                    }
                }
                dofs
            })
            .collect();
        Numbering { nodes }
    }

    /// Global index of each local unknown of element `e` (nodes `e`, `e + 1`).
    fn element_dofs(numbering: &Numbering, e: usize) -> [Option<usize>; 6] {
        let (a, b) = (numbering.nodes[e], numbering.nodes[e + 1]);
        [a[0], a[1], a[2], b[0], b[1], b[2]]
    }

    /// Adds the mesh's mass and stiffness to `mass`, `stiffness` and its
    /// internal force `f2 + f3` to `force` (components and variables are the
    /// global indices of `numbering`; terms on removed unknowns vanish).
    pub fn assemble(
        &self,
        numbering: &Numbering,
        mass: &mut SparseMatrix,
        stiffness: &mut SparseMatrix,
        force: &mut PolyVector,
    ) {
        let element = self.element();
        let (me, ke) = (element.mass(), element.stiffness());
        let mut terms: Vec<LocalTerm> = element.quadratic_force();
        terms.extend(element.cubic_force());
        for e in 0..self.elements {
            let g = Self::element_dofs(numbering, e);
            for i in 0..6 {
                let Some(gi) = g[i] else { continue };
                for j in 0..6 {
                    if let Some(gj) = g[j] {
                        mass.push(gi, gj, me[i][j]);
                        stiffness.push(gi, gj, ke[i][j]);
                    }
                }
            }
            LocalTerm::scatter(&terms, &g, force);
        }
    }

    /// Weights `(global index, weight)` with `w(s length) = sum weight q[index]`
    /// for `s` in `[0, 1]` (Hermite interpolation in the element holding the
    /// point); the same weights are the consistent nodal load of a unit
    /// transverse point force there.
    pub fn transverse_at(&self, numbering: &Numbering, s: f64) -> Vec<(usize, f64)> {
        let pos = s.clamp(0.0, 1.0) * self.elements as f64;
        let e = (pos.floor() as usize).min(self.elements - 1);
        let xi = pos - e as f64;
        let n = hermite(xi, self.length / self.elements as f64);
        let g = Self::element_dofs(numbering, e);
        [1, 2, 4, 5]
            .iter()
            .zip(n)
            .filter_map(|(&local, w)| g[local].map(|gi| (gi, w)))
            .filter(|&(_, w)| w.abs() > 1e-15)
            .collect()
    }
}
