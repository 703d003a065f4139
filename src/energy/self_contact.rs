//! Contact of the sheet with itself and between sheets (`[self_contact]`): mid-surfaces stay an
//! offset apart, and no step ever carries one surface through another.
//!
//! **Pairs.** Every vertex with every face not incident to it (point–triangle), and every edge
//! with every edge sharing no vertex (edge–edge), measured by their exact distance `d`
//! ([`crate::contact::distance`]). The offset between mid-surfaces is
//! `ξ = (h_a + h_b)/2`, the mean of the two sides' thicknesses (a vertex's thickness is its
//! faces' area-weighted mean, a triangle's or an edge's the mean of its vertices'), or one
//! `offset` for every pair.
//!
//! **Normal law: a smoothed penalty with a physical stiffness.** Each vertex presses on the
//! closest point of the surface on either side of it (the side is the sign of `(x_p − q)·n_p`,
//! `q` the closest point, `n_p` the vertex's area-weighted normal): of the point–triangle pairs
//! of vertex `p`, only the nearest on each side carries energy,
//!
//! `E_p = k (A_p/2) ψ(ξ − d)`,
//!
//! with `A_p` the vertex's reference area, `k` the stiffness (Pa/m) and `ψ` the ground's C²
//! penalty with smoothing δ ([`crate::contact::penalty`]). Both sheets of a contact press with
//! half their area, so two flat sheets pressed by a pressure σ sink into their offset by the
//! ground's closed form, `√(2δσ/k)` below `kδ/2` and `σ/k + δ/2` beyond, on any mesh: the
//! stiffness converges under refinement. The closest point of a surface is a continuous function of
//! the vertex, so the energy is C¹ where a vertex slides from one face to the next.
//!
//! With `pairs = "all"` every point–triangle pair within reach presses instead, as IPC's do:
//! the energy is then a sum of C¹ terms, C¹ everywhere, where the nearest-on-each-side rule
//! changes which faces count abruptly where a fold turns the other surface edge-on to the
//! vertex (Newton stalled there on a cloth folding over a sphere and on a coarse rolled paper
//! strip, which complete with all pairs). The price: a vertex over an edge or a vertex of the
//! other surface presses on every face there, so contact is stiffer where meshes align (two
//! stacked copies of one mesh sink 21% less than the closed form).
//!
//! **The barrier law** (`law = "barrier"`): IPC's log barrier in place of the penalty, on the
//! gap beyond the law's reach `r` (ξ for a point on a face, ξ/2 for two edges),
//!
//! `E = m k A b(d − r)`, `b(g) = −(g − ĝ)² ln(g/ĝ)` below the activation distance `ĝ`
//! (`smoothing`) ([`crate::contact::barrier`]),
//!
//! with the same weights `A`, pairs and mollifier. It is infinite at `d = r`, so a vertex never
//! enters the offset (an edge never comes within ξ/2 of another): every step's CCD bound and
//! check keep each pair above `max(s ξ, r)`, and the bound leaves a tenth of the margin. Two
//! sheets pressed by σ stop at the gap `g` where `−k b′(g) = σ`, inside `ĝ`: the stiffness is a
//! scale, not a material's (the gap depends on `ĝ`, not on the sheets). `ĝ` must be below the
//! `halo`, so that every pair that presses was gathered. Measured against the penalty
//! (`scripts/contact_laws.py`): the rolled strip 757 Newton iterations against 709, the dropped
//! sheet 111 against 96, the stack 12 against 9; the disk draped with friction over a sphere
//! mesh stalls at 0.30 s, where the penalty completes. The penalty is the default: a physical
//! stiffness that converges under refinement, and fewer iterations.
//!
//! **Edge–edge pairs** carry the contact where no vertex is near a face (two creases crossing).
//! They act only inside half the offset, `E = m(c) k w ψ(ξ/2 − d)`, `w` a quarter of the mean
//! of the four vertex areas, `m` IPC's mollifier of nearly parallel edges
//! ([`crate::contact::distance::mollifier`]): on a flat contact they are idle and the pressure
//! is the vertex law's alone.
//!
//! **Friction** (`friction` μ > 0; dynamic mode, and stick/slip in explicit mode, below): the ground's lagged, smoothed Coulomb
//! dissipation ([`crate::contact::friction_potential`]) on each pair's relative slip. A pair
//! that presses at the friction lag's iterate `x̃` ([`crate::energy::potential::Friction`])
//! has there its normal force `λ = m k w ψ′`, its closest points' coefficients `c` (the
//! distance vector is `r = Σᵢ cᵢ yᵢ`, point minus closest point; `c = (1, −β₂, −β₁, −β₀)` for a
//! point and a triangle's barycentric `β`, `(1 − s, s, −(1 − t), −t)` for two edges) and
//! its normal `n = r/‖r‖`. Over the step from `x⁰` the pair slips by
//! `u = (I − n nᵀ) Σᵢ cᵢ (xᵢ − x⁰ᵢ)`, the motion of the point relative to the surface it
//! touches, and dissipates
//!
//! `D = μ λ f₀(‖u‖)`,
//!
//! exactly Coulomb's force μλ against the slip once it exceeds `ε = ε_v Δt` (`contact.slip_speed`
//! ε_v), a stiff sticking spring below. Its gradient on vertex `i` is `cᵢ ∇_u D` and its Hessian
//! block `(i, j)` is `cᵢ cⱼ ∇²_u D` (positive semi-definite). The integrator re-solves a step
//! until the normal forces agree with the lag ([`crate::integrate`]). Static solves are
//! frictionless.
//!
//! **The guarantee.** No step takes a pair closer than `s ξ` (`min_separation` s, default 0.1):
//! every Newton step is bounded by additive CCD over the pairs ([`crate::contact::ccd`]) and
//! every trial state is checked before the line search accepts it. The pairs are gathered into
//! the Hessian's pattern once per step (at the step's start, when the pattern is refreshed),
//! all those within `ξ + halo`. Every Newton step also runs the broad phase over the boxes of
//! the straight paths: a pair that was not gathered may not come within its offset, where its
//! law would begin (CCD to `ξ`). When such a pair limits the step and is within reach, the pairs
//! are gathered again at the current iterate (a new pattern), and Newton goes on. The broad
//! phase's pairs are kept over a wider radius (a few times the last corrections' length, at
//! most two mean edges): a later query whose positions stay within the margin is answered from
//! them by the broad phase's own box test, the same pairs in the same order, without a new
//! grid. A step's long jump (its predicted start) is searched once, over its paths' boxes
//! inflated by that margin, and cached around its end. With the pairs is kept their room, the
//! least distance of any pair beyond where its law begins (its exact distance for the cached
//! pairs, the margin for the others): while no point moves from there by 0.45 of it, no pair
//! comes within its law, and Newton's corrections are checked in O(n), without a broad phase
//! or CCD beyond the gathered pairs; the next step's gathering at the same place is empty
//! without a search when the room exceeds the halo by twice the motion. Likewise, while no
//! vertex has moved half the halo from where the pairs were gathered, no pair that was not
//! gathered can press, and the paths are not searched at all. A cloth falling 3 cm per step
//! with nothing near contact pays 3–4% for it (`scripts/implicit_contact_cost.py`).
//!
//! **Explicit mode.** The explicit driver has no Newton step to bound: it moves each vertex
//! at most a radius from where the pairs were gathered
//! ([`StepLimit::displacement_bounds`]: half the halo, and half the room each of its gathered
//! pairs has to its floor), pulls back a vertex that would leave it, and gathers again before
//! one would (`crate::integrate::explicit`'s contact). A mesh obstacle moved with the dial gets
//! the same radius for its move ([`StepLimit::dial_room`]), and its move past it is checked by
//! CCD. The penalty's default stiffness there is
//! at most `ρh/(4Δt²)` (`default_stiffness`); the barrier is refused. Each pressing pair has a
//! dashpot on its normal approach (`damping` ζ), and friction there is Coulomb's stick/slip of
//! the pressing pairs solved together in each step (the term's explicit hook,
//! [`ExplicitHooks::explicit_step`]), not the lagged potential.
//!
//! **Far pairs.** Each evaluation skips the exact distance of a pair whose two sides' bounding
//! boxes are beyond its reach (`beyond_reach`): most gathered pairs of a sheet in motion,
//! whose halo is as wide as the offset.
//!
//! **Exclusion.** Pairs within the exclusion radius `R` of each other on the reference sheet,
//! measured both in space and along its edges (the graph distance, at most `2R` plus two edge
//! lengths), never touch: without it a mesh finer than its thickness would be in contact
//! with itself at rest. `R` defaults to `2 (ξ + δ)`. An arc of that length comes within the
//! offset of its own start only when bent to a radius below about `0.53 (ξ + δ)`: folds
//! tighter than about half the thickness cannot self-contact, and Kirchhoff–Love shells cannot
//! represent them anyway. Reference pairs that are close in space but far along the sheet are
//! separate layers: closer than their offset, they are an error naming the faces. A reference
//! surface with an edge through a face (not sharing a vertex) is an error naming the two faces.
//!
//! **Mesh obstacles** (`[[obstacles]]` with `shape = "mesh"`): a rigid triangle mesh, fixed,
//! moved by its `displacement` × the dial, or pushed by a `force`, is the one-sided case of the
//! same pairs, through the same distances, CCD and checks; moved with the dial, it stands still
//! within a solve, and its move to a new step's dial is checked by CCD over the jump before the
//! step is solved (with the jump of the vertices on prescribed paths), a refused jump cutting
//! the step. Its
//! vertices are no DOFs (absent slots of the stencil, [`crate::elements::ABSENT`]) and its
//! thickness is 0, so the offset of a pair with it is half the sheet's thickness: the sheet's
//! surface rests on the obstacle's. Only the sheet presses: a sheet vertex on an obstacle's face
//! with its whole area, `E = k A_p ψ(ξ − d)`, the analytic obstacles' law, so that a sheet on a
//! flat mesh sinks by the same closed form; an obstacle's vertex on a sheet face (a corner the
//! sheet's vertices do not see) with half the smaller of its own area and the face's vertex
//! areas, at the offset; an obstacle's edge against a sheet edge inside half the offset, as
//! between sheet edges. `k`, `δ` and `μ` are the obstacle's (`stiffness`, `smoothing`,
//! `friction`; defaults as for the sheet's pairs). Without `[self_contact]` the term is
//! `mesh_obstacles` and gathers no sheet–sheet pairs. At rest no edge of the sheet may pass
//! through a face of an obstacle or the reverse, and no pair may be within its reach.
//!
//! **Force control** (`force` F ê at dial 1, `mass` M): the obstacle's vertices sit at
//! `y_o = ȳ_o + q ê`, its offset `q` (m) a global DOF of the solve, with the energy of an
//! analytic force-controlled obstacle's force and inertia, `−s F q + M (q − q̂)²/(2Δt²)`
//! ([`crate::energy::obstacles::pressed`]). A pair with it depends on `q` through its rigid
//! slots: with `P` the twelve-vector of `ê` in those slots, `∂E/∂q = Pᵀ∇E`,
//! `∂²E/∂x∂q = ∇²E P`, `∂²E/∂q² = Pᵀ∇²E P`. The stencil then has a fifth slot of one DOF,
//! `q`'s node (absent for the pairs without such an obstacle), and ends with one element per
//! such obstacle for its force. Within a solve its vertices move along each Newton step by
//! `dq ê`, inside the same CCD, broad phase over the paths and checks as the sheet's. It is
//! frictionless, and refused in explicit mode.
//!
//! Units: positions m, k Pa/m, δ, ξ, R m, A m², energies J. DOF order per pair: the four
//! points' coordinates, point–triangle `(p, t₂, t₁, t₀)` with `t₀ < t₁ < t₂`, edge–edge
//! `(a, b, c, d)` with `a < b`, `c < d` (the order of the last two slots tells the kinds apart);
//! with a force-controlled mesh obstacle, then its offset `q` (m; a 13th DOF, the fifth slot).

use super::term::{
    ExplicitHooks, GlobalDof, GlobalDofs, LaggedNormals, Reports, StepBound, StepLimit, Term,
};
use crate::body::Body;
use crate::contact::{barrier, broad, ccd, distance, friction_potential, penalty};
use crate::elements::Stencil;
use crate::elements::{assemble_elements, no_contribution, ElementMap, Want, ABSENT};
use crate::energy::term::ChangingElements;
use crate::energy::{HessianProjection, Potential};
use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use crate::mesh::MeshError;
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::atomic::{AtomicU64, Ordering};

/// A vertex's point–triangle pair within reach ([`SelfContact::active`]): the side of the
/// vertex its closest point lies on, and their squared distance (m²).
type Side = (bool, Real);

/// The mollifier's threshold as a fraction of the product of the squared rest lengths
/// (Li et al. 2020, §4.3).
const MOLLIFIER: Real = 1e-3;

/// The contact of a sheet with itself, with other sheets of the mesh, and with rigid mesh
/// obstacles.
///
/// Vertices are numbered as the sheet's, `0..nv`, then the obstacles' (`nv + k`, the term's
/// internal numbering; `ABSENT + k` in the stencils it hands out, slots that are no DOF of the
/// solve). Faces and edges are the sheet's, then the obstacles'.
pub struct SelfContact {
    /// The term's name: `self_contact`, or `mesh_obstacles` when it holds no sheet–sheet pairs.
    name: &'static str,
    /// The sheet's vertices.
    nv: usize,
    /// The sheet's faces: the first of [`SelfContact::faces`].
    sheet_faces: usize,
    /// The sheet's edges: the first of [`SelfContact::edges`].
    sheet_edges: usize,
    /// Whether the sheet's pairs with itself count (`[self_contact]` enabled).
    self_pairs: bool,
    /// The rigid mesh obstacles.
    rigid: Rigid,
    /// The faces, the sheet's then the obstacles'.
    faces: Vec<[usize; 3]>,
    /// The edges `(a, b)`, `a < b`, the sheet's then the obstacles'.
    edges: Vec<[usize; 2]>,
    /// Reference positions (the mollifier's rest lengths).
    rest: Vec<Vec3>,
    /// Thickness per vertex (m), or the fixed offset in every entry; 0 on the obstacles.
    thickness: Vec<Real>,
    /// Reference area per vertex (m²); 0 on the obstacles.
    area: Vec<Real>,
    /// Stiffness k of the normal law (Pa/m).
    pub stiffness: Real,
    /// The normal law's length (m): the penalty's smoothing δ, the barrier's activation ĝ.
    pub smoothing: Real,
    /// The normal law is IPC's log barrier (`law = "barrier"`), not the penalty.
    pub barrier: bool,
    /// The farthest beyond its reach a pair presses (m): the largest activation distance with
    /// the barrier, 0 with the penalty.
    pub beyond_max: Real,
    /// The largest offset (m).
    pub xi_max: Real,
    /// How far beyond the offset pairs are gathered (m).
    pub halo: Real,
    /// The exclusion radius (m).
    pub exclusion: Real,
    /// The smallest distance as a fraction of the offset.
    pub min_separation: Real,
    /// Coulomb coefficient μ between sheets (0: frictionless, and always in statics).
    pub friction: Real,
    /// Every point–triangle pair within reach presses, not only the nearest on either side.
    pub all_pairs: bool,
    /// The explicit driver's dashpot on each pressing pair, a fraction ζ of critical damping
    /// (0 in the implicit modes, whose steps damp the contact themselves).
    pub damping: Real,
    /// Wall time spent so far (ns) in the broad phase and gathering, in CCD and the
    /// separation checks, and in the term's assembly ([`Clock`]).
    clock: [AtomicU64; 3],
    /// Excluded point–triangle pairs `p << 32 | f`, sorted.
    excluded_pt: Vec<u64>,
    /// Excluded edge–edge pairs `a << 32 | b` (edge indices, `a < b`), sorted.
    excluded_ee: Vec<u64>,
    /// The broad phase's pairs over a wider radius, reused while they cover a query, and the
    /// path length of the last query over paths.
    cache: std::sync::Mutex<Cached>,
    /// The widest margin a cache may have beyond a query's radius (m): twice the mean edge of
    /// the sheet, so that it holds a bounded number of pairs per primitive.
    cache_cap: Real,
    /// The force-controlled mesh obstacles (indices into the rigid bodies), in the order of
    /// their global DOFs; empty when none is: the stencil then has no fifth slot.
    pushed: Vec<usize>,
}

