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
}
