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
//! **Edge–edge pairs** carry the contact where no vertex is near a face (two creases crossing).
//! They act only inside half the offset, `E = m(c) k w ψ(ξ/2 − d)`, `w` a quarter of the mean
//! of the four vertex areas, `m` IPC's mollifier of nearly parallel edges
//! ([`crate::contact::distance::mollifier`]): on a flat contact they are idle and the pressure
//! is the vertex law's alone.
//!
//! **Friction** (`friction` μ > 0, dynamic mode): the ground's lagged, smoothed Coulomb
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
//! are gathered again at the current iterate (a new pattern), and Newton goes on.
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
//! Units: positions m, k Pa/m, δ, ξ, R m, A m², energies J. DOF order per pair: the four
//! points' coordinates, point–triangle `(p, t₂, t₁, t₀)` with `t₀ < t₁ < t₂`, edge–edge
//! `(a, b, c, d)` with `a < b`, `c < d` (the order of the last two slots tells the kinds apart).

use super::term::{LaggedNormals, Reports, StepBound, StepLimit, Term};
use crate::body::Body;
use crate::contact::{broad, ccd, distance, friction_potential, penalty};
use crate::elements::Stencil;
use crate::elements::{assemble_elements, no_contribution, ElementMap, Want};
use crate::energy::term::ChangingElements;
use crate::energy::{HessianProjection, Potential};
use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::MeshError;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// The mollifier's threshold as a fraction of the product of the squared rest lengths
/// (Li et al. 2020, §4.3).
const MOLLIFIER: Real = 1e-3;

/// The contact of a sheet with itself and with other sheets of the mesh.
pub struct SelfContact {
    /// The mesh's faces.
    faces: Vec<[usize; 3]>,
    /// The mesh's edges `(a, b)`, `a < b`.
    edges: Vec<[usize; 2]>,
    /// Reference positions (the mollifier's rest lengths).
    rest: Vec<Vec3>,
    /// Thickness per vertex (m), or the fixed offset in every entry.
    thickness: Vec<Real>,
    /// Reference area per vertex (m²).
    area: Vec<Real>,
    /// Penalty stiffness k (Pa/m).
    pub stiffness: Real,
    /// Smoothing length δ (m).
    pub smoothing: Real,
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
    /// Wall time spent so far (ns) in the broad phase and gathering, in CCD and the
    /// separation checks, and in the term's assembly ([`Clock`]).
    clock: [AtomicU64; 3],
    /// Excluded point–triangle pairs `p << 32 | f`, sorted.
    excluded_pt: Vec<u64>,
    /// Excluded edge–edge pairs `a << 32 | b` (edge indices, `a < b`), sorted.
    excluded_ee: Vec<u64>,
}