/// The pairs the broad phase found at the positions `at` within `reach`: a superset of what
/// it finds at any positions `x` (over the straight paths to `to`) within a radius `r`, as
/// long as no vertex is farther than `U` from `at` there, with `r + 2U ≤ reach` (the boxes
/// grow by at most `U` each). Such a query is served by the broad phase's own box test on the
/// cached pairs, in their order: the same pairs, in the same order, as the broad phase would
/// give, so the cache changes no result. It spares a Newton iteration's step bound the broad
/// phase over its paths.
struct Cache {
    /// The positions where the pairs were found (the sheet's and the obstacles').
    at: Vec<Vec3>,
    /// The broad phase's radius there (m).
    reach: Real,
    /// 1e-12 of the largest coordinate magnitude there (m), against rounding.
    slack: Real,
    /// Point–triangle pairs `(p, f)`, sorted, not excluded.
    pt: Vec<(u32, u32)>,
    /// Edge pairs `(a, b)`, `a < b`, sorted, not excluded.
    ee: Vec<(u32, u32)>,
    /// How far every pair is at `at` beyond where its law begins (m; [`SelfContact::room`]),
    /// when the cache was built for a query over paths (a Newton step's: the static
    /// gatherings of the explicit driver never ask).
    room: Option<Real>,
}

/// [`SelfContact`]'s cache of pairs.
#[derive(Default)]
struct Cached {
    /// The pairs, when some query built them.
    pairs: Option<Cache>,
    /// The longest path of the last query over paths (m).
    last: Real,
    /// The longest path of the queries over paths since the last jump (m).
    corrections: Real,
}

impl Cache {
    /// Twice the largest distance of a point of `x` (and of `to`) from `at`, plus the rounding
    /// slack (m): the most any pair's distance, or its boxes' gap, can have shrunk since the
    /// pairs were found. `None` for points of another scene (another count).
    fn spread(&self, x: &[Vec3], to: Option<&[Vec3]>) -> Option<Real> {
        if self.at.len() != x.len() {
            return None;
        }
        let u = farthest(x, &self.at).max(to.map_or(0.0, |t| farthest(t, &self.at)));
        // The boxes' bounds round at the coordinates' last bits: a margin of 1e-12 of the
        // largest keeps the superset exact.
        Some(2.0 * u + self.slack)
    }

    /// Whether the cache covers the query (struct doc).
    fn covers(&self, x: &[Vec3], to: Option<&[Vec3]>, r: Real) -> bool {
        self.spread(x, to).is_some_and(|s| r + s <= self.reach)
    }

    /// The cached pairs whose boxes at `x` (with `to`) overlap as the broad phase tests them
    /// with radius `r`: the broad phase's answer whenever the cached pairs hold it.
    #[allow(clippy::type_complexity)]
    fn filter(
        &self,
        faces: &[[usize; 3]],
        edges: &[[usize; 2]],
        x: &[Vec3],
        to: Option<&[Vec3]>,
        r: Real,
    ) -> (Vec<(u32, u32)>, Vec<(u32, u32)>) {
        let vertices: Vec<[usize; 1]> = (0..x.len()).map(|v| [v]).collect();
        let (fb, vb) = (
            broad::boxes(faces, x, to, r),
            broad::boxes(&vertices, x, to, 0.0),
        );
        let pt = self
            .pt
            .par_iter()
            .copied()
            .filter(|&(p, f)| fb[f as usize].overlaps(&vb[p as usize]))
            .collect();
        let (inflated, own) = (
            broad::boxes(edges, x, to, r),
            broad::boxes(edges, x, to, 0.0),
        );
        let ee = self
            .ee
            .par_iter()
            .copied()
            .filter(|&(a, b)| inflated[b as usize].overlaps(&own[a as usize]))
            .collect();
        (pt, ee)
    }
}

/// The rigid mesh obstacles' vertices and laws (`[[obstacles]]` with `shape = "mesh"`).
#[derive(Default)]
struct Rigid {
    /// Vertex positions at dial 0 (m).
    rest: Vec<Vec3>,
    /// Per vertex, its obstacle (an index into `bodies`).
    owner: Vec<u32>,
    /// Per vertex, a third of the area of its faces (m²).
    area: Vec<Real>,
    /// The obstacles.
    bodies: Vec<RigidBody>,
}

/// One rigid mesh obstacle's contact law.
struct RigidBody {
    /// Its index in `[[obstacles]]`.
    index: usize,
    /// Its file, for messages.
    file: String,
    /// Stiffness k of the normal law (Pa/m).
    stiffness: Real,
    /// The normal law's length (m): the penalty's smoothing δ, the barrier's activation ĝ.
    smoothing: Real,
    /// Coulomb coefficient μ against the sheet (0 in statics).
    friction: Real,
    /// Its displacement at dial 1 (m; zero when fixed or force-controlled).
    shift: Vec3,
    /// The force that pushes it, when it is force-controlled (`force`).
    push: Option<Push>,
}

/// A force-controlled mesh obstacle's push: it moves by `q ê`, `q` a global DOF of the solve
/// (module doc).
#[derive(Clone, Copy)]
struct Push {
    /// Unit direction ê of the force.
    direction: Vec3,
    /// Magnitude of the force at dial 1 (N).
    force: Real,
    /// Mass (kg; 0 in statics).
    mass: Real,
    /// Largest Newton step of the offset (m).
    max_step: Real,
    /// Its global node (set by [`GlobalDofs::bind`]).
    node: usize,
}

/// Whether the element with these four nodes is a point–triangle pair (module doc: the order
/// of the last two slots).
#[inline]
fn is_point_triangle(nodes: &[usize]) -> bool {
    nodes[2] > nodes[3]
}

/// The largest distance between corresponding points of `a` and `b` (m).
fn farthest(a: &[Vec3], b: &[Vec3]) -> Real {
    a.par_iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm_squared())
        .reduce(|| 0.0, Real::max)
        .sqrt()
}

/// The squared distance between the bounding boxes of the two sides of the pair with these
/// nodes at `y` (the point or first edge, the triangle or second edge): a lower bound of the
/// pair's distance (m²).
#[inline]
fn box_gap_squared(nodes: &[usize], y: &[Vec3; 4]) -> Real {
    let split = if is_point_triangle(nodes) { 1 } else { 2 };
    let (a, b) = y.split_at(split);
    let bounds = |p: &[Vec3]| {
        p.iter()
            .skip(1)
            .fold((p[0], p[0]), |(lo, hi), q| (lo.inf(q), hi.sup(q)))
    };
    let ((alo, ahi), (blo, bhi)) = (bounds(a), bounds(b));
    (blo - ahi)
        .sup(&(alo - bhi))
        .sup(&Vec3::zeros())
        .norm_squared()
}

/// The four positions of an element.
#[inline]
fn points(x: &[Vec3], nodes: &[usize]) -> [Vec3; 4] {
    std::array::from_fn(|i| x[nodes[i]])
}

/// The parts of [`SelfContact::clock`].
#[derive(Clone, Copy)]
enum Clock {
    Broad = 0,
    Ccd = 1,
    Assembly = 2,
}

/// A pair's friction over a step, lagged (module doc).
#[derive(Clone, Copy)]
struct Slip {
    /// `μ λ` (N).
    bound: Real,
    /// The closest points' coefficients.
    c: [Real; 4],
    /// The unit normal from the surface to the point.
    normal: Vec3,
}

/// A pair that presses ([`SelfContact::presses`]).
struct Press {
    /// Its index among the pairs.
    pair: usize,
    /// Its normal force λ (N).
    force: Real,
    /// Its stiffness along the normal, `m k w ψ″` (N/m; the penalty's, the mollifier's `m`
    /// held).
    stiffness: Real,
    /// The closest points' coefficients.
    c: [Real; 4],
    /// The unit normal from the surface to the point.
    normal: Vec3,
}

impl Slip {
    /// The relative motion `Σ cᵢ (xᵢ − x⁰ᵢ)` of the pair with these nodes over the step from
    /// `x_prev` to `x` (m; module doc).
    #[inline]
    fn moved(&self, nodes: &[usize], x: &[Vec3], x_prev: &[Vec3]) -> Vec3 {
        (0..4)
            .map(|i| (x[nodes[i]] - x_prev[nodes[i]]) * self.c[i])
            .sum()
    }
}

impl SelfContact {
    /// The internal number of node `u` of a stencil (struct doc).
    #[inline]
    fn at(&self, u: usize) -> usize {
        if u < ABSENT {
            u
        } else {
            self.nv + (u - ABSENT)
        }
    }

