//! Exact squared distances between a point and a triangle and between two edges, with their
//! gradients and Hessians in the 12 coordinates of the four points, and the mollifier that
//! fades edge–edge contact out as the edges turn parallel.
//!
//! **The distance as a minimum.** Both pairs measure `d² = min_w ‖r(x, w)‖²` over the
//! barycentric parameters `w` of the closest points, where the difference of the closest points
//! `r = Σ_i c_i(w) x_i` is affine in `w` for fixed positions and linear in the positions for
//! fixed `w`:
//! * point–triangle `(p, a, b, c)`: `r = p − a − u (b − a) − v (c − a)`, `u, v ≥ 0`, `u + v ≤ 1`;
//! * edge–edge `(a, b, c, d)`: `r = a + s (b − a) − c − t (d − c)`, `s, t ∈ [0, 1]`.
//!
//! The minimiser lies either inside (all of `w` free) or on the boundary, where the pair reduces
//! to a point–edge or point–point pair with fewer free parameters; [`Kind`] says which. The
//! classification is the exact constrained minimum: the interior solution when it is feasible
//! (and the pair not degenerate), otherwise the smallest of the boundary pairs.
//!
//! **Derivatives.** With the free parameters at their optimum `w*` (`∂f/∂w = 0` for
//! `f = ‖r‖²`), the envelope theorem gives `∂d²/∂x_i = 2 c_i(w*) r`, and the implicit function
//! theorem the Hessian of the minimum value,
//!
//! `∇²d² = f_xx − f_xw f_ww⁻¹ f_wx`, `f_xx = 2 (c cᵀ) ⊗ I₃`,
//! `∂²f/∂x_i∂w_k = 2 (∂c_i/∂w_k r + c_i t_k)`, `f_ww = 2 [t_k · t_l]`,
//!
//! with `t_k = ∂r/∂w_k = Σ_j (∂c_j/∂w_k) x_j` (`r` is affine in `w`, so `∂²r/∂w² = 0`). This is
//! one formula for all five pair types (the classical closed forms of IPC, Li et al. 2020, §4 and
//! its supplement, follow from it); a finite-difference test checks every type. It is exact
//! wherever the type does not change; across a type change `d²` and its gradient are
//! continuous and the Hessian jumps.
//!
//! **Mollifier.** Two nearly parallel edges have a distance whose closest points jump along the
//! edges; IPC multiplies edge–edge energies by `m(c) = (2 − c/ε) c/ε` for `c < ε`, 1 beyond,
//! `c = ‖(b − a) × (d − c)‖²`, `ε = 10⁻³ ‖b̄ − ā‖² ‖d̄ − c̄‖²` at rest (Li et al. 2020, §4.3). `m`
//! is C¹ in `c` and vanishes at parallel edges, where the point–edge pairs of their end points
//! carry the contact.
//!
//! Units: positions m, `d²` m², gradient m, Hessian dimensionless. DOF order: the three
//! coordinates of each of the pair's four points, in the order above.

use crate::math::{Mat3, Real, SMat, SVec, Vec3};

/// Which features of a pair are closest: the type of the distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Two points (slots `i`, `j`).
    PointPoint(u8, u8),
    /// Point `p` and the inside of edge `a`–`b` (slots).
    PointEdge(u8, u8, u8),
    /// The point inside the triangle (point–triangle pairs only).
    PointTriangle,
    /// The insides of both edges (edge–edge pairs only).
    EdgeEdge,
}

/// A squared distance with the type that gives it and the closest points' parameters.
#[derive(Clone, Copy, Debug)]
pub struct Closest {
    /// `d²` (m²).
    pub d2: Real,
    /// Which features are closest.
    pub kind: Kind,
    /// The coefficients `c_i` of the four points in `r = Σ c_i x_i` at the optimum.
    pub c: [Real; 4],
}

/// `r = Σ c_i x_i` over the four points.
#[inline]
fn combine(x: &[Vec3; 4], c: &[Real; 4]) -> Vec3 {
    x[0] * c[0] + x[1] * c[1] + x[2] * c[2] + x[3] * c[3]
}

