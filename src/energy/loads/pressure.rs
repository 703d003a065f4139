//! Follower pressure on faces (`[[loads.pressure]]`), as the conservative potential of the
//! volume it sweeps:
//!
//! `E = −s p V(x)`, `V = Σ_f (1/6) x₀·(x₁ × x₂)` over the loaded faces (signed volume of the
//! cones to the origin), `s` the dial.
//!
//! `∂V/∂x₀ = (x₁ × x₂)/6` (cyclically), i.e. the vertex force `s p (x₁ × x₂)/6`; summed over the
//! faces around an interior vertex this is exactly `s p Σ A_f n_f / 3`, the follower load along
//! the normals. `∇²V` has zero diagonal blocks and `∂²V/∂x₀∂x₁ = −[x₂]×/6` (cyclically), so the
//! Hessian is exact and symmetric. On a closed surface V is the enclosed volume; on an open one
//! the origin enters only through the boundary vertices, which must therefore be held (fixed or
//! clamped), and the registry refuses an open loaded region with a free boundary vertex. The
//! per-face Hessian depends on the origin, so it is never projected face by face.
//!
//! Units: p in Pa, E in J, gradient N, Hessian N/m. DOF order (9): `x[v0], x[v1], x[v2]`.

use super::select_faces;
use crate::body::Body;
use crate::energy::term::{ElementKernel, ElementTerm, Stencil, Term};
use crate::energy::Potential;
use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::MeshError;

/// The pressure kernel: pressure per face (Pa, 0 where unloaded).
pub struct Pressure {
    /// The loaded faces and their pressures.
    pub faces: Vec<(usize, Real)>,
}

impl ElementKernel<9, 3> for Pressure {
    /// The per-face split of `∇²V` depends on the origin: never projected face by face.
    const PROJECTABLE: bool = false;
    const LOAD: bool = true;

    #[inline]
    fn eval(
        &self,
        pot: &Potential,
        e: usize,
        nodes: &[usize],
        x: &[Vec3],
        _: &[Real],
        _: bool,
        grad: Option<&mut SVec<9>>,
        hess: Option<&mut SMat<9, 9>>,
    ) -> Real {
        let xs = [x[nodes[0]], x[nodes[1]], x[nodes[2]]];
        crate::geometry::cone_volume(&xs, -pot.dial * self.faces[e].1, grad, hess)
    }
}

fn stencil(body: &Body, k: &Pressure) -> Stencil {
    Stencil::faces(&body.mesh, k.faces.iter().map(|&(f, _)| f))
}

/// The pressure term of a scene (`None` without pressure loads). A loaded region whose
/// boundary has a free vertex is refused (module doc); the mesh's orientation is consistent by
/// the time a scene exists ([`crate::mesh::Topology::build`] refuses an inconsistent one).
pub fn term(
    body: &Body,
    loads: &[crate::config::loads::PressureLoad],
) -> Result<Option<Box<dyn Term>>, MeshError> {
    if loads.is_empty() {
        return Ok(None);
    }
    let mesh = &body.mesh;
    let mut p = vec![0.0; body.num_faces()];
    for (i, l) in loads.iter().enumerate() {
        for f in select_faces(mesh, &l.on, &format!("loads.pressure[{i}]"))? {
            p[f] += l.pressure;
        }
    }
    // Boundary of the loaded region: edges with exactly one loaded face.
    let loaded = |f: usize| f != crate::mesh::topology::NONE && p[f] != 0.0;
    for (e, ef) in body.topo.edge_faces.iter().enumerate() {
        if loaded(ef[0]) != loaded(ef[1]) {
            for &v in &body.topo.edges[e] {
                if !body.fixed[v] {
                    return Err(mesh.invalid(format!(
                        "loads.pressure: vertex {v} on the boundary of the loaded faces is free; a \
                         pressure on an open surface needs its boundary held (fix or clamp it), or \
                         load a closed surface"
                    )));
                }
            }
        }
    }
    let faces = p
        .iter()
        .enumerate()
        .filter(|(_, &v)| v != 0.0)
        .map(|(f, &v)| (f, v))
        .collect();
    Ok(Some(Box::new(ElementTerm {
        name: "pressure",
        kernel: Pressure { faces },
        stencil,
    })))
}
