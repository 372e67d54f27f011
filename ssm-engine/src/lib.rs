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
//! The folders follow a run ([`job::run`]):
//! - [`scene`]: the TOML scene format, validated with line numbers;
//! - [`job`]: a scene's run: its model built from `[model]` or by the
//!   reducer of `[reduce]`, its plan resolved, the plan executed;
//! - [`plan`]: what a run computes, as the span-free specs of
//!   `ssm_core::spec` (code builds a [`plan::Plan`] directly), checked
//!   against the model and costed against the machine's limits;
//! - [`analyses`]: analyses added as vertical slices (one folder each:
//!   spec, run, writer; one registration line), e.g. the damping curve;
//! - [`pipeline`]: a plan run on a model, stage after stage
//!   ([`pipeline::execute`]; it reads no scene type);
//! - [`output`]: writers of `summary.json`, CSV and SVG from typed results
//!   (they compute nothing), written atomically;
//! - [`plot`]: the SVG plots (and `csv`, the rows) that the writers of
//!   `output` and of the analyses share, so that an analysis does not
//!   reach into `output`.
//!
//! Dependencies point one way: `job` uses every stage, `pipeline` runs a
//! plan, `output` reads the stages' result types, and no two files or
//! folders import each other (checked by the suite's
//! `layers::no_import_cycles_between_files_or_folders`; the suite's
//! `layers::numerics_do_not_read_the_scene` keeps the pipeline free of scene
//! types).

#![warn(missing_docs)]

pub mod analyses;
mod csv;
mod error;
pub mod job;
pub mod json;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod plot;
pub mod progress;
pub mod scene;
pub mod study;

pub use ssm_core::C64;
