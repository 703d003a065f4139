//! The element loops every term runs: where each element's entries go ([`ElementMap`]), the
//! elements' stencils ([`Stencil`]), and the assembly of one term's energy, gradient and sparse
//! Hessian over them ([`assemble_elements`], [`assemble_elements_owned`]), with the per-element
//! eigenvalue projection ([`projection`]). The global pattern that holds every term's entries
//! is [`crate::assembly::Pattern`], one floor up; this module knows no term and no scene.
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

pub mod pattern;
pub mod projection;

use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use projection::{project, HessianProjection};
use rayon::prelude::*;

/// A kernel's answer for an element that contributes nothing here (a fixed vertex, a contact
/// pair out of reach): its gradient and Hessian buffers, which the element loops reuse from
/// element to element, set to zero, and energy 0.
#[inline]
pub fn no_contribution<const N: usize>(
    grad: Option<&mut SVec<N>>,
    hess: Option<&mut SMat<N, N>>,
) -> Real {
    if let Some(g) = grad {
        g.fill(0.0);
    }
    if let Some(h) = hess {
        h.fill(0.0);
    }
    0.0
}

/// Node ids from this one up are absent slots, which receive no entries: [`NONE`], and the
/// points of an element that are not DOFs of the solve (a rigid obstacle's vertices in a
/// contact pair), numbered `ABSENT + k` by the term that owns them.
pub const ABSENT: usize = usize::MAX / 2;

/// Whether node id `u` is an absent slot ([`ABSENT`]).
#[inline(always)]
pub fn is_absent(u: usize) -> bool {
    u >= ABSENT
}

/// The stencil of an element term: every element's DOF nodes in slot order (absent slots
/// numbered from [`ABSENT`] up, [`NONE`] where a slot is empty), the number of DOFs of each slot, and one point per element that orders elements
/// into spatially coherent blocks.
#[derive(Clone, Debug)]
pub struct Stencil {
    /// DOFs per slot (3 for a vertex node, 1 for an edge node).
    pub slot_dofs: Vec<usize>,
    /// Node ids, `elements × slots`.
    pub nodes: Vec<usize>,
    /// One point per element (its centroid) for the Morton ordering.
    pub anchors: Vec<Vec3>,
}

impl Stencil {
    /// Number of slots per element.
    pub fn slots(&self) -> usize {
        self.slot_dofs.len()
    }
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.anchors.len()
    }
    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.anchors.is_empty()
    }
    /// The three-slot stencil of faces `faces` of `mesh` (their vertices; anchors at their
    /// reference centroids).
    pub fn faces(mesh: &crate::mesh::Mesh, faces: impl Iterator<Item = usize>) -> Stencil {
        let p = &mesh.positions;
        let (mut nodes, mut anchors) = (Vec::new(), Vec::new());
        for f in faces {
            let t = mesh.faces[f];
            nodes.extend_from_slice(&t);
            anchors.push((p[t[0]] + p[t[1]] + p[t[2]]) / 3.0);
        }
        Stencil {
            slot_dofs: vec![3; 3],
            nodes,
            anchors,
        }
    }

    /// The one-slot stencil of every vertex (vertex terms).
    pub fn vertices(x: &[Vec3]) -> Stencil {
        Stencil {
            slot_dofs: vec![3],
            nodes: (0..x.len()).collect(),
            anchors: x.to_vec(),
        }
    }
}

/// Where one term's element entries go in the global pattern, and its colouring.
#[derive(Clone, Debug)]
pub struct ElementMap {
    /// Slots per element.
    pub slots: usize,
    /// Local DOF offset of each slot in the element vector.
    pub local: Vec<usize>,
    /// Node ids, `elements × slots` (from [`ABSENT`] up where absent).
    pub nodes: Vec<usize>,
    /// Number of vertices (nodes below it are vertices with 3 DOFs, above it edges with 1).
    pub(crate) num_vertices: usize,
    /// Per element and slot pair (s, t) with node `u_s > u_t`: offset of `u_s`'s rows among the
    /// rows of `u_t`'s columns below its own diagonal block.
    pub(crate) offsets: Vec<u32>,
    /// Blocks of elements grouped by colour; blocks of one colour share no stencil node.
    pub(crate) colours: Vec<Vec<Vec<usize>>>,
    /// Number of nodes (vertices, then edges when the stencil has edge DOFs).
    pub(crate) num_nodes: usize,
    /// The element's DOFs (`N` of its kernel).
    pub(crate) dofs: usize,
    /// The elements along the Morton curve of their anchors.
    pub(crate) morton: Vec<u32>,
    /// The gradient's partition and buffers, reused.
    pub(crate) scratch: Scratch,
}

