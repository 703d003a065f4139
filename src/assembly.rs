//! Global assembly of energy, gradient and sparse Hessian.
//!
//! The sparsity pattern (lower triangle, compressed sparse columns, 3 DOFs per vertex in the
//! order `x, y, z`) is built once per mesh from each face's 6-vertex stencil, together with a
//! greedy colouring of the faces in which no two faces of a colour share a stencil vertex.
//! Colours are processed in order; within a colour, faces are evaluated in parallel (rayon) and
//! each scatters its gradient and Hessian directly into entries no other face of that colour
//! touches. Every entry therefore receives its contributions in a fixed order (colour by colour)
//! that does not depend on the threads: no floating-point atomics, no per-thread accumulators,
//! results bitwise identical for any number of threads. Energies are stored per face and summed
//! in face order.

use crate::energy::patch::{patch_face, Patch};
use crate::energy::projection::{project, HessianProjection};
use crate::energy::shell::{shell_face, shell_face_gauss_newton};
use crate::energy::KoiterDensity;
use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use rayon::prelude::*;

/// The Hessian's sparsity pattern and, per face, where its entries go.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of DOFs (3 × vertices).
    pub n: usize,
    /// CSC column pointers (lower triangle).
    pub col_ptr: Vec<usize>,
    /// CSC row indices.
    pub row_idx: Vec<usize>,
    /// Per face: vertex ids of its 18-DOF stencil `[v0, v1, v2, p0, p1, p2]` (`NONE` if absent).
    pub stencil: Vec<[usize; 6]>,
    /// Per face and slot pair (s, t) with `u_s > u_t`: rank of `u_s` among the neighbours of
    /// `u_t` with larger index.
    ranks: Vec<[u16; 36]>,
    /// Blocks of faces grouped by colour; blocks of one colour share no stencil vertex.
    colours: Vec<Vec<Vec<usize>>>,
}

/// Faces per block: large enough for cache locality and cheap scheduling, small enough that a
/// colour holds many blocks.
pub const BLOCK: usize = 256;

impl Pattern {
    /// Builds the pattern for faces and their opposite vertices; `positions` (any configuration,
    /// usually the reference one) only orders the faces into spatially coherent blocks.
    pub fn new(positions: &[Vec3], faces: &[[usize; 3]], opposite: &[[usize; 3]]) -> Pattern {
        let nv = positions.len();
        let stencil: Vec<[usize; 6]> = faces
            .iter()
            .zip(opposite)
            .map(|(f, o)| [f[0], f[1], f[2], o[0], o[1], o[2]])
            .collect();
        let mut hi: Vec<Vec<usize>> = vec![Vec::new(); nv];
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
        let n = 3 * nv;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (v, hv) in hi.iter().enumerate() {
            for d in 0..3 {
                for c in d..3 {
                    row_idx.push(3 * v + c);
                }
                for &u in hv {
                    for c in 0..3 {
                        row_idx.push(3 * u + c);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let ranks = stencil
            .iter()
            .map(|st| {
                let mut r = [0u16; 36];
                for s in 0..6 {
                    for t in 0..6 {
                        let (u, v) = (st[s], st[t]);
                        if u != NONE && v != NONE && u > v {
                            r[6 * s + t] = hi[v].binary_search(&u).unwrap_or(0) as u16;
                        }
                    }
                }
                r
            })
            .collect();
        let colours = colour_blocks(nv, &stencil, &morton_blocks(positions, faces));
        Pattern {
            n,
            col_ptr,
            row_idx,
            stencil,
            ranks,
            colours,
        }
    }

    /// Number of block colours.
    pub fn num_colours(&self) -> usize {
        self.colours.len()
    }

    /// Blocks of faces by colour (no two blocks of a colour share a stencil vertex).
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

    /// Adds an element Hessian (lower parts) into the values, skipping fixed vertices.
    ///
    /// # Safety
    /// No other thread writes the Hessian columns of face `f`'s stencil vertices concurrently.
    #[inline]
    unsafe fn scatter_hessian(&self, f: usize, h: &SMat<18, 18>, fixed: &[bool], values: Shared) {
        let st = &self.stencil[f];
        let rk = &self.ranks[f];
        for t in 0..6 {
            let v = st[t];
            if v == NONE || fixed[v] {
                continue;
            }
            for s in 0..6 {
                let u = st[s];
                if u == NONE || fixed[u] || u < v {
                    continue;
                }
                for d in 0..3 {
                    let base = self.col_ptr[3 * v + d];
                    if u == v {
                        for c in d..3 {
                            unsafe { values.add(base + c - d, h[(3 * s + c, 3 * t + d)]) };
                        }
                    } else {
                        let off = base + (3 - d) + 3 * rk[6 * s + t] as usize;
                        for c in 0..3 {
                            unsafe { values.add(off + c, h[(3 * s + c, 3 * t + d)]) };
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
fn colour_blocks(nv: usize, stencil: &[[usize; 6]], blocks: &[Vec<usize>]) -> Vec<Vec<Vec<usize>>> {
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

/// Assembles face terms. `density(f)` gives the face's energy density; `fixed` is per vertex;
/// `patches` selects the patch-fit bending kernel when non-empty (mid-edge average otherwise).
/// Returns the total face energy; fills `grad` (len n) and `values` (len nnz) when wanted
/// (they are overwritten, not accumulated).
#[allow(clippy::too_many_arguments)]
pub fn assemble_faces<F>(
    pattern: &Pattern,
    x: &[Vec3],
    patches: &[Patch],
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
    let nf = pattern.stencil.len();
    if want == Want::Energy {
        let es: Vec<Real> = (0..nf)
            .into_par_iter()
            .map(|f| {
                let (xs, has) = gather(pattern, x, f);
                match patches.get(f) {
                    Some(p) => patch_face::<_, false>(&xs, &p.weights, &density(f), None, None),
                    None => shell_face(&xs, has, &density(f), None, None),
                }
            })
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
            for &f in block {
                let (xs, has) = gather(pattern, x, f);
                let d = density(f);
                let mut g = SVec::<18>::zeros();
                let mut h = SMat::<18, 18>::zeros();
                let hout = (want == Want::Hessian).then_some(&mut h);
                let gn = projection == HessianProjection::GaussNewton;
                let e = match (patches.get(f), gn) {
                    (Some(p), true) => {
                        patch_face::<_, true>(&xs, &p.weights, &d, Some(&mut g), hout)
                    }
                    (Some(p), false) => {
                        patch_face::<_, false>(&xs, &p.weights, &d, Some(&mut g), hout)
                    }
                    (None, true) => shell_face_gauss_newton(&xs, has, &d, Some(&mut g), hout),
                    (None, false) => shell_face(&xs, has, &d, Some(&mut g), hout),
                };
                // SAFETY: see `Shared`: faces of one colour touch disjoint entries.
                unsafe {
                    ep.add(f, e);
                    for (s, &u) in pattern.stencil[f].iter().enumerate() {
                        if u == NONE || fixed[u] {
                            continue;
                        }
                        for c in 0..3 {
                            gp.add(3 * u + c, g[3 * s + c]);
                        }
                    }
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
