//! `[time]`: dynamic mode's time stepping: end, steps, frames, damping and the equilibrium
//! stop.

use super::limits::{MAX_FRAMES, MAX_STEPS};
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Time stepping for dynamic mode.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Time {
    /// End time (s, default: `1.0`).
    pub end: Real,
    /// First time step (s, default: `1e-3`).
    pub dt: Real,
    /// Smallest time step before the run stops unconverged (s, default: `1e-9`).
    pub dt_min: Real,
    /// Largest time step (s, default: `0.1`).
    pub dt_max: Real,
    /// Interval between output frames (s, default: `0.1`).
    pub output_interval: Real,
    /// Kelvin–Voigt retardation time η of seed 000's damping potential (s, default: `0` = off).
    pub damping: Real,
    /// Stop early when the residual without inertia is below tolerance and the kinetic energy is
    /// below `equilibrium_kinetic` × elastic energy (default: `false`).
    pub stop_at_equilibrium: bool,
    /// Relative kinetic-energy threshold for `stop_at_equilibrium` (dimensionless, default: `1e-10`).
    pub equilibrium_kinetic: Real,
}

impl Default for Time {
    fn default() -> Self {
        Time {
            end: 1.0,
            dt: 1e-3,
            dt_min: 1e-9,
            dt_max: 0.1,
            output_interval: 0.1,
            damping: 0.0,
            stop_at_equilibrium: false,
            equilibrium_kinetic: 1e-10,
        }
    }
}

impl Time {
    /// Validates `[time]`: positive times, `dt_min ≤ dt ≤ dt_max`.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let t = self;
        ck.pos("time.end", t.end)?;
        ck.pos("time.dt", t.dt)?;
        ck.pos("time.dt_min", t.dt_min)?;
        ck.pos("time.dt_max", t.dt_max)?;
        ck.pos("time.output_interval", t.output_interval)?;
        ck.nonneg("time.damping", t.damping)?;
        ck.pos("time.equilibrium_kinetic", t.equilibrium_kinetic)?;
        if t.dt_min > t.dt || t.dt > t.dt_max {
            return ck.inv(
                "time.dt",
                format!(
                    "need dt_min ≤ dt ≤ dt_max, got {} ≤ {} ≤ {}",
                    crate::math::human(t.dt_min),
                    crate::math::human(t.dt),
                    crate::math::human(t.dt_max)
                ),
            );
        }
        // Bounds on the work a run can ask for: steps at the largest step, and frames.
        let steps = t.end / t.dt_max;
        if steps > MAX_STEPS {
            return ck.inv(
                "time.end",
                format!(
                    "{} s at steps of at most time.dt_max = {} s is {steps_h} steps, more \
                     than {MAX_STEPS_h}; raise time.dt_max or lower time.end",
                    crate::math::human(t.end),
                    crate::math::human(t.dt_max),
                    steps_h = crate::math::human(steps),
                    MAX_STEPS_h = crate::math::human(MAX_STEPS)
                ),
            );
        }
        let frames = t.end / t.output_interval;
        if frames > MAX_FRAMES {
            return ck.inv(
                "time.output_interval",
                format!(
                    "{} s between frames over {} s is {frames_h} frames, more than \
                     {MAX_FRAMES_h}",
                    crate::math::human(t.output_interval),
                    crate::math::human(t.end),
                    frames_h = crate::math::human(frames),
                    MAX_FRAMES_h = crate::math::human(MAX_FRAMES)
                ),
            );
        }
        if t.output_interval < t.dt_min {
            return ck.inv(
                "time.output_interval",
                format!(
                    "{} s is below time.dt_min = {} s: frames cannot be closer than the \
                     smallest step",
                    crate::math::human(t.output_interval),
                    crate::math::human(t.dt_min)
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults pass; each bound names its key.
    #[test]
    fn steps_and_frames_are_bounded() {
        assert_eq!(Time::default().validate(), Ok(()));
        let bad = |t: Time| t.validate().unwrap_err().key;
        let d = Time::default;
        assert_eq!(bad(Time { end: 0.0, ..d() }), "time.end");
        assert_eq!(
            bad(Time {
                damping: -1.0,
                ..d()
            }),
            "time.damping"
        );
        // dt_min ≤ dt ≤ dt_max.
        assert_eq!(bad(Time { dt: 1.0, ..d() }), "time.dt");
        // More than MAX_STEPS steps at the largest step.
        assert_eq!(
            bad(Time {
                end: 1e9,
                dt_max: 0.1,
                output_interval: 1e6,
                ..d()
            }),
            "time.end"
        );
        // More than MAX_FRAMES frames.
        assert_eq!(
            bad(Time {
                end: 10.0,
                output_interval: 1e-6,
                ..d()
            }),
            "time.output_interval"
        );
        // Frames closer than the smallest step.
        assert_eq!(
            bad(Time {
                output_interval: 1e-10,
                end: 1e-5,
                ..d()
            }),
            "time.output_interval"
        );
    }
}