    /// The internal numbers of a stencil's pairs, four nodes each: without the fifth slot
    /// and the force elements a stencil has with force-controlled obstacles
    /// ([`Self::handed_out`]).
    fn internal<'a>(&self, nodes: &'a [usize]) -> Cow<'a, [usize]> {
        if self.rigid.rest.is_empty() {
            Cow::Borrowed(nodes)
        } else if self.pushed.is_empty() {
            Cow::Owned(nodes.iter().map(|&u| self.at(u)).collect())
        } else {
            let pairs = (nodes.len() / 5).saturating_sub(self.pushed.len());
            Cow::Owned(
                nodes[..5 * pairs]
                    .chunks_exact(5)
                    .flat_map(|n| n[..4].iter().map(|&u| self.at(u)))
                    .collect(),
            )
        }
    }

    /// The offset `q` (m) of rigid body `b` in the scalar DOFs `phi`: 0 unless it is
    /// force-controlled (and 0 where `phi` does not hold its DOF: the explicit driver's
    /// positions, which no force-controlled obstacle takes part in).
    #[inline]
    fn pushed_by(&self, b: usize, phi: &[Real]) -> Real {
        self.rigid.bodies[b]
            .push
            .map_or(0.0, |p| phi.get(p.node - self.nv).copied().unwrap_or(0.0))
    }

    /// The sheet's positions `x` followed by the obstacles' at dial `dial` (clamped to
    /// [0, 1]), a force-controlled one offset along its force by its DOF in `phi`.
    fn placed<'a>(&self, x: &'a [Vec3], phi: &[Real], dial: Real) -> Cow<'a, [Vec3]> {
        if self.rigid.rest.is_empty() {
            return Cow::Borrowed(x);
        }
        let s = dial.clamp(0.0, 1.0);
        let offsets: Vec<Vec3> = self
            .rigid
            .bodies
            .iter()
            .enumerate()
            .map(|(b, body)| {
                body.push
                    .map_or(Vec3::zeros(), |p| p.direction * self.pushed_by(b, phi))
            })
            .collect();
        let mut all = Vec::with_capacity(x.len() + self.rigid.rest.len());
        all.extend_from_slice(&x[..self.nv]);
        all.extend(
            self.rigid
                .rest
                .iter()
                .zip(&self.rigid.owner)
                .map(|(r, &b)| r + self.rigid.bodies[b as usize].shift * s + offsets[b as usize]),
        );
        Cow::Owned(all)
    }

    /// The force-controlled obstacle a pair (internal numbering) involves, as its body index.
    #[inline]
    fn pusher(&self, nodes: &[usize]) -> Option<usize> {
        let u = nodes.iter().copied().find(|&u| u >= self.nv)?;
        let b = self.rigid.owner[u - self.nv] as usize;
        self.rigid.bodies[b].push.is_some().then_some(b)
    }

    /// The obstacle of a pair that involves one (the one its rigid nodes belong to).
    #[inline]
    fn body(&self, nodes: &[usize]) -> Option<&RigidBody> {
        let u = nodes.iter().copied().find(|&u| u >= self.nv)?;
        Some(&self.rigid.bodies[self.rigid.owner[u - self.nv] as usize])
    }

    /// The stiffness k (Pa/m) and smoothing δ (m) of a pair: its obstacle's, or the sheet's.
    #[inline]
    fn material(&self, nodes: &[usize]) -> (Real, Real) {
        self.body(nodes)
            .map_or((self.stiffness, self.smoothing), |b| {
                (b.stiffness, b.smoothing)
            })
    }

    /// The Coulomb coefficient μ of a pair: its obstacle's, or the sheet's.
    #[inline]
    fn mu(&self, nodes: &[usize]) -> Real {
        self.body(nodes).map_or(self.friction, |b| b.friction)
    }

    /// Whether any pair has friction.
    fn has_friction(&self) -> bool {
        self.friction > 0.0 || self.rigid.bodies.iter().any(|b| b.friction > 0.0)
    }

    /// Runs `f`, adding its wall time to the clock of `part`.
    #[inline]
    fn timed<T>(&self, part: Clock, f: impl FnOnce() -> T) -> T {
        let start = std::time::Instant::now();
        let out = f();
        let ns = u64::try_from(start.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.clock[part as usize].fetch_add(ns, Ordering::Relaxed);
        out
    }

    /// The offset of the pair with these nodes (m).
    #[inline]
    fn offset(&self, nodes: &[usize]) -> Real {
        let h = &self.thickness;
        if is_point_triangle(nodes) {
            0.5 * (h[nodes[0]] + (h[nodes[1]] + h[nodes[2]] + h[nodes[3]]) / 3.0)
        } else {
            0.25 * (h[nodes[0]] + h[nodes[1]] + h[nodes[2]] + h[nodes[3]])
        }
    }

    /// The distance below which a pair presses and its area weight (m², module doc): a sheet
    /// vertex on a sheet face, the offset and half the vertex's area; on an obstacle's face, the
    /// offset and the whole area; an obstacle's vertex on a sheet face, the offset and half the
    /// smaller of the obstacle vertex's area and the mean of the face's vertex areas; two sheet
    /// edges, half the offset and a quarter of the mean of the four vertex areas; a sheet edge
    /// and an obstacle's, half the offset and a quarter of the mean of the sheet edge's two (the
    /// obstacle's entries of `area` are 0).
    #[inline]
    fn law(&self, nodes: &[usize]) -> (Real, Real) {
        let xi = self.offset(nodes);
        let a = &self.area;
        let rigid = |k: usize| nodes[k] >= self.nv;
        if is_point_triangle(nodes) {
            if rigid(0) {
                let face = (a[nodes[1]] + a[nodes[2]] + a[nodes[3]]) / 3.0;
                (xi, 0.5 * face.min(self.rigid.area[nodes[0] - self.nv]))
            } else if rigid(1) {
                (xi, a[nodes[0]])
            } else {
                (xi, 0.5 * a[nodes[0]])
            }
        } else {
            let sum = a[nodes[0]] + a[nodes[1]] + a[nodes[2]] + a[nodes[3]];
            let share = if rigid(0) || rigid(2) { 0.125 } else { 0.0625 };
            (0.5 * xi, share * sum)
        }
    }

    /// The normal law of the pair with these nodes at distance `d` (module doc), where it
    /// presses: `(k, A, φ, f, s)`, its energy `k A φ` with `k` the stiffness (Pa/m) and `A`
    /// the law's weight (m²), `f = −dφ/dd` (m; the force `k A f` pushes the pair apart) and
    /// `s = d²φ/dd²`. The penalty's `φ = ψ(r − d)` for `d < r`, the barrier's `φ = b(d − r)`
    /// for `d < r + ĝ` (`+∞` at `d ≤ r`), `r` the law's reach ([`Self::law`]).
    #[inline]
    fn normal(&self, nodes: &[usize], d: Real) -> Option<(Real, Real, Real, Real, Real)> {
        let (reach, weight) = self.law(nodes);
        let (k, delta) = self.material(nodes);
        let (phi, f, s) = if self.barrier {
            if d >= reach + delta {
                return None;
            }
            let (b, db, ddb) = barrier(d - reach, delta);
            (b, -db, ddb)
        } else {
            if d >= reach {
                return None;
            }
            penalty(reach - d, delta)
        };
        Some((k, weight, phi, f, s))
    }

    /// How far beyond its reach the pair with these nodes presses (m): its activation
    /// distance with the barrier, 0 with the penalty.
    #[inline]
    fn beyond(&self, nodes: &[usize]) -> Real {
        if self.barrier {
            self.material(nodes).1
        } else {
            0.0
        }
    }

    /// The distance the pair with these nodes may never come within (m): `s ξ` with the
    /// penalty, and with the barrier the larger of that and the law's reach, where the
    /// barrier is infinite (the CCD bound then keeps a tenth of the margin above it).
    #[inline]
    fn floor(&self, nodes: &[usize]) -> Real {
        let s = self.min_separation * self.offset(nodes);
        if self.barrier {
            s.max(self.law(nodes).0)
        } else {
            s
        }
    }

    /// Whether the pair with these nodes is farther apart than its floor at squared distance
    /// `d2` (strictly with the barrier, infinite at the floor).
    #[inline]
    fn clear(&self, nodes: &[usize], d2: Real) -> bool {
        let f = self.floor(nodes);
        if self.barrier {
            d2 > f * f
        } else {
            d2 >= f * f
        }
    }

    /// The mollifier `(m, m′, m″)` of an edge–edge pair at `y` where it is below 1 (nearly
    /// parallel edges), `None` elsewhere.
    #[inline]
    fn mollifier(&self, nodes: &[usize], y: &[Vec3; 4]) -> Option<(Real, Real, Real)> {
        let r = &self.rest;
        let eps = MOLLIFIER
            * (r[nodes[1]] - r[nodes[0]]).norm_squared()
            * (r[nodes[3]] - r[nodes[2]]).norm_squared();
        let (c, _) = distance::cross_squared(y, None);
        (c < eps).then(|| distance::mollifier(c, eps))
    }

    /// The closest points of an element at `x`.
    #[inline]
    fn closest(&self, x: &[Vec3; 4], nodes: &[usize]) -> distance::Closest {
        if is_point_triangle(nodes) {
            distance::point_triangle(x)
        } else {
            distance::edge_edge(x)
        }
    }

    /// The nodes of point–triangle pair `(p, f)` in slot order (module doc).
    #[inline]
    fn pt_nodes(&self, p: usize, f: usize) -> [usize; 4] {
        let mut t = self.faces[f];
        t.sort_unstable();
        [p, t[2], t[1], t[0]]
    }

    /// The nodes of edge–edge pair `(a, b)` (edge indices) in slot order.
    #[inline]
    fn ee_nodes(&self, a: usize, b: usize) -> [usize; 4] {
        let (ea, eb) = (self.edges[a], self.edges[b]);
        [ea[0], ea[1], eb[0], eb[1]]
    }

    /// Whether the pair with these nodes counts: one node at least on the sheet, and one on
    /// an obstacle unless the sheet's pairs with itself count.
    #[inline]
    fn counts(&self, nodes: &[usize; 4]) -> bool {
        let sheet = nodes.iter().filter(|&&u| u < self.nv).count();
        sheet > 0 && (self.self_pairs || sheet < 4)
    }

    /// The pairs the broad phase finds within `radius` at `x` (the sheet's and the obstacles'
    /// positions; over the straight paths to `to`, when given), not excluded: their nodes,
    /// point–triangle pairs first, each kind sorted.
    fn candidates(&self, x: &[Vec3], to: Option<&[Vec3]>, radius: Real) -> Vec<[usize; 4]> {
        let (pt, ee) = self.candidate_pairs(x, to, radius);
        pt.par_iter()
            .map(|&(p, f)| self.pt_nodes(p as usize, f as usize))
            .chain(
                ee.par_iter()
                    .map(|&(a, b)| self.ee_nodes(a as usize, b as usize)),
            )
            .filter(|n| self.counts(n))
            .collect()
    }

    /// The point–triangle pairs `(p, f)` and edge pairs `(a, b)` of [`Self::candidates`], each
    /// sorted: from the cache of pairs when it covers the query ([`Cache`]), else from the
    /// broad phase, caching a wider one first when the query is a Newton step's paths.
    ///
    /// A step's queries are one long jump (the predicted start, a whole step's motion) and
    /// then Newton's corrections, each a fraction of the one before. A cache as wide as a few
    /// corrections holds the pairs of the corrections that follow, and few of them; one as wide
    /// as the jump would hold the pairs of the whole sheet within a step's motion (on an
    /// 800-face cloth falling 3 cm per step, 85 thousand pairs where a correction's paths meet
    /// a few hundred), and box-testing them costs more than a broad phase. So a query over
    /// paths more than [`JUMP`] times longer than the last one (or than the halo, when that is
    /// longer) is a jump: one broad phase over its paths' boxes, inflated by a few of the last
    /// step's corrections beyond the query's radius, answers it (the pairs it finds at the
    /// query's radius, by the broad phase's own box test) and is cached around the jump's end,
    /// where Newton goes on. A pair that is not found is farther apart than the wider radius
    /// everywhere along the paths, at their end too.
    #[allow(clippy::type_complexity)]
    fn candidate_pairs(
        &self,
        x: &[Vec3],
        to: Option<&[Vec3]>,
        radius: Real,
    ) -> (Vec<(u32, u32)>, Vec<(u32, u32)>) {
        let moved = to.map_or(0.0, |t| farthest(x, t));
        let largest = |y: &[Vec3]| y.par_iter().map(|p| p.amax()).reduce(|| 0.0, Real::max);
        let mut cached = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let last = cached.last;
        if let Some(to) = to {
            cached.last = moved;
            if moved > JUMP * last.max(self.halo) {
                let margin = (3.0 * cached.corrections)
                    .max(self.halo)
                    .min(self.cache_cap);
                cached.corrections = 0.0;
                let (pt, ee) = self.broad_pairs(x, Some(to), radius + margin);
                let c = Cache {
                    at: to.to_vec(),
                    reach: radius + margin,
                    slack: 1e-12 * (1.0 + largest(x).max(largest(to))),
                    room: Some(self.room(to, radius + margin, &pt, &ee)),
                    pt,
                    ee,
                };
                let hit = c.filter(&self.faces, &self.edges, x, Some(to), radius);
                cached.pairs = Some(c);
                return hit;
            }
            cached.corrections = cached.corrections.max(moved);
        }
        if let Some(hit) = cached
            .pairs
            .as_ref()
            .filter(|c| c.covers(x, to, radius))
            .map(|c| c.filter(&self.faces, &self.edges, x, to, radius))
        {
            return hit;
        }
        // A few of this query's lengths (the corrections that follow are shorter), at least
        // the halo, at most the cap (which wins when the halo is wider: a sheet thicker than
        // its edges).
        let margin = (3.0 * moved).max(self.halo).min(self.cache_cap);
        if 2.0 * moved > margin {
            // Too far for a cache of bounded width: the broad phase over the paths.
            return self.broad_pairs(x, to, radius);
        }
        let (pt, ee) = self.broad_pairs(x, None, radius + margin);
        let c = Cache {
            at: x.to_vec(),
            reach: radius + margin,
            slack: 1e-12 * (1.0 + largest(x)),
            room: to.map(|_| self.room(x, radius + margin, &pt, &ee)),
            pt,
            ee,
        };
        let hit = c
            .covers(x, to, radius)
            .then(|| c.filter(&self.faces, &self.edges, x, to, radius));
        cached.pairs = Some(c);
        // Covered but for the rounding margin at the edge of the width: the broad phase.
        hit.unwrap_or_else(|| self.broad_pairs(x, to, radius))
    }

    /// The pairs of [`Self::candidate_pairs`] from the broad phase: those that count and are
    /// not excluded. Pairs that do not count are never stored: the sheet's with itself when
    /// only mesh obstacles are on (a free sheet's first step sweeps boxes over the whole
    /// sheet).
    #[allow(clippy::type_complexity)]
    fn broad_pairs(
        &self,
        x: &[Vec3],
        to: Option<&[Vec3]>,
        radius: Real,
    ) -> (Vec<(u32, u32)>, Vec<(u32, u32)>) {
        let (nv, nf, ne) = (
            self.nv as u32,
            self.sheet_faces as u32,
            self.sheet_edges as u32,
        );
        let both = |a: bool, b: bool| if a && b { self.self_pairs } else { a || b };
        let pt =
            broad::point_triangle_where(x, to, &self.faces, radius, |p, f| both(p < nv, f < nf));
        let ee = broad::edge_edge_where(x, to, &self.edges, radius, |a, b| both(a < ne, b < ne));
        let key = |a: u32, b: u32| (a as u64) << 32 | b as u64;
        (
            pt.into_par_iter()
                .filter(|&(p, f)| self.excluded_pt.binary_search(&key(p, f)).is_err())
                .collect(),
            ee.into_par_iter()
                .filter(|&(a, b)| self.excluded_ee.binary_search(&key(a, b)).is_err())
                .collect(),
        )
    }

    /// How far every pair is at `at` (the sheet's and the obstacles' positions) beyond where
    /// its law begins (its offset `ξ`, plus the barrier's activation distance), given the pairs
    /// `pt`, `ee` the broad phase found there within `reach` (m): each of those by its exact
    /// distance (or its boxes' gap, when that already exceeds the bound for the rest), every
    /// other by `reach` less the largest start. While no point moves half of it from `at`, no
    /// pair comes within its law: one that was not gathered cannot press.
    fn room(&self, at: &[Vec3], reach: Real, pt: &[(u32, u32)], ee: &[(u32, u32)]) -> Real {
        let rest = reach - (self.xi_max + self.beyond_max);
        let one = |n: [usize; 4]| {
            let start = self.offset(&n) + self.beyond(&n);
            let y = points(at, &n);
            if box_gap_squared(&n, &y) >= (start + rest).powi(2) {
                return rest;
            }
            self.closest(&y, &n).d2.sqrt() - start
        };
        let pts = pt
            .par_iter()
            .map(|&(p, f)| one(self.pt_nodes(p as usize, f as usize)));
        let ees = ee
            .par_iter()
            .map(|&(a, b)| one(self.ee_nodes(a as usize, b as usize)));
        pts.chain(ees).reduce(|| rest, Real::min)
    }

    /// Whether every pair at `x` (the sheet's and the obstacles' positions) is farther apart
    /// than its offset and `beyond`: no point is half the cache's room, less `beyond`, from
    /// where it was built ([`Self::room`]).
    fn clear_of_all(&self, x: &[Vec3], beyond: Real) -> bool {
        let cached = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        cached.pairs.as_ref().is_some_and(|c| {
            c.room
                .zip(c.spread(x, None))
                .is_some_and(|(room, s)| s < room - beyond)
        })
    }

    /// Whether no pair can come within its law on the straight paths from `x` to `to` (the
    /// sheet's and the obstacles' positions): every point stays within less than 0.45 of the
    /// cache's room from where it was built. Each pair's distance then changes by less than
    /// 0.9 of the room, and stays beyond where its law begins by a tenth of it. Such a query
    /// counts as one over paths for [`Self::candidate_pairs`]'s jumps.
    fn roomy(&self, x: &[Vec3], to: &[Vec3]) -> bool {
        let mut cached = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let passes = cached.pairs.as_ref().is_some_and(|c| {
            c.room
                .zip(c.spread(x, Some(to)))
                .is_some_and(|(room, s)| s < 0.9 * room)
        });
        if !passes {
            return false;
        }
        let moved = farthest(to, x);
        cached.last = moved;
        cached.corrections = cached.corrections.max(moved);
        true
    }

    /// The pairs within `beyond` of their offset at `x` (the sheet's and the obstacles'
    /// positions), not excluded: the stencil in the internal numbering, point–triangle pairs
    /// first (module doc for the slot order).
    fn pairs(&self, x: &[Vec3], beyond: Real) -> Stencil {
        self.timed(Clock::Broad, || self.pairs_untimed(x, beyond))
    }

    /// A stencil in the internal numbering as the solve numbers it (struct doc). With
    /// force-controlled obstacles, each pair has a fifth slot, the global node of the
    /// obstacle it involves (or none), and the stencil ends with one element per such
    /// obstacle, its force and inertia on its node alone.
    fn handed_out(&self, mut st: Stencil) -> Stencil {
        let solve = |u: usize| {
            if u >= self.nv {
                ABSENT + (u - self.nv)
            } else {
                u
            }
        };
        if self.pushed.is_empty() {
            for u in st.nodes.iter_mut() {
                *u = solve(*u);
            }
            return st;
        }
        let pairs = st.nodes.len() / 4;
        let mut nodes = Vec::with_capacity(5 * (pairs + self.pushed.len()));
        for n in st.nodes.chunks_exact(4) {
            nodes.extend(n.iter().map(|&u| solve(u)));
            nodes.push(self.pusher(n).map_or(NONE, |b| self.push_node(b)));
        }
        for &b in &self.pushed {
            nodes.extend_from_slice(&[NONE, NONE, NONE, NONE, self.push_node(b)]);
            st.anchors.push(self.rigid.rest[self.first_vertex(b)]);
        }
        st.nodes = nodes;
        st.slot_dofs = vec![3, 3, 3, 3, 1];
        st
    }

    /// The global node of force-controlled body `b`.
    #[inline]
    fn push_node(&self, b: usize) -> usize {
        self.rigid.bodies[b].push.map_or(NONE, |p| p.node)
    }

    /// The first vertex of rigid body `b` (an index into the obstacles' vertices).
    fn first_vertex(&self, b: usize) -> usize {
        self.rigid
            .owner
            .iter()
            .position(|&o| o as usize == b)
            .unwrap_or(0)
    }

    /// [`SelfContact::pairs`], untimed (the checks at build).
    fn pairs_untimed(&self, x: &[Vec3], beyond: Real) -> Stencil {
        let near: Vec<[usize; 4]> = if self.clear_of_all(x, beyond) {
            Vec::new()
        } else {
            self.candidates(x, None, self.xi_max + beyond)
                .into_par_iter()
                .filter(|n| {
                    let (y, within) = (points(x, n), (self.offset(n) + beyond).powi(2));
                    box_gap_squared(n, &y) < within && self.closest(&y, n).d2 < within
                })
                .collect()
        };
        let mut st = Stencil {
            slot_dofs: vec![3; 4],
            nodes: Vec::with_capacity(4 * near.len()),
            anchors: Vec::with_capacity(near.len()),
        };
        for n in &near {
            st.nodes.extend_from_slice(n);
            st.anchors.push(points(x, n).iter().sum::<Vec3>() / 4.0);
        }
        st
    }

    /// Area-weighted vertex normals at `x` (unnormalised: only their direction is used).
    fn vertex_normals(&self, x: &[Vec3]) -> Vec<Vec3> {
        let mut n = vec![Vec3::zeros(); x.len()];
        for f in &self.faces {
            let c = (x[f[1]] - x[f[0]]).cross(&(x[f[2]] - x[f[0]]));
            for &v in f {
                n[v] += c;
            }
        }
        n
    }

    /// Whether the bounding boxes of the pair's two sides (the point or first edge, the
    /// triangle or second edge) at `y` are at least as far apart as where its law begins
    /// (its reach, plus the barrier's activation distance): their distance bounds the pair's
    /// from below, so such a pair has no energy, and its exact distance is not needed.
    #[inline]
    fn beyond_reach(&self, nodes: &[usize], y: &[Vec3; 4]) -> bool {
        let reach = self.law(nodes).0 + self.beyond(nodes);
        box_gap_squared(nodes, y) >= reach * reach
    }

    /// Per pair of `nodes` (four per pair), whether it carries energy at `x`: every edge–edge
    /// pair, and of each vertex's point–triangle pairs the nearest on each side (module doc;
    /// ties go to the first in element order), or all of them with `all_pairs`; but none whose
    /// sides' bounding boxes are beyond its reach ([`Self::beyond_reach`]), which has no
    /// energy. (When a side's nearest pair is within reach, it is the nearest among those
    /// within reach; when it is not, no pair on that side is: leaving the others out of the
    /// choice changes no energy.)
    fn active(&self, nodes: &[usize], x: &[Vec3]) -> Vec<bool> {
        let ne = nodes.len() / 4;
        let near: Vec<bool> = (0..ne)
            .into_par_iter()
            .map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                !self.beyond_reach(n, &points(x, n))
            })
            .collect();
        let chosen = |e: usize| {
            let n = &nodes[4 * e..4 * e + 4];
            near[e] && is_point_triangle(n) && n[0] < self.nv
        };
        if self.all_pairs || !(0..ne).any(chosen) {
            return near;
        }
        let normals = self.vertex_normals(x);
        // Per sheet vertex's point–triangle pair: the vertex, and when within reach its side
        // and squared distance.
        let measured: Vec<Option<(usize, Option<Side>)>> = (0..ne)
            .into_par_iter()
            .map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                if !is_point_triangle(n) || n[0] >= self.nv {
                    // Edge pairs and an obstacle's vertices always count (the nearest face on
                    // each side of an obstacle's vertex stalled a mesh pressing a sheet).
                    return None;
                }
                if !near[e] {
                    return Some((n[0], None));
                }
                let y = points(x, n);
                let cl = distance::point_triangle(&y);
                let r = y[0] * cl.c[0] + y[1] * cl.c[1] + y[2] * cl.c[2] + y[3] * cl.c[3];
                Some((n[0], Some((r.dot(&normals[n[0]]) >= 0.0, cl.d2))))
            })
            .collect();
        let mut active = near;
        // Point–triangle elements come sorted by vertex: one run per vertex.
        let mut e = 0;
        while e < ne {
            let Some((p, _)) = measured[e] else {
                e += 1;
                continue;
            };
            let mut end = e;
            let mut best: [Option<(Real, usize)>; 2] = [None, None];
            while end < ne {
                match measured[end] {
                    Some((q, within)) if q == p => {
                        if let Some((side, d2)) = within {
                            let b = &mut best[usize::from(side)];
                            if b.is_none_or(|(bd, _)| d2 < bd) {
                                *b = Some((d2, end));
                            }
                        }
                        end += 1;
                    }
                    _ => break,
                }
            }
            for (k, a) in active[e..end].iter_mut().enumerate() {
                *a = best.iter().any(|b| b.is_some_and(|(_, i)| i == e + k));
            }
            e = end;
        }
        active
    }

    /// Energy, gradient and Hessian of one active element (module doc); with `gauss_newton`
    /// the Hessian is the positive semi-definite model `m w ψ″ ∇d ∇dᵀ`.
    fn element(
        &self,
        nodes: &[usize],
        x: &[Vec3],
        gauss_newton: bool,
        grad: Option<&mut SVec<12>>,
        hess: Option<&mut SMat<12, 12>>,
    ) -> Real {
        let y = points(x, nodes);
        let pt = is_point_triangle(nodes);
        let cl = self.closest(&y, nodes);
        if cl.d2 <= 0.0 {
            return no_contribution(grad, hess);
        }
        let d = cl.d2.sqrt();
        let Some((k, weight, psi, dpsi, ddpsi)) = self.normal(nodes, d) else {
            return no_contribution(grad, hess);
        };
        let w = k * weight;
        if !psi.is_finite() {
            // Inside the barrier's reach: an inadmissible state, which the line search refuses.
            no_contribution(grad, hess);
            return Real::INFINITY;
        }
        let mollifier = if pt { None } else { self.mollifier(nodes, &y) };
        let m = mollifier.map_or(1.0, |(m, _, _)| m);
        let energy = m * w * psi;
        if grad.is_none() && hess.is_none() {
            return energy;
        }
        let want_h = hess.is_some();
        let mut h2 = SMat::<12, 12>::zeros();
        let g2 = distance::derivatives(&y, &cl, want_h.then_some(&mut h2));
        // ∇d = ∇d²/(2d); E₀ = wφ(d) with φ′ = −f (`ψ′` for the penalty): ∇E₀ = −wf∇d.
        let gd = g2 / (2.0 * d);
        let g0 = gd * (-w * dpsi);
        // E = m E₀: ∇E = m∇E₀ + E₀∇m, ∇²E = m∇²E₀ + ∇m∇E₀ᵀ + ∇E₀∇mᵀ + E₀∇²m, with
        // ∇m = m′∇c and ∇²m = m″∇c∇cᵀ + m′∇²c.
        let mut hc = SMat::<12, 12>::zeros();
        let gc = mollifier.map(|_| distance::cross_squared(&y, want_h.then_some(&mut hc)).1);
        if let Some(g) = grad {
            *g = g0 * m;
            if let (Some((_, dm, _)), Some(gc)) = (mollifier, &gc) {
                *g += gc * (dm * w * psi);
            }
        }
        if let Some(h) = hess {
            if gauss_newton {
                // The Gauss–Newton model: the penalty's curvature along the distance alone,
                // m w ψ″ ∇d ∇dᵀ, positive semi-definite (the distance's own curvature and the
                // mollifier's derivatives are left out).
                *h = gd * gd.transpose() * (ddpsi * w * m);
                return energy;
            }
            // ∇²d = ∇²d²/(2d) − ∇d ∇dᵀ/d; ∇²E₀ = w(φ″∇d∇dᵀ − f∇²d).
            let hd = h2 / (2.0 * d) - gd * gd.transpose() / d;
            *h = (gd * gd.transpose() * ddpsi - hd * dpsi) * (w * m);
            if let (Some((_, dm, ddm)), Some(gc)) = (mollifier, &gc) {
                let gm = gc * dm;
                *h += gm * g0.transpose()
                    + g0 * gm.transpose()
                    + (gc * gc.transpose() * ddm + hc * dm) * (w * psi);
            }
        }
        energy
    }
}

