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
    let dmin = 0.7 * edge;
    let cell = dmin / std::f64::consts::SQRT_2;
    let (gx, gy) = (
        (lx / cell).ceil() as usize + 1,
        (ly / cell).ceil() as usize + 1,
    );
    let mut grid: Vec<Vec<usize>> = vec![Vec::new(); gx * gy];
    let at = |p: Vec2| {
        (((p.x - x0) / cell) as usize).min(gx - 1) + gx * (((p.y - y0) / cell) as usize).min(gy - 1)
    };
    for (k, p) in pts.iter().enumerate() {
        grid[at(*p)].push(k);
    }
    let mut rng = Rng::new(sp.seed);
    let target = (1.15 * lx * ly / (edge * edge * 3f64.sqrt() / 2.0)) as usize;
    let mut misses = 0;
    while misses < 30 * target.max(1) && pts.len() < target + 2 * (nx + ny) {
        let p = Vec2::new(x0 + lx * rng.uniform(), y0 + ly * rng.uniform());
        // Keep away from the boundary by half the spacing, too.
        if p.x - x0 < 0.5 * edge
            || x0 + lx - p.x < 0.5 * edge
            || p.y - y0 < 0.5 * edge
            || y0 + ly - p.y < 0.5 * edge
        {
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
    let faces = triangulate(&pts);
    Mesh {
        positions: pts.iter().map(|p| Vec3::new(p.x, p.y, 0.0)).collect(),
        faces,
        ..Default::default()
    }
}
