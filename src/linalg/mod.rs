//! Sparse symmetric solves with faer's Cholesky, on any lower-triangular CSC pattern (the
//! assembled Hessian's, the moisture diffusion's): LLᵀ for positive-definite matrices, and LDLᵀ
//! (no pivoting) with its inertia for the symmetric indefinite ones that a dense low-rank term
//! makes positive definite (an inflated balloon past its pressure limit point: the sparse part
//! has one negative eigenvalue, the gas's rank-one stiffness removes it; see
//! `solve::low_rank`).
//!
//! The symbolic factorisation (a fill-reducing ordering, the elimination tree, supernodes) is
//! computed once per sparsity pattern, at the first factorisation; every Newton iteration only
//! refactorises numerically. The ordering is AMD, or for large patterns the cheaper of AMD and
//! METIS's nested dissection by the factorisation's flop count ([`ordering`]). Factorisation and
//! solves run sequentially (`Par::Seq`) so the result never depends on the thread count.
//!
//! The inertia of an LDLᵀ factorisation is that of `D` (Sylvester's law: `P A Pᵀ = L D Lᵀ` is a
//! congruence), read from the diagonal of the factor's storage (the first entry of each
//! simplicial column, the diagonal of each supernode's block).

pub mod ordering;
mod split;

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

/// The size from which nested dissection is tried against AMD (unknowns). Below it METIS's
/// ordering costs more than it saves: on a 6.8k-unknown balloon it cut the flops by 28% but not
/// the factorisation's time, while the ordering took 5 ms; from 30k unknowns it saves 20% of
/// every factorisation on closed surfaces (docs/solvers.md).
pub const DISSECT_FROM: usize = 20_000;

/// A fill-reducing ordering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ordering {
    /// faer's approximate minimum degree.
    Amd,
    /// METIS's multilevel nested dissection.
    NestedDissection,
}

impl Ordering {
    /// Its name in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Ordering::Amd => "amd",
            Ordering::NestedDissection => "nested_dissection",
        }
    }
}

/// Flops of a numeric factorisation with this symbolic structure: Σ c² over the columns of L,
/// c the column's count with the diagonal.
fn symbolic_flops(symbolic: &SymbolicCholesky<usize>) -> f64 {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let cp = s.col_ptr();
            ordering::cholesky_flops((0..s.nrows()).map(|j| cp[j + 1] - cp[j]))
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let begin = s.supernode_begin();
            let end = s.supernode_end();
            ordering::cholesky_flops((0..s.n_supernodes()).flat_map(|k| {
                let ncols = end[k] - begin[k];
                let nrows = ncols + s.supernode(k).pattern().len();
                (0..ncols).map(move |j| nrows - j)
            }))
        }
    }
}

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

impl From<faer::linalg::cholesky::llt::factor::LltError> for LinearError {
    fn from(e: faer::linalg::cholesky::llt::factor::LltError) -> Self {
        match e {
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                LinearError::NonPositivePivot { index }
            }
        }
    }
}

impl From<faer::linalg::cholesky::ldlt::factor::LdltError> for LinearError {
    fn from(e: faer::linalg::cholesky::ldlt::factor::LdltError) -> Self {
        match e {
            faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                LinearError::ZeroPivot { index }
            }
        }
    }
}

/// faer's numeric factorisation of `a` (lower triangle) into `l` under `symbolic`: LDLᵀ without
/// pivoting when `ldlt`, LLᵀ otherwise; sequential, with the scratch `mem`. Shared by the whole
/// and the split factorisations.
fn factorize_numeric(
    symbolic: &SymbolicCholesky<usize>,
    l: &mut [Real],
    a: SparseColMatRef<'_, usize, Real>,
    ldlt: bool,
    mem: &mut MemBuffer,
) -> Result<(), LinearError> {
    let stack = MemStack::new(mem);
    if ldlt {
        symbolic.factorize_numeric_ldlt::<Real>(
            l,
            a,
            Side::Lower,
            LdltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        )?;
    } else {
        symbolic.factorize_numeric_llt::<Real>(
            l,
            a,
            Side::Lower,
            LltRegularization::default(),
            Par::Seq,
            stack,
            Default::default(),
        )?;
    }
    Ok(())
}

/// Which factorisation the solver holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    None,
    Llt,
    Ldlt,
}

