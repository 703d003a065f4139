//! A flat film with printed parallel strips (`shellsim mesh film`): the rectangle
//! `[−lx/2, lx/2] × [−ly/2, ly/2]` with strips of width `w` every `p` (the pitch), centred on the
//! lines `n·x = j p` (j an integer), where `n = (−sin θ, cos θ)` is normal to the strip direction
//! `d = (cos θ, sin θ)` at angle θ to x. Faces carry `tri_tags` 1 (bare film) and 2 (under a
//! strip), the pattern of Wang et al.'s shape-changing gelatin films (CHI 2017), where printed
//! ethyl-cellulose strips keep water from the film's top layer.
//!
//! ## Conforming to the strips at any angle
//! The vertices lie on rows parallel to the strips, `n·x = c`, each row clipped to the rectangle
//! and divided into pieces of about `edge`. The row offsets `c` include every strip boundary and
//! every corner of the rectangle, with rows about `edge √3/2` apart between them, so no corner
//! lies strictly between two neighbouring rows: the band between them is a trapezoid whose two
//! other sides lie on the rectangle's sides, and it is triangulated by zipping the two rows
//! together, always taking the shorter diagonal. Every strip boundary is thus a line of mesh
//! edges, for any angle; a boundary closer than a quarter row spacing to a corner row moves onto
//! it (the strip's edge moves by at most `edge/5`).

use super::{Field, Mesh};
use crate::math::{Real, Vec3};

/// The printed pattern of a film.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strips {
    /// Angle θ of the strips to the x axis (rad).
    pub angle: Real,
    /// Width of a strip (m).
    pub width: Real,
    /// Distance between the centre lines of neighbouring strips (m), more than `width`.
    pub pitch: Real,
}

impl Strips {
    /// True when the point at offset `c = n·x` lies under a strip.
    pub fn covers(&self, c: Real) -> bool {
        let j = (c / self.pitch).round();
        (c - j * self.pitch).abs() < 0.5 * self.width
    }
}

/// The number of faces of a film, about (for planning).
pub fn planned_faces(lx: Real, ly: Real, edge: Real) -> Real {
    // Rows about edge √3/2 apart, pieces of about edge along them: two faces per cell.
    let r = lx.hypot(ly);
    2.0 * (lx * ly / (edge * edge * 0.75f64.sqrt()) + 4.0 * r / edge + 8.0)
}

