//! Mesh generators: rectangles (squares, strips), disks and annuli, uniform or with graded
//! spacing, optionally with every interior vertex jittered by a seeded random offset.
//!
//! All meshes lie in the plane z = 0 with counter-clockwise faces (normal +z).

use super::Mesh;
use crate::math::{Real, Vec3};
use std::f64::consts::PI;

/// A small deterministic generator (SplitMix64), so that meshes and perturbations are
/// reproducible from a seed on every platform.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// New generator from a seed.
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> Real {
        (self.next_u64() >> 11) as Real / (1u64 << 53) as Real
    }
    /// Uniform in [-1, 1).
    pub fn symmetric(&mut self) -> Real {
        2.0 * self.uniform() - 1.0
    }
}

/// How vertices are placed.
#[derive(Clone, Copy, Debug, Default)]
pub struct Spacing {
    /// Ratio of the largest to the smallest spacing along each axis (1 = uniform). Spacing grows
    /// geometrically from the low side to the high side.
    pub grading: Real,
    /// Interior vertices move by up to this fraction of the local edge length in a random
    /// direction (0 = none).
    pub jitter: Real,
    /// Seed for the jitter.
    pub seed: u64,
    /// Rectangles: split grid cells along alternating diagonals (a checkerboard) instead of all
    /// along the same diagonal. The default, translation-invariant mesh is the one on which the
    /// mid-edge second fundamental form converges face by face; the checkerboard is not.
    pub checkerboard: bool,
}

/// The most faces `shellsim mesh` generates (10⁷): a mesh beyond it takes gigabytes and hours
/// to simulate. The generators' sizes are planned in floating point from their arguments and
/// checked against it before anything is allocated ([`check_planned`]).
pub const MAX_FACES: Real = 1e7;

/// Checks a planned count of faces (or of another item a generator allocates per face, named by
/// `what`), computed in floating point so that no size overflows, against [`MAX_FACES`]. `args`
/// names the arguments that set it, for the message.
pub fn check_planned(count: Real, what: &str, args: &str) -> Result<(), String> {
    check_planned_within(count, MAX_FACES, what, args)
}

/// [`check_planned`] against the bound `max` in place of [`MAX_FACES`] (the fuzzer keeps its
/// meshes small with it).
pub fn check_planned_within(count: Real, max: Real, what: &str, args: &str) -> Result<(), String> {
    if count.is_finite() && count <= max {
        return Ok(());
    }
    let count = if count.is_finite() {
        format!("about {}", crate::math::human(count))
    } else {
        "uncountably many (beyond floating point)".into()
    };
    Err(format!(
        "{args} would make {count} {what}, more than the {max:e} shellsim allows: make \
         --edge larger or the shape smaller"
    ))
}

/// The number of cells along a side of length `l` at spacing `edge`, as the generators round
/// it (at least 1), in floating point.
fn cells(l: Real, edge: Real) -> Real {
    (l / edge).round().max(1.0)
}

/// The faces [`rectangle`] makes for sides `lx`, `ly` at spacing `edge`: 2 per grid cell.
pub fn rectangle_faces(lx: Real, ly: Real, edge: Real) -> Real {
    2.0 * cells(lx, edge) * cells(ly, edge)
}

/// An upper bound of the faces [`annulus`] makes: each band between two rings has as many
/// faces as its two rings have vertices, and the outer ring has the most.
pub fn annulus_faces(r_in: Real, r_out: Real, sweep: Real, edge: Real) -> Real {
    let ring = (sweep.min(2.0 * PI) * r_out / edge).round().max(6.0) + 1.0;
    2.0 * cells(r_out - r_in, edge) * ring
}

