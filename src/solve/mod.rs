//! Nonlinear solves of a step's incremental potential ([`crate::energy::potential`]): Newton's method with a backtracking line search and a growing diagonal shift ([`mod@newton`]), and the sparse Cholesky
//! it uses ([`linear`]), with dense low-rank Hessian parts through the Woodbury identity
//! ([`low_rank`]).

/// The sparse Cholesky solver, which lives on the lowest floor ([`crate::linalg`]).
pub use crate::linalg as linear;
pub mod low_rank;
pub mod newton;
pub mod state;

pub use crate::linalg::{LinearError, LinearSolver};
pub use newton::{newton, NewtonOptions, NewtonReport, SolveError};
pub use state::State;

impl LinearSolver {
    /// Symbolic analysis of an assembled sparsity pattern, done once per pattern.
    pub fn new(p: &crate::assembly::Pattern) -> Result<Self, LinearError> {
        // The Hessian's factorisation is split at the top separator when nested dissection is
        // chosen: its halves run on two threads.
        Ok(Self::from_csc(p.n, p.col_ptr.clone(), p.row_idx.clone())?.with_split())
    }
}
