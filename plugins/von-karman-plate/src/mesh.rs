//! A rectangular plate `[0, a] x [0, b]` of `nx x ny` equal [`Element`]s:
//! numbering of its free unknowns under the edge conditions, assembly of
//! mass, stiffness and the polynomial internal force into the global sparse
//! arrays of a model, point evaluation of `w` (point loads and outputs) and
//! the consistent load of a uniform pressure.

use ssm_api::{PolyVector, SparseMatrix};

use crate::element::{bending_dof, Element, Material, CORNERS, DOF_NAMES, NODE_DOFS};
use von_karman_beam::LocalTerm;

/// Transverse condition on the plate's four edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    /// `w = 0` and `dw/dn = 0`: `w`, `w_x`, `w_y`, `w_xy` removed on the edge.
    Clamped,
    /// `w = 0` (so the tangential slope vanishes too): `w` and the tangential
    /// derivative removed on the edge.
    SimplySupported,
}

/// In-plane condition on the plate's four edges.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InPlane {
    /// `u = v = 0` on the edges (immovable).
    Fixed,
    /// The normal displacement is zero, the tangential one free (`u = 0` on
    /// `x = 0, a`, `v = 0` on `y = 0, b`; the edges slide along themselves
    /// without shear).
    Sliding,
}

/// A rectangular plate mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mesh {
    /// Side along `x`.
    pub a: f64,
    /// Side along `y`.
    pub b: f64,
    /// Elements along `x` (at least 1).
    pub nx: usize,
    /// Elements along `y` (at least 1).
    pub ny: usize,
    /// Material and thickness.
    pub material: Material,
    /// Transverse edge condition.
    pub support: Support,
    /// In-plane edge condition.
    pub inplane: InPlane,
}

/// Global index of each nodal unknown (`None` where an edge condition removes
/// it); node `(i, j)` at `(i a / nx, j b / ny)` is entry `j (nx + 1) + i`.
#[derive(Clone, Debug, PartialEq)]
pub struct Numbering {
    /// Nodes along `x` (`nx + 1`).
    pub columns: usize,
    /// Unknowns of every node.
    pub nodes: Vec<[Option<usize>; NODE_DOFS]>,
}

impl Numbering {
    /// Number of unknowns numbered.
    pub fn len(&self) -> usize {
        self.nodes.iter().flatten().flatten().count()
    }

    /// True when no unknown is left.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `(global index, name)` of each unknown, named `n<i>_<j>_<unknown>`.
    pub fn names(&self) -> Vec<(usize, String)> {
        let mut out = Vec::with_capacity(self.len());
        for (k, dofs) in self.nodes.iter().enumerate() {
            let (i, j) = (k % self.columns, k / self.columns);
            for (d, idx) in dofs.iter().enumerate() {
                if let Some(g) = idx {
                    out.push((*g, format!("n{i}_{j}_{}", DOF_NAMES[d])));
                }
            }
        }
        out
    }

    /// Global index of unknown `dof` (see [`DOF_NAMES`]) of node `(i, j)`.
    pub fn get(&self, i: usize, j: usize, dof: usize) -> Option<usize> {
        self.nodes.get(j * self.columns + i).and_then(|d| d[dof])
    }

    /// True for an in-plane unknown (`u`, `v`).
    pub fn is_membrane(dof: usize) -> bool {
        dof < 2
    }
}

impl Mesh {
    /// The (common) element of the mesh.
    pub fn element(&self) -> Element {
        Element {
            hx: self.a / self.nx as f64,
            hy: self.b / self.ny as f64,
            material: self.material,
        }
    }

    /// Number of unknowns before the edge conditions.
    pub fn unknowns_before_supports(&self) -> usize {
        (self.nx + 1) * (self.ny + 1) * NODE_DOFS
    }

    /// True when the edge conditions remove unknown `dof` of node `(i, j)`.
    fn removes(&self, i: usize, j: usize, dof: usize) -> bool {
        let on_x_edge = i == 0 || i == self.nx; // an edge x = const
        let on_y_edge = j == 0 || j == self.ny; // an edge y = const
        let (w, wx, wy) = (2, 3, 4);
        let bending = |tangential: usize| match self.support {
            Support::Clamped => dof >= w,
            Support::SimplySupported => dof == w || dof == tangential,
        };
        let membrane = |normal: usize| match self.inplane {
            InPlane::Fixed => dof < 2,
            InPlane::Sliding => dof == normal,
        };
        (on_x_edge && (bending(wy) || membrane(0))) || (on_y_edge && (bending(wx) || membrane(1)))
    }

