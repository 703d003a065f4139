//! Nonlinear solves: the incremental potential of a step ([`potential`]) with its ground contact
//! ([`contact`]), Newton's method with a
//! backtracking line search and a growing diagonal shift ([`mod@newton`]), and the sparse Cholesky
//! it uses ([`linear`]).

pub mod contact;
pub mod linear;
pub mod newton;
pub mod potential;

pub use linear::{LinearError, LinearSolver};
pub use newton::{newton, NewtonOptions, NewtonReport};
pub use potential::Potential;
