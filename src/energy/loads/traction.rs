//! Dead tractions per unit reference length on boundary edges (`[[loads.traction]]`): a
//! boundary edge whose two vertices are both selected carries `t ℓ₀` (N), half to each end
//! (the consistent load of a constant traction on a linear edge), scaled by the dial; see
//! [`super::NodalForces`].

use super::{nodal_term, select_vertices};
use crate::body::Body;
use crate::energy::term::Term;
use crate::math::Vec3;
use crate::mesh::MeshError;

/// The traction term of a scene (`None` without tractions).
pub fn term(
    body: &Body,
    loads: &[crate::config::loads::TractionLoad],
) -> Result<Option<Box<dyn Term>>, MeshError> {
    if loads.is_empty() {
        return Ok(None);
    }
    let mesh = &body.mesh;
    let mut force = vec![Vec3::zeros(); body.num_vertices()];
    for (i, l) in loads.iter().enumerate() {
        let what = format!("loads.traction[{i}]");
        let mut on = vec![false; body.num_vertices()];
        for v in select_vertices(mesh, &l.on, &what)? {
            on[v] = true;
        }
        let t = Vec3::from(l.traction);
        let mut edges = 0;
        for (e, ends) in body.topo.edges.iter().enumerate() {
            let boundary = body.topo.edge_faces[e][1] == crate::mesh::topology::NONE;
            if boundary && on[ends[0]] && on[ends[1]] {
                let len = (mesh.positions[ends[0]] - mesh.positions[ends[1]]).norm();
                force[ends[0]] += t * (0.5 * len);
                force[ends[1]] += t * (0.5 * len);
                edges += 1;
            }
        }
        if edges == 0 {
            return Err(mesh.invalid(format!(
                "{what} selects no boundary edge (both ends of a boundary edge must be selected)"
            )));
        }
    }
    Ok(Some(nodal_term("traction", "traction_displacement", force)))
}