impl SelfContact {
    /// The normal force `λ = m k w ψ′` (N) of every pair of `nodes` (four per pair) that
    /// carries energy at `x`, with its closest points' coefficients (module doc).
    fn forces(&self, nodes: &[usize], x: &[Vec3]) -> Vec<(usize, Real, [Real; 4])> {
        self.presses(nodes, x)
            .into_iter()
            .map(|p| (p.pair, p.force, p.c))
            .collect()
    }

    /// The pairs of `nodes` that press at `x` ([`Press`]), in pair order.
    fn presses(&self, nodes: &[usize], x: &[Vec3]) -> Vec<Press> {
        let active = self.active(nodes, x);
        (0..nodes.len() / 4)
            .into_par_iter()
            .filter(|&e| active[e])
            .filter_map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                let y = points(x, n);
                let cl = self.closest(&y, n);
                let d = cl.d2.sqrt();
                if d <= 0.0 {
                    return None;
                }
                let (k, weight, _, f, s) = self.normal(n, d)?;
                let m = if is_point_triangle(n) {
                    1.0
                } else {
                    self.mollifier(n, &y).map_or(1.0, |(m, _, _)| m)
                };
                let r: Vec3 = (0..4).map(|i| y[i] * cl.c[i]).sum();
                Some(Press {
                    pair: e,
                    force: m * k * weight * f,
                    stiffness: m * k * weight * s,
                    c: cl.c,
                    normal: r / d,
                })
            })
            .collect()
    }

    /// Per pair of `nodes`, its friction at the lag's iterate `x_lag` (module doc): the bound
    /// `μ λ` (N), the closest points' coefficients and the unit normal, for the pairs that press
    /// there; `None` for the others.
    fn lagged_friction(&self, nodes: &[usize], x_lag: &[Vec3]) -> Vec<Option<Slip>> {
        let mut out = vec![None; nodes.len() / 4];
        for (e, lambda, c) in self.forces(nodes, x_lag) {
            let n = &nodes[4 * e..4 * e + 4];
            let mu = self.mu(n);
            let y = points(x_lag, n);
            let r: Vec3 = (0..4).map(|i| y[i] * c[i]).sum();
            let norm = r.norm();
            if norm > 0.0 && lambda > 0.0 && mu > 0.0 {
                out[e] = Some(Slip {
                    bound: mu * lambda,
                    c,
                    normal: r / norm,
                });
            }
        }
        out
    }

    /// The friction step of the pairs `nodes` (internal numbering): the potential's friction,
    /// the step's start placed at its dial (the obstacles where they were), and each pair's
    /// friction lagged at the lag's iterate and dial.
    fn step_friction<'f>(
        &self,
        fr: crate::energy::potential::Friction<'f>,
        nodes: &[usize],
    ) -> (
        crate::energy::potential::Friction<'f>,
        Vec<Vec3>,
        Vec<Option<Slip>>,
    ) {
        // A force-controlled obstacle is frictionless: its pairs have no friction to lag, and
        // its place (offset 0 here) in these positions is never read.
        let lag = self.placed(fr.x_lag, &[], fr.dial_lag);
        let prev = self.placed(fr.x_prev, &[], fr.dial_prev).into_owned();
        (fr, prev, self.lagged_friction(nodes, &lag))
    }

    /// The friction of one pair at `x` over the step from `x_prev` with slip smoothing `eps`
    /// (module doc): its dissipation, added to `grad` and `hess` (DOF order of the pair).
    fn slip(
        s: &Slip,
        nodes: &[usize],
        x: &[Vec3],
        x_prev: &[Vec3],
        eps: Real,
        grad: Option<&mut SVec<12>>,
        hess: Option<&mut SMat<12, 12>>,
    ) -> Real {
        let (e, g, h) = friction_potential(s.bound, &s.normal, &s.moved(nodes, x, x_prev), eps);
        if let Some(grad) = grad {
            for i in 0..4 {
                for a in 0..3 {
                    grad[3 * i + a] += s.c[i] * g[a];
                }
            }
        }
        if let Some(hess) = hess {
            for i in 0..4 {
                for j in 0..4 {
                    let cc = s.c[i] * s.c[j];
                    for a in 0..3 {
                        for b in 0..3 {
                            hess[(3 * i + a, 3 * j + b)] += cc * h[a][b];
                        }
                    }
                }
            }
        }
        e
    }

    /// The normal force on each vertex (N) from the pairs of `nodes` that press at `x`, each
    /// pair's force shared by its closest points' coefficients.
    fn vertex_forces(&self, nodes: &[usize], x: &[Vec3]) -> Vec<Real> {
        let mut f = vec![0.0; x.len()];
        for (e, lambda, c) in self.forces(nodes, x) {
            for (k, ci) in c.iter().enumerate() {
                f[nodes[4 * e + k]] += lambda * ci.abs();
            }
        }
        f
    }

    /// Energy of the term at `x` (with its gradient and Hessian as `want` asks), with the
    /// friction when `with_friction` and the potential carries a step's.
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
        with_friction: bool,
    ) -> Real {
        if map.nodes.is_empty() {
            return 0.0;
        }
        let all = self.internal(&map.nodes);
        let x = &*self.placed(x, phi, pot.dial);
        let active = self.active(&all, x);
        let gauss_newton = projection == HessianProjection::GaussNewton;
        let friction = pot
            .friction
            .filter(|_| with_friction && self.has_friction())
            .map(|fr| self.step_friction(fr, &all));
        let pair = |e: usize, mut g: Option<&mut SVec<12>>, mut h: Option<&mut SMat<12, 12>>| {
            let nodes = &all[4 * e..4 * e + 4];
            let mut energy = if active[e] {
                self.element(nodes, x, gauss_newton, g.as_deref_mut(), h.as_deref_mut())
            } else {
                no_contribution(g.as_deref_mut(), h.as_deref_mut())
            };
            if let Some((fr, prev, Some(s))) =
                friction.as_ref().map(|(fr, prev, l)| (fr, prev, &l[e]))
            {
                energy += Self::slip(s, nodes, x, prev, fr.eps, g, h);
            }
            energy
        };
        if self.pushed.is_empty() {
            return assemble_elements::<12, 4, _>(
                map,
                |e, _, g, h| pair(e, g, h),
                pot.node_fixed,
                projection,
                want,
                grad,
                values,
                &pot.pattern.col_ptr,
            );
        }
        let pairs = all.len() / 4;
        assemble_elements::<13, 5, _>(
            map,
            |e, slots, g, h| {
                if e >= pairs {
                    return self.force_element(pot, phi, self.pushed[e - pairs], g, h);
                }
                let nodes = &all[4 * e..4 * e + 4];
                let direction = self
                    .pusher(nodes)
                    .and_then(|b| self.rigid.bodies[b].push)
                    .map(|p| p.direction);
                debug_assert_eq!(direction.is_some(), slots[4] != NONE);
                let (mut g12, mut h12) = (SVec::<12>::zeros(), SMat::<12, 12>::zeros());
                let energy = pair(
                    e,
                    g.is_some().then_some(&mut g12),
                    h.is_some().then_some(&mut h12),
                );
                Self::pushed_pair(nodes, self.nv, direction, &g12, &h12, g, h);
                energy
            },
            pot.node_fixed,
            projection,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
        )
    }

    /// A pair's derivatives in the DOF order of a stencil with force-controlled obstacles:
    /// its twelve coordinates, then the offset `q` of the obstacle it involves, if it is
    /// pushed along `direction` ê. Its rigid vertices move with `q` by `ê`, so with `P` the
    /// twelve-vector of `ê` in their slots (0 in the sheet's), `∂E/∂q = Pᵀg`,
    /// `∂²E/∂x∂q = H P` and `∂²E/∂q² = PᵀHP`; the rigid slots, no DOFs of the solve, are
    /// cleared, so that a projected Hessian is the projection of the one over the pair's true
    /// DOFs.
    fn pushed_pair(
        nodes: &[usize],
        nv: usize,
        direction: Option<Vec3>,
        g12: &SVec<12>,
        h12: &SMat<12, 12>,
        grad: Option<&mut SVec<13>>,
        hess: Option<&mut SMat<13, 13>>,
    ) {
        let mut p = SVec::<12>::zeros();
        if let Some(u) = direction {
            for (i, &n) in nodes.iter().enumerate() {
                if n >= nv {
                    p.fixed_rows_mut::<3>(3 * i).copy_from(&u);
                }
            }
        }
        let rigid = |k: usize| direction.is_some() && nodes[k / 3] >= nv;
        if let Some(g) = grad {
            g.fixed_rows_mut::<12>(0).copy_from(g12);
            g[12] = p.dot(g12);
            for k in (0..12).filter(|&k| rigid(k)) {
                g[k] = 0.0;
            }
        }
        if let Some(h) = hess {
            let hp = h12 * p;
            h.fixed_view_mut::<12, 12>(0, 0).copy_from(h12);
            h.fixed_view_mut::<12, 1>(0, 12).copy_from(&hp);
            h.fixed_view_mut::<1, 12>(12, 0).copy_from(&hp.transpose());
            h[(12, 12)] = p.dot(&hp);
            for k in (0..12).filter(|&k| rigid(k)) {
                h.row_mut(k).fill(0.0);
                h.column_mut(k).fill(0.0);
            }
        }
    }

    /// The force's element of force-controlled body `b` ([`crate::energy::obstacles::pressed::push`]),
    /// in the fifth slot's DOF.
    fn force_element(
        &self,
        pot: &Potential,
        phi: &[Real],
        b: usize,
        grad: Option<&mut SVec<13>>,
        hess: Option<&mut SMat<13, 13>>,
    ) -> Real {
        let Some(p) = self.rigid.bodies[b].push else {
            return no_contribution(grad, hess);
        };
        let k = p.node - self.nv;
        let (e, dq, ddq) = crate::energy::obstacles::pressed::push(
            pot,
            k,
            self.pushed_by(b, phi),
            p.force,
            p.mass,
        );
        if let Some(g) = grad {
            g.fill(0.0);
            g[12] = dq;
        }
        if let Some(h) = hess {
            h.fill(0.0);
            h[(12, 12)] = ddq;
        }
        e
    }

    /// The sum over the pairs of the magnitudes of their friction forces at `x` over the
    /// potential's step (N; 0 without one).
    fn friction_force(&self, pot: &Potential, map: &ElementMap, x: &[Vec3], phi: &[Real]) -> Real {
        let Some(fr) = pot.friction.as_ref() else {
            return 0.0;
        };
        let nodes = self.internal(&map.nodes);
        let x = &*self.placed(x, phi, pot.dial);
        let (_, prev, lagged) = self.step_friction(*fr, &nodes);
        let per_pair: Vec<Real> = (0..lagged.len())
            .into_par_iter()
            .map(|e| {
                lagged[e].as_ref().map_or(0.0, |s| {
                    let moved = s.moved(&nodes[4 * e..4 * e + 4], x, &prev);
                    friction_potential(s.bound, &s.normal, &moved, fr.eps)
                        .1
                        .norm()
                })
            })
            .collect();
        // Summed in pair order: the same bits on any thread count.
        per_pair.iter().sum()
    }

    /// This term's element map in `pot`'s pattern.
    fn map<'p>(&self, pot: &Potential<'p>) -> Option<&'p ElementMap> {
        let i = pot.terms.iter().position(|t| t.name() == self.name())?;
        pot.pattern.maps.get(i)
    }
}

