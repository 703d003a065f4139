//! Drivers: static equilibrium by adaptive continuation of the dial factor, and implicit-Euler
//! dynamics with adaptive time steps.
//!
//! Membrane continuation (statics): the dial continuation runs with the stretching weight
//! divided by c (`solver.membrane_continuation`, by default c = (L/10h)² with L the mesh's
//! bounding-box diagonal), which makes the sheet effectively √c times thicker relative to its
//! bending, as stiff as a plate of thickness L/10; then the weight is raised back to 1 by
//! warm-started solves at dial 1 (×10, then ×100 after an easy solve; a failed solve takes the
//! square root of the ratio). Newton's quadratic model is poor for thin sheets making large rotations (stiff
//! stretching, soft bending): measured on the 13.5k-face Gauss–Codazzi–Mainardi cone, 269 Newton
//! iterations without it, 17 with it, the same equilibrium to 1e-7. Both call Newton on a [`Potential`] and write frames
//! through an [`output::Writer`](crate::output::Writer).
//!
//! Symmetry breaking: a perfectly flat start is a saddle for many programmed shapes (a metric
//! that asks for a cone, for one). When the initial sheet is exactly planar, every free vertex is
//! moved along the vertex normal by `symmetry_breaking × mean edge × u`, `u` uniform in [−1, 1)
//! from a SplitMix64 stream seeded by `solver.seed`: deterministic and reproducible. After a
//! static solve, the equilibrium is tested for stability (Cholesky of `H + δ·mean|diag|·I`,
//! δ = 1e-9, which fails iff H has an eigenvalue below −δ·mean|diag|); a saddle is perturbed again
//! (amplitude ×10 each time) and re-solved. A saddle is never reported as an equilibrium.

//!
//! One driver per file: `statics.rs` (continuation of the dial, membrane continuation, saddle
//! check) and `dynamics.rs` (implicit Euler with adaptive steps), over the shared solver state,
//! step control, output timing, frame output and counters here; `moisture.rs` couples the
//! moisture diffusion to the rest forms of a dynamic run, and `friction.rs` is the lag of the
//! frictional normal forces.

pub mod config;
mod dynamics;
pub mod explicit;
pub mod friction;
pub(crate) mod moisture;
mod statics;

use crate::assembly::{Pattern, Want};
use crate::math::{Real, Vec3};
use crate::mesh::generate::Rng;
use crate::output::{LogRow, OutputError, Summary, Writer};
use crate::scene::Scene;
use crate::settings::Mode;
use crate::solve::linear::LinearError;
use crate::solve::newton::Workspace;
use crate::solve::{
    newton, LinearSolver, NewtonOptions, NewtonReport, Potential, SolveError, State,
};
use std::time::Instant;

