//! The distance between a shape and a target surface of any triangulation, after the best rigid
//! motion.
//!
//! With the shape's vertices `x_v` (weights `w_v`: the lumped reference areas, summing to 1),
//! the target `S` with vertices `y_u` (weights `ω_u`: its lumped areas, summing to 1), the
//! shape's surface `X` and the target's size `L` (its bounding-box diagonal):
//!
//! `J_d = min_{R, t} ¼ [Σ_v w_v d(R x_v + t, S)² + Σ_u ω_u d(y_u, R X + t)²] / L²`,
//!
//! the mean of the two one-sided mean-square distances, halved: `√(2 J_d)` is the RMS distance
//! over `L`, as for the point-to-point objective. Both sides are needed: the shape's points near
//! the target alone would let the shape cover a part of it.
//!
//! A distance `d(p, S)² = |p − c|²` to its closest point `c` is differentiable wherever `c` is
//! unique, with gradient `2(p − c)` (the closest point's own motion is tangent to the distance
//! sphere). The second side's closest point on the shape is `Σ β_i x_i` on one of its faces, so
//! its gradient reaches the face's vertices with the barycentric weights `β_i`. The alignment is
//! found by iterative closest points (Besl & McKay, IEEE PAMI 14, 1992): closest points both
//! ways, then the weighted Kabsch rotation of the pairs ([`super::objective::kabsch`]), until
//! the objective stops decreasing; it is warm-started from the previous shape's alignment. At
//! its fixed point the objective is stationary in `(R, t)`, so by the envelope theorem
//! `∂J_d/∂x_v = ½ w_v Rᵀ(R x_v + t − c_v)/L² + ½ Σ_u ω_u β_{u,v} Rᵀ(R q_u + t − y_u)/L²`.
//! ICP finds the nearest local optimum, not the global one: the target should lie roughly
//! where the designed shape will, as it does when both are drawn in the same coordinates.
//!
//! Closest points are found in a bounding-volume hierarchy of axis-aligned boxes, split at the
//! median centroid along the longest axis; a query visits the nearer child first and skips
//! boxes further than the best distance found, and ties go to the lower face number, so the
//! answer does not depend on the thread count. (Written here rather than taken from
//! `parry3d-f64`, a whole collision library for one query, or `kiddo`, whose k-d trees hold
//! points, not triangles.)

use super::objective::{kabsch, lumped_weights, Distance};
use crate::contact::distance::{point_triangle, Kind};
use crate::math::{Mat3, Real, SMat, SVec, Vec3};
use std::ops::AddAssign;
use std::sync::Mutex;

/// Faces per leaf of the hierarchy.
const LEAF: usize = 4;

/// The most ICP iterations before the Gauss–Newton refinement.
const MAX_ICP: usize = 50;

/// ICP hands over to Gauss–Newton when the objective decreases by less than this, relative,
/// in one iteration.
const ICP_TOLERANCE: Real = 1e-6;

/// The most Gauss–Newton steps of the alignment.
const MAX_GAUSS_NEWTON: usize = 50;

/// Gauss–Newton stops when its step moves no point by more than this, over the target's size.
const STEP_TOLERANCE: Real = 1e-14;

#[derive(Clone, Debug)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// Leaf: the range `start..start + count` of `order`; inner (`count == 0`): the children
    /// `start` and `start + 1`.
    start: usize,
    count: usize,
}

/// A bounding-volume hierarchy over a triangle mesh's faces.
#[derive(Clone, Debug)]
pub struct Tree {
    nodes: Vec<Node>,
    order: Vec<usize>,
    triangles: Vec<[Vec3; 3]>,
}

/// A closest point on a mesh.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// The face.
    pub face: usize,
    /// The barycentric weights of the point on the face.
    pub bary: [Real; 3],
    /// The point (m).
    pub point: Vec3,
    /// The squared distance (m²).
    pub d2: Real,
    /// The Hessian of `½ d²` in the query point at fixed feature (dimensionless): `n nᵀ` inside
    /// the face, `I − e eᵀ` on an edge of direction `e`, `I` at a vertex.
    pub hess: Mat3,
}

