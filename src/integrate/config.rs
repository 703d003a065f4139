//! The controls of a run, taken once from the validated settings when the run starts: the
//! drivers, Newton and the friction lag read these values, never the settings.

use crate::math::{Real, Vec3};
use crate::model::Scene;
use crate::settings::{Mode, Softening, Time};
use crate::solve::NewtonOptions;

/// Everything the drivers need to know about a run besides its scene and terms.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// Static continuation or implicit-Euler dynamics.
    pub mode: Mode,
    /// Newton's tolerance (‖∇Φ‖∞/F), iteration limit and Hessian projection.
    pub newton: NewtonOptions,
    /// Amplitude of the symmetry-breaking perturbation of a planar start (× mean edge).
    pub symmetry_breaking: Real,
    /// Seed of that perturbation.
    pub seed: u64,
    /// Gravity (m/s²).
    pub gravity: Vec3,
    /// Static continuation.
    pub statics: StaticConfig,
    /// Dynamics.
    pub dynamics: DynamicConfig,
}

/// Controls of the static driver.
#[derive(Clone, Debug)]
pub struct StaticConfig {
    /// First dial increment.
    pub first_step: Real,
    /// The run stops below this increment.
    pub min_step: Real,
    /// Largest dial increment.
    pub max_step: Real,
    /// Test the final equilibrium for a minimum.
    pub check_stability: bool,
    /// Perturb-and-resolve attempts at a saddle.
    pub max_saddle_escapes: usize,
    /// Write a frame after every accepted continuation step (each solved to full tolerance).
    pub continuation_frames: bool,
    /// Under a prescribed gas pressure, its value at dial 1 (Pa): a stalled continuation is
    /// reported as the pressure's limit point.
    pub pressure_control: Option<Real>,
    /// Membrane continuation: the stretching weight starts at 1/softening (1 = off). Off when
    /// loads, prescribed paths or a gas are given: a softened membrane would follow another
    /// path (and inflate without bound).
    pub softening: Real,
}

/// Controls of the dynamic driver.
#[derive(Clone, Debug)]
pub struct DynamicConfig {
    /// End, time steps, output interval, damping and the equilibrium stop.
    pub time: Time,
    /// The dial reaches 1 at this time (s; 0 = at once).
    pub dial_time: Real,
    /// Slip speed of the smoothed Coulomb friction (m/s).
    pub slip_speed: Real,
}

impl RunConfig {
    /// The controls of a run of `scene` (whose settings are validated).
    pub fn new(scene: &Scene) -> RunConfig {
        let s = &scene.settings;
        let st = &s.solver;
        let h_min = scene
            .body
            .thickness
            .iter()
            .copied()
            .fold(Real::INFINITY, Real::min);
        let loaded = s.loads.any_external()
            || !scene.body.prescribed.is_empty()
            || !s.obstacles.is_empty()
            || s.gas.control != crate::settings::GasControl::None;
        let softening = match st.membrane_continuation {
            Softening::Auto(_) if loaded => 1.0,
            m => m.factor(scene.body.mesh.bbox_diagonal(), h_min),
        };
        RunConfig {
            mode: st.mode,
            newton: NewtonOptions {
                tol: st.tolerance,
                max_iter: st.max_newton_iterations,
                projection: st.hessian_projection,
                // Chord iterations in the implicit dynamics with a fixed time step: the inertia
                // keeps the Hessian close to the one last factorised. An adaptive step grows
                // after easy steps as counted in Newton iterations, which chord iterations
                // would change: there, every iteration factorises.
                chord: st.chord
                    && st.mode == crate::settings::Mode::Dynamic
                    && s.time.dt_max <= s.time.dt,
            },
            symmetry_breaking: st.symmetry_breaking,
            seed: st.seed,
            gravity: Vec3::from(s.loads.gravity),
            statics: StaticConfig {
                first_step: st.continuation_step,
                min_step: st.min_continuation_step,
                max_step: st.max_continuation_step,
                check_stability: st.check_stability,
                max_saddle_escapes: st.max_saddle_escapes,
                continuation_frames: s.output.continuation_frames,
                softening: softening.max(1.0),
                pressure_control: (s.gas.control == crate::settings::GasControl::Pressure)
                    .then_some(s.gas.pressure),
            },
            dynamics: DynamicConfig {
                time: s.time.clone(),
                dial_time: s.rest.dial_time,
                slip_speed: s.contact.slip_speed,
            },
        }
    }
}

impl Default for NewtonOptions {
    /// The `[solver]` settings' defaults.
    fn default() -> Self {
        let s = crate::settings::Solver::default();
        NewtonOptions {
            tol: s.tolerance,
            max_iter: s.max_newton_iterations,
            projection: s.hessian_projection,
            chord: false,
        }
    }
}
