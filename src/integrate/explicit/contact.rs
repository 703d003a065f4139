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
//! A mesh obstacle that moves with the dial cannot be pulled back either. Its radius is the
//! dial's: it may move half the halo, and half the room of each gathered pair it is part of
//! (the sheet's vertices take the other half), from where the pairs were gathered
//! ([`crate::energy::term::StepLimit::dial_room`]). The pairs are gathered again before the
//! dial would use 0.9 of that room within three more steps; when one step's dial moves it
//! further, its move from the last step's dial is checked by additive CCD, and either the pairs
//! are gathered again there or the run stops, naming the obstacle.
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
    /// The dial they were gathered at.
    dial: Real,
    /// How far the dial may move from there with what moves with it (a mesh obstacle; `+∞`
    /// when nothing does).
    dial_room: Real,
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
                dial: 0.0,
                dial_room: Real::INFINITY,
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
        self.dial_room = pot.dial_room(&state.x);
        self.dial = dial;
        self.at.copy_from_slice(&state.x);
        self.stale = false;
        self.gathers += 1;
        Ok(())
    }

    /// Before a step at dial `dial`, the last one's at `last`, with the sheet at `state`: when
    /// what moves with the dial (a mesh obstacle) has left its room from where the pairs were
    /// gathered, checks its move from `last` (where it was within its room, and the sheet
    /// within its radii: an admissible state) to `dial` by additive CCD over every pair the
    /// broad phase finds along it, and gathers the pairs again at `dial`, or returns why the
    /// run stops at time `t`: the move would bring a pair below its floor (the run then ends
    /// at `last`). When it would leave 0.9 of its room within [`LOOKAHEAD`] more steps like
    /// the last, marks the pairs stale.
    pub(super) fn dialled(
        &mut self,
        s: &mut Solver,
        state: &State,
        dial: Real,
        last: Real,
        t: Real,
    ) -> Result<Option<String>, RunError> {
        let moved = (dial - self.dial).abs();
        if moved > self.dial_room {
            let pat = s.pattern();
            let pot = s.potential_at(&pat, dial, state);
            if pot.jump_fraction(&state.x, &state.x, &state.dofs, last) < 1.0 {
                let moving: Vec<String> = s
                    .scene
                    .settings
                    .obstacles
                    .iter()
                    .enumerate()
                    .filter(|(_, o)| {
                        o.shape == Some(crate::config::obstacle::ShapeKind::Mesh)
                            && o.displacement.iter().any(|&c| c != 0.0)
                    })
                    .map(|(i, _)| format!("obstacles[{i}]"))
                    .collect();
                return Ok(Some(format!(
                    "the mesh obstacle moving with the dial ({}) would drive the sheet within \
                     self_contact.min_separation of it at t = {} s, as the dial moves from \
                     {last:.9} to {dial:.9}; the state written is the last one before",
                    moving.join(", "),
                    crate::math::human(t),
                )));
            }
            self.gather(s, state, dial)?;
        } else if moved + LOOKAHEAD * (dial - last).abs() > 0.9 * self.dial_room {
            self.stale = true;
        }
        Ok(None)
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
