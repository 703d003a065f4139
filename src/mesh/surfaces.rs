//! Closed surfaces for balloons: a geodesic sphere of any resolution, and surfaces built on it
//! from an implicit function (a capsule or closed-end tube, a two-lobed peanut, a teddy-like
//! head with two ears on a body), and a torus. Each is a closed, consistently oriented
//! 2-manifold with outward normals (counter-clockwise seen from outside).
//!
//! **Implicit surfaces.** A shape is the zero set of `f` (negative inside), star-shaped about a
//! centre: every ray from the centre leaves it once. The geodesic sphere's directions are
//! projected onto it along those rays (bisection to round-off; a ray that re-enters the shape
//! is an error), then the vertices are relaxed: each moves halfway to the area-weighted
//! centroid of its triangles and back onto the surface along `∇f` (Newton, `f` to 1e-12 of the
//! size), so that triangles even out where the rays meet the surface obliquely (the creases
//! between lobes). The relaxation never flips a triangle (checked: every face's normal points
//! along `∇f`). The lobes are joined smoothly by the polynomial smooth minimum
//! `smin(a, b; k) = min(a, b) − h² k/4`, `h = max(k − |a − b|, 0)/k`, of their distance
//! functions, so the surface has no crease.
//!
//! The teddy: a head sphere of radius R, two ears of radius 0.38 R centred at distance R from
//! the head's centre, 45° either side of the vertical, and a body sphere of radius 1.25 R
//! centred 1.55 R below (smoothing k = 0.15 R); star-shaped about the head's centre (every
//! lobe's tangent cone from there enters it before leaving the head).

use super::Mesh;
use crate::math::{Real, Vec3};
use std::collections::HashMap;

/// The geodesic sphere of frequency `k ≥ 1` and `radius`: each icosahedron face split into
/// `k²` triangles, vertices projected onto the sphere. `10k² + 2` vertices, `20k²` faces.
pub fn geodesic_sphere(radius: Real, k: usize) -> Mesh {
    let ico = super::generate::icosphere(1.0, 0);
    let k = k.max(1);
    let mut ids: HashMap<Vec<(usize, usize)>, usize> = HashMap::new();
    let mut positions: Vec<Vec3> = Vec::new();
    let mut id = |w: [(usize, usize); 3], positions: &mut Vec<Vec3>| -> usize {
        let mut key: Vec<(usize, usize)> = w.iter().copied().filter(|&(_, n)| n > 0).collect();
        key.sort_unstable();
        *ids.entry(key).or_insert_with(|| {
            let p: Vec3 = w
                .iter()
                .map(|&(c, n)| ico.positions[c] * n as Real)
                .sum::<Vec3>();
            positions.push(p.normalize() * radius);
            positions.len() - 1
        })
    };
    let mut faces = Vec::with_capacity(20 * k * k);
    for &[a, b, c] in &ico.faces {
        // Point (i, j): weights (k − i − j) on a, i on b, j on c.
        let mut v = |i: usize, j: usize, positions: &mut Vec<Vec3>| {
            id([(a, k - i - j), (b, i), (c, j)], positions)
        };
        for j in 0..k {
            for i in 0..k - j {
                let p00 = v(i, j, &mut positions);
                let p10 = v(i + 1, j, &mut positions);
                let p01 = v(i, j + 1, &mut positions);
                faces.push([p00, p10, p01]);
                if i + j + 1 < k {
                    let p11 = v(i + 1, j + 1, &mut positions);
                    faces.push([p10, p11, p01]);
                }
            }
        }
    }
    Mesh {
        positions,
        faces,
        ..Default::default()
    }
}

/// The frequency of a geodesic sphere whose edges are about `edge` long on a surface of area
/// `area` (equilateral triangles, `20k²` of them).
pub fn frequency_for(area: Real, edge: Real) -> usize {
    let tri = 3.0_f64.sqrt() / 4.0 * edge * edge;
    ((area / (20.0 * tri)).sqrt().round() as usize).max(1)
}

/// Polynomial smooth minimum with blending width `k`.
pub fn smin(a: Real, b: Real, k: Real) -> Real {
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

/// A closed shape as the zero set of `f` (negative inside), star-shaped about `centre`, within
/// `reach` of it.
pub struct Implicit<'a> {
    /// The function.
    pub f: &'a dyn Fn(Vec3) -> Real,
    /// A centre about which the shape is star-shaped.
    pub centre: Vec3,
    /// An upper bound of the distance from the centre to the surface.
    pub reach: Real,
}

