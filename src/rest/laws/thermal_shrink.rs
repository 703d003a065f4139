//! Irreversible thermal shrink (`growth.law = "thermal_shrink"`): oriented polymers such as
//! injection-moulded or drawn polypropylene shrink when heated, because heat releases their
//! frozen-in molecular orientation (seed 000 §5.5, the spoon). The shrink is set by the
//! **highest** temperature a point has reached, not the current one, so cooling does not undo
//! it and reheating below that maximum changes nothing.
//!
//! ## Formula
//! The table `growth.shrink` gives at each temperature the shrink strains `ε∥(T)`, `ε⊥(T)` along
//! and across the machine (flow) direction `d` and `ε_n(T)` through the thickness, linear
//! between rows and constant beyond its ends. At height `z` with highest temperature
//! `T̂(z)`, lengths along `d` scale by `1 − ε∥(T̂(z))`, across by `1 − ε⊥(T̂(z))`: with `P = [d d⊥]`
//! (`d⊥` the `a⁰`-orthogonal complement) and `M(z) = diag(1 − ε∥, 1 − ε⊥)`,
//!
//! `ḡ(z) = P⁻ᵀ M(z) Pᵀ (a⁰ + 2z b⁰) P M(z) P⁻¹`,
//!
//! projected onto `ā + 2z b̄` as in [`super`] at its six sample heights, where `T̂` is the
//! conduction's own through-thickness profile (quadratic per element layer), not a straight line.
//! The thickness scales by the thickness mean `λ_n = ⟨1 − ε_n(T̂(z))⟩`: heights map `z ↦ λ_n z`,
//! so `h̄ = λ_n h` and `b̄ = b̄_projected / λ_n` (exact when `ε_n` is uniform through the
//! thickness; otherwise the through-thickness stretch enters through its mean only).
//!
//! Uniform heating with equal strains in all three columns is uniform volumetric growth,
//! `ā = λ² a⁰`, `b̄ = λ b⁰`, `h̄ = λ h` with `λ = 1 − ε`: a curved shell shrinks to its scaled copy
//! with zero energy. A linear profile with `ε` linear in T is linear differential swelling
//! (see [`super::linear_swelling`]) with `1 + μ m(z) = 1 − ε(z)`.
//!
//! Units: T in kelvin, strains dimensionless, ā in m², b̄ in m.

use super::machine_direction::direction_frame;
use super::{
    project_samples, reference_metric, sample_weights, FaceInput, Grown, GrowthError, LawEntry,
    RestLaw,
};
use crate::config::growth::{GrowthLaw, GrowthModel, ShrinkTable};
use crate::math::{Mat2, Real};

/// The thermal shrink law with its table.
#[derive(Debug)]
pub struct ThermalShrink {
    /// Shrink strains against the highest temperature reached.
    pub table: ShrinkTable,
}

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::ThermalShrink,
    example: "shrink = [[293.15, 0, 0], [393.15, 0.04, 0.02]]\ntemperature_top = 373.15\ntemperature_bottom = 333.15\nmachine_direction = [1, 1, 0]",
    build: |m| match m {
        GrowthModel::ThermalShrink { table } => Some(Box::new(ThermalShrink {
            table: table.clone(),
        })),
        _ => None,
    },
};

impl RestLaw for ThermalShrink {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let eps = i.heat.map(|t| self.table.at(t));
        let (p, pinv) = direction_frame(&i.a0, i.direction);
        let (abar, bbar) = project_samples(i.h, |k, z| {
            let m = Mat2::new(1.0 - eps[k][0], 0.0, 0.0, 1.0 - eps[k][1]);
            pinv.transpose() * m * p.transpose() * reference_metric(&i.a0, &i.b0, z) * p * m * pinv
        });
        // Exactly 1 when nothing changes through the thickness (the weights' sum is 1 only to
        // rounding).
        let lambda: Real = if eps.iter().all(|e| e[2] == 0.0) {
            1.0
        } else {
            eps.iter()
                .zip(sample_weights())
                .map(|(e, w)| w * (1.0 - e[2]))
                .sum()
        };
        Ok(Grown {
            abar,
            bbar: bbar / lambda,
            thickness_ratio: lambda,
        })
    }
    fn needs_direction(&self) -> bool {
        !self.table.isotropic_in_plane()
    }
}

#[cfg(test)]
mod tests {
    use super::super::linear_swelling::linear_swelling;
    use super::super::{close, sample_heights};
    use super::*;
    use crate::math::Sym2;

