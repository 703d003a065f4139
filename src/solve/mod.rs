//! Nonlinear solves: the incremental potential of a step ([`potential`]) with its ground contact
//! ([`contact`]), Newton's method with a
//! backtracking line search and a growing diagonal shift ([`mod@newton`]), and the sparse Cholesky
//! it uses ([`linear`]), with dense low-rank Hessian parts through the Woodbury identity
//! ([`low_rank`]).

pub mod contact;
pub mod linear;
pub mod low_rank;
pub mod newton;
pub mod potential;
pub mod state;

pub use linear::{LinearError, LinearSolver};
pub use newton::{newton, NewtonOptions, NewtonReport, SolveError};
pub use potential::Potential;
pub use state::State;
