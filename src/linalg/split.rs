//! The factorisation split at the top separator of a nested dissection, the two halves on two
//! threads (George 1973's one-level dissection, as a block elimination).
//!
//! With the unknowns ordered as the first half (1), the second (2) and the separator (3), no
//! entry joins 1 and 2:
//!
//! ```text
//!     A = | A11   0   A13 |      S = A33 − A31 A11⁻¹ A13 − A32 A22⁻¹ A23
//!         |  0   A22  A23 |
//!         | A31  A32  A33 |
//! ```
//!
//! Each half h factorises its own matrix `M_h = [A_hh A_h3; A_3h A33]` (a principal submatrix of
//! A, positive definite when A is) with faer's supernodal LLᵀ or LDLᵀ: its leading columns are
//! `L_hh` and `L_3h`, its trailing block `L_c` satisfies `L_c D_c L_cᵀ = A33 − L_3h D_h L_3hᵀ`.
//! So `S = S_1 + S_2 − A33` with `S_h = L_c D_c L_cᵀ`, dense, factorised densely. The inertia of
//! A is that of D_1, D_2 and S's pivots together (Sylvester's law on the block elimination).
//!
//! Solving `A x = b`: a forward sweep of each half's leading columns on `[b_h; 0]` gives
//! `y_h = L_hh⁻¹ b_h` and leaves `−L_3h y_h` in the separator rows; `S x3 = b3 − L_31 y_1 −
//! L_32 y_2`; a backward sweep of each half with x3 in its separator rows gives x_h. (LDLᵀ: unit
//! L, and the pivots divide between the sweeps.)
//!
//! The two halves run in parallel (`rayon::join`), the separator's dense work after them; the
//! arithmetic of each part is fixed, so the result does not depend on the thread count. It
//! costs the separator's dense factorisation three times over, negligible when the separator is
//! small against the halves (the teddy balloon: 495 of 32,676 unknowns).

use crate::math::Real;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Mat, Par, Side};

use super::ordering::Dissection;
use super::LinearError;

/// One half with the separator: its local lower-triangular matrix and factor.
struct Half {
    /// Unknowns of the half (the leading columns).
    nh: usize,
    /// Local unknown → original unknown (the half's, then the separator's).
    map: Vec<usize>,
    pattern: SymbolicSparseColMat<usize>,
    /// Local entry → entry of the original matrix's values.
    gather: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<Real>,
    l: Vec<Real>,
    mem: MemBuffer,
    /// `S_h = L_c D_c L_cᵀ` (ns × ns) of the last factorisation.
    schur: Mat<Real>,
    /// Negative pivots among the leading columns (LDLᵀ).
    negative: usize,
}

/// The split factorisation of one pattern.
pub(super) struct Split {
    halves: [Half; 2],
    /// Separator position → original unknown.
    sep: Vec<usize>,
    /// (row, column, original entry) of the separator block's lower triangle.
    a33: Vec<(usize, usize, usize)>,
    /// The dense factor of S (lower; LDLᵀ: unit L below, D on the diagonal).
    s: Mat<Real>,
    /// Scratch of S's dense LLᵀ or LDLᵀ, allocated once.
    dense_mem: MemBuffer,
    ldlt: bool,
}

/// The column of each supernodal factor entry: for every column j, its rows (local) and the
/// offset of its values.
fn for_each_column(
    symbolic: &SymbolicCholesky<usize>,
    mut f: impl FnMut(usize, &mut dyn Iterator<Item = (usize, usize)>),
) {
    let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
        unreachable!("the halves are supernodal")
    };
    let begin = s.supernode_begin();
    let end = s.supernode_end();
    let vp = s.col_ptr_for_val();
    for k in 0..s.n_supernodes() {
        let ncols = end[k] - begin[k];
        let pattern = s.supernode(k).pattern();
        let nrows = ncols + pattern.len();
        for jj in 0..ncols {
            let base = vp[k] + jj * nrows;
            let mut rows = (jj..nrows).map(|ii| {
                let row = if ii < ncols {
                    begin[k] + ii
                } else {
                    pattern[ii - ncols]
                };
                (row, base + ii)
            });
            f(begin[k] + jj, &mut rows);
        }
    }
}

