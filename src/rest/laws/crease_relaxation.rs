//! Crease relaxation (`growth.law = "crease_relaxation"`): a sheet creased or crushed when dry
//! (paper folded into an accordion, a straw's wrapper pushed down) holds its creases by a
//! plastic set that water releases. The mesh is the creased state, stress-free when dry; the
//! vertex field `original_positions` stores the shape before creasing (a flat strip, a tube),
//! whose discrete forms `(â, b̂)` are computed with the bending model's own definition. With the
//! face's mean moisture `m̄ = (m⁺ + m⁻)/2` and `relax_moisture = [m₀, m₁]`, the blend
//! `w = clamp((m̄ − m₀)/(m₁ − m₀), 0, 1)` takes the rest forms linearly from the creased forms
//! `(a⁰, b⁰)` to the original ones, and an optional hygroexpansion `μ` (`growth.mu`, default 0)
//! scales them as the in-plane swelling at kept thickness does:
//!
//! `ā = (1 + μ m̄)² ((1 − w) a⁰ + w â)`,   `b̄ = (1 + μ m̄)² ((1 − w) b⁰ + w b̂)`.
//!
//! A free crease relaxes to the blend of its angles: a circular crease of angle θ on an
//! isometric fold (`â = a⁰`) keeps its length and opens to `(1 − w) θ` in the continuum limit.
//! `growth.mu_through` grows the thickness ([`super::through_thickness`]). The law follows the
//! current moisture: drying does not re-crease a sheet in reality, so use it for wetting.
//! Units: ā in m², b̄ in m, moisture dimensionless.

use super::{check_stretch, through_thickness, FaceInput, Grown, GrowthError, LawEntry, RestLaw};
use crate::config::growth::{GrowthLaw, GrowthModel};
use crate::math::Real;

/// The crease-relaxation law with its moisture range.
#[derive(Debug)]
pub struct CreaseRelaxation {
    /// `[m₀, m₁]`.
    pub relax: [Real; 2],
}

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::CreaseRelaxation,
    example: "relax_moisture = [0.0, 0.2]\nmoisture_top = 0.1\nmoisture_bottom = 0.1",
    build: |m| match m {
        GrowthModel::CreaseRelaxation { relax } => {
            Some(Box::new(CreaseRelaxation { relax: *relax }))
        }
        _ => None,
    },
};

impl CreaseRelaxation {
    /// The blend `w ∈ [0, 1]` at mean moisture `m`.
    pub fn blend(&self, m: Real) -> Real {
        let [m0, m1] = self.relax;
        ((m - m0) / (m1 - m0)).clamp(0.0, 1.0)
    }
}

impl RestLaw for CreaseRelaxation {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let (a1, b1) = i.relaxed.unwrap_or((i.a0, i.b0));
        let mu = i.coef.mu;
        check_stretch(i, mu, true, true)?;
        let m = 0.5 * (i.m_top + i.m_bottom);
        let w = self.blend(m);
        let s = (1.0 + mu * m).powi(2);
        let abar = (i.a0 * (1.0 - w) + a1 * w) * s;
        let bbar = (i.b0 * (1.0 - w) + b1 * w) * s;
        through_thickness(i, (abar, bbar))
    }
    fn needs_stored_state(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::super::{close, Coefficients};
    use super::*;
    use crate::math::Sym2;

    fn input(m: Real, mu: Real) -> FaceInput {
        FaceInput {
            face: 0,
            a0: Sym2::new(1.0, 0.2, 0.9),
            b0: Sym2::new(0.5, 0.1, -0.2),
            h: 0.01,
            m_top: m,
            m_bottom: m,
            s: 0.0,
            direction: [1.0, 0.0],
            heat: [293.15; 6],
            coef: Coefficients {
                mu,
                ..Coefficients::default()
            },
            relaxed: Some((Sym2::new(1.1, 0.0, 1.0), Sym2::zeros())),
        }
    }

    #[test]
    fn the_blend_runs_from_the_creased_to_the_original_forms() {
        let law = CreaseRelaxation { relax: [0.1, 0.5] };
        let dry = law.grow(&input(0.0, 0.0)).unwrap();
        assert!(
            close(&dry.abar, &Sym2::new(1.0, 0.2, 0.9), 1e-15)
                && close(&dry.bbar, &Sym2::new(0.5, 0.1, -0.2), 1e-15)
        );
        let half = law.grow(&input(0.3, 0.0)).unwrap();
        assert!(
            close(&half.abar, &Sym2::new(1.05, 0.1, 0.95), 1e-15),
            "{:?}",
            half.abar
        );
        assert!(close(&half.bbar, &Sym2::new(0.25, 0.05, -0.1), 1e-15));
        let wet = law.grow(&input(0.9, 0.0)).unwrap();
        assert!(close(&wet.abar, &Sym2::new(1.1, 0.0, 1.0), 1e-15) && wet.bbar.amax() == 0.0);
        // Hygroexpansion on top: lengths × (1 + μ m̄).
        let swollen = law.grow(&input(0.9, 0.05)).unwrap();
        assert!(close(
            &swollen.abar,
            &(Sym2::new(1.1, 0.0, 1.0) * 1.045f64.powi(2)),
            1e-14
        ));
        assert_eq!(swollen.thickness_ratio, 1.0);
    }
}
