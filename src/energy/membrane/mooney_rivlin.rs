//! Incompressible Mooney–Rivlin rubber membrane, `W = c₁(I₁ − 3) + c₂(I₂ − 3)` per unit rest
//! volume.
//!
//! With `C₂ = ā⁻¹a`, `λ₃ = 1/J`, `J² = det a / det ā`: `I₁ = tr C₂ + 1/J²` and
//! `I₂ = J² + tr C₂ / J²`, so per face
//!
//! `W = V [c₁ (t·a + det ā/d − 3) + c₂ (d/det ā + (t·a) det ā/d − 3)]`, `V = h √det ā / 2`,
//!
//! (`t`, `d` as in [`super::neo_hookean`]). With `c₂ = 0` and `μ = 2c₁` it is the neo-Hookean
//! membrane; the small-strain shear modulus is `2(c₁ + c₂)`. Units: J, c₁ and c₂ in Pa.
//!
//! `∂I₂/∂a = ∇d/det ā + det ā (t/d − (t·a)∇d/d²)`,
//! `∂²I₂/∂a² = ∇²d/det ā + det ā (−(t∇dᵀ + ∇d tᵀ)/d² + (t·a)(2∇d∇dᵀ/d³ − ∇²d/d²))`.

use super::neo_hookean::{det_derivs, NeoHookeanFace};
use super::{bending_wells, psd3, psd_ga, Membrane, MembraneLaw, WithKoiterBending};
use crate::energy::Potential;
use crate::math::{Mat3, Real, Sym2};

/// The Mooney–Rivlin membrane with constants `c1`, `c2` (Pa).
#[derive(Clone, Copy, Debug)]
pub struct MooneyRivlin {
    /// `c₁` (Pa).
    pub c1: Real,
    /// `c₂` (Pa).
    pub c2: Real,
}

/// The law on one face.
#[derive(Clone, Copy, Debug)]
pub struct MooneyRivlinFace {
    /// The `c₁` part, a neo-Hookean law with `μ = 2c₁`.
    pub nh: NeoHookeanFace,
    /// `V c₂` (J).
    pub w2: Real,
}

impl MembraneLaw for MooneyRivlinFace {
    #[inline]
    fn eval(&self, a: &Sym2, derivs: Option<(&mut Sym2, &mut Mat3)>) -> Real {
        let (d, gd, hd) = det_derivs(a);
        let (t, da) = (self.nh.t, self.nh.det_abar);
        let ta = t.dot(a);
        let i2 = d / da + ta * da / d;
        match derivs {
            None => self.nh.eval(a, None) + self.w2 * (i2 - 3.0),
            Some((ga, haa)) => {
                let e1 = self.nh.eval(a, Some((ga, haa)));
                let g2 = gd / da + (t / d - gd * (ta / (d * d))) * da;
                let h2 = hd / da
                    + ((t * gd.transpose() + gd * t.transpose()) * (-1.0 / (d * d))
                        + (gd * gd.transpose() * (2.0 / (d * d * d)) - hd / (d * d)) * ta)
                        * da;
                *ga += g2 * self.w2;
                *haa += h2 * self.w2;
                e1 + self.w2 * (i2 - 3.0)
            }
        }
    }

    fn psd(&self, a: &Sym2, ga: &mut Sym2, haa: &mut Mat3) {
        let (mut g, mut h) = (Sym2::zeros(), Mat3::zeros());
        self.eval(a, Some((&mut g, &mut h)));
        *ga = psd_ga(&g);
        *haa = psd3(&h);
    }
}

impl Membrane for MooneyRivlin {
    type Density = WithKoiterBending<MooneyRivlinFace>;
    #[inline]
    fn density(&self, pot: &Potential, f: usize) -> Self::Density {
        let (abar, _) = pot.rest_forms(f);
        let h = pot.thickness(f);
        let s = pot.stretch_scale;
        let soft = pot.modulus(f);
        let nh = NeoHookeanFace::new(&abar, h, 2.0 * self.c1 * soft, s);
        let vol = h * 0.5 * crate::math::sym_det(&abar).max(0.0).sqrt();
        WithKoiterBending {
            law: MooneyRivlinFace {
                nh,
                w2: vol * self.c2 * soft * s,
            },
            koiter: bending_wells(pot, f),
        }
    }
}