/// The closest points of point `x[p]` and segment `x[a]`–`x[b]`.
#[inline]
fn point_segment(x: &[Vec3; 4], p: u8, a: u8, b: u8) -> Closest {
    let (pi, ai, bi) = (p as usize, a as usize, b as usize);
    let e = x[bi] - x[ai];
    let l2 = e.norm_squared();
    let t = if l2 > 0.0 {
        ((x[pi] - x[ai]).dot(&e) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut c = [0.0; 4];
    c[pi] = 1.0;
    let kind = if t <= 0.0 {
        c[ai] = -1.0;
        Kind::PointPoint(p, a)
    } else if t >= 1.0 {
        c[bi] = -1.0;
        Kind::PointPoint(p, b)
    } else {
        c[ai] = -(1.0 - t);
        c[bi] = -t;
        Kind::PointEdge(p, a, b)
    };
    Closest {
        d2: combine(x, &c).norm_squared(),
        kind,
        c,
    }
}

/// The smallest of `candidates` (the first on a tie).
#[inline]
fn smallest(candidates: impl Iterator<Item = Closest>) -> Closest {
    candidates
        .reduce(|best, c| if c.d2 < best.d2 { c } else { best })
        .expect("at least one candidate")
}

/// A 2×2 system's solution by Cramer's rule, or `None` when its determinant is below
/// `tiny` × the product of the diagonal (a degenerate triangle, parallel edges).
#[inline]
fn solve2(m: [[Real; 2]; 2], rhs: [Real; 2], tiny: Real) -> Option<[Real; 2]> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    if det.is_nan() || det <= tiny * m[0][0] * m[1][1] {
        return None;
    }
    Some([
        (rhs[0] * m[1][1] - m[0][1] * rhs[1]) / det,
        (m[0][0] * rhs[1] - m[1][0] * rhs[0]) / det,
    ])
}

/// The relative determinant below which a triangle counts as degenerate and two edges as
/// parallel for the interior solution: the boundary pairs then give the distance.
const DEGENERATE: Real = 1e-12;

/// The closest points of point `x[0]` and triangle `x[1] x[2] x[3]`.
pub fn point_triangle(x: &[Vec3; 4]) -> Closest {
    let (e1, e2, r0) = (x[2] - x[1], x[3] - x[1], x[0] - x[1]);
    let m = [[e1.dot(&e1), e1.dot(&e2)], [e1.dot(&e2), e2.dot(&e2)]];
    if let Some([u, v]) = solve2(m, [e1.dot(&r0), e2.dot(&r0)], DEGENERATE) {
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
            let c = [1.0, -(1.0 - u - v), -u, -v];
            return Closest {
                d2: combine(x, &c).norm_squared(),
                kind: Kind::PointTriangle,
                c,
            };
        }
    }
    smallest(
        [(1, 2), (2, 3), (3, 1)]
            .into_iter()
            .map(|(a, b)| point_segment(x, 0, a, b)),
    )
}

/// The closest points of edges `x[0]`–`x[1]` and `x[2]`–`x[3]`.
pub fn edge_edge(x: &[Vec3; 4]) -> Closest {
    let (u, v, w0) = (x[1] - x[0], x[3] - x[2], x[0] - x[2]);
    let m = [[u.dot(&u), -u.dot(&v)], [-u.dot(&v), v.dot(&v)]];
    if let Some([s, t]) = solve2(m, [-u.dot(&w0), v.dot(&w0)], DEGENERATE) {
        if s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0 {
            let c = [1.0 - s, s, -(1.0 - t), -t];
            return Closest {
                d2: combine(x, &c).norm_squared(),
                kind: Kind::EdgeEdge,
                c,
            };
        }
    }
    smallest(
        [(0, 2, 3), (1, 2, 3), (2, 0, 1), (3, 0, 1)]
            .into_iter()
            .map(|(p, a, b)| point_segment(x, p, a, b)),
    )
}