impl Reports for SelfContact {
    /// The normal law's energy alone (the friction is dissipated, not stored).
    fn energies(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
    ) -> Option<Vec<(&'static str, Real)>> {
        let e = self.assemble(
            pot,
            map,
            x,
            phi,
            Want::Energy,
            HessianProjection::None,
            &mut [],
            &mut [],
            false,
        );
        Some(vec![(self.name, e)])
    }

    /// `NAME_pairs` (NAME the term's name, `self_contact` or `mesh_obstacles`): the pairs
    /// that press; `NAME_friction` (with friction): the sum of the magnitudes of their friction
    /// forces (N); `NAME_broad_seconds`, `NAME_ccd_seconds`, `NAME_assembly_seconds`: the wall
    /// time spent so far in the broad phase and gathering, in CCD and the separation checks,
    /// and in the term's assembly (s); `NAME_gap`: the smallest distance of a gathered pair over
    /// its offset (the gathering's reach over the offset when none was gathered);
    /// `NAME_force`: the sum of the pairs' normal forces (N). Per mesh obstacle `i`:
    /// `obstacle{i}_force_x/y/z`, the force its pairs exert on the sheet (N, the normal law's
    /// and, with friction, the friction's), and `obstacle{i}_gap`, the smallest `d − ξ` of its
    /// gathered pairs (m; the halo when none is gathered).
    fn observables(&self, pot: &Potential, x: &[Vec3], phi: &[Real]) -> Vec<(String, Real)> {
        let Some(map) = self.map(pot) else {
            return Vec::new();
        };
        let nodes = self.internal(&map.nodes);
        let xs = x;
        let x = &*self.placed(x, phi, pot.dial);
        let forces = self.forces(&nodes, x);
        let gap = nodes
            .par_chunks(4)
            .map(|n| self.closest(&points(x, n), n).d2.sqrt() / self.offset(n))
            .reduce(
                || 1.0 + self.halo / self.xi_max.max(Real::MIN_POSITIVE),
                Real::min,
            );
        let name = self.name;
        let mut out = vec![
            (format!("{name}_pairs"), forces.len() as Real),
            (format!("{name}_gap"), gap),
            (format!("{name}_force"), forces.iter().map(|f| f.1).sum()),
        ];
        if self.has_friction() {
            out.push((
                format!("{name}_friction"),
                self.friction_force(pot, map, xs, phi),
            ));
        }
        for (part, clock) in [
            ("broad", Clock::Broad),
            ("ccd", Clock::Ccd),
            ("assembly", Clock::Assembly),
        ] {
            let ns = self.clock[clock as usize].load(Ordering::Relaxed);
            out.push((format!("{name}_{part}_seconds"), ns as Real * 1e-9));
        }
        out.extend(self.rigid_observables(pot, &nodes, x, phi));
        out
    }

    /// `contact_pressure` (Pa): per face, the mean over its vertices of the normal force the
    /// pairs put on the vertex (shared by the closest points' coefficients) over its area;
    /// `contact_gap` (m): per face, the smallest `d − ξ` of the gathered pairs that involve one
    /// of its vertices (the halo where none does).
    fn face_fields(&self, pot: &Potential, x: &[Vec3], phi: &[Real]) -> Vec<(String, Vec<Real>)> {
        let Some(map) = self.map(pot) else {
            return Vec::new();
        };
        let nodes = self.internal(&map.nodes);
        let x = &*self.placed(x, phi, pot.dial);
        let force = self.vertex_forces(&nodes, x);
        let mut gap = vec![self.halo; x.len()];
        for n in nodes.chunks(4) {
            let g = self.closest(&points(x, n), n).d2.sqrt() - self.offset(n);
            for &v in n {
                gap[v] = gap[v].min(g);
            }
        }
        let per_face =
            |f: &[usize; 3], per: &dyn Fn(usize) -> Real| (per(f[0]) + per(f[1]) + per(f[2])) / 3.0;
        let sheet = &self.faces[..self.sheet_faces];
        let pressure = sheet
            .iter()
            .map(|f| {
                per_face(f, &|v| {
                    if self.area[v] > 0.0 {
                        force[v] / self.area[v]
                    } else {
                        0.0
                    }
                })
            })
            .collect();
        let face_gap = sheet
            .iter()
            .map(|f| gap[f[0]].min(gap[f[1]]).min(gap[f[2]]))
            .collect();
        vec![
            ("contact_pressure".into(), pressure),
            ("contact_gap".into(), face_gap),
        ]
    }
}

impl SelfContact {
    /// Per mesh obstacle, its force on the sheet and its smallest gap ([`Self::observables`]).
    fn rigid_observables(
        &self,
        pot: &Potential,
        nodes: &[usize],
        x: &[Vec3],
        phi: &[Real],
    ) -> Vec<(String, Real)> {
        if self.rigid.bodies.is_empty() {
            return Vec::new();
        }
        let active = self.active(nodes, x);
        let friction = pot
            .friction
            .filter(|_| self.has_friction())
            .map(|fr| self.step_friction(fr, nodes));
        let nb = self.rigid.bodies.len();
        // Per pair with an obstacle: the obstacle, −∇E summed over its sheet nodes (the force
        // on the sheet) and the pair's d − ξ. Summed in pair order below.
        let per_pair: Vec<Option<(usize, Vec3, Real)>> = (0..nodes.len() / 4)
            .into_par_iter()
            .map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                let u = n.iter().copied().find(|&u| u >= self.nv)?;
                let b = self.rigid.owner[u - self.nv] as usize;
                let mut g = SVec::<12>::zeros();
                if active[e] {
                    self.element(n, x, false, Some(&mut g), None);
                }
                if let Some((fr, prev, Some(s))) =
                    friction.as_ref().map(|(fr, prev, l)| (fr, prev, &l[e]))
                {
                    Self::slip(s, n, x, prev, fr.eps, Some(&mut g), None);
                }
                let f: Vec3 = (0..4)
                    .filter(|&i| n[i] < self.nv)
                    .map(|i| -Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2]))
                    .sum();
                let gap = self.closest(&points(x, n), n).d2.sqrt() - self.offset(n);
                Some((b, f, gap))
            })
            .collect();
        let mut force = vec![Vec3::zeros(); nb];
        let mut gap = vec![self.halo; nb];
        for (b, f, g) in per_pair.into_iter().flatten() {
            force[b] += f;
            gap[b] = gap[b].min(g);
        }
        let mut out = Vec::new();
        for (k, body) in self.rigid.bodies.iter().enumerate() {
            let i = body.index;
            for (c, v) in ["x", "y", "z"].iter().zip(force[k].iter()) {
                out.push((format!("obstacle{i}_force_{c}"), *v));
            }
            out.push((format!("obstacle{i}_gap"), gap[k]));
            if body.push.is_some() {
                out.push((format!("obstacle{i}_offset"), self.pushed_by(k, phi)));
            }
        }
        out
    }
}

impl SelfContact {
    /// [`StepLimit::displacement_bounds`] over the gathered pairs `nodes` (internal numbering)
    /// at the positions `y` (the sheet's, then the obstacles').
    fn bounds_at(&self, nodes: &[usize], y: &[Vec3], bounds: &mut [Real]) {
        let cap = 0.5 * (self.halo - self.beyond_max);
        for b in bounds.iter_mut().take(self.nv) {
            *b = b.min(cap);
        }
        let room: Vec<Real> = (0..nodes.len() / 4)
            .into_par_iter()
            .map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                let d = self.closest(&points(y, n), n).d2.sqrt();
                (0.5 * (d - self.floor(n))).max(0.0)
            })
            .collect();
        for (n, r) in nodes.chunks_exact(4).zip(room) {
            for &u in n.iter().filter(|&&u| u < self.nv) {
                bounds[u] = bounds[u].min(r);
            }
        }
    }
}

impl GlobalDofs for SelfContact {
    /// The offset of each force-controlled mesh obstacle along its force (m), as an analytic
    /// force-controlled obstacle's ([`crate::energy::obstacles::pressed`]).
    fn dofs(&self) -> Vec<GlobalDof> {
        self.pushed
            .iter()
            .filter_map(|&b| {
                let body = &self.rigid.bodies[b];
                body.push.map(|p| GlobalDof {
                    name: format!("obstacle{}_offset", body.index),
                    length: 1.0,
                    max_step: p.max_step,
                    mass: p.mass,
                })
            })
            .collect()
    }

    fn bind(&mut self, first_node: usize) {
        for (k, &b) in self.pushed.iter().enumerate() {
            if let Some(p) = self.rigid.bodies[b].push.as_mut() {
                p.node = first_node + k;
            }
        }
    }
}

impl ChangingElements for SelfContact {
    fn stencil_at(&self, _: &Body, x: &[Vec3], phi: &[Real], dial: Real) -> Stencil {
        self.handed_out(self.pairs(&self.placed(x, phi, dial), self.halo))
    }
}

impl LaggedNormals for SelfContact {
    /// Over the vertices, the largest normal force the pairs put on one at `trial`, and the
    /// largest change of one from the lagged iterate (the pairs that press at each).
    fn lag_change(&self, trial: &[Vec3], dial: Real, lag: &[Vec3], dial_lag: Real) -> (Real, Real) {
        // One after the other: each gathering is timed on the broad phase's clock.
        // A force-controlled obstacle is frictionless: its pairs, whose place these positions
        // do not hold, are left out.
        let at = |x: &[Vec3], dial: Real| {
            let x = self.placed(x, &[], dial);
            let nodes: Vec<usize> = self
                .pairs(&x, 0.0)
                .nodes
                .chunks_exact(4)
                .filter(|n| self.pusher(n).is_none())
                .flatten()
                .copied()
                .collect();
            self.vertex_forces(&nodes, &x)
        };
        let (new, old) = (at(trial, dial), at(lag, dial_lag));
        new.iter().zip(&old).fold((0.0, 0.0), |(s, d), (a, b)| {
            (Real::max(s, *a), Real::max(d, (a - b).abs()))
        })
    }
}

impl ExplicitHooks for SelfContact {
    /// A dashpot on each pressing pair's normal approach, then Coulomb stick/slip on its
    /// slip, for the pairs that press at `x` in the step `dt`. With `c` a pair's closest
    /// points' coefficients, `n` its normal, `λ` its normal force, `K` its normal stiffness
    /// (`m k w ψ″`) and `v*ᵢ = vᵢ − Δt gᵢ/mᵢ` the velocity each of its sheet vertices would
    /// reach (a mesh obstacle's vertices move at its displacement × the dial's rate,
    /// `Potential::dial_rate`), the pair's relative velocity is `Σ cᵢ vᵢ` and `w = Σ cᵢ²/mᵢ`
    /// its inverse mass along it.
    ///
    /// *Dashpot* (`damping` ζ, a fraction of critical damping of the pair on its penalty
    /// spring, `c = 2ζ √(K/w)`): the backward-Euler normal impulse `J = −c Δt u_n/(1 + c Δt w)`,
    /// `u_n = n·Σ cᵢ v*ᵢ`, which leaves the pair the approach `u_n − w J` and so never stops
    /// it outright (a dashpot that did would hold a load at rest that the spring never
    /// carries), and no more pull while the pair parts than its spring pushes (`λ Δt`), so
    /// that contact never sticks. Without it an explicit contact
    /// rings at its own frequency, undamped by the driver's drag, and a sheet resting on
    /// another chatters: it loses its grip while its vertices hop, and creeps down a slope
    /// steeper than friction allows.
    ///
    /// *Friction* (μ > 0), solved together by projected Gauss–Seidel on the impulses: each
    /// pair's slip is the tangential part `u` of `Σ cᵢ vᵢ` with the impulses so far, and its
    /// impulse `J` is updated to `J − u/w`, projected onto the disc `|J| ≤ μ N`, `N` the pair's
    /// whole normal impulse (its spring's `λ Δt` and its dashpot's): inside, the pair sticks;
    /// on the edge it slides with Coulomb's force against its slip. Sweeps in pair
    /// order until no impulse changes by more than 1e-9 of the largest bound (at most
    /// [`FRICTION_SWEEPS`]).
    ///
    /// The impulses enter as the forces `cᵢ J/Δt` on the vertices.
    fn explicit_step(&self, pot: &Potential, x: &[Vec3], v: &mut [Vec3], g: &mut [Real], dt: Real) {
        let Some(map) = self.map(pot) else {
            return;
        };
        let nodes = self.internal(&map.nodes);
        // No force-controlled obstacle in explicit mode.
        let y = self.placed(x, &[], pot.dial);
        let fixed = &pot.body.fixed;
        let free = |u: usize| u < self.nv && !fixed[u] && pot.mass[u] > 0.0;
        let pairs: Vec<(&[usize], Press, Real)> = self
            .presses(&nodes, &y)
            .into_iter()
            .filter_map(|p| {
                let n = &nodes[4 * p.pair..4 * p.pair + 4];
                let w: Real = (0..4)
                    .filter(|&i| free(n[i]))
                    .map(|i| p.c[i] * p.c[i] / pot.mass[n[i]])
                    .sum();
                (w > 0.0).then_some((n, p, w))
            })
            .collect();
        if pairs.is_empty() {
            return;
        }
        // The velocities the step would reach, then with the impulses.
        let mut reach: std::collections::BTreeMap<usize, Vec3> = Default::default();
        for (n, _, _) in &pairs {
            for &u in n.iter().filter(|&&u| free(u)) {
                reach.entry(u).or_insert_with(|| {
                    let gu = Vec3::new(g[3 * u], g[3 * u + 1], g[3 * u + 2]);
                    v[u] - gu * (dt / pot.mass[u])
                });
            }
        }
        // A mesh obstacle moved with the dial moves at its displacement × the dial's rate.
        let carried = |u: usize| {
            if u >= self.nv && u < y.len() {
                self.rigid.bodies[self.rigid.owner[u - self.nv] as usize].shift * pot.dial_rate
            } else {
                Vec3::zeros()
            }
        };
        let relative =
            |reach: &std::collections::BTreeMap<usize, Vec3>, n: &[usize], c: &[Real; 4]| {
                (0..4)
                    .map(|i| {
                        if free(n[i]) {
                            reach[&n[i]] * c[i]
                        } else {
                            carried(n[i]) * c[i]
                        }
                    })
                    .sum::<Vec3>()
            };
        let apply = |reach: &mut std::collections::BTreeMap<usize, Vec3>,
                     n: &[usize],
                     c: &[Real; 4],
                     j: Vec3| {
            for i in (0..4).filter(|&i| free(n[i])) {
                if let Some(r) = reach.get_mut(&n[i]) {
                    *r += j * (c[i] / pot.mass[n[i]]);
                }
            }
        };
        let mut impulse = vec![Vec3::zeros(); pairs.len()];
        if self.damping > 0.0 {
            for (k, (n, p, w)) in pairs.iter().enumerate() {
                // Backward Euler on the dashpot, `J = c Δt u'` with `u' = u − w J` the approach
                // it leaves: `J = c Δt u/(1 + c Δt w)` from the velocity `u` the step would
                // reach. It never stops the approach outright (which would hold a load at rest
                // that the spring never carries), and it is stable at any stiffness.
                let un = p.normal.dot(&relative(&reach, n, &p.c));
                let rate = 2.0 * self.damping * (p.stiffness / w).sqrt() * dt;
                let jn = (-rate * un / (1.0 + rate * w)).max(-p.force * dt);
                let j = p.normal * jn;
                apply(&mut reach, n, &p.c, j);
                impulse[k] = j;
            }
        }
        let rough: Vec<usize> = (0..pairs.len())
            .filter(|&k| self.mu(pairs[k].0) > 0.0)
            .collect();
        let mut friction = vec![Vec3::zeros(); pairs.len()];
        let largest = rough
            .iter()
            .map(|&k| {
                self.mu(pairs[k].0) * (pairs[k].1.force * dt + pairs[k].1.normal.dot(&impulse[k]))
            })
            .fold(0.0, Real::max);
        for _ in 0..FRICTION_SWEEPS {
            let mut change: Real = 0.0;
            for &k in &rough {
                let (n, p, w) = &pairs[k];
                let rel = relative(&reach, n, &p.c);
                let slip = rel - p.normal * p.normal.dot(&rel);
                // Coulomb's bound on the whole normal impulse, the spring's and the dashpot's.
                let limit = self.mu(n) * (p.force * dt + p.normal.dot(&impulse[k]));
                let mut j = friction[k] - slip / *w;
                let size = j.norm();
                if size > limit {
                    j *= limit / size;
                }
                let delta = j - friction[k];
                if delta == Vec3::zeros() {
                    continue;
                }
                apply(&mut reach, n, &p.c, delta);
                friction[k] = j;
                change = change.max(delta.norm());
            }
            if change <= 1e-9 * largest {
                break;
            }
        }
        for (((n, p, _), j), f) in pairs.iter().zip(&impulse).zip(&friction) {
            for i in (0..4).filter(|&i| free(n[i])) {
                let force = (j + f) * (p.c[i] / dt);
                let u = n[i];
                for k in 0..3 {
                    g[3 * u + k] -= force[k];
                }
            }
        }
    }
}