impl Tree {
    /// The hierarchy of `faces` at `positions`.
    pub fn new(positions: &[Vec3], faces: &[[usize; 3]]) -> Tree {
        let triangles: Vec<[Vec3; 3]> = faces.iter().map(|f| f.map(|v| positions[v])).collect();
        let centroids: Vec<Vec3> = triangles
            .iter()
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let mut tree = Tree {
            nodes: vec![Node {
                min: Vec3::zeros(),
                max: Vec3::zeros(),
                start: 0,
                count: 0,
            }],
            order: (0..faces.len()).collect(),
            triangles,
        };
        // Build breadth-first with an explicit stack: (node, range).
        let mut stack = vec![(0usize, 0usize, faces.len())];
        while let Some((node, lo, hi)) = stack.pop() {
            let (mut min, mut max) = (Vec3::repeat(Real::INFINITY), Vec3::repeat(-Real::INFINITY));
            let (mut cmin, mut cmax) = (min, max);
            for &f in &tree.order[lo..hi] {
                for p in &tree.triangles[f] {
                    min = min.inf(p);
                    max = max.sup(p);
                }
                cmin = cmin.inf(&centroids[f]);
                cmax = cmax.sup(&centroids[f]);
            }
            tree.nodes[node].min = min;
            tree.nodes[node].max = max;
            if hi - lo <= LEAF {
                tree.nodes[node].start = lo;
                tree.nodes[node].count = hi - lo;
                continue;
            }
            let axis = (cmax - cmin).imax();
            let mid = (lo + hi) / 2;
            tree.order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
                centroids[a][axis]
                    .total_cmp(&centroids[b][axis])
                    .then(a.cmp(&b))
            });
            let left = tree.nodes.len();
            for _ in 0..2 {
                tree.nodes.push(Node {
                    min: Vec3::zeros(),
                    max: Vec3::zeros(),
                    start: 0,
                    count: 0,
                });
            }
            tree.nodes[node].start = left;
            tree.nodes[node].count = 0;
            stack.push((left, lo, mid));
            stack.push((left + 1, mid, hi));
        }
        tree
    }

    /// The squared distance from `p` to node `n`'s box.
    fn box_d2(&self, n: usize, p: &Vec3) -> Real {
        let node = &self.nodes[n];
        let mut d2 = 0.0;
        for k in 0..3 {
            let d = (node.min[k] - p[k]).max(p[k] - node.max[k]).max(0.0);
            d2 += d * d;
        }
        d2
    }

    /// The closest point to `p` (`None` for an empty mesh).
    pub fn closest(&self, p: &Vec3) -> Option<Hit> {
        if self.triangles.is_empty() {
            return None;
        }
        let mut best: Option<Hit> = None;
        let mut stack = vec![(0usize, self.box_d2(0, p))];
        while let Some((n, d2)) = stack.pop() {
            if best.is_some_and(|b| d2 > b.d2) {
                continue;
            }
            let node = &self.nodes[n];
            if node.count > 0 {
                for &f in &self.order[node.start..node.start + node.count] {
                    let t = &self.triangles[f];
                    let c = point_triangle(&[*p, t[0], t[1], t[2]]);
                    let better = match best {
                        None => true,
                        Some(b) => c.d2 < b.d2 || (c.d2 == b.d2 && f < b.face),
                    };
                    if better {
                        let bary = [-c.c[1], -c.c[2], -c.c[3]];
                        let hess = match c.kind {
                            Kind::PointTriangle => {
                                let n = crate::geometry::area_normal(t).normalize();
                                n * n.transpose()
                            }
                            Kind::PointEdge(_, a, b) => {
                                let e = (t[b as usize - 1] - t[a as usize - 1]).normalize();
                                Mat3::identity() - e * e.transpose()
                            }
                            _ => Mat3::identity(),
                        };
                        best = Some(Hit {
                            face: f,
                            bary,
                            point: t[0] * bary[0] + t[1] * bary[1] + t[2] * bary[2],
                            d2: c.d2,
                            hess,
                        });
                    }
                }
                continue;
            }
            let (a, b) = (node.start, node.start + 1);
            let (da, db) = (self.box_d2(a, p), self.box_d2(b, p));
            // The nearer child is popped first.
            if da <= db {
                stack.push((b, db));
                stack.push((a, da));
            } else {
                stack.push((a, da));
                stack.push((b, db));
            }
        }
        best
    }
}

