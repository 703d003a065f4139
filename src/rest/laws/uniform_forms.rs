//! Target forms from the settings (`rest.target = "uniform"`): `rest.abar` and `rest.bbar`, each
//! `[xx, xy, yy]` in reference Cartesian coordinates, numbers or expressions of x, y, sampled on
//! each face's edges ([`crate::rest::sample_on_edges`]) and pulled back to its barycentric frame
//! (seed 000, "Pullback Forms"). A flat reference mesh in a plane z = const is required.
//!
//! Units: `ā` dimensionless in reference coordinates (m² barycentric), `b̄` in 1/m (m
//! barycentric).

use super::{TargetLaw, Targets};
use crate::math::{Real, Sym2};
use crate::mesh::{Mesh, MeshError};
use crate::rest::pulled_back_targets;
use crate::settings::Rest;

/// The law of `rest.target = "uniform"`.
pub struct UniformForms;

impl TargetLaw for UniformForms {
    fn targets(&self, mesh: &Mesh, rest: &Rest) -> Result<Targets, MeshError> {
        let a = settings_form(mesh, &rest.abar, "rest.abar")?;
        let b = settings_form(mesh, &rest.bbar, "rest.bbar")?;
        let (abar, bbar) =
            pulled_back_targets(mesh, |f| a[f], |f| b[f], "rest.target = \"uniform\"")?;
        Ok(Targets {
            abar,
            bbar,
            lce: Vec::new(),
        })
    }
}

/// A symmetric 2×2 form `[xx, xy, yy]` of settings fields (numbers or expressions of x, y) at
/// every face, in reference Cartesian coordinates, sampled on the edges as
/// [`crate::rest::sample_on_edges`] does; a non-finite value is an error naming the face.
fn settings_form(
    mesh: &Mesh,
    form: &[crate::settings::Field; 3],
    key: &str,
) -> Result<Vec<Sym2>, MeshError> {
    let e = form
        .iter()
        .enumerate()
        .map(|(i, c)| {
            c.compile()
                .map_err(|e| mesh.invalid(format!("{key}[{i}]: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    (0..mesh.faces.len())
        .map(|f| {
            let at =
                |x: Real, y: Real| Sym2::new(e[0].eval(x, y), e[1].eval(x, y), e[2].eval(x, y));
            let m = crate::rest::sample_on_edges(mesh, f, at);
            if m.iter().all(|v| v.is_finite()) {
                Ok(crate::rest::push_forward(
                    &crate::rest::reference_frame(mesh, f),
                    &m,
                ))
            } else {
                Err(mesh.invalid(format!("{key} is not finite on an edge of face {f}")))
            }
        })
        .collect()
}