impl Implicit<'_> {
    fn grad(&self, p: Vec3, h: Real) -> Vec3 {
        let f = self.f;
        Vec3::new(
            f(p + Vec3::x() * h) - f(p - Vec3::x() * h),
            f(p + Vec3::y() * h) - f(p - Vec3::y() * h),
            f(p + Vec3::z() * h) - f(p - Vec3::z() * h),
        ) / (2.0 * h)
    }

    /// The point where the ray from the centre along unit `d` leaves the shape; an error if it
    /// enters it again (the shape is not star-shaped).
    fn ray(&self, d: Vec3) -> Result<Vec3, String> {
        let f = self.f;
        let n = 2000;
        let step = self.reach / n as Real;
        let mut exit = None;
        let mut inside = f(self.centre) < 0.0;
        if !inside {
            return Err("the centre is not inside the shape".into());
        }
        for i in 1..=n {
            let t = step * i as Real;
            let now = f(self.centre + d * t) < 0.0;
            if inside && !now {
                if exit.is_some() {
                    return Err(format!(
                        "the shape is not star-shaped about its centre (direction {d:?})"
                    ));
                }
                let (mut lo, mut hi) = (t - step, t);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if f(self.centre + d * mid) < 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                exit = Some(self.centre + d * (0.5 * (lo + hi)));
            }
            inside = now;
        }
        if inside {
            return Err(format!(
                "the shape reaches beyond {} from its centre",
                self.reach
            ));
        }
        exit.ok_or_else(|| "a ray never leaves the shape".into())
    }

    /// Moves `p` onto the surface along the gradient (Newton).
    fn project(&self, mut p: Vec3, h: Real) -> Vec3 {
        for _ in 0..8 {
            let v = (self.f)(p);
            if v.abs() < 1e-12 * self.reach {
                break;
            }
            let g = self.grad(p, h);
            p -= g * (v / g.norm_squared());
        }
        p
    }

    /// The shape meshed from the geodesic sphere of frequency `k` with `relax` relaxation sweeps
    /// (module doc).
    pub fn mesh(&self, k: usize, relax: usize) -> Result<Mesh, String> {
        let mut m = geodesic_sphere(1.0, k);
        for p in &mut m.positions {
            *p = self.ray(*p)?;
        }
        let nv = m.positions.len();
        let mean_edge = self.reach / k as Real;
        let h = 1e-6 * self.reach;
        for _ in 0..relax {
            let mut sum = vec![Vec3::zeros(); nv];
            let mut w = vec![0.0; nv];
            for f in &m.faces {
                let [a, b, c] = f.map(|v| m.positions[v]);
                let area = 0.5 * (b - a).cross(&(c - a)).norm();
                let centroid = (a + b + c) / 3.0;
                for &v in f {
                    sum[v] += centroid * area;
                    w[v] += area;
                }
            }
            let next: Vec<Vec3> = (0..nv)
                .map(|v| {
                    let p = m.positions[v];
                    let target = if w[v] > 0.0 { sum[v] / w[v] } else { p };
                    self.project(p + (target - p) * 0.5, h)
                })
                .collect();
            m.positions = next;
        }
        for (i, f) in m.faces.iter().enumerate() {
            let [a, b, c] = f.map(|v| m.positions[v]);
            let n = (b - a).cross(&(c - a));
            let g = self.grad((a + b + c) / 3.0, h);
            let dot = n.dot(&g);
            if dot.is_nan() || dot <= 0.0 {
                return Err(format!(
                    "face {i} turned over while meshing (try a finer --edge than {})",
                    crate::math::human(mean_edge)
                ));
            }
        }
        Ok(m)
    }
}