fn graded(n: usize, grading: Real) -> Vec<Real> {
    // Nodes in [0, 1] whose consecutive spacings form a geometric series with ratio r such that
    // last/first = grading.
    if n == 0 {
        return vec![0.0];
    }
    if (grading - 1.0).abs() < 1e-12 || n == 1 {
        return (0..=n).map(|i| i as Real / n as Real).collect();
    }
    let r = grading.powf(1.0 / (n as Real - 1.0));
    let mut x = vec![0.0];
    let mut h = 1.0;
    for _ in 0..n {
        x.push(x.last().copied().unwrap_or(0.0) + h);
        h *= r;
    }
    let total = x[n];
    x.iter().map(|v| v / total).collect()
}

/// A rectangle `[x0, x0+lx] × [y0, y0+ly]` with about `edge` spacing. Each grid cell is split
/// along the same diagonal (or alternating ones with `checkerboard`).
pub fn rectangle(x0: Real, y0: Real, lx: Real, ly: Real, edge: Real, sp: Spacing) -> Mesh {
    let nx = ((lx / edge).round() as usize).max(1);
    let ny = ((ly / edge).round() as usize).max(1);
    let g = if sp.grading > 0.0 { sp.grading } else { 1.0 };
    let xs = graded(nx, g);
    let ys = graded(ny, g);
    let mut positions = Vec::with_capacity((nx + 1) * (ny + 1));
    for &y in &ys {
        for &x in &xs {
            positions.push(Vec3::new(x0 + lx * x, y0 + ly * y, 0.0));
        }
    }
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut faces = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if !sp.checkerboard || (i + j) % 2 == 0 {
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            } else {
                faces.push([a, b, d]);
                faces.push([b, c, d]);
            }
        }
    }
    let mut mesh = Mesh {
        positions,
        faces,
        ..Default::default()
    };
    jitter(&mut mesh, sp, |p| {
        (p.x - x0).abs() < 1e-12 * lx
            || (p.x - x0 - lx).abs() < 1e-12 * lx
            || (p.y - y0).abs() < 1e-12 * ly
            || (p.y - y0 - ly).abs() < 1e-12 * ly
    });
    mesh
}

/// An annulus `r_in ≤ r ≤ r_out` (a disk when `r_in = 0`) covering angles `[0, sweep)` (a full
/// ring when `sweep ≥ 2π`, otherwise a sector with two straight edges), with rings of vertices
/// about `edge` apart.
pub fn annulus(r_in: Real, r_out: Real, sweep: Real, edge: Real, sp: Spacing) -> Mesh {
    let full = sweep >= 2.0 * PI - 1e-12;
    let sweep = sweep.min(2.0 * PI);
    let nr = (((r_out - r_in) / edge).round() as usize).max(1);
    let g = if sp.grading > 0.0 { sp.grading } else { 1.0 };
    let rs: Vec<Real> = graded(nr, g)
        .into_iter()
        .map(|t| r_in + (r_out - r_in) * t)
        .collect();
    let mut positions = Vec::new();
    let mut rings: Vec<Vec<usize>> = Vec::new();
    for &r in &rs {
        let mut ring = Vec::new();
        if r < 1e-14 * r_out {
            ring.push(positions.len());
            positions.push(Vec3::zeros());
        } else {
            let n = ((sweep * r / edge).round() as usize).max(if full { 6 } else { 1 });
            let count = if full { n } else { n + 1 };
            for k in 0..count {
                let t = sweep * k as Real / n as Real;
                ring.push(positions.len());
                positions.push(Vec3::new(r * t.cos(), r * t.sin(), 0.0));
            }
        }
        rings.push(ring);
    }
    let angle = |p: &Vec3| {
        let a = p.y.atan2(p.x);
        if a < -1e-12 {
            a + 2.0 * PI
        } else {
            a.max(0.0)
        }
    };
    let mut faces = Vec::new();
    for w in rings.windows(2) {
        let (inner, outer) = (&w[0], &w[1]);
        if inner.len() == 1 {
            // Fan around the centre.
            let c = inner[0];
            let m = outer.len();
            let segs = if full { m } else { m - 1 };
            for k in 0..segs {
                faces.push([c, outer[k], outer[(k + 1) % m]]);
            }
            continue;
        }
        // Zip two rings by angle: always advance the ring whose next vertex has the smaller angle.
        let (ni, no) = (inner.len(), outer.len());
        let (si, so) = if full { (ni, no) } else { (ni - 1, no - 1) };
        let (mut i, mut o) = (0usize, 0usize);
        let ang_at = |ring: &Vec<usize>, k: usize, segs: usize| -> Real {
            if full && k == segs {
                2.0 * PI
            } else {
                angle(&positions[ring[k % ring.len()]])
            }
        };
        while i < si || o < so {
            let adv_inner = if i == si {
                false
            } else if o == so {
                true
            } else {
                ang_at(inner, i + 1, si) <= ang_at(outer, o + 1, so)
            };
            let a = inner[i % ni];
            let b = outer[o % no];
            if adv_inner {
                let a2 = inner[(i + 1) % ni];
                faces.push([a, b, a2]);
                i += 1;
            } else {
                let b2 = outer[(o + 1) % no];
                faces.push([a, b, b2]);
                o += 1;
            }
        }
    }
    // Orient counter-clockwise.
    for f in &mut faces {
        let (p, q, r) = (positions[f[0]], positions[f[1]], positions[f[2]]);
        if (q - p).cross(&(r - p)).z < 0.0 {
            f.swap(1, 2);
        }
    }
    let mut mesh = Mesh {
        positions,
        faces,
        ..Default::default()
    };
    let tol = 1e-9 * r_out;
    jitter(&mut mesh, sp, |p| {
        let r = p.norm();
        (r - r_out).abs() < tol
            || (r_in > 0.0 && (r - r_in).abs() < tol)
            || r < tol
            || (!full && (p.y.abs() < tol && p.x > 0.0 || (angle(p) - sweep).abs() < 1e-9))
    });
    mesh
}

