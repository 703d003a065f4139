//! Plane-stress Lamé parameters of a face ([`crate::energy::material`] explains the choice).

use crate::math::Real;

/// Plane-stress (2D) Lamé parameters (Pa).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lame2d {
    /// `α = Eν/(1−ν²)` (Pa).
    pub alpha: Real,
    /// `β = E/(2(1+ν))`, the shear modulus (Pa).
    pub beta: Real,
}

impl Lame2d {
    /// From Young's modulus `E` (Pa) and Poisson's ratio `ν` (dimensionless, −1 < ν ≤ ½).
    pub fn from_young_poisson(young: Real, poisson: Real) -> Self {
        Lame2d {
            alpha: young * poisson / (1.0 - poisson * poisson),
            beta: young / (2.0 * (1.0 + poisson)),
        }
    }
}
