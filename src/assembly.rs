//! Global assembly of energy, gradient and sparse Hessian over the terms of a scene.
//!
//! DOFs are grouped in *nodes*: vertex `v` (node `v`) owns the 3 DOFs `3v..3v+3` (`x, y, z`);
//! with edge DOFs, edge `e` (node `nv + e`) owns the single DOF `3 nv + e`. The sparsity pattern
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
//! of threads. Energies are stored per element and summed in element order.

use crate::energy::projection::{project, HessianProjection};
use crate::energy::term::Stencil;
use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use rayon::prelude::*;

/// The Hessian's sparsity pattern and, per term, where its elements' entries go.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of DOFs (3 × vertices + edge DOFs).
    pub n: usize,
    /// Number of vertices.
    pub num_vertices: usize,
    /// Number of edge DOFs (0 unless a term declares them).
    pub num_edge_dofs: usize,
    /// CSC column pointers (lower triangle).
    pub col_ptr: Vec<usize>,
    /// CSC row indices.
    pub row_idx: Vec<usize>,
    /// One element map per term, in the scene's term order.
    pub maps: Vec<ElementMap>,
    /// Positions in the values of every entry in the row or column of a pinned DOF.
    pinned: Vec<usize>,
}

/// Where one term's element entries go in the global pattern, and its colouring.
#[derive(Clone, Debug)]
pub struct ElementMap {
    /// Slots per element.
    pub slots: usize,
    /// Local DOF offset of each slot in the element vector.
    pub local: Vec<usize>,
    /// Node ids, `elements × slots` (`NONE` where absent).
    pub nodes: Vec<usize>,
    /// Number of vertices (nodes below it are vertices with 3 DOFs, above it edges with 1).
    num_vertices: usize,
    /// Per element and slot pair (s, t) with node `u_s > u_t`: offset of `u_s`'s rows among the
    /// rows of `u_t`'s columns below its own diagonal block.
    offsets: Vec<u32>,
    /// Blocks of elements grouped by colour; blocks of one colour share no stencil node.
    colours: Vec<Vec<Vec<usize>>>,
    /// The gradient's gather: for node u, `gather[gather_ptr[u]..gather_ptr[u + 1]]` lists
    /// where its entries sit in the per-element gradient buffer (element × `stride` + the slot's
    /// local offset), in element order.
    gather_ptr: Vec<usize>,
    gather: Vec<u32>,
    /// Per-element stride of that buffer: the element's DOFs plus its energy.
    stride: usize,
    /// Reused storage of the per-element gradients (`elements × N`).
    scratch: Scratch,
}

/// A reusable buffer behind a lock (cloning gives an empty one).
#[derive(Debug, Default)]
struct Scratch(std::sync::Mutex<Vec<Real>>);

impl Clone for Scratch {
    fn clone(&self) -> Self {
        Scratch::default()
    }
}

/// Elements per block: large enough for cache locality and cheap scheduling, small enough that
/// a colour holds many blocks.
pub const BLOCK: usize = 256;

/// First DOF and number of DOFs of node `u` when nodes below `nv` are vertices.
#[inline(always)]
fn node_dofs(nv: usize, u: usize) -> (usize, usize) {
    if u < nv {
        (3 * u, 3)
    } else {
        (3 * nv + (u - nv), 1)
    }
}

impl Pattern {
    /// The pattern of a scene: the union of its terms' stencils, edge DOFs when a term has them.
    pub fn for_scene(scene: &crate::scene::Scene) -> Pattern {
        let stencils: Vec<Stencil> = scene.terms.iter().map(|t| t.stencil(scene)).collect();
        let mut p = Self::build(&scene.mesh.positions, scene.num_edge_dofs(), &stencils);
        p.pin(&scene.pinned_dofs);
        p
    }

