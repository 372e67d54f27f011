//! # ssm-model-files: mechanical models as files
//!
//! A model folder holds the mechanical system
//! `M x'' + C x' + K x + f(x) + G(x)^T mu = eps fext cos(Omega t)`,
//! `g(x) = G0 x + g_nl(x) = 0` (Li, Jain & Haller 2023, eq. 1) as files that
//! plain numpy and `scipy.io.mmwrite` can write:
//!
//! | file | holds | required |
//! |---|---|---|
//! | `M.mtx`, `K.mtx` | mass and stiffness, `n x n` Matrix Market | yes |
//! | `C.mtx` | damping `n x n` (or Rayleigh damping from parameters) | no |
//! | `G.mtx` | linear constraint Jacobian `G0`, `n_c x n` | no |
//! | `f2.coo`, `f3.coo` | `f_i += v x_j x_k` (`i j k v`), `f_i += v x_j x_k x_l` (`i j k l v`) | no |
//! | `g2.coo`, `g3.coo` | the same for `g_nl` (`i` the constraint) | no |
//! | `fext.mtx` | load shape, `n x 1` (array or coordinate) | no |
//! | `outputs.csv` | `name,dof[,weight]` rows naming outputs | no |
//!
//! Indices are 1-based, `%` starts a comment, duplicates are summed. Every
//! read error names its file and line ([`FileError`]). This crate reads and
//! writes the format; a folder becomes a mechanical system, and a model a
//! folder, in `ssm-plugin-kit` (beside the mechanical builder it inverts).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023) 8881-8911, eqs. (1)-(2).

#![warn(missing_docs)]

mod coo;
mod error;
pub mod input;
mod lines;
mod mass;
mod mtx;
mod outputs;

use std::path::Path;

use ssm_api::{PolyVector, SparseMatrix};

pub use coo::{read_tensor, write_tensor};
pub use error::{ExportError, FileError};
pub use lines::Progress;
pub use mass::mass_defect;
pub use mtx::{read_matrix, summed, write_matrix, write_vector};
pub use outputs::{read_outputs, valid_name, write_outputs, NamedOutput};

/// Names of the files of a model folder.
pub mod names {
    /// Mass matrix.
    pub const M: &str = "M.mtx";
    /// Stiffness matrix.
    pub const K: &str = "K.mtx";
    /// Damping matrix.
    pub const C: &str = "C.mtx";
    /// Linear constraint Jacobian `G0`.
    pub const G: &str = "G.mtx";
    /// Quadratic internal force.
    pub const F2: &str = "f2.coo";
    /// Cubic internal force.
    pub const F3: &str = "f3.coo";
    /// Quadratic constraint terms.
    pub const G2: &str = "g2.coo";
    /// Cubic constraint terms.
    pub const G3: &str = "g3.coo";
    /// Load shape.
    pub const FEXT: &str = "fext.mtx";
    /// Named outputs.
    pub const OUTPUTS: &str = "outputs.csv";
    /// Every file a folder may hold.
    pub const ALL: [&str; 10] = [M, K, C, G, F2, F3, G2, G3, FEXT, OUTPUTS];
}

/// The contents of a model folder.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelFiles {
    /// Mass matrix `M` (`n x n`).
    pub mass: SparseMatrix,
    /// Stiffness matrix `K` (`n x n`).
    pub stiffness: SparseMatrix,
    /// Damping matrix `C` (`n x n`), when the folder has one.
    pub damping: Option<SparseMatrix>,
    /// Linear constraint Jacobian `G0` (`n_c x n`), when constrained.
    pub constraint_jacobian: Option<SparseMatrix>,
    /// Internal force `f(x)`: `n` equations in the `n` displacements, degrees 2 and 3.
    pub internal_force: PolyVector,
    /// Nonlinear constraint terms `g_nl(x)`: `n_c` equations in the `n`
    /// displacements, degrees 2 and 3.
    pub constraint_terms: PolyVector,
    /// Load shape `fext` (`n` values), when forced.
    pub load: Option<Vec<f64>>,
    /// Named outputs.
    pub outputs: Vec<NamedOutput>,
}

impl ModelFiles {
    /// Number of displacements `n`.
    pub fn n_dof(&self) -> usize {
        self.mass.nrows as usize
    }

    /// Number of constraints `n_c`.
    pub fn n_constraints(&self) -> usize {
        self.constraint_jacobian
            .as_ref()
            .map_or(0, |g| g.nrows as usize)
    }