    /// Numbers the unknowns node by node, starting at `first`.
    pub fn number(&self, first: usize) -> Numbering {
        let mut next = first;
        let mut nodes = Vec::with_capacity((self.nx + 1) * (self.ny + 1));
        for j in 0..=self.ny {
            for i in 0..=self.nx {
                let mut dofs = [None; NODE_DOFS];
                for (d, slot) in dofs.iter_mut().enumerate() {
                    if !self.removes(i, j, d) {
                        *slot = Some(next);
                        next += 1;
                    }
                }
                nodes.push(dofs);
            }
        }
        Numbering {
            columns: self.nx + 1,
            nodes,
        }
    }

    /// Global index of each local unknown of element `(ex, ey)`.
    fn element_dofs(numbering: &Numbering, ex: usize, ey: usize) -> Vec<Option<usize>> {
        CORNERS
            .iter()
            .flat_map(|&(a, c)| numbering.nodes[(ey + c) * numbering.columns + ex + a])
            .collect()
    }

    /// Adds the mesh's mass and stiffness to `mass`, `stiffness` and its
    /// internal force `f2 + f3` to `force` (global indices of `numbering`;
    /// terms on removed unknowns vanish).
    pub fn assemble(
        &self,
        numbering: &Numbering,
        mass: &mut SparseMatrix,
        stiffness: &mut SparseMatrix,
        force: &mut PolyVector,
    ) {
        let element = self.element();
        let (me, ke) = (element.mass(), element.stiffness());
        let terms = element.polynomial_force();
        for ey in 0..self.ny {
            for ex in 0..self.nx {
                let g = Self::element_dofs(numbering, ex, ey);
                for (i, gi) in g.iter().enumerate() {
                    let Some(gi) = *gi else { continue };
                    for (j, gj) in g.iter().enumerate() {
                        if let Some(gj) = *gj {
                            if me[i][j] != 0.0 {
                                mass.push(gi, gj, me[i][j]);
                            }
                            if ke[i][j] != 0.0 {
                                stiffness.push(gi, gj, ke[i][j]);
                            }
                        }
                    }
                }
                LocalTerm::scatter(&terms, &g, force);
            }
        }
    }

    /// The element holding `(x, y)` and the point's coordinates in it.
    fn locate(&self, x: f64, y: f64) -> (usize, usize, f64, f64) {
        let px = (x / self.a).clamp(0.0, 1.0) * self.nx as f64;
        let py = (y / self.b).clamp(0.0, 1.0) * self.ny as f64;
        let ex = (px.floor() as usize).min(self.nx - 1);
        let ey = (py.floor() as usize).min(self.ny - 1);
        (ex, ey, px - ex as f64, py - ey as f64)
    }

    /// Weights `(global index, weight)` with `w(x, y) = sum weight q[index]`
    /// (the bending interpolation of the element holding the point); the same
    /// weights are the consistent nodal load of a unit transverse point force
    /// there.
    pub fn transverse_at(&self, numbering: &Numbering, x: f64, y: f64) -> Vec<(usize, f64)> {
        let (ex, ey, xi, eta) = self.locate(x, y);
        let b = self.element().bending_at(xi, eta);
        let g = Self::element_dofs(numbering, ex, ey);
        (0..16)
            .filter_map(|f| g[bending_dof(f)].map(|gi| (gi, b.n[f])))
            .filter(|&(_, w)| w.abs() > 1e-15)
            .collect()
    }

    /// The consistent nodal load of a uniform unit pressure on the whole
    /// plate, summed per global unknown.
    pub fn pressure_load(&self, numbering: &Numbering) -> Vec<(usize, f64)> {
        let fe = self.element().pressure_load();
        let mut load = vec![0.0; numbering.len()];
        let first = numbering.nodes.iter().flatten().flatten().min().copied();
        let first = first.unwrap_or(0);
        for ey in 0..self.ny {
            for ex in 0..self.nx {
                let g = Self::element_dofs(numbering, ex, ey);
                for (f, v) in fe.iter().enumerate() {
                    if let Some(gi) = g[bending_dof(f)] {
                        load[gi - first] += v;
                    }
                }
            }
        }
        load.into_iter()
            .enumerate()
            .filter(|&(_, v)| v != 0.0)
            .map(|(i, v)| (i + first, v))
            .collect()
    }
}