/// How many times longer than the last query's (or the halo, when longer) a query's paths
/// must be to count as a jump, answered by the broad phase without a new cache
/// ([`SelfContact::candidate_pairs`]).
const JUMP: Real = 4.0;

/// The most projected Gauss–Seidel sweeps of the explicit friction between sheets per step.
const FRICTION_SWEEPS: usize = 100;

impl StepLimit for SelfContact {
    /// The smallest of each gathered pair's additive CCD fraction to its floor (`s ξ`; with
    /// the barrier, at least the law's reach), and of each other pair's fraction to its offset
    /// `ξ` (with the barrier, `ξ` plus the activation distance), where its law would begin: a
    /// pair that was not gathered may not press within the step. The others are found by the
    /// broad phase over the boxes of the straight paths, inflated by that distance. When one
    /// of them would begin to press and is within the gathering's reach now, gathering again
    /// at `x` adds it and allows the longer step. The broad phase is skipped while no sheet
    /// vertex (nor force-controlled obstacle) has moved from where the pairs were gathered by
    /// more than 0.45 of the halo (less the barrier's activation distance) along the step: no
    /// pair not gathered can then come near its law. A force-controlled obstacle's vertices
    /// move along the step by its offset's step times its direction; the others stand still.
    fn max_fraction(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        step: &[Real],
    ) -> StepBound {
        let nv = self.nv;
        // Each obstacle's offset step (a force-controlled one's, 0 for the others) and its move
        // along the step, the offset step along its force.
        let dq: Vec<Real> = self
            .rigid
            .bodies
            .iter()
            .map(|b| {
                b.push
                    .map_or(0.0, |p| step[crate::elements::node_dofs(nv, p.node).0])
            })
            .collect();
        let pushes: Vec<Vec3> = self
            .rigid
            .bodies
            .iter()
            .zip(&dq)
            .map(|(b, &d)| b.push.map_or(Vec3::zeros(), |p| p.direction * d))
            .collect();
        let dx = |v: usize| {
            if v < nv {
                Vec3::new(step[3 * v], step[3 * v + 1], step[3 * v + 2])
            } else {
                pushes[self.rigid.owner[v - nv] as usize]
            }
        };
        let nodes = &*self.internal(&map.nodes);
        let sheet = x;
        let x = &*self.placed(x, phi, pot.dial);
        let gathered = self.timed(Clock::Ccd, || {
            (0..nodes.len() / 4)
                .into_par_iter()
                .map(|e| {
                    let n = &nodes[4 * e..4 * e + 4];
                    let d: [Vec3; 4] = std::array::from_fn(|i| dx(n[i]));
                    let d_min = self.floor(n);
                    ccd::safe_fraction(&points(x, n), &d, is_point_triangle(n), d_min, 1.0)
                })
                .reduce(|| 1.0, Real::min)
        });
        // The pairs not gathered: where the pairs were gathered (the solver's positions, or `x`
        // outside a solve), they were farther apart than their offset and the halo.
        let (taken, taken_phi) = if pot.taken_at.len() == sheet.len() {
            (pot.taken_at, pot.taken_dofs)
        } else {
            (sheet, phi)
        };
        // The force-controlled obstacles' offsets from where the pairs were gathered, now and
        // at the step's end.
        let pushed_from: Vec<(Real, Real)> = self
            .pushed
            .iter()
            .map(|&b| {
                let now = self.pushed_by(b, phi) - self.pushed_by(b, taken_phi);
                (now, now + dq[b])
            })
            .collect();
        let moved = (!std::ptr::eq(taken, sheet) && taken != sheet)
            || pushed_from.iter().any(|&(now, _)| now != 0.0);
        // Every pair not gathered was at least the halo beyond where its law begins (its
        // offset, plus the barrier's activation distance) where the pairs were gathered, and
        // along the step its distance has changed by at most twice the largest displacement
        // of a sheet vertex or an obstacle from there. While that is below 0.9 of the margin,
        // none comes within its law, nor within the tenth of its margin at which the CCD below
        // would stop: the broad phase over the paths is skipped (a scene with nothing near
        // contact then pays O(n) per step bound).
        let far = (0..nv)
            .into_par_iter()
            .map(|v| {
                let (a, b) = (sheet[v] - taken[v], sheet[v] + dx(v) - taken[v]);
                a.norm_squared().max(b.norm_squared())
            })
            .reduce(|| 0.0, Real::max)
            .sqrt()
            .max(
                pushed_from
                    .iter()
                    .fold(0.0, |m: Real, &(a, b)| m.max(a.abs()).max(b.abs())),
            );
        if 2.0 * far < 0.9 * (self.halo - self.beyond_max) {
            return StepBound {
                fraction: gathered,
                regather: false,
            };
        }
        let to: Vec<Vec3> = (0..x.len()).map(|v| x[v] + dx(v)).collect();
        // Newton's corrections after a jump: every pair was far enough from its law where the
        // broad phase's pairs were last cached for these paths to stay clear of it.
        if self.timed(Clock::Broad, || self.roomy(x, &to)) {
            return StepBound {
                fraction: gathered,
                regather: false,
            };
        }
        let taken = &*self.placed(taken, taken_phi, pot.dial);
        let candidates = self.timed(Clock::Broad, || {
            self.candidates(x, Some(&to), self.xi_max + self.beyond_max)
        });
        let others = self.timed(Clock::Ccd, || {
            candidates
                .into_par_iter()
                .map(|n| {
                    let d: [Vec3; 4] = std::array::from_fn(|i| dx(n[i]));
                    let y = points(x, &n);
                    let xi = self.offset(&n);
                    let start = xi + self.beyond(&n);
                    let t = ccd::safe_fraction(&y, &d, is_point_triangle(&n), start, 1.0);
                    // The gathering's own test (`pairs`): those within reach were gathered, and
                    // answer to the bound above.
                    if t >= 1.0
                        || self.closest(&points(taken, &n), &n).d2 < (xi + self.halo).powi(2)
                    {
                        return (1.0, false);
                    }
                    // Within reach now: gathering again would add it.
                    (t, self.closest(&y, &n).d2 < (xi + self.halo).powi(2))
                })
                .reduce(|| (1.0, false), |a, b| (a.0.min(b.0), a.1 || b.1))
        });
        if others.0 < gathered && others.1 && moved {
            return StepBound {
                fraction: others.0,
                regather: true,
            };
        }
        StepBound {
            fraction: gathered.min(others.0),
            regather: false,
        }
    }

    /// The smallest additive CCD fraction to their floor (`s ξ`; with the barrier, at least the
    /// law's reach) of the pairs the broad phase finds over the
    /// boxes of the jump's straight paths (the sheet from `from` to `to`, the mesh obstacles
    /// from their place at `from_dial` to theirs at `pot.dial`), inflated by the largest
    /// offset.
    fn jump_fraction(
        &self,
        pot: &Potential,
        from: &[Vec3],
        to: &[Vec3],
        phi: &[Real],
        from_dial: Real,
    ) -> Real {
        let (x0, x1) = (
            self.placed(from, phi, from_dial),
            self.placed(to, phi, pot.dial),
        );
        if x0 == x1 {
            return 1.0;
        }
        let candidates = self.timed(Clock::Broad, || {
            self.candidates(&x0, Some(&x1), self.xi_max)
        });
        self.timed(Clock::Ccd, || {
            candidates
                .into_par_iter()
                .map(|n| {
                    let d: [Vec3; 4] = std::array::from_fn(|i| x1[n[i]] - x0[n[i]]);
                    let d_min = self.floor(&n);
                    ccd::safe_fraction(&points(&x0, &n), &d, is_point_triangle(&n), d_min, 1.0)
                })
                .reduce(|| 1.0, Real::min)
        })
    }

    /// Every sheet vertex may move half the halo (less the barrier's activation distance) from
    /// `x`, and half its room to the floor in each gathered pair it belongs to,
    /// `(d − max(s ξ, r))/2` at the pair's distance `d` there. A pair's distance shrinks by at
    /// most the largest displacement of its point (or first edge) plus that of its triangle
    /// (or second edge), every point of which is a convex combination of its vertices; a mesh
    /// obstacle that moves with the dial takes the other half ([`StepLimit::dial_room`]). So a
    /// gathered pair stays at or above its floor, and one that was not gathered, at least
    /// `ξ + halo` apart at `x`, stays beyond the reach of its law.
    fn displacement_bounds(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        bounds: &mut [Real],
    ) {
        let nodes = &*self.internal(&map.nodes);
        // No force-controlled obstacle in explicit mode.
        let y = &*self.placed(x, &[], pot.dial);
        self.timed(Clock::Ccd, || self.bounds_at(nodes, y, bounds));
    }

    /// Each mesh obstacle moved with the dial may move half the halo from its place at
    /// `pot.dial`, and half the room to the floor of each gathered pair it is part of: with
    /// every sheet vertex within its bound (which leaves each pair's other half to it), a
    /// gathered pair stays at or above its floor, and one that was not gathered, at least
    /// `ξ + halo` apart at `x`, beyond the reach of its law. An obstacle moved by `u` at dial 1
    /// moves by `|u| Δs` over a change `Δs` of the dial (the dial clamped to [0, 1] moves no
    /// more): the room is the least of those radii over `|u|`.
    fn dial_room(&self, pot: &Potential, map: &ElementMap, x: &[Vec3]) -> Real {
        let moving: Vec<Real> = self.rigid.bodies.iter().map(|b| b.shift.norm()).collect();
        if moving.iter().all(|&u| u == 0.0) {
            return Real::INFINITY;
        }
        let nodes = &*self.internal(&map.nodes);
        let y = &*self.placed(x, &[], pot.dial);
        let mut room = vec![0.5 * (self.halo - self.beyond_max); moving.len()];
        let per_pair: Vec<Option<(usize, Real)>> = (0..nodes.len() / 4)
            .into_par_iter()
            .map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                let u = n.iter().copied().find(|&u| u >= self.nv)?;
                let b = self.rigid.owner[u - self.nv] as usize;
                let d = self.closest(&points(y, n), n).d2.sqrt();
                Some((b, (0.5 * (d - self.floor(n))).max(0.0)))
            })
            .collect();
        for (b, r) in per_pair.into_iter().flatten() {
            room[b] = room[b].min(r);
        }
        room.iter()
            .zip(&moving)
            .filter(|(_, &u)| u > 0.0)
            .map(|(r, u)| r / u)
            .fold(Real::INFINITY, Real::min)
    }

    /// Every pair at least `s ξ` apart, and with the barrier farther than its law's reach.
    fn admits(&self, pot: &Potential, map: &ElementMap, x: &[Vec3], phi: &[Real]) -> bool {
        let nodes = &*self.internal(&map.nodes);
        let x = &*self.placed(x, phi, pot.dial);
        self.timed(Clock::Ccd, || {
            (0..nodes.len() / 4).into_par_iter().all(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                self.clear(n, self.closest(&points(x, n), n).d2)
            })
        })
    }
}

impl Term for SelfContact {
    fn name(&self) -> &'static str {
        self.name
    }
    fn stencil(&self, body: &Body) -> Stencil {
        self.handed_out(self.pairs(&self.placed(&body.mesh.positions, &[], 0.0), self.halo))
    }
    fn changing(&self) -> Option<&dyn ChangingElements> {
        Some(self)
    }
    fn global_dofs(&mut self) -> Option<&mut dyn GlobalDofs> {
        (!self.pushed.is_empty()).then_some(self as &mut dyn GlobalDofs)
    }
    fn step_limit(&self) -> Option<&dyn StepLimit> {
        Some(self)
    }
    fn lagged(&self) -> Option<&dyn LaggedNormals> {
        self.has_friction().then_some(self as &dyn LaggedNormals)
    }
    fn explicit(&self) -> Option<&dyn ExplicitHooks> {
        (self.damping > 0.0 || self.has_friction()).then_some(self as &dyn ExplicitHooks)
    }
    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }
    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        self.timed(Clock::Assembly, || {
            self.assemble(pot, map, x, phi, want, projection, grad, values, true)
        })
    }
}

/// The term of `[self_contact]` and the mesh obstacles of `[[obstacles]]` on `body`, or
/// `None` when self-contact is disabled and no obstacle is a mesh; friction only when
/// `dynamic`; `explicit_step` the explicit driver's time step Δt (s) in explicit mode, which
/// caps the default stiffness. Errors name the obstacle's file and key: a file that is no
/// valid triangle mesh, an obstacle that crosses the sheet or lies within its offset at rest.
pub fn term(
    body: &Body,
    c: &crate::config::self_contact::SelfContact,
    obstacles: &[crate::config::obstacle::ObstacleSettings],
    dynamic: bool,
    explicit_step: Option<Real>,
) -> Result<Option<Box<dyn Term>>, MeshError> {
    Ok(build(body, c, obstacles, dynamic, explicit_step)?.map(|sc| Box::new(sc) as Box<dyn Term>))
}