/// Errors that stop a run (as opposed to non-convergence, which is reported in the summary).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunError {
    /// Output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The linear solver could not be set up.
    #[error(transparent)]
    Linear(#[from] LinearError),
    /// The moisture state made the rest forms invalid.
    #[error("moisture: {0}")]
    Growth(#[from] crate::rest::laws::GrowthError),
    /// The moisture boundary conditions contradict each other.
    #[error("moisture: {0}")]
    Surface(#[from] crate::diffusion::SurfaceError),
    /// The moisture regions or fields are invalid.
    #[error("moisture: {0}")]
    Regions(#[from] crate::mesh::MeshError),
    /// A restart's driver state does not fit the scene.
    #[error("restart: {0}")]
    Restart(String),
    /// The scene asks for something its driver does not do.
    #[error("{0}")]
    Unsupported(String),
}

/// Why a run stopped before converging (exit 1); its text is `summary.json`'s `reason`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RunFailure {
    /// Statics: the dial increment was halved below `solver.min_continuation_step`.
    #[error("continuation step fell below {min_h} at dial {dial:.6}: {cause}", min_h = crate::math::human(*.min))]
    ContinuationStep {
        /// The minimum increment.
        min: Real,
        /// The dial reached.
        dial: Real,
        /// The last solve's failure.
        cause: SolveError,
    },
    /// Statics under a prescribed gas pressure: no equilibrium beyond a pressure (a limit
    /// point of the pressure–volume curve, or a snap).
    #[error(
        "no equilibrium found beyond a gauge pressure of {} Pa (dial {dial:.6}, enclosed volume {} m³): the balloon's pressure has a maximum there (its limit point: a rubber sphere's pressure peaks at a stretch of 7^(1/6) = 1.38) and a higher pressure has no equilibrium nearby. Prescribe the volume (gas.control = \"volume\") or the amount of gas (\"amount\") to follow the curve through it. Last solve: {cause}",
        crate::math::human(*.pressure),
        crate::math::human(*.volume)
    )]
    PressureLimit {
        /// The last gauge pressure with an equilibrium (Pa).
        pressure: Real,
        /// Its dial.
        dial: Real,
        /// The enclosed volume there (m³).
        volume: Real,
        /// The last solve's failure.
        cause: SolveError,
    },
    /// Statics: raising the stretching weight back to 1 failed.
    #[error("membrane continuation stalled at stretching weight {scale_h}: {cause}", scale_h = crate::math::human(*.scale))]
    MembraneContinuation {
        /// The stretching weight reached.
        scale: Real,
        /// The last solve's failure.
        cause: SolveError,
    },
    /// Statics: the equilibrium stayed a saddle after every perturbation.
    #[error("equilibrium is a saddle (Hessian indefinite) after {escapes} perturbations")]
    Saddle {
        /// Perturb-and-resolve attempts made.
        escapes: usize,
    },
    /// Statics: a solve after a saddle perturbation failed.
    #[error("after escaping a saddle: {0}")]
    AfterSaddle(SolveError),
    /// Dynamics: the time step was halved below `time.dt_min`.
    #[error("time step fell below dt_min = {dt_min_h} at t = {t_h}: {cause}", dt_min_h = crate::math::human(*.dt_min), t_h = crate::math::human(*.t))]
    TimeStep {
        /// The minimum time step (s).
        dt_min: Real,
        /// The time reached (s).
        t: Real,
        /// The last solve's failure.
        cause: SolveError,
    },
    /// A signal (SIGINT, SIGTERM) asked the run to stop; the state reached is the last frame.
    #[error("interrupted by {signal} at {what} {at_h}", at_h = crate::math::human(*.at))]
    Interrupted {
        /// The signal's name.
        signal: &'static str,
        /// "dial" or "t".
        what: &'static str,
        /// The dial or time reached.
        at: Real,
    },
    /// Dynamics: the moisture boundary conditions could not be switched.
    #[error("moisture at t = {t_h}: {source}", t_h = crate::math::human(*.t))]
    MoistureSurface {
        /// The time reached (s).
        t: Real,
        /// What went wrong.
        source: crate::diffusion::SurfaceError,
    },
    /// Dynamics: the moisture diffusion solve failed.
    #[error("moisture diffusion at t = {t_h}: {source}", t_h = crate::math::human(*.t))]
    Diffusion {
        /// The time reached (s).
        t: Real,
        /// What went wrong.
        source: crate::diffusion::DiffusionError,
    },
    /// Dynamics: the moisture made a rest form invalid.
    #[error("at t = {t_h}: {source}", t_h = crate::math::human(*.t))]
    Growth {
        /// The time reached (s).
        t: Real,
        /// What went wrong.
        source: crate::rest::laws::GrowthError,
    },
}

/// The signal that asked the run to stop (0: none). Set by [`catch_signals`]' handler and read
/// by the drivers between steps.
static STOP: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(0);

/// Makes SIGINT and SIGTERM stop a run cleanly: the drivers finish the step under way, write
/// the state reached as the last frame, the log and `summary.json` (`reason` "interrupted …")
/// and return. A second signal exits at once with 128 + its number.
pub fn catch_signals() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    for sig in [SIGINT, SIGTERM] {
        // SAFETY: the handler only touches an atomic and calls `_exit`, both async-signal-safe.
        unsafe {
            signal_hook::low_level::register(sig, move || {
                if STOP.swap(sig, std::sync::atomic::Ordering::SeqCst) != 0 {
                    signal_hook::low_level::exit(128 + sig);
                }
            })?;
        }
    }
    Ok(())
}

