//! The Hessian's sparsity pattern: the union of every term's stencil in compressed sparse
//! columns (lower triangle), with one [`ElementMap`] per term (where each element's entries go,
//! and the colouring of its element blocks). Built from stencils alone, so it sits below the
//! terms; [`crate::assembly`] builds it for a scene.

use super::is_absent;
use super::{block_size, colour_blocks, morton_order, node_dofs, ElementMap, Scratch, Stencil};
use crate::math::{Mat3, Real, Vec3};

/// The Hessian's sparsity pattern and, per term, where its elements' entries go.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of DOFs (3 × vertices + scalar DOFs).
    pub n: usize,
    /// Number of vertices.
    pub num_vertices: usize,
    /// Number of scalar DOFs: edge DOFs, then global DOFs (0 unless terms declare them).
    pub num_scalar_dofs: usize,
    /// CSC column pointers (lower triangle).
    pub col_ptr: Vec<usize>,
    /// CSC row indices.
    pub row_idx: Vec<usize>,
    /// One element map per term, in the scene's term order.
    pub maps: Vec<ElementMap>,
    /// Positions in the values of every entry in the row or column of a pinned DOF.
    pinned: Vec<usize>,
    /// The stored blocks in the rows or columns of a skew vertex ([`Pattern::project_skew`]).
    skew: Vec<SkewBlock>,
}

/// A stored block of the lower triangle between the rows of node `u` and the columns of node
/// `v` (`u ≥ v`), one of them a skew vertex: the positions of its entries (row-major, up to
/// 3 × 3, `NO_ENTRY` where the block has none: past a scalar node's one DOF, or above the
/// diagonal of a diagonal block).
#[derive(Clone, Debug)]
struct SkewBlock {
    u: u32,
    v: u32,
    pos: [[u32; 3]; 3],
}

const NO_ENTRY: u32 = u32::MAX;

impl Pattern {
    /// Whether `other` has the same entries (the union of the stencils), so that a symbolic
    /// factorisation of one serves the other.
    pub fn same_union(&self, other: &Pattern) -> bool {
        self.n == other.n && self.col_ptr == other.col_ptr && self.row_idx == other.row_idx
    }

    /// Builds the pattern of the vertices at `positions` (which only order the elements into
    /// spatially coherent blocks) and `ne` single-DOF nodes (edges, globals) from the stencils.
    pub fn build(positions: &[Vec3], ne: usize, stencils: &[Stencil]) -> Pattern {
        let nv = positions.len();
        let nodes = nv + ne;
        let mut hi: Vec<Vec<usize>> = vec![Vec::new(); nodes];
        for st in stencils {
            for el in st.nodes.chunks(st.slots().max(1)) {
                for &u in el {
                    for &v in el {
                        if !is_absent(u) && !is_absent(v) && u > v {
                            hi[v].push(u);
                        }
                    }
                }
            }
        }
        for h in &mut hi {
            h.sort_unstable();
            h.dedup();
        }
        let size = |u: usize| node_dofs(nv, u).1;
        // prefix[v][r]: DOFs of v's higher neighbours before the r-th.
        let prefix: Vec<Vec<u32>> = hi
            .iter()
            .map(|h| {
                let mut acc = 0u32;
                h.iter()
                    .map(|&u| {
                        let p = acc;
                        acc += size(u) as u32;
                        p
                    })
                    .collect()
            })
            .collect();
        let n = 3 * nv + ne;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (v, hv) in hi.iter().enumerate() {
            let (d0, kv) = node_dofs(nv, v);
            for d in 0..kv {
                for c in d..kv {
                    row_idx.push(d0 + c);
                }
                for &u in hv {
                    let (du, ku) = node_dofs(nv, u);
                    row_idx.extend(du..du + ku);
                }
                col_ptr.push(row_idx.len());
            }
        }
        let maps = stencils
            .iter()
            .map(|st| {
                let s = st.slots();
                let mut local = Vec::with_capacity(s);
                let mut acc = 0;
                for &k in &st.slot_dofs {
                    local.push(acc);
                    acc += k;
                }
                let mut offsets = vec![0u32; st.len() * s * s];
                for (e, el) in st.nodes.chunks(s.max(1)).enumerate() {
                    for a in 0..s {
                        for b in 0..s {
                            let (u, v) = (el[a], el[b]);
                            if !is_absent(u) && !is_absent(v) && u > v {
                                let rank = hi[v].binary_search(&u).unwrap_or(0);
                                offsets[e * s * s + s * a + b] = prefix[v][rank];
                            }
                        }
                    }
                }
                let morton = morton_order(&st.anchors, positions);
                let blocks: Vec<Vec<usize>> = morton
                    .chunks(block_size(morton.len()))
                    .map(|c| {
                        let mut b: Vec<usize> = c.iter().map(|&e| e as usize).collect();
                        b.sort_unstable();
                        b
                    })
                    .collect();
                let colours = colour_blocks(nodes, st, &blocks);
                ElementMap {
                    slots: s,
                    local,
                    nodes: st.nodes.clone(),
                    num_vertices: nv,
                    offsets,
                    colours,
                    num_nodes: nodes,
                    dofs: st.slot_dofs.iter().sum(),
                    morton,
                    scratch: Scratch::default(),
                }
            })
            .collect();
        Pattern {
            n,
            num_vertices: nv,
            num_scalar_dofs: ne,
            col_ptr,
            row_idx,
            maps,
            pinned: Vec::new(),
            skew: Vec::new(),
        }
    }