/// The unsplit symbolic factorisation of a pattern under its ordering, with the scratch memory
/// of its numeric factorisations and solves.
struct Whole {
    symbolic: SymbolicCholesky<usize>,
    mem: MemBuffer,
}

impl Whole {
    /// The symbolic factorisation of the lower-triangular `pattern` under `perm` (new position
    /// → unknown). Supernodal from [`SUPERNODAL_FROM`] unknowns: faer's default flop-ratio
    /// threshold picks the simplicial factorisation for small systems, which measured slower on
    /// the shell Hessians of a few thousand unknowns (docs/solvers.md). The choice depends on
    /// the size alone, so results stay identical across runs.
    fn new(pattern: &SymbolicSparseColMat<usize>, perm: &[usize]) -> Result<Self, LinearError> {
        let n = pattern.nrows();
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: if n >= SUPERNODAL_FROM {
                SupernodalThreshold::FORCE_SUPERNODAL
            } else {
                SupernodalThreshold::AUTO
            },
            ..Default::default()
        };
        let inv = ordering::inverse(perm);
        let symbolic = factorize_symbolic_cholesky(
            pattern.as_ref(),
            Side::Lower,
            SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(perm, &inv, n)),
            params,
        )
        .map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<Real>(Par::Seq, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<Real>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<Real>(1, Par::Seq),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        Ok(Whole { symbolic, mem })
    }
}

/// The analysis of a pattern: its ordering and symbolic factorisation.
struct Analysis {
    ordering: Ordering,
    /// The ordering's permutation: new position → unknown.
    perm: Vec<usize>,
    /// The unsplit symbolic factorisation. Made with the analysis, except under the split,
    /// whose factorisations and solves do not use it: there the first [`LinearSolver::factor_to`]
    /// makes it (on a shell's Hessian, never).
    whole: Option<Whole>,
    /// Under nested dissection, with [`LinearSolver::with_split`]: the factorisation split at
    /// the top separator, its halves on two threads ([`split`]); `factor`, `factor_indefinite`
    /// and `solve_in_place` use it.
    split: Option<split::Split>,
}

/// A Cholesky solver bound to one sparsity pattern.
pub struct LinearSolver {
    pattern: SymbolicSparseColMat<usize>,
    /// The symbolic analysis, made by the first factorisation (or [`Self::analyse`]): a scene
    /// that never factorises (the explicit driver) never pays for it.
    analysis: Option<Analysis>,
    /// An ordering imposed by the caller (comparisons, benches); `None` chooses by flops.
    imposed: Option<Ordering>,
    /// Whether a nested dissection's factorisation is split at its top separator.
    split: bool,
    l_values: Vec<Real>,
    kind: Kind,
    /// Negative pivots of the last factorisation (0 for Cholesky).
    negative: usize,
    /// Numeric factorisations attempted, and of those the ones that failed.
    counts: FactorCounts,
}

/// How many numeric factorisations a solver attempted, and how many failed (a non-positive or
/// zero pivot).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FactorCounts {
    /// Numeric factorisations attempted.
    pub factorisations: usize,
    /// Of those, the ones that failed.
    pub failed: usize,
}

impl LinearSolver {
    /// A solver for any lower-triangular CSC pattern (sorted rows, diagonal first). The
    /// symbolic analysis waits for the first factorisation or [`Self::analyse`].
    pub fn from_csc(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
    ) -> Result<Self, LinearError> {
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Ok(LinearSolver {
            l_values: Vec::new(),
            pattern,
            analysis: None,
            imposed: None,
            split: false,
            kind: Kind::None,
            negative: 0,
            counts: FactorCounts::default(),
        })
    }

    /// Imposes an ordering instead of choosing the cheaper one (for comparisons); before the
    /// analysis. Nested dissection that fails still falls back to AMD.
    pub fn with_ordering(mut self, ordering: Ordering) -> Self {
        self.imposed = Some(ordering);
        self.analysis = None;
        self
    }

    /// Splits the factorisation at the top separator when the ordering is nested dissection:
    /// the two halves factorise and solve in parallel ([`split`]), and the result does not depend
    /// on the thread count. Before the analysis. [`Self::factor_to`] and [`Self::solve_with`]
    /// stay unsplit.
    pub fn with_split(mut self) -> Self {
        self.split = true;
        self.analysis = None;
        self
    }

