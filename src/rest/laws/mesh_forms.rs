//! Target forms given per face by the mesh (`rest.target = "mesh"`, MorphoShell's files): the
//! face field `abar_info` (required) and `bbar_info` (optional, zero when absent), each
//! `[xx, xy, yy]` in reference Cartesian coordinates, pulled back to the face's barycentric frame
//! (seed 000, "Pullback Forms"). A flat reference mesh in a plane z = const is required.
//!
//! Units: `ā` dimensionless in reference coordinates (m² barycentric), `b̄` in 1/m (m
//! barycentric).

use super::{TargetLaw, Targets};
use crate::math::Sym2;
use crate::mesh::{Mesh, MeshError};
use crate::rest::pulled_back_targets;
use crate::settings::Rest;

/// The law of `rest.target = "mesh"`.
pub struct MeshForms;

impl TargetLaw for MeshForms {
    fn targets(&self, mesh: &Mesh, _rest: &Rest) -> Result<Targets, MeshError> {
        let af = mesh.face_field("abar_info", 3)?.ok_or_else(|| {
            mesh.invalid(
                "rest.target = \"mesh\" needs the per-face field 'abar_info' (3 components xx, \
                 xy, yy)",
            )
        })?;
        let bf = mesh.face_field("bbar_info", 3)?;
        let (abar, bbar) = pulled_back_targets(
            mesh,
            |f| Sym2::from_column_slice(af.get(f)),
            |f| {
                bf.map(|b| Sym2::from_column_slice(b.get(f)))
                    .unwrap_or_else(Sym2::zeros)
            },
            "abar_info/bbar_info",
        )?;
        Ok(Targets {
            abar,
            bbar,
            lce: Vec::new(),
        })
    }
}
