//! # ssm-api: the stable ABI between the `ssm` engine and model plugins
//!
//! A plugin is a `cdylib` that depends on this crate only. It exports one root
//! module ([`SsmPlugin`]) with [`declare_plugin!`], lists the models it offers
//! ([`ModelInfo`], with their parameters and defaults), and builds a [`Model`] from
//! the scene's parameter table.
//!
//! ## The four concepts
//! - **Model** ([`Model`]): stable *data*, the first-order system
//!   `B z' = A z + F(z) + eps * Fext(z, Omega t)` (flow) or the map
//!   `z_{k+1} = A z_k + F(z_k)` ([`TimeKind`]), with sparse `A`, `B`
//!   ([`SparseMatrix`]), a sparse multivariate polynomial `F` ([`PolyVector`]),
//!   harmonic forcing ([`Harmonic`]), named and tagged states ([`StateInfo`]) and
//!   named outputs ([`Output`]).
//! - **Constraint** ([`Constraints`]): stable data, the polynomial configuration
//!   constraints `g(x) = G0 x + g_nl(x) = 0` of a mechanical system. The
//!   [`MechanicalSystem`] builder turns `(M, C, K, f(x, x'), g(x), fext)` into the
//!   first-order DAE of eqs. (4)-(5) of Li, Jain & Haller (2023), so plugins never
//!   assemble block matrices by hand; the resulting [`Model`] keeps the constraint
//!   structure in [`MechanicalInfo`].
//! - **Recast** ([`Expr`], [`ExprVector`]): non-polynomial terms (`sin`, `cos`,
//!   `exp`, `ln`, `sqrt`, `1/x`, integer powers) written as expressions over the
//!   states, with an optional equilibrium to expand about. The engine turns them
//!   into a polynomial DAE with auxiliary states (`u1 = sin phi`,
//!   `u2 = 1 - cos phi`) and knows which states are auxiliary.
//! - **Reducer**: a further constructor of the root module. The root module is a
//!   prefix type whose fields are only ever appended, so such entry points are
//!   added as new trailing fields in later API versions without breaking plugins
//!   built against this one; an engine that finds a plugin without them treats
//!   the capability as absent.
//!
//! ## Versioning
//! The API version is this crate's package version ([`API_VERSION`]). The engine
//! refuses a plugin built against an incompatible version (different major, or for
//! 0.x a different minor) and names both versions; abi_stable additionally checks
//! the full type layout of the root module at load time.

mod expr;
mod mechanical;
mod model;
mod params;
mod plugin;

pub use expr::{Expr, ExprNode, ExprOp, ExprTerm, ExprVector};
pub use mechanical::{BuildError, Constraints, Equilibrium, MechanicalSystem};
pub use model::{
    Harmonic, MechanicalInfo, Model, MotionKind, Output, PolyTerm, PolyVector, SparseMatrix,
    StateInfo, StateKind, TimeKind, Triplet, VarPower, Weight,
};
pub use params::{ParamKind, ParamSpec, ParamValue, Params};
pub use plugin::{
    guard, ErrorKind, ModelInfo, ParamInfo, PluginError, SsmPlugin, SsmPluginRef, API_VERSION,
};

/// Re-exports used by [`declare_plugin!`]; not part of the documented API.
#[doc(hidden)]
pub mod reexports {
    pub use abi_stable;
}