    /// Builds the pattern of the vertices at `positions` (which only order the elements into
    /// spatially coherent blocks) and `ne` edge nodes from the stencils.
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
                let colours = colour_blocks(nodes, st, &morton_blocks(&st.anchors, positions));
                let mut count = vec![0usize; nodes + 1];
                for &u in &st.nodes {
                    if u != NONE {
                        count[u + 1] += 1;
                    }
                }
                for u in 0..nodes {
                    count[u + 1] += count[u];
                }
                let gather_ptr = count.clone();
                let stride = st.slot_dofs.iter().sum::<usize>() + 1;
                let mut gather = vec![0u32; st.nodes.len()];
                for (k, &u) in st.nodes.iter().enumerate() {
                    if u != NONE {
                        let (e, slot) = (k / s.max(1), k % s.max(1));
                        gather[count[u]] = (e * stride + local[slot]) as u32;
                        count[u] += 1;
                    }
                }
                gather.truncate(gather_ptr[nodes]);
                ElementMap {
                    slots: s,
                    local,
                    nodes: st.nodes.clone(),
                    num_vertices: nv,
                    offsets,
                    colours,
                    gather_ptr,
                    gather,
                    stride,
                    scratch: Scratch::default(),
                }
            })
            .collect();
        Pattern {
            n,
            num_vertices: nv,
            num_edge_dofs: ne,
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

impl ElementMap {
    /// The nodes of element `e`.
    #[inline]
    pub fn element(&self, e: usize) -> &[usize] {
        &self.nodes[e * self.slots..(e + 1) * self.slots]
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.nodes.len() / self.slots.max(1)
    }

    /// Whether the map has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of block colours.
    pub fn num_colours(&self) -> usize {
        self.colours.len()
    }

    /// Adds an element gradient into `grad`, skipping fixed nodes; `S` slots (= `self.slots`).
    ///
    /// # Safety
    /// No other thread writes the gradient entries of element `e`'s nodes concurrently.
    #[inline(always)]
    unsafe fn scatter_gradient<const N: usize, const S: usize>(
        &self,
        st: &[usize; S],
        local: &[usize; S],
        g: &SVec<N>,
        fixed: &[bool],
        grad: Shared,
    ) {
        for s in 0..S {
            let u = st[s];
            if u == NONE || fixed[u] {
                continue;
            }
            let (d0, k) = node_dofs(self.num_vertices, u);
            let l = local[s];
            for c in 0..k {
                unsafe { grad.add(d0 + c, g[l + c]) };
            }
        }
    }

    /// Adds an element Hessian (lower parts) into the values, skipping fixed nodes.
    ///
    /// # Safety
    /// No other thread writes the Hessian columns of element `e`'s nodes concurrently.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    unsafe fn scatter_hessian<const N: usize, const S: usize>(
        &self,
        pattern_col_ptr: &[usize],
        e: usize,
        st: &[usize; S],
        local: &[usize; S],
        h: &SMat<N, N>,
        fixed: &[bool],
        values: Shared,
    ) {
        let off = &self.offsets[e * S * S..(e + 1) * S * S];
        for t in 0..S {
            let v = st[t];
            if v == NONE || fixed[v] {
                continue;
            }
            let (dv, kv) = node_dofs(self.num_vertices, v);
            let lt = local[t];
            for s in 0..S {
                let u = st[s];
                if u == NONE || fixed[u] || u < v {
                    continue;
                }
                let ls = local[s];
                let ku = node_dofs(self.num_vertices, u).1;
                for d in 0..kv {
                    let base = pattern_col_ptr[dv + d];
                    if u == v {
                        // A node in two slots (s ≠ t) gets both cross blocks' lower triangles:
                        // the lower part of H_st + H_ts, as the symmetric sum requires.
                        for c in d..kv {
                            unsafe { values.add(base + c - d, h[(ls + c, lt + d)]) };
                        }
                    } else {
                        let o = base + (kv - d) + off[S * s + t] as usize;
                        for c in 0..ku {
                            unsafe { values.add(o + c, h[(ls + c, lt + d)]) };
                        }
                    }
                }
            }
        }
    }
}

/// What to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Want {
    /// Energy only.
    Energy,
    /// Energy and gradient.
    Gradient,
    /// Energy, gradient and Hessian.
    Hessian,
}