/// Whether the element with these four nodes is a point–triangle pair (module doc: the order
/// of the last two slots).
#[inline]
fn is_point_triangle(nodes: &[usize]) -> bool {
    nodes[2] > nodes[3]
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

    /// The distance below which a pair presses (the offset for a point–triangle pair, half
    /// of it for an edge–edge pair) and its area weight (m²): half the vertex's area, or a
    /// quarter of the mean of the four vertex areas (module doc).
    #[inline]
    fn law(&self, nodes: &[usize]) -> (Real, Real) {
        let xi = self.offset(nodes);
        let a = &self.area;
        if is_point_triangle(nodes) {
            (xi, 0.5 * a[nodes[0]])
        } else {
            (
                0.5 * xi,
                0.0625 * (a[nodes[0]] + a[nodes[1]] + a[nodes[2]] + a[nodes[3]]),
            )
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

    /// The pairs the broad phase finds within `radius` at `x` (over the straight paths to
    /// `to`, when given), not excluded: their nodes, point–triangle pairs first, each kind
    /// sorted.
    fn candidates(&self, x: &[Vec3], to: Option<&[Vec3]>, radius: Real) -> Vec<[usize; 4]> {
        let pt = broad::point_triangle(x, to, &self.faces, radius);
        let ee = broad::edge_edge(x, to, &self.edges, radius);
        let key = |a: u32, b: u32| (a as u64) << 32 | b as u64;
        pt.par_iter()
            .filter(|&&(p, f)| self.excluded_pt.binary_search(&key(p, f)).is_err())
            .map(|&(p, f)| self.pt_nodes(p as usize, f as usize))
            .chain(
                ee.par_iter()
                    .filter(|&&(a, b)| self.excluded_ee.binary_search(&key(a, b)).is_err())
                    .map(|&(a, b)| self.ee_nodes(a as usize, b as usize)),
            )
            .collect()
    }

    /// The pairs within `beyond` of their offset at `x`, not excluded: the stencil,
    /// point–triangle pairs first (module doc for the slot order).
    fn pairs(&self, x: &[Vec3], beyond: Real) -> Stencil {
        self.timed(Clock::Broad, || self.pairs_untimed(x, beyond))
    }

    /// [`SelfContact::pairs`], untimed (the checks at build).
    fn pairs_untimed(&self, x: &[Vec3], beyond: Real) -> Stencil {
        let near: Vec<[usize; 4]> = self
            .candidates(x, None, self.xi_max + beyond)
            .into_par_iter()
            .filter(|n| self.closest(&points(x, n), n).d2 < (self.offset(n) + beyond).powi(2))
            .collect();
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

    /// Per pair of `nodes` (four per pair), whether it carries energy at `x`: every edge–edge
    /// pair, and of each vertex's point–triangle pairs the nearest on each side (module doc;
    /// ties go to the first in element order), or all of them with `all_pairs`.
    fn active(&self, nodes: &[usize], x: &[Vec3]) -> Vec<bool> {
        let ne = nodes.len() / 4;
        if self.all_pairs {
            return vec![true; ne];
        }
        let normals = self.vertex_normals(x);
        let measured: Vec<Option<(usize, bool, Real)>> = (0..ne)
            .into_par_iter()
            .map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                if !is_point_triangle(n) {
                    return None;
                }
                let y = points(x, n);
                let cl = distance::point_triangle(&y);
                let r = y[0] * cl.c[0] + y[1] * cl.c[1] + y[2] * cl.c[2] + y[3] * cl.c[3];
                Some((n[0], r.dot(&normals[n[0]]) >= 0.0, cl.d2))
            })
            .collect();
        let mut active = vec![true; ne];
        // Point–triangle elements come sorted by vertex: one run per vertex.
        let mut e = 0;
        while e < ne {
            let Some((p, _, _)) = measured[e] else {
                e += 1;
                continue;
            };
            let mut end = e;
            let mut best: [Option<(Real, usize)>; 2] = [None, None];
            while end < ne {
                match measured[end] {
                    Some((q, side, d2)) if q == p => {
                        let b = &mut best[usize::from(side)];
                        if b.is_none_or(|(bd, _)| d2 < bd) {
                            *b = Some((d2, end));
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
        let (reach, weight) = self.law(nodes);
        let cl = self.closest(&y, nodes);
        if cl.d2 >= reach * reach || cl.d2 <= 0.0 {
            return no_contribution(grad, hess);
        }
        let d = cl.d2.sqrt();
        let w = self.stiffness * weight;
        let (psi, dpsi, ddpsi) = penalty(reach - d, self.smoothing);
        let mollifier = if pt { None } else { self.mollifier(nodes, &y) };
        let m = mollifier.map_or(1.0, |(m, _, _)| m);
        let energy = m * w * psi;
        if grad.is_none() && hess.is_none() {
            return energy;
        }
        let want_h = hess.is_some();
        let mut h2 = SMat::<12, 12>::zeros();
        let g2 = distance::derivatives(&y, &cl, want_h.then_some(&mut h2));
        // ∇d = ∇d²/(2d); E₀ = wψ(reach − d): ∇E₀ = −wψ′∇d.
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
            // ∇²d = ∇²d²/(2d) − ∇d ∇dᵀ/d; ∇²E₀ = w(ψ″∇d∇dᵀ − ψ′∇²d).
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
        let active = self.active(nodes, x);
        (0..nodes.len() / 4)
            .into_par_iter()
            .filter(|&e| active[e])
            .filter_map(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                let y = points(x, n);
                let cl = self.closest(&y, n);
                let (reach, weight) = self.law(n);
                let d = cl.d2.sqrt();
                if d >= reach || d <= 0.0 {
                    return None;
                }
                let m = if is_point_triangle(n) {
                    1.0
                } else {
                    self.mollifier(n, &y).map_or(1.0, |(m, _, _)| m)
                };
                let dpsi = penalty(reach - d, self.smoothing).1;
                Some((e, m * self.stiffness * weight * dpsi, cl.c))
            })
            .collect()
    }

    /// Per pair of `nodes`, its friction at the lag's iterate `x_lag` (module doc): the bound
    /// `μ λ` (N), the closest points' coefficients and the unit normal, for the pairs that press
    /// there; `None` for the others.
    fn lagged_friction(&self, nodes: &[usize], x_lag: &[Vec3]) -> Vec<Option<Slip>> {
        let mut out = vec![None; nodes.len() / 4];
        for (e, lambda, c) in self.forces(nodes, x_lag) {
            let y = points(x_lag, &nodes[4 * e..4 * e + 4]);
            let r: Vec3 = (0..4).map(|i| y[i] * c[i]).sum();
            let norm = r.norm();
            if norm > 0.0 && lambda > 0.0 {
                out[e] = Some(Slip {
                    bound: self.friction * lambda,
                    c,
                    normal: r / norm,
                });
            }
        }
        out
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
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
        with_friction: bool,
    ) -> Real {
        if map.nodes.is_empty() {
            return 0.0;
        }
        let active = self.active(&map.nodes, x);
        let gauss_newton = projection == HessianProjection::GaussNewton;
        let friction = pot
            .friction
            .filter(|_| with_friction && self.friction > 0.0)
            .map(|fr| (fr, self.lagged_friction(&map.nodes, fr.x_lag)));
        assemble_elements::<12, 4, _>(
            map,
            |e, nodes, mut g, mut h| {
                let mut energy = if active[e] {
                    self.element(nodes, x, gauss_newton, g.as_deref_mut(), h.as_deref_mut())
                } else {
                    no_contribution(g.as_deref_mut(), h.as_deref_mut())
                };
                if let Some((fr, Some(s))) = friction.as_ref().map(|(fr, l)| (fr, &l[e])) {
                    energy += Self::slip(s, nodes, x, fr.x_prev, fr.eps, g, h);
                }
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

    /// The sum over the pairs of the magnitudes of their friction forces at `x` over the
    /// potential's step (N; 0 without one).
    fn friction_force(&self, pot: &Potential, map: &ElementMap, x: &[Vec3]) -> Real {
        let Some(fr) = pot.friction.as_ref() else {
            return 0.0;
        };
        let lagged = self.lagged_friction(&map.nodes, fr.x_lag);
        let per_pair: Vec<Real> = (0..lagged.len())
            .into_par_iter()
            .map(|e| {
                lagged[e].as_ref().map_or(0.0, |s| {
                    let moved = s.moved(&map.nodes[4 * e..4 * e + 4], x, fr.x_prev);
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
        _phi: &[Real],
    ) -> Option<Vec<(&'static str, Real)>> {
        let e = self.assemble(
            pot,
            map,
            x,
            Want::Energy,
            HessianProjection::None,
            &mut [],
            &mut [],
            false,
        );
        Some(vec![("self_contact", e)])
    }

    /// `self_contact_pairs`: the pairs that press; `self_contact_friction` (with friction):
    /// the sum of the magnitudes of their friction forces (N); `self_contact_broad_seconds`,
    /// `self_contact_ccd_seconds`, `self_contact_assembly_seconds`: the wall time spent so far
    /// in the broad phase and gathering, in CCD and the separation checks, and in the term's
    /// assembly (s); `self_contact_gap`: the smallest distance
    /// of a gathered pair over its offset (the gathering's reach over the offset when none
    /// was gathered); `self_contact_force`: the sum of the pairs' normal forces (N).
    fn observables(&self, pot: &Potential, x: &[Vec3], _phi: &[Real]) -> Vec<(String, Real)> {
        let Some(map) = self.map(pot) else {
            return Vec::new();
        };
        let forces = self.forces(&map.nodes, x);
        let gap = map
            .nodes
            .par_chunks(4)
            .map(|n| self.closest(&points(x, n), n).d2.sqrt() / self.offset(n))
            .reduce(
                || 1.0 + self.halo / self.xi_max.max(Real::MIN_POSITIVE),
                Real::min,
            );
        let mut out = vec![
            ("self_contact_pairs".into(), forces.len() as Real),
            ("self_contact_gap".into(), gap),
            (
                "self_contact_force".into(),
                forces.iter().map(|f| f.1).sum(),
            ),
        ];
        if self.friction > 0.0 {
            out.push((
                "self_contact_friction".into(),
                self.friction_force(pot, map, x),
            ));
        }
        for (name, part) in [
            ("self_contact_broad_seconds", Clock::Broad),
            ("self_contact_ccd_seconds", Clock::Ccd),
            ("self_contact_assembly_seconds", Clock::Assembly),
        ] {
            let ns = self.clock[part as usize].load(Ordering::Relaxed);
            out.push((name.into(), ns as Real * 1e-9));
        }
        out
    }

    /// `contact_pressure` (Pa): per face, the mean over its vertices of the normal force the
    /// pairs put on the vertex (shared by the closest points' coefficients) over its area;
    /// `contact_gap` (m): per face, the smallest `d − ξ` of the gathered pairs that involve one
    /// of its vertices (the halo where none does).
    fn face_fields(&self, pot: &Potential, x: &[Vec3], _phi: &[Real]) -> Vec<(String, Vec<Real>)> {
        let Some(map) = self.map(pot) else {
            return Vec::new();
        };
        let nv = x.len();
        let force = self.vertex_forces(&map.nodes, x);
        let mut gap = vec![self.halo; nv];
        for n in map.nodes.chunks(4) {
            let g = self.closest(&points(x, n), n).d2.sqrt() - self.offset(n);
            for &v in n {
                gap[v] = gap[v].min(g);
            }
        }
        let per_face =
            |f: &[usize; 3], per: &dyn Fn(usize) -> Real| (per(f[0]) + per(f[1]) + per(f[2])) / 3.0;
        let pressure = self
            .faces
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
        let face_gap = self
            .faces
            .iter()
            .map(|f| gap[f[0]].min(gap[f[1]]).min(gap[f[2]]))
            .collect();
        vec![
            ("contact_pressure".into(), pressure),
            ("contact_gap".into(), face_gap),
        ]
    }
}

impl ChangingElements for SelfContact {
    fn stencil_at(&self, _: &Body, x: &[Vec3], _: &[Real]) -> Stencil {
        self.pairs(x, self.halo)
    }
}

impl LaggedNormals for SelfContact {
    /// Over the vertices, the largest normal force the pairs put on one at `trial`, and the
    /// largest change of one from the lagged iterate (the pairs that press at each).
    fn lag_change(&self, trial: &[Vec3], _: Real, lag: &[Vec3], _: Real) -> (Real, Real) {
        // One after the other: each gathering is timed on the broad phase's clock.
        let at = |x: &[Vec3]| self.vertex_forces(&self.pairs(x, 0.0).nodes, x);
        let (new, old) = (at(trial), at(lag));
        new.iter().zip(&old).fold((0.0, 0.0), |(s, d), (a, b)| {
            (Real::max(s, *a), Real::max(d, (a - b).abs()))
        })
    }
}

impl StepLimit for SelfContact {
    /// The smallest of each gathered pair's additive CCD fraction to `s ξ`, and of each other
    /// pair's fraction to its offset `ξ`, where its law would begin: a pair that was not
    /// gathered may not press within the step. The others are found by the broad phase over
    /// the boxes of the straight paths, inflated by the largest offset. When one of them would
    /// enter its offset and is within the gathering's reach now, gathering again at `x` adds it
    /// and allows the longer step.
    fn max_fraction(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        step: &[Real],
    ) -> StepBound {
        let dx = |v: usize| Vec3::new(step[3 * v], step[3 * v + 1], step[3 * v + 2]);
        let nodes = &map.nodes;
        let gathered = self.timed(Clock::Ccd, || {
            (0..nodes.len() / 4)
                .into_par_iter()
                .map(|e| {
                    let n = &nodes[4 * e..4 * e + 4];
                    let d: [Vec3; 4] = std::array::from_fn(|i| dx(n[i]));
                    let d_min = self.min_separation * self.offset(n);
                    ccd::safe_fraction(&points(x, n), &d, is_point_triangle(n), d_min, 1.0)
                })
                .reduce(|| 1.0, Real::min)
        });
        // The pairs not gathered: where the pairs were gathered (the solver's positions, or `x`
        // outside a solve), they were farther apart than their offset and the halo.
        let taken = if pot.taken_at.len() == x.len() {
            pot.taken_at
        } else {
            x
        };
        let to: Vec<Vec3> = (0..x.len()).map(|v| x[v] + dx(v)).collect();
        let candidates = self.timed(Clock::Broad, || self.candidates(x, Some(&to), self.xi_max));
        let others = self.timed(Clock::Ccd, || {
            candidates
                .into_par_iter()
                .map(|n| {
                    let d: [Vec3; 4] = std::array::from_fn(|i| dx(n[i]));
                    let y = points(x, &n);
                    let xi = self.offset(&n);
                    let t = ccd::safe_fraction(&y, &d, is_point_triangle(&n), xi, 1.0);
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
        let moved = !std::ptr::eq(taken, x) && taken != x;
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

    /// Every pair at least `s ξ` apart.
    fn admits(&self, _: &Potential, map: &ElementMap, x: &[Vec3]) -> bool {
        let nodes = &map.nodes;
        self.timed(Clock::Ccd, || {
            (0..nodes.len() / 4).into_par_iter().all(|e| {
                let n = &nodes[4 * e..4 * e + 4];
                let d_min = self.min_separation * self.offset(n);
                self.closest(&points(x, n), n).d2 >= d_min * d_min
            })
        })
    }
}

impl Term for SelfContact {
    fn name(&self) -> &'static str {
        "self_contact"
    }
    fn stencil(&self, body: &Body) -> Stencil {
        self.pairs(&body.mesh.positions, self.halo)
    }
    fn changing(&self) -> Option<&dyn ChangingElements> {
        Some(self)
    }
    fn step_limit(&self) -> Option<&dyn StepLimit> {
        Some(self)
    }
    fn lagged(&self) -> Option<&dyn LaggedNormals> {
        (self.friction > 0.0).then_some(self as &dyn LaggedNormals)
    }
    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }
    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        _phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        self.timed(Clock::Assembly, || {
            self.assemble(pot, map, x, want, projection, grad, values, true)
        })
    }
}

/// The term of `[self_contact]` on `body`, or `None` when disabled; friction only when
/// `dynamic`.
pub fn term(
    body: &Body,
    c: &crate::config::self_contact::SelfContact,
    dynamic: bool,
) -> Result<Option<Box<dyn Term>>, MeshError> {
    if !c.enabled {
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
    let mut edges: Vec<[usize; 2]> = body
        .topo
        .edges
        .iter()
        .map(|e| [e[0].min(e[1]), e[0].max(e[1])])
        .collect();
    edges.sort_unstable();
    let mut sc = SelfContact {
        faces: mesh.faces.clone(),
        edges,
        rest: mesh.positions.clone(),
        thickness,
        area: ca.area,
        stiffness: c.stiffness.or(ca.e_over_h),
        smoothing,
        xi_max,
        halo: c.halo.or(xi_max),
        exclusion: c.exclusion.or(2.0 * (xi_max + smoothing)),
        min_separation: c.min_separation,
        friction: if dynamic { c.friction } else { 0.0 },
        all_pairs: c.pairs == crate::config::self_contact::Pairs::All,
        clock: Default::default(),
        excluded_pt: Vec::new(),
        excluded_ee: Vec::new(),
    };
    exclude(&mut sc, body)?;
    Ok(Some(Box::new(sc)))
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
    if let Some((e, f)) = crossing(x, &sc.edges, &sc.faces) {
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
fn crossing(x: &[Vec3], edges: &[[usize; 2]], faces: &[[usize; 3]]) -> Option<(usize, usize)> {
    broad::edge_triangle(x, edges, faces)
        .into_par_iter()
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
