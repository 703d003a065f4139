//! An infinite circular cylinder through `p` with unit axis `e` and radius `R`: with
//! `w = (I − eeᵀ)(x − p)`, `r = ‖w‖`, `d = r − R`, `∇d = u = w/r`,
//! `∇²d = (I − eeᵀ − uuᵀ)/r` (m, 1/m).

use super::Distance;
use crate::math::{Mat3, Real, Vec3};

/// A cylinder.
#[derive(Clone, Copy, Debug)]
pub struct Cylinder {
    /// A point on the axis (m).
    pub point: Vec3,
    /// Unit axis.
    pub axis: Vec3,
    /// Radius (m).
    pub radius: Real,
}

impl Distance for Cylinder {
    #[inline]
    fn distance(&self, x: &Vec3) -> (Real, Vec3, Mat3) {
        let e = self.axis;
        let q = x - self.point;
        let w = q - e * e.dot(&q);
        super::round_distance(w, self.radius, &(Mat3::identity() - e * e.transpose()))
    }
}
