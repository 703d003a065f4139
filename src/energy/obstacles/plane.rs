//! A plane through `p` with unit normal `n` toward the sheet: `d = n·(x − p)`, `∇d = n`,
//! `∇²d = 0` (m). Unlike `[contact]`'s ground it can be moved with the dial and several can be
//! combined.

use super::Distance;
use crate::math::{Mat3, Real, Vec3};

/// A plane.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    /// A point on the plane (m).
    pub point: Vec3,
    /// Unit normal toward the sheet.
    pub normal: Vec3,
}

impl Distance for Plane {
    #[inline]
    fn distance(&self, x: &Vec3) -> (Real, Vec3, Mat3) {
        (
            self.normal.dot(&(x - self.point)),
            self.normal,
            Mat3::zeros(),
        )
    }
}