    /// The symbolic analysis (ordering, elimination tree, supernodes), once per pattern.
    pub fn analyse(&mut self) -> Result<(), LinearError> {
        self.analysis_mut().map(|_| ())
    }

    fn analysis_mut(&mut self) -> Result<&mut Analysis, LinearError> {
        if self.analysis.is_none() {
            self.analysis = Some(Self::symbolic(&self.pattern, self.imposed, self.split)?);
        }
        Ok(self.analysis.as_mut().expect("made above"))
    }

    /// The symbolic factorisation under the cheaper of AMD and nested dissection, by the flop
    /// count of the factorisation ([`ordering::cholesky_flops`]), or with `split` of its critical
    /// path (the longer half and the separator, [`split::Split::critical_flops`]); AMD on a tie,
    /// below [`DISSECT_FROM`] unknowns, or when the dissection fails (with a warning on stderr).
    /// The choice depends on the pattern alone, never on the thread count.
    fn symbolic(
        pattern: &SymbolicSparseColMat<usize>,
        imposed: Option<Ordering>,
        split: bool,
    ) -> Result<Analysis, LinearError> {
        let setup = |e: faer::sparse::FaerError| LinearError::Setup(format!("{e:?}"));
        let n = pattern.nrows();
        let whole = |perm: Vec<usize>, ordering: Ordering| {
            Ok(Analysis {
                whole: Some(Whole::new(pattern, &perm)?),
                ordering,
                perm,
                split: None,
            })
        };
        if imposed == Some(Ordering::Amd) || imposed.is_none() && n < DISSECT_FROM {
            let amd = ordering::amd(pattern.as_ref()).map_err(setup)?;
            return whole(amd, Ordering::Amd);
        }
        // The two orderings are independent and deterministic: computed side by side on the
        // pool's threads (the result does not depend on how many there are), AMD's flop count
        // with it (METIS takes longer).
        let (amd, nd) = rayon::join(
            || {
                ordering::amd(pattern.as_ref())
                    .map(|p| (ordering::flops_under(pattern.as_ref(), &p), p))
            },
            || ordering::nested_dissection(n, pattern.col_ptr(), pattern.row_idx()),
        );
        let (amd_flops, amd) = amd.map_err(setup)?;
        let Some(nd) = nd else {
            eprintln!(
                "warning: nested dissection failed on a {n}-unknown pattern; ordering by AMD"
            );
            return whole(amd, Ordering::Amd);
        };
        if split {
            // Split at the top separator, the cost is the longer half's factorisation and the
            // separator's dense work, which the two threads do not share.
            if let Some(sp) = split::Split::new(pattern, &nd)? {
                if imposed == Some(Ordering::NestedDissection) || sp.critical_flops() < amd_flops {
                    return Ok(Analysis {
                        ordering: Ordering::NestedDissection,
                        perm: nd.perm,
                        whole: None,
                        split: Some(sp),
                    });
                }
                return whole(amd, Ordering::Amd);
            }
        }
        if imposed == Some(Ordering::NestedDissection)
            || ordering::flops_under(pattern.as_ref(), &nd.perm) < amd_flops
        {
            whole(nd.perm, Ordering::NestedDissection)
        } else {
            whole(amd, Ordering::Amd)
        }
    }

    /// The fill-reducing ordering the solver chose for its pattern (`None` before the
    /// analysis).
    pub fn ordering(&self) -> Option<Ordering> {
        self.analysis.as_ref().map(|a| a.ordering)
    }

    /// Floating-point operations of one numeric factorisation (Σ over columns of L of the squared
    /// column count; 0 before the analysis). Split at the top separator, those it performs: the
    /// two halves, each with the separator's trailing block, and the separator's dense
    /// factorisation.
    pub fn factor_flops(&self) -> f64 {
        self.analysis
            .as_ref()
            .map_or(0.0, |a| match (&a.split, &a.whole) {
                (Some(sp), _) => sp.flops(),
                (None, Some(w)) => symbolic_flops(&w.symbolic),
                (None, None) => 0.0,
            })
    }

    /// The numeric factorisations attempted so far, and the failed ones.
    pub fn counts(&self) -> FactorCounts {
        self.counts
    }

