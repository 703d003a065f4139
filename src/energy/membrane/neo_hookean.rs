//! Incompressible neo-Hookean rubber membrane.
//!
//! With the in-plane stretch tensor `C₂ = ā⁻¹a` and the thickness stretch `λ₃ = 1/J`,
//! `J² = det a / det ā` (incompressibility), `I₁ = tr C₂ + λ₃²` and the energy of a face is
//!
//! `W = V μ/2 (tr(ā⁻¹a) + det ā / det a − 3)`, `V = h √det ā / 2` (rest volume),
//!
//! with μ the shear modulus `E/(2(1+ν))` of the face (for rubber ν = ½ and μ = E/3). In the
//! small-strain limit it equals the Koiter membrane with ν = ½. Units: J; `a` in m², μ in Pa.
//!
//! Derivatives, with `tr(ā⁻¹a) = t·a`, `t = (Ā11, 2Ā12, Ā22)`, `d = det a`, `∇d = (a22, −2a12,
//! a11)`, `∇²d = [[0,0,1],[0,−2,0],[1,0,0]]`:
//! `∂W/∂a = Vμ/2 (t − det ā ∇d/d²)`, `∂²W/∂a² = Vμ/2 det ā (2∇d∇dᵀ/d³ − ∇²d/d²)`.

use super::{bending_wells, psd3, psd_ga, Membrane, MembraneLaw, WithKoiterBending};
use crate::energy::Potential;
use crate::math::{sym_det, sym_to_mat, Mat3, Real, SVec, Sym2};

/// The neo-Hookean membrane.
#[derive(Clone, Copy, Debug, Default)]
pub struct NeoHookean;

/// The law on one face.
#[derive(Clone, Copy, Debug)]
pub struct NeoHookeanFace {
    /// `V μ/2` (J).
    pub w: Real,
    /// `t = (Ā11, 2Ā12, Ā22)`, `Ā = ā⁻¹`.
    pub t: SVec<3>,
    /// `det ā`.
    pub det_abar: Real,
}

impl NeoHookeanFace {
    /// The law for rest metric `ā`, thickness `h` and shear modulus `mu`, energy × `scale`.
    pub fn new(abar: &Sym2, h: Real, mu: Real, scale: Real) -> Self {
        let det_abar = sym_det(abar);
        let ai = sym_to_mat(abar).try_inverse().unwrap_or_default();
        let vol = h * 0.5 * det_abar.max(0.0).sqrt();
        NeoHookeanFace {
            w: 0.5 * vol * mu * scale,
            t: SVec::<3>::new(ai[(0, 0)], 2.0 * ai[(0, 1)], ai[(1, 1)]),
            det_abar,
        }
    }
}

/// `(det a, ∇det a, ∇²det a)` in `[a11, a12, a22]`.
#[inline]
pub fn det_derivs(a: &Sym2) -> (Real, SVec<3>, Mat3) {
    (
        sym_det(a),
        SVec::<3>::new(a[2], -2.0 * a[1], a[0]),
        Mat3::new(0.0, 0.0, 1.0, 0.0, -2.0, 0.0, 1.0, 0.0, 0.0),
    )
}

impl MembraneLaw for NeoHookeanFace {
    #[inline]
    fn eval(&self, a: &Sym2, derivs: Option<(&mut Sym2, &mut Mat3)>) -> Real {
        let (d, gd, hd) = det_derivs(a);
        let e = self.w * (self.t.dot(a) + self.det_abar / d - 3.0);
        if let Some((ga, haa)) = derivs {
            *ga = (self.t - gd * (self.det_abar / (d * d))) * self.w;
            *haa = (gd * gd.transpose() * (2.0 / (d * d * d)) - hd / (d * d))
                * (self.w * self.det_abar);
        }
        e
    }

    fn psd(&self, a: &Sym2, ga: &mut Sym2, haa: &mut Mat3) {
        let (mut g, mut h) = (Sym2::zeros(), Mat3::zeros());
        self.eval(a, Some((&mut g, &mut h)));
        *ga = psd_ga(&g);
        *haa = psd3(&h);
    }
}

impl Membrane for NeoHookean {
    type Density = WithKoiterBending<NeoHookeanFace>;
    #[inline]
    fn density(&self, pot: &Potential, f: usize) -> Self::Density {
        let (abar, _) = pot.rest_forms(f);
        WithKoiterBending {
            law: NeoHookeanFace::new(&abar, pot.thickness(f), pot.lame(f).beta, pot.stretch_scale),
            koiter: bending_wells(pot, f),
        }
    }
}
