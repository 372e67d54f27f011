//! The model the analyses run on: plugins found and loaded ([`plugin`]), the
//! declared constraint layout checked and made canonical (`layout`), the
//! engine-side first-order system ([`system`]), its velocities eliminated
//! where it is mechanical (`condense`), and non-polynomial terms
//! recast into a polynomial DAE ([`recast`]). A scene's `[model]` is built
//! by the front end (`crate::pipeline::source`).

pub(crate) mod condense;
pub(crate) mod layout;
pub mod plugin;
pub mod recast;
pub mod system;