/// The gradient's partition for one part count and its per-part buffers, reused across calls
/// behind a lock (cloning gives an empty one).
#[derive(Debug, Default)]
pub(crate) struct Scratch(std::sync::Mutex<Option<(Parts, Vec<Vec<Real>>)>>);

/// The owner-computes partition of an element term's gradient into `count` parts (see
/// [`gather_gradient`]).
#[derive(Debug, Default)]
struct Parts {
    /// Number of parts.
    count: usize,
    /// Per part, the elements it evaluates, in element order.
    elements: Vec<Vec<u32>>,
    /// Per part, the nodes it owns and writes.
    nodes: Vec<Vec<u32>>,
    /// Per part, element (in `elements`) and slot: where the slot's node's sum starts in the
    /// part's sums (its owned nodes in order, [`node_dofs`] entries each), or `u32::MAX` when
    /// another part owns the node.
    dst: Vec<Vec<u32>>,
    /// Per part, the positions in `elements` of the elements it is home to, by Morton rank:
    /// the part sums their energies in blocks of [`ENERGY_BLOCK`] into the tail of its buffer.
    home: Vec<Vec<u32>>,
    /// The home ranges: part p is home to Morton ranks `cuts[p]..cuts[p + 1]`.
    cuts: Vec<usize>,
    /// Per part and team call since the last rebalancing (`BALANCE_CALLS` slots), the
    /// nanoseconds spent in it, and the calls counted.
    busy: Vec<Vec<std::sync::atomic::AtomicU64>>,
    calls: u32,
    /// Set by hand ([`ElementMap::set_gradient_partition`]): never rebalanced.
    pinned: bool,
}

/// Work fused into the parts of an element term's gradient ([`assemble_elements_owned`],
/// from [`crate::energy::Potential::owned`]): called once
/// per part, on the thread that runs it, right after the part has summed the gradient of the
/// nodes it owns, with those node ids, their sums (3 entries per vertex node, 1 per edge node,
/// in the nodes' order; N for vertices, N·m for edge DOFs; fixed nodes included and not
/// masked) and the term's mask of fixed nodes (by node id), whose entries the unfused gradient
/// leaves at zero. Each node of the term's elements is owned by exactly one part.
pub type OwnedNodes<'a> = dyn Fn(&[u32], &[Real], &[bool]) + Sync + 'a;

/// Elements per energy block. A term's energy is summed in blocks of this many consecutive
/// elements along the Morton curve, each block in that order, then the blocks' sums in that
/// order ([`ElementMap::sum_energies`]): the parts of the gradient's partition, whose home
/// ranges start at multiples of it, sum their own blocks, and the caller adds one number per
/// block instead of fetching one per element from the other cores' caches.
pub const ENERGY_BLOCK: usize = 8;

/// Team calls between two looks at the balance of the parts ([`Parts::rebalanced`]).
const BALANCE_CALLS: u32 = 64;

impl Clone for Scratch {
    fn clone(&self) -> Self {
        Scratch::default()
    }
}

/// Most elements per block: large enough for cache locality and cheap scheduling.
pub const BLOCK: usize = 256;

/// Fewest elements per block: below this, rayon's scheduling (about a microsecond per block)
/// would no longer be small against the block's work (16 shell faces with edge DOFs take about 50 µs).
pub const MIN_BLOCK: usize = 16;

/// Blocks a term's elements are cut into at least, when [`MIN_BLOCK`] allows: a greedy
/// colouring of a surface mesh's blocks takes 4–8 colours, and each colour must still hold
/// several blocks per thread, or a small mesh (a 1000-face strip in 4 blocks of 256 has one
/// block per colour) assembles on one core.
pub const MIN_BLOCKS: usize = 64;

/// Elements per block for a term of `ne` elements: `⌈ne / MIN_BLOCKS⌉` within
/// [`MIN_BLOCK`]..=[`BLOCK`]. It depends on the mesh only, never on the thread count, so the
/// order in which an entry receives its contributions (colour by colour, block by block) is
/// the same for any number of threads.
pub fn block_size(ne: usize) -> usize {
    ne.div_ceil(MIN_BLOCKS).clamp(MIN_BLOCK, BLOCK)
}

