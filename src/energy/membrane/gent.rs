//! Incompressible Gent rubber membrane: limited chain extensibility.
//!
//! Per unit rest volume `W = −(μ J_m/2) ln(1 − (I₁ − 3)/J_m)` (Gent, Rubber Chem. Technol.
//! 1996; for balloons: Mangan & Destrade, Int. J. Non-Linear Mech. 2015). With the in-plane
//! stretch `C₂ = ā⁻¹a` and incompressibility (`λ₃ = 1/J`, `J² = det a / det ā`),
//! `ψ = I₁ − 3 = t·a + det ā/d − 3` exactly as in [`super::neo_hookean`] (`t = (Ā11, 2Ā12, Ā22)`,
//! `Ā = ā⁻¹`, `d = det a`), and the energy of a face is
//!
//! `W = −V μ J_m/2 ln(1 − ψ/J_m)`, `V = h √det ā / 2`,
//!
//! with μ = E/(2(1+ν)) the face's shear modulus (ν = ½ for rubber). As `J_m → ∞` it is the
//! neo-Hookean membrane `V μ/2 ψ`; at `ψ ≥ J_m` the chains are fully stretched and the energy is
//! `+∞` (a line search steps back). Units: J; `a` in m², μ in Pa, `J_m` dimensionless.
//!
//! Derivatives, with `g = 1/(1 − ψ/J_m)` and ψ's derivatives from the neo-Hookean law,
//! `∂ψ/∂a = t − det ā ∇d/d²`, `∂²ψ/∂a² = det ā (2∇d∇dᵀ/d³ − ∇²d/d²)`:
//! `∂W/∂a = Vμ/2 g ∂ψ/∂a`, `∂²W/∂a² = Vμ/2 (g ∂²ψ/∂a² + g²/J_m ∂ψ/∂a ∂ψ/∂aᵀ)`.
//! The extra rank-one part is positive semi-definite, so the projected Hessian clamps the
//! same two pieces as the neo-Hookean law's.

use super::neo_hookean::{det_derivs, NeoHookeanFace};
use super::{bending_wells, psd3, psd_ga, Membrane, MembraneLaw, WithKoiterBending};
use crate::energy::Potential;
use crate::math::{Mat3, Real, Sym2};

/// The Gent membrane with limiting extensibility `jm`.
#[derive(Clone, Copy, Debug)]
pub struct Gent {
    /// `J_m` (dimensionless, > 0).
    pub jm: Real,
}

/// The law on one face.
#[derive(Clone, Copy, Debug)]
pub struct GentFace {
    /// `V μ/2`, `t` and `det ā`, shared with the neo-Hookean law.
    pub nh: NeoHookeanFace,
    /// `J_m`.
    pub jm: Real,
}

impl MembraneLaw for GentFace {
    #[inline]
    fn eval(&self, a: &Sym2, derivs: Option<(&mut Sym2, &mut Mat3)>) -> Real {
        let (d, gd, hd) = det_derivs(a);
        let (t, da, w) = (self.nh.t, self.nh.det_abar, self.nh.w);
        let psi = t.dot(a) + da / d - 3.0;
        let room = 1.0 - psi / self.jm;
        if !(room > 0.0 && d > 0.0) {
            if let Some((ga, haa)) = derivs {
                *ga = Sym2::zeros();
                *haa = Mat3::zeros();
            }
            return Real::INFINITY;
        }
        if let Some((ga, haa)) = derivs {
            let g = 1.0 / room;
            let dpsi = t - gd * (da / (d * d));
            let hpsi = (gd * gd.transpose() * (2.0 / (d * d * d)) - hd / (d * d)) * da;
            *ga = dpsi * (w * g);
            *haa = (hpsi * g + dpsi * dpsi.transpose() * (g * g / self.jm)) * w;
        }
        // −J_m ln(1 − ψ/J_m), written with ln_1p so that it tends to ψ for J_m → ∞.
        -w * self.jm * (-psi / self.jm).ln_1p()
    }

    fn psd(&self, a: &Sym2, ga: &mut Sym2, haa: &mut Mat3) {
        let (mut g, mut h) = (Sym2::zeros(), Mat3::zeros());
        self.eval(a, Some((&mut g, &mut h)));
        *ga = psd_ga(&g);
        *haa = psd3(&h);
    }
}

impl Membrane for Gent {
    type Density = WithKoiterBending<GentFace>;
    #[inline]
    fn density(&self, pot: &Potential, f: usize) -> Self::Density {
        let (abar, _) = pot.rest_forms(f);
        WithKoiterBending {
            law: GentFace {
                nh: NeoHookeanFace::new(
                    &abar,
                    pot.thickness(f),
                    pot.lame(f).beta,
                    pot.stretch_scale,
                ),
                jm: self.jm,
            },
            koiter: bending_wells(pot, f),
        }
    }
}