    /// Number of non-zeros in the factor L (0 before the analysis); split at the top
    /// separator, those of the two halves' factors and of the dense separator.
    pub fn factor_nnz(&self) -> usize {
        self.analysis.as_ref().map_or(0, |a| {
            a.split
                .as_ref()
                .map(|s| s.factor_nnz())
                .or(a.whole.as_ref().map(|w| w.symbolic.len_val()))
                .unwrap_or(0)
        })
    }

    /// Whether the factorisation is split at the top separator of a nested dissection.
    pub fn is_split(&self) -> bool {
        self.analysis.as_ref().is_some_and(|a| a.split.is_some())
    }

    /// The number of unknowns.
    pub fn unknowns(&self) -> usize {
        self.pattern.nrows()
    }

    /// Numeric factorisation of the matrix with the pattern's structure and these values.
    pub fn factor(&mut self, values: &[Real]) -> Result<(), LinearError> {
        self.kind = Kind::None;
        self.negative = 0;
        let r = if let Some(sp) = self.analysis_mut()?.split.as_mut() {
            sp.factor(values, false).map(|_| ())
        } else {
            let mut l = std::mem::take(&mut self.l_values);
            let r = self.numeric_into(values, &mut l, false);
            self.l_values = l;
            r
        };
        self.tally(r)?;
        self.kind = Kind::Llt;
        Ok(())
    }

    /// Counts a factorisation attempt and whether it failed, passing its result on.
    fn tally<T>(&mut self, r: Result<T, LinearError>) -> Result<T, LinearError> {
        self.counts.factorisations += 1;
        self.counts.failed += usize::from(r.is_err());
        r
    }

    /// The unsplit numeric factorisation into `l` (resized to the factor), not counted.
    fn numeric_into(
        &mut self,
        values: &[Real],
        l: &mut Vec<Real>,
        ldlt: bool,
    ) -> Result<(), LinearError> {
        self.analyse()?;
        let an = self.analysis.as_mut().expect("analysed above");
        // The unsplit symbolic factorisation, made on first use under the split.
        if an.whole.is_none() {
            an.whole = Some(Whole::new(&self.pattern, &an.perm)?);
        }
        let w = an.whole.as_mut().expect("made above");
        l.resize(w.symbolic.len_val(), 0.0);
        let a = SparseColMatRef::new(self.pattern.as_ref(), values);
        factorize_numeric(&w.symbolic, l, a, ldlt, &mut w.mem)
    }

    /// Numeric LDLᵀ factorisation (no pivoting) of a symmetric, possibly indefinite matrix with
    /// the pattern's structure; returns its number of negative eigenvalues (the negative
    /// pivots). An exactly zero pivot is an error. Without pivoting the factorisation is stable
    /// for matrices that are positive definite up to a few directions, which is what it serves
    /// (callers check their solves' results).
    pub fn factor_indefinite(&mut self, values: &[Real]) -> Result<usize, LinearError> {
        self.kind = Kind::None;
        let r = if let Some(sp) = self.analysis_mut()?.split.as_mut() {
            sp.factor(values, true)
        } else {
            let mut l = std::mem::take(&mut self.l_values);
            let r = self.numeric_into(values, &mut l, true);
            self.l_values = l;
            r.and_then(|()| {
                let d = self.ldlt_diagonal();
                match d.iter().position(|v| !v.is_finite()) {
                    Some(index) => Err(LinearError::ZeroPivot { index }),
                    None => Ok(d.iter().filter(|&&v| v < 0.0).count()),
                }
            })
        };
        self.negative = self.tally(r)?;
        self.kind = Kind::Ldlt;
        Ok(self.negative)
    }

    /// The pivots `D` of the last LDLᵀ factorisation, in the permuted order.
    fn ldlt_diagonal(&self) -> Vec<Real> {
        let l = &self.l_values;
        let Some(w) = self.analysis.as_ref().and_then(|an| an.whole.as_ref()) else {
            return Vec::new();
        };
        match w.symbolic.raw() {
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
    /// simplicial (the two store the LDLᵀ pivots differently). The split's halves are.
    pub fn is_supernodal(&self) -> bool {
        self.analysis.as_ref().is_some_and(|a| {
            a.split.is_some()
                || a.whole
                    .as_ref()
                    .is_some_and(|w| matches!(w.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)))
        })
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
        let r = self.numeric_into(values, l, false);
        self.tally(r)
    }

    /// Solves `A x = rhs` in place with a factor made by [`Self::factor_to`].
    pub fn solve_with(&mut self, l: &[Real], rhs: &mut [Real]) {
        let n = rhs.len();
        let Some(w) = self.analysis.as_mut().and_then(|an| an.whole.as_mut()) else {
            panic!("solve before a factorisation")
        };
        let llt = LltRef::new(&w.symbolic, l);
        let stack = MemStack::new(&mut w.mem);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            stack,
        );
    }

