//! Seed 000's isotropic growth as printed (§3, "Isotropic Growth";
//! `growth.law = "isotropic_metric_only"`): the metric grows, the second form does not,
//!
//! `ā = e^{2s} a⁰`, `b̄ = b⁰`, `h̄ = h`.
//!
//! On a flat sheet it equals the other isotropic laws (but for the thickness under the
//! volumetric one); on a curved shell the reference curvature `ā⁻¹b̄` falls by `e^{-2s}`.
//! Units: ā in m², b̄ in m, s dimensionless.

use super::{FaceInput, Grown, GrowthError, LawEntry, RestLaw};
use crate::config::growth::{GrowthLaw, GrowthModel};

/// Seed 000's printed law.
#[derive(Debug)]
pub struct IsotropicMetricOnly;

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::IsotropicMetricOnly,
    example: "s = \"0.05 * x\"",
    build: |m| {
        matches!(m, GrowthModel::IsotropicMetricOnly)
            .then(|| Box::new(IsotropicMetricOnly) as Box<dyn RestLaw>)
    },
};

impl RestLaw for IsotropicMetricOnly {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        Ok(Grown::at_fixed_thickness((i.a0 * (2.0 * i.s).exp(), i.b0)))
    }
    fn needs_s(&self) -> bool {
        true
    }
}
