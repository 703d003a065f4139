//! Sparse symmetric positive-definite solves with faer's Cholesky (LLᵀ).
//!
//! The symbolic factorisation (AMD ordering, elimination tree, supernodes) is computed once per
//! sparsity pattern; every Newton iteration only refactorises numerically. Factorisation and
//! solves run sequentially (`Par::Seq`) so the result never depends on the thread count.

use crate::assembly::Pattern;
use crate::math::Real;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// A failed factorisation or setup.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LinearError {
    /// The matrix is not (numerically) positive definite.
    #[error("matrix not positive definite (non-positive pivot at {index})")]
    NonPositivePivot {
        /// Pivot index (in the permuted order).
        index: usize,
    },
    /// faer could not build the symbolic structure (out of memory, bad pattern).
    #[error("sparse Cholesky setup failed: {0}")]
    Setup(String),
}

/// A Cholesky solver bound to one sparsity pattern.
pub struct LinearSolver {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<Real>,
    mem: MemBuffer,
    factored: bool,
}

impl LinearSolver {
    /// Symbolic analysis of the pattern, done once.
    pub fn new(p: &Pattern) -> Result<Self, LinearError> {
        Self::from_csc(p.n, p.col_ptr.clone(), p.row_idx.clone())
    }

    /// Symbolic analysis of any lower-triangular CSC pattern (sorted rows, diagonal first).
    pub fn from_csc(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
    ) -> Result<Self, LinearError> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            Default::default(),
        )
        .map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<Real>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<Real>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        Ok(LinearSolver {
            l_values: vec![0.0; symbolic.len_val()],
            pattern,
            symbolic,
            mem,
            factored: false,
        })
    }

    /// Number of non-zeros in the factor L.
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Numeric factorisation of the matrix with the pattern's structure and these values.
    pub fn factor(&mut self, values: &[Real]) -> Result<(), LinearError> {
        self.factored = false;
        let mut l = std::mem::take(&mut self.l_values);
        let r = self.factor_to(values, &mut l);
        self.l_values = l;
        r?;
        self.factored = true;
        Ok(())
    }

    /// Numeric factorisation into caller-owned storage `l` (resized to [`Self::factor_nnz`]), to
    /// keep several factors of one pattern (e.g. one per time step size) and solve with
    /// [`Self::solve_with`].
    pub fn factor_to(&mut self, values: &[Real], l: &mut Vec<Real>) -> Result<(), LinearError> {
        l.resize(self.symbolic.len_val(), 0.0);
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let stack = MemStack::new(&mut self.mem);
        self.symbolic
            .factorize_numeric_llt::<Real>(
                l,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    LinearError::NonPositivePivot { index }
                }
            })?;
        Ok(())
    }

    /// Solves `A x = rhs` in place with a factor made by [`Self::factor_to`].
    pub fn solve_with(&mut self, l: &[Real], rhs: &mut [Real]) {
        let n = rhs.len();
        let llt = LltRef::new(&self.symbolic, l);
        let stack = MemStack::new(&mut self.mem);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            stack,
        );
    }

    /// Solves `A x = rhs` in place with the last successful factorisation.
    pub fn solve_in_place(&mut self, rhs: &mut [Real]) {
        debug_assert!(self.factored, "solve before a successful factorisation");
        let l = std::mem::take(&mut self.l_values);
        self.solve_with(&l, rhs);
        self.l_values = l;
    }
}
