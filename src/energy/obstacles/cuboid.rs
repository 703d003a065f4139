//! An axis-aligned box `[min, max]`. Outside it, with `q = x − clamp(x, min, max)` and
//! `r = ‖q‖`: `d = r`, `∇d = u = q/r`, `∇²d = (P − uuᵀ)/r` where `P` keeps the axes on which
//! `x` lies outside the box's slab (the distance does not change along the others): a face, an
//! edge or a corner nearest. Inside: `d = −` the distance to the nearest face, `∇d` that
//! face's outward normal, `∇²d = 0` (m, 1/m). The distance is C¹ outside the box; its Hessian
//! jumps where the nearest feature changes.

use super::Distance;
use crate::math::{Mat3, Real, Vec3};

/// An axis-aligned box.
#[derive(Clone, Copy, Debug)]
pub struct Cuboid {
    /// Lower corner (m).
    pub min: Vec3,
    /// Upper corner (m).
    pub max: Vec3,
}

impl Distance for Cuboid {
    #[inline]
    fn distance(&self, x: &Vec3) -> (Real, Vec3, Mat3) {
        let c = Vec3::new(
            x.x.clamp(self.min.x, self.max.x),
            x.y.clamp(self.min.y, self.max.y),
            x.z.clamp(self.min.z, self.max.z),
        );
        let q = x - c;
        if q.norm_squared() > 0.0 {
            let outside =
                Mat3::from_diagonal(&Vec3::from_fn(|k, _| Real::from(u8::from(q[k] != 0.0))));
            return super::round_distance(q, 0.0, &outside);
        }
        // Inside: the nearest face.
        let (mut best, mut n) = (Real::INFINITY, Vec3::zeros());
        for k in 0..3 {
            for (gap, sign) in [(x[k] - self.min[k], -1.0), (self.max[k] - x[k], 1.0)] {
                if gap < best {
                    best = gap;
                    n = Vec3::zeros();
                    n[k] = sign;
                }
            }
        }
        (-best, n, Mat3::zeros())
    }
}