/// The signal number that interrupted the run, if any.
pub fn interrupted() -> Option<i32> {
    match STOP.load(std::sync::atomic::Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// The [`RunFailure`] of an interruption, if a signal came.
fn interruption(what: &'static str, at: Real) -> Option<RunFailure> {
    interrupted().map(|sig| RunFailure::Interrupted {
        signal: match sig {
            signal_hook::consts::SIGINT => "SIGINT",
            signal_hook::consts::SIGTERM => "SIGTERM",
            _ => "a signal",
        },
        what,
        at,
    })
}

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

/// Area-weighted vertex normals.
pub fn vertex_normals(scene: &Scene, x: &[Vec3]) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); x.len()];
    for f in &scene.mesh.faces {
        let c = (x[f[1]] - x[f[0]]).cross(&(x[f[2]] - x[f[0]]));
        for &v in f {
            n[v] += c;
        }
    }
    for v in &mut n {
        let l = v.norm();
        if l > 0.0 {
            *v /= l;
        }
    }
    n
}

/// True when all face normals are parallel (the sheet is planar).
pub fn is_planar(scene: &Scene, x: &[Vec3]) -> bool {
    let mut n0: Option<Vec3> = None;
    for f in &scene.mesh.faces {
        let c = (x[f[1]] - x[f[0]]).cross(&(x[f[2]] - x[f[0]])).normalize();
        match n0 {
            None => n0 = Some(c),
            Some(n) => {
                if n.dot(&c) < 1.0 - 1e-12 {
                    return false;
                }
            }
        }
    }
    true
}

/// Moves free vertices along their normals by `amp × u`, u uniform in [−1, 1) (seeded).
pub fn perturb(scene: &Scene, x: &mut [Vec3], amp: Real, seed: u64) {
    let normals = vertex_normals(scene, x);
    let mut rng = Rng::new(seed);
    for (v, p) in x.iter_mut().enumerate() {
        let u = rng.symmetric();
        if !scene.fixed[v] {
            *p += normals[v] * (amp * u);
        }
    }
}

/// `r ← H⁻¹ r` with the last factorisation of `lin` and the low-rank parts of `pot` at `state`
/// (Woodbury); `false` when there is no factor or the low-rank solve is singular.
fn apply_inverse(lin: &mut LinearSolver, pot: &Potential, state: &State, r: &mut [Real]) -> bool {
    if !lin.is_factored() {
        return false;
    }
    let lr = pot.low_rank(&state.x, &state.dofs);
    let wb = crate::solve::low_rank::Woodbury::new(lin, &lr);
    wb.solve_in_place(lin, r)
}

/// Multiplier updates allowed per solve (see [`Solver::solve`]).
const MAX_UPDATES: usize = 50;

struct Solver<'a> {
    scene: &'a Scene,
    /// The current sparsity pattern (replaced when a term's elements change, see
    /// [`Solver::refresh`]); potentials borrow a clone of the handle ([`Solver::pattern`]).
    pattern: std::sync::Arc<Pattern>,
    /// Whether some term's elements change during the run.
    changing: bool,
    /// The run's controls, from the validated settings.
    config: config::RunConfig,
    lin: LinearSolver,
    ws: Workspace,
    summary: Summary,
    start: Instant,
    /// The summary's counters when the previous frame was written; log rows report the
    /// differences.
    at_last_frame: Counters,
    /// The driver's state as of the next frame (the drivers keep it current).
    driver: DriverState,
}

/// Counters that log rows report per frame.
#[derive(Clone, Copy, Default)]
struct Counters {
    newton: usize,
    steps: usize,
    shifted: usize,
    gauss_newton: usize,
    rejected: usize,
}

impl Counters {
    fn of(s: &Summary) -> Self {
        Counters {
            newton: s.newton_iterations,
            steps: s.steps,
            shifted: s.shifted_iterations,
            gauss_newton: s.gauss_newton_iterations,
            rejected: s.rejected_steps,
        }
    }
}

impl<'a> Solver<'a> {
    fn new(scene: &'a Scene, pattern: Pattern, threads: usize) -> Result<Self, RunError> {
        let lin = LinearSolver::new(&pattern)?;
        let ws = Workspace::new(&pattern);
        let changing = scene.terms.iter().any(|t| {
            let x = &scene.mesh.positions;
            t.stencil_at(scene, x, &vec![0.0; scene.num_scalar_dofs()])
                .is_some()
        });
        let config = config::RunConfig::new(scene);
        let summary = Summary {
            mode: match config.mode {
                Mode::Static => "static",
                Mode::Dynamic => "dynamic",
                Mode::Explicit => "explicit",
            }
            .into(),
            vertices: scene.num_vertices(),
            faces: scene.num_faces(),
            threads,
            warnings: scene.warnings.clone(),
            ..Default::default()
        };
        Ok(Solver {
            scene,
            pattern: std::sync::Arc::new(pattern),
            changing,
            config,
            lin,
            ws,
            summary,
            start: Instant::now(),
            at_last_frame: Counters::default(),
            driver: DriverState::default(),
        })
    }

