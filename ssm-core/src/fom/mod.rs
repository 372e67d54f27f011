//! Full-system time integration of `B z' = A z + F(z) + eps Fext(z, Omega t)`:
//! the reference against which reduced models are validated.
//!
//! # Method
//! The systems are differential-algebraic: configuration constraints make the
//! multipliers index-3 variables (`0 = g(x)` with `G(x)^T mu` in the momentum
//! equations, eqs. (1)-(5)), and a recast adds index-1 algebraic equations
//! (`0 = u_s^2 - 2 u_c + u_c^2`, eq. (22)). We integrate them as they are, with
//! the three-stage Radau IIA collocation method (order 5), for these reasons:
//! - it is stiffly accurate, so the step end is the last collocation point and
//!   every algebraic equation, the position constraints included, holds there
//!   to the Newton tolerance: there is no drift, unlike index reduction to
//!   `g'' = 0` (the paper's index-1 form (95), which needs Baumgarte terms) or
//!   to `g' = 0`;
//! - it converges for index-3 problems without reformulation (positions
//!   `O(h^5)`, velocities `O(h^3)`, multipliers `O(h^2)`), and its local error
//!   estimate is made index-aware by scaling the index-2 and index-3 components
//!   by `h` and `h^2` (Hairer & Wanner, Sect. VII.8), so the step size is not
//!   driven down by the multipliers;
//! - high order pays for the long steady-state runs of validation (hundreds of
//!   forcing periods at tolerance `1e-8`), where the second-order HHT /
//!   generalized-alpha methods would need many more steps;
//! - it is L-stable, damping the infinite (constraint) modes of the pencil.
//!
//! Each step solves the `3N` stage equations by a simplified Newton iteration
//! with the analytic sparse Jacobian `A + DF(z) + eps DFext` (exact for the
//! polynomial `F`), decoupled by the eigen-decomposition of the Radau matrix
//! into one real and one complex sparse system, `(gamma/h) B - J` and
//! `((alpha + i beta)/h) B - J`; both are factorized with faer's sparse LU on one
//! symbolic analysis of the union pattern, reused for the whole run.
//! Factorizations and Jacobians are reused across steps when the Newton
//! contraction is fast and the step size is unchanged (within 20 %). The step
//! size follows the predictive (Gustafsson) controller of RADAU5.
//!
//! No crate provides Radau IIA for index-3 DAEs on sparse matrices with a
//! singular mass matrix (`diffsol`'s BDF/SDIRK handle index 1 only, and the
//! available Radau5 ports need C sparse solvers), so the stepper is written
//! here on top of faer's sparse LU.
//!
//! Radau IIA ([`Radau`]) and HHT-alpha ([`hht::Hht`], the integrator of the
//! POD study) are both steppers of the kernel's one integrator interface
//! (`ssm_kernel::stepper::Stepper`: accepted steps and dense output), so a
//! sampled run reads either through the same `ssm_kernel::stepper::sample`.
//!
//! Consistent initial values ([`consistent`]) come from a point `W(p0)` on an
//! SSM or from given displacements and velocities: positions are projected onto
//! `g(x) = 0` and velocities onto `G(x) v = 0` in the mass metric, then the
//! multipliers are solved from the acceleration-level constraint (eq. (90)).
//!
//! # References
//! E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed.,
//! Sects. IV.8 (implementation of implicit Runge-Kutta methods, RADAU5), VI.6
//! and VII.4 (convergence for index 2 and 3), VII.8 (index-aware error
//! control); E. Hairer, C. Lubich, M. Roche, *The Numerical Solution of
//! Differential-Algebraic Systems by Runge-Kutta Methods*, LNM 1409 (1989);
//! M. Li, S. Jain, G. Haller, Nonlinear Dyn. 111 (2023), Appendix E and eq. (47).

pub mod consistent;
pub mod hht;
pub mod lifted;
pub mod periodic;
pub(crate) mod problem;
pub mod radau;
pub mod sample;
pub(crate) mod steady;

pub(crate) use consistent::consistent_initial_keeping;
pub use consistent::{consistent_initial, given_start, Consistent};
pub use problem::DaeProblem;
pub use radau::{Radau, RadauOptions, RadauStats};
pub use sample::{add_noise, sample_run, Integrator, SampledRun, Simulation};
use ssm_kernel::number::short;
pub use steady::{steady_state, SteadyOptions, SteadyState};

/// Why a full-system simulation failed. Every variant names the time reached.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The step size fell below its floor.
    #[error("full-system integration: step size collapsed to {h:.3e} at t = {}: {cause}", short(.t))]
    StepCollapse {
        /// Time reached.
        t: f64,
        /// Last step size tried.
        h: f64,
        /// What kept rejecting the steps.
        cause: String,
    },
    /// The iteration matrix `(gamma/h) B - J` could not be solved.
    #[error(
        "full-system integration: singular iteration matrix at t = {} (h = {h:.3e}): {detail}",
        short(.t)
    )]
    SingularIteration {
        /// Time reached.
        t: f64,
        /// Step size.
        h: f64,
        /// What was observed.
        detail: String,
    },
    /// The state became NaN or infinite.
    #[error("full-system integration: non-finite state at t = {} (state '{state}'): the solution blew up", short(.t))]
    NonFinite {
        /// Time reached.
        t: f64,
        /// First non-finite state.
        state: String,
    },
    /// The step budget ran out.
    #[error("full-system integration: the step budget of {steps} steps ran out at t = {} before t_end = {}: shorten [validate] t_end (or max_periods), loosen rtol/atol, or check the model for a fast or unbounded motion", short(.t), short(.t_end))]
    TooManySteps {
        /// Time reached.
        t: f64,
        /// Steps taken.
        steps: usize,
        /// Requested end time.
        t_end: f64,
    },
    /// The initial point cannot be made consistent with the constraints.
    #[error("inconsistent initial condition at t = {}: {detail}", short(.t))]
    Inconsistent {
        /// Initial time.
        t: f64,
        /// What failed.
        detail: String,
    },
    /// The work was asked to stop ([`ssm_kernel::cancel`]).
    #[error("full-system integration interrupted at t = {}", short(.t))]
    Interrupted {
        /// Time reached.
        t: f64,
    },
    /// The steady state was not reached.
    #[error("steady state at Omega = {}: not periodic after {periods} forcing periods (t = {}); last relative change over one period {change:.3e} > delta = {delta:.1e} (criterion (47), periods up to {max_multiple} T tried); raise max_periods, or max_period_multiple if the response may be subharmonic", short(.omega), short(.t))]
    NotPeriodic {
        /// Forcing frequency.
        omega: f64,
        /// Periods integrated.
        periods: usize,
        /// Time reached.
        t: f64,
        /// Last value of the criterion.
        change: f64,
        /// Threshold.
        delta: f64,
        /// Largest period multiple tried.
        max_multiple: usize,
    },
    /// Settings that cannot be used.
    #[error("simulation settings: {0}")]
    Settings(String),
}
