//! Global assembly of energy, gradient and sparse Hessian over the terms of a scene.
//!
//! DOFs are grouped in *nodes*: vertex `v` (node `v`) owns the 3 DOFs `3v..3v+3` (`x, y, z`);
//! with edge DOFs, edge `e` (node `nv + e`) owns the single DOF `3 nv + e`; the global DOFs
//! that terms declare follow as single-DOF nodes ([`crate::energy::term::GlobalDof`]). The
//! sparsity pattern
//! (lower triangle, compressed sparse columns) is the union of every term's stencil
//! ([`crate::energy::term::Stencil`]) and is built once per mesh, together with one
//! [`ElementMap`] per term: where each element's entries go, and a greedy colouring of blocks of
//! elements in which no two blocks of a colour share a stencil node.
//!
//! Terms are assembled in their registry order; within a term, colours are processed in order,
//! and within a colour, blocks are evaluated in parallel (rayon), each scattering its gradient and
//! Hessian directly into entries no other block of that colour touches. Every entry therefore
//! receives its contributions in a fixed order that does not depend on the threads: no
//! floating-point atomics, no per-thread accumulators, results bitwise identical for any number
//! of threads. Energies are stored per element and summed in fixed blocks along the elements'
//! Morton curve ([`ElementMap::sum_energies`]).

pub use crate::elements::{
    assemble_elements, assemble_elements_owned, ElementMap, OwnedNodes, Want, ENERGY_BLOCK,
};
use crate::elements::{colour_blocks, morton_order, node_dofs, Scratch, Stencil, BLOCK};
use crate::math::{Real, Vec3};
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
    /// The pattern of a scene: the union of its terms' stencils, edge DOFs when a term has them.
    pub fn for_scene(scene: &crate::scene::Scene) -> Pattern {
        let stencils: Vec<Stencil> = scene.terms.iter().map(|t| t.stencil(scene)).collect();
        let mut p = Self::build(&scene.mesh.positions, scene.num_scalar_dofs(), &stencils);
        p.pin(&scene.pinned_dofs);
        p
    }

    /// The pattern of `scene` at the state `(x, phi)` when a term's elements there
    /// ([`crate::energy::term::ChangingElements`]) differ from `self`'s; `None` when none do.
    /// The caller keeps its symbolic factorisation when the new pattern's union
    /// ([`Pattern::same_union`]) is unchanged.
    pub fn refreshed(
        &self,
        scene: &crate::scene::Scene,
        x: &[Vec3],
        phi: &[Real],
    ) -> Option<Pattern> {
        let mut changed = false;
        let fresh: Vec<Option<Stencil>> = scene
            .terms
            .iter()
            .zip(&self.maps)
            .map(|(t, map)| {
                let st = t.changing()?.stencil_at(scene, x, phi);
                changed |= st.nodes != map.nodes || st.slot_dofs.len() != map.slots;
                Some(st)
            })
            .collect();
        if !changed {
            return None;
        }
        let stencils: Vec<Stencil> = scene
            .terms
            .iter()
            .zip(fresh)
            .map(|(t, st)| st.unwrap_or_else(|| t.stencil(scene)))
            .collect();
        let mut p = Self::build(&scene.mesh.positions, scene.num_scalar_dofs(), &stencils);
        p.pin(&scene.pinned_dofs);
        Some(p)
    }

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
        for col in 0..self.n {
            for k in self.col_ptr[col]..self.col_ptr[col + 1] {
                if dofs.contains(&col) || dofs.contains(&self.row_idx[k]) {
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
