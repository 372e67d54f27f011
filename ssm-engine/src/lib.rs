//! # ssm-engine
//!
//! Nonlinear model reduction of mechanical systems, possibly with configuration
//! constraints (DAEs), on spectral submanifolds (SSMs). Models arrive as
//! plugins through the stable ABI of [`ssm_api`].
//!
//! This crate is the front end: it reads scenes, resolves them to the typed
//! specs of `ssm-core`, runs them and writes the results. The numerics live
//! below it, in crates that know no TOML and write no file: `ssm-kernel`
//! (series, Chebyshev tables, continuation) and `ssm-core` (model, spectrum,
//! SSM, reduced-model answers, full-order model, reducers, comparisons).
//!
//! The folders follow the pipeline of a run ([`pipeline::run`]):
//! - [`scene`]: the TOML scene format, validated with line numbers;
//! - [`plan`]: a scene's sections resolved to the span-free specs of
//!   `ssm_core::spec` (code builds specs directly: no TOML below `plan`);
//! - [`analyses`]: analyses added as vertical slices (one folder each:
//!   spec, run, writer; one registration line), e.g. the damping curve;
//! - [`output`]: writers of `summary.json`, CSV and SVG from typed results
//!   (they compute nothing), written atomically;
//! - [`pipeline`]: running a scene, stage after stage (its model built from
//!   `[model]` or by the reducer of `[reduce]`).
//!
//! Dependencies point one way: `pipeline` uses every stage, `output` reads
//! the stages' result types, and no two files or folders import each other
//! (checked by the suite's `layers::no_import_cycles_between_files_or_folders`).

#![warn(missing_docs)]

pub mod analyses;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod scene;

pub use ssm_core::C64;