    /// The current pattern, for potentials to borrow.
    fn pattern(&self) -> std::sync::Arc<Pattern> {
        self.pattern.clone()
    }

    /// Follows the terms whose elements change to the state `state`: a new pattern when their
    /// elements there differ, a new symbolic factorisation only when the union of the stencils
    /// changed. Returns whether the pattern was replaced (take a new [`Solver::pattern`]).
    fn refresh(&mut self, state: &State) -> Result<bool, RunError> {
        if !self.changing {
            return Ok(false);
        }
        let Some(p) = self.pattern.refreshed(self.scene, &state.x, &state.dofs) else {
            return Ok(false);
        };
        self.summary.element_changes += 1;
        if !p.same_union(&self.pattern) {
            self.lin = LinearSolver::new(&p)?;
            self.ws = Workspace::new(&p);
            self.summary.pattern_rebuilds += 1;
        }
        self.pattern = std::sync::Arc::new(p);
        Ok(true)
    }

    fn potential<'p>(&self, pattern: &'p Pattern, dial: Real) -> Potential<'p>
    where
        'a: 'p,
    {
        self.potential_scaled(pattern, dial, 1.0)
    }

    fn potential_scaled<'p>(
        &self,
        pattern: &'p Pattern,
        dial: Real,
        stretch_scale: Real,
    ) -> Potential<'p>
    where
        'a: 'p,
    {
        Potential {
            dial,
            gravity: self.config.gravity,
            stretch_scale,
            ..Potential::new(self.scene, pattern)
        }
    }

    fn record(&mut self, rep: &NewtonReport) {
        self.summary.newton_iterations += rep.iterations;
        self.summary.shifted_iterations += rep.shifted_iterations;
        self.summary.gauss_newton_iterations += rep.gauss_newton_iterations;
        self.summary.indefinite_iterations += rep.indefinite_iterations;
        self.summary.residual = rep.residual;
        self.summary.timing.newton.add(&rep.timing);
    }

    /// Newton on `pot` from `state`, then the terms' multiplier updates (a prescribed volume's
    /// pressure, [`crate::energy::term::Term::update`]), re-solving until no term asks for
    /// another solve. The report sums the iterations of every solve; more than
    /// [`MAX_UPDATES`] updates is a failure.
    fn solve(&mut self, pot: &Potential, state: &mut State, opts: NewtonOptions) -> NewtonReport {
        assert!(
            std::ptr::eq(pot.pattern, &*self.pattern),
            "a potential on a replaced pattern was solved"
        );
        let mut total = NewtonReport::default();
        for _ in 0..MAX_UPDATES {
            let rep = newton(pot, &mut self.lin, &mut self.ws, state, opts);
            self.record(&rep);
            total.absorb(&rep);
            if !rep.converged {
                return total;
            }
            let lin = &mut self.lin;
            let mut sensitivity = |u: &[Real]| -> Option<Real> {
                let mut y = u.to_vec();
                apply_inverse(lin, pot, state, &mut y)
                    .then(|| u.iter().zip(&y).map(|(a, b)| a * b).sum::<Real>())
            };
            if !self
                .scene
                .update(pot, &state.x, &state.dofs, &mut sensitivity)
            {
                return total;
            }
        }
        total.converged = false;
        total.failure = Some(SolveError::MultiplierNotConverged {
            updates: MAX_UPDATES,
        });
        total
    }

    fn frame(
        &mut self,
        writer: &mut Writer,
        pot: &Potential,
        state: &State,
        v: &[Vec3],
        time: Real,
    ) -> Result<(), RunError> {
        let (now, last) = (Counters::of(&self.summary), self.at_last_frame);
        let row = LogRow {
            frame: 0,
            time,
            dial: pot.dial,
            energy: Default::default(),
            observables: Vec::new(),
            residual: self.summary.residual,
            newton_iterations: now.newton - last.newton,
            steps: now.steps - last.steps,
            shifted_iterations: now.shifted - last.shifted,
            gauss_newton_iterations: now.gauss_newton - last.gauss_newton,
            rejected_steps: now.rejected - last.rejected,
            wall_seconds: self.start.elapsed().as_secs_f64(),
        };
        self.at_last_frame = now;
        let clock = Instant::now();
        let mut driver = self.driver.clone();
        driver.mode = self.summary.mode.clone();
        driver.globals = state.dofs[self.scene.num_edge_dofs()..].to_vec();
        for t in self.scene.terms.iter() {
            let saved = t.saved_state();
            if !saved.is_empty() {
                driver.terms.insert(t.name().to_string(), saved);
            }
        }
        let r = writer.frame(pot, state, v, row, Some(&driver));
        self.summary.timing.output += clock.elapsed().as_secs_f64();
        r?;
        Ok(())
    }

    /// Lets the terms predict the equilibrium at dial `pot.dial` from the one at `from`
    /// (see [`crate::energy::term::Term::predict`]) with the last factorisation.
    fn predict(&mut self, pot: &Potential, from: Real, state: &mut State) {
        if !self.scene.terms.iter().any(|t| t.predicts()) {
            return;
        }
        if !self.lin.is_factored() {
            // The first step: the Hessian at the start (dial `from`).
            let at = Potential { dial: from, ..*pot };
            let mut values = vec![0.0; pot.pattern.nnz()];
            let mut g = vec![0.0; pot.pattern.n];
            at.eval(&state.x, &state.dofs, Want::Hessian, &mut g, &mut values);
            let lr = at.low_rank(&state.x, &state.dofs);
            let mut shifted = vec![0.0; values.len()];
            if crate::solve::newton::exact_model(
                &mut self.lin,
                &at,
                &values,
                &mut shifted,
                &lr,
                1e-8,
            )
            .is_none()
            {
                return;
            }
        }
        let lin = &mut self.lin;
        let mut predicted = state.clone();
        let at = &*state;
        let mut solve = |r: &mut [Real]| apply_inverse(lin, pot, at, r);
        for t in self.scene.terms.iter() {
            t.predict(pot, from, &mut predicted.x, &predicted.dofs, &mut solve);
        }
        // Safeguard: a linear prediction from a nearly singular Hessian (an unstressed membrane
        // has soft modes) can land far off; keep it only when it lowers the potential.
        let e = |s: &State| pot.eval(&s.x, &s.dofs, Want::Energy, &mut [], &mut []);
        let ep = e(&predicted);
        if ep.is_finite() && ep < e(state) {
            state.copy_from(&predicted);
        }
    }

    /// Tests `H + δI ≻ 0` at `state` (see module doc).
    fn is_stable(&mut self, dial: Real, state: &State) -> bool {
        let (x, phi) = (&state.x, &state.dofs);
        let pattern = self.pattern();
        let pot = self.potential(&pattern, dial);
        let mut values = vec![0.0; pattern.nnz()];
        let mut g = vec![0.0; pattern.n];
        pot.eval(x, phi, Want::Hessian, &mut g, &mut values);
        // One factorisation of H + 1e-9·mean|diag|·I, with the dense low-rank part through
        // the inertia (an indefinite sparse part is fine when the whole is positive definite).
        let lr = pot.low_rank(x, phi);
        crate::solve::newton::is_positive_definite(&mut self.lin, &pot, &values, &lr, 1e-9)
    }
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

