//! MorphoShell's bend stiffening (seed 001 §2): the bending energy density `W_b` is replaced by
//!
//! `W_b' = W_b + W_b² / (γ μ t)`,
//!
//! with μ the face's shear modulus (Pa), t its thickness (m) and γ a dimensionless setting
//! (`material.bend_stiffening`). `μ t` is the scale of `W_b` when curvatures reach `1/t`, where
//! shell theory breaks down; a moderate γ (~1) stops a steep cone's tip from buckling into
//! something pathological, a huge γ removes the effect.
//!
//! Per face, with `E_b = A W_b` the face's bending energy (J) and A its rest area (m²):
//! `E_b' = E_b + s E_b²`, `s = 1 / (A γ μ t)` (1/J), so
//!
//! `∂E_b'/∂b = (1 + 2 s E_b) ∂E_b/∂b`,
//! `∂²E_b'/∂b² = (1 + 2 s E_b) ∂²E_b/∂b² + 2 s (∂E_b/∂b)(∂E_b/∂b)ᵀ`.
//!
//! Both Hessian parts are positive semi-definite when `∂²E_b/∂b²` is, so the Gauss–Newton
//! Hessian stays a descent model. It acts on the Koiter bending well that every material and
//! bending model shares ([`crate::energy::material::KoiterDensity`]), so it works with all of
//! them; the damping well is not stiffened.

use crate::math::{Mat3, Real, Sym2};

/// The coefficient `s = 1/(A γ μ t)` (1/J) of a face with rest area `area` (m²), shear modulus
/// `mu` (Pa) and thickness `t` (m); 0 (off) without γ.
#[inline]
pub fn coefficient(gamma: Option<Real>, area: Real, mu: Real, t: Real) -> Real {
    match gamma {
        Some(g) => 1.0 / (area * g * mu * t),
        None => 0.0,
    }
}

/// Stiffens a bending energy `e` (J) with gradient `g` and Hessian `h` in `b` by coefficient `s`
/// (module doc); returns the stiffened energy. `h` is updated only when given.
#[inline]
pub fn stiffen(s: Real, e: Real, g: &mut Sym2, h: Option<&mut Mat3>) -> Real {
    if s == 0.0 {
        return e;
    }
    let f = 1.0 + 2.0 * s * e;
    if let Some(h) = h {
        *h = *h * f + *g * g.transpose() * (2.0 * s);
    }
    *g *= f;
    e + s * e * e
}
