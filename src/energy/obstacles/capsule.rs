//! A capsule: the points within `R` of the segment `a`–`b`. With `p` the segment's point
//! nearest `x` (parameter `t = clamp((x − a)·e/L, 0, 1)`, `e` the unit axis, `L` the length),
//! `w = x − p`, `r = ‖w‖`: `d = r − R`, `∇d = u = w/r`, and `∇²d = (P − uuᵀ)/r` with
//! `P = I − eeᵀ` beside the segment (`0 < t < 1`) and `P = I` beyond its ends (m, 1/m).

use super::Distance;
use crate::math::{Mat3, Real, Vec3};

/// A capsule.
#[derive(Clone, Copy, Debug)]
pub struct Capsule {
    /// One end of the segment (m).
    pub a: Vec3,
    /// The other end (m).
    pub b: Vec3,
    /// Radius (m).
    pub radius: Real,
}

impl Distance for Capsule {
    #[inline]
    fn distance(&self, x: &Vec3) -> (Real, Vec3, Mat3) {
        let ab = self.b - self.a;
        let len = ab.norm();
        let e = ab / len;
        let s = (x - self.a).dot(&e);
        let (p, proj) = if s <= 0.0 {
            (self.a, Mat3::identity())
        } else if s >= len {
            (self.b, Mat3::identity())
        } else {
            (self.a + e * s, Mat3::identity() - e * e.transpose())
        };
        super::round_distance(x - p, self.radius, &proj)
    }
}
