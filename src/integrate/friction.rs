//! The friction lag of a dynamic step: Coulomb friction needs the normal contact force, which
//! the step's own solution sets. The step is solved with the lagged forces `λ`, `λ` is updated
//! from the solution, and the step is re-solved until `λ` changes by at most
//! [`FRICTION_LAG_TOL`] of its largest entry or [`FRICTION_LAG_MAX`] solves were made (the last
//! one is accepted). `λ` carries over to the next step, so a resting contact needs one solve
//! per step. The ground's `λ` is kept per vertex; an obstacle's normal force and normal are taken
//! at the lagged iterate's positions and dial, which the lag keeps. See [`crate::contact`] for the friction potential.

use crate::energy::potential::Friction;
use crate::math::{Real, Vec3};
use crate::model::Scene;

/// `λ` has converged when it changes by at most this fraction of its largest entry ...
pub const FRICTION_LAG_TOL: Real = 1e-3;
/// ... or after this many solves of one step.
pub const FRICTION_LAG_MAX: usize = 6;

/// The lagged normal forces of a scene with friction: the ground's per vertex, and the
/// positions and dial of the friction iterate that the frictional terms (the obstacles,
/// [`crate::energy::term::LaggedNormals`]) take their normal forces and normals at.
pub struct FrictionLag {
    /// Normal contact force per vertex against a frictional ground (N), lagged; empty without.
    lambda: Vec<Real>,
    /// Positions of the lagged iterate (m).
    x_lag: Vec<Vec3>,
    /// Dial of the lagged iterate.
    dial_lag: Real,
    /// The lag the last solve used (`lambda`, `x_lag`, `dial_lag` before its update): the
    /// friction forces of the accepted step.
    solved: (Vec<Real>, Vec<Vec3>, Real),
    /// Slip speed ε_v of the smoothed friction (m/s).
    slip_speed: Real,
    /// Solves of the current step.
    solves: usize,
}

impl FrictionLag {
    /// The lag of `scene` started at positions `x` and dial `dial`, with the smoothed
    /// friction's slip speed (`contact.slip_speed`, m/s), or `None` without a frictional ground
    /// or obstacle.
    pub fn new(scene: &Scene, x: &[Vec3], dial: Real, slip_speed: Real) -> Option<FrictionLag> {
        let ground = scene.body.ground.as_ref().filter(|g| g.friction > 0.0);
        let lagged = scene.terms.iter().any(|t| t.lagged().is_some());
        if ground.is_none() && !lagged {
            return None;
        }
        let lambda = ground.map_or_else(Vec::new, |g| g.normal_forces(x));
        Some(FrictionLag {
            solved: (lambda.clone(), x.to_vec(), dial),
            lambda,
            x_lag: x.to_vec(),
            dial_lag: dial,
            slip_speed,
            solves: 0,
        })
    }

    /// Starts a new step (its solve count).
    pub fn start_step(&mut self) {
        self.solves = 0;
    }

    /// The friction term of a step of length `h` from `x_prev` at dial `dial_prev`, with the
    /// current lag.
    pub fn friction<'a>(&'a self, x_prev: &'a [Vec3], dial_prev: Real, h: Real) -> Friction<'a> {
        Friction {
            x_prev,
            dial_prev,
            normal_force: &self.lambda,
            x_lag: &self.x_lag,
            dial_lag: self.dial_lag,
            eps: self.slip_speed * h,
        }
    }

    /// The friction term of the last solve (the lag it used) over the step of length `h` from
    /// `x_prev` at dial `dial_prev`: at the accepted state, its forces are the friction forces
    /// that balance the step (the frames report them).
    pub fn solved<'a>(&'a self, x_prev: &'a [Vec3], dial_prev: Real, h: Real) -> Friction<'a> {
        Friction {
            x_prev,
            dial_prev,
            normal_force: &self.solved.0,
            x_lag: &self.solved.1,
            dial_lag: self.solved.2,
            eps: self.slip_speed * h,
        }
    }

    /// Updates the lag from a converged solve at `trial` and dial `dial`. Returns whether the
    /// step must be solved again (a normal force moved by more than the tolerance of the
    /// largest, and the solve limit is not reached).
    pub fn resolve(&mut self, scene: &Scene, trial: &[Vec3], dial: Real) -> bool {
        self.solves += 1;
        self.solved.0.clone_from(&self.lambda);
        self.solved.1.copy_from_slice(&self.x_lag);
        self.solved.2 = self.dial_lag;
        let (mut scale, mut diff) = (0.0 as Real, 0.0 as Real);
        if let Some(g) = scene
            .body
            .ground
            .as_ref()
            .filter(|_| !self.lambda.is_empty())
        {
            let new = g.normal_forces(trial);
            scale = new.iter().fold(scale, |m, v| m.max(*v));
            diff = new
                .iter()
                .zip(&self.lambda)
                .fold(diff, |m, (a, b)| m.max((a - b).abs()));
            self.lambda = new;
        }
        // The terms whose friction lags its normal forces (the frictional obstacles).
        for t in scene.terms.iter().filter_map(|t| t.lagged()) {
            let (s, d) = t.lag_change(trial, dial, &self.x_lag, self.dial_lag);
            scale = scale.max(s);
            diff = diff.max(d);
        }
        self.x_lag.copy_from_slice(trial);
        self.dial_lag = dial;
        diff > FRICTION_LAG_TOL * scale && self.solves < FRICTION_LAG_MAX
    }
}