    fn input(a0: Sym2, b0: Sym2, h: Real, heat: [Real; 6], direction: [Real; 2]) -> FaceInput {
        FaceInput {
            face: 0,
            a0,
            b0,
            h,
            m_top: 0.0,
            m_bottom: 0.0,
            s: 0.0,
            direction,
            heat,
            coef: Default::default(),
            relaxed: None,
        }
    }

    fn table(rows: &[[Real; 4]]) -> ShrinkTable {
        ShrinkTable {
            temperature: rows.iter().map(|r| r[0]).collect(),
            shrink: rows.iter().map(|r| [r[1], r[2], r[3]]).collect(),
        }
    }

    /// Uniform heating with equal strains in every direction shrinks a curved face to its
    /// scaled copy: ā = λ² a⁰, b̄ = λ b⁰, h̄ = λ h (the volumetric law's forms).
    #[test]
    fn uniform_isotropic_shrink_is_volumetric() {
        let law = ThermalShrink {
            table: table(&[[300.0, 0.0, 0.0, 0.0], [400.0, 0.1, 0.1, 0.1]]),
        };
        let (a0, b0) = (Sym2::new(1.0, 0.3, 1.2), Sym2::new(0.2, 0.05, -0.1));
        // 380 K: 80% of the way, ε = 0.08.
        let g = law
            .grow(&input(a0, b0, 0.05, [380.0; 6], [1.0, 0.0]))
            .unwrap();
        let l: Real = 0.92;
        assert!(close(&g.abar, &(a0 * l * l), 1e-14), "{:?}", g.abar);
        assert!(close(&g.bbar, &(b0 * l), 1e-13), "{:?}", g.bbar);
        assert!((g.thickness_ratio - l).abs() < 1e-15);
    }

    /// A linear temperature profile with ε linear in T is linear swelling with
    /// 1 + μ m(z) = 1 − ε(z), on a curved face.
    #[test]
    fn a_linear_profile_is_linear_swelling() {
        let law = ThermalShrink {
            table: table(&[[300.0, 0.0, 0.0, 0.0], [500.0, 0.2, 0.2, 0.0]]),
        };
        let (a0, b0, h) = (Sym2::new(1.0, 0.3, 1.2), Sym2::new(0.2, 0.05, -0.1), 0.05);
        let (top, bottom) = (450.0, 330.0);
        let heat = sample_heights(h).map(|z| 0.5 * (top + bottom) + (top - bottom) * z / h);
        let g = law.grow(&input(a0, b0, h, heat, [1.0, 0.0])).unwrap();
        // ε = 0.001 (T − 300): m = T − 300 with μ = −0.001.
        let (a, b) = linear_swelling(&a0, &b0, h, top - 300.0, bottom - 300.0, -0.001);
        assert!(close(&g.abar, &a, 1e-14) && close(&g.bbar, &b, 1e-13));
        assert_eq!(g.thickness_ratio, 1.0);
    }

    /// Along/across: a flat unit face heated uniformly, d = e1, shrinks 4% along and 2% across;
    /// the forms do not depend on the direction's length.
    #[test]
    fn anisotropic_shrink_follows_the_machine_direction() {
        let law = ThermalShrink {
            table: table(&[[293.15, 0.0, 0.0, 0.0], [393.15, 0.04, 0.02, -0.03]]),
        };
        let id = Sym2::new(1.0, 0.0, 1.0);
        let g = law
            .grow(&input(id, Sym2::zeros(), 0.001, [393.15; 6], [2.0, 0.0]))
            .unwrap();
        assert!(close(
            &g.abar,
            &Sym2::new(0.96 * 0.96, 0.0, 0.98 * 0.98),
            1e-15
        ));
        // Flat and uniform: b̄ vanishes to the projection's round-off, ε |ā| / h.
        assert!(g.bbar.amax() < 1e-12 / 0.001, "{:?}", g.bbar);
        assert!((g.thickness_ratio - 1.03).abs() < 1e-15);
        // Beyond the table's ends the strain is held.
        let hot = law
            .grow(&input(id, Sym2::zeros(), 0.001, [900.0; 6], [1.0, 0.0]))
            .unwrap();
        assert_eq!(hot, g);
        let cold = law
            .grow(&input(id, Sym2::zeros(), 0.001, [250.0; 6], [1.0, 0.0]))
            .unwrap();
        assert!(close(&cold.abar, &id, 1e-15) && cold.thickness_ratio == 1.0);
        assert!(law.needs_direction());
    }
}