/// What a driver carries from step to step beyond the positions, velocities, edge DOFs and the
/// terms' frame fields: written beside every frame as `PREFIX_NNNNN.state.json` (numbers
/// round-trip exactly) and read back by a restart, so that a restarted run takes the same steps
/// as the uninterrupted one.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DriverState {
    /// `"static"`, `"dynamic"` or `"explicit"`: a restart in another mode ignores the rest.
    pub mode: String,
    /// Time (s); in statics the dial.
    pub time: Real,
    /// The dial factor.
    pub dial: Real,
    /// The step control: the next step (time step or dial increment) and the count of easy
    /// steps towards growing it.
    pub step: Option<Real>,
    /// See `step`.
    pub easy_steps: usize,
    /// Hold points: waiting on one, the index of the next, and how many were reached.
    pub holding: bool,
    /// See `holding`.
    pub next_hold: Option<usize>,
    /// See `holding`.
    pub holds_reached: usize,
    /// Moisture: the diffusion's nodal values and its next sub-step (s).
    pub moisture: Option<Vec<Real>>,
    /// See `moisture`.
    pub diffusion_substep: Option<Real>,
    /// Terms' states that no frame field carries (a gas's pressure multiplier, a moving slide),
    /// by term name.
    pub terms: std::collections::BTreeMap<String, Vec<Real>>,
    /// The explicit driver's own numbers: `phase` (0 dialling, 1 waiting), `next_frame` (s),
    /// `steps` (since its start, which align the equilibrium windows), `gradient_descent_left`,
    /// `energy_floor` (J) and `window_energy` (J, absent before the first window).
    pub explicit: std::collections::BTreeMap<String, Real>,
    /// The explicit driver's positions at its last equilibrium window (x, y, z per vertex).
    pub window_positions: Option<Vec<Real>>,
    /// The global DOFs' values ([`crate::energy::term::GlobalDof`]; frames carry no field for
    /// them), in node order.
    pub globals: Vec<Real>,
    /// Their velocities (dynamics).
    pub global_velocities: Vec<Real>,
}

