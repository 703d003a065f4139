//! The Hessian's sparsity pattern: the union of every term's stencil in compressed sparse
//! columns (lower triangle), with one [`ElementMap`] per term (where each element's entries go,
//! and the colouring of its element blocks). Built from stencils alone, so it sits below the
//! terms; [`crate::assembly`] builds it for a scene.

use super::{colour_blocks, morton_order, node_dofs, ElementMap, Scratch, Stencil, BLOCK};
use crate::math::Vec3;
use crate::mesh::topology::NONE;

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
}

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
                        if u != NONE && v != NONE && u > v {
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
                            if u != NONE && v != NONE && u > v {
                                let rank = hi[v].binary_search(&u).unwrap_or(0);
                                offsets[e * s * s + s * a + b] = prefix[v][rank];
                            }
                        }
                    }
                }
                let morton = morton_order(&st.anchors, positions);
                let blocks: Vec<Vec<usize>> = morton
                    .chunks(BLOCK)
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
