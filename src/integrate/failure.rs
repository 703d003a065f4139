//! What stops a run: the errors that end it ([`RunError`]), the failures a driver reports
//! ([`RunFailure`]), and the signals that interrupt it.

use super::report::OutputError;
use crate::math::Real;
use crate::solve::linear::LinearError;
use crate::solve::SolveError;

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
    /// The moisture or temperature state made the rest forms invalid.
    #[error("rest forms: {0}")]
    Growth(#[from] crate::rest::laws::GrowthError),
    /// The moisture or temperature boundary conditions contradict each other.
    #[error("surface conditions: {0}")]
    Surface(#[from] crate::diffusion::SurfaceError),
    /// The moisture or temperature regions or fields are invalid.
    #[error("{0}")]
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
    #[error(
        "continuation step fell below {min_h} at dial {dial:.6}: {cause}. The residual is \
         ‖∇Φ‖∞ relative to the force scale F = {f_h} N ({scale_of}) and must reach \
         solver.tolerance = {tol_h} (a hold, the end, or a written frame) or {loose_h} (other \
         steps); {ran_out}",
        min_h = crate::math::human(*.min),
        f_h = crate::math::human(*.force_scale),
        tol_h = crate::math::human(*.tolerance),
        loose_h = crate::math::human(*.loose),
        scale_of = if *.from_loads { "from the applied loads" } else { "max(E h) × mean edge" },
        ran_out = ran_out(cause)
    )]
    ContinuationStep {
        /// The minimum increment.
        min: Real,
        /// The dial reached.
        dial: Real,
        /// The last solve's failure.
        cause: SolveError,
        /// The tolerance of holds, the end and written frames.
        tolerance: Real,
        /// The tolerance of the other steps.
        loose: Real,
        /// The force scale F (N).
        force_scale: Real,
        /// Whether F is the applied loads' scale.
        from_loads: bool,
    },
    /// Arc-length continuation: the step along the path was halved below
    /// `solver.min_continuation_step`.
    #[error(
        "arc-length step fell below {min_h} at dial {dial:.6} (arc length {arc_h}): {cause}. \
         The residual is ‖∇Φ‖∞ relative to F = {f_h} N and must reach solver.tolerance = \
         {tol_h} at every step; {ran_out}",
        min_h = crate::math::human(*.min),
        arc_h = crate::math::human(*.arc_length),
        f_h = crate::math::human(*.force_scale),
        tol_h = crate::math::human(*.tolerance),
        ran_out = arc_ran_out(cause)
    )]
    ArcLengthStep {
        /// The minimum step.
        min: Real,
        /// The dial reached.
        dial: Real,
        /// The path coordinate reached.
        arc_length: Real,
        /// The last solve's failure.
        cause: SolveError,
        /// The tolerance.
        tolerance: Real,
        /// The force scale F (N).
        force_scale: Real,
    },
    /// Arc-length continuation: no path can start from the first state.
    #[error("arc-length continuation cannot start: {0}")]
    ArcLengthStart(String),
    /// Statics under a prescribed gas pressure: no equilibrium beyond a pressure (a limit
    /// point of the pressure–volume curve, or a snap).
    #[error(
        "no equilibrium found beyond a gauge pressure of {} Pa (dial {dial:.6}, enclosed volume {} m³): the balloon's pressure has a maximum there (its limit point{limit}) and a higher pressure has no equilibrium nearby. Follow the path through it with solver.continuation = \"arc_length\", or prescribe the volume (gas.control = \"volume\") or the amount of gas (\"amount\"). Last solve: {cause}",
        crate::math::human(*.pressure),
        crate::math::human(*.volume),
        limit = match .limit_stretch {
            Some(l) => format!(": a thin sphere of this material peaks at the stretch {l:.4}"),
            None => String::new(),
        }
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
        /// The thin-sphere limit stretch of the material, when it has one
        /// ([`crate::energy::membrane::thin_sphere_limit_stretch`]).
        limit_stretch: Option<Real>,
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
    /// Dynamics: the moisture or temperature boundary conditions could not be switched.
    #[error("surface conditions at t = {t_h}: {source}", t_h = crate::math::human(*.t))]
    MoistureSurface {
        /// The time reached (s).
        t: Real,
        /// What went wrong.
        source: crate::diffusion::SurfaceError,
    },
    /// Dynamics: the moisture or heat diffusion solve failed.
    #[error("diffusion at t = {t_h}: {source}", t_h = crate::math::human(*.t))]
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
    /// Dynamics: the sheet lost more water than it holds, so a vertex's mass is not positive.
    #[error(
        "at t = {t_h}: vertex {vertex} would have mass {m_h} kg: the moisture fell below what \
         the material holds (density + moisture × water_density must stay positive)",
        t_h = crate::math::human(*.t), m_h = crate::math::human(*.mass)
    )]
    Mass {
        /// The time reached (s).
        t: Real,
        /// The vertex.
        vertex: usize,
        /// Its mass (kg).
        mass: Real,
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
pub(super) fn interruption(what: &'static str, at: Real) -> Option<RunFailure> {
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

/// What ran out in a failed continuation step, and what to change.
fn ran_out(cause: &SolveError) -> &'static str {
    match cause {
        SolveError::NotConverged { .. } => {
            "the Newton iterations ran out first: raise solver.max_newton_iterations, or lower \
             solver.continuation_step so that each step starts closer to its equilibrium"
        }
        SolveError::LineSearchStalled { .. } => {
            "the line search stalled before the tolerance: the tolerance may be below the \
             round-off of the energy at this force scale (raise solver.tolerance), or the path \
             has a limit point here (the load has a maximum: follow the path through it with \
             solver.continuation = \"arc_length\", or control a displacement)"
        }
        _ => "the step size ran out: every smaller step failed the same way",
    }
}

/// What ran out in a failed arc-length step.
fn arc_ran_out(cause: &SolveError) -> &'static str {
    match cause {
        SolveError::NotConverged { .. } => {
            "the Newton iterations ran out first at every step length: raise \
             solver.max_newton_iterations"
        }
        SolveError::Factor | SolveError::LowRankSingular => {
            "the Hessian was singular at every step length (a support that leaves a rigid \
             motion free, or a path exactly through a singular point)"
        }
        _ => "the step length ran out: every shorter step failed the same way",
    }
}
