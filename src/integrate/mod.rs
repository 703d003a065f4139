//! Drivers, one per file or folder, and the dispatch between them ([`run`]):
//!
//! * `statics.rs`: static equilibrium by adaptive continuation of the dial factor, then membrane
//!   continuation (the dial runs with the stretching weight divided by c,
//!   `solver.membrane_continuation`, by default c = (L/10h)² with L the bounding-box diagonal, so
//!   that Newton's quadratic model holds for thin sheets making large rotations; the weight is
//!   then raised back to 1 by warm-started solves at dial 1), and the saddle check: an
//!   equilibrium is tested for stability (Cholesky of `H + δ·mean|diag|·I`, δ = 1e-9) and a
//!   saddle is perturbed again (amplitude ×10 each time) and re-solved, so a saddle is never
//!   reported as an equilibrium;
//! * `dynamics.rs`: implicit Euler with adaptive time steps, the friction lag (`friction.rs`)
//!   and the coupled moisture or temperature field (`transport.rs`);
//! * `explicit/`: MorphoShell's damped Newtonian dynamics, gradient only.
//!
//! They share the solver state (`solver.rs`: the pattern, the factorisation, Newton's workspace,
//! the summary, the frames), the step control and output timing (`StepControl`,
//! `OutputClock`, here), what a frame records for a restart (`resume.rs`), the run's controls
//! (`config.rs`), what stops a run (`failure.rs`) and the symmetry breaking of a planar start
//! (`symmetry.rs`: every free vertex moved along its normal by `symmetry_breaking × mean edge ×
//! u`, `u` uniform in [−1, 1) from a SplitMix64 stream seeded by `solver.seed`, deterministic).
//! Every driver calls Newton on a [`Potential`](crate::energy::Potential) and hands its frames
//! and summary to a [`Sink`] (`report.rs`: the records a run fills, the energies, and the sink
//! that [`crate::output::Writer`] implements).

mod arclength;
pub mod config;
mod dynamics;
pub mod explicit;
mod failure;
pub mod friction;
pub(crate) mod hooks;
pub mod report;
mod resume;
mod solver;
mod statics;
mod symmetry;
pub(crate) mod transport;

pub use arclength::check as check_continuation;
pub use failure::{catch_signals, interrupted, RunError, RunFailure};
pub use resume::{DriverState, InitialState};
pub use statics::{check_start, check_supports};
pub use symmetry::{is_planar, perturb, vertex_normals};

use failure::interruption;
use resume::Resume;
use solver::Solver;

use crate::math::Real;
use crate::model::Scene;
use crate::settings::{Continuation, Mode};
use crate::solve::State;
pub use report::{OutputError, Sink, Summary};

/// Receives progress updates (a terminal progress bar, or nothing).
pub trait Progress {
    /// Called after every accepted step with (progress in [0, 1], label).
    fn update(&mut self, fraction: Real, message: &str);
}

/// A progress sink that ignores everything.
pub struct Quiet;
impl Progress for Quiet {
    fn update(&mut self, _: Real, _: &str) {}
}

/// Adaptive step size, shared by the drivers (the dial increment of statics, the time step of
/// dynamics): halved from the step taken when a solve fails, grown ×`grow` (up to `max`) after
/// `easy_needed` consecutive easy steps (at most `easy_iterations` Newton iterations, and calm
/// by the driver's other criteria), and given up below `min`.
#[derive(Clone, Copy, Debug)]
pub(super) struct StepControl {
    /// The next step.
    pub step: Real,
    min: Real,
    max: Real,
    grow: Real,
    easy_iterations: usize,
    easy_needed: usize,
    easy: usize,
}

impl StepControl {
    pub fn new(
        step: Real,
        min: Real,
        max: Real,
        grow: Real,
        easy_iterations: usize,
        easy_needed: usize,
    ) -> Self {
        StepControl {
            step,
            min,
            max,
            grow,
            easy_iterations,
            easy_needed,
            easy: 0,
        }
    }

    /// Resumes a restart's step control: its next step (when given) and its count of easy
    /// steps.
    pub fn resume(&mut self, step: Option<Real>, easy: usize) {
        if let Some(h) = step.filter(|h| h.is_finite() && *h > 0.0) {
            self.step = h.clamp(self.min, self.max);
        }
        self.easy = easy.min(self.easy_needed);
    }

    /// Easy steps counted towards the next growth.
    pub fn easy(&self) -> usize {
        self.easy
    }

    /// After an accepted step that took `iterations` Newton iterations.
    pub fn accepted(&mut self, iterations: usize, calm: bool) {
        if iterations <= self.easy_iterations && calm {
            self.easy += 1;
            if self.easy >= self.easy_needed {
                self.step = (self.step * self.grow).min(self.max);
                self.easy = 0;
            }
        } else {
            self.easy = 0;
        }
    }

    /// After a failed step of length `taken`: the next one is half of it. Returns `false` when
    /// that falls below the minimum (the run stops).
    pub fn rejected(&mut self, taken: Real) -> bool {
        self.step = taken * 0.5;
        self.easy = 0;
        self.step >= self.min
    }
}

