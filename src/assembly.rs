//! Global assembly of energy, gradient and sparse Hessian.
//!
//! The sparsity pattern (lower triangle, compressed sparse columns, 3 DOFs per vertex in the
//! order `x, y, z`, then one DOF per edge when the bending model has edge DOFs) is built once per
//! mesh from each face's stencil (6 vertices, plus its 3 edges), together with a greedy colouring
//! of the faces in which no two faces of a colour share a stencil node.
//! Colours are processed in order; within a colour, faces are evaluated in parallel (rayon) and
//! each scatters its gradient and Hessian directly into entries no other face of that colour
//! touches. Every entry therefore receives its contributions in a fixed order (colour by colour)
//! that does not depend on the threads: no floating-point atomics, no per-thread accumulators,
//! results bitwise identical for any number of threads. Energies are stored per face and summed
//! in face order.

use crate::energy::midedge_angle::{midedge_angle_face, AngleVariant};
use crate::energy::patch::{patch_face, Patch};
use crate::energy::projection::{project, HessianProjection};
use crate::energy::shell::{shell_face, shell_face_gauss_newton};
use crate::energy::KoiterDensity;
use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use rayon::prelude::*;

/// Stencil slots per face: 6 vertices, then up to 3 edge-DOF nodes.
const SLOTS: usize = 9;

/// The Hessian's sparsity pattern and, per face, where its entries go.
///
/// DOFs are grouped in *nodes*: vertex `v` (node `v`) owns the 3 DOFs `3v..3v+3`; with edge DOFs,
/// edge `e` (node `nv + e`) owns the single DOF `3 nv + e`.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of DOFs (3 × vertices + edge DOFs).
    pub n: usize,
    /// Number of vertices.
    pub num_vertices: usize,
    /// Number of edge DOFs (0 unless the bending model has them).
    pub num_edge_dofs: usize,
    /// CSC column pointers (lower triangle).
    pub col_ptr: Vec<usize>,
    /// CSC row indices.
    pub row_idx: Vec<usize>,
    /// Per face: node ids of its stencil `[v0, v1, v2, p0, p1, p2, e0, e1, e2]` (`NONE` if
    /// absent; the edge slots are `NONE` without edge DOFs).
    pub stencil: Vec<[usize; SLOTS]>,
    /// Per face and slot pair (s, t) with node `u_s > u_t`: offset of `u_s`'s rows among the
    /// rows of `u_t`'s columns below its own diagonal block.
    offsets: Vec<[u32; SLOTS * SLOTS]>,
    /// Blocks of faces grouped by colour; blocks of one colour share no stencil node.
    colours: Vec<Vec<Vec<usize>>>,
    /// Positions in the values of every entry in the row or column of a pinned DOF.
    pinned: Vec<usize>,
}

/// Faces per block: large enough for cache locality and cheap scheduling, small enough that a
/// colour holds many blocks.
pub const BLOCK: usize = 256;

/// Local DOF offset of stencil slot `s` in an element vector (vertices 3 each, then edges).
#[inline(always)]
fn local(s: usize) -> usize {
    if s < 6 {
        3 * s
    } else {
        12 + s
    }
}

impl Pattern {
    /// Builds the pattern for faces and their extra bending vertices, without edge DOFs;
    /// `positions` (any configuration, usually the reference one) only orders the faces into
    /// spatially coherent blocks.
    pub fn new(positions: &[Vec3], faces: &[[usize; 3]], extra: &[[usize; 3]]) -> Pattern {
        Self::with_edges(positions, faces, extra, None)
    }

