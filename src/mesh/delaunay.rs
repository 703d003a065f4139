//! Delaunay triangulation of points in the plane (Bowyer–Watson), used to mesh a rectangle
//! from well-spaced random points: an irregular mesh of the kind users' meshers produce.
//!
//! Points are inserted in Morton order; each insertion locates its triangle by walking from the
//! previous one and re-triangulates the cavity of triangles whose circumcircle contains it.
//! Adjacency is maintained, so an insertion costs O(cavity) on average.

use super::generate::{Rng, Spacing};
use super::Mesh;
use crate::math::{Real, Vec2, Vec3};

const NONE: usize = usize::MAX;

fn orient(a: Vec2, b: Vec2, c: Vec2) -> Real {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// True when `d` lies strictly inside the circumcircle of the counter-clockwise triangle abc.
fn in_circle(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let (ax, ay) = (a.x - d.x, a.y - d.y);
    let (bx, by) = (b.x - d.x, b.y - d.y);
    let (cx, cy) = (c.x - d.x, c.y - d.y);
    let det = (ax * ax + ay * ay) * (bx * cy - cx * by) - (bx * bx + by * by) * (ax * cy - cx * ay)
        + (cx * cx + cy * cy) * (ax * by - bx * ay);
    det > 0.0
}

/// Delaunay triangles (counter-clockwise) of distinct points in general position.
pub fn triangulate(points: &[Vec2]) -> Vec<[usize; 3]> {
    let n = points.len();
    if n < 3 {
        return Vec::new();
    }
    let mut lo = Vec2::repeat(Real::INFINITY);
    let mut hi = Vec2::repeat(Real::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let c = (lo + hi) / 2.0;
    let r = (hi - lo).norm().max(Real::MIN_POSITIVE) * 20.0;
    let mut pts = points.to_vec();
    pts.push(c + Vec2::new(-r, -r));
    pts.push(c + Vec2::new(r, -r));
    pts.push(c + Vec2::new(0.0, r));
    let mut tris: Vec<[usize; 3]> = vec![[n, n + 1, n + 2]];
    // nbr[t][i]: triangle across the edge opposite vertex i.
    let mut nbr: Vec<[usize; 3]> = vec![[NONE; 3]];
    let mut alive = vec![true];
    let mut order: Vec<usize> = (0..n).collect();
    let key = |p: Vec2| {
        let q = (p - lo).component_div(&(hi - lo).map(|e| if e > 0.0 { e } else { 1.0 }));
        let (x, y) = ((q.x * 65535.0) as u32, (q.y * 65535.0) as u32);
        (0..16).fold(0u64, |k, b| {
            k | (((x >> b) & 1) as u64) << (2 * b) | (((y >> b) & 1) as u64) << (2 * b + 1)
        })
    };
    order.sort_by_key(|&i| key(points[i]));
    let mut last = 0usize;
    let mut cavity: Vec<usize> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let mut in_cavity: Vec<bool> = vec![false];
    for &pi in &order {
        let p = pts[pi];
        // Walk to the triangle containing p.
        let mut t = last;
        let mut steps = 0;
        'walk: loop {
            steps += 1;
            let tri = tris[t];
            for i in 0..3 {
                let (a, b) = (pts[tri[(i + 1) % 3]], pts[tri[(i + 2) % 3]]);
                if orient(a, b, p) < 0.0 && nbr[t][i] != NONE {
                    t = nbr[t][i];
                    if steps > 4 * tris.len() + 10 {
                        break 'walk;
                    }
                    continue 'walk;
                }
            }
            break;
        }
        // Cavity: triangles whose circumcircle contains p, connected to t.
        cavity.clear();
        stack.clear();
        stack.push(t);
        in_cavity[t] = true;
        while let Some(u) = stack.pop() {
            cavity.push(u);
            for &w in &nbr[u] {
                if w != NONE && !in_cavity[w] {
                    let [a, b, c] = tris[w];
                    if in_circle(pts[a], pts[b], pts[c], p) {
                        in_cavity[w] = true;
                        stack.push(w);
                    }
                }
            }
        }
        // Boundary edges of the cavity, each with its outer neighbour.
        let mut boundary: Vec<(usize, usize, usize)> = Vec::new();
        for &u in &cavity {
            for i in 0..3 {
                let w = nbr[u][i];
                if w == NONE || !in_cavity[w] {
                    boundary.push((tris[u][(i + 1) % 3], tris[u][(i + 2) % 3], w));
                }
            }
        }
        for &u in &cavity {
            alive[u] = false;
            in_cavity[u] = false;
        }
        // New triangles (a, b, p); link them to the outside and to each other.
        let mut by_start: std::collections::HashMap<usize, usize> =
            std::collections::HashMap::new();
        let mut new_tris = Vec::with_capacity(boundary.len());
        for &(a, b, w) in &boundary {
            let id = tris.len();
            tris.push([a, b, pi]);
            nbr.push([NONE, NONE, w]);
            alive.push(true);
            in_cavity.push(false);
            if w != NONE {
                for j in 0..3 {
                    let tw = tris[w];
                    if (tw[(j + 1) % 3] == b && tw[(j + 2) % 3] == a)
                        || (tw[(j + 1) % 3] == a && tw[(j + 2) % 3] == b)
                    {
                        nbr[w][j] = id;
                    }
                }
            }
            by_start.insert(a, id);
            new_tris.push(id);
        }
        for &id in &new_tris {
            let [_, b, _] = tris[id];
            // Edge (b, p) is opposite vertex a (index 0): shared with the triangle starting at b.
            if let Some(&o) = by_start.get(&b) {
                nbr[id][0] = o;
                // In triangle o = (b, c, p), edge (p, b) is opposite vertex c (index 1).
                nbr[o][1] = id;
            }
        }
        last = *new_tris.last().unwrap_or(&0);
    }
    tris.iter()
        .zip(&alive)
        .filter(|(t, &a)| a && t.iter().all(|&v| v < n))
        .map(|(t, _)| *t)
        .filter(|t| {
            orient(points[t[0]], points[t[1]], points[t[2]]) > 1e-14 * (hi - lo).norm_squared()
        })
        .collect()
}

/// What a Delaunay mesh of a domain of area `area` in a box `lx × ly` at spacing `edge`
/// allocates, in floating point: about twice its interior points in faces, and the cells of the
/// dart-throwing grid (both are checked with [`super::generate::check_planned`]).
pub fn delaunay_planned(area: Real, lx: Real, ly: Real, edge: Real) -> (Real, Real) {
    let points = 1.15 * area / (edge * edge * 3f64.sqrt() / 2.0) + 2.0 * (lx + ly) / edge;
    let cell = 0.7 * edge / std::f64::consts::SQRT_2;
    (2.0 * points, (lx / cell + 2.0) * (ly / cell + 2.0))
}

/// A rectangle `[x0, x0+lx] × [y0, y0+ly]` meshed by the Delaunay triangulation of points about
/// `edge` apart: equally spaced points on the boundary, and interior points thrown at random
/// (seeded) and kept when no earlier point is closer than `0.7 × edge` (dart throwing), so the
/// triangles are irregular but not slivers.
pub fn delaunay_rectangle(x0: Real, y0: Real, lx: Real, ly: Real, edge: Real, sp: Spacing) -> Mesh {
    let nx = ((lx / edge).round() as usize).max(1);
    let ny = ((ly / edge).round() as usize).max(1);
    let mut pts: Vec<Vec2> = Vec::new();
    for i in 0..nx {
        pts.push(Vec2::new(x0 + lx * i as Real / nx as Real, y0));
        pts.push(Vec2::new(x0 + lx * (i + 1) as Real / nx as Real, y0 + ly));
    }
    for j in 0..ny {
        pts.push(Vec2::new(x0 + lx, y0 + ly * j as Real / ny as Real));
        pts.push(Vec2::new(x0, y0 + ly * (j + 1) as Real / ny as Real));
    }
    let depth = |p: Vec2| {
        (p.x - x0)
            .min(x0 + lx - p.x)
            .min(p.y - y0)
            .min(y0 + ly - p.y)
    };
    delaunay_domain(pts, depth, [x0, y0], [x0 + lx, y0 + ly], lx * ly, edge, sp)
}

/// An annulus `r_in ≤ r ≤ r_out`, or its sector `0 ≤ θ ≤ sweep` (rad) when `sweep < 2π`, meshed
/// like [`delaunay_rectangle`]: boundary points about `edge` apart on the circles (and the two
/// radial sides of a sector), random interior points at least `0.7 × edge` apart.
pub fn delaunay_annulus(r_in: Real, r_out: Real, sweep: Real, edge: Real, sp: Spacing) -> Mesh {
    use std::f64::consts::PI;
    let full = sweep >= 2.0 * PI - 1e-12;
    let sweep = sweep.min(2.0 * PI);
    let mut pts: Vec<Vec2> = Vec::new();
    for r in [r_in, r_out] {
        let n = ((sweep * r / edge).round() as usize).max(6);
        let count = if full { n } else { n + 1 };
        for k in 0..count {
            let t = sweep * k as Real / n as Real;
            pts.push(Vec2::new(r * t.cos(), r * t.sin()));
        }
    }
    if !full {
        let nr = (((r_out - r_in) / edge).round() as usize).max(1);
        for j in 1..nr {
            let r = r_in + (r_out - r_in) * j as Real / nr as Real;
            pts.push(Vec2::new(r, 0.0));
            pts.push(Vec2::new(r * sweep.cos(), r * sweep.sin()));
        }
    }
    let depth = move |p: Vec2| {
        let r = p.norm();
        let radial = (r - r_in).min(r_out - r);
        if full {
            return radial;
        }
        // Distance to the two straight sides, negative outside the sector.
        let mut t = p.y.atan2(p.x);
        if t < -1e-12 {
            t += 2.0 * PI;
        }
        let side0 = p.y; // side θ = 0 (x > 0)
        let side1 = -(p.x * sweep.sin() - p.y * sweep.cos()); // side θ = sweep
        let inside = t <= sweep + 1e-12;
        let sides = if inside {
            side0.abs().min(side1.abs()).min(r)
        } else {
            -side0.abs().min(side1.abs())
        };
        radial.min(sides)
    };
    let area = 0.5 * sweep * (r_out * r_out - r_in * r_in);
    delaunay_domain(pts, depth, [-r_out, -r_out], [r_out, r_out], area, edge, sp)
}

/// Delaunay mesh of a domain given by its boundary points and `depth(p)` (distance to the
/// boundary, negative outside) inside the box `[lo, hi]`: interior points by dart throwing
/// (`0.7 × edge` apart, at least `0.5 × edge` from the boundary) until about
/// `1.15 area / (√3/2 edge²)` points, then the triangles whose centroid lies outside are dropped
/// (this carves holes and notches out of the convex hull).
pub(crate) fn delaunay_domain(
    mut pts: Vec<Vec2>,
    depth: impl Fn(Vec2) -> Real,
    lo: [Real; 2],
    hi: [Real; 2],
    area: Real,
    edge: Real,
    sp: Spacing,
) -> Mesh {
    let (x0, y0) = (lo[0], lo[1]);
    let (lx, ly) = (hi[0] - lo[0], hi[1] - lo[1]);
    let nb = pts.len();
    let dmin = 0.7 * edge;
    let cell = dmin / std::f64::consts::SQRT_2;
    let (gx, gy) = (
        (lx / cell).ceil() as usize + 1,
        (ly / cell).ceil() as usize + 1,
    );
    let mut grid: Vec<Vec<usize>> = vec![Vec::new(); gx * gy];
    let at = |p: Vec2| {
        (((p.x - x0) / cell).max(0.0) as usize).min(gx - 1)
            + gx * (((p.y - y0) / cell).max(0.0) as usize).min(gy - 1)
    };
    for (k, p) in pts.iter().enumerate() {
        grid[at(*p)].push(k);
    }
    let mut rng = Rng::new(sp.seed);
    let target = (1.15 * area / (edge * edge * 3f64.sqrt() / 2.0)) as usize;
    let mut misses = 0;
    while misses < 30 * target.max(1) && pts.len() < target + nb {
        let p = Vec2::new(x0 + lx * rng.uniform(), y0 + ly * rng.uniform());
        // Keep away from the boundary by half the spacing, too.
        if depth(p) < 0.5 * edge {
            misses += 1;
            continue;
        }
        let (ci, cj) = (((p.x - x0) / cell) as isize, ((p.y - y0) / cell) as isize);
        let mut ok = true;
        'near: for dj in -2..=2 {
            for di in -2..=2 {
                let (i, j) = (ci + di, cj + dj);
                if i < 0 || j < 0 || i as usize >= gx || j as usize >= gy {
                    continue;
                }
                for &k in &grid[i as usize + gx * j as usize] {
                    if (pts[k] - p).norm() < dmin {
                        ok = false;
                        break 'near;
                    }
                }
            }
        }
        if ok {
            grid[at(p)].push(pts.len());
            pts.push(p);
        } else {
            misses += 1;
        }
    }
    let faces: Vec<[usize; 3]> = triangulate(&pts)
        .into_iter()
        .filter(|t| depth((pts[t[0]] + pts[t[1]] + pts[t[2]]) / 3.0) > 0.0)
        .collect();
    // Drop points no kept triangle uses (none for convex domains).
    let mut map = vec![usize::MAX; pts.len()];
    let mut positions = Vec::new();
    let faces = faces
        .iter()
        .map(|t| {
            t.map(|v| {
                if map[v] == usize::MAX {
                    map[v] = positions.len();
                    positions.push(Vec3::new(pts[v].x, pts[v].y, 0.0));
                }
                map[v]
            })
        })
        .collect();
    Mesh {
        positions,
        faces,
        ..Default::default()
    }
}
