//! # ssm-core
//!
//! Nonlinear model reduction of mechanical systems, possibly with
//! configuration constraints (DAEs), on spectral submanifolds (SSMs), as a
//! library: typed inputs (a [`model::system::System`] and span-free
//! [`spec`]s), typed results. It reads no scene, no TOML and writes no file;
//! the front end (`ssm-engine`) does. Models arrive as plugins through the
//! stable ABI of [`ssm_api`], from model files, or built from matrices.
//!
//! The folders follow a run:
//! - [`model`]: plugins found and loaded, the declared constraint layout, the
//!   engine-side first-order system, the recast of non-polynomial terms;
//! - [`reduce`]: models made by reducers, from data signals and/or a model;
//! - [`spectrum`]: finite spectrum of the (possibly singular) pencil `(A, B)`,
//!   master modes, normalization, spectral quotients and non-resonance checks;
//! - [`ssm`]: autonomous and periodic SSMs of flows and maps (parametrization
//!   method), polar form, invariance error, reduced dynamics;
//! - [`rom`]: answers of the reduced model: backbones, lifted transients,
//!   forced response curves (one pair; several pairs by continuation);
//! - [`fom`]: the full-order model: Radau IIA and HHT integration of the DAE,
//!   consistent initial values, periodic orbits and their Floquet multipliers;
//! - [`compare`]: full against reduced (transients, distance to the SSM,
//!   steady-state references) and the speed-against-error report;
//! - [`spec`]: the span-free specs of the answers, with documented defaults,
//!   to and from JSON.
//!
//! ## The front door
//!
//! The path most programs take is re-exported at the crate root: a
//! [`System`] (from a plugin's model, a model folder or matrices), the
//! spectral stage [`spectral`] on an [`SsmSpec`] and a [`SpectrumSpec`]
//! (spectrum, master modes, non-resonance checks and their warnings), the
//! SSM [`compute_ssm`] to an order, and the answers read off it, each with
//! its error estimate: [`backbone`] ([`BackboneSpec`]), [`forced_response`]
//! ([`FrcSpec`]) and [`transient`] ([`TransientSpec`]); and the full
//! system's periodic orbits [`reference_frc`] ([`ReferenceSettings`]) to
//! compare with. `ssm-engine/examples/duffing.rs` takes this path from the
//! matrices of the Duffing oscillator. The folders below hold the rest
//! (the solvers' options, the comparisons, the reducers, the full-order
//! integrators); modules that only serve others are private.
//!
//! Below it, `ssm-kernel` holds the series, Chebyshev tables and the
//! continuation core. No two files or folders import each other (checked by
//! the suite's `layers::no_import_cycles_between_files_or_folders`), and the
//! crate does not depend on `toml` (`layers::core_crates_do_not_depend_on_the_front_end`).

#![warn(missing_docs)]

pub mod compare;
pub mod fom;
pub mod model;
pub mod reduce;
pub mod rom;
pub mod spec;
pub mod spectrum;
pub mod ssm;

pub use ssm_kernel::C64;

pub use fom::periodic::frc::{reference_frc, ReferenceFrc, ReferenceSettings};
pub use model::system::System;
pub use rom::autonomous::{backbone, transient, BackboneCurve, LiftedTransient};
pub use rom::forced_response::{forced_response, ForcedResponse};
pub use spec::{BackboneSpec, FrcSpec, SpectrumSpec, SsmSpec, TransientSpec};
pub use spectrum::{MasterMode, Spectrum};
pub use ssm::spectral::{spectral, Spectral};
pub use ssm::{compute as compute_ssm, SsmExpansion, SsmOptions};
