//! `[solver]`: the mode (static, implicit dynamics, explicit dynamics) and Newton's and the
//! static continuation's controls.

use super::shell::HessianProjection;
use super::values::{Auto, Softening};
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Static equilibrium or dynamics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Minimise the potential energy, dialling the rest forms in by adaptive continuation.
    #[default]
    Static,
    /// Implicit Euler dynamics with Kelvin–Voigt damping.
    Dynamic,
    /// MorphoShell's explicit damped Newtonian dynamics (symplectic Euler, gradient only), run
    /// until the equilibrium test fires (`[explicit]`).
    Explicit,
}

/// How statics follow the dial (the load factor).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Continuation {
    /// Load control: the dial rises monotonically from 0 to 1 in adaptive steps, each solved by
    /// minimising the potential at that dial.
    #[default]
    Load,
    /// Arc-length control (Crisfield's spherical method): the dial is an unknown beside the
    /// positions, so the path continues through limit points of the load (snap-through,
    /// snap-back, a balloon's pressure maximum).
    ArcLength,
}

/// Solver controls.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Solver {
    /// `"static"` or `"dynamic"` (default: `"static"`).
    pub mode: Mode,
    /// Newton converges when ‖∇E‖∞ ≤ tolerance × F, with F = max(E·h) × mean edge length, the
    /// membrane force of a unit strain on one edge, or in static mode the largest applied
    /// nodal load (at least 1e-4 of the former) when that is smaller (dimensionless, default:
    /// `1e-9`).
    pub tolerance: Real,
    /// Newton iterations allowed per solve before the step is cut (default: `40`).
    pub max_newton_iterations: usize,
    /// Dynamic mode: chord iterations, which solve with the factorisation of an earlier
    /// iteration of the same time step while the residual at least halves per iteration
    /// (default: `true`; `false` factorises every iteration).
    pub chord: bool,
    /// Hessian used by Newton: `"adaptive"` (exact when it factorises, Gauss–Newton otherwise),
    /// `"none"` (exact + growing diagonal shift), `"gauss_newton"` (always), or per-element
    /// eigenvalue projection `"clamp_zero"` / `"abs"` (default: `"adaptive"`).
    pub hessian_projection: HessianProjection,
    /// Static mode: first continuation increment of the dial factor (dimensionless, (0, 1],
    /// default: `1.0`).
    pub continuation_step: Real,
    /// Static mode: the increment below which continuation gives up (default: `1e-4`).
    pub min_continuation_step: Real,
    /// Static mode: the largest increment of the dial factor (dimensionless, (0, 1], default:
    /// `1.0`); with `output.continuation_frames`, the spacing of the frames along the path.
    pub max_continuation_step: Real,
    /// Static mode: `"load"` (default) dials the loads and rest forms up monotonically;
    /// `"arc_length"` follows the equilibrium path with the dial as an unknown, through limit
    /// points, writing a frame per step.
    pub continuation: Continuation,
    /// Arc-length control: the first step's length along the path, in dial units (the path
    /// coordinate `s` with `ds² = ‖W du‖²/ψ² + dλ²`, ψ the first tangent's displacement per unit
    /// dial; dimensionless, default: `0.05`).
    pub arc_length_step: Real,
    /// Arc-length control: the largest step along the path (dimensionless, default: `0.5`).
    pub max_arc_length_step: Real,
    /// Arc-length control: the run ends after this many accepted steps if the dial has not
    /// reached 1 (default: `1000`).
    pub max_arc_length_steps: usize,
    /// Static mode: membrane continuation. The dial continuation runs with the stretching
    /// weight divided by a factor c (a sheet √c times thicker, relative to bending), then the
    /// weight is raised to its true value in warm-started solves (×10, ×100, … per solve). Thin
    /// sheets that roll or fold take far fewer Newton iterations this way, and the final state is
    /// a converged, stability-checked equilibrium of the true energy. `"auto"` (default): c =
    /// (L / 10 h)², L the reference mesh's bounding-box diagonal and h its smallest thickness, so
    /// that the softened sheet is as stiff as one of thickness L/10; a number ≥ 1 sets c; 1
    /// disables it.
    pub membrane_continuation: Softening,
    /// Out-of-plane perturbation that breaks the symmetry of a flat start, as a fraction of the
    /// mean edge length (dimensionless, default: `1e-3`; 0 disables). Applied when the sheet is
    /// exactly planar, and again (×10 each time) when a converged state is found to be a saddle.
    pub symmetry_breaking: Real,
    /// Seed of the symmetry-breaking perturbation (default: `1`).
    pub seed: u64,
    /// Check that a static equilibrium is a minimum (Cholesky of H + δI with a tiny δ), and
    /// perturb and re-solve if it is a saddle (default: `true`).
    pub check_stability: bool,
    /// Newton solves allowed to escape a saddle before giving up (default: `4`).
    pub max_saddle_escapes: usize,
}

