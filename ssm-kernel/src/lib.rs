//! # ssm-kernel
//!
//! The numerical kernel of ssm, below the model and the SSM: it knows no
//! mechanical system, scene or file.
//! - [`poly`]: multi-indices, truncated series, order-by-order composition
//!   `F(W(p))`;
//! - [`chebyshev`]: adaptive Chebyshev tables in one variable;
//! - [`continuation`]: the continuation core (local parametrization, step
//!   control, test functions and the events they locate);
//! - [`sparse_lu`]: a sparse LU analyzed once and refactored in place;
//! - [`sparse_sym`]: complex symmetric sparse matrices factorized through
//!   their real symmetric form (`L B L^T`, minimum-degree order);
//! - [`stepper`]: the one interface of the time integrators, and sampling
//!   any of them at given times;
//! - [`dopri`]: the Dormand-Prince 5(4) pair on complex states;
//! - [`number`]: numbers from user input in messages and CSV files;
//! - [`search`]: the first failing point of a costly test along a scan;
//! - [`cancel`]: cooperative cancellation of the long loops;
//! - [`heap`]: live and peak heap bytes, counted by the front end's
//!   allocator;
//! - [`workspace`]: the address space of the dense kernels' per-thread
//!   buffers, taken before the memory gate reads its room.

#![warn(missing_docs)]

pub mod cancel;
pub mod chebyshev;
pub mod continuation;
pub mod dopri;
pub mod heap;
pub mod number;
pub mod poly;
pub mod search;
pub mod sparse_lu;
pub mod sparse_sym;
pub mod stepper;
pub mod workspace;

pub use num_complex::Complex64 as C64;
