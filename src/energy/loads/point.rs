//! Dead point forces (`[[loads.point]]`): each load's total force is shared equally among its
//! selected vertices, `f_v = F / n` (N), scaled by the dial; see [`super::NodalForces`].

use super::{nodal_term, select_vertices};
use crate::body::Body;
use crate::energy::term::Term;
use crate::math::Vec3;
use crate::mesh::MeshError;

/// The point-load term of a scene (`None` without point loads).
pub fn term(
    body: &Body,
    loads: &[crate::config::loads::PointLoad],
) -> Result<Option<Box<dyn Term>>, MeshError> {
    if loads.is_empty() {
        return Ok(None);
    }
    let mut force = vec![Vec3::zeros(); body.num_vertices()];
    for (i, l) in loads.iter().enumerate() {
        let vs = select_vertices(&body.mesh, &l.on, &format!("loads.point[{i}]"))?;
        let f = Vec3::from(l.force) / vs.len() as f64;
        for v in vs {
            force[v] += f;
        }
    }
    Ok(Some(nodal_term(
        "point_load",
        "point_load_displacement",
        force,
    )))
}
