//! Planar von Karman beam finite elements shared by the beam models of the
//! plugins (the frequency divider of Li, Jain & Haller 2023, Sect. 5.3, and the
//! clamped-clamped beam used for data-driven identification).
//!
//! - [`element`]: one two-node element; mass, linear stiffness and the
//!   quadratic and cubic internal forces as exact sparse polynomials.
//! - [`mesh`]: a straight beam of equal elements with end supports, assembled
//!   into the sparse arrays of an `ssm_plugin_kit::MechanicalSystem`.
//! - [`ancf`]: the planar element in absolute nodal coordinates on the same
//!   Hermite functions, for flexible members that move and rotate freely
//!   (constant mass, polynomial forces, no force under rigid motion).
//!
//! Units are whatever the caller uses consistently (the divider: mm, kg, s, so
//! forces in kg mm/s^2 and moduli in kPa).
//!
//! # References
//! - S. Jain, P. Tiso, G. Haller, *Exact nonlinear model reduction for a von
//!   Karman beam: slow-fast decomposition and spectral submanifolds*, J. Sound
//!   Vib. 423 (2018) 195-211.
//! - M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical
//!   systems via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5.3.

pub mod ancf;
pub mod element;
pub mod mesh;

pub use element::{Element, LocalTerm, Section};
pub use mesh::{Mesh, Numbering, Support};