/// `∂c_i/∂w_k` of the free parameters of `kind` (at most two), with the points' slots.
fn parameter_derivatives(kind: Kind) -> ([[Real; 4]; 2], usize) {
    let mut dc = [[0.0; 4]; 2];
    let m = match kind {
        Kind::PointPoint(..) => 0,
        Kind::PointEdge(_, a, b) => {
            // r = p − (1 − t) a − t b: ∂c_a/∂t = 1, ∂c_b/∂t = −1.
            dc[0][a as usize] = 1.0;
            dc[0][b as usize] = -1.0;
            1
        }
        Kind::PointTriangle => {
            // r = p − (1 − u − v) a − u b − v c.
            dc[0] = [0.0, 1.0, -1.0, 0.0];
            dc[1] = [0.0, 1.0, 0.0, -1.0];
            2
        }
        Kind::EdgeEdge => {
            // r = (1 − s) a + s b − (1 − t) c − t d.
            dc[0] = [-1.0, 1.0, 0.0, 0.0];
            dc[1] = [0.0, 0.0, 1.0, -1.0];
            2
        }
    };
    (dc, m)
}

/// `d²`, its gradient (m) and its Hessian in the 12 coordinates of `x` at the closest points
/// `cl` of a point–triangle or edge–edge pair (module doc).
pub fn derivatives(x: &[Vec3; 4], cl: &Closest, hess: Option<&mut SMat<12, 12>>) -> SVec<12> {
    let c = &cl.c;
    let r = combine(x, c);
    let mut g = SVec::<12>::zeros();
    for (i, ci) in c.iter().enumerate() {
        g.fixed_rows_mut::<3>(3 * i).copy_from(&(r * (2.0 * ci)));
    }
    let Some(h) = hess else {
        return g;
    };
    h.fill(0.0);
    for i in 0..4 {
        for j in 0..4 {
            let cij = 2.0 * c[i] * c[j];
            if cij != 0.0 {
                for a in 0..3 {
                    h[(3 * i + a, 3 * j + a)] = cij;
                }
            }
        }
    }
    let (dc, m) = parameter_derivatives(cl.kind);
    if m == 0 {
        return g;
    }
    // Columns f_k of f_xw (12 × m) and f_ww (m × m).
    let t: [Vec3; 2] = [combine(x, &dc[0]), combine(x, &dc[1])];
    let mut f = SMat::<12, 2>::zeros();
    for k in 0..m {
        for i in 0..4 {
            let col = (r * dc[k][i] + t[k] * c[i]) * 2.0;
            f.fixed_view_mut::<3, 1>(3 * i, k).copy_from(&col);
        }
    }
    if m == 1 {
        let w = 2.0 * t[0].norm_squared();
        if w > 0.0 {
            let f0 = f.column(0);
            *h -= f0 * f0.transpose() / w;
        }
    } else {
        let w = [
            [2.0 * t[0].dot(&t[0]), 2.0 * t[0].dot(&t[1])],
            [2.0 * t[1].dot(&t[0]), 2.0 * t[1].dot(&t[1])],
        ];
        let det = w[0][0] * w[1][1] - w[0][1] * w[1][0];
        if det > 0.0 {
            let inv = nalgebra::Matrix2::new(w[1][1], -w[0][1], -w[1][0], w[0][0]) / det;
            *h -= f * inv * f.transpose();
        }
    }
    g
}

