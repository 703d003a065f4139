//! Continuous collision detection with an offset: how far along a straight displacement a
//! point–triangle or edge–edge pair can move before its distance falls to a minimum `d_min`.
//!
//! **Additive CCD** (Li, Kaufman & Jiang 2021, "Codimensional Incremental Potential Contact",
//! §4, Algorithm 1), conservative advancement. Along `x(t) = x + t Δ`, the distance between the
//! pair's closest points changes no faster than `l = max_i ‖Δ̄_i‖ + max_j ‖Δ̄_j‖` per unit `t`,
//! the largest relative speed of a point of one primitive against the other, where `Δ̄` is the
//! displacement with its mean removed (a common translation changes no distance). From `t`, a
//! further advance of `τ = (1 − s)(d(t) − d_min)/l` therefore keeps `d ≥ d_min + s (d(t) −
//! d_min)`. The advance repeats until `t` reaches the end of the step, or the remaining margin
//! `d(t) − d_min` falls below `s` of the initial one, where `t` is the safe fraction returned.
//! Every `t' ∈ [0, t]` keeps the distance above `d_min`. The guarantee is exact in real
//! arithmetic; in floating point it holds up to the distance's round-off, which the static
//! check after a line search covers.
//!
//! Units: positions and distances m, `t` dimensionless. DOF order: the pair's four points as in
//! [`super::distance`].

use super::distance::{edge_edge, point_triangle};
use crate::math::{Real, Vec3};

/// The share `s` of the initial margin at which the advance stops (Li et al. use 0.1 as
/// well): the returned step leaves at least a tenth of the margin above `d_min`, up to the
/// conservative bound.
const STOP: Real = 0.1;

/// The most advances before the search gives up and returns the safe fraction it reached.
const MAX_ADVANCES: usize = 1000;