    /// Records the entries in the rows and columns of `dofs` (see [`Pattern::pinned_entries`]).
    pub fn pin(&mut self, dofs: &[usize]) {
        self.pinned.clear();
        let mut pinned = vec![false; self.n];
        for &d in dofs {
            pinned[d] = true;
        }
        for col in 0..self.n {
            for k in self.col_ptr[col]..self.col_ptr[col + 1] {
                if pinned[col] || pinned[self.row_idx[k]] {
                    self.pinned.push(k);
                }
            }
        }
    }

    /// Records the stored blocks in the rows and columns of the vertices `skew` (ascending),
    /// for [`Pattern::project_skew`].
    pub fn pin_skew(&mut self, skew: &[usize]) {
        self.skew.clear();
        if skew.is_empty() {
            return;
        }
        let nv = self.num_vertices;
        let node = |d: usize| {
            if d < 3 * nv {
                (d / 3, d % 3)
            } else {
                (d - 2 * nv, 0)
            }
        };
        let is_skew = |u: usize| u < nv && skew.binary_search(&u).is_ok();
        let mut index: std::collections::HashMap<(usize, usize), usize> = Default::default();
        for col in 0..self.n {
            let (v, j) = node(col);
            for k in self.col_ptr[col]..self.col_ptr[col + 1] {
                let (u, i) = node(self.row_idx[k]);
                if !(is_skew(u) || is_skew(v)) {
                    continue;
                }
                let b = *index.entry((u, v)).or_insert_with(|| {
                    self.skew.push(SkewBlock {
                        u: u as u32,
                        v: v as u32,
                        pos: [[NO_ENTRY; 3]; 3],
                    });
                    self.skew.len() - 1
                });
                self.skew[b].pos[i][j] = k as u32;
            }
        }
    }

    /// Applies the skew vertices' projectors to the Hessian `values`: every stored block
    /// `H_uv` becomes `T_u H_uv T_v`, `T` the projector `P` of a skew vertex (`proj`) and the
    /// identity elsewhere, and a skew vertex's diagonal block gains `scale (I − P)`, so that its
    /// held directions decouple with the pivot `scale`.
    pub fn project_skew(
        &self,
        values: &mut [Real],
        proj: &dyn Fn(usize) -> Option<Mat3>,
        scale: Real,
    ) {
        for b in &self.skew {
            let (u, v) = (b.u as usize, b.v as usize);
            let mut m = Mat3::zeros();
            for i in 0..3 {
                for j in 0..3 {
                    if b.pos[i][j] != NO_ENTRY {
                        m[(i, j)] = values[b.pos[i][j] as usize];
                    }
                }
            }
            if u == v {
                // The lower triangle of a symmetric block.
                for i in 0..3 {
                    for j in i + 1..3 {
                        m[(i, j)] = m[(j, i)];
                    }
                }
            }
            let (pu, pv) = (proj(u), proj(v));
            if let Some(p) = pu {
                m = p * m;
            }
            if let Some(p) = pv {
                m *= p;
            }
            if u == v {
                if let Some(p) = pu {
                    m += (Mat3::identity() - p) * scale;
                }
            }
            for i in 0..3 {
                for j in 0..3 {
                    if b.pos[i][j] != NO_ENTRY {
                        values[b.pos[i][j] as usize] = m[(i, j)];
                    }
                }
            }
        }
    }

    /// Positions of the entries in the rows and columns of the pinned DOFs.
    pub fn pinned_entries(&self) -> &[usize] {
        &self.pinned
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Position of the diagonal entry of DOF `i`.
    #[inline]
    pub fn diag(&self, i: usize) -> usize {
        self.col_ptr[i]
    }

    /// First DOF and number of DOFs of node `u`.
    #[inline]
    pub fn node_dofs(&self, u: usize) -> (usize, usize) {
        node_dofs(self.num_vertices, u)
    }

    /// The first term's map (the shell faces in every scene).
    pub fn faces(&self) -> &ElementMap {
        &self.maps[0]
    }

    /// Number of block colours of the shell faces.
    pub fn num_colours(&self) -> usize {
        self.faces().colours.len()
    }

    /// Blocks of shell faces by colour (no two blocks of a colour share a stencil node).
    pub fn colours(&self) -> &[Vec<Vec<usize>>] {
        &self.faces().colours
    }
}
