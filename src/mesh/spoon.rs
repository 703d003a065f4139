//! A plastic spoon (`shellsim mesh spoon`): an elliptical bowl joined to a tapering handle with a
//! rounded end, both curved, the proportions of a disposable polypropylene spoon scaled to a
//! total length `L` (`--size`), meshed by the Delaunay triangulation of points about `edge`
//! apart ([`super::planform`]). Faces carry `tri_tags` 1 (bowl) and 2 (handle).
//!
//! ## Shape (lengths in units of L; a 160 mm spoon)
//! * Planform along x ∈ [0, L], symmetric in y, of half-width `w(x) = max(w_bowl, w_handle)`:
//!   the bowl an ellipse of length 0.28 and width 0.19 centred at x = 0.14; the handle from
//!   x = 0.22 (inside the bowl) to L, widening linearly from 0.06 to 0.085 and rounded by a
//!   half-ellipse over its last 0.0425.
//! * Height: inside the bowl's ellipse (ρ² = ((x − 0.14)/0.14)² + (y/0.095)² < 1) the bowl dips
//!   by `z = −0.044 (1 − ρ²)²` (7 mm deep, level with the rim and tangent to it there); the handle
//!   beyond the bowl's end rises as `z = 0.05 ((x − 0.28)/0.72)²`, tangent to the rim's plane.
//!   The normals point up (+z), into the bowl's hollow.
//!
//! The machine (flow) direction of an injection-moulded spoon runs along the handle, +x: give
//! `growth.machine_direction = [1, 0, 0]` for an anisotropic shrink.

use super::generate::Spacing;
use super::{Field, Mesh};
use crate::math::{Real, Vec3};

/// Bowl length, width, centre and depth, handle start, widths, end rounding and rise, all over
/// the total length.
const BOWL_L: Real = 0.28;
const BOWL_W: Real = 0.19;
const BOWL_C: Real = 0.14;
const DEPTH: Real = 0.044;
const HANDLE_X: Real = 0.22;
const NECK: Real = 0.06;
const END: Real = 0.085;
const RISE: Real = 0.05;

/// The half-width of the planform at `x` (units of L), 0 outside [0, 1].
fn half_width(x: Real) -> Real {
    let bowl = {
        let u = (x - BOWL_C) / (0.5 * BOWL_L);
        if u.abs() < 1.0 {
            0.5 * BOWL_W * (1.0 - u * u).sqrt()
        } else {
            0.0
        }
    };
    let handle = if (HANDLE_X..=1.0).contains(&x) {
        let w = 0.5 * (NECK + (END - NECK) * (x - HANDLE_X) / (1.0 - HANDLE_X));
        let r = 0.5 * END;
        if x > 1.0 - r {
            let u = (x - (1.0 - r)) / r;
            w * (1.0 - u * u).max(0.0).sqrt()
        } else {
            w
        }
    } else {
        0.0
    };
    bowl.max(handle)
}

/// The height of the planform point `(x, y)` (units of L).
fn height(x: Real, y: Real) -> Real {
    let rho2 = ((x - BOWL_C) / (0.5 * BOWL_L)).powi(2) + (y / (0.5 * BOWL_W)).powi(2);
    if rho2 < 1.0 {
        -DEPTH * (1.0 - rho2).powi(2)
    } else if x > BOWL_L {
        RISE * ((x - BOWL_L) / (1.0 - BOWL_L)).powi(2)
    } else {
        0.0
    }
}

/// The planform's area over L² (for planning the mesh's size).
pub fn area() -> Real {
    super::planform::area(half_width)
}

/// The number of faces a spoon of length `length` with edges `edge` will have, about (for
/// [`super::generate::check_planned`]).
pub fn planned_faces(length: Real, edge: Real) -> Real {
    super::planform::planned_faces(area(), length, edge)
}

/// A spoon of total length `length` (m) with edges about `edge` (m); see the module doc.
pub fn spoon(length: Real, edge: Real, sp: Spacing) -> Mesh {
    let mut mesh = super::planform::mesh(half_width, 0.5 * BOWL_W.max(END), length, edge, sp);
    let mut tags = Vec::with_capacity(mesh.faces.len());
    for f in &mesh.faces {
        let c = f.iter().map(|&v| mesh.positions[v]).sum::<Vec3>() / 3.0;
        let rho2 = ((c.x / length - BOWL_C) / (0.5 * BOWL_L)).powi(2)
            + (c.y / length / (0.5 * BOWL_W)).powi(2);
        tags.push(if rho2 < 1.0 { 1.0 } else { 2.0 });
    }
    for p in &mut mesh.positions {
        p.z = height(p.x / length, p.y / length) * length;
    }
    mesh.face_fields
        .insert("tri_tags".into(), Field::scalar(tags));
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The planform closes at both tips and is continuous where the handle leaves the bowl;
    /// the bowl's rim and the handle's start are level, so the surface is continuous.
    #[test]
    fn the_outline_and_the_height_are_continuous() {
        assert_eq!(half_width(0.0), 0.0);
        // The rounding of (1 − u²) under the square root leaves at most ~1e-8.
        assert!(half_width(1.0) < 1e-6);
        assert!((half_width(0.5) - 0.5 * (NECK + (END - NECK) * 0.28 / 0.78)).abs() < 1e-12);
        for x in [0.05, 0.14, 0.2, 0.26, 0.3] {
            let y = half_width(x);
            let (a, b) = (height(x, y - 1e-9), height(x, y + 1e-9));
            assert!((a - b).abs() < 1e-6, "x {x}: {a} {b}");
        }
        assert!((height(BOWL_C, 0.0) + DEPTH).abs() < 1e-15);
        assert!(height(1.0, 0.0) > 0.04);
    }

    /// A 16 cm spoon with 5 mm edges is a valid oriented surface with tags on both parts, and
    /// the planned size is not below the real one.
    #[test]
    fn a_spoon_mesh_is_valid_and_tagged() {
        let m = spoon(0.16, 0.005, Spacing::default());
        m.validate().unwrap();
        super::super::Topology::build(&m).unwrap();
        let tags = &m.face_fields["tri_tags"].data;
        assert!(tags.contains(&1.0) && tags.contains(&2.0));
        assert!((m.faces.len() as Real) < planned_faces(0.16, 0.005));
        // Upward normals.
        let up = m
            .faces
            .iter()
            .filter(|f| {
                let p = f.map(|v| m.positions[v]);
                (p[1] - p[0]).cross(&(p[2] - p[0])).z > 0.0
            })
            .count();
        assert_eq!(up, m.faces.len());
        // Its area is the planform's within the bowl's added slope (a few percent).
        let a: Real = (0..m.faces.len()).map(|f| m.face_area(f)).sum();
        let plan = area() * 0.16 * 0.16;
        assert!(a > plan * 0.97 && a < plan * 1.1, "{a} against {plan}");
    }
}
