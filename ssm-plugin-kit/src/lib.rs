//! # ssm-plugin-kit: building models for the `ssm` engine
//!
//! `ssm-api` is the ABI: the data that crosses the plugin boundary. This
//! crate is what plugins (and code that builds models directly, such as the
//! engine's examples and bindings) write that data with:
//! - [`MechanicalSystem`]: `(M, C, K, f(x, x'), g(x), fext)` to the
//!   first-order DAE of eqs. (4)-(5) of Li, Jain & Haller (2023), with
//!   [`Constraints`] and an optional [`Equilibrium`] to expand about;
//! - [`Expr`]: non-polynomial terms as expressions over the states, lowered
//!   into the boundary's `ExprVector` by [`expr_vector`];
//! - [`ParamSpec`], [`Params`]: a model's parameters with defaults, their
//!   listing ([`model_info`], [`reducer_info`]) and the parsing of the
//!   scene's parameter table (TOML text) with errors naming the key;
//! - [`mechanical_from_files`], [`files_from_model`]: a model folder
//!   (`ssm-model-files`) to a mechanical system and back.
//!
//! A plugin depends on `ssm-api` and this crate; only `ssm-api`'s layout is
//! checked when the engine loads it.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023) 8881-8911, eqs. (1)-(5).

#![warn(missing_docs)]

mod expr;
mod files;
mod listing;
mod mechanical;
mod params;

pub use expr::{expr_vector, Expr};
pub use files::{files_from_model, mechanical_from_files};
pub use listing::{model_info, reducer_info};
pub use mechanical::{BuildError, Constraints, Equilibrium, MechanicalSystem};
pub use params::{ParamKind, ParamSpec, ParamValue, Params};