impl Half {
    fn new(
        a: &SymbolicSparseColMat<usize>,
        map: Vec<usize>,
        nh: usize,
    ) -> Result<Self, LinearError> {
        let m = map.len();
        // Local index of each original unknown (usize::MAX: not in this half).
        let mut local = vec![usize::MAX; a.nrows()];
        for (k, &g) in map.iter().enumerate() {
            local[g] = k;
        }
        // The local lower triangle by two counting sorts, with no per-column lists and no
        // sorting: the entries bucketed by local row, then by local column taking the rows in
        // increasing order, which leaves every column's rows sorted. `gather` follows each
        // entry to its place in the original values.
        let (cp, ri, local) = (a.col_ptr(), a.row_idx(), &local);
        let entries = || {
            map.iter().flat_map(move |&j| {
                let lj = local[j];
                (cp[j]..cp[j + 1]).filter_map(move |e| {
                    let li = local[ri[e]];
                    (li != usize::MAX).then(|| (li.max(lj), li.min(lj), e))
                })
            })
        };
        let mut row_ptr = vec![0usize; m + 1];
        for (r, _, _) in entries() {
            row_ptr[r + 1] += 1;
        }
        for k in 0..m {
            row_ptr[k + 1] += row_ptr[k];
        }
        let nnz = row_ptr[m];
        // By rows: (column, original entry).
        let mut by_row = vec![(0usize, 0usize); nnz];
        let mut next = row_ptr.clone();
        for (r, c, e) in entries() {
            by_row[next[r]] = (c, e);
            next[r] += 1;
        }
        let mut col_ptr = vec![0usize; m + 1];
        for &(c, _) in &by_row {
            col_ptr[c + 1] += 1;
        }
        for k in 0..m {
            col_ptr[k + 1] += col_ptr[k];
        }
        let mut row_idx = vec![0usize; nnz];
        let mut gather = vec![0usize; nnz];
        let mut next = col_ptr.clone();
        for r in 0..m {
            for &(c, e) in &by_row[row_ptr[r]..row_ptr[r + 1]] {
                row_idx[next[c]] = r;
                gather[next[c]] = e;
                next[c] += 1;
            }
        }
        drop(by_row);
        // The symbolic factorisation in the local order as it stands (`Identity`), which faer
        // reads from the upper triangle: the transposed pattern, the lower one by rows (again
        // sorted, taking the columns in increasing order). The numeric factorisation then takes
        // the gathered lower triangle as it is, without permuting a copy of it first.
        let mut up_idx = vec![0usize; nnz];
        let mut next = row_ptr.clone();
        for c in 0..m {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                up_idx[next[r]] = c;
                next[r] += 1;
            }
        }
        let up_ptr = row_ptr;
        let upper = SymbolicSparseColMat::new_checked(m, m, up_ptr, None, up_idx);
        let pattern = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let symbolic = factorize_symbolic_cholesky(
            upper.as_ref(),
            Side::Upper,
            SymmetricOrdering::Identity,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<Real>(Par::Seq, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<Real>(Par::Seq, Default::default()),
        ]);
        let mem = MemBuffer::try_new(req).map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        let ns = m - nh;
        Ok(Half {
            nh,
            map,
            l: vec![0.0; symbolic.len_val()],
            values: vec![0.0; gather.len()],
            pattern,
            gather,
            symbolic,
            mem,
            schur: Mat::zeros(ns, ns),
            negative: 0,
        })
    }

    /// Factorises `M_h` from the original values and forms `S_h`.
    fn factor(&mut self, a: &[Real], ldlt: bool) -> Result<(), LinearError> {
        for (v, &e) in self.values.iter_mut().zip(&self.gather) {
            *v = a[e];
        }
        let m = SparseColMatRef::new(self.pattern.as_ref(), &self.values);
        super::factorize_numeric(&self.symbolic, &mut self.l, m, ldlt, &mut self.mem)?;
        // L_c (and D_c) of the trailing block, then S_h = L_c D_c L_cᵀ.
        let nh = self.nh;
        let ns = self.map.len() - nh;
        let mut lc = Mat::<Real>::zeros(ns, ns);
        let mut d = vec![1.0; ns];
        let mut negative = 0;
        let l = &self.l;
        let mut bad = false;
        for_each_column(&self.symbolic, |j, rows| {
            for (i, at) in rows {
                let v = l[at];
                if i == j && ldlt {
                    if !v.is_finite() {
                        bad = true;
                    }
                    if j < nh {
                        negative += usize::from(v < 0.0);
                    } else {
                        d[j - nh] = v;
                        lc[(j - nh, j - nh)] = 1.0;
                    }
                } else if j >= nh {
                    lc[(i - nh, j - nh)] = v;
                }
            }
        });
        if bad {
            return Err(LinearError::ZeroPivot { index: 0 });
        }
        self.negative = negative;
        let mut lcd = lc.clone();
        if ldlt {
            for (k, &dk) in d.iter().enumerate() {
                for i in 0..ns {
                    lcd[(i, k)] *= dk;
                }
            }
        }
        // Only the lower triangle of the symmetric product.
        use faer::linalg::matmul::triangular::{matmul, BlockStructure};
        matmul(
            self.schur.as_mut(),
            BlockStructure::TriangularLower,
            faer::Accum::Replace,
            lcd.as_ref(),
            BlockStructure::TriangularLower,
            lc.transpose(),
            BlockStructure::TriangularUpper,
            1.0,
            Par::Seq,
        );
        Ok(())
    }

    /// The forward sweep of the leading columns on `x`, `k` local vectors one after another
    /// (the separator rows start at 0 and end holding `−L_3h y_h`; LDLᵀ: then divided by the
    /// leading pivots).
    ///
    /// Per supernode (columns `b..e`, below them the rows `pattern`), column-major values: the
    /// triangular solve on `x[b..e]` by columns (contiguous updates), then `t = L_below x[b..e]`
    /// accumulated column by column into a dense buffer and scattered once, `x[pattern] −= t`.
    /// Each supernode serves all `k` vectors while its values are in cache: the sweep is bound by
    /// reading the factor, so k right-hand sides cost little more than one.
    fn forward(&self, x: &mut [Real], ldlt: bool) {
        let (nh, nl) = (self.nh, self.map.len());
        let l = &self.l;
        let SymbolicCholeskyRaw::Supernodal(s) = self.symbolic.raw() else {
            unreachable!("the halves are supernodal")
        };
        let (begin, end, vp) = (s.supernode_begin(), s.supernode_end(), s.col_ptr_for_val());
        let mut t: Vec<Real> = Vec::new();
        for k in 0..s.n_supernodes() {
            if begin[k] >= nh {
                break;
            }
            let (b, ncols) = (begin[k], end[k] - begin[k]);
            let pattern = s.supernode(k).pattern();
            let nrows = ncols + pattern.len();
            let nc = ncols.min(nh - b);
            let block = &l[vp[k]..vp[k] + ncols * nrows];
            for x in x.chunks_exact_mut(nl) {
                let xs = &mut x[b..b + ncols];
                for jj in 0..nc {
                    let col = &block[jj * nrows..jj * nrows + ncols];
                    if !ldlt {
                        xs[jj] /= col[jj];
                    }
                    let xj = xs[jj];
                    axpy(&mut xs[jj + 1..], &col[jj + 1..], -xj);
                }
                t.clear();
                t.resize(pattern.len(), 0.0);
                for jj in 0..nc {
                    axpy(&mut t, &block[jj * nrows + ncols..(jj + 1) * nrows], xs[jj]);
                }
                for (&row, v) in pattern.iter().zip(&t) {
                    x[row] -= v;
                }
            }
        }
        if ldlt {
            for k in 0..s.n_supernodes() {
                let ncols = end[k] - begin[k];
                let nrows = ncols + s.supernode(k).pattern().len();
                for jj in 0..ncols {
                    let j = begin[k] + jj;
                    if j < nh {
                        let d = l[vp[k] + jj * nrows + jj];
                        for x in x.chunks_exact_mut(nl) {
                            x[j] /= d;
                        }
                    }
                }
            }
        }
    }

    /// The backward sweep of the leading columns on `k` local vectors (separator rows hold x3).
    ///
    /// Per supernode, last first: `x[pattern]` gathered into a dense buffer, then each column's
    /// `x_j = (x_j − L_belowᵀ t − L_blockᵀ x[j+1..e]) / L_jj` by contiguous dot products.
    fn backward(&self, x: &mut [Real], ldlt: bool) {
        let (nh, nl) = (self.nh, self.map.len());
        let l = &self.l;
        let SymbolicCholeskyRaw::Supernodal(s) = self.symbolic.raw() else {
            unreachable!("the halves are supernodal")
        };
        let (begin, end, vp) = (s.supernode_begin(), s.supernode_end(), s.col_ptr_for_val());
        let mut t: Vec<Real> = Vec::new();
        for k in (0..s.n_supernodes()).rev() {
            if begin[k] >= nh {
                continue;
            }
            let (b, ncols) = (begin[k], end[k] - begin[k]);
            let pattern = s.supernode(k).pattern();
            let nrows = ncols + pattern.len();
            let nc = ncols.min(nh - b);
            let block = &l[vp[k]..vp[k] + ncols * nrows];
            for x in x.chunks_exact_mut(nl) {
                t.clear();
                t.extend(pattern.iter().map(|&row| x[row]));
                let xs = &mut x[b..b + ncols];
                for jj in (0..nc).rev() {
                    let col = &block[jj * nrows..(jj + 1) * nrows];
                    let acc =
                        xs[jj] - dot(&col[ncols..], &t) - dot(&col[jj + 1..ncols], &xs[jj + 1..]);
                    xs[jj] = if ldlt { acc } else { acc / col[jj] };
                }
            }
        }
    }
}

