//! Linear differential swelling (`growth.law = "linear_swelling"`, seed 000 §3): moisture varies
//! linearly from `m⁻` (bottom, `z = −h/2`) to `m⁺` (top, `z = +h/2`), and lengths scale by
//! `1 + μ m(z)` in every in-plane direction: `ḡ = (1 + μ m(z))² (a⁰ + 2z b⁰)`. With
//! `s₀ = 1 + μ(m⁺ + m⁻)/2`, `s₁ = μ(m⁺ − m⁻)/h`, the projection of [`super`] gives
//!
//! `ā = (s₀² + s₁²h²/12) a⁰ + (s₀ s₁ h²/3) b⁰`, `b̄ = s₀ s₁ a⁰ + (s₀² + 3 s₁²h²/20) b⁰`.
//!
//! Seed 000 prints `ā = (ḡ⁺ + ḡ⁻)/2` (which weights the `z²` term by h²/4 instead of h²/12) and
//! `b̄ = (ḡ⁻ − ḡ⁺)/(2h)` (the same `s₀s₁` term, opposite sign convention); the projection is the
//! one consistent with the energy. A wetter top (`m⁺ > m⁻`, μ > 0) gives `b̄ > 0`: the sheet
//! bulges toward the wet side's normal, i.e. curls away from the water. The thickness is kept,
//! unless `growth.mu_through` grows it ([`super::through_thickness`]). Coefficient: `growth.mu`
//! (per unit moisture), per face when regions or face fields give it. Units: ā in m², b̄ in m.

use super::{
    check_stretch, moisture_at, project_through_thickness, reference_metric, through_thickness,
    FaceInput, Grown, GrowthError, LawEntry, RestLaw,
};
use crate::config::growth::{GrowthLaw, GrowthModel};
use crate::math::{Real, Sym2};

/// Linear differential swelling with each face's `mu` ([`super::Coefficients`]).
#[derive(Debug)]
pub struct LinearSwelling;

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::LinearSwelling,
    example: "mu = 0.05\nmoisture_top = 0.4\nmoisture_bottom = 0.1",
    build: |m| {
        matches!(m, GrowthModel::LinearSwelling { .. })
            .then(|| Box::new(LinearSwelling) as Box<dyn RestLaw>)
    },
};

/// Linear differential swelling with moisture `m_top` at `z = +h/2`, `m_bottom` at `z = −h/2`
/// and moisture-length coefficient `mu`.
pub fn linear_swelling(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    m_top: Real,
    m_bottom: Real,
    mu: Real,
) -> (Sym2, Sym2) {
    project_through_thickness(h, |z| {
        let m = moisture_at(z, h, m_top, m_bottom);
        let s = 1.0 + mu * m;
        reference_metric(a0, b0, z) * (s * s)
    })
}

impl RestLaw for LinearSwelling {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let mu = i.coef.mu;
        check_stretch(i, mu, true, true)?;
        through_thickness(
            i,
            linear_swelling(&i.a0, &i.b0, i.h, i.m_top, i.m_bottom, mu),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::close;
    use super::*;

    #[test]
    fn equal_moisture_keeps_a_flat_sheet_flat() {
        let a0 = Sym2::new(1.0, 0.2, 0.8);
        let (a, b) = linear_swelling(&a0, &Sym2::zeros(), 0.01, 0.3, 0.3, 0.05);
        assert!(close(&a, &(a0 * 1.015f64.powi(2)), 1e-14));
        assert!(b.amax() < 1e-14);
    }

    #[test]
    fn wetter_top_bulges_toward_the_normal() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let (_, b) = linear_swelling(&a0, &Sym2::zeros(), 0.01, 0.4, 0.0, 0.1);
        assert!(b[0] > 0.0 && b[2] > 0.0);
        let (_, b) = linear_swelling(&a0, &Sym2::zeros(), 0.01, 0.0, 0.4, 0.1);
        assert!(b[0] < 0.0 && b[2] < 0.0);
    }

    #[test]
    fn linear_swelling_matches_the_closed_form() {
        // ā = (s₀² + s₁²h²/12) a⁰ + (s₀s₁h²/3) b⁰, b̄ = s₀s₁ a⁰ + (s₀² + 3s₁²h²/20) b⁰.
        let (a0, b0) = (Sym2::new(1.0, 0.1, 0.9), Sym2::new(0.3, -0.1, 0.2));
        let (h, mt, mb, mu) = (0.02, 0.5, -0.2, 0.3);
        let s0 = 1.0 + mu * (mt + mb) / 2.0;
        let s1 = mu * (mt - mb) / h;
        let ea = a0 * (s0 * s0 + s1 * s1 * h * h / 12.0) + b0 * (s0 * s1 * h * h / 3.0);
        let eb = a0 * (s0 * s1) + b0 * (s0 * s0 + 0.15 * s1 * s1 * h * h);
        let (a, b) = linear_swelling(&a0, &b0, h, mt, mb, mu);
        assert!(close(&a, &ea, 1e-14), "{a:?} vs {ea:?}");
        assert!(close(&b, &eb, 1e-13), "{b:?} vs {eb:?}");
    }
}
