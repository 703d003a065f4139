//! The St Venant–Kirchhoff (Koiter) membrane of seed 000 §3, the default material:
//! `W = √det ā/2 · h/4 · f · ‖ā⁻¹a − I‖²_SV` with the plane-stress Lamé parameters (`f` = 1, or 4
//! under MorphoShell's stretching convention); see [`crate::energy::material::KoiterDensity`].

use super::Membrane;
use crate::energy::material::KoiterDensity;
use crate::energy::Potential;

/// The Koiter membrane.
#[derive(Clone, Copy, Debug, Default)]
pub struct Koiter;

impl Membrane for Koiter {
    type Density = KoiterDensity;
    #[inline(always)]
    fn density(&self, pot: &Potential, f: usize) -> KoiterDensity {
        pot.density(f)
    }

    fn rest_face(
        &self,
        pot: &Potential,
        f: usize,
    ) -> Result<crate::energy::sensitivity::KoiterFace, String> {
        let body = pot.body;
        if body.bend_stiffening.is_some() {
            return Err(
                "bend stiffening (material.bend_stiffening) has no rest sensitivities".into(),
            );
        }
        if pot.damping.is_some() || pot.frozen.is_some() {
            return Err("rest sensitivities are taken at a static equilibrium".into());
        }
        let (abar, bbar) = pot.rest_forms(f);
        Ok(crate::energy::sensitivity::KoiterFace {
            abar,
            bbar,
            h: pot.thickness(f),
            lame: pot.lame(f),
            stretch: body.stretch_factor * pot.stretch_scale,
            bending: body.has_bending,
        })
    }
}
