//! Uniform volumetric growth (`growth.law = "isotropic"`, the default isotropic law): every
//! length of the shell grows by `e^s`, its thickness included, so the grown rest state is a
//! scaled copy of the reference shell:
//!
//! `ā = e^{2s} a⁰`, `b̄ = e^s b⁰`, `h̄ = e^s h`
//!
//! (derivation in [`super`]; `REFERENCES.md`, "Growth of a curved shell"). A curved shell grown
//! this way reaches its scaled shape with zero energy. Units: ā in m², b̄ in m, s dimensionless.

use super::{FaceInput, Grown, GrowthError, LawEntry, RestLaw};
use crate::config::growth::{GrowthLaw, GrowthModel};
use crate::math::{Real, Sym2};

/// Uniform volumetric growth.
#[derive(Debug)]
pub struct Isotropic;

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::Isotropic,
    example: "s = \"0.05 * x\"",
    build: |m| matches!(m, GrowthModel::Isotropic).then(|| Box::new(Isotropic) as Box<dyn RestLaw>),
};

/// `(ā, b̄, h̄/h) = (e^{2s} a⁰, e^s b⁰, e^s)`.
pub fn isotropic(a0: &Sym2, b0: &Sym2, s: Real) -> (Sym2, Sym2, Real) {
    let f = s.exp();
    (a0 * (f * f), b0 * f, f)
}

impl RestLaw for Isotropic {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let (abar, bbar, thickness_ratio) = isotropic(&i.a0, &i.b0, i.s);
        Ok(Grown {
            abar,
            bbar,
            thickness_ratio,
        })
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

    /// The grown shell's metric at grown height `z' = e^s z` is the reference one at `z` scaled
    /// by `e^{2s}`; its projection over the grown thickness is the law.
    #[test]
    fn volumetric_growth_is_a_scaled_copy() {
        let (a0, b0, h) = (Sym2::new(1.0, 0.1, 0.9), Sym2::new(0.3, -0.1, 0.2), 0.05);
        let s: Real = -0.2;
        let (a, b, r) = isotropic(&a0, &b0, s);
        let f = s.exp();
        let (pa, pb) = project_through_thickness(h * f, |zg| {
            (sym_to_mat(&a0) + sym_to_mat(&b0) * (2.0 * zg / f)) * (f * f)
        });
        assert!(
            close(&pa, &a, 1e-14) && close(&pb, &b, 1e-13),
            "{pb:?} {b:?}"
        );
        assert_eq!(r, f);
        // The shape operator ā⁻¹b̄ scales by e^{-s}: curvature radii grow by e^s.
        let k0 = sym_to_mat(&a0).try_inverse().unwrap() * sym_to_mat(&b0);
        let k = sym_to_mat(&a).try_inverse().unwrap() * sym_to_mat(&b);
        assert!((k * f - k0).amax() < 1e-14);
    }
}