/// First DOF and number of DOFs of node `u` when nodes below `nv` are vertices.
#[inline(always)]
pub(crate) fn node_dofs(nv: usize, u: usize) -> (usize, usize) {
    if u < nv {
        (3 * u, 3)
    } else {
        (3 * nv + (u - nv), 1)
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
            if is_absent(u) || fixed[u] {
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
            if is_absent(v) || fixed[v] {
                continue;
            }
            let (dv, kv) = node_dofs(self.num_vertices, v);
            let lt = local[t];
            for s in 0..S {
                let u = st[s];
                if is_absent(u) || fixed[u] || u < v {
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

/// The elements ordered along the Morton curve of their anchors (ties by element index) in the
/// bounding box of `bounds`.
pub(crate) fn morton_order(anchors: &[Vec3], bounds: &[Vec3]) -> Vec<u32> {
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
    keyed.iter().map(|k| k.1 as u32).collect()
}

/// Greedy colouring of blocks: each takes the smallest colour not used by a block sharing one of
/// its stencil vertices. Deterministic.
pub(crate) fn colour_blocks(
    nv: usize,
    stencil: &Stencil,
    blocks: &[Vec<usize>],
) -> Vec<Vec<Vec<usize>>> {
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
                    .filter(|&v| !is_absent(v)),
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
/// returns its energy ([`ElementMap::sum_energies`]). `kernel(e, nodes, grad, hess)` evaluates
/// element `e` with `N` local DOFs and `S` slots (slot `s` at `map.local[s]`); `fixed` is per
/// node. `S` must equal `map.slots`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
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
    assemble_elements_owned::<N, S, K>(
        map, kernel, fixed, projection, want, grad, values, col_ptr, None,
    )
}

/// [`assemble_elements`], with the explicit driver's fused step: given `owned` (from
/// [`crate::energy::Potential::owned`]) and asked for a gradient, each part of the gradient's
/// partition hands the sums of the nodes it owns to the hook, on the thread that summed them,
/// instead of adding them into `grad`, which is left alone ([`OwnedNodes`]). Element terms
/// pass their potential's hook here.
#[allow(clippy::too_many_arguments)]
pub fn assemble_elements_owned<const N: usize, const S: usize, K>(
    map: &ElementMap,
    kernel: K,
    fixed: &[bool],
    projection: HessianProjection,
    want: Want,
    grad: &mut [Real],
    values: &mut [Real],
    col_ptr: &[usize],
    owned: Option<&OwnedNodes<'_>>,
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
        return map.sum_energies(&es);
    }
    if want == Want::Gradient {
        return gather_gradient::<N, S, K>(map, &kernel, fixed, grad, owned);
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
    map.sum_energies(&energies)
}

impl Parts {
    /// Splits the elements of `map` into `count = cuts.len() − 1` ranges along their Morton
    /// order, part p taking ranks `cuts[p]..cuts[p + 1]` (an element's *home* part); a node
    /// belongs to the home of the first element in that order that holds it. Each part
    /// evaluates the elements that hold one of its nodes, plus those it is home to (for the
    /// energy): elements across a part boundary are evaluated by each part that needs them.
    fn new(map: &ElementMap, cuts: Vec<usize>) -> Parts {
        let ne = map.len();
        let count = cuts.len() - 1;
        debug_assert!(cuts[0] == 0 && cuts[count] == ne && cuts.is_sorted());
        let num_nodes = map.num_nodes;
        let mut home = vec![0u32; ne];
        for p in 0..count {
            for &e in &map.morton[cuts[p]..cuts[p + 1]] {
                home[e as usize] = p as u32;
            }
        }
        let mut owner = vec![u32::MAX; num_nodes];
        for &e in &map.morton {
            for &u in map.element(e as usize) {
                if !is_absent(u) && owner[u] == u32::MAX {
                    owner[u] = home[e as usize];
                }
            }
        }
        let mut elements: Vec<Vec<u32>> = vec![Vec::new(); count];
        let mut last = vec![u32::MAX; count];
        for (e, &h) in home.iter().enumerate() {
            let h = h as usize;
            let parts = map
                .element(e)
                .iter()
                .filter(|&&u| !is_absent(u))
                .map(|&u| owner[u] as usize);
            for p in std::iter::once(h).chain(parts) {
                if last[p] != e as u32 {
                    elements[p].push(e as u32);
                    last[p] = e as u32;
                }
            }
        }
        let mut nodes: Vec<Vec<u32>> = vec![Vec::new(); count];
        let mut dst: Vec<Vec<u32>> = vec![Vec::new(); count];
        // Each node's first entry among its owner's sums.
        let mut sum_at = vec![u32::MAX; num_nodes];
        // Per part, its home elements by Morton rank, as positions in its elements.
        let mut homes: Vec<Vec<u32>> = vec![Vec::new(); count];
        let mut pos = vec![0u32; ne];
        for p in 0..count {
            for (k, &e) in elements[p].iter().enumerate() {
                pos[e as usize] = k as u32;
            }
            homes[p] = map.morton[cuts[p]..cuts[p + 1]]
                .iter()
                .map(|&e| pos[e as usize])
                .collect();
            let mut at = 0;
            for u in (0..num_nodes).filter(|&u| owner[u] as usize == p) {
                nodes[p].push(u as u32);
                sum_at[u] = at as u32;
                at += node_dofs(map.num_vertices, u).1;
            }
            dst[p] = elements[p]
                .iter()
                .flat_map(|&e| map.element(e as usize))
                .map(|&u| {
                    if !is_absent(u) && owner[u] as usize == p {
                        sum_at[u]
                    } else {
                        u32::MAX
                    }
                })
                .collect();
        }
        Parts {
            count,
            elements,
            nodes,
            dst,
            home: homes,
            cuts,
            busy: (0..count)
                .map(|_| (0..BALANCE_CALLS).map(|_| Default::default()).collect())
                .collect(),
            calls: 0,
            pinned: false,
        }
    }

    /// New home ranges that even out the parts' measured times, or `None` while they are
    /// even enough: each part's cost per home element is its median time over the calls since
    /// the last look (a median, because a shared host now and then stalls one thread for many
    /// steps) over its home count, the new counts are in inverse proportion to it, and the cuts
    /// move half way there, in whole energy blocks. Any partition gives the same bits
    /// ([`gather_gradient`]), so this only changes the speed.
    fn rebalanced(&mut self) -> Option<Vec<usize>> {
        use std::sync::atomic::Ordering::Relaxed;
        let calls = (self.calls as usize).min(BALANCE_CALLS as usize);
        let t: Vec<f64> = self
            .busy
            .iter()
            .map(|b| {
                let mut ns: Vec<u64> = b[..calls].iter().map(|t| t.load(Relaxed)).collect();
                ns.sort_unstable();
                ns.get(calls / 2).map_or(0.0, |&t| t as f64)
            })
            .collect();
        self.calls = 0;
        let (count, ne) = (self.count, *self.cuts.last()?);
        let n: Vec<f64> = self.cuts.windows(2).map(|w| (w[1] - w[0]) as f64).collect();
        if self.pinned || t.iter().zip(&n).any(|(&t, &n)| t <= 0.0 || n <= 0.0) {
            return None;
        }
        let speed: Vec<f64> = t.iter().zip(&n).map(|(t, n)| n / t).collect();
        let total: f64 = speed.iter().sum();
        let mut cuts = vec![0usize; count + 1];
        cuts[count] = ne;
        let mut target = 0.0;
        for p in 1..count {
            target += speed[p - 1] / total * ne as f64;
            let old = self.cuts[p] as f64;
            let cut = (old + 0.5 * (target - old)) / ENERGY_BLOCK as f64;
            cuts[p] = (cut.round().max(0.0) as usize * ENERGY_BLOCK)
                .min(ne)
                .max(cuts[p - 1]);
        }
        (cuts != self.cuts).then_some(cuts)
    }

    /// Per part, a zeroed buffer for its elements' energies, its nodes' sums and the sums of
    /// its home elements' energy blocks.
    fn buffers(&self, map: &ElementMap) -> Vec<Vec<Real>> {
        (0..self.count)
            .map(|p| {
                let sums: usize = self.nodes[p]
                    .iter()
                    .map(|&u| node_dofs(map.num_vertices, u as usize).1)
                    .sum();
                let blocks = self.home[p].len().div_ceil(ENERGY_BLOCK);
                vec![0.0; self.elements[p].len() + sums + blocks]
            })
            .collect()
    }

    /// Equal home ranges of `ne` elements for `count` parts.
    fn even_cuts(ne: usize, count: usize) -> Vec<usize> {
        (0..=count)
            .map(|p| {
                if p == count {
                    ne
                } else {
                    p * ne / count / ENERGY_BLOCK * ENERGY_BLOCK
                }
            })
            .collect()
    }
}

impl ElementMap {
    /// The term's energy from its elements' `energies` (J): summed in blocks of
    /// [`ENERGY_BLOCK`] along the Morton curve, then the blocks in order. Every assembly path
    /// sums this way, so energy, gradient and Hessian calls agree to the bit.
    pub fn sum_energies(&self, energies: &[Real]) -> Real {
        self.morton
            .chunks(ENERGY_BLOCK)
            .map(|b| b.iter().map(|&e| energies[e as usize]).sum::<Real>())
            .sum()
    }

    /// Installs the gradient partition with home ranges `cuts` (Morton ranks, `cuts[0] = 0`,
    /// last = the element count, increasing, the others multiples of [`ENERGY_BLOCK`]): for
    /// tests that check that the gradient does not depend on the partition. It stays until the
    /// part count changes and is never rebalanced.
    #[doc(hidden)]
    pub fn set_gradient_partition(&self, cuts: &[usize]) {
        assert!(
            cuts.len() >= 2
                && cuts[0] == 0
                && *cuts.last().unwrap() == self.len()
                && cuts.windows(2).all(|w| w[0] < w[1])
                && cuts[1..cuts.len() - 1]
                    .iter()
                    .all(|c| c.is_multiple_of(ENERGY_BLOCK)),
            "bad cuts {cuts:?} for {} elements",
            self.len()
        );
        let mut parts = Parts::new(self, cuts.to_vec());
        parts.pinned = true;
        let bufs = parts.buffers(self);
        *self
            .scratch
            .0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner()) = Some((parts, bufs));
    }
}

/// The gradient of one element term without colouring, owner-computes: the nodes are split
/// into one part per thread along the Morton curve ([`Parts`]), and each part, in one parallel
/// task, evaluates every element holding one of its nodes, in element order, adding the
/// element's entries for the nodes it owns into its own sums as it goes; then one sequential
/// pass adds the sums into `grad`. One synchronisation per call and no memory written by two
/// threads; elements on a part boundary are evaluated more than once (1.0–2.6% of them on the
/// explicit bench's meshes, 8632 to 793 faces, on two threads).
/// The parts run on the calling thread's active [`crate::team::Team`] when there is one (one
/// part per team thread), otherwise on rayon's pool. With `hook`, each part hands its nodes'
/// sums to it instead, and `grad` is left alone ([`assemble_elements_owned`]).
/// Every entry is the same sum in the same order whatever the partition, so results are
/// bitwise identical for any number of threads. Returns the energy
/// ([`ElementMap::sum_energies`]).
fn gather_gradient<const N: usize, const S: usize, K>(
    map: &ElementMap,
    kernel: &K,
    fixed: &[bool],
    grad: &mut [Real],
    hook: Option<&OwnedNodes<'_>>,
) -> Real
where
    K: Fn(usize, &[usize], Option<&mut SVec<N>>, Option<&mut SMat<N, N>>) -> Real + Sync,
{
    assert_eq!(map.dofs, N, "element map and kernel disagree on the DOFs");
    crate::team::with_active(|team| {
        let threads = team.map_or_else(rayon::current_num_threads, |t| t.threads());
        gather_gradient_on::<N, S, K>(map, kernel, fixed, grad, team, threads, hook)
    })
}

/// [`gather_gradient`] in `threads` parts, run by `team` when there is one, else by rayon;
/// with `hook`, each part hands its nodes' sums to it instead of `grad`.
fn gather_gradient_on<const N: usize, const S: usize, K>(
    map: &ElementMap,
    kernel: &K,
    fixed: &[bool],
    grad: &mut [Real],
    team: Option<&crate::team::Team>,
    threads: usize,
    hook: Option<&OwnedNodes<'_>>,
) -> Real
where
    K: Fn(usize, &[usize], Option<&mut SVec<N>>, Option<&mut SMat<N, N>>) -> Real + Sync,
{
    let ne = map.len();
    let count = threads.clamp(1, ne.max(1));
    let mut guard = map
        .scratch
        .0
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    // A new partition for a new part count, or new home ranges from the measured times.
    let cuts = match guard.as_mut() {
        Some((parts, _)) if parts.count == count => {
            let look = team.is_some() && parts.calls >= BALANCE_CALLS;
            look.then(|| parts.rebalanced()).flatten()
        }
        _ => Some(Parts::even_cuts(ne, count)),
    };
    if let Some(cuts) = cuts {
        let parts = Parts::new(map, cuts);
        let bufs = parts.buffers(map);
        *guard = Some((parts, bufs));
    }
    let (parts, bufs) = guard.as_mut().expect("the partition was just built");
    let nv = map.num_vertices;
    let work = |p: usize, buf: &mut [Real]| {
        let (own, dst) = (&parts.nodes[p], &parts.dst[p]);
        let homes = &parts.home[p];
        let blocks = homes.len().div_ceil(ENERGY_BLOCK);
        let (energies, sums) = buf.split_at_mut(parts.elements[p].len());
        let (sums, block_sums) = sums.split_at_mut(sums.len() - blocks);
        // The owned nodes' sums, in the part's own buffer (writing them straight into `grad`,
        // whose lines the parts share, would make the cores fight over them): each element's
        // entries are added as it is evaluated, in element order, so every node's sum is
        // `0 + Σ` over its elements in element order, whatever the partition.
        sums.fill(0.0);
        let mut g = SVec::<N>::zeros();
        for ((en, &e), to) in energies
            .iter_mut()
            .zip(&parts.elements[p])
            .zip(dst.chunks_exact(S))
        {
            let e = e as usize;
            let mut st = [NONE; S];
            st.copy_from_slice(map.element(e));
            *en = kernel(e, &st, Some(&mut g), None);
            for (s, &d) in to.iter().enumerate() {
                if d != u32::MAX {
                    let (l, d) = (map.local[s], d as usize);
                    for c in 0..node_dofs(nv, st[s]).1 {
                        sums[d + c] += g[l + c];
                    }
                }
            }
        }
        // The home elements' energies, summed by block: the caller reads the block sums
        // (reading the energies in place would share one line per element with the part's
        // next writes).
        for (b, ks) in block_sums.iter_mut().zip(homes.chunks(ENERGY_BLOCK)) {
            *b = ks.iter().map(|&k| energies[k as usize]).sum::<Real>();
        }
        if let Some(hook) = hook {
            hook(own, sums, fixed);
        }
    };
    if parts.count == 1 {
        work(0, &mut bufs[0]);
    } else if let Some(team) = team.filter(|t| t.threads() == parts.count) {
        let shared: Vec<Shared> = bufs.iter_mut().map(|b| Shared::new(b)).collect();
        // Rebalancing looks after `BALANCE_CALLS` calls and restarts the count.
        let call = parts.calls as usize % BALANCE_CALLS as usize;
        team.run(&|p| {
            let Shared(ptr, len) = shared[p];
            let start = std::time::Instant::now();
            // SAFETY: part p alone touches buffer p, and `run` returns after every part.
            work(p, unsafe { std::slice::from_raw_parts_mut(ptr, len) });
            let ns = start.elapsed().as_nanos() as u64;
            parts.busy[p][call].store(ns, std::sync::atomic::Ordering::Relaxed);
        });
        parts.calls += 1;
    } else {
        bufs.par_iter_mut()
            .enumerate()
            .for_each(|(p, buf)| work(p, buf));
    }
    for (p, buf) in bufs.iter().enumerate().filter(|_| hook.is_none()) {
        let mut at = parts.elements[p].len();
        for &u in &parts.nodes[p] {
            let u = u as usize;
            let (d0, dofs) = node_dofs(nv, u);
            if !fixed[u] {
                for c in 0..dofs {
                    grad[d0 + c] += buf[at + c];
                }
            }
            at += dofs;
        }
    }
    // The block sums, part after part: the blocks in Morton order, as `sum_energies` adds
    // them.
    bufs.iter()
        .zip(&parts.home)
        .flat_map(|(buf, h)| &buf[buf.len() - h.len().div_ceil(ENERGY_BLOCK)..])
        .sum()
}
