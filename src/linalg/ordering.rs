//! Fill-reducing orderings of a symmetric sparsity pattern: METIS's multilevel nested
//! dissection (George 1973; Karypis & Kumar, SIAM J. Sci. Comput. 20, 1998), on the graph of the
//! pattern with indistinguishable unknowns merged, and the cost model that chooses between it and
//! faer's approximate minimum degree.
//!
//! A shell's Hessian has three unknowns per vertex with the same neighbours (and one per edge for
//! the edge-DOF bending model). Consecutive unknowns whose closed neighbourhoods coincide form one
//! graph node, weighted by their number; the ordering keeps each such group together, in its
//! original internal order, which also makes the factor's supernodes line up with vertices.
//!
//! METIS runs single-threaded with a fixed seed: the ordering is a function of the pattern alone,
//! identical across runs and thread counts.

use std::os::raw::c_int;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::simplicial::{
    prefactorize_symbolic_cholesky, prefactorize_symbolic_cholesky_scratch,
};
use faer::sparse::{FaerError, SymbolicSparseColMat, SymbolicSparseColMatRef};
use metis_sys as m;

/// A permutation with its top-level split: `perm[k]` is the original unknown placed at position
/// `k`; positions `0..sizes[0]` are the first half, the next `sizes[1]` the second half, and the
/// last `sizes[2]` the separator that decouples them (no entry of the matrix joins the halves).
#[derive(Clone, Debug)]
pub struct Dissection {
    /// New position → original unknown.
    pub perm: Vec<usize>,
    /// Unknowns in the first half, the second half and the top separator.
    pub sizes: [usize; 3],
}

/// The symmetric adjacency (no diagonal) of a lower-triangular CSC pattern, per unknown.
fn adjacency(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut count = vec![0usize; n + 1];
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            if i != j {
                count[i + 1] += 1;
                count[j + 1] += 1;
            }
        }
    }
    for k in 0..n {
        count[k + 1] += count[k];
    }
    let ptr = count.clone();
    let mut next = count;
    let mut adj = vec![0usize; ptr[n]];
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            if i != j {
                adj[next[j]] = i;
                next[j] += 1;
                adj[next[i]] = j;
                next[i] += 1;
            }
        }
    }
    for j in 0..n {
        adj[ptr[j]..ptr[j + 1]].sort_unstable();
    }
    (ptr, adj)
}

/// The closed neighbourhood `adj(a) ∪ {a}` of unknown `a`, sorted.
fn closed(ptr: &[usize], adj: &[usize], a: usize) -> Vec<usize> {
    let nb = &adj[ptr[a]..ptr[a + 1]];
    let at = nb.partition_point(|&x| x < a);
    let mut v = Vec::with_capacity(nb.len() + 1);
    v.extend_from_slice(&nb[..at]);
    v.push(a);
    v.extend_from_slice(&nb[at..]);
    v
}

/// The pattern's graph with consecutive indistinguishable unknowns merged: `start[g]..start[g+1]`
/// are group g's unknowns, and (xadj, adjncy, vwgt) its METIS graph.
struct Compressed {
    start: Vec<usize>,
    xadj: Vec<m::idx_t>,
    adjncy: Vec<m::idx_t>,
    vwgt: Vec<m::idx_t>,
}