/// Output times on a fixed grid of `interval` up to `end`, resumed on the grid after a restart.
/// The k-th output time is `k × interval`, computed afresh (not summed), so a restarted run
/// has the same output times, to the bit, as the uninterrupted one.
#[derive(Clone, Copy, Debug)]
pub(super) struct OutputClock {
    /// The next output time.
    pub next: Real,
    /// Its index on the grid.
    k: Real,
    interval: Real,
    end: Real,
}

impl OutputClock {
    /// The clock of a run starting at `t0`.
    pub fn new(t0: Real, interval: Real, end: Real) -> Self {
        let k = ((t0 / interval) + 1e-9).floor() + 1.0;
        OutputClock {
            next: (k * interval).min(end),
            k,
            interval,
            end,
        }
    }

    /// Whether time `t`, reached by a step `h`, is an output time (within round-off: 1e-9 of
    /// the step, at least `eps`).
    pub fn due(&self, t: Real, h: Real, eps: Real) -> bool {
        t >= self.next - 1e-9 * h.max(eps)
    }

    /// Moves the next output time past `t`, reached by a step `h` (with [`Self::due`]'s
    /// tolerance, so that an output time just ahead of `t` by round-off is passed too).
    pub fn passed(&mut self, t: Real, h: Real, eps: Real) {
        let tol = 1e-9 * h.max(eps);
        while self.next <= t + tol && self.next < self.end {
            self.k += 1.0;
            self.next = (self.k * self.interval).min(self.end);
        }
    }

    /// The step to take from `t` given the step control's `step`: `step`, shortened to land on
    /// the next output time, or stretched by up to 1% to land on it instead of leaving a sliver
    /// (a step of round-off size, which an implicit solve cannot resolve).
    pub fn step_from(&self, t: Real, step: Real) -> Real {
        let left = self.next - t;
        if left <= 1.01 * step {
            left
        } else {
            step
        }
    }
}

/// Runs a scene to completion from the reference mesh, or from `initial` (a restart), writing
/// frames, the log and the summary.
pub fn run(
    scene: &Scene,
    writer: &mut dyn Sink,
    progress: &mut dyn Progress,
    threads: usize,
    initial: Option<InitialState>,
) -> Result<Summary, RunError> {
    let mut s = Solver::new(scene, threads)?;
    let (mut state, v, start, dial, driver) = match initial {
        Some(st) => (st.state, st.v, Some(st.time), st.dial, st.driver),
        None => (State::reference(scene), None, None, None, None),
    };
    // A driver state of another mode (a static frame restarting a dynamic run) only gives
    // what the frame gives.
    let driver = driver.filter(|d| d.mode == s.summary.mode);
    if let Some(d) = &driver {
        s.ws.set_model_hints(d.model_hints);
        for t in scene.terms.iter() {
            if let (Some(s), Some(v)) = (t.stateful(), d.terms.get(t.name())) {
                s.check_state(v)
                    .map_err(|e| RunError::Restart(format!("the {}'s state: {e}", t.name())))?;
                state.terms.set(t.name(), v.clone());
            }
        }
    }
    let sb = s.config.symmetry_breaking;
    // A restart with its driver's state continues the state it is given, planar or not,
    // unless that state is a planar start the run perturbed right after writing it.
    let pending = driver.as_ref().is_none_or(|d| d.perturb_pending);
    if sb > 0.0 && pending && is_planar(scene, &state.x) {
        // The first frame shows the reference state; the drivers start from the perturbed one.
        s.reference = Some(state.clone());
        let amplitude = sb * scene.body.mean_edge;
        let mut moved = state.x.clone();
        perturb(scene, &mut moved, amplitude, s.config.seed);
        // Contact bounds the perturbation like any step: sheets stacked closer than the
        // amplitude (or a barrier's activation distance) keep their order and separation.
        let fraction = if scene.terms.iter().any(|t| t.step_limit().is_some()) {
            let at = dial.or(start).unwrap_or(0.0).clamp(0.0, 1.0);
            let pat = s.pattern();
            s.potential(&pat, at)
                .jump_fraction(&state.x, &moved, &state.dofs, at)
        } else {
            1.0
        };
        if fraction >= 1.0 {
            state.x = moved;
        } else {
            for (x, m) in state.x.iter_mut().zip(&moved) {
                *x += (m - *x) * fraction;
            }
        }
        s.summary.symmetry_breaking = Some(amplitude * fraction.min(1.0));
    }
    let ran = match s.config.mode {
        Mode::Static if scene.settings.solver.continuation == Continuation::ArcLength => {
            arclength::run_arc_length(&mut s, writer, progress, state, dial.or(start), driver)
        }
        Mode::Static => statics::run_static(&mut s, writer, progress, state, dial.or(start)),
        Mode::Dynamic | Mode::Explicit => {
            let from = Resume {
                v,
                t0: start.unwrap_or(0.0),
                dial,
                driver,
            };
            if s.config.mode == Mode::Dynamic {
                dynamics::run_dynamic(&mut s, writer, progress, state, from)
            } else {
                explicit::run_explicit(&mut s, writer, progress, state, from)
            }
        }
    };
    match ran {
        Ok(()) => {}
        // A state that would put NaN or infinity into a frame ends the run (exit 1) with the
        // last good frame and a summary saying where.
        Err(RunError::Output(e @ OutputError::NonFinite { .. })) => {
            s.summary.converged = false;
            s.summary.reason = format!(
                "{e}; the run stopped{}",
                match writer.num_frames() {
                    0 => String::from(" before its first frame"),
                    _ => format!(", last good frame {}", writer.last_frame()),
                }
            );
        }
        // An output failure mid-run (a full disk): the frames, series and log written so far
        // stay in step; a summary saying why is written if there is still room for it.
        Err(RunError::Output(e @ OutputError::Io { .. })) => {
            writer.release_reserve();
            s.summary.converged = false;
            s.summary.reason = format!("output failed: {e}");
            s.summary.wall_seconds = s.start.elapsed().as_secs_f64();
            s.summary.frames = writer.num_frames();
            s.summary.final_frame = writer.last_frame();
            s.summary.refuse_non_finite();
            let _ = writer.summary(&s.summary);
            return Err(RunError::Output(e));
        }
        Err(e) => return Err(e),
    }
    s.summary.wall_seconds = s.start.elapsed().as_secs_f64();
    s.summary.frames = writer.num_frames();
    s.summary.final_frame = writer.last_frame();
    let t = &mut s.summary.timing;
    t.diffusion = s.summary.moisture_seconds;
    t.build = scene.build_seconds;
    let n = t.newton;
    t.other = (s.summary.wall_seconds
        - (t.build
            + t.analysis
            + n.assembly
            + n.factorisation
            + n.solve
            + n.line_search
            + t.diffusion
            + t.output))
        .max(0.0);
    s.summary.linear_system = s.linear_system_report();
    s.summary.refuse_non_finite();
    writer.summary(&s.summary)?;
    Ok(s.summary)
}

