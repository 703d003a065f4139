//! Contact in the explicit driver: per-vertex displacement bounds in place of Newton's
//! CCD-bounded steps.
//!
//! An explicit step has no line search to shorten, and CCD over every step would cost more than
//! the step itself. Instead, as offset geometric contact does (Chen et al. 2025, "Offset
//! Geometric Contact", §4), the contact pairs are gathered at some positions `X`, and each
//! vertex gets a radius `b_v` around `X_v`
//! ([`crate::energy::term::StepLimit::displacement_bounds`]): while every vertex stays within
//! its radius, no gathered pair comes closer than its floor (`s ξ`), and no pair that was not
//! gathered comes within reach of its law, so the gathered pairs' forces are the whole contact.
//!
//! After each step, a vertex that left its sphere is pulled back inside it (`x ← X + 0.9 b u/|u|`,
//! `u = x − X`), and its velocity loses the distance removed over the step, so that position
//! and velocity stay consistent (the truncation is inelastic). When a vertex would leave 0.9 of
//! its radius within three more steps like its last, the pairs are gathered again at the next
//! step's start, where they and the radii are measured afresh: a vertex is pulled back only
//! when its step grows threefold at once. Far from contact the radius is half the halo everywhere, and a
//! step costs one pass over the vertices beyond the no-contact step.
//!
//! Vertices on prescribed paths cannot be pulled back. When one leaves its sphere, the paths'
//! move of that step is checked by additive CCD over every pair the broad phase finds along
//! it ([`crate::energy::term::StepLimit::jump_fraction`]); if no pair comes below its floor,
//! the pairs are gathered again where the paths took the sheet, and otherwise the run stops,
//! naming the vertex: its path drives the sheet into itself or an obstacle.
//!
//! A frame's state is always a gathering's: the pairs are gathered again right after each
//! frame, so that a restart from a frame continues with the same pairs and radii, bit for bit.

use crate::integrate::{RunError, Solver};
use crate::math::{Real, Vec3};
use crate::solve::State;

/// The explicit driver's contact bounds: where the pairs were gathered, each vertex's radius,
/// and whether to gather again.
pub(super) struct Bounds {
    /// The positions the pairs were gathered at (m).
    at: Vec<Vec3>,
    /// How far each vertex may move from there (m; `+∞` where no term bounds it).
    room: Vec<Real>,
    /// Gather again before the next step.
    pub(super) stale: bool,
    /// Gatherings so far.
    pub(super) gathers: usize,
    /// Vertex steps pulled back onto their sphere so far.
    pub(super) clipped: usize,
}

impl Bounds {
    /// The bounds of a scene whose terms bound the steps (contact), else `None`.
    pub(super) fn of(s: &Solver, n: usize) -> Option<Bounds> {
        s.scene
            .terms
            .iter()
            .any(|t| t.step_limit().is_some())
            .then(|| Bounds {
                at: vec![Vec3::zeros(); n],
                room: vec![Real::INFINITY; n],
                stale: true,
                gathers: 0,
                clipped: 0,
            })
    }

    /// Gathers the pairs at `state` and dial `dial` (a new pattern when they changed) and
    /// measures every vertex's radius there.
    pub(super) fn gather(
        &mut self,
        s: &mut Solver,
        state: &State,
        dial: Real,
    ) -> Result<(), RunError> {
        s.refresh(state, dial)?;
        let pat = s.pattern();
        let pot = s.potential_at(&pat, dial, state);
        self.room.fill(Real::INFINITY);
        pot.displacement_bounds(&state.x, &mut self.room);
        self.at.copy_from_slice(&state.x);
        self.stale = false;
        self.gathers += 1;
        Ok(())
    }

    /// After the step's paths moved the vertices of `paths` (the prescribed ones) to `x`: the
    /// first that left its sphere, if any.
    pub(super) fn prescribed(&self, paths: &[usize], x: &[Vec3]) -> Option<usize> {
        paths
            .iter()
            .copied()
            .find(|&v| (x[v] - self.at[v]).norm_squared() > self.room[v] * self.room[v])
    }

    /// After a step `dt` (s) to `x` with velocities `v` (None for the gradient-descent start,
    /// whose velocities are discarded): pulls every free vertex (`inv_m > 0`) that left its
    /// sphere back inside it, to 0.9 of its radius, taking the distance removed off its
    /// velocity, and marks the pairs stale when a vertex would leave 0.9 of its radius within
    /// [`LOOKAHEAD`] more steps like this one (half its radius on the gradient-descent start).
    /// (Pulled onto the sphere itself, two vertices could end exactly at their pair's floor,
    /// where the next gathering would give them no room, not even to part; within 0.9 of it
    /// they keep a tenth of their room, which grows back as they part.)
    pub(super) fn clip(
        &mut self,
        x: &mut [Vec3],
        mut v: Option<&mut [Vec3]>,
        inv_m: &[Real],
        dt: Real,
    ) {
        let mut stale = false;
        for (i, xi) in x.iter_mut().enumerate() {
            let r = self.room[i];
            let u = *xi - self.at[i];
            let u2 = u.norm_squared();
            let ahead = match v.as_deref() {
                Some(v) => u2.sqrt() + LOOKAHEAD * dt * v[i].norm() > 0.9 * r,
                None => u2 > 0.25 * r * r,
            };
            stale |= ahead;
            if u2 > r * r && inv_m[i] > 0.0 {
                let pulled = self.at[i] + u * (0.9 * r / u2.sqrt());
                if let Some(v) = v.as_deref_mut() {
                    v[i] -= (*xi - pulled) / dt;
                }
                *xi = pulled;
                self.clipped += 1;
            }
        }
        self.stale |= stale;
    }
}

/// How many steps ahead [`Bounds::clip`] looks: a vertex is pulled back only when its step
/// grew more than that many times over in one step (a sudden impact the penalty could not
/// stop within a step).
const LOOKAHEAD: Real = 3.0;