/// `c = ‖(b − a) × (d − c)‖²` of edges `x[0]`–`x[1]`, `x[2]`–`x[3]`, its gradient and (when
/// asked) its Hessian in the 12 coordinates.
pub fn cross_squared(x: &[Vec3; 4], hess: Option<&mut SMat<12, 12>>) -> (Real, SVec<12>) {
    let (u, v) = (x[1] - x[0], x[3] - x[2]);
    let (uu, vv, uv) = (u.dot(&u), v.dot(&v), u.dot(&v));
    let c = uu * vv - uv * uv;
    // ∂c/∂u = 2‖v‖² u − 2(u·v) v, ∂c/∂v = 2‖u‖² v − 2(u·v) u.
    let gu = u * (2.0 * vv) - v * (2.0 * uv);
    let gv = v * (2.0 * uu) - u * (2.0 * uv);
    let mut g = SVec::<12>::zeros();
    g.fixed_rows_mut::<3>(0).copy_from(&(-gu));
    g.fixed_rows_mut::<3>(3).copy_from(&gu);
    g.fixed_rows_mut::<3>(6).copy_from(&(-gv));
    g.fixed_rows_mut::<3>(9).copy_from(&gv);
    if let Some(h) = hess {
        // ∂²c/∂u² = 2‖v‖² I − 2vvᵀ, ∂²c/∂v² = 2‖u‖² I − 2uuᵀ,
        // ∂²c/∂u∂v = 4uvᵀ − 2vuᵀ − 2(u·v) I (row: u, column: v).
        let huu = Mat3::identity() * (2.0 * vv) - v * v.transpose() * 2.0;
        let hvv = Mat3::identity() * (2.0 * uu) - u * u.transpose() * 2.0;
        let huv = u * v.transpose() * 4.0 - v * u.transpose() * 2.0 - Mat3::identity() * (2.0 * uv);
        // u = x1 − x0, v = x3 − x2: signs ±1 per point.
        let su = [-1.0, 1.0];
        for (i, si) in su.iter().enumerate() {
            for (j, sj) in su.iter().enumerate() {
                h.fixed_view_mut::<3, 3>(3 * i, 3 * j)
                    .copy_from(&(huu * (si * sj)));
                h.fixed_view_mut::<3, 3>(6 + 3 * i, 6 + 3 * j)
                    .copy_from(&(hvv * (si * sj)));
                h.fixed_view_mut::<3, 3>(3 * i, 6 + 3 * j)
                    .copy_from(&(huv * (si * sj)));
                h.fixed_view_mut::<3, 3>(6 + 3 * j, 3 * i)
                    .copy_from(&(huv.transpose() * (si * sj)));
            }
        }
    }
    (c, g)
}

/// The mollifier `(m, m′, m″)` at `c` with threshold `eps` (module doc): `m = (2 − c/ε) c/ε`
/// below `ε`, 1 beyond.
#[inline]
pub fn mollifier(c: Real, eps: Real) -> (Real, Real, Real) {
    if c >= eps {
        (1.0, 0.0, 0.0)
    } else {
        let s = c / eps;
        ((2.0 - s) * s, (2.0 - 2.0 * s) / eps, -2.0 / (eps * eps))
    }
}