fn compress(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Option<Compressed> {
    let (ptr, adj) = adjacency(n, col_ptr, row_idx);
    let mut start = Vec::with_capacity(n + 1);
    let mut group = vec![0usize; n];
    let mut j = 0;
    while j < n {
        start.push(j);
        let g = start.len() - 1;
        group[j] = g;
        let first = closed(&ptr, &adj, j);
        let mut k = j + 1;
        while k < n && ptr[k + 1] - ptr[k] + 1 == first.len() && closed(&ptr, &adj, k) == first {
            group[k] = g;
            k += 1;
        }
        j = k;
    }
    start.push(n);
    let ng = start.len() - 1;
    let idx = |v: usize| m::idx_t::try_from(v).ok();
    let mut xadj = Vec::with_capacity(ng + 1);
    let mut adjncy = Vec::new();
    let mut vwgt = Vec::with_capacity(ng);
    xadj.push(0);
    for g in 0..ng {
        let first = start[g];
        let mut last = usize::MAX;
        for &i in &adj[ptr[first]..ptr[first + 1]] {
            let h = group[i];
            // Sorted neighbours map to non-decreasing groups: duplicates are consecutive.
            if h != g && h != last {
                adjncy.push(idx(h)?);
                last = h;
            }
        }
        xadj.push(idx(adjncy.len())?);
        vwgt.push(idx(start[g + 1] - first)?);
    }
    Some(Compressed {
        start,
        xadj,
        adjncy,
        vwgt,
    })
}

/// METIS's nested dissection of a lower-triangular CSC pattern (sorted rows, diagonal
/// included or not), with its top-level split. `None` when the graph is too large for METIS's
/// 32-bit indices, has no edges to dissect, or METIS reports an error.
pub fn nested_dissection(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Option<Dissection> {
    if n < 2 {
        return None;
    }
    let mut c = compress(n, col_ptr, row_idx)?;
    let ng = c.start.len() - 1;
    if c.adjncy.is_empty() || ng < 2 {
        return None;
    }
    let mut options = [0 as m::idx_t; m::METIS_NOPTIONS as usize];
    let mut perm = vec![0 as m::idx_t; ng];
    let mut iperm = vec![0 as m::idx_t; ng];
    let mut sizes = [0 as m::idx_t; 3];
    let status: c_int;
    // METIS keeps its random generator in global state, seeded at each call: calls are
    // serialised so that concurrent ones (a sweep's scenes, parallel tests) cannot interleave
    // their draws and each ordering stays a function of its pattern.
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = METIS.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the arrays are METIS's documented inputs for a graph of `ng` vertices: xadj has
    // ng + 1 offsets into adjncy, adjncy holds valid vertex numbers without self-loops (each
    // edge stored from both ends, as `adjacency` builds it), vwgt has ng positive weights; perm
    // and iperm have ng entries and sizes 2·npes − 1 = 3; options is METIS_NOPTIONS long and
    // set to defaults before use. METIS keeps no pointer past the call.
    unsafe {
        m::METIS_SetDefaultOptions(options.as_mut_ptr());
        options[m::moptions_et_METIS_OPTION_NUMBERING as usize] = 0;
        options[m::moptions_et_METIS_OPTION_SEED as usize] = 1;
        // The graph is compressed already.
        options[m::moptions_et_METIS_OPTION_COMPRESS as usize] = 0;
        status = m::METIS_NodeNDP(
            m::idx_t::try_from(ng).ok()?,
            c.xadj.as_mut_ptr(),
            c.adjncy.as_mut_ptr(),
            c.vwgt.as_mut_ptr(),
            2,
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
            sizes.as_mut_ptr(),
        );
    }
    if status != m::rstatus_et_METIS_OK {
        return None;
    }
    // `perm[k]` is the group at position k; expand groups in their internal order.
    let mut out = Vec::with_capacity(n);
    let mut seen = vec![false; ng];
    for &g in &perm {
        let g = usize::try_from(g).ok().filter(|&g| g < ng)?;
        if std::mem::replace(&mut seen[g], true) {
            return None;
        }
        out.extend(c.start[g]..c.start[g + 1]);
    }
    let sizes = sizes.map(|s| usize::try_from(s).unwrap_or(usize::MAX));
    if out.len() != n || sizes.iter().try_fold(0usize, |a, &s| a.checked_add(s)) != Some(n) {
        return None;
    }
    Some(Dissection { perm: out, sizes })
}

/// Floating-point operations of a Cholesky factorisation with these column counts of L
/// (diagonal included): Σ c², the multiply-adds of the column updates.
pub fn cholesky_flops(column_counts: impl Iterator<Item = usize>) -> f64 {
    column_counts.map(|c| (c as f64) * (c as f64)).sum()
}

/// The inverse of a permutation.
pub fn inverse(perm: &[usize]) -> Vec<usize> {
    let mut inv = vec![0; perm.len()];
    for (k, &p) in perm.iter().enumerate() {
        inv[p] = k;
    }
    inv
}

/// The upper triangle of `P A Pᵀ` (position `k` holds unknown `perm[k]`) as a CSC pattern, from
/// the lower triangle of A (rows unsorted within a column).
fn upper_permuted(
    a: SymbolicSparseColMatRef<'_, usize>,
    perm: &[usize],
) -> SymbolicSparseColMat<usize> {
    let n = a.nrows();
    let inv = inverse(perm);
    let mut count = vec![0usize; n + 1];
    for j in 0..n {
        for &i in a.row_idx_of_col_raw(j) {
            count[inv[i].max(inv[j]) + 1] += 1;
        }
    }
    for k in 0..n {
        count[k + 1] += count[k];
    }
    let col_ptr = count.clone();
    let mut next = count;
    let mut row_idx = vec![0usize; col_ptr[n]];
    for j in 0..n {
        for &i in a.row_idx_of_col_raw(j) {
            let (r, c) = (inv[i].min(inv[j]), inv[i].max(inv[j]));
            row_idx[next[c]] = r;
            next[c] += 1;
        }
    }
    for c in 0..n {
        row_idx[col_ptr[c]..col_ptr[c + 1]].sort_unstable();
    }
    SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx)
}

/// Flops of the Cholesky factorisation of `P A Pᵀ` ([`cholesky_flops`]), from the column counts
/// of its elimination tree (Gilbert, Ng & Peyton 1994, as faer computes them): a fraction of
/// the cost of the symbolic factorisation, so that orderings can be compared before it.
pub fn flops_under(a: SymbolicSparseColMatRef<'_, usize>, perm: &[usize]) -> f64 {
    let n = a.nrows();
    let upper = upper_permuted(a, perm);
    let mut etree = vec![0isize; n];
    let mut counts = vec![0usize; n];
    let mut mem = MemBuffer::new(prefactorize_symbolic_cholesky_scratch::<usize>(
        n,
        upper.compute_nnz(),
    ));
    prefactorize_symbolic_cholesky(
        &mut etree,
        &mut counts,
        upper.as_ref(),
        MemStack::new(&mut mem),
    );
    cholesky_flops(counts.into_iter())
}

/// faer's approximate minimum degree ordering of a lower-triangular pattern (Amestoy, Davis &
/// Duff 1996): `perm[k]` is the unknown at position `k`.
pub fn amd(a: SymbolicSparseColMatRef<'_, usize>) -> Result<Vec<usize>, FaerError> {
    let n = a.nrows();
    let identity: Vec<usize> = (0..n).collect();
    let upper = upper_permuted(a, &identity);
    let mut perm = vec![0usize; n];
    let mut inv = vec![0usize; n];
    let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n, upper.compute_nnz()))
        .map_err(|_| FaerError::OutOfMemory)?;
    amd::order(
        &mut perm,
        &mut inv,
        upper.as_ref(),
        amd::Control::default(),
        MemStack::new(&mut mem),
    )?;
    Ok(perm)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lower-triangular CSC of a k×k grid's 5-point Laplacian with `b` unknowns per node (all
    /// coupled), nodes in row-major order.
    fn grid(k: usize, b: usize) -> (usize, Vec<usize>, Vec<usize>) {
        let nodes = k * k;
        let n = nodes * b;
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); n];
        let node = |r: usize, c: usize| r * k + c;
        for r in 0..k {
            for c in 0..k {
                let p = node(r, c);
                let mut nb = vec![p];
                if c + 1 < k {
                    nb.push(node(r, c + 1));
                }
                if r + 1 < k {
                    nb.push(node(r + 1, c));
                }
                for &q in &nb {
                    for a in 0..b {
                        for d in 0..b {
                            let (i, j) = (q * b + a, p * b + d);
                            if i >= j {
                                cols[j].push(i);
                            }
                        }
                    }
                }
            }
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for mut c in cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend(c);
            col_ptr.push(row_idx.len());
        }
        (n, col_ptr, row_idx)
    }

    #[test]
    fn groups_the_unknowns_of_a_node() {
        let (n, cp, ri) = grid(6, 3);
        let c = compress(n, &cp, &ri).expect("compressible");
        assert_eq!(c.start.len() - 1, 36);
        assert!(c.vwgt.iter().all(|&w| w == 3));
    }

    #[test]
    fn is_a_permutation_with_a_separating_split() {
        let (n, cp, ri) = grid(20, 3);
        let d = nested_dissection(n, &cp, &ri).expect("ordering");
        let mut seen = vec![false; n];
        for &p in &d.perm {
            assert!(!seen[p]);
            seen[p] = true;
        }
        assert_eq!(d.sizes.iter().sum::<usize>(), n);
        assert!(d.sizes[0] > 0 && d.sizes[1] > 0 && d.sizes[2] > 0);
        // The separator of a 20×20 grid is about one grid line: far below the halves.
        assert!(d.sizes[2] <= 3 * 25, "separator {}", d.sizes[2]);
        // No matrix entry joins the two halves.
        let mut pos = vec![0; n];
        for (k, &p) in d.perm.iter().enumerate() {
            pos[p] = k;
        }
        let part = |i: usize| {
            let k = pos[i];
            if k < d.sizes[0] {
                0
            } else if k < d.sizes[0] + d.sizes[1] {
                1
            } else {
                2
            }
        };
        for j in 0..n {
            for &i in &ri[cp[j]..cp[j + 1]] {
                let (a, b) = (part(i), part(j));
                assert!(!(a == 0 && b == 1 || a == 1 && b == 0), "{i}–{j} crosses");
            }
        }
    }

    #[test]
    fn identical_across_calls() {
        let (n, cp, ri) = grid(15, 3);
        let a = nested_dissection(n, &cp, &ri).expect("ordering");
        let b = nested_dissection(n, &cp, &ri).expect("ordering");
        assert_eq!(a.perm, b.perm);
        assert_eq!(a.sizes, b.sizes);
    }

    #[test]
    fn flops_from_column_counts_match_the_symbolic_factor() {
        use faer::sparse::linalg::cholesky::{
            factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholeskyRaw,
            SymmetricOrdering,
        };
        use faer::sparse::linalg::SupernodalThreshold;
        let (n, cp, ri) = grid(12, 3);
        let pattern = SymbolicSparseColMat::new_checked(n, n, cp.clone(), None, ri.clone());
        let nd = nested_dissection(n, &cp, &ri).expect("ordering");
        let amd = amd(pattern.as_ref()).expect("amd");
        for perm in [&nd.perm, &amd] {
            let inv = inverse(perm);
            let sym = factorize_symbolic_cholesky(
                pattern.as_ref(),
                faer::Side::Lower,
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(perm, &inv, n)),
                CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
                    ..Default::default()
                },
            )
            .expect("symbolic");
            let SymbolicCholeskyRaw::Simplicial(s) = sym.raw() else {
                panic!("simplicial forced")
            };
            let c = s.col_ptr();
            let exact = cholesky_flops((0..n).map(|j| c[j + 1] - c[j]));
            assert_eq!(flops_under(pattern.as_ref(), perm), exact);
        }
        // On a grid, nested dissection needs fewer flops than no reordering at all.
        let identity: Vec<usize> = (0..n).collect();
        assert!(flops_under(pattern.as_ref(), &nd.perm) < flops_under(pattern.as_ref(), &identity));
    }

    #[test]
    fn no_edges_no_dissection() {
        let n = 5;
        let cp: Vec<usize> = (0..=n).collect();
        let ri: Vec<usize> = (0..n).collect();
        assert!(nested_dissection(n, &cp, &ri).is_none());
    }
}
