//! # ssm-api: the stable ABI between the `ssm` engine and model plugins
//!
//! A plugin is a `cdylib` that depends on this crate. It exports one root
//! module ([`SsmPlugin`]) with [`declare_plugin!`], lists the models it offers
//! ([`ModelInfo`], with their parameters and defaults), and builds a [`Model`] from
//! the scene's parameter table.
//!
//! This crate holds the ABI and nothing else: the data that crosses the
//! boundary and the root module. The helpers plugins build that data with
//! (the mechanical builder, the `Expr` builder, parameter specs and their
//! parsing, models from model folders) live in `ssm-plugin-kit`, which
//! plugins use beside this crate; they changed crate in 1.2 without changing
//! any layout, so plugins built before load as they did.
//!
//! ## The four concepts
//! - **Model** ([`Model`]): stable *data*, the first-order system
//!   `B z' = A z + F(z) + eps * Fext(z, Omega t)` (flow) or the map
//!   `z_{k+1} = A z_k + F(z_k)` ([`TimeKind`]), with sparse `A`, `B`
//!   ([`SparseMatrix`]), a sparse multivariate polynomial `F` ([`PolyVector`]),
//!   harmonic forcing ([`Harmonic`]), named and tagged states ([`StateInfo`]) and
//!   named outputs ([`Output`]).
//! - **Constraint** (the layout in [`MechanicalInfo`]): the polynomial configuration
//!   constraints `g(x) = G0 x + g_nl(x) = 0` of a mechanical system. The
//!   `MechanicalSystem` builder of `ssm-plugin-kit` turns `(M, C, K, f(x, x'), g(x), fext)` into the
//!   first-order DAE of eqs. (4)-(5) of Li, Jain & Haller (2023), so plugins never
//!   assemble block matrices by hand; the resulting [`Model`] keeps the constraint
//!   structure in [`MechanicalInfo`].
//! - **Recast** ([`ExprVector`], written with the `Expr` builder of
//!   `ssm-plugin-kit`): non-polynomial terms (`sin`, `cos`,
//!   `exp`, `ln`, `sqrt`, `1/x`, integer powers) written as expressions over the
//!   states, with an optional equilibrium to expand about. The engine turns them
//!   into a polynomial DAE with auxiliary states (`u1 = sin phi`,
//!   `u2 = 1 - cos phi`) and knows which states are auxiliary.
//! - **Reducer** ([`ReducerInfo`], [`ReducerInput`], [`Reduced`]): turns sampled
//!   [`Signals`] and/or a [`Model`] into a reduced model (flow or map), with an
//!   optional [`Lift`] back to the full coordinates and named [`Diagnostic`]s.
//!   A plugin offers reducers through the `reducers:`/`reduce:` arguments of
//!   [`declare_plugin!`].
//!
//! ## Versioning and growth
//! The API version is this crate's package version ([`API_VERSION`]). 1.0 is
//! the model layout (root module up to `build_model`); 1.1 appended the reducer
//! entry. The rules that let the API grow without breaking plugins:
//! - the root module ([`SsmPlugin`]) only grows by appended fields, each
//!   optional (`missing_field(option)`): an engine loads every plugin built
//!   against an older 1.x API and sees a missing entry as an absent capability;
//!   abi_stable checks only the major version for 1.x and the full layout of
//!   the fields both sides know;
//! - tags that will grow ([`ErrorKind`], [`StateKind`], [`MotionKind`],
//!   [`InputNeeds`]) are transparent `u8` values with named constants, not
//!   enums, so new values change no layout;
//! - a plugin built against another major version is refused at load with
//!   both versions named.

#![warn(missing_docs)]

#[macro_use]
mod tag;

mod error;
mod expr;
pub mod limits;
mod listing;
mod model;
mod plugin;
mod reducer;
pub mod v1_0;

pub use error::{guard, ErrorKind, PluginError};
pub use expr::{ExprNode, ExprOp, ExprTerm, ExprVector};
pub use listing::{select_model, ModelInfo, ParamInfo, PATH_KIND};
pub use model::{
    Harmonic, MechanicalInfo, Model, MotionKind, Output, PolyTerm, PolyVector, SparseMatrix,
    StateInfo, StateKind, TimeKind, Triplet, VarPower, Weight, SYMMETRY_TOLERANCE,
};
pub use plugin::{SsmPlugin, SsmPluginRef, API_VERSION};
pub use reducer::{
    Diagnostic, InputNeeds, Lift, Reduced, ReducerInfo, ReducerInput, Signals, Trajectory,
};

/// Re-exports used by [`declare_plugin!`]; not part of the documented API.
#[doc(hidden)]
pub mod reexports {
    pub use abi_stable;
}
