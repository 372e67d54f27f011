//! The model the analyses run on: plugins found and loaded ([`plugin`]), the
//! declared constraint layout checked and made canonical ([`layout`]), the
//! engine-side first-order system ([`system`]), and non-polynomial terms
//! recast into a polynomial DAE ([`recast`]), and the scene's `[model]`
//! built by its plugin ([`source`]).

pub mod layout;
pub mod plugin;
pub mod recast;
pub mod source;
pub mod system;