impl Default for Solver {
    fn default() -> Self {
        Solver {
            mode: Mode::Static,
            tolerance: 1e-9,
            max_newton_iterations: 40,
            chord: true,
            hessian_projection: HessianProjection::Adaptive,
            continuation_step: 1.0,
            min_continuation_step: 1e-4,
            max_continuation_step: 1.0,
            continuation: Continuation::Load,
            arc_length_step: 0.05,
            max_arc_length_step: 0.5,
            max_arc_length_steps: 1000,
            membrane_continuation: Softening::Auto(Auto::Auto),
            symmetry_breaking: 1e-3,
            seed: 1,
            check_stability: true,
            max_saddle_escapes: 4,
        }
    }
}

impl Solver {
    /// Validates `[solver]`: tolerance, iteration and continuation controls.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let s = self;
        ck.pos("solver.tolerance", s.tolerance)?;
        if s.max_newton_iterations == 0 {
            return ck.inv("solver.max_newton_iterations", "must be at least 1".into());
        }
        if !(s.continuation_step > 0.0 && s.continuation_step <= 1.0) {
            return ck.inv(
                "solver.continuation_step",
                format!(
                    "must lie in (0, 1], got {}",
                    crate::math::human(s.continuation_step)
                ),
            );
        }
        ck.pos("solver.min_continuation_step", s.min_continuation_step)?;
        if !(s.max_continuation_step > 0.0 && s.max_continuation_step <= 1.0) {
            return ck.inv(
                "solver.max_continuation_step",
                format!(
                    "must lie in (0, 1], got {}",
                    crate::math::human(s.max_continuation_step)
                ),
            );
        }
        if let Softening::Factor(c) = s.membrane_continuation {
            if !(c >= 1.0 && c.is_finite()) {
                return ck.inv(
                    "solver.membrane_continuation",
                    format!(
                        "must be \"auto\" or a finite number ≥ 1, got {c_h}",
                        c_h = crate::math::human(c)
                    ),
                );
            }
        }
        ck.nonneg("solver.symmetry_breaking", s.symmetry_breaking)?;
        ck.pos("solver.arc_length_step", s.arc_length_step)?;
        ck.pos("solver.max_arc_length_step", s.max_arc_length_step)?;
        if s.max_arc_length_step < s.arc_length_step {
            return ck.inv(
                "solver.max_arc_length_step",
                format!(
                    "must be at least solver.arc_length_step ({}), got {}",
                    crate::math::human(s.arc_length_step),
                    crate::math::human(s.max_arc_length_step)
                ),
            );
        }
        if s.max_arc_length_steps == 0 {
            return ck.inv("solver.max_arc_length_steps", "must be at least 1".into());
        }
        if s.continuation == Continuation::ArcLength && s.mode != Mode::Static {
            return ck.inv(
                "solver.continuation",
                "\"arc_length\" follows a static equilibrium path; dynamics have no load \
                 factor to control (use mode = \"static\")"
                    .into(),
            );
        }
        Ok(())
    }
}