/// Splits elements into blocks of [`BLOCK`] consecutive elements along the Morton curve of their
/// anchors (ties by element index) in the bounding box of `bounds`, each block sorted by
/// element index.
fn morton_blocks(anchors: &[Vec3], bounds: &[Vec3]) -> Vec<Vec<usize>> {
    let mut lo = Vec3::repeat(Real::INFINITY);
    let mut hi = Vec3::repeat(Real::NEG_INFINITY);
    for p in bounds {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let ext = (hi - lo).map(|e| if e > 0.0 { e } else { 1.0 });
    let spread = |mut v: u64| {
        // Spread the low 21 bits of v to every third bit.
        v &= 0x1f_ffff;
        v = (v | (v << 32)) & 0x1f00000000ffff;
        v = (v | (v << 16)) & 0x1f0000ff0000ff;
        v = (v | (v << 8)) & 0x100f00f00f00f00f;
        v = (v | (v << 4)) & 0x10c30c30c30c30c3;
        (v | (v << 2)) & 0x1249249249249249
    };
    let mut keyed: Vec<(u64, usize)> = anchors
        .iter()
        .enumerate()
        .map(|(f, c)| {
            let q = (c - lo).component_div(&ext) * ((1u64 << 21) - 1) as Real;
            let k = spread(q.x as u64) | (spread(q.y as u64) << 1) | (spread(q.z as u64) << 2);
            (k, f)
        })
        .collect();
    keyed.sort_unstable();
    keyed
        .chunks(BLOCK)
        .map(|c| {
            let mut b: Vec<usize> = c.iter().map(|k| k.1).collect();
            b.sort_unstable();
            b
        })
        .collect()
}

/// Greedy colouring of blocks: each takes the smallest colour not used by a block sharing one of
/// its stencil vertices. Deterministic.
fn colour_blocks(nv: usize, stencil: &Stencil, blocks: &[Vec<usize>]) -> Vec<Vec<Vec<usize>>> {
    let s = stencil.slots().max(1);
    let mut used: Vec<Vec<u32>> = vec![Vec::new(); nv];
    let mut colours: Vec<Vec<Vec<usize>>> = Vec::new();
    let mut taken: Vec<bool> = Vec::new();
    let mut verts: Vec<usize> = Vec::new();
    for block in blocks {
        verts.clear();
        for &f in block {
            verts.extend(
                stencil.nodes[f * s..(f + 1) * s]
                    .iter()
                    .copied()
                    .filter(|&v| v != NONE),
            );
        }
        verts.sort_unstable();
        verts.dedup();
        taken.clear();
        taken.resize(colours.len() + 1, false);
        for &v in &verts {
            for &c in &used[v] {
                taken[c as usize] = true;
            }
        }
        let c = taken.iter().position(|t| !t).unwrap_or(colours.len());
        if c == colours.len() {
            colours.push(Vec::new());
        }
        colours[c].push(block.clone());
        for &v in &verts {
            if !used[v].contains(&(c as u32)) {
                used[v].push(c as u32);
            }
        }
    }
    colours
}

/// A raw pointer to a buffer written concurrently at disjoint indices.
#[derive(Clone, Copy)]
struct Shared(*mut Real, usize);
// SAFETY: `Shared` is only used within one colour of `Pattern::colours`, whose blocks write
// pairwise disjoint indices (they share no stencil vertex, hence no gradient entry and no
// Hessian column; a block's own faces run sequentially), and each face writes its own energy
// slot.
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    fn new(s: &mut [Real]) -> Self {
        Shared(s.as_mut_ptr(), s.len())
    }
    /// Adds `v` at `i`.
    ///
    /// # Safety
    /// No other thread accesses index `i` concurrently.
    #[inline]
    unsafe fn add(self, i: usize, v: Real) {
        debug_assert!(i < self.1);
        unsafe { *self.0.add(i) += v };
    }
}

/// Accumulates one element term into `grad` (len n) and `values` (len nnz) as `want` says and
/// returns its energy, summed in element order. `kernel(e, nodes, grad, hess)` evaluates
/// element `e` with `N` local DOFs and `S` slots (slot `s` at `map.local[s]`); `fixed` is per
/// node. `S` must equal `map.slots`.
#[allow(clippy::too_many_arguments)]
pub fn assemble_elements<const N: usize, const S: usize, K>(
    map: &ElementMap,
    kernel: K,
    fixed: &[bool],
    projection: HessianProjection,
    want: Want,
    grad: &mut [Real],
    values: &mut [Real],
    col_ptr: &[usize],
) -> Real
where
    K: Fn(usize, &[usize], Option<&mut SVec<N>>, Option<&mut SMat<N, N>>) -> Real + Sync,
{
    assert_eq!(map.slots, S, "element map and kernel disagree on the slots");
    let ne = map.len();
    if want == Want::Energy {
        let es: Vec<Real> = (0..ne)
            .into_par_iter()
            .map(|e| kernel(e, map.element(e), None, None))
            .collect();
        return es.iter().sum();
    }
    if want == Want::Gradient {
        return gather_gradient::<N, S, K>(map, &kernel, fixed, grad);
    }
    let mut local = [0usize; S];
    local.copy_from_slice(&map.local);
    let mut energies = vec![0.0; ne];
    let (ep, gp) = (Shared::new(&mut energies), Shared::new(grad));
    let vp = Shared::new(values);
    for blocks in &map.colours {
        blocks.par_iter().for_each(|block| {
            let mut g = SVec::<N>::zeros();
            let mut h = SMat::<N, N>::zeros();
            for &e in block {
                let mut st = [NONE; S];
                st.copy_from_slice(map.element(e));
                let hout = (want == Want::Hessian).then_some(&mut h);
                let en = kernel(e, &st, Some(&mut g), hout);
                // SAFETY: see `Shared`: blocks of one colour touch disjoint entries.
                unsafe {
                    ep.add(e, en);
                    map.scatter_gradient(&st, &local, &g, fixed, gp);
                    if want == Want::Hessian {
                        project(&mut h, projection);
                        map.scatter_hessian(col_ptr, e, &st, &local, &h, fixed, vp);
                    }
                }
            }
        });
    }
    energies.iter().sum()
}

