//! Closed surfaces: the volume a closed triangle mesh encloses, its gradient, and the check that
//! a mesh can enclose a gas (a closed, consistently oriented 2-manifold with outward normals).
//!
//! The volume is the divergence theorem applied to `x/3` over the polyhedron,
//!
//! `V = (1/6) Σ_f x₀ · (x₁ × x₂)`,
//!
//! exact for the polyhedron (not an approximation of a smooth surface), and independent of the
//! origin when the surface is closed (each translation term is the flux of a constant field).
//! Its gradient with respect to vertex `x₀` of a face is `(1/6) x₁ × x₂` (cyclically for the
//! other two); summed over faces it is the area-weighted vertex normal `(1/3) Σ A n̂`.
//! Units: m³ and m².

use super::{Mesh, MeshError, Topology};
use crate::math::{Real, Vec3};

/// Enclosed volume `V = (1/6) Σ_f x₀ · (x₁ × x₂)` (m³) of the closed surface `faces` at
/// `positions`; positive when the faces are counter-clockwise seen from outside.
pub fn enclosed_volume(positions: &[Vec3], faces: &[[usize; 3]]) -> Real {
    faces
        .iter()
        .map(|f| positions[f[0]].dot(&positions[f[1]].cross(&positions[f[2]])))
        .sum::<Real>()
        / 6.0
}

/// Adds `∂V/∂x` to `grad` (one entry per vertex, m²): `(1/6) x₁ × x₂` for vertex 0 of each
/// face, cyclically for vertices 1 and 2.
pub fn add_enclosed_volume_gradient(positions: &[Vec3], faces: &[[usize; 3]], grad: &mut [Vec3]) {
    for f in faces {
        let [a, b, c] = f.map(|v| positions[v]);
        grad[f[0]] += b.cross(&c) / 6.0;
        grad[f[1]] += c.cross(&a) / 6.0;
        grad[f[2]] += a.cross(&b) / 6.0;
    }
}

/// Checks that `mesh` (already validated, with its topology `topo`) can enclose a gas: no
/// boundary edge (every edge has two faces; the topology already refuses non-manifold edges and
/// inconsistent orientation) and a positive enclosed volume, i.e. outward normals. The errors
/// name the first open edge, or the fix for an inward mesh.
pub fn check_closed_outward(mesh: &Mesh, topo: &Topology) -> Result<Real, MeshError> {
    let open = topo
        .edge_faces
        .iter()
        .filter(|ef| ef[1] == super::topology::NONE)
        .count();
    if let Some(e) = topo
        .edge_faces
        .iter()
        .position(|ef| ef[1] == super::topology::NONE)
    {
        return Err(mesh.invalid(format!(
            "an enclosed gas needs a closed surface, but {open} edges have only one face (first: \
             edge {:?} of face {})",
            topo.edges[e], topo.edge_faces[e][0]
        )));
    }
    let v = enclosed_volume(&mesh.positions, &mesh.faces);
    if v.is_nan() || v <= 0.0 {
        return Err(mesh.invalid(format!(
            "the surface's normals point inward (enclosed volume {} m³ is not positive): \
             reverse the vertex order of every face (e.g. in ParaView: Filters > Reverse Sense, \
             or swap two indices of each triangle)",
            crate::math::human(v)
        )));
    }
    Ok(v)
}