/// A closed shape's name and its implicit function, centre and reach, for a size `r` (m): the
/// head radius of the teddy, the radius of the others (the capsule's length is 3 r, the peanut's
/// lobes are centred ±0.8 r apart).
pub fn implicit_shape(name: &str, r: Real) -> Option<Box<dyn Fn(Vec3) -> Real>> {
    Some(match name {
        "capsule" => Box::new(move |p: Vec3| {
            let half = 1.5 * r - r;
            let z = p.z.clamp(-half, half);
            (p - Vec3::new(0.0, 0.0, z)).norm() - r
        }),
        "peanut" => Box::new(move |p: Vec3| {
            let a = (p - Vec3::new(0.0, 0.0, 0.8 * r)).norm() - r;
            let b = (p - Vec3::new(0.0, 0.0, -0.8 * r)).norm() - 0.85 * r;
            smin(a, b, 0.4 * r)
        }),
        "teddy" => Box::new(move |p: Vec3| {
            let s = std::f64::consts::FRAC_1_SQRT_2;
            let head = p.norm() - r;
            let ear1 = (p - Vec3::new(s * r, 0.0, s * r)).norm() - 0.38 * r;
            let ear2 = (p - Vec3::new(-s * r, 0.0, s * r)).norm() - 0.38 * r;
            let body = (p - Vec3::new(0.0, 0.0, -1.55 * r)).norm() - 1.25 * r;
            let k = 0.15 * r;
            smin(smin(smin(head, ear1, k), ear2, k), body, k)
        }),
        _ => return None,
    })
}

/// Area of an implicit shape's mesh, estimated on a coarse one (for choosing the frequency).
fn area(m: &Mesh) -> Real {
    (0..m.faces.len()).map(|f| m.face_area(f)).sum()
}

/// A named closed shape (`sphere`, `capsule`, `peanut`, `teddy`) of size `r` (m) with edges
/// about `edge` long.
pub fn closed_shape(name: &str, r: Real, edge: Real) -> Result<Mesh, String> {
    closed_shape_within(name, r, edge, super::generate::MAX_FACES)
}

/// [`closed_shape`], refused when it would have more than `max_faces` faces.
pub fn closed_shape_within(
    name: &str,
    r: Real,
    edge: Real,
    max_faces: Real,
) -> Result<Mesh, String> {
    // A geodesic sphere of frequency k has 20 k² faces: planned from the area in floating point.
    let planned = |area: Real| {
        let tri = 3.0_f64.sqrt() / 4.0 * edge * edge;
        super::generate::check_planned_within(area / tri, max_faces, "faces", "--edge and --radius")
    };
    // Every shape holds the sphere of radius r: its area is a lower bound, checked first.
    let sphere = 4.0 * std::f64::consts::PI * r * r;
    planned(sphere)?;
    if name == "sphere" {
        return Ok(geodesic_sphere(r, frequency_for(sphere, edge)));
    }
    let f = implicit_shape(name, r).ok_or_else(|| format!("unknown closed shape '{name}'"))?;
    let shape = Implicit {
        f: &*f,
        centre: Vec3::zeros(),
        reach: 4.0 * r,
    };
    let coarse = shape.mesh(8, 0)?;
    planned(area(&coarse))?;
    let k = frequency_for(area(&coarse), edge);
    shape.mesh(k, 40)
}

/// The faces [`torus`] makes: 2 per cell of its `u`, `v` grid, in floating point.
pub fn torus_faces(major: Real, minor: Real, edge: Real) -> Real {
    use std::f64::consts::TAU;
    2.0 * (TAU * major / edge).round().max(6.0) * (TAU * minor / edge).round().max(6.0)
}

/// A torus about the z axis: major radius `major` (centre to tube centre), tube radius
/// `minor`, edges about `edge` long; outward normals.
pub fn torus(major: Real, minor: Real, edge: Real) -> Mesh {
    use std::f64::consts::TAU;
    let nu = ((TAU * major / edge).round() as usize).max(6);
    let nv = ((TAU * minor / edge).round() as usize).max(6);
    let mut positions = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        let u = TAU * i as Real / nu as Real;
        for j in 0..nv {
            let v = TAU * j as Real / nv as Real;
            let rho = major + minor * v.cos();
            positions.push(Vec3::new(rho * u.cos(), rho * u.sin(), minor * v.sin()));
        }
    }
    let id = |i: usize, j: usize| (i % nu) * nv + (j % nv);
    let mut faces = Vec::with_capacity(2 * nu * nv);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // Split along alternating diagonals; (u, v) with u around z and v around the tube
            // from outside is counter-clockwise seen from outside.
            if (i + j) % 2 == 0 {
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            } else {
                faces.push([a, b, d]);
                faces.push([b, c, d]);
            }
        }
    }
    Mesh {
        positions,
        faces,
        ..Default::default()
    }
}