/// Elements per parallel task of the gradient; nodes per task of its gather.
const GRADIENT_CHUNK: usize = 64;

/// The gradient of one element term without colouring: every element's local gradient into a
/// buffer (one parallel pass over fixed chunks of elements), then every node gathers its
/// entries in element order (one parallel pass over fixed chunks of nodes). Two synchronisations
/// per call whatever the mesh, and each sum has a fixed order: bitwise identical for any number
/// of threads. Returns the energy, summed in element order.
fn gather_gradient<const N: usize, const S: usize, K>(
    map: &ElementMap,
    kernel: &K,
    fixed: &[bool],
    grad: &mut [Real],
) -> Real
where
    K: Fn(usize, &[usize], Option<&mut SVec<N>>, Option<&mut SMat<N, N>>) -> Real + Sync,
{
    let ne = map.len();
    assert_eq!(
        map.stride,
        N + 1,
        "element map and kernel disagree on the DOFs"
    );
    let mut guard = map
        .scratch
        .0
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let buf = &mut *guard;
    buf.resize(ne * (N + 1), 0.0);
    // Per element: N gradient entries, then its energy.
    buf.par_chunks_mut(GRADIENT_CHUNK * (N + 1))
        .enumerate()
        .for_each(|(c, chunk)| {
            let mut g = SVec::<N>::zeros();
            for (i, out) in chunk.chunks_mut(N + 1).enumerate() {
                let e = c * GRADIENT_CHUNK + i;
                let mut st = [NONE; S];
                st.copy_from_slice(map.element(e));
                let en = kernel(e, &st, Some(&mut g), None);
                out[..N].copy_from_slice(g.as_slice());
                out[N] = en;
            }
        });
    let buf = &*buf;
    let nv = map.num_vertices;
    let nodes = map.gather_ptr.len() - 1;
    let gather_node = |u: usize, out: &mut [Real]| {
        if fixed[u] {
            return;
        }
        for &off in &map.gather[map.gather_ptr[u]..map.gather_ptr[u + 1]] {
            let src = &buf[off as usize..off as usize + out.len()];
            for (o, v) in out.iter_mut().zip(src) {
                *o += v;
            }
        }
    };
    let (gv, ge) = grad.split_at_mut(3 * nv);
    gv.par_chunks_mut(3 * GRADIENT_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            for (i, out) in chunk.chunks_exact_mut(3).enumerate() {
                let u = c * GRADIENT_CHUNK + i;
                if fixed[u] {
                    continue;
                }
                let mut acc = [out[0], out[1], out[2]];
                for &off in &map.gather[map.gather_ptr[u]..map.gather_ptr[u + 1]] {
                    let o = off as usize;
                    acc[0] += buf[o];
                    acc[1] += buf[o + 1];
                    acc[2] += buf[o + 2];
                }
                out.copy_from_slice(&acc);
            }
        });
    ge[..nodes - nv]
        .par_chunks_mut(GRADIENT_CHUNK)
        .enumerate()
        .for_each(|(c, chunk)| {
            for (i, out) in chunk.chunks_mut(1).enumerate() {
                gather_node(nv + c * GRADIENT_CHUNK + i, out);
            }
        });
    (0..ne).map(|e| buf[e * (N + 1) + N]).sum()
}
