//! Piecewise-constant bilayer (`growth.law = "bilayer"`; van Rees, Vouga & Mahadevan, PNAS
//! 2017): the top half has metric `(1 + μ⁺ m⁺)²(a⁰ + 2z b⁰)`, the bottom half
//! `(1 + μ⁻ m⁻)²(a⁰ + 2z b⁰)`, projected as in [`super`]. For a flat reference,
//! `ā = (ḡ⁺ + ḡ⁻)/2`, `b̄ = 3(ḡ⁺ − ḡ⁻)/(4h)`: van Rees' equivalence, which with equal layers
//! reproduces Timoshenko's κ = 3Δε/(2h). The thickness is kept, unless `growth.mu_through`
//! grows it ([`super::through_thickness`]). Coefficients: `growth.mu_top`, `growth.mu_bottom`
//! (per unit moisture), per face when regions or face fields give them. Units: ā in m², b̄ in m.

use super::{
    check_stretch, project_through_thickness, reference_metric, through_thickness, FaceInput,
    Grown, GrowthError, LawEntry, RestLaw,
};
use crate::config::growth::{GrowthLaw, GrowthModel};
use crate::math::{Real, Sym2};

/// The bilayer law with each face's `mu_top` and `mu_bottom` ([`super::Coefficients`]).
#[derive(Debug)]
pub struct Bilayer;

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::Bilayer,
    example: "mu_top = 0.05\nmu_bottom = 0.01\nmoisture_top = 0.4\nmoisture_bottom = 0.3",
    build: |m| {
        matches!(m, GrowthModel::Bilayer { .. }).then(|| Box::new(Bilayer) as Box<dyn RestLaw>)
    },
};

/// Piecewise-constant bilayer: top half swells by `1 + mu_top m_top`, bottom half by
/// `1 + mu_bottom m_bottom`.
pub fn bilayer(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    m_top: Real,
    m_bottom: Real,
    mu_top: Real,
    mu_bottom: Real,
) -> (Sym2, Sym2) {
    project_through_thickness(h, |z| {
        let s = if z > 0.0 {
            1.0 + mu_top * m_top
        } else {
            1.0 + mu_bottom * m_bottom
        };
        reference_metric(a0, b0, z) * (s * s)
    })
}

impl RestLaw for Bilayer {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let (mt, mb) = (i.coef.mu_top, i.coef.mu_bottom);
        check_stretch(i, mt, true, false)?;
        check_stretch(i, mb, false, true)?;
        through_thickness(i, bilayer(&i.a0, &i.b0, i.h, i.m_top, i.m_bottom, mt, mb))
    }
}

#[cfg(test)]
mod tests {
    use super::super::close;
    use super::*;

    #[test]
    fn bilayer_is_van_rees_and_timoshenko() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let (h, de) = (0.002, 0.002);
        // Layers stretched by 1 ± Δε/2: μ = 1, m± = ±Δε/2.
        let (a, b) = bilayer(&a0, &Sym2::zeros(), h, de / 2.0, -de / 2.0, 1.0, 1.0);
        let (gp, gm) = ((1.0 + de / 2.0).powi(2), (1.0 - de / 2.0).powi(2));
        assert!(close(&a, &(a0 * ((gp + gm) / 2.0)), 1e-14));
        assert!(close(&b, &(a0 * (3.0 * (gp - gm) / (4.0 * h))), 1e-13));
        // Timoshenko, equal layers: κ = 3Δε/(2h) (to O(Δε²)).
        let kappa = b[0] / a[0];
        assert!((kappa / (1.5 * de / h) - 1.0).abs() < 1e-5, "{kappa}");
    }
}
