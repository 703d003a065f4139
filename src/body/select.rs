//! The vertices and faces a settings selection picks on the reference mesh (tags and boxes).

use crate::mesh::{Mesh, MeshError};
use crate::settings::Selection;

/// The vertices a selection picks (`node_tags` and/or a box on reference positions); an error
/// naming `what` when it needs a missing field or picks nothing.
pub fn select_vertices(mesh: &Mesh, sel: &Selection, what: &str) -> Result<Vec<usize>, MeshError> {
    if sel.tags.is_empty() && sel.inside.is_none() {
        return Err(mesh.invalid(format!(
            "{what}: give tags or a box ('inside') to select vertices"
        )));
    }
    let tags = if sel.tags.is_empty() {
        None
    } else {
        Some(mesh.vertex_field("node_tags", 1)?.ok_or_else(|| {
            mesh.invalid(format!(
                "{what} selects vertices by tags, which needs the vertex field 'node_tags'"
            ))
        })?)
    };
    let picked: Vec<usize> = (0..mesh.positions.len())
        .filter(|&v| tags.is_none_or(|t| sel.tags.contains(&(t.data[v].round() as i64))))
        .filter(|&v| {
            let p = mesh.positions[v];
            sel.inside
                .as_ref()
                .is_none_or(|b| (0..3).all(|k| p[k] >= b.min[k] && p[k] <= b.max[k]))
        })
        .collect();
    if picked.is_empty() {
        return Err(mesh.invalid(format!(
            "{what} selects no vertex (tags {:?}, box {:?})",
            sel.tags, sel.inside
        )));
    }
    Ok(picked)
}

/// The faces a selection picks (`tri_tags` and/or a box on reference centroids; every face when
/// neither is given); an error naming `what` when it picks nothing.
pub fn select_faces(mesh: &Mesh, sel: &Selection, what: &str) -> Result<Vec<usize>, MeshError> {
    let picked = faces_matching(mesh, &sel.tags, sel.inside.as_ref(), what)?;
    if picked.is_empty() {
        return Err(mesh.invalid(format!(
            "{what} selects no face (tags {:?}, box {:?})",
            sel.tags, sel.inside
        )));
    }
    Ok(picked)
}

/// The faces whose `tri_tags` value is in `tags` (any, when empty) and whose reference centroid
/// lies in `inside` (when given): [`Mesh::faces_matching`].
pub fn faces_matching(
    mesh: &Mesh,
    tags: &[i64],
    inside: Option<&crate::settings::FixBox>,
    what: &str,
) -> Result<Vec<usize>, MeshError> {
    mesh.faces_matching(tags, inside.map(|b| (b.min, b.max)), what)
}
