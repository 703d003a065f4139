//! A flat leaf with veins (`shellsim mesh leaf`): an ovate blade of length `L` (`--size`) from its
//! base at x = 0 to its tip at x = L, a midrib along it and six pairs of secondary veins, meshed
//! by the Delaunay triangulation of points about `edge` apart ([`super::planform`]). Faces carry
//! `tri_tags` 1 (blade), 2 (midrib) and 3 (secondary veins); with a thickness H
//! (`--thickness`) also `ref_thicknesses`: H on the blade, 2H on the secondary veins and 3H on
//! the midrib (8× and 27× the blade's bending stiffness).
//!
//! ## Shape (lengths in units of L)
//! * Blade half-width `w(x) = 0.25 sin(πx)^0.9 (1 − 0.35x)`: pointed at base and tip, widest
//!   (0.42 L across) at x ≈ 0.44.
//! * Midrib: the faces within `0.012 (1 − 0.6x)` of y = 0 (it tapers toward the tip).
//! * Secondary veins: from the midrib at x = 0.12, 0.26, …, 0.82, straight toward the margin at
//!   50° to the midrib on both sides, the faces within 0.005 of them.
//!
//! A vein is the set of faces whose centroid lies on it, so its edge is as ragged as the mesh;
//! resolve it with edges at most about its width (0.01 L for the secondary veins).

use super::generate::Spacing;
use super::{Field, Mesh};
use crate::math::{Real, Vec3};

/// Blade width factor, the midrib's half-width at the base, the secondary veins' half-width,
/// their angle to the midrib (rad) and where they leave it.
const WIDTH: Real = 0.25;
const MIDRIB: Real = 0.012;
const VEIN: Real = 0.005;
const ANGLE: Real = 50.0 * std::f64::consts::PI / 180.0;
const VEINS_AT: [Real; 6] = [0.12, 0.26, 0.40, 0.54, 0.68, 0.82];

/// The blade's half-width at `x` (units of L), 0 outside [0, 1].
fn half_width(x: Real) -> Real {
    if !(0.0..=1.0).contains(&x) {
        return 0.0;
    }
    WIDTH * (std::f64::consts::PI * x).sin().max(0.0).powf(0.9) * (1.0 - 0.35 * x)
}

/// The tag of the planform point `(x, y)` (units of L): 2 on the midrib, 3 on a secondary vein,
/// 1 elsewhere.
fn tag(x: Real, y: Real) -> Real {
    if y.abs() <= MIDRIB * (1.0 - 0.6 * x) {
        return 2.0;
    }
    let (c, s) = (ANGLE.cos(), ANGLE.sin());
    for x0 in VEINS_AT {
        // Distance from the ray (x0, 0) + t (cos, ±sin), t ≥ 0, on the point's side.
        let (dx, dy) = (x - x0, y.abs());
        let t = dx * c + dy * s;
        if t >= 0.0 && (dx * s - dy * c).abs() <= VEIN {
            return 3.0;
        }
    }
    1.0
}

/// The blade's area over L² (for planning the mesh's size).
pub fn area() -> Real {
    super::planform::area(half_width)
}

/// The number of faces a leaf of length `length` with edges `edge` will have, about.
pub fn planned_faces(length: Real, edge: Real) -> Real {
    super::planform::planned_faces(area(), length, edge)
}

/// A leaf of length `length` (m) with edges about `edge` (m) and, when given, the blade's
/// thickness (m); see the module doc.
pub fn leaf(length: Real, edge: Real, thickness: Option<Real>, sp: Spacing) -> Mesh {
    let mut mesh = super::planform::mesh(half_width, WIDTH, length, edge, sp);
    let tags: Vec<Real> = mesh
        .faces
        .iter()
        .map(|f| {
            let c = f.iter().map(|&v| mesh.positions[v]).sum::<Vec3>() / 3.0;
            tag(c.x / length, c.y / length)
        })
        .collect();
    if let Some(h) = thickness {
        let t = tags
            .iter()
            .map(|&g| match g as i64 {
                2 => 3.0 * h,
                3 => 2.0 * h,
                _ => h,
            })
            .collect();
        mesh.face_fields
            .insert("ref_thicknesses".into(), Field::scalar(t));
    }
    mesh.face_fields
        .insert("tri_tags".into(), Field::scalar(tags));
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_veins_are_where_the_doc_says() {
        assert_eq!(tag(0.5, 0.0), 2.0);
        assert_eq!(tag(0.5, 0.009), 1.0);
        // On the vein from x = 0.40 at 50°, 0.1 along it, on either side.
        let (x, y) = (0.40 + 0.1 * ANGLE.cos(), 0.1 * ANGLE.sin());
        assert_eq!(tag(x, y), 3.0);
        assert_eq!(tag(x, -y), 3.0);
        assert_eq!(tag(x + 0.02, y), 1.0);
        // Not behind the midrib: the ray starts at the midrib.
        assert_eq!(tag(0.40 - 0.05, 0.02), 1.0);
        assert!(half_width(0.0) == 0.0 && half_width(1.0) < 1e-12);
    }

    /// An 8 cm leaf with 2 mm edges is a valid surface with all three tags, thicker veins,
    /// and the blade's area.
    #[test]
    fn a_leaf_mesh_is_valid_and_tagged() {
        let m = leaf(0.08, 0.002, Some(2e-4), Spacing::default());
        m.validate().unwrap();
        super::super::Topology::build(&m).unwrap();
        let tags = &m.face_fields["tri_tags"].data;
        for t in [1.0, 2.0, 3.0] {
            assert!(tags.contains(&t), "no tag {t}");
        }
        let h = &m.face_fields["ref_thicknesses"].data;
        for (g, t) in tags.iter().zip(h) {
            assert_eq!(*t, 2e-4 * [1.0, 3.0, 2.0][*g as usize - 1]);
        }
        let a: Real = (0..m.faces.len()).map(|f| m.face_area(f)).sum();
        let plan = area() * 0.08 * 0.08;
        assert!((a / plan - 1.0).abs() < 0.03, "{a} against {plan}");
        assert!((m.faces.len() as Real) < planned_faces(0.08, 0.002));
    }
}
