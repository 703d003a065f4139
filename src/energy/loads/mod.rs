//! External loads, one file each: dead point forces ([`point`]), dead tractions per unit length
//! on boundary edges ([`traction`]), follower pressure on faces ([`pressure`]) and distributed
//! moments along boundaries ([`moment`]). Every load is
//! scaled by the potential's dial, the load factor that the static driver dials adaptively
//! (like the rest forms) and the dynamic driver ramps over `rest.dial_time`.

pub mod moment;
pub mod point;
pub mod pressure;
pub mod traction;

use super::term::{Term, VertexKernel, VertexTerm};
use crate::math::{Mat3, Real, Vec3};
use crate::mesh::{Mesh, MeshError};
use crate::settings::Selection;
use crate::solve::Potential;

/// Dead nodal forces `f_v` (N) at dial 1: `E = −s Σ_v f_v·x_v` at dial `s` (J); gradient
/// `−s f_v`, no Hessian. DOF order: `x[v]`.
pub struct NodalForces {
    /// Force per vertex (N).
    pub force: Vec<Vec3>,
    /// Column name of the conjugate displacement in `log.csv`.
    pub label: &'static str,
}

impl VertexKernel for NodalForces {
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let f = self.force[v] * pot.dial;
        if f == Vec3::zeros() {
            return None;
        }
        Some((-f.dot(x), -f, Mat3::zeros()))
    }

    /// The displacement conjugate to the load, `Σ_v f_v·(x_v − X_v) / |Σ_v f_v|` (m; the
    /// plain work `Σ f·u` in N·m when the forces sum to zero), for load–displacement curves.
    fn observables(&self, pot: &Potential, x: &[Vec3]) -> Vec<(String, Real)> {
        let x0 = &pot.scene.mesh.positions;
        let work: Real = self
            .force
            .iter()
            .zip(x.iter().zip(x0))
            .map(|(f, (p, q))| f.dot(&(p - q)))
            .sum();
        let total = self.force.iter().sum::<Vec3>().norm();
        let d = if total > 0.0 { work / total } else { work };
        vec![(self.label.to_string(), d)]
    }
}

/// Nodal forces as a reported term.
pub fn nodal_term(name: &'static str, label: &'static str, force: Vec<Vec3>) -> Box<dyn Term> {
    Box::new(VertexTerm {
        name,
        kernel: NodalForces { force, label },
        report: true,
    })
}

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
/// lies in `inside` (when given); possibly none. Needing `tri_tags` on a mesh without it is an
/// error naming `what`.
pub fn faces_matching(
    mesh: &Mesh,
    tags: &[i64],
    inside: Option<&crate::settings::FixBox>,
    what: &str,
) -> Result<Vec<usize>, MeshError> {
    let wanted = tags;
    let tags = if wanted.is_empty() {
        None
    } else {
        Some(mesh.face_field("tri_tags", 1)?.ok_or_else(|| {
            mesh.invalid(format!(
                "{what} selects faces by tags, which needs the face field 'tri_tags'"
            ))
        })?)
    };
    let picked: Vec<usize> = (0..mesh.faces.len())
        .filter(|&f| tags.is_none_or(|t| wanted.contains(&(t.data[f].round() as i64))))
        .filter(|&f| {
            let [p0, p1, p2] = mesh.face_positions(f);
            let c = (p0 + p1 + p2) / 3.0;
            inside.is_none_or(|b| (0..3).all(|k| c[k] >= b.min[k] && c[k] <= b.max[k]))
        })
        .collect();
    Ok(picked)
}
