//! In-plane isotropic growth at fixed thickness (`growth.law = "isotropic_in_plane"`): every
//! layer of the shell grows in its own plane by `e^s`, and the thickness is kept:
//!
//! `ḡ(z) = e^{2s}(a⁰ + 2z b⁰)`, so `ā = e^{2s} a⁰`, `b̄ = e^{2s} b⁰`, `h̄ = h`
//!
//! (derivation in [`super`]). It keeps the reference curvature `ā⁻¹b̄`, but not the ratio of
//! thickness to radius, so a curved shell grown this way is frustrated: a 60° cap grown by
//! s = ln 0.9 keeps energy that grows with h/R. Units: ā in m², b̄ in m, s dimensionless.

use super::{FaceInput, Grown, GrowthError, LawEntry, RestLaw};
use crate::config::growth::{GrowthLaw, GrowthModel};
use crate::math::{Real, Sym2};

/// In-plane growth at fixed thickness.
#[derive(Debug)]
pub struct IsotropicInPlane;

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::IsotropicInPlane,
    example: "s = \"0.05 * x\"",
    build: |m| {
        matches!(m, GrowthModel::IsotropicInPlane)
            .then(|| Box::new(IsotropicInPlane) as Box<dyn RestLaw>)
    },
};

/// `(ā, b̄) = (e^{2s} a⁰, e^{2s} b⁰)`.
pub fn isotropic_in_plane(a0: &Sym2, b0: &Sym2, s: Real) -> (Sym2, Sym2) {
    let f = (2.0 * s).exp();
    (a0 * f, b0 * f)
}

impl RestLaw for IsotropicInPlane {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        Ok(Grown::at_fixed_thickness(isotropic_in_plane(
            &i.a0, &i.b0, i.s,
        )))
    }
    fn needs_s(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::{close, project_through_thickness};
    use super::*;
    use crate::math::sym_to_mat;

    #[test]
    fn in_plane_growth_scales_both_forms() {
        let (a0, b0) = (Sym2::new(1.0, 0.1, 0.9), Sym2::new(0.3, -0.1, 0.2));
        let (a, b) = isotropic_in_plane(&a0, &b0, 0.1);
        let f = 0.2f64.exp();
        assert!(close(&a, &(a0 * f), 1e-15) && close(&b, &(b0 * f), 1e-15));
        // The projection of e^{2s}(a⁰ + 2z b⁰) agrees.
        let (pa, pb) = project_through_thickness(0.05, |z| {
            (sym_to_mat(&a0) + sym_to_mat(&b0) * (2.0 * z)) * f
        });
        assert!(close(&pa, &a, 1e-14) && close(&pb, &b, 1e-13));
    }
}
