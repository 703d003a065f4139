//! Symmetry breaking (see the module doc of [`super`]): the vertex normals, the planarity
//! test, and the deterministic perturbation of a planar start.

use crate::math::{Real, Vec3};
use crate::mesh::generate::Rng;
use crate::model::Scene;

/// Area-weighted vertex normals.
pub fn vertex_normals(scene: &Scene, x: &[Vec3]) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); x.len()];
    for f in &scene.body.mesh.faces {
        let c = (x[f[1]] - x[f[0]]).cross(&(x[f[2]] - x[f[0]]));
        for &v in f {
            n[v] += c;
        }
    }
    for v in &mut n {
        let l = v.norm();
        if l > 0.0 {
            *v /= l;
        }
    }
    n
}

/// True when all face normals are parallel (the sheet is planar).
pub fn is_planar(scene: &Scene, x: &[Vec3]) -> bool {
    let mut n0: Option<Vec3> = None;
    for f in &scene.body.mesh.faces {
        let c = (x[f[1]] - x[f[0]]).cross(&(x[f[2]] - x[f[0]])).normalize();
        match n0 {
            None => n0 = Some(c),
            Some(n) => {
                if n.dot(&c) < 1.0 - 1e-12 {
                    return false;
                }
            }
        }
    }
    true
}

/// Moves free vertices along their normals by `amp × u`, u uniform in [−1, 1) (seeded); the
/// components a support holds ([`crate::body::Body::held_dofs`]) stay, and so do the held
/// directions of a skew vertex ([`crate::body::Body::skew`]).
pub fn perturb(scene: &Scene, x: &mut [Vec3], amp: Real, seed: u64) {
    let normals = vertex_normals(scene, x);
    let mut free = vec![[true; 3]; x.len()];
    for &d in &scene.body.held_dofs {
        free[d / 3][d % 3] = false;
    }
    let mut rng = Rng::new(seed);
    for (v, p) in x.iter_mut().enumerate() {
        let u = rng.symmetric();
        if !scene.body.fixed[v] {
            let step = match scene.body.skew_projector(v) {
                Some(proj) => proj * normals[v],
                None => normals[v],
            };
            for k in 0..3 {
                if free[v][k] {
                    p[k] += step[k] * (amp * u);
                }
            }
        }
    }
}