/// Checks what the scene's driver needs before anything is written (the explicit driver's
/// bounds, [`explicit::check`]); the error names the mesh file.
pub fn check_scene(scene: &Scene) -> Result<(), crate::mesh::MeshError> {
    if scene.settings.solver.mode == crate::settings::Mode::Explicit {
        explicit::check(scene).map_err(|r| scene.body.mesh.invalid(r))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{OutputClock, StepControl};

    #[test]
    fn step_control_halves_grows_and_gives_up() {
        let mut s = StepControl::new(0.1, 0.01, 0.3, 1.5, 3, 2);
        s.accepted(3, true);
        assert_eq!(s.step, 0.1, "one easy step is not enough");
        s.accepted(4, true);
        s.accepted(3, true);
        assert_eq!(s.step, 0.1, "a hard step resets the count");
        s.accepted(1, false);
        s.accepted(1, true);
        assert_eq!(s.step, 0.1, "a step that is not calm resets the count");
        s.accepted(1, true);
        assert!((s.step - 0.15).abs() < 1e-15);
        for _ in 0..10 {
            s.accepted(1, true);
        }
        assert_eq!(s.step, 0.3, "capped at the maximum");
        // Halved from the step taken (shortened to land on an output time, say).
        assert!(s.rejected(0.04));
        assert_eq!(s.step, 0.02);
        assert!(!s.rejected(0.015), "0.0075 is below the minimum");
    }

    #[test]
    fn output_clock_resumes_the_grid_and_lands_on_the_end() {
        let mut c = OutputClock::new(0.0, 0.1, 0.25);
        assert!((c.next - 0.1).abs() < 1e-15);
        assert!(!c.due(0.05, 0.05, 1e-12));
        assert!(c.due(0.1, 0.05, 1e-12));
        c.passed(0.1, 0.05, 1e-12);
        assert!((c.next - 0.2).abs() < 1e-12);
        c.passed(0.2, 0.05, 1e-12);
        assert_eq!(c.next, 0.25, "the last output is at the end");
        // Steps of 0.0333333333 s: the third is stretched to land on 0.1 instead of leaving a
        // 1e-10 s sliver, which an implicit solve cannot resolve.
        let mut c = OutputClock::new(0.0, 0.1, 1.0);
        let t = 2.0 * 0.0333333333;
        let h = c.step_from(t, 0.0333333333);
        assert_eq!(h, c.next - t);
        assert!(c.due(t + h, h, 1e-12));
        // An output reached within round-off is passed (the next one is 0.2, not 0.1).
        let t = 0.1 - 1e-11;
        assert!(c.due(t, 0.0333333333, 1e-12));
        c.passed(t, 0.0333333333, 1e-12);
        assert!((c.next - 0.2).abs() < 1e-12);
        assert_eq!(c.step_from(t, 0.0333333333), 0.0333333333);
        // A step that would leave a sliver before the output is stretched to it.
        let c = OutputClock::new(0.0, 0.1, 1.0);
        assert_eq!(c.step_from(0.0667, 0.0333), c.next - 0.0667);
        // A restart at 0.3 of a grid of 0.1 resumes at 0.4.
        let c = OutputClock::new(0.3, 0.1, 1.0);
        assert!((c.next - 0.4).abs() < 1e-12);
    }
}