/// The two-sided distance to a target surface of any triangulation.
#[derive(Debug)]
pub struct Surface {
    target: Tree,
    /// The target's vertices (m) and weights.
    target_points: Vec<(Vec3, Real)>,
    /// The shape's faces and vertex weights.
    faces: Vec<[usize; 3]>,
    weights: Vec<Real>,
    /// The target's size `L` (m).
    pub size: Real,
    align: bool,
    /// The last alignment found (ICP's warm start).
    last: Mutex<Option<(Mat3, Vec3)>>,
}

/// One side's correspondences at an alignment: the source point in the shape's frame (as
/// barycentric weights on shape vertices), the target point and the weight.
struct Pairs {
    /// Shape to target: per shape vertex, the closest target point.
    near: Vec<Vec3>,
    /// Target to shape: per target vertex, the closest shape face and barycentric weights.
    back: Vec<(usize, [Real; 3])>,
    /// The Hessian of each correspondence's `½ d²` at its feature ([`Hit::hess`]), front ones
    /// first, then back ones.
    hess: Vec<Mat3>,
    value: Real,
}

impl Surface {
    /// Whether the shape is compared after the best rigid motion.
    pub fn aligns(&self) -> bool {
        self.align
    }

    /// The shape side's Gauss–Newton weights `½ w_v/L²` ([`super::objective::DistanceTerm::model_weights`]).
    pub fn model_weights(&self) -> Vec<Real> {
        let l2 = self.size * self.size;
        self.weights.iter().map(|w| 0.5 * w / l2).collect()
    }

    /// The distance to the target `(positions, faces)` of a shape on `mesh`'s connectivity
    /// (whose reference areas weigh its vertices).
    pub fn new(
        mesh: &crate::mesh::Mesh,
        target_positions: &[Vec3],
        target_faces: &[[usize; 3]],
        align: bool,
    ) -> Surface {
        let tw = lumped_weights(target_positions, target_faces);
        Surface {
            target: Tree::new(target_positions, target_faces),
            target_points: target_positions.iter().copied().zip(tw).collect(),
            faces: mesh.faces.clone(),
            weights: lumped_weights(&mesh.positions, &mesh.faces),
            size: super::objective::bounding_diagonal(target_positions),
            align,
            last: Mutex::new(None),
        }
    }

    /// The correspondences of `x` moved by `(r, t)`, and the objective they give.
    fn pairs(&self, x: &[Vec3], r: &Mat3, t: &Vec3) -> Pairs {
        let moved: Vec<Vec3> = x.iter().map(|p| r * p + t).collect();
        let l2 = self.size * self.size;
        let mut value = 0.0;
        let mut hess = Vec::with_capacity(x.len() + self.target_points.len());
        let near: Vec<Vec3> = moved
            .iter()
            .zip(&self.weights)
            .map(|(p, w)| {
                let hit = self.target.closest(p).expect("a target has faces");
                value += 0.25 * w * hit.d2 / l2;
                hess.push(hit.hess);
                hit.point
            })
            .collect();
        let shape = Tree::new(&moved, &self.faces);
        let back = self
            .target_points
            .iter()
            .map(|(y, w)| {
                let hit = shape.closest(y).expect("a shape has faces");
                value += 0.25 * w * hit.d2 / l2;
                hess.push(hit.hess);
                (hit.face, hit.bary)
            })
            .collect();
        Pairs {
            near,
            back,
            hess,
            value,
        }
    }

