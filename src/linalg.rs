//! Sparse symmetric solves with faer's Cholesky, on any lower-triangular CSC pattern (the
//! assembled Hessian's, the moisture diffusion's): LLᵀ for positive-definite matrices, and LDLᵀ
//! (no pivoting) with its inertia for the symmetric indefinite ones that a dense low-rank term
//! makes positive definite (an inflated balloon past its pressure limit point: the sparse part
//! has one negative eigenvalue, the gas's rank-one stiffness removes it; see
//! `solve::low_rank`).
//!
//! The symbolic factorisation (AMD ordering, elimination tree, supernodes) is computed once per
//! sparsity pattern; every Newton iteration only refactorises numerically. Factorisation and
//! solves run sequentially (`Par::Seq`) so the result never depends on the thread count.
//!
//! The inertia of an LDLᵀ factorisation is that of `D` (Sylvester's law: `P A Pᵀ = L D Lᵀ` is a
//! congruence), read from the diagonal of the factor's storage (the first entry of each
//! simplicial column, the diagonal of each supernode's block).

use crate::math::Real;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};

/// The size from which the factorisation is always supernodal (unknowns).
pub const SUPERNODAL_FROM: usize = 1000;

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
    /// An LDLᵀ factorisation met an exactly zero pivot (the matrix is singular).
    #[error("matrix singular (zero pivot at {index})")]
    ZeroPivot {
        /// Pivot index (in the permuted order).
        index: usize,
    },
    /// faer could not build the symbolic structure (out of memory, bad pattern).
    #[error("sparse Cholesky setup failed: {0}")]
    Setup(String),
}

/// Which factorisation the solver holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    None,
    Llt,
    Ldlt,
}

/// A Cholesky solver bound to one sparsity pattern.
pub struct LinearSolver {
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<Real>,
    mem: MemBuffer,
    kind: Kind,
    /// Negative pivots of the last factorisation (0 for Cholesky).
    negative: usize,
}

impl LinearSolver {
    /// Symbolic analysis of any lower-triangular CSC pattern (sorted rows, diagonal first).
    pub fn from_csc(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
    ) -> Result<Self, LinearError> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        // Supernodal from SUPERNODAL_FROM unknowns: faer's default flop-ratio threshold picks
        // the simplicial factorisation for small systems, which measured slower on the shell
        // Hessians of a few thousand unknowns (docs/solvers.md). The choice depends on the size
        // alone, so results stay identical across runs.
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: if n >= SUPERNODAL_FROM {
                SupernodalThreshold::FORCE_SUPERNODAL
            } else {
                SupernodalThreshold::AUTO
            },
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Amd,
            params,
        )
        .map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<Real>(Par::Seq, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<Real>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<Real>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        Ok(LinearSolver {
            l_values: vec![0.0; symbolic.len_val()],
            pattern,
            symbolic,
            mem,
            kind: Kind::None,
            negative: 0,
        })
    }

    /// Number of non-zeros in the factor L.
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Numeric factorisation of the matrix with the pattern's structure and these values.
    pub fn factor(&mut self, values: &[Real]) -> Result<(), LinearError> {
        self.kind = Kind::None;
        self.negative = 0;
        let mut l = std::mem::take(&mut self.l_values);
        let r = self.factor_to(values, &mut l);
        self.l_values = l;
        r?;
        self.kind = Kind::Llt;
        Ok(())
    }

    /// Numeric LDLᵀ factorisation (no pivoting) of a symmetric, possibly indefinite matrix with
    /// the pattern's structure; returns its number of negative eigenvalues (the negative
    /// pivots). An exactly zero pivot is an error. Without pivoting the factorisation is stable
    /// for matrices that are positive definite up to a few directions, which is what it serves
    /// (callers check their solves' results).
    pub fn factor_indefinite(&mut self, values: &[Real]) -> Result<usize, LinearError> {
        self.kind = Kind::None;
        let mut l = std::mem::take(&mut self.l_values);
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        let stack = MemStack::new(&mut self.mem);
        let r = self
            .symbolic
            .factorize_numeric_ldlt::<Real>(
                &mut l,
                a,
                Side::Lower,
                LdltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map(|_| ())
            .map_err(|e| match e {
                faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                    LinearError::ZeroPivot { index }
                }
            });
        self.l_values = l;
        r?;
        let d = self.ldlt_diagonal();
        if d.iter().any(|v| !v.is_finite()) {
            return Err(LinearError::ZeroPivot {
                index: d.iter().position(|v| !v.is_finite()).unwrap_or(0),
            });
        }
        self.kind = Kind::Ldlt;
        self.negative = d.iter().filter(|&&v| v < 0.0).count();
        Ok(self.negative)
    }

    /// The pivots `D` of the last LDLᵀ factorisation, in the permuted order.
    fn ldlt_diagonal(&self) -> Vec<Real> {
        let l = &self.l_values;
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                // Each column stores its diagonal first.
                let cp = s.col_ptr();
                (0..s.nrows()).map(|j| l[cp[j]]).collect()
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let mut d = Vec::with_capacity(s.nrows());
                let begin = s.supernode_begin();
                let end = s.supernode_end();
                let vp = s.col_ptr_for_val();
                for k in 0..s.n_supernodes() {
                    let ncols = end[k] - begin[k];
                    let nrows = ncols + s.supernode(k).pattern().len();
                    for j in 0..ncols {
                        d.push(l[vp[k] + j * nrows + j]);
                    }
                }
                d
            }
        }
    }

    /// Whether the symbolic factorisation is supernodal (larger matrices) rather than
    /// simplicial (the two store the LDLᵀ pivots differently).
    pub fn is_supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// Whether a factorisation is held (the last one succeeded).
    pub fn is_factored(&self) -> bool {
        self.kind != Kind::None
    }

    /// Whether the last factorisation was of an indefinite matrix (LDLᵀ with negative pivots).
    pub fn is_indefinite(&self) -> bool {
        self.kind == Kind::Ldlt && self.negative > 0
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
        debug_assert!(
            self.kind != Kind::None,
            "solve before a successful factorisation"
        );
        let l = std::mem::take(&mut self.l_values);
        if self.kind == Kind::Ldlt {
            let n = rhs.len();
            let ldlt = LdltRef::new(&self.symbolic, &l);
            let stack = MemStack::new(&mut self.mem);
            ldlt.solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(rhs, n, 1),
                Par::Seq,
                stack,
            );
        } else {
            self.solve_with(&l, rhs);
        }
        self.l_values = l;
    }
}