/// The default stiffness (Pa/m) of the sheet's pairs and of the mesh obstacles' pairs: the
/// area-weighted mean E/h, and in explicit mode (step `dt`, s) at most the stiffest spring the
/// step resolves at `ω Δt = 1`. A vertex pressed on a rigid face with its area `A` and mass
/// `ρ h A` has `ω² = k/(ρh)`: `ρ h/Δt²`, as for the analytic obstacles. Between sheets
/// each vertex presses with half its area and is pressed through its faces by the other
/// sheet's vertices; in a stack of many sheets the highest mode of the chain of layers,
/// neighbours moving against each other, has `ω² → 4k/(ρh)`: `ρ h/(4Δt²)`. `h` is the mean
/// thickness.
fn default_stiffness(
    ca: &crate::body::ContactAreas,
    density: Real,
    dt: Option<Real>,
) -> (Real, Real) {
    match dt {
        Some(dt) => {
            let rho_h = density * ca.h_mean;
            (
                ca.e_over_h.min(rho_h / (4.0 * dt * dt)),
                ca.e_over_h.min(rho_h / (dt * dt)),
            )
        }
        None => (ca.e_over_h, ca.e_over_h),
    }
}

/// [`term`], unboxed.
fn build(
    body: &Body,
    c: &crate::config::self_contact::SelfContact,
    obstacles: &[crate::config::obstacle::ObstacleSettings],
    dynamic: bool,
    explicit_step: Option<Real>,
) -> Result<Option<SelfContact>, MeshError> {
    let meshes: Vec<(usize, &crate::config::obstacle::ObstacleSettings)> = obstacles
        .iter()
        .enumerate()
        .filter(|(_, o)| o.shape == Some(crate::config::obstacle::ShapeKind::Mesh))
        .collect();
    if !c.enabled && meshes.is_empty() {
        return Ok(None);
    }
    let mesh = &body.mesh;
    let ca = crate::body::ContactAreas::of(mesh, &body.thickness, &body.young);
    let thickness: Vec<Real> = match c.offset {
        crate::config::values::AutoOr::Value(xi) => vec![xi; mesh.positions.len()],
        _ => ca.half_thickness.iter().map(|h| 2.0 * h).collect(),
    };
    let xi_max = thickness.iter().copied().fold(0.0, Real::max);
    let smoothing = c.smoothing.or(ca.h_mean / 100.0);
    let (k_sheet, k_rigid) = default_stiffness(&ca, body.density, explicit_step);
    let mut edges: Vec<[usize; 2]> = body
        .topo
        .edges
        .iter()
        .map(|e| [e[0].min(e[1]), e[0].max(e[1])])
        .collect();
    edges.sort_unstable();
    let mut sc = SelfContact {
        name: if c.enabled {
            "self_contact"
        } else {
            "mesh_obstacles"
        },
        nv: mesh.positions.len(),
        sheet_faces: mesh.faces.len(),
        sheet_edges: edges.len(),
        self_pairs: c.enabled,
        rigid: Rigid::default(),
        faces: mesh.faces.clone(),
        edges,
        rest: mesh.positions.clone(),
        thickness,
        area: ca.area.clone(),
        stiffness: c.stiffness.or(k_sheet),
        smoothing,
        barrier: c.law == crate::config::self_contact::Law::Barrier,
        beyond_max: 0.0,
        xi_max,
        halo: c.halo.or(xi_max),
        exclusion: c.exclusion.or(2.0 * (xi_max + smoothing)),
        min_separation: c.min_separation,
        friction: if dynamic || explicit_step.is_some() {
            c.friction
        } else {
            0.0
        },
        all_pairs: c.pairs == crate::config::self_contact::Pairs::All,
        damping: if explicit_step.is_some() {
            c.damping
        } else {
            0.0
        },
        clock: Default::default(),
        cache: Default::default(),
        cache_cap: 2.0 * body.mean_edge,
        excluded_pt: Vec::new(),
        excluded_ee: Vec::new(),
        pushed: Vec::new(),
    };
    if c.enabled {
        exclude(&mut sc, body)?;
    }
    for (i, o) in meshes {
        add_rigid(
            &mut sc,
            i,
            o,
            &ca,
            k_rigid,
            dynamic || explicit_step.is_some(),
        )?;
    }
    if sc.barrier {
        sc.beyond_max = sc
            .rigid
            .bodies
            .iter()
            .map(|b| b.smoothing)
            .chain(c.enabled.then_some(sc.smoothing))
            .fold(0.0, Real::max);
        // The pairs the barrier acts on must be gathered where it begins.
        if sc.beyond_max >= sc.halo {
            let key = match sc.rigid.bodies.iter().find(|b| b.smoothing >= sc.halo) {
                Some(b) => format!("obstacles[{}].smoothing", b.index),
                None => "self_contact.smoothing".to_string(),
            };
            return Err(MeshError::Invalid {
                path: "[self_contact]".into(),
                reason: format!(
                    "{key}: the barrier's activation distance {} must be below \
                     self_contact.halo ({}), the distance beyond the offset within which pairs \
                     are gathered: lower it, or raise the halo",
                    crate::math::human(sc.beyond_max),
                    crate::math::human(sc.halo)
                ),
            });
        }
    }
    if !sc.rigid.rest.is_empty() {
        check_rigid(&sc)?;
    }
    Ok(Some(sc))
}

/// Reads mesh obstacle `i` (`o`) and appends its vertices, faces and edges to the term's, with
/// its law: the obstacle's `stiffness` and `smoothing`, by default `k_default`
/// ([`default_stiffness`]) and the mean thickness over 100, and its `friction` when `dynamic`
/// (a mode with time to slip over: dynamic or explicit). Vertices that no face uses are
/// dropped.
fn add_rigid(
    sc: &mut SelfContact,
    i: usize,
    o: &crate::config::obstacle::ObstacleSettings,
    ca: &crate::body::ContactAreas,
    k_default: Real,
    dynamic: bool,
) -> Result<(), MeshError> {
    let file = o.file.clone().unwrap_or_default();
    let named = |e: MeshError| MeshError::Invalid {
        path: file.clone(),
        reason: format!(
            "obstacles[{i}].file: {}",
            match e {
                MeshError::Read { reason, .. }
                | MeshError::Write { reason, .. }
                | MeshError::Invalid { reason, .. } => reason,
            }
        ),
    };
    let m = crate::mesh::io::read_mesh(std::path::Path::new(&file)).map_err(named)?;
    m.validate().map_err(named)?;
    let first = sc.rest.len();
    let (scale, translate) = (
        o.scale.unwrap_or(1.0),
        Vec3::from(o.translate.unwrap_or([0.0; 3])),
    );
    let mut number = vec![usize::MAX; m.positions.len()];
    for f in &m.faces {
        for &v in f {
            if number[v] == usize::MAX {
                number[v] = sc.rest.len();
                sc.rest.push(m.positions[v] * scale + translate);
            }
        }
    }
    let added = sc.rest.len() - first;
    let owner = sc.rigid.bodies.len() as u32;
    sc.rigid.rest.extend_from_slice(&sc.rest[first..]);
    sc.rigid.owner.extend(std::iter::repeat_n(owner, added));
    sc.thickness.extend(std::iter::repeat_n(0.0, added));
    sc.area.extend(std::iter::repeat_n(0.0, added));
    let mut area = vec![0.0; added];
    let mut edges = Vec::with_capacity(3 * m.faces.len());
    for f in &m.faces {
        let t = f.map(|v| number[v]);
        let y = t.map(|v| sc.rest[v]);
        let third = 0.5 * (y[1] - y[0]).cross(&(y[2] - y[0])).norm() / 3.0;
        for &v in &t {
            area[v - first] += third;
        }
        sc.faces.push(t);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push([a.min(b), a.max(b)]);
        }
    }
    edges.sort_unstable();
    edges.dedup();
    sc.edges.extend(edges);
    sc.rigid.area.extend(area);
    let push = match o.control(i).map_err(|e| MeshError::Invalid {
        path: file.clone(),
        reason: format!("{}: {}", e.key, e.reason),
    })? {
        crate::config::obstacle::Control::Moved(_) => None,
        crate::config::obstacle::Control::Pressed {
            direction,
            magnitude,
            mass,
        } => Some(Push {
            direction: Vec3::from(direction),
            force: magnitude,
            mass: mass.unwrap_or(0.0),
            // As an analytic force-controlled obstacle's.
            max_step: ca.h_mean / 2.0,
            node: NONE,
        }),
    };
    if push.is_some() {
        sc.pushed.push(sc.rigid.bodies.len());
    }
    sc.rigid.bodies.push(RigidBody {
        index: i,
        file,
        stiffness: o.stiffness.unwrap_or(k_default),
        smoothing: o.smoothing.unwrap_or(ca.h_mean / 100.0),
        friction: if dynamic { o.friction } else { 0.0 },
        shift: Vec3::from(o.displacement),
        push,
    });
    Ok(())
}

/// Checks the sheet against the mesh obstacles at rest (dial 0): no edge of one through a
/// face of the other, and no pair within the distance where it would press (touching, to
/// 1e-9 of the offset, is allowed). Errors name the obstacle's file and key, its face or
/// vertex and the sheet's.
fn check_rigid(sc: &SelfContact) -> Result<(), MeshError> {
    let x = &*sc.placed(&sc.rest[..sc.nv], &[], 0.0);
    let (ne, nf) = (sc.sheet_edges, sc.sheet_faces);
    let body_err = |n: &[usize], reason: String| match sc.body(n) {
        Some(b) => MeshError::Invalid {
            path: b.file.clone(),
            reason: format!("obstacles[{}]: {reason}", b.index),
        },
        None => MeshError::Invalid {
            path: "[[obstacles]]".into(),
            reason,
        },
    };
    if let Some((e, f)) = crossing(x, &sc.edges, &sc.faces, |e, f| (e < ne) != (f < nf)) {
        let [a, b] = sc.edges[e];
        let t = sc.faces[f];
        let (what, with) = if e < ne {
            (
                format!("the sheet's edge {a}–{b}"),
                format!("the obstacle's face {}", f - nf),
            )
        } else {
            (
                format!("the obstacle's edge {}–{}", a - sc.nv, b - sc.nv),
                format!("the sheet's face {f}"),
            )
        };
        return Err(body_err(
            &[a, b, t[0], t[1]],
            format!(
                "{what} passes through {with} in the reference state: the sheet must start \
                 clear of the obstacle (move it, or let its displacement bring it in)"
            ),
        ));
    }
    let near = sc.pairs_untimed(x, 0.0);
    for n in near
        .nodes
        .chunks(4)
        .filter(|n| n.iter().any(|&u| u >= sc.nv))
    {
        let (reach, _) = sc.law(n);
        let d = sc.closest(&points(x, n), n).d2.sqrt();
        // With the barrier, touching is infinite energy.
        let inside = if sc.barrier {
            d <= reach
        } else {
            d < reach - 1e-9 * sc.offset(n)
        };
        if inside {
            let which = if is_point_triangle(n) && n[0] < sc.nv {
                format!("the sheet's vertex {}", n[0])
            } else if is_point_triangle(n) {
                format!("the obstacle's vertex {}", n[0] - sc.nv)
            } else {
                format!("the sheet's edge {}–{}", n[0], n[1])
            };
            return Err(body_err(
                n,
                format!(
                    "{which} is {} from the obstacle's surface at rest, within the {} where \
                     contact begins (half the sheet's thickness): move the obstacle away, or \
                     let its displacement bring it in",
                    crate::math::human(d),
                    crate::math::human(reach)
                ),
            ));
        }
    }
    Ok(())
}

/// Fills the exclusion lists (module doc) and checks the reference state: a pair close in
/// space but far along the sheet and closer than its offset is an error naming its faces.
fn exclude(sc: &mut SelfContact, body: &Body) -> Result<(), MeshError> {
    let x = &body.mesh.positions;
    let r = sc.exclusion;
    let longest = sc
        .edges
        .iter()
        .map(|e| (x[e[1]] - x[e[0]]).norm())
        .fold(0.0, Real::max);
    let graph = 2.0 * r + 2.0 * longest;
    if let Some((e, f)) = crossing(x, &sc.edges, &sc.faces, |_, _| true) {
        let [a, b] = sc.edges[e];
        let g = (0..sc.faces.len())
            .find(|&g| sc.faces[g].contains(&a) && sc.faces[g].contains(&b))
            .unwrap_or(0);
        return Err(body.mesh.invalid(format!(
            "self_contact: faces {g} and {f} intersect in the reference state (the edge \
             {a}–{b} of face {g} passes through face {f}): the sheet must start free of \
             crossings"
        )));
    }
    let adjacency = Adjacency::new(x.len(), &sc.edges, x);
    // Point–triangle pairs within r in space, grouped by vertex.
    let pt = broad::point_triangle(x, None, &sc.faces, r);
    let pt: Vec<(u32, u32, Real)> = pt
        .into_par_iter()
        .filter_map(|(p, f)| {
            let t = sc.faces[f as usize];
            let d2 = distance::point_triangle(&[x[p as usize], x[t[0]], x[t[1]], x[t[2]]]).d2;
            (d2 < r * r).then_some((p, f, d2.sqrt()))
        })
        .collect();
    let ee = broad::edge_edge(x, None, &sc.edges, r);
    let ee: Vec<(u32, u32, Real)> = ee
        .into_par_iter()
        .filter_map(|(a, b)| {
            let (ea, eb) = (sc.edges[a as usize], sc.edges[b as usize]);
            let d2 = distance::edge_edge(&[x[ea[0]], x[ea[1]], x[eb[0]], x[eb[1]]]).d2;
            (d2 < r * r).then_some((a, b, d2.sqrt()))
        })
        .collect();
    // Close along the sheet too: a vertex of the other primitive within the graph radius.
    let pt_flags: Vec<bool> = pt
        .par_iter()
        .map(|&(p, f, _)| adjacency.within(p as usize, graph, &sc.faces[f as usize]))
        .collect();
    let ee_flags: Vec<bool> = ee
        .par_iter()
        .map(|&(a, b, _)| {
            let (ea, eb) = (sc.edges[a as usize], sc.edges[b as usize]);
            adjacency.within(ea[0], graph + longest, &eb)
        })
        .collect();
    for (&(p, f, d), &close) in pt.iter().zip(&pt_flags) {
        if close {
            sc.excluded_pt.push((p as u64) << 32 | f as u64);
        } else {
            let n = sc.pt_nodes(p as usize, f as usize);
            if d < sc.offset(&n) {
                return Err(body.mesh.invalid(format!(
                    "self_contact: vertex {p} and face {f} are {} apart in the reference \
                     state, closer than their offset {} though far apart along the sheet: \
                     separate the layers, or set self_contact.offset smaller",
                    crate::math::human(d),
                    crate::math::human(sc.offset(&n)),
                )));
            }
        }
    }
    for (&(a, b, d), &close) in ee.iter().zip(&ee_flags) {
        if close {
            sc.excluded_ee.push((a as u64) << 32 | b as u64);
        } else {
            let n = sc.ee_nodes(a as usize, b as usize);
            if d < sc.offset(&n) {
                return Err(body.mesh.invalid(format!(
                    "self_contact: edges {}–{} and {}–{} are {} apart in the reference state, \
                     closer than their offset {} though far apart along the sheet: separate \
                     the layers, or set self_contact.offset smaller",
                    n[0],
                    n[1],
                    n[2],
                    n[3],
                    crate::math::human(d),
                    crate::math::human(sc.offset(&n)),
                )));
            }
        }
    }
    sc.excluded_pt.sort_unstable();
    sc.excluded_ee.sort_unstable();
    // Pairs not excluded that are within the offset at rest: the exclusion radius is too small
    // for this mesh and offset.
    let reach = sc.pairs_untimed(x, 0.0);
    if let Some(n) = reach.nodes.chunks(4).next() {
        let d = sc.closest(&points(x, n), n).d2.sqrt();
        return Err(body.mesh.invalid(format!(
            "self_contact: the pair of vertices {:?} is {} apart at rest, within its offset {}, \
             yet not excluded: raise self_contact.exclusion to at least {} (or refine the mesh, \
             or set a smaller self_contact.offset)",
            n,
            crate::math::human(d),
            crate::math::human(sc.offset(n)),
            crate::math::human(2.0 * sc.offset(n) + longest),
        )));
    }
    Ok(())
}