/// `y += a x`, four lanes at a time (the order of each entry's operations is fixed).
fn axpy(y: &mut [Real], x: &[Real], a: Real) {
    let n = y.len().min(x.len());
    let (y, x) = (&mut y[..n], &x[..n]);
    let mut yc = y.chunks_exact_mut(4);
    let mut xc = x.chunks_exact(4);
    for (yy, xx) in (&mut yc).zip(&mut xc) {
        yy[0] += a * xx[0];
        yy[1] += a * xx[1];
        yy[2] += a * xx[2];
        yy[3] += a * xx[3];
    }
    for (yy, xx) in yc.into_remainder().iter_mut().zip(xc.remainder()) {
        *yy += a * xx;
    }
}

/// `Σ a_i b_i` with four partial sums (a fixed order, so the same on any thread).
fn dot(a: &[Real], b: &[Real]) -> Real {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; 4];
    let mut ac = a.chunks_exact(4);
    let mut bc = b.chunks_exact(4);
    for (x, y) in (&mut ac).zip(&mut bc) {
        acc[0] += x[0] * y[0];
        acc[1] += x[1] * y[1];
        acc[2] += x[2] * y[2];
        acc[3] += x[3] * y[3];
    }
    let mut tail = 0.0;
    for (x, y) in ac.remainder().iter().zip(bc.remainder()) {
        tail += x * y;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

impl Split {
    /// The split of pattern `a` at the dissection's top separator; `None` when a part is empty.
    pub(super) fn new(
        a: &SymbolicSparseColMat<usize>,
        d: &Dissection,
    ) -> Result<Option<Self>, LinearError> {
        let [n0, n1, ns] = d.sizes;
        if n0 == 0 || n1 == 0 || ns == 0 {
            return Ok(None);
        }
        let sep: Vec<usize> = d.perm[n0 + n1..].to_vec();
        let half = |range: std::ops::Range<usize>| {
            let nh = range.len();
            let map: Vec<usize> = d.perm[range].iter().chain(&sep).copied().collect();
            Half::new(a, map, nh)
        };
        let (h0, h1) = rayon::join(|| half(0..n0), || half(n0..n0 + n1));
        let halves = [h0?, h1?];
        let mut spos = vec![usize::MAX; a.nrows()];
        for (k, &g) in sep.iter().enumerate() {
            spos[g] = k;
        }
        let mut a33 = Vec::new();
        for j in 0..a.ncols() {
            if spos[j] == usize::MAX {
                continue;
            }
            for e in a.col_ptr()[j]..a.col_ptr()[j + 1] {
                let i = a.row_idx()[e];
                if spos[i] != usize::MAX {
                    let (r, c) = (spos[i].max(spos[j]), spos[i].min(spos[j]));
                    a33.push((r, c, e));
                }
            }
        }
        use faer::linalg::cholesky::{ldlt, llt};
        let dense_mem = MemBuffer::try_new(StackReq::any_of(&[
            ldlt::factor::cholesky_in_place_scratch::<Real>(ns, Par::Seq, Default::default()),
            llt::factor::cholesky_in_place_scratch::<Real>(ns, Par::Seq, Default::default()),
        ]))
        .map_err(|e| LinearError::Setup(format!("{e:?}")))?;
        Ok(Some(Split {
            halves,
            sep,
            a33,
            s: Mat::zeros(ns, ns),
            dense_mem,
            ldlt: false,
        }))
    }

    /// Flops on the critical path of a factorisation on two threads: the longer half's sparse
    /// factorisation (Σ c², [`super::symbolic_flops`]) and the separator's dense work (the
    /// product `L_c L_cᵀ`, about ns³/3 multiply-adds, then the dense Cholesky of S, ns³/3).
    pub(super) fn critical_flops(&self) -> f64 {
        let ns = self.sep.len() as f64;
        let halves = self
            .halves
            .iter()
            .map(|h| super::symbolic_flops(&h.symbolic))
            .fold(0.0, f64::max);
        halves + 2.0 * ns * ns * ns / 3.0
    }

    /// Flops of one factorisation as the split performs it: the two halves (each with the
    /// separator's trailing block, Σ c² over their columns) and the separator's dense
    /// factorisation (Σ c² over its columns, about ns³/3).
    pub(super) fn flops(&self) -> f64 {
        let ns = self.sep.len();
        self.halves
            .iter()
            .map(|h| super::symbolic_flops(&h.symbolic))
            .sum::<f64>()
            + super::ordering::cholesky_flops((1..=ns).rev())
    }

    /// Non-zeros of the two halves' factors and the dense separator's lower triangle.
    pub(super) fn factor_nnz(&self) -> usize {
        let ns = self.sep.len();
        self.halves.iter().map(|h| h.l.len()).sum::<usize>() + ns * (ns + 1) / 2
    }

    /// Factorises A (values in the original pattern's order): LLᵀ, or LDLᵀ without pivoting
    /// returning the negative pivots.
    pub(super) fn factor(&mut self, a: &[Real], ldlt: bool) -> Result<usize, LinearError> {
        self.ldlt = ldlt;
        let [h0, h1] = &mut self.halves;
        let (r0, r1) = rayon::join(|| h0.factor(a, ldlt), || h1.factor(a, ldlt));
        r0?;
        r1?;
        let ns = self.sep.len();
        // S = S_1 + S_2 − A33 (lower triangle).
        for j in 0..ns {
            for i in j..ns {
                self.s[(i, j)] = h0.schur[(i, j)] + h1.schur[(i, j)];
            }
        }
        for &(r, c, e) in &self.a33 {
            self.s[(r, c)] -= a[e];
        }
        let stack = MemStack::new(&mut self.dense_mem);
        let negative = if ldlt {
            faer::linalg::cholesky::ldlt::factor::cholesky_in_place(
                self.s.as_mut(),
                LdltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )?;
            let d: Vec<Real> = (0..ns).map(|k| self.s[(k, k)]).collect();
            if d.iter().any(|v| !v.is_finite()) {
                return Err(LinearError::ZeroPivot { index: 0 });
            }
            d.iter().filter(|&&v| v < 0.0).count() + h0.negative + h1.negative
        } else {
            faer::linalg::cholesky::llt::factor::cholesky_in_place(
                self.s.as_mut(),
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )?;
            0
        };
        Ok(negative)
    }

    /// Solves `A X = B` in place with the last factorisation, `rhs` holding the columns of B
    /// one after another (its length a multiple of n).
    pub(super) fn solve_in_place(&self, rhs: &mut [Real]) {
        let ldlt = self.ldlt;
        let ns = self.sep.len();
        let n = self.halves[0].nh + self.halves[1].nh + ns;
        let nrhs = rhs.len() / n;
        let local = |h: &Half| {
            let nl = h.map.len();
            let mut x = vec![0.0; nl * nrhs];
            for (x, b) in x.chunks_exact_mut(nl).zip(rhs.chunks_exact(n)) {
                for k in 0..h.nh {
                    x[k] = b[h.map[k]];
                }
            }
            h.forward(&mut x, ldlt);
            x
        };
        let [h0, h1] = &self.halves;
        let (mut x0, mut x1) = rayon::join(|| local(h0), || local(h1));
        let (nl0, nl1) = (h0.map.len(), h1.map.len());
        let s = &self.s;
        let mut x3s = Vec::with_capacity(nrhs * ns);
        for r in 0..nrhs {
            // r3 = b3 − L31 y1 − L32 y2, then x3 = S⁻¹ r3 by the dense factor.
            let b = &rhs[r * n..(r + 1) * n];
            let mut x3: Vec<Real> = (0..ns)
                .map(|k| b[self.sep[k]] + x0[r * nl0 + h0.nh + k] + x1[r * nl1 + h1.nh + k])
                .collect();
            for j in 0..ns {
                if !ldlt {
                    x3[j] /= s[(j, j)];
                }
                let xj = x3[j];
                for i in j + 1..ns {
                    x3[i] -= s[(i, j)] * xj;
                }
            }
            if ldlt {
                for (j, v) in x3.iter_mut().enumerate() {
                    *v /= s[(j, j)];
                }
            }
            for j in (0..ns).rev() {
                let mut acc = x3[j];
                for i in j + 1..ns {
                    acc -= s[(i, j)] * x3[i];
                }
                x3[j] = if ldlt { acc } else { acc / s[(j, j)] };
            }
            x0[r * nl0 + h0.nh..(r + 1) * nl0].copy_from_slice(&x3);
            x1[r * nl1 + h1.nh..(r + 1) * nl1].copy_from_slice(&x3);
            x3s.extend_from_slice(&x3);
        }
        rayon::join(|| h0.backward(&mut x0, ldlt), || h1.backward(&mut x1, ldlt));
        for (r, b) in rhs.chunks_exact_mut(n).enumerate() {
            for (h, x) in [(h0, &x0[r * nl0..]), (h1, &x1[r * nl1..])] {
                for k in 0..h.nh {
                    b[h.map[k]] = x[k];
                }
            }
            for (k, &g) in self.sep.iter().enumerate() {
                b[g] = x3s[r * ns + k];
            }
        }
    }
}
