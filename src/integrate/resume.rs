//! What a frame records of a driver for an exact restart ([`DriverState`]), and where a run
//! starts from ([`InitialState`], [`Resume`]).

use super::StepControl;
use crate::math::{Real, Vec3};
use crate::solve::State;

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
    /// Temperature: the conduction's nodal values (K) and the highest each has reached.
    pub temperature: Option<Vec<Real>>,
    /// See `temperature`.
    pub temperature_max: Option<Vec<Real>>,
    /// The stateful terms' states ([`crate::solve::State::terms`]: a gas's pressure
    /// multiplier, a moving slide, a moment's frames, the prism's thickness), by term name.
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
    /// The dynamic driver's last change of velocity per unit time (m/s², x, y, z per vertex,
    /// then the global DOFs'), which its Newton start extrapolates with; absent before the
    /// first step.
    pub acceleration: Option<Vec<Real>>,
    /// What Newton's last solves learnt about the Hessian ([`crate::solve::newton::Workspace::model_hints`]):
    /// whether its last exact model needed LDLᵀ, and whether it was rejected.
    pub model_hints: [bool; 2],
    /// The frame is the reference state of a planar start, which the run perturbs right after
    /// writing it (the symmetry breaking): a restart from it perturbs it the same way.
    pub perturb_pending: bool,
    /// The arc-length driver's numbers: `arc_length` (the path coordinate), `psi` (m per unit
    /// dial), `step` (the next step), `direction` (±1, the sign of dλ/ds) and
    /// `negative_eigenvalues` (the Hessian's, at this frame).
    pub arc_length: std::collections::BTreeMap<String, Real>,
}

impl DriverState {
    /// A static run's state: the dial (its time too) and the step control.
    pub(super) fn at_dial(dial: Real, steps: &StepControl) -> Self {
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
    pub(super) v: Option<Vec<Vec3>>,
    pub(super) t0: Real,
    pub(super) dial: Option<Real>,
    pub(super) driver: Option<DriverState>,
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