/// The film `lx × ly` (m) with edges about `edge` (m) and the strips `strips`; see the module doc.
/// Errors when two corners lie on nearly but not exactly one row (strips within a hair of
/// parallel to a side or a diagonal), which would leave a sliver band.
pub fn film(lx: Real, ly: Real, edge: Real, strips: Strips) -> Result<Mesh, String> {
    let (s, c) = strips.angle.sin_cos();
    let (d, n) = ([c, s], [-s, c]);
    let corners = [
        [-0.5 * lx, -0.5 * ly],
        [0.5 * lx, -0.5 * ly],
        [0.5 * lx, 0.5 * ly],
        [-0.5 * lx, 0.5 * ly],
    ];
    let offset = |p: [Real; 2]| n[0] * p[0] + n[1] * p[1];
    let mut fixed: Vec<Real> = corners.iter().map(|&p| offset(p)).collect();
    fixed.sort_by(Real::total_cmp);
    let (lo, hi) = (fixed[0], fixed[3]);
    let spacing = edge * 0.75f64.sqrt();
    let snap = 0.25 * spacing;
    if let Some(w) = fixed
        .windows(2)
        .find(|w| w[1] - w[0] > 1e-12 * (lx + ly) && w[1] - w[0] < snap)
    {
        return Err(format!(
            "strips at {:.4}° leave two corners of the film {:.3e} m apart across the strips, \
             less than a quarter row ({:.3e} m): make them exactly parallel to a side or turn \
             them by a degree",
            strips.angle.to_degrees(),
            w[1] - w[0],
            snap
        ));
    }
    // Strip boundaries strictly inside, unless within `snap` of a corner row.
    let mut rows = fixed.clone();
    let first = ((lo - 0.5 * strips.width) / strips.pitch).floor() as i64 - 1;
    let last = ((hi + 0.5 * strips.width) / strips.pitch).ceil() as i64 + 1;
    for j in first..=last {
        for side in [-0.5, 0.5] {
            let b = j as Real * strips.pitch + side * strips.width;
            if b > lo && b < hi && fixed.iter().all(|&f| (f - b).abs() > snap) {
                rows.push(b);
            }
        }
    }
    rows.sort_by(Real::total_cmp);
    rows.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (hi - lo));
    // Subdivide each band into rows about `spacing` apart.
    let mut all = vec![rows[0]];
    for w in rows.windows(2) {
        let k = ((w[1] - w[0]) / spacing).ceil().max(1.0) as usize;
        all.extend((1..=k).map(|i| w[0] + (w[1] - w[0]) * i as Real / k as Real));
    }
    // Each row: its points along d, clipped to the rectangle.
    let mut positions = Vec::new();
    let mut row_points: Vec<Vec<usize>> = Vec::with_capacity(all.len());
    for &off in &all {
        let (mut t0, mut t1) = (Real::NEG_INFINITY, Real::INFINITY);
        for (k, half) in [0.5 * lx, 0.5 * ly].into_iter().enumerate() {
            // |off n_k + t d_k| ≤ half.
            if d[k].abs() < 1e-14 {
                continue;
            }
            let (a, b) = ((-half - off * n[k]) / d[k], (half - off * n[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        let len = (t1 - t0).max(0.0);
        let k = if len <= 1e-9 * (hi - lo) {
            0
        } else {
            (len / edge).ceil().max(1.0) as usize
        };
        let mut ids = Vec::with_capacity(k + 1);
        for i in 0..=k {
            let t = if k == 0 {
                0.5 * (t0 + t1)
            } else {
                t0 + len * i as Real / k as Real
            };
            let p = [off * n[0] + t * d[0], off * n[1] + t * d[1]];
            // Round-off may put a boundary point a hair outside.
            let p = [
                p[0].clamp(-0.5 * lx, 0.5 * lx),
                p[1].clamp(-0.5 * ly, 0.5 * ly),
            ];
            ids.push(positions.len());
            positions.push(Vec3::new(p[0], p[1], 0.0));
        }
        row_points.push(ids);
    }
    let mut faces = Vec::new();
    for w in row_points.windows(2) {
        zip_rows(&w[0], &w[1], &positions, &mut faces);
    }
    let tags = faces
        .iter()
        .map(|f: &[usize; 3]| {
            let g = f.iter().map(|&v| positions[v]).sum::<Vec3>() / 3.0;
            if strips.covers(offset([g.x, g.y])) {
                2.0
            } else {
                1.0
            }
        })
        .collect();
    let mut mesh = Mesh {
        positions,
        faces,
        ..Mesh::default()
    };
    mesh.face_fields
        .insert("tri_tags".into(), Field::scalar(tags));
    Ok(mesh)
}

/// Triangulates the band between two rows of points (each ordered along the strips), taking at
/// each step the shorter diagonal; faces counter-clockwise seen from +z.
fn zip_rows(a: &[usize], b: &[usize], p: &[Vec3], faces: &mut Vec<[usize; 3]>) {
    let (mut i, mut j) = (0, 0);
    let dist = |u: usize, v: usize| (p[u] - p[v]).norm();
    while i + 1 < a.len() || j + 1 < b.len() {
        let advance_a = if i + 1 == a.len() {
            false
        } else if j + 1 == b.len() {
            true
        } else {
            dist(a[i + 1], b[j]) < dist(a[i], b[j + 1])
        };
        let tri = if advance_a {
            i += 1;
            [a[i - 1], a[i], b[j]]
        } else {
            j += 1;
            [a[i], b[j - 1], b[j]]
        };
        let (u, v) = (p[tri[1]] - p[tri[0]], p[tri[2]] - p[tri[0]]);
        let area = u.x * v.y - u.y * v.x;
        faces.push(if area >= 0.0 {
            tri
        } else {
            [tri[0], tri[2], tri[1]]
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quality(m: &Mesh) -> Real {
        (0..m.faces.len())
            .map(|f| {
                let [a, b, c] = m.faces[f].map(|v| m.positions[v]);
                let l2 = (b - a).norm_squared() + (c - b).norm_squared() + (a - c).norm_squared();
                // 4√3 A / Σl²: 1 for an equilateral triangle.
                4.0 * 3f64.sqrt() * m.face_area(f) / l2
            })
            .fold(Real::INFINITY, Real::min)
    }

    /// At any angle the film is a valid surface of the rectangle's area, the strip boundaries
    /// are mesh edges (the tagged area is exactly the strips' area), and no triangle is a
    /// sliver.
    #[test]
    fn films_conform_to_their_strips_at_any_angle() {
        let (lx, ly, edge) = (0.04, 0.01, 0.001);
        for deg in [0.0, 30.0, 45.0, 90.0, 117.0] {
            let strips = Strips {
                angle: Real::to_radians(deg),
                width: 0.0015,
                pitch: 0.004,
            };
            let m = film(lx, ly, edge, strips).unwrap();
            m.validate().unwrap();
            super::super::Topology::build(&m).unwrap();
            let area: Real = (0..m.faces.len()).map(|f| m.face_area(f)).sum();
            assert!(
                (area / (lx * ly) - 1.0).abs() < 1e-12,
                "{deg}°: area {area}"
            );
            assert!(
                (m.faces.len() as Real) < planned_faces(lx, ly, edge),
                "{deg}°"
            );
            // The strips' own area, by sampling the rectangle finely.
            let (s, c) = strips.angle.sin_cos();
            let k = 2000;
            let mut covered = 0usize;
            for i in 0..k {
                for j in 0..k / 4 {
                    let x = -0.5 * lx + lx * (i as Real + 0.5) / k as Real;
                    let y = -0.5 * ly + ly * (j as Real + 0.5) / (k / 4) as Real;
                    covered += usize::from(strips.covers(-s * x + c * y));
                }
            }
            let exact = covered as Real / (k * k / 4) as Real;
            let tags = &m.face_fields["tri_tags"].data;
            let tagged: Real = (0..m.faces.len())
                .filter(|&f| tags[f] == 2.0)
                .map(|f| m.face_area(f))
                .sum::<Real>()
                / (lx * ly);
            // Sampling error about 1/k per boundary crossing; a snapped boundary moves ≤ edge/5
            // over a corner's short row only.
            assert!((tagged - exact).abs() < 0.01, "{deg}°: {tagged} vs {exact}");
            let q = quality(&m);
            assert!(q > 0.3, "{deg}°: worst triangle quality {q}");
        }
        let near = Strips {
            angle: 1e-4,
            width: 0.0015,
            pitch: 0.004,
        };
        assert!(film(lx, ly, edge, near)
            .unwrap_err()
            .contains("parallel to a side"));
    }
}
