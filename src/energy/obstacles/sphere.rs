//! A sphere of centre `c` and radius `R`: `d = ‖x − c‖ − R`, `∇d = u = (x − c)/r`,
//! `∇²d = (I − uuᵀ)/r` with `r = ‖x − c‖` (m, dimensionless, 1/m).

use super::Distance;
use crate::math::{Mat3, Real, Vec3};

/// A sphere.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre (m).
    pub center: Vec3,
    /// Radius (m).
    pub radius: Real,
}

impl Distance for Sphere {
    #[inline]
    fn distance(&self, x: &Vec3) -> (Real, Vec3, Mat3) {
        super::round_distance(x - self.center, self.radius, &Mat3::identity())
    }
}
