//! The friction lag of a dynamic step: Coulomb friction needs the normal contact force, which
//! the step's own solution sets. The step is solved with the lagged forces `λ`, `λ` is updated
//! from the solution, and the step is re-solved until `λ` changes by at most
//! [`FRICTION_LAG_TOL`] of its largest entry or [`FRICTION_LAG_MAX`] solves were made (the last
//! one is accepted). `λ` carries over to the next step, so a resting contact needs one solve
//! per step. See [`crate::solve::contact`] for the friction potential.

use crate::math::{Real, Vec3};
use crate::scene::Scene;
use crate::solve::potential::Friction;

/// `λ` has converged when it changes by at most this fraction of its largest entry ...
pub const FRICTION_LAG_TOL: Real = 1e-3;
/// ... or after this many solves of one step.
pub const FRICTION_LAG_MAX: usize = 6;

/// The lagged normal forces of a scene with friction.
pub struct FrictionLag {
    /// Normal contact force per vertex (N), lagged.
    lambda: Vec<Real>,
    /// Slip speed ε_v of the smoothed friction (m/s).
    slip_speed: Real,
    /// Solves of the current step.
    solves: usize,
}

impl FrictionLag {
    /// The lag of `scene` started at positions `x`, with the smoothed friction's slip speed
    /// (`contact.slip_speed`, m/s), or `None` without a frictional ground.
    pub fn new(scene: &Scene, x: &[Vec3], slip_speed: Real) -> Option<FrictionLag> {
        let g = scene.ground.as_ref().filter(|g| g.friction > 0.0)?;
        Some(FrictionLag {
            lambda: g.normal_forces(x),
            slip_speed,
            solves: 0,
        })
    }

    /// Starts a new step (its solve count).
    pub fn start_step(&mut self) {
        self.solves = 0;
    }

    /// The friction term of a step of length `h` from `x_prev`, with the current `λ`.
    pub fn friction<'a>(&'a self, x_prev: &'a [Vec3], h: Real) -> Friction<'a> {
        Friction {
            x_prev,
            normal_force: &self.lambda,
            eps: self.slip_speed * h,
        }
    }

    /// Updates `λ` from a converged solve at `trial`. Returns whether the step must be solved
    /// again (λ moved by more than the tolerance and the solve limit is not reached).
    pub fn resolve(&mut self, scene: &Scene, trial: &[Vec3]) -> bool {
        let Some(g) = scene.ground.as_ref() else {
            return false;
        };
        self.solves += 1;
        let new = g.normal_forces(trial);
        let scale = new.iter().fold(0.0, |m: Real, v| m.max(*v));
        let diff = new
            .iter()
            .zip(&self.lambda)
            .fold(0.0, |m: Real, (a, b)| m.max((a - b).abs()));
        self.lambda = new;
        diff > FRICTION_LAG_TOL * scale && self.solves < FRICTION_LAG_MAX
    }
}