    /// The pattern of a scene (with edge DOFs when its bending model has them).
    pub fn for_scene(scene: &crate::scene::Scene) -> Pattern {
        let edges = scene
            .has_edge_dofs()
            .then_some((scene.topo.face_edges.as_slice(), scene.topo.edges.len()));
        let mut p = Self::with_edges(
            &scene.mesh.positions,
            &scene.mesh.faces,
            &scene.stencil_extra(),
            edges,
        );
        p.pin(&scene.pinned_dofs);
        p
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

    /// As [`Pattern::new`], with one DOF per edge when `edges = Some((face_edges, num_edges))`
    /// (`face_edges[f][i]` the edge opposite vertex `i` of face `f`).
    pub fn with_edges(
        positions: &[Vec3],
        faces: &[[usize; 3]],
        extra: &[[usize; 3]],
        edges: Option<(&[[usize; 3]], usize)>,
    ) -> Pattern {
        let nv = positions.len();
        let ne = edges.map_or(0, |e| e.1);
        let nodes = nv + ne;
        let stencil: Vec<[usize; SLOTS]> = faces
            .iter()
            .zip(extra)
            .enumerate()
            .map(|(fi, (f, o))| {
                let e = edges.map_or([NONE; 3], |(fe, _)| fe[fi].map(|e| nv + e));
                [f[0], f[1], f[2], o[0], o[1], o[2], e[0], e[1], e[2]]
            })
            .collect();
        let size = |u: usize| if u < nv { 3 } else { 1 };
        let dof = |u: usize| if u < nv { 3 * u } else { 3 * nv + (u - nv) };
        let mut hi: Vec<Vec<usize>> = vec![Vec::new(); nodes];
        for st in &stencil {
            for &u in st {
                for &v in st {
                    if u != NONE && v != NONE && u > v {
                        hi[v].push(u);
                    }
                }
            }
        }
        for h in &mut hi {
            h.sort_unstable();
            h.dedup();
        }
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
            let kv = size(v);
            for d in 0..kv {
                for c in d..kv {
                    row_idx.push(dof(v) + c);
                }
                for &u in hv {
                    for c in 0..size(u) {
                        row_idx.push(dof(u) + c);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let offsets = stencil
            .iter()
            .map(|st| {
                let mut r = [0u32; SLOTS * SLOTS];
                for s in 0..SLOTS {
                    for t in 0..SLOTS {
                        let (u, v) = (st[s], st[t]);
                        if u != NONE && v != NONE && u > v {
                            let rank = hi[v].binary_search(&u).unwrap_or(0);
                            r[SLOTS * s + t] = prefix[v][rank];
                        }
                    }
                }
                r
            })
            .collect();
        let colours = colour_blocks(nodes, &stencil, &morton_blocks(positions, faces));
        Pattern {
            n,
            num_vertices: nv,
            num_edge_dofs: ne,
            col_ptr,
            row_idx,
            stencil,
            offsets,
            colours,
            pinned: Vec::new(),
        }
    }

    /// Number of block colours.
    pub fn num_colours(&self) -> usize {
        self.colours.len()
    }

    /// Blocks of faces by colour (no two blocks of a colour share a stencil node).
    pub fn colours(&self) -> &[Vec<Vec<usize>>] {
        &self.colours
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
        let nv = self.num_vertices;
        if u < nv {
            (3 * u, 3)
        } else {
            (3 * nv + (u - nv), 1)
        }
    }

    /// Adds an element gradient into `grad`, skipping fixed nodes.
    ///
    /// # Safety
    /// No other thread writes the gradient entries of face `f`'s stencil nodes concurrently.
    #[inline]
    unsafe fn scatter_gradient<const N: usize>(
        &self,
        f: usize,
        g: &SVec<N>,
        fixed: &[bool],
        grad: Shared,
    ) {
        for (s, &u) in self.stencil[f].iter().enumerate() {
            if u == NONE || fixed[u] {
                continue;
            }
            let (d0, k) = self.node_dofs(u);
            for c in 0..k {
                unsafe { grad.add(d0 + c, g[local(s) + c]) };
            }
        }
    }

    /// Adds an element Hessian (lower parts) into the values, skipping fixed nodes.
    ///
    /// # Safety
    /// No other thread writes the Hessian columns of face `f`'s stencil nodes concurrently.
    #[inline]
    unsafe fn scatter_hessian<const N: usize>(
        &self,
        f: usize,
        h: &SMat<N, N>,
        fixed: &[bool],
        values: Shared,
    ) {
        let st = &self.stencil[f];
        let off = &self.offsets[f];
        for t in 0..SLOTS {
            let v = st[t];
            if v == NONE || fixed[v] {
                continue;
            }
            let (dv, kv) = self.node_dofs(v);
            let lt = local(t);
            for s in 0..SLOTS {
                let u = st[s];
                if u == NONE || fixed[u] || u < v {
                    continue;
                }
                let ls = local(s);
                let ku = self.node_dofs(u).1;
                for d in 0..kv {
                    let base = self.col_ptr[dv + d];
                    if u == v {
                        for c in d..kv {
                            unsafe { values.add(base + c - d, h[(ls + c, lt + d)]) };
                        }
                    } else {
                        let o = base + (kv - d) + off[SLOTS * s + t] as usize;
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

/// Splits the faces into blocks of [`BLOCK`] consecutive faces along the Morton curve of their
/// centroids (ties by face index), each block sorted by face index.
fn morton_blocks(positions: &[Vec3], faces: &[[usize; 3]]) -> Vec<Vec<usize>> {
    let mut lo = Vec3::repeat(Real::INFINITY);
    let mut hi = Vec3::repeat(Real::NEG_INFINITY);
    for p in positions {
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
    let mut keyed: Vec<(u64, usize)> = faces
        .iter()
        .enumerate()
        .map(|(f, t)| {
            let c = (positions[t[0]] + positions[t[1]] + positions[t[2]]) / 3.0;
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
fn colour_blocks(
    nv: usize,
    stencil: &[[usize; SLOTS]],
    blocks: &[Vec<usize>],
) -> Vec<Vec<Vec<usize>>> {
    let mut used: Vec<Vec<u32>> = vec![Vec::new(); nv];
    let mut colours: Vec<Vec<Vec<usize>>> = Vec::new();
    let mut taken: Vec<bool> = Vec::new();
    let mut verts: Vec<usize> = Vec::new();
    for block in blocks {
        verts.clear();
        for &f in block {
            verts.extend(stencil[f].iter().copied().filter(|&v| v != NONE));
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

/// The bending model of the face kernel, with its per-face data.
#[derive(Clone, Copy, Debug)]
pub enum Bending<'a> {
    /// Seed 000's mid-edge average ([`shell_face`]), 18 DOFs.
    MidedgeAverage,
    /// MorphoShell's patch fit ([`patch_face`]), 18 DOFs, one patch per face.
    PatchFit(&'a [Patch]),
    /// Mid-edge normals with edge DOFs ([`midedge_angle_face`]), 21 DOFs; `sigma[f][i]` is face
    /// `f`'s orientation sign on its edge `i`.
    MidedgeAngle {
        /// `sin` or `tan`.
        variant: AngleVariant,
        /// Orientation signs per face and edge.
        sigma: &'a [[Real; 3]],
    },
}

/// Assembles face terms. `density(f)` gives the face's energy density; `fixed` is per node
/// (vertices, then edge DOFs); `phi` holds the edge DOFs (empty without them). Returns the total
/// face energy; fills `grad` (len n) and `values` (len nnz) when wanted (they are overwritten,
/// not accumulated).
#[allow(clippy::too_many_arguments)]
pub fn assemble_faces<F>(
    pattern: &Pattern,
    x: &[Vec3],
    phi: &[Real],
    bending: Bending,
    density: F,
    fixed: &[bool],
    projection: HessianProjection,
    want: Want,
    grad: &mut [Real],
    values: &mut [Real],
) -> Real
where
    F: Fn(usize) -> KoiterDensity + Sync,
{
    let gn = projection == HessianProjection::GaussNewton;
    match bending {
        Bending::MidedgeAverage => assemble_generic::<18, _>(
            pattern,
            |f, g, h| {
                let (xs, has) = gather(pattern, x, f);
                if gn {
                    shell_face_gauss_newton(&xs, has, &density(f), g, h)
                } else {
                    shell_face(&xs, has, &density(f), g, h)
                }
            },
            fixed,
            projection,
            want,
            grad,
            values,
        ),
        Bending::PatchFit(patches) => assemble_generic::<18, _>(
            pattern,
            |f, g, h| {
                let (xs, _) = gather(pattern, x, f);
                let w = &patches[f].weights;
                if gn {
                    patch_face::<_, true>(&xs, w, &density(f), g, h)
                } else {
                    patch_face::<_, false>(&xs, w, &density(f), g, h)
                }
            },
            fixed,
            projection,
            want,
            grad,
            values,
        ),
        Bending::MidedgeAngle { variant, sigma } => {
            let nv = pattern.num_vertices;
            assemble_generic::<21, _>(
                pattern,
                |f, g, h| {
                    let (xs, has) = gather(pattern, x, f);
                    let st = &pattern.stencil[f];
                    let ph = [phi[st[6] - nv], phi[st[7] - nv], phi[st[8] - nv]];
                    let d = density(f);
                    if gn {
                        midedge_angle_face::<_, true>(&xs, has, &ph, sigma[f], variant, &d, g, h)
                    } else {
                        midedge_angle_face::<_, false>(&xs, has, &ph, sigma[f], variant, &d, g, h)
                    }
                },
                fixed,
                projection,
                want,
                grad,
                values,
            )
        }
    }
}

/// The colour-by-colour assembly loop for a kernel with `N` local DOFs.
#[allow(clippy::too_many_arguments)]
fn assemble_generic<const N: usize, K>(
    pattern: &Pattern,
    kernel: K,
    fixed: &[bool],
    projection: HessianProjection,
    want: Want,
    grad: &mut [Real],
    values: &mut [Real],
) -> Real
where
    K: Fn(usize, Option<&mut SVec<N>>, Option<&mut SMat<N, N>>) -> Real + Sync,
{
    let nf = pattern.stencil.len();
    if want == Want::Energy {
        let es: Vec<Real> = (0..nf)
            .into_par_iter()
            .map(|f| kernel(f, None, None))
            .collect();
        return es.iter().sum();
    }
    grad.par_chunks_mut(1 << 14).for_each(|c| c.fill(0.0));
    if want == Want::Hessian {
        values.par_chunks_mut(1 << 14).for_each(|c| c.fill(0.0));
    }
    let mut energies = vec![0.0; nf];
    let (ep, gp) = (Shared::new(&mut energies), Shared::new(grad));
    let vp = Shared::new(values);
    for blocks in &pattern.colours {
        blocks.par_iter().for_each(|block| {
            let mut g = SVec::<N>::zeros();
            let mut h = SMat::<N, N>::zeros();
            for &f in block {
                let hout = (want == Want::Hessian).then_some(&mut h);
                let e = kernel(f, Some(&mut g), hout);
                // SAFETY: see `Shared`: faces of one colour touch disjoint entries.
                unsafe {
                    ep.add(f, e);
                    pattern.scatter_gradient(f, &g, fixed, gp);
                    if want == Want::Hessian {
                        project(&mut h, projection);
                        pattern.scatter_hessian(f, &h, fixed, vp);
                    }
                }
            }
        });
    }
    energies.iter().sum()
}

/// The face's 6 stencil positions (absent neighbours get the face's own first vertex, unused).
#[inline]
fn gather(pattern: &Pattern, x: &[Vec3], f: usize) -> ([Vec3; 6], [bool; 3]) {
    let st = &pattern.stencil[f];
    let has = [st[3] != NONE, st[4] != NONE, st[5] != NONE];
    let xs = std::array::from_fn(|s| if st[s] == NONE { x[st[0]] } else { x[st[s]] });
    (xs, has)
}
