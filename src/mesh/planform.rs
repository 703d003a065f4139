//! Sheets whose outline is symmetric about the x axis, `|y| ≤ w(x)` for `x ∈ [0, L]` with `w`
//! given in units of L (the spoon's and the leaf's), meshed by the Delaunay triangulation of
//! points about `edge` apart ([`super::delaunay`]): boundary points equally spaced by arc length
//! along the outline, interior points by dart throwing.

use super::delaunay::delaunay_domain;
use super::generate::Spacing;
use super::Mesh;
use crate::math::{Real, Vec2};

/// The area over L² of the planform of half-width `w` (midpoint rule, 4000 strips).
pub fn area(w: impl Fn(Real) -> Real) -> Real {
    let n = 4000;
    (0..n)
        .map(|i| 2.0 * w((i as Real + 0.5) / n as Real) / n as Real)
        .sum()
}

/// The number of faces a planform of area `area` (over L²) and length `length` with edges
/// `edge` will have, about, from above (for [`super::generate::check_planned`]).
pub fn planned_faces(area: Real, length: Real, edge: Real) -> Real {
    2.3 * area * (length / edge).powi(2) / (3f64.sqrt() / 2.0)
}

/// Points about `e` apart along the closed polygon `outline` (units of the length), by arc
/// length, scaled by `length` (m).
fn resample(outline: &[Vec2], e: Real, length: Real) -> Vec<Vec2> {
    let n = outline.len();
    let perimeter: Real = (0..n)
        .map(|i| (outline[(i + 1) % n] - outline[i]).norm())
        .sum();
    let count = ((perimeter / e).round() as usize).max(8);
    let step = perimeter / count as Real;
    let mut boundary = Vec::with_capacity(count);
    let (mut walked, mut next) = (0.0, 0.0);
    for i in 0..n {
        let (a, b) = (outline[i], outline[(i + 1) % n]);
        let l = (b - a).norm();
        while next < walked + l && boundary.len() < count {
            let s = (next - walked) / l;
            boundary.push((a + (b - a) * s) * length);
            next += step;
        }
        walked += l;
    }
    boundary
}

/// The flat mesh (z = 0) of the planform `|y| ≤ w(x/L) L`, `0 ≤ x ≤ L = length`, with edges
/// about `edge` (m); `w` is at most `max_w` (units of L).
pub fn mesh(w: impl Fn(Real) -> Real, max_w: Real, length: Real, edge: Real, sp: Spacing) -> Mesh {
    let e = edge / length;
    // The outline traced finely: the upper half from tip to tip, then the lower.
    let fine = ((8.0 / e).ceil() as usize).clamp(200, 2_000_000);
    let upper: Vec<Vec2> = (0..=fine)
        .map(|i| {
            let x = i as Real / fine as Real;
            Vec2::new(x, w(x))
        })
        .collect();
    let mut outline = upper.clone();
    outline.extend(
        upper
            .iter()
            .rev()
            .skip(1)
            .take(fine - 1)
            .map(|p| Vec2::new(p.x, -p.y)),
    );
    let boundary = resample(&outline, e, length);
    let depth = |p: Vec2| w(p.x / length) * length - p.y.abs();
    let half = max_w * length;
    delaunay_domain(
        boundary,
        depth,
        [0.0, -half],
        [length, half],
        area(&w) * length * length,
        edge,
        sp,
    )
}