    /// The point on the shape (in its own frame) of a back correspondence.
    fn on_shape(&self, x: &[Vec3], (f, b): &(usize, [Real; 3])) -> Vec3 {
        let v = self.faces[*f];
        x[v[0]] * b[0] + x[v[1]] * b[1] + x[v[2]] * b[2]
    }

    /// The best rigid motion by iterative closest points from the last one found, and the
    /// correspondences there.
    fn align(&self, x: &[Vec3]) -> (Mat3, Vec3, Pairs) {
        let (mut r, mut t) = (Mat3::identity(), Vec3::zeros());
        if self.align {
            let last = *self.last.lock().unwrap_or_else(|e| e.into_inner());
            match last {
                Some(rt) => (r, t) = rt,
                None => {
                    // First call: the centroids on each other.
                    let cx: Vec3 = x.iter().zip(&self.weights).map(|(p, w)| p * *w).sum();
                    let cy: Vec3 = self.target_points.iter().map(|(p, w)| p * *w).sum();
                    t = cy - cx;
                }
            }
        }
        let mut pairs = self.pairs(x, &r, &t);
        if !self.align {
            return (r, t, pairs);
        }
        for _ in 0..MAX_ICP {
            let sources = x
                .iter()
                .zip(&pairs.near)
                .zip(&self.weights)
                .map(|((p, c), w)| (*p, *c, *w))
                .chain(
                    pairs
                        .back
                        .iter()
                        .zip(&self.target_points)
                        .map(|(b, (y, w))| (self.on_shape(x, b), *y, *w)),
                );
            let (r2, t2) = kabsch(sources);
            let next = self.pairs(x, &r2, &t2);
            if next.value > pairs.value {
                break;
            }
            let gain = pairs.value - next.value;
            (r, t, pairs) = (r2, t2, next);
            if gain <= ICP_TOLERANCE * pairs.value.max(Real::MIN_POSITIVE) {
                break;
            }
        }
        // Newton on the distances themselves, each closest feature held (point to plane inside
        // a face, point to line on an edge, point to point at a vertex): its fixed point is where
        // the objective is stationary in (R, t), to rounding.
        for _ in 0..MAX_GAUSS_NEWTON {
            let Some((dr, dt, reach)) = self.gauss_newton_step(x, &r, &t, &pairs) else {
                break;
            };
            let mut scale = 1.0;
            let mut taken = false;
            for _ in 0..20 {
                let rot = nalgebra::Rotation3::new(dr * scale).into_inner();
                let (r2, t2) = (rot * r, rot * t + dt * scale);
                let next = self.pairs(x, &r2, &t2);
                if next.value <= pairs.value {
                    (r, t, pairs) = (r2, t2, next);
                    taken = true;
                    break;
                }
                scale *= 0.5;
            }
            if !taken || reach * scale <= STEP_TOLERANCE * self.size {
                break;
            }
        }
        *self.last.lock().unwrap_or_else(|e| e.into_inner()) = Some((r, t));
        (r, t, pairs)
    }