/// The largest fraction `t ∈ [0, max]` of the displacements `dx` of the four points `x` of a
/// point–triangle (`pt`) or edge–edge pair for which the distance stays at least `d_min`
/// along the whole path (module doc). `0` when the pair already is at or below `d_min`.
pub fn safe_fraction(x: &[Vec3; 4], dx: &[Vec3; 4], pt: bool, d_min: Real, max: Real) -> Real {
    let mean = (dx[0] + dx[1] + dx[2] + dx[3]) / 4.0;
    let n: [Real; 4] = std::array::from_fn(|i| (dx[i] - mean).norm());
    let l = if pt {
        n[0] + n[1].max(n[2]).max(n[3])
    } else {
        n[0].max(n[1]) + n[2].max(n[3])
    };
    // A lower bound of the distance first, from the primitives' boxes: most pairs the broad
    // phase hands over are too far apart for their relative motion, and need no exact
    // distance.
    let (a, b): (&[Vec3], &[Vec3]) = if pt {
        (&x[..1], &x[1..])
    } else {
        (&x[..2], &x[2..])
    };
    let gap = (0..3)
        .map(|k| {
            let (alo, ahi) = a
                .iter()
                .fold((Real::INFINITY, -Real::INFINITY), |(l, h), p| {
                    (l.min(p[k]), h.max(p[k]))
                });
            let (blo, bhi) = b
                .iter()
                .fold((Real::INFINITY, -Real::INFINITY), |(l, h), p| {
                    (l.min(p[k]), h.max(p[k]))
                });
            (blo - ahi).max(alo - bhi).max(0.0)
        })
        .fold(0.0, |s: Real, g| s + g * g)
        .sqrt();
    if l * max <= (gap - d_min) * (1.0 - STOP) {
        return max;
    }
    let dist = |t: Real| -> Real {
        let y: [Vec3; 4] = std::array::from_fn(|i| x[i] + dx[i] * t);
        if pt {
            point_triangle(&y).d2.sqrt()
        } else {
            edge_edge(&y).d2.sqrt()
        }
    };
    let margin0 = dist(0.0) - d_min;
    if margin0.is_nan() || margin0 <= 0.0 {
        return 0.0;
    }
    if l.is_nan() || l <= 0.0 || l * max <= margin0 * (1.0 - STOP) {
        // Too slow to use up the margin within the step.
        return max;
    }
    let mut t = 0.0;
    let mut margin = margin0;
    for _ in 0..MAX_ADVANCES {
        let tau = (1.0 - STOP) * margin / l;
        if t + tau >= max {
            return max;
        }
        let next = t + tau;
        let m = dist(next) - d_min;
        // The bound guarantees m ≥ STOP × margin; round-off aside, a smaller value means the
        // motion is not straight enough for the bound, and the last safe t stands.
        if m.is_nan() || m <= 0.0 {
            return t;
        }
        t = next;
        margin = m;
        if margin < STOP * margin0 {
            return t;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_min(x: &[Vec3; 4], dx: &[Vec3; 4], pt: bool, t: Real) -> Real {
        let n = 2000;
        (0..=n)
            .map(|k| {
                let s = t * k as Real / n as Real;
                let y: [Vec3; 4] = std::array::from_fn(|i| x[i] + dx[i] * s);
                if pt {
                    point_triangle(&y).d2.sqrt()
                } else {
                    edge_edge(&y).d2.sqrt()
                }
            })
            .fold(Real::INFINITY, Real::min)
    }

    /// A point falling through a triangle: the safe fraction stops it above `d_min`, within
    /// the stop share of the exact time of impact with the offset, and the sampled path up to
    /// it never comes closer than `d_min`.
    #[test]
    fn a_point_falling_through_a_triangle_stops_above_the_offset() {
        let x = [
            Vec3::new(0.2, 0.2, 1.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let dx = [
            Vec3::new(0.0, 0.0, -2.0),
            Vec3::zeros(),
            Vec3::zeros(),
            Vec3::zeros(),
        ];
        let d_min = 0.1;
        let t = safe_fraction(&x, &dx, true, d_min, 1.0);
        // Impact with the offset at t* = (1 − 0.1)/2 = 0.45; stop within 10% of the margin.
        assert!(t < 0.45 && t > 0.45 - 0.1 * 0.45 - 1e-12, "t = {t}");
        assert!(brute_min(&x, &dx, true, t) >= d_min);
    }

    /// Edges that cross during the step, with a rotation (the bound must hold for motion that
    /// is not a translation); edges that move apart, and a pair too slow to reach the offset,
    /// take the whole step; a pair already inside the offset takes none.
    #[test]
    fn crossing_edges_stop_and_separating_edges_go() {
        let x = [
            Vec3::new(-1.0, 0.0, 0.5),
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let dx = [
            Vec3::new(0.0, 0.3, -1.0),
            Vec3::new(0.0, -0.3, -1.0),
            Vec3::zeros(),
            Vec3::zeros(),
        ];
        let t = safe_fraction(&x, &dx, false, 0.05, 1.0);
        assert!(t > 0.3 && t < 0.45, "t = {t}");
        assert!(brute_min(&x, &dx, false, t) >= 0.05);
        let up = dx.map(|d| -d);
        assert_eq!(safe_fraction(&x, &up, false, 0.05, 1.0), 1.0);
        let slow = dx.map(|d| d * 0.1);
        assert_eq!(safe_fraction(&x, &slow, false, 0.05, 1.0), 1.0);
        assert_eq!(safe_fraction(&x, &dx, false, 0.6, 1.0), 0.0);
    }

    /// Random pairs and motions: the returned fraction is always safe on a fine sampling of
    /// the path, and not needlessly short (when the sampled path never comes within `d_min`
    /// the whole step is returned or the stop share explains the difference).
    #[test]
    fn random_motions_are_always_safe() {
        let mut seed = 0x2545f4914f6cdd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as Real / (1u64 << 53) as Real - 0.5
        };
        let mut stopped = 0;
        for k in 0..300 {
            let pt = k % 2 == 0;
            let x: [Vec3; 4] = std::array::from_fn(|_| Vec3::new(rnd(), rnd(), rnd()));
            let dx: [Vec3; 4] = std::array::from_fn(|_| Vec3::new(rnd(), rnd(), rnd()) * 2.0);
            let d_min = 0.02;
            let t = safe_fraction(&x, &dx, pt, d_min, 1.0);
            let d0 = brute_min(&x, &dx, pt, 0.0);
            if d0 <= d_min {
                assert_eq!(t, 0.0);
                continue;
            }
            assert!(brute_min(&x, &dx, pt, t) >= d_min, "case {k}: t = {t}");
            stopped += usize::from(t < 1.0);
        }
        assert!(stopped > 10, "the random motions should include impacts");
    }
}