    /// Reads the model folder `dir` (and checks that `M` gives every degree
    /// of freedom mass, [`mass_defect`]); `progress` is told the bytes read.
    pub fn read(dir: &Path, progress: &mut Progress<'_>) -> Result<Self, FileError> {
        let path = |name: &str| dir.join(name);
        let required = |name: &str, what: &'static str| {
            let p = path(name);
            if p.exists() {
                Ok(p)
            } else {
                Err(FileError::Missing { file: p, what })
            }
        };
        let optional = |name: &str| Some(path(name)).filter(|p| p.exists());
        let mass = read_matrix(&required(names::M, "the mass matrix M")?, progress)?;
        let n = mass.nrows as usize;
        // the first-order model has 2 n + n_c <= 3 n states, indexed by u32
        if n == 0 || mass.ncols as usize != n || n > (u32::MAX / 3) as usize {
            return Err(FileError::Content {
                file: path(names::M),
                message: format!(
                    "M is {}x{}; it must be square with 1 to {} rows",
                    mass.nrows,
                    mass.ncols,
                    u32::MAX / 3
                ),
            });
        }
        let square = |name: &str, m: SparseMatrix| {
            if (m.nrows as usize, m.ncols as usize) == (n, n) {
                Ok(m)
            } else {
                Err(FileError::Content {
                    file: path(name),
                    message: format!("is {}x{}, but M.mtx is {n}x{n}", m.nrows, m.ncols),
                })
            }
        };
        // before any O(n) memory: a size line far beyond the entries read is
        // refused here
        if let Some(message) = mass_defect(&mass, optional(names::G).is_some()) {
            return Err(FileError::Content {
                file: path(names::M),
                message,
            });
        }
        let k_path = required(names::K, "the stiffness matrix K")?;
        let stiffness = square(names::K, read_matrix(&k_path, progress)?)?;
        let damping = match optional(names::C) {
            Some(p) => Some(square(names::C, read_matrix(&p, progress)?)?),
            None => None,
        };
        let constraint_jacobian = match optional(names::G) {
            Some(p) => {
                let g = read_matrix(&p, progress)?;
                if g.ncols as usize != n || g.nrows == 0 || g.nrows as usize > n {
                    return Err(FileError::Content {
                        file: p,
                        message: format!(
                            "is {}x{}; G0 must have 1 <= n_c <= n rows and n = {n} columns (M.mtx is {n}x{n})",
                            g.nrows, g.ncols
                        ),
                    });
                }
                let mut has_linear = vec![false; g.nrows as usize];
                for (j, _, v) in g.iter() {
                    has_linear[j] |= v != 0.0;
                }
                if let Some(j) = has_linear.iter().position(|h| !h) {
                    return Err(FileError::Content {
                        file: p,
                        message: format!(
                            "row {} is empty: constraint {} has no linear part, so G0 is rank \
                             deficient (a redundant or degenerate constraint)",
                            j + 1,
                            j + 1
                        ),
                    });
                }
                Some(g)
            }
            None => None,
        };
        let nc = constraint_jacobian.as_ref().map_or(0, |g| g.nrows as usize);
        let mut internal_force = PolyVector::zeros(n, n);
        let mut constraint_terms = PolyVector::zeros(nc, n);
        for (name, degree) in [(names::F2, 2), (names::F3, 3)] {
            if let Some(p) = optional(name) {
                read_tensor(&p, degree, n, &mut internal_force, progress)?;
            }
        }
        for (name, degree) in [(names::G2, 2), (names::G3, 3)] {
            if let Some(p) = optional(name) {
                if nc == 0 {
                    return Err(FileError::Content {
                        file: p,
                        message: "nonlinear constraint terms need the linear part G.mtx \
                                  (a constraint without a linear term is degenerate)"
                            .to_owned(),
                    });
                }
                read_tensor(&p, degree, n, &mut constraint_terms, progress)?;
            }
        }
        let load = match optional(names::FEXT) {
            Some(p) => {
                let f = read_matrix(&p, progress)?;
                if (f.nrows as usize, f.ncols) != (n, 1) {
                    return Err(FileError::Content {
                        file: p,
                        message: format!(
                            "is {}x{}; the load shape must be {n}x1 (M.mtx is {n}x{n})",
                            f.nrows, f.ncols
                        ),
                    });
                }
                let mut v = vec![0.0; n];
                for (i, _, x) in f.iter() {
                    v[i] += x;
                }
                Some(v)
            }
            None => None,
        };
        let outputs = match optional(names::OUTPUTS) {
            Some(p) => read_outputs(&p, n, progress)?,
            None => Vec::new(),
        };
        Ok(Self {
            mass,
            stiffness,
            damping,
            constraint_jacobian,
            internal_force,
            constraint_terms,
            load,
            outputs,
        })
    }

    /// The folder's files as `(name, contents)`, only those the model needs
    /// (written to memory; the caller places them, e.g. as one atomic set).
    pub fn encode(&self, source: &str) -> std::io::Result<Vec<(&'static str, Vec<u8>)>> {
        // one comment line whatever the source's name holds
        let comment: String = format!("written by ssm-engine export from {source}")
            .chars()
            .map(|c| if c.is_control() { ' ' } else { c })
            .collect();
        let mut files = Vec::new();
        let mut file = |name: &'static str, body: &dyn Fn(&mut Vec<u8>) -> std::io::Result<()>| {
            let mut w = Vec::new();
            body(&mut w)?;
            files.push((name, w));
            Ok::<(), std::io::Error>(())
        };
        file(names::M, &|w| write_matrix(w, &self.mass, &comment))?;
        file(names::K, &|w| write_matrix(w, &self.stiffness, &comment))?;
        if let Some(c) = &self.damping {
            file(names::C, &|w| write_matrix(w, c, &comment))?;
        }
        if let Some(g) = &self.constraint_jacobian {
            file(names::G, &|w| write_matrix(w, g, &comment))?;
        }
        for (name, poly, degree) in [
            (names::F2, &self.internal_force, 2),
            (names::F3, &self.internal_force, 3),
            (names::G2, &self.constraint_terms, 2),
            (names::G3, &self.constraint_terms, 3),
        ] {
            if poly.terms.iter().any(|t| t.degree() == degree) {
                file(name, &|w| write_tensor(w, poly, degree, &comment))?;
            }
        }
        if let Some(f) = &self.load {
            file(names::FEXT, &|w| write_vector(w, f, &comment))?;
        }
        if !self.outputs.is_empty() {
            file(names::OUTPUTS, &|w| write_outputs(w, &self.outputs))?;
        }
        Ok(files)
    }
}