    /// The Gauss–Newton step `(ω, τ)` of the alignment from `(r, t)`, the motion `y ↦ Q(ω) y
    /// + τ` applied after it, and the largest distance it moves a point (`None`: no step).
    fn gauss_newton_step(
        &self,
        x: &[Vec3],
        r: &Mat3,
        t: &Vec3,
        pairs: &Pairs,
    ) -> Option<(Vec3, Vec3, Real)> {
        // Newton on Σ ½ w d², each closest feature held. A shape point moves to
        // z = Q(ω) m + τ ≈ m + ω × m + τ + ½ ω × (ω × m); a target point's distance to the
        // moving shape is its distance to the shape held still from z = Qᵀ(y − τ) ≈ y − τ −
        // ω × (y − τ) + ½ ω × (ω × y). With g = ∂(½ d²)/∂z = z − c: the gradient Jᵀ g, with
        // J = [−[m]×, I] or [[y]×, −I]; the Hessian Jᵀ H J (Gauss–Newton) plus the motion's own
        // curvature, S = ½(p gᵀ + g pᵀ) − (p·g) I in the ωω block (p = m or y) and, for a
        // target point, −[g]× in the ωτ block from the bilinear ω × τ.
        let mut a = SMat::<6, 6>::zeros();
        let mut curv = SMat::<6, 6>::zeros();
        let mut b = SVec::<6>::zeros();
        let mut extent: Real = 0.0;
        let mut add = |p: Vec3, g: Vec3, h: &Mat3, w: Real, shape_point: bool| {
            extent = extent.max(p.norm());
            let sign = if shape_point { 1.0 } else { -1.0 };
            let mut jac = SMat::<3, 6>::zeros();
            jac.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(-crate::math::skew(&p) * sign));
            jac.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&(Mat3::identity() * sign));
            a += jac.transpose() * (h * jac) * w;
            b += jac.transpose() * g * w;
            let sww =
                ((p * g.transpose() + g * p.transpose()) * 0.5 - Mat3::identity() * p.dot(&g)) * w;
            curv.fixed_view_mut::<3, 3>(0, 0).add_assign(&sww);
            if !shape_point {
                let m = -crate::math::skew(&g) * w;
                curv.fixed_view_mut::<3, 3>(0, 3).add_assign(&m);
                curv.fixed_view_mut::<3, 3>(3, 0).add_assign(&m.transpose());
            }
        };
        let mut k = 0;
        for ((p, c), w) in x.iter().zip(&pairs.near).zip(&self.weights) {
            let m = r * p + t;
            add(m, m - c, &pairs.hess[k], *w, true);
            k += 1;
        }
        for (bk, (y, w)) in pairs.back.iter().zip(&self.target_points) {
            let c = r * self.on_shape(x, bk) + t;
            add(*y, y - c, &pairs.hess[k], *w, false);
            k += 1;
        }
        // Newton with the motion's curvature where that is positive definite, else
        // Gauss–Newton. A rotation the target does not see (about a symmetry axis) has no
        // curvature: a tiny damping keeps the system solvable and leaves that motion alone.
        let damping = 1e-12 * a.trace().max(Real::MIN_POSITIVE);
        let mut newton = a + SMat::<6, 6>::identity() * damping;
        let gauss_newton = newton;
        newton += curv;
        let step = newton
            .cholesky()
            .or_else(|| gauss_newton.cholesky())?
            .solve(&(-b));
        let (w, tau) = (
            Vec3::new(step[0], step[1], step[2]),
            Vec3::new(step[3], step[4], step[5]),
        );
        let reach = w.norm() * extent + tau.norm();
        reach.is_finite().then_some((w, tau, reach))
    }

    /// `J_d` and its gradient at `x`.
    pub fn eval(&self, x: &[Vec3]) -> Distance {
        let (r, t, pairs) = self.align(x);
        let l2 = self.size * self.size;
        let rt = r.transpose();
        let mut gradient: Vec<Vec3> = x
            .iter()
            .zip(&pairs.near)
            .zip(&self.weights)
            .map(|((p, c), w)| rt * (r * p + t - c) * (0.5 * w / l2))
            .collect();
        for (b, (y, w)) in pairs.back.iter().zip(&self.target_points) {
            let d = rt * (r * self.on_shape(x, b) + t - y) * (0.5 * w / l2);
            for (v, beta) in self.faces[b.0].iter().zip(b.1) {
                gradient[*v] += d * beta;
            }
        }
        Distance {
            value: pairs.value,
            gradient,
            rotation: r,
            translation: t,
            nearest: pairs.near,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, z: impl Fn(Real, Real) -> Real) -> (Vec<Vec3>, Vec<[usize; 3]>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as Real / n as Real - 0.5, j as Real / n as Real - 0.5);
                p.push(Vec3::new(x, y, z(x, y)));
            }
        }
        let mut f = Vec::new();
        let id = |i: usize, j: usize| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (p, f)
    }

    #[test]
    fn the_tree_finds_the_same_closest_point_as_every_face() {
        let (p, f) = grid(9, |x, y| 0.3 * (3.0 * x).sin() * y);
        let tree = Tree::new(&p, &f);
        for k in 0..200 {
            let s = k as Real * 0.37;
            let q = Vec3::new(0.8 * s.sin(), 0.7 * (1.3 * s).cos(), 0.5 * (0.7 * s).sin());
            let hit = tree.closest(&q).unwrap();
            let brute = f
                .iter()
                .map(|t| point_triangle(&[q, p[t[0]], p[t[1]], p[t[2]]]).d2)
                .fold(Real::INFINITY, Real::min);
            assert!((hit.d2 - brute).abs() <= 1e-15, "{} {}", hit.d2, brute);
            assert!(((hit.point - q).norm_squared() - hit.d2).abs() < 1e-14);
        }
    }

    #[test]
    fn the_gradient_matches_differences_and_a_moved_copy_is_at_zero() {
        let (tp, tf) = grid(12, |x, y| 0.4 * (x * x - 0.5 * y * y));
        let (mut sp, sf) = grid(7, |_, _| 0.0);
        let mesh = crate::mesh::Mesh {
            positions: sp.clone(),
            faces: sf.clone(),
            face_fields: Default::default(),
            vertex_fields: Default::default(),
            source: None,
        };
        // The shape: a bent, rotated and moved copy of a coarser grid.
        let rot = nalgebra::Rotation3::from_euler_angles(0.1, -0.2, 0.3);
        for p in sp.iter_mut() {
            *p = rot * Vec3::new(p.x, p.y, 0.3 * (p.x * p.x - 0.5 * p.y * p.y) + 0.05 * p.x)
                + Vec3::new(0.02, -0.01, 0.03);
        }
        let s = Surface::new(&mesh, &tp, &tf, true);
        let d = s.eval(&sp);
        assert!(d.value > 0.0);
        // The gradient's scale: entries are compared to 1e-6 of its largest.
        let gmax = d.gradient.iter().map(|g| g.amax()).fold(0.0, Real::max);
        let h = 1e-6;
        for v in [0, 5, 17, 40, 63] {
            for c in 0..3 {
                let mut a = sp.clone();
                a[v][c] += h;
                let mut b = sp.clone();
                b[v][c] -= h;
                let fd = (s.eval(&a).value - s.eval(&b).value) / (2.0 * h);
                let g = d.gradient[v][c];
                assert!(
                    (fd - g).abs() <= 1e-6 * gmax,
                    "vertex {v} {c}: {g} against {fd}"
                );
            }
        }
        // A rigidly moved copy of the target itself is at distance zero once aligned.
        let same = crate::mesh::Mesh {
            positions: tp.clone(),
            faces: tf.clone(),
            face_fields: Default::default(),
            vertex_fields: Default::default(),
            source: None,
        };
        let s = Surface::new(&same, &tp, &tf, true);
        let small = nalgebra::Rotation3::from_euler_angles(0.02, 0.01, -0.03);
        let moved: Vec<Vec3> = tp
            .iter()
            .map(|p| small * p + Vec3::new(0.01, 0.0, -0.02))
            .collect();
        let d = s.eval(&moved);
        assert!(d.value < 1e-16, "{}", d.value);
    }
}