/// The first edge (in edge order) that passes through a face at `x`, with that face (the
/// face first in order); `None` when the surface has no crossing. Edges and faces that share a
/// vertex are not tested.
fn crossing(
    x: &[Vec3],
    edges: &[[usize; 2]],
    faces: &[[usize; 3]],
    keep: impl Fn(usize, usize) -> bool + Sync,
) -> Option<(usize, usize)> {
    broad::edge_triangle(x, edges, faces)
        .into_par_iter()
        .filter(|&(e, f)| keep(e as usize, f as usize))
        .find_first(|&(e, f)| {
            let (ed, t) = (edges[e as usize], faces[f as usize]);
            distance::segment_crosses_triangle(&[x[ed[0]], x[ed[1]], x[t[0]], x[t[1]], x[t[2]]])
        })
        .map(|(e, f)| (e as usize, f as usize))
}

/// The mesh's edge graph with reference edge lengths, for bounded Dijkstra searches.
struct Adjacency {
    start: Vec<usize>,
    next: Vec<(usize, Real)>,
}

impl Adjacency {
    fn new(nv: usize, edges: &[[usize; 2]], x: &[Vec3]) -> Adjacency {
        let mut count = vec![0usize; nv + 1];
        for e in edges {
            count[e[0] + 1] += 1;
            count[e[1] + 1] += 1;
        }
        for i in 0..nv {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut next = vec![(0, 0.0); count[nv]];
        for e in edges {
            let l = (x[e[1]] - x[e[0]]).norm();
            next[fill[e[0]]] = (e[1], l);
            fill[e[0]] += 1;
            next[fill[e[1]]] = (e[0], l);
            fill[e[1]] += 1;
        }
        Adjacency { start: count, next }
    }

    /// Whether any of `targets` is within graph distance `reach` of `from`.
    fn within(&self, from: usize, reach: Real, targets: &[usize]) -> bool {
        if targets.contains(&from) {
            return true;
        }
        let mut dist: std::collections::HashMap<usize, Real> = std::collections::HashMap::new();
        let mut heap = std::collections::BinaryHeap::new();
        dist.insert(from, 0.0);
        heap.push(std::cmp::Reverse((Ordered(0.0), from)));
        while let Some(std::cmp::Reverse((Ordered(d), v))) = heap.pop() {
            if dist.get(&v).is_some_and(|&dv| d > dv) {
                continue;
            }
            if targets.contains(&v) {
                return true;
            }
            for &(u, l) in &self.next[self.start[v]..self.start[v + 1]] {
                let du = d + l;
                if du <= reach && dist.get(&u).is_none_or(|&old| du < old) {
                    dist.insert(u, du);
                    heap.push(std::cmp::Reverse((Ordered(du), u)));
                }
            }
        }
        false
    }
}

/// A finite real with a total order, for the heap.
#[derive(Clone, Copy, PartialEq)]
struct Ordered(Real);
impl Eq for Ordered {}
impl PartialOrd for Ordered {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ordered {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{rectangle, Rng, Spacing};

    /// A 1 × 0.2 strip of thickness `h` with self-contact (edges about 0.05), built.
    fn strip(h: Real) -> (Body, SelfContact) {
        let mesh = rectangle(
            0.0,
            0.0,
            1.0,
            0.2,
            0.05,
            Spacing {
                jitter: 0.2,
                seed: 7,
                ..Default::default()
            },
        );
        let settings = crate::settings::Settings::from_str_with(
            &format!("[material]\nthickness = {h}\nyoung = 1e6\n[self_contact]\nenabled = true\n"),
            "test",
            &[],
        )
        .unwrap();
        let body = Body::build(mesh, &settings).unwrap();
        let sc = build(&body, &settings.self_contact, &[], false, None)
            .unwrap()
            .unwrap();
        (body, sc)
    }

    /// The cache of broad-phase pairs ([`Cache`]) serves exactly what the broad phase finds:
    /// a 1 × 0.2 strip (h = 0.05) folded flat onto itself 0.06 apart, queried over random
    /// paths whose lengths grow by 1.3× from 1e-4 to 0.2 (each over the gathering's static
    /// boxes too): every answer equals the broad phase's, pair for pair and in order, while
    /// some queries are served by a cache built for an earlier one and others are not.
    #[test]
    fn cached_candidates_equal_the_broad_phase() {
        let (body, sc) = strip(0.05);
        let folded: Vec<Vec3> = body
            .mesh
            .positions
            .iter()
            .map(|p| {
                if p.x > 0.5 {
                    Vec3::new(1.0 - p.x, p.y, 0.06)
                } else {
                    *p
                }
            })
            .collect();
        let mut rng = Rng::new(3);
        let mut noise =
            |scale: Real| Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * scale;
        // Queries the cache covered, queries it did not (a new cache or the broad phase).
        let (mut served, mut built, mut pairs) = (0, 0, 0);
        let mut length = 1e-4;
        while length < 0.2 {
            let x: Vec<Vec3> = folded.iter().map(|p| p + noise(0.3 * length)).collect();
            let to: Vec<Vec3> = x.iter().map(|p| p + noise(length)).collect();
            for (to, r) in [(Some(&to[..]), sc.xi_max), (None, sc.xi_max + sc.halo)] {
                let covered = sc
                    .cache
                    .lock()
                    .unwrap()
                    .pairs
                    .as_ref()
                    .is_some_and(|c| c.covers(&x, to, r));
                let got = sc.candidate_pairs(&x, to, r);
                if covered {
                    served += 1;
                } else {
                    built += 1;
                }
                let fresh = sc.broad_pairs(&x, to, r);
                assert_eq!(got, fresh, "paths of {length} m, radius {r}");
                pairs += fresh.0.len() + fresh.1.len();
            }
            length *= 1.3;
        }
        println!("{served} served, {built} built, {pairs} pairs");
        assert!(
            served > 10 && built > 2 && pairs > 1000,
            "{served} {built} {pairs}"
        );
    }

    /// A sheet thicker than its edges (h = 0.5 on edges of 0.05): the halo (the offset, 0.5)
    /// is wider than the cache may be (two mean edges); the cap wins, and the answer is the
    /// broad phase's (this query once panicked, the bounds crossed).
    #[test]
    fn a_sheet_thicker_than_its_edges_caps_its_cache() {
        let (body, sc) = strip(0.5);
        assert!(sc.halo > sc.cache_cap, "{} {}", sc.halo, sc.cache_cap);
        let x = &body.mesh.positions;
        let to: Vec<Vec3> = x.iter().map(|p| p + Vec3::new(0.0, 0.0, 0.01)).collect();
        let got = sc.candidate_pairs(x, Some(&to), sc.xi_max);
        assert_eq!(got, sc.broad_pairs(x, Some(&to), sc.xi_max));
        let reach = sc.cache.lock().unwrap().pairs.as_ref().map(|c| c.reach);
        assert_eq!(reach, Some(sc.xi_max + sc.cache_cap));
    }

    /// The explicit driver's displacement bounds hold: a 1 × 0.2 strip (h = 0.05, halo 0.05)
    /// folded flat onto itself 0.07 apart (inside the gathering's reach, the halo's cap
    /// binding) and 0.052 apart (just outside the offset, the room to the floor binding), its
    /// vertices then moved by their whole bound, the two layers straight at each other or in
    /// random directions, 40 times. Over every pair that is not excluded (brute force, no broad
    /// phase), each gathered pair stays at or above its floor `s ξ` and every other stays
    /// beyond its offset, where its law would begin; and the bounds are not vacuous: the layers'
    /// straight approach brings them to within 1% of what the bounds allow (0.02, and the floor
    /// 0.005).
    #[test]
    fn vertices_within_their_displacement_bounds_keep_every_pair_clear() {
        let (body, sc) = strip(0.05);
        let floor = sc.min_separation * 0.05;
        for (gap, allowed) in [(0.07, 0.07 - sc.halo), (0.052, floor)] {
            let closest = approach(&body, &sc, gap);
            println!("{gap} apart: closest {closest}, allowed {allowed}");
            assert!(closest >= floor * (1.0 - 1e-12), "{gap}: {closest}");
            assert!(closest <= 1.01 * allowed, "{gap}: {closest}");
        }
    }

    /// Every pair of `sc`'s sheet that is not incident or excluded, in slot order (brute
    /// force, no broad phase).
    fn every_pair(sc: &SelfContact) -> Vec<[usize; 4]> {
        let mut all = Vec::new();
        for p in 0..sc.nv {
            for (f, t) in sc.faces.iter().enumerate() {
                if !t.contains(&p)
                    && sc
                        .excluded_pt
                        .binary_search(&((p as u64) << 32 | f as u64))
                        .is_err()
                {
                    all.push(sc.pt_nodes(p, f));
                }
            }
        }
        for a in 0..sc.edges.len() {
            for b in a + 1..sc.edges.len() {
                let (ea, eb) = (sc.edges[a], sc.edges[b]);
                if !ea.iter().any(|v| eb.contains(v))
                    && sc
                        .excluded_ee
                        .binary_search(&((a as u64) << 32 | b as u64))
                        .is_err()
                {
                    all.push(sc.ee_nodes(a, b));
                }
            }
        }
        all
    }

    /// The cache's room holds (`room`, `roomy`, `clear_of_all`): a 1 × 0.2 strip, h = 0.05
    /// folded onto itself 0.08, 0.15 or 0.4 apart, or h = 0.002 flat, moved as a dynamic step
    /// moves it, a jump of the whole strip by 0.3 (which caches the pairs around its end) and
    /// then corrections of random directions and shrinking lengths from there, 30 times each. Every
    /// correction that `roomy` lets pass without the broad phase keeps every pair that is not
    /// excluded (brute force, sampled at eleven points of the paths) beyond where its law
    /// begins, by a tenth of the room; every end that `clear_of_all` calls clear has no pair
    /// within its offset and the halo; and neither is vacuous: some corrections pass, and some
    /// are refused.
    #[test]
    fn what_the_cached_room_lets_pass_stays_clear_of_every_law() {
        let mut rng = Rng::new(11);
        let (mut passed, mut refused, mut clear) = (0, 0, 0);
        // Folded (the layers near, the room small), and flat and thin (the room wider than
        // the halo: the pairs' gathering can be answered clear).
        for (h, gaps) in [
            (0.05, [Some(0.08), Some(0.15), Some(0.4)]),
            (0.002, [None; 3]),
        ] {
            let (body, sc) = strip(h);
            let all = every_pair(&sc);
            for (k, gap) in gaps.into_iter().cycle().take(30).enumerate() {
                let x: Vec<Vec3> = body
                    .mesh
                    .positions
                    .iter()
                    .map(|p| match gap {
                        Some(g) if p.x > 0.5 => Vec3::new(1.0 - p.x, p.y, g),
                        _ => *p,
                    })
                    .collect();
                let shift =
                    Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()).normalize() * 0.3;
                let jump: Vec<Vec3> = x.iter().map(|p| p + shift).collect();
                let _ = sc.candidate_pairs(&x, Some(&jump), sc.xi_max);
                let mut at = jump;
                let mut length = 0.004 * (1 + k % 5) as Real;
                for _ in 0..4 {
                    let to: Vec<Vec3> = at
                        .iter()
                        .map(|p| {
                            p + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric())
                                * length
                        })
                        .collect();
                    let room = sc
                        .cache
                        .lock()
                        .unwrap()
                        .pairs
                        .as_ref()
                        .and_then(|c| c.room)
                        .unwrap_or(0.0);
                    if sc.roomy(&at, &to) {
                        passed += 1;
                        for n in &all {
                            let start = sc.offset(n) + sc.beyond(n);
                            for i in 0..=10 {
                                let s = i as Real / 10.0;
                                let y: Vec<Vec3> =
                                    at.iter().zip(&to).map(|(a, b)| a + (b - a) * s).collect();
                                let d = sc.closest(&points(&y, n), n).d2.sqrt();
                                assert!(d >= start + 0.1 * room, "{h} {gap:?}: {n:?} at {d}");
                            }
                        }
                    } else {
                        // As the step bound goes on: the broad phase, or the cache.
                        refused += 1;
                        let _ = sc.candidate_pairs(&at, Some(&to), sc.xi_max);
                    }
                    if sc.clear_of_all(&to, sc.halo) {
                        clear += 1;
                        for n in &all {
                            let d = sc.closest(&points(&to, n), n).d2.sqrt();
                            assert!(d >= sc.offset(n) + sc.halo, "{h} {gap:?}: {n:?} at {d}");
                        }
                    }
                    at = to;
                    length *= 0.4;
                }
            }
        }
        println!("{passed} passed, {refused} refused, {clear} clear");
        assert!(
            passed > 20 && refused > 20 && clear > 10,
            "{passed} {refused} {clear}"
        );
    }

    /// The strip of `sc` folded flat onto itself `gap` apart, moved within its displacement
    /// bounds (40 trials, module test above), every pair checked; returns the closest gathered
    /// pair after the layers' straight approach.
    fn approach(body: &Body, sc: &SelfContact, gap: Real) -> Real {
        let x: Vec<Vec3> = body
            .mesh
            .positions
            .iter()
            .map(|p| {
                if p.x > 0.5 {
                    Vec3::new(1.0 - p.x, p.y, gap)
                } else {
                    *p
                }
            })
            .collect();
        let st = sc.pairs(&x, sc.halo);
        assert!(!st.nodes.is_empty());
        let mut bounds = vec![Real::INFINITY; x.len()];
        sc.bounds_at(&st.nodes, &x, &mut bounds);
        assert!(bounds.iter().all(|b| *b >= 0.0 && *b <= 0.5 * sc.halo));
        let gathered: std::collections::BTreeSet<[usize; 4]> = st
            .nodes
            .chunks_exact(4)
            .map(|n| [n[0], n[1], n[2], n[3]])
            .collect();
        let all = every_pair(sc);
        let mut rng = Rng::new(5);
        let mut closest: Real = Real::INFINITY;
        for trial in 0..40 {
            let moved: Vec<Vec3> = x
                .iter()
                .zip(&bounds)
                .map(|(p, b)| {
                    let dir = if trial == 0 {
                        // The layers straight at each other.
                        Vec3::new(0.0, 0.0, if p.z > 0.0 { -1.0 } else { 1.0 })
                    } else {
                        Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()).normalize()
                    };
                    p + dir * *b
                })
                .collect();
            for n in &all {
                let d = sc.closest(&points(&moved, n), n).d2.sqrt();
                if gathered.contains(n) {
                    assert!(
                        d >= sc.floor(n) * (1.0 - 1e-12),
                        "trial {trial}: {n:?} at {d}"
                    );
                    if trial == 0 {
                        closest = closest.min(d);
                    }
                } else {
                    assert!(
                        d >= sc.offset(n),
                        "trial {trial}: {n:?} not gathered, at {d}"
                    );
                }
            }
        }
        closest
    }
}
