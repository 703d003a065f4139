//! Nonlinear solves: the incremental potential of a step ([`potential`]), Newton's method with a
//! backtracking line search and a growing diagonal shift ([`mod@newton`]), and the sparse Cholesky
//! it uses ([`linear`]).

pub mod linear;
pub mod newton;
pub mod potential;

pub use linear::{LinearError, LinearSolver};
pub use newton::{newton, NewtonOptions, NewtonReport};
pub use potential::Potential;