    /// Solves `A x = rhs` in place with the last successful factorisation. `rhs` may hold
    /// several right-hand sides one after another (its length a multiple of n): they are solved
    /// in one pass over the factor, which costs little more than one.
    pub fn solve_in_place(&mut self, rhs: &mut [Real]) {
        debug_assert!(
            self.kind != Kind::None,
            "solve before a successful factorisation"
        );
        let Some(an) = self.analysis.as_mut() else {
            panic!("solve before a factorisation")
        };
        let n = self.pattern.nrows();
        assert!(
            n > 0 && rhs.len().is_multiple_of(n),
            "right-hand sides of length {} for {n} unknowns",
            rhs.len()
        );
        if let Some(sp) = an.split.as_ref() {
            sp.solve_in_place(rhs);
            return;
        }
        let Some(w) = an.whole.as_mut() else {
            panic!("solve before a factorisation")
        };
        let k = rhs.len() / n;
        let mut wide =
            (k > 1).then(|| MemBuffer::new(w.symbolic.solve_in_place_scratch::<Real>(k, Par::Seq)));
        let stack = MemStack::new(wide.as_mut().unwrap_or(&mut w.mem));
        let rhs = MatMut::from_column_major_slice_mut(rhs, n, k);
        if self.kind == Kind::Ldlt {
            LdltRef::new(&w.symbolic, &self.l_values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                Par::Seq,
                stack,
            );
        } else {
            LltRef::new(&w.symbolic, &self.l_values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                Par::Seq,
                stack,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lower triangle of a k×k grid's 5-point Laplacian with 3 coupled unknowns per node,
    /// plus `shift` on the diagonal (positive definite for shift > 0): (n, col_ptr, row_idx,
    /// values).
    fn grid(k: usize, shift: Real) -> (usize, Vec<usize>, Vec<usize>, Vec<Real>) {
        let n = 3 * k * k;
        let mut cols: Vec<Vec<(usize, Real)>> = vec![Vec::new(); n];
        let node = |r: usize, c: usize| r * k + c;
        for r in 0..k {
            for c in 0..k {
                let p = node(r, c);
                let mut nb = Vec::new();
                if c + 1 < k {
                    nb.push(node(r, c + 1));
                }
                if r + 1 < k {
                    nb.push(node(r + 1, c));
                }
                for a in 0..3 {
                    let j = 3 * p + a;
                    cols[j].push((j, 4.0 + shift));
                    for b in a + 1..3 {
                        cols[j].push((3 * p + b, 0.5));
                    }
                    for &q in &nb {
                        for b in 0..3 {
                            cols[j].push((3 * q + b, if a == b { -1.0 } else { -0.1 }));
                        }
                    }
                }
            }
        }
        let (mut cp, mut ri, mut v) = (vec![0], Vec::new(), Vec::new());
        for mut c in cols {
            c.sort_by_key(|e| e.0);
            for (i, x) in c {
                ri.push(i);
                v.push(x);
            }
            cp.push(ri.len());
        }
        (n, cp, ri, v)
    }

    fn residual(n: usize, cp: &[usize], ri: &[usize], v: &[Real], x: &[Real], b: &[Real]) -> Real {
        let mut r = b.to_vec();
        for j in 0..n {
            for k in cp[j]..cp[j + 1] {
                let i = ri[k];
                r[i] -= v[k] * x[j];
                if i != j {
                    r[j] -= v[k] * x[i];
                }
            }
        }
        r.iter().fold(0.0, |m, e| m.max(e.abs()))
    }

    /// Asserts that `y` agrees with `x` entry by entry to `tol` × x's largest entry.
    fn assert_agree(x: &[Real], y: &[Real], tol: Real, what: &str) {
        let xmax = x.iter().fold(0.0, |m: Real, a| m.max(a.abs()));
        let d = x
            .iter()
            .zip(y)
            .fold(0.0, |m: Real, (a, c)| m.max((a - c).abs()));
        assert!(d <= tol * xmax, "{what}: {d} of {xmax}");
    }

    #[test]
    fn chooses_the_cheaper_ordering_and_solves_with_it() {
        let (n, cp, ri, v) = grid(84, 0.5);
        assert!(n >= DISSECT_FROM);
        let b: Vec<Real> = (0..n).map(|i| ((i * 7919) % 101) as Real - 50.0).collect();
        let mut flops = Vec::new();
        for imposed in [None, Some(Ordering::Amd), Some(Ordering::NestedDissection)] {
            let mut lin = LinearSolver::from_csc(n, cp.clone(), ri.clone()).expect("pattern");
            if let Some(o) = imposed {
                lin = lin.with_ordering(o);
            }
            lin.factor(&v).expect("positive definite");
            let mut x = b.clone();
            lin.solve_in_place(&mut x);
            let r = residual(n, &cp, &ri, &v, &x, &b);
            assert!(r < 1e-10 * 50.0, "{imposed:?}: residual {r}");
            flops.push((lin.ordering(), lin.factor_flops()));
        }
        // On a planar grid nested dissection needs fewer flops than AMD, and is chosen.
        assert!(flops[2].1 < flops[1].1, "{flops:?}");
        assert_eq!(flops[0], flops[2]);
        assert_eq!(flops[0].0, Some(Ordering::NestedDissection));
    }

    #[test]
    fn the_split_factorisation_solves_and_counts_negative_pivots_like_the_whole() {
        let (n, cp, ri, v) = grid(84, 0.5);
        let b: Vec<Real> = (0..n).map(|i| ((i * 7919) % 101) as Real - 50.0).collect();
        let mut whole = LinearSolver::from_csc(n, cp.clone(), ri.clone()).expect("pattern");
        let mut split = LinearSolver::from_csc(n, cp.clone(), ri.clone())
            .expect("pattern")
            .with_split();
        whole.factor(&v).expect("positive definite");
        split.factor(&v).expect("positive definite");
        assert!(split.is_split() && !whole.is_split());
        let (mut xw, mut xs) = (b.clone(), b.clone());
        whole.solve_in_place(&mut xw);
        split.solve_in_place(&mut xs);
        let r = residual(n, &cp, &ri, &v, &xs, &b);
        assert!(r < 1e-10 * 50.0, "split residual {r}");
        assert_agree(&xw, &xs, 1e-12, "split against whole");
        // Shifted into indefiniteness: the same inertia and solution by LDLᵀ (the shift keeps
        // clear of the spectrum, so no pivot is near zero), and LLᵀ refuses it.
        let mut ind = v.clone();
        for j in 0..n {
            ind[cp[j]] -= 1.2;
        }
        let nw = whole.factor_indefinite(&ind).expect("no zero pivot");
        let ns = split.factor_indefinite(&ind).expect("no zero pivot");
        assert!(nw > 0);
        assert_eq!(nw, ns);
        let (mut xw, mut xs) = (b.clone(), b.clone());
        whole.solve_in_place(&mut xw);
        split.solve_in_place(&mut xs);
        let r = residual(n, &cp, &ri, &ind, &xs, &b);
        let xmax = xs.iter().fold(0.0, |m: Real, a| m.max(a.abs()));
        assert!(
            r < 1e-9 * 50.0 * xmax.max(1.0),
            "indefinite split residual {r}"
        );
        assert!(split.factor(&ind).is_err());
        // Bitwise the same on one thread as on two.
        let mut on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut x = b.clone();
            pool.install(|| {
                split.factor(&v).expect("positive definite");
                split.solve_in_place(&mut x);
            });
            x
        };
        let (x1, x2) = (on(1), on(2));
        assert!(x1.iter().zip(&x2).all(|(a, c)| a.to_bits() == c.to_bits()));
    }

    #[test]
    fn the_split_makes_its_unsplit_factor_on_first_use_and_counts_its_own_flops() {
        let (n, cp, ri, v) = grid(84, 0.5);
        let b: Vec<Real> = (0..n).map(|i| ((i * 7919) % 101) as Real - 50.0).collect();
        let mut split = LinearSolver::from_csc(n, cp.clone(), ri.clone())
            .expect("pattern")
            .with_split()
            .with_ordering(Ordering::NestedDissection);
        split.analyse().expect("analysis");
        assert!(split.is_split() && split.is_supernodal());
        let an = split.analysis.as_ref().expect("analysed");
        assert!(
            an.whole.is_none(),
            "the split needs no unsplit symbolic factorisation"
        );
        // The flops it performs: more than the unsplit factorisation's under the same order
        // (the separator's dense work is done three times over), less than twice as many.
        let sp = an.split.as_ref().expect("split");
        let unsplit = ordering::flops_under(split.pattern.as_ref(), &an.perm);
        let f = split.factor_flops();
        assert_eq!(f, sp.flops());
        assert!(f > unsplit && f < 2.0 * unsplit, "{f} against {unsplit}");
        // factor_to and solve_with stay unsplit, and agree with the split solve.
        split.factor(&v).expect("positive definite");
        let mut xs = b.clone();
        split.solve_in_place(&mut xs);
        let mut l = Vec::new();
        split.factor_to(&v, &mut l).expect("positive definite");
        assert_eq!(
            l.len(),
            split
                .analysis
                .as_ref()
                .and_then(|a| a.whole.as_ref())
                .expect("made")
                .symbolic
                .len_val()
        );
        let mut xw = b.clone();
        split.solve_with(&l, &mut xw);
        let r = residual(n, &cp, &ri, &v, &xw, &b);
        assert!(r < 1e-10 * 50.0, "unsplit residual {r}");
        assert_agree(&xw, &xs, 1e-12, "split against whole");
        assert_eq!(split.counts().factorisations, 2);
    }

    #[test]
    fn several_right_hand_sides_solve_as_each_alone() {
        let (n, cp, ri, v) = grid(84, 0.5);
        let b1: Vec<Real> = (0..n).map(|i| ((i * 7919) % 101) as Real - 50.0).collect();
        let b2: Vec<Real> = (0..n)
            .map(|i| ((i * 104_729) % 37) as Real - 18.0)
            .collect();
        let mut ind = v.clone();
        for j in 0..n {
            ind[cp[j]] -= 1.2;
        }
        for split in [false, true] {
            let mut lin = LinearSolver::from_csc(n, cp.clone(), ri.clone()).expect("pattern");
            if split {
                lin = lin.with_split();
            }
            for indefinite in [false, true] {
                if indefinite {
                    lin.factor_indefinite(&ind).expect("no zero pivot");
                } else {
                    lin.factor(&v).expect("positive definite");
                }
                assert_eq!(lin.is_split(), split);
                let (mut x1, mut x2) = (b1.clone(), b2.clone());
                lin.solve_in_place(&mut x1);
                lin.solve_in_place(&mut x2);
                let mut both: Vec<Real> = b1.iter().chain(&b2).copied().collect();
                lin.solve_in_place(&mut both);
                let (y1, y2) = both.split_at(n);
                if split {
                    // The same sweeps per vector: bitwise.
                    assert!(x1
                        .iter()
                        .chain(&x2)
                        .zip(y1.iter().chain(y2))
                        .all(|(a, c)| a.to_bits() == c.to_bits()));
                } else {
                    // faer's blocked kernels may sum in another order: the difference is
                    // round-off times the condition number, larger for the matrix shifted
                    // towards its spectrum.
                    let tol = if indefinite { 1e-10 } else { 1e-12 };
                    for (x, y) in [(&x1, y1), (&x2, y2)] {
                        assert_agree(x, y, tol, &format!("indefinite {indefinite}"));
                    }
                }
            }
        }
    }

    #[test]
    fn small_systems_keep_amd_and_count_factorisations() {
        let (n, cp, ri, v) = grid(10, 0.5);
        let mut lin = LinearSolver::from_csc(n, cp, ri).expect("pattern");
        assert_eq!(lin.ordering(), None, "no analysis before it is needed");
        lin.factor(&v).expect("positive definite");
        let mut bad = v.clone();
        bad[0] = -1.0;
        assert!(lin.factor(&bad).is_err());
        assert_eq!(lin.ordering(), Some(Ordering::Amd));
        assert_eq!(
            lin.counts(),
            FactorCounts {
                factorisations: 2,
                failed: 1
            }
        );
    }
}