/// Moves each vertex that is not on the boundary by up to `jitter × (local shortest edge)` in a
/// random in-plane direction, deterministically from the seed.
fn jitter(mesh: &mut Mesh, sp: Spacing, on_boundary: impl Fn(&Vec3) -> bool) {
    if sp.jitter <= 0.0 {
        return;
    }
    let n = mesh.positions.len();
    let mut shortest = vec![Real::INFINITY; n];
    for f in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let l = (mesh.positions[a] - mesh.positions[b]).norm();
            shortest[a] = shortest[a].min(l);
            shortest[b] = shortest[b].min(l);
        }
    }
    let mut rng = Rng::new(sp.seed);
    for (i, p) in mesh.positions.iter_mut().enumerate() {
        let (u, v) = (rng.symmetric(), rng.symmetric());
        if on_boundary(p) || !shortest[i].is_finite() {
            continue;
        }
        // Radius ≤ jitter·h in a random direction (uniform in the square, clipped to the disk).
        let s = (u * u + v * v).sqrt().max(1.0);
        p.x += sp.jitter * shortest[i] * u / s;
        p.y += sp.jitter * shortest[i] * v / s;
    }
}

/// An icosphere of `radius` centred at the origin: the icosahedron with each face split into
/// 4 `subdivisions` times, new vertices projected onto the sphere. `10·4ⁿ + 2` vertices and
/// `20·4ⁿ` faces, counter-clockwise seen from outside (outward normals), closed and manifold.
pub fn icosphere(radius: Real, subdivisions: usize) -> Mesh {
    let t = (1.0 + (5.0 as Real).sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::new(p[0], p[1], p[2]).normalize())
    .collect();
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: usize, b: usize, positions: &mut Vec<Vec3>| -> usize {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                positions.push(((positions[a] + positions[b]) / 2.0).normalize());
                positions.len() - 1
            })
        };
        let mut next = Vec::with_capacity(4 * faces.len());
        for &[a, b, c] in &faces {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        faces = next;
    }
    for p in &mut positions {
        *p *= radius;
    }
    Mesh {
        positions,
        faces,
        ..Default::default()
    }
}