/// Whether the segment `s = (x[0], x[1])` crosses the triangle `(x[2], x[3], x[4])`: its ends
/// strictly on opposite sides of the triangle's plane and the line through it strictly inside
/// the triangle, by the signs of orientation determinants (a segment touching the triangle's
/// boundary, or coplanar with it, does not cross).
pub fn segment_crosses_triangle(x: &[Vec3; 5]) -> bool {
    let orient = |a: &Vec3, b: &Vec3, c: &Vec3, d: &Vec3| (b - a).cross(&(c - a)).dot(&(d - a));
    let (p, q) = (&x[0], &x[1]);
    let (a, b, c) = (&x[2], &x[3], &x[4]);
    let (sp, sq) = (orient(a, b, c, p), orient(a, b, c, q));
    if !(sp > 0.0 && sq < 0.0 || sp < 0.0 && sq > 0.0) {
        return false;
    }
    let s = [orient(p, q, a, b), orient(p, q, b, c), orient(p, q, c, a)];
    s.iter().all(|&v| v > 0.0) || s.iter().all(|&v| v < 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A segment through a triangle's interior crosses it; one beside it, one ending on its
    /// plane, one in its plane and one parallel above it do not.
    #[test]
    fn segments_cross_triangles_only_through_their_interior() {
        let t = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let with = |p: [Real; 3], q: [Real; 3]| {
            segment_crosses_triangle(&[Vec3::from(p), Vec3::from(q), t[0], t[1], t[2]])
        };
        assert!(with([0.2, 0.2, -1.0], [0.3, 0.1, 1.0]));
        assert!(with([0.3, 0.1, 1.0], [0.2, 0.2, -1.0]));
        assert!(!with([0.8, 0.8, -1.0], [0.8, 0.8, 1.0]));
        assert!(!with([0.2, 0.2, 0.0], [0.2, 0.2, 1.0]));
        assert!(!with([-0.5, 0.2, 0.0], [1.0, 0.2, 0.0]));
        assert!(!with([0.1, 0.1, 0.5], [0.5, 0.1, 0.5]));
    }

    fn pts(v: [[Real; 3]; 4]) -> [Vec3; 4] {
        v.map(Vec3::from)
    }

    /// A tiny deterministic generator (xorshift), to perturb points.
    fn noise(seed: &mut u64) -> Real {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 11) as Real / (1u64 << 53) as Real - 0.5
    }

    /// The brute-force distance: the minimum of `‖r‖²` over a fine grid of the parameters.
    fn brute(x: &[Vec3; 4], pt: bool) -> Real {
        let n = 400;
        let mut best = Real::INFINITY;
        for i in 0..=n {
            for j in 0..=n {
                let (s, t) = (i as Real / n as Real, j as Real / n as Real);
                let r = if pt {
                    if s + t > 1.0 {
                        continue;
                    }
                    x[0] - x[1] - (x[2] - x[1]) * s - (x[3] - x[1]) * t
                } else {
                    x[0] + (x[1] - x[0]) * s - x[2] - (x[3] - x[2]) * t
                };
                best = best.min(r.norm_squared());
            }
        }
        best
    }

    /// Configurations of every type, both pairs: the point above the triangle's inside, beside
    /// each edge, beyond each corner; crossing edges, edges meeting end to inside, end to end,
    /// and parallel edges overlapping and not.
    fn cases() -> Vec<([Vec3; 4], bool)> {
        let tri = |p: [Real; 3]| pts([p, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let mut v = vec![
            (tri([0.2, 0.3, 0.4]), true),
            (tri([0.5, -0.3, 0.2]), true),
            (tri([0.7, 0.7, -0.1]), true),
            (tri([-0.3, 0.4, 0.3]), true),
            (tri([-0.2, -0.3, 0.1]), true),
            (tri([1.4, -0.1, 0.2]), true),
            (tri([-0.1, 1.3, -0.3]), true),
            (
                pts([
                    [0.0, 0.0, 0.0],
                    [1.0, 0.1, 0.0],
                    [0.4, -0.5, 0.3],
                    [0.6, 0.6, 0.35],
                ]),
                false,
            ),
            (
                pts([
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [1.3, 0.2, 0.1],
                    [1.5, 0.9, 0.2],
                ]),
                false,
            ),
            (
                pts([
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.5, -0.2, 0.3],
                    [0.5, -1.0, 0.4],
                ]),
                false,
            ),
            (
                pts([
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.3, 0.2, 0.1],
                    [1.4, 0.2, 0.1],
                ]),
                false,
            ),
            (
                pts([
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [1.5, 0.2, 0.1],
                    [2.4, 0.2, 0.1],
                ]),
                false,
            ),
        ];
        // Randomly perturbed copies (types change only where the test sees it).
        let mut seed = 0x9e3779b97f4a7c15u64;
        let base = v.clone();
        for (x, pt) in base {
            let mut y = x;
            for p in &mut y {
                for k in 0..3 {
                    p[k] += 0.05 * noise(&mut seed);
                }
            }
            v.push((y, pt));
        }
        v
    }

    fn closest(x: &[Vec3; 4], pt: bool) -> Closest {
        if pt {
            point_triangle(x)
        } else {
            edge_edge(x)
        }
    }

    /// Every configuration's distance equals the brute-force minimum over a parameter grid of
    /// step 1/400, to the grid's resolution (its error is second order in the step at an
    /// inside minimum and first order at the boundary: 1e-4 of the scale squared covers both).
    #[test]
    fn distances_are_the_minimum_over_the_closest_points() {
        for (x, pt) in cases() {
            let cl = closest(&x, pt);
            let b = brute(&x, pt);
            assert!(cl.d2 <= b + 1e-14, "{:?}: {} > brute {}", cl.kind, cl.d2, b);
            assert!(b - cl.d2 < 1e-4, "{:?}: {} vs brute {}", cl.kind, cl.d2, b);
        }
    }

    /// Gradient and Hessian against central differences of `d²` and of the gradient, for every
    /// type: the differences' error is O(h²) = 1e-12 of unit-sized terms, so 1e-6 relative
    /// catches any wrong sign or missing term (a missing `f_xw f_ww⁻¹ f_wx` is O(1)).
    #[test]
    fn derivatives_match_finite_differences_for_every_type() {
        let mut kinds = Vec::new();
        for (x, pt) in cases() {
            // Exactly parallel edges tie between end points (the next test).
            if !pt && cross_squared(&x, None).0 < 1e-12 {
                continue;
            }
            let cl = closest(&x, pt);
            kinds.push(format!("{:?}", cl.kind));
            let mut h = SMat::<12, 12>::zeros();
            let g = derivatives(&x, &cl, Some(&mut h));
            let eps = 1e-6;
            for k in 0..12 {
                let (mut xp, mut xm) = (x, x);
                xp[k / 3][k % 3] += eps;
                xm[k / 3][k % 3] -= eps;
                let (cp, cm) = (closest(&xp, pt), closest(&xm, pt));
                assert_eq!(cp.kind, cl.kind, "a test point sits on a type boundary");
                let fd = (cp.d2 - cm.d2) / (2.0 * eps);
                assert!(
                    (fd - g[k]).abs() < 1e-6 * (1.0 + g[k].abs()),
                    "{:?} g[{k}]",
                    cl.kind
                );
                let gp = derivatives(&xp, &cp, None);
                let gm = derivatives(&xm, &cm, None);
                for j in 0..12 {
                    let fd = (gp[j] - gm[j]) / (2.0 * eps);
                    assert!(
                        (fd - h[(j, k)]).abs() < 1e-6 * (1.0 + h[(j, k)].abs()),
                        "{:?} H[{j},{k}] = {} vs {fd}",
                        cl.kind,
                        h[(j, k)]
                    );
                }
            }
        }
        // Every type was tested.
        for k in ["PointTriangle", "EdgeEdge", "PointEdge", "PointPoint"] {
            assert!(kinds.iter().any(|s| s.starts_with(k)), "no {k} case");
        }
    }

    /// Parallel edges and a degenerate (collinear) triangle take the boundary pairs: the
    /// distance is right and finite, the Hessian finite.
    #[test]
    fn parallel_edges_and_flat_triangles_fall_back_to_the_boundary_pairs() {
        let x = pts([
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.25, 0.3, 0.4],
            [1.25, 0.3, 0.4],
        ]);
        let cl = edge_edge(&x);
        assert!(matches!(cl.kind, Kind::PointEdge(..)));
        assert!((cl.d2 - 0.25).abs() < 1e-15);
        let mut h = SMat::<12, 12>::zeros();
        let g = derivatives(&x, &cl, Some(&mut h));
        assert!(g.iter().chain(h.iter()).all(|v| v.is_finite()));
        let x = pts([
            [0.5, 0.5, 0.5],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
        ]);
        let cl = point_triangle(&x);
        assert!((cl.d2 - 0.5).abs() < 1e-15, "{cl:?}");
    }

    /// `c = ‖u × v‖²` and the mollifier against finite differences.
    #[test]
    fn the_cross_product_and_the_mollifier_match_finite_differences() {
        for (x, _) in cases() {
            let mut h = SMat::<12, 12>::zeros();
            let (c, g) = cross_squared(&x, Some(&mut h));
            let (u, v) = (x[1] - x[0], x[3] - x[2]);
            assert!((c - u.cross(&v).norm_squared()).abs() < 1e-14);
            let eps = 1e-6;
            for k in 0..12 {
                let (mut xp, mut xm) = (x, x);
                xp[k / 3][k % 3] += eps;
                xm[k / 3][k % 3] -= eps;
                let (cp, gp) = cross_squared(&xp, None);
                let (cm, gm) = cross_squared(&xm, None);
                assert!(((cp - cm) / (2.0 * eps) - g[k]).abs() < 1e-7);
                for j in 0..12 {
                    assert!(((gp[j] - gm[j]) / (2.0 * eps) - h[(j, k)]).abs() < 1e-7);
                }
            }
        }
        let e = 0.3;
        for c in [0.0, 0.1, 0.29, 0.31] {
            let (m, dm, ddm) = mollifier(c, e);
            let h = 1e-7;
            let (mp, dmp, _) = mollifier(c + h, e);
            assert!(((mp - m) / h - dm).abs() < 1e-5, "m' at {c}");
            if c + h < e {
                assert!(((dmp - dm) / h - ddm).abs() < 1e-5, "m'' at {c}");
            }
        }
        assert_eq!(mollifier(0.0, e).0, 0.0);
        assert_eq!(mollifier(e, e), (1.0, 0.0, 0.0));
    }
}
