//! `[explicit]`: MorphoShell's explicit damped dynamics: time step, damping, dialling, frames
//! and the equilibrium test.

use super::limits::{MAX_FRAMES, MAX_STEPS};
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Which equilibrium test stops an explicit run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EquilibriumTest {
    /// The force residual relative to the force scale, the kinetic energy, and the changes of
    /// the energy and of the shape over a window of time (cannot fire while the shape moves).
    #[default]
    Window,
    /// MorphoShell's: the largest node force below a fraction of μ t a_min and the largest node
    /// speed below a fraction of √(μ/ρ), checked once per check interval.
    Morphoshell,
}

/// Explicit damped dynamics (MorphoShell's integrator; [`crate::integrate`]'s explicit driver).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Explicit {
    /// The time step's prefactor p in `dt = p · min(0.185 √(ρ/μ) a_min, √(ρt/D) a_min²/2π)`
    /// (default: `0.8`, MorphoShell's common value; the run reports the mesh's stability limit).
    pub time_step_prefactor: Real,
    /// Damping while the forms are dialled, as a multiple of the critical damping of the longest
    /// bending mode (default: `1.0`).
    pub damping_prefactor_dial: Real,
    /// Damping while waiting for equilibrium (default: `1.0`).
    pub damping_prefactor_wait: Real,
    /// Time to dial the forms from 0 to 1, in long times (default: `1.0`).
    pub dial_long_times: Real,
    /// Steps of gradient-descent (overdamped) dynamics before the Newtonian dynamics (default: `0`).
    pub gradient_descent_steps: usize,
    /// Frames per long time (default: `10`).
    pub frames_per_long_time: Real,
    /// The run stops, unconverged, after this many long times (default: `1000`).
    pub max_long_times: Real,
    /// `"window"` (default) or `"morphoshell"`.
    pub equilibrium: EquilibriumTest,
    /// Window test: the force residual ‖∇E‖∞ / F must be below this (default: `1e-7`).
    pub force_tolerance: Real,
    /// Window test: the largest vertex displacement over a window, over the sheet's size, must be
    /// below this (default: `1e-7`).
    pub shape_tolerance: Real,
    /// Window test: the relative change of the elastic energy over a window (default: `1e-7`).
    pub energy_tolerance: Real,
    /// The window (and MorphoShell's check interval), in long times (default: `0.01`).
    pub window_long_times: Real,
    /// MorphoShell's test: largest force / (μ t a_min) (default: `1e-6`).
    pub morphoshell_force_threshold: Real,
    /// MorphoShell's test: largest speed / √(μ/ρ) (default: `1e-5`).
    pub morphoshell_speed_threshold: Real,
}

impl Default for Explicit {
    fn default() -> Self {
        Explicit {
            time_step_prefactor: 0.8,
            damping_prefactor_dial: 1.0,
            damping_prefactor_wait: 1.0,
            dial_long_times: 1.0,
            gradient_descent_steps: 0,
            frames_per_long_time: 10.0,
            max_long_times: 1000.0,
            equilibrium: EquilibriumTest::Window,
            force_tolerance: 1e-7,
            shape_tolerance: 1e-7,
            energy_tolerance: 1e-7,
            window_long_times: 0.01,
            morphoshell_force_threshold: 1e-6,
            morphoshell_speed_threshold: 1e-5,
        }
    }
}

impl Explicit {
    /// Validates `[explicit]`: positive prefactors, tolerances and times, bounded frames.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let e = self;
        ck.pos("explicit.time_step_prefactor", e.time_step_prefactor)?;
        ck.nonneg("explicit.damping_prefactor_dial", e.damping_prefactor_dial)?;
        ck.nonneg("explicit.damping_prefactor_wait", e.damping_prefactor_wait)?;
        ck.nonneg("explicit.dial_long_times", e.dial_long_times)?;
        ck.pos("explicit.frames_per_long_time", e.frames_per_long_time)?;
        ck.pos("explicit.max_long_times", e.max_long_times)?;
        ck.pos("explicit.force_tolerance", e.force_tolerance)?;
        ck.pos("explicit.shape_tolerance", e.shape_tolerance)?;
        ck.pos("explicit.energy_tolerance", e.energy_tolerance)?;
        ck.pos("explicit.window_long_times", e.window_long_times)?;
        ck.pos(
            "explicit.morphoshell_force_threshold",
            e.morphoshell_force_threshold,
        )?;
        ck.pos(
            "explicit.morphoshell_speed_threshold",
            e.morphoshell_speed_threshold,
        )?;
        if e.window_long_times > e.max_long_times {
            return ck.inv(
                "explicit.window_long_times",
                format!(
                    "a window of {} long times is longer than the run's limit, \
                     explicit.max_long_times = {}: the equilibrium test could never run",
                    crate::math::human(e.window_long_times),
                    crate::math::human(e.max_long_times)
                ),
            );
        }
        if e.gradient_descent_steps as Real > MAX_STEPS {
            return ck.inv(
                "explicit.gradient_descent_steps",
                format!(
                    "{} steps is more than {MAX_STEPS_h}",
                    e.gradient_descent_steps,
                    MAX_STEPS_h = crate::math::human(MAX_STEPS)
                ),
            );
        }
        if e.max_long_times * e.frames_per_long_time > MAX_FRAMES {
            return ck.inv(
                "explicit.frames_per_long_time",
                format!(
                    "{} frames per long time over {} long times is more than {MAX_FRAMES_h} frames",
                    e.frames_per_long_time,
                    e.max_long_times,
                    MAX_FRAMES_h = crate::math::human(MAX_FRAMES)
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults pass; a non-positive prefactor or tolerance, or too many frames, names its
    /// key.
    #[test]
    fn prefactors_and_frames_are_checked() {
        assert_eq!(Explicit::default().validate(), Ok(()));
        let bad = |e: Explicit| e.validate().unwrap_err().key;
        let d = Explicit::default;
        assert_eq!(
            bad(Explicit {
                time_step_prefactor: 0.0,
                ..d()
            }),
            "explicit.time_step_prefactor"
        );
        assert_eq!(
            bad(Explicit {
                force_tolerance: Real::NAN,
                ..d()
            }),
            "explicit.force_tolerance"
        );
        assert_eq!(
            bad(Explicit {
                frames_per_long_time: 1e9,
                max_long_times: 1e9,
                ..d()
            }),
            "explicit.frames_per_long_time"
        );
    }
}