impl DriverState {
    /// A static run's state: the dial (its time too) and the step control.
    fn at_dial(dial: Real, steps: &StepControl) -> Self {
        DriverState {
            time: dial,
            dial,
            step: Some(steps.step),
            easy_steps: steps.easy(),
            ..Default::default()
        }
    }
}

/// Where a dynamic or explicit driver starts: the velocities (at rest when `None`), the time,
/// the dial when the restart file gives it, and the driver's saved state.
pub(super) struct Resume {
    v: Option<Vec<Vec3>>,
    t0: Real,
    dial: Option<Real>,
    driver: Option<DriverState>,
}

/// A state to start from instead of the reference mesh (a restart).
#[derive(Clone, Debug)]
pub struct InitialState {
    /// Positions and edge DOFs.
    pub state: State,
    /// Velocities (m/s), for dynamics; `None` starts at rest.
    pub v: Option<Vec<Vec3>>,
    /// Time (dynamics, s) or dial factor (statics) to resume from.
    pub time: Real,
    /// The dial factor to resume from when the file gives it (a MorphoShell ansatz); otherwise
    /// the dial follows from `time`.
    pub dial: Option<Real>,
    /// The driver's state written with the frame, when there is one.
    pub driver: Option<DriverState>,
}

/// Runs a scene to completion from the reference mesh, or from `initial` (a restart), writing
/// frames, the log and the summary.
pub fn run(
    scene: &Scene,
    writer: &mut Writer,
    progress: &mut dyn Progress,
    threads: usize,
    initial: Option<InitialState>,
) -> Result<Summary, RunError> {
    let mut s = Solver::new(scene, Pattern::for_scene(scene), threads)?;
    let (mut state, v, start, dial, driver) = match initial {
        Some(st) => (st.state, st.v, Some(st.time), st.dial, st.driver),
        None => (State::reference(scene), None, None, None, None),
    };
    // A driver state of another mode (a static frame restarting a dynamic run) only gives
    // what the frame gives.
    let driver = driver.filter(|d| d.mode == s.summary.mode);
    if let Some(d) = &driver {
        for t in scene.terms.iter() {
            if let Some(v) = d.terms.get(t.name()) {
                t.load_state(v).map_err(RunError::Restart)?;
            }
        }
    }
    let sb = s.config.symmetry_breaking;
    // A restart with its driver's state continues the state it is given, planar or not.
    if sb > 0.0 && driver.is_none() && is_planar(scene, &state.x) {
        perturb(scene, &mut state.x, sb * scene.mean_edge, s.config.seed);
    }
    let ran = match s.config.mode {
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
    let n = t.newton;
    t.other = (s.summary.wall_seconds
        - (n.assembly + n.factorisation + n.solve + n.line_search + t.diffusion + t.output))
        .max(0.0);
    s.summary.refuse_non_finite();
    writer.summary(&s.summary)?;
    Ok(s.summary)
}

/// Checks what the scene's driver needs before anything is written (the explicit driver's
/// bounds, [`explicit::check`]); the error names the mesh file.
pub fn check_scene(scene: &Scene) -> Result<(), crate::mesh::MeshError> {
    if scene.settings.solver.mode == crate::settings::Mode::Explicit {
        explicit::check(scene).map_err(|r| scene.mesh.invalid(r))?;
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
