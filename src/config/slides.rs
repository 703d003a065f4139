//! `[slides]`: MorphoShell's two glass slides, the upper one moved at a speed or pressed by a
//! force.

use super::limits::MAX_LOAD;
use super::solver::Mode;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// How the upper glass slide moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlideControl {
    /// Down at `speed` until it has moved `travel`.
    #[default]
    Speed,
    /// Pressed down by `force`, moving overdamped against the sheet's push.
    Force,
}

/// Glass slides: two planes z = lower and z = upper (see [`crate::energy::slides`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Slides {
    /// Build the slides (default: `false`).
    pub enabled: bool,
    /// Height of the fixed lower slide (m; default: the reference mesh's lowest z).
    pub lower: Option<Real>,
    /// Starting height of the upper slide (m; default: the reference mesh's highest z).
    pub upper: Option<Real>,
    /// MorphoShell's `slide_stiffness_prefactor` p_k: a vertex beyond a slide by d feels
    /// `p_k μ t d` (N), μ and t the smallest shear modulus and thickness (default: `100`).
    pub stiffness_prefactor: Real,
    /// Coulomb friction coefficient of stick/slip friction on vertices in contact (default: `0`;
    /// explicit mode).
    pub friction: Real,
    /// Damping of the contact along the normal, as a fraction of the critical damping
    /// `2√(k m)` of a vertex of mass m on the penalty spring k (default: `1`, critical;
    /// MorphoShell's contact is undamped, `0`; explicit mode). It dissipates only while a vertex
    /// moves into or out of a slide, so equilibria are unchanged.
    pub contact_damping: Option<Real>,
    /// `"speed"` (default) or `"force"` (explicit mode).
    pub control: SlideControl,
    /// Speed control: downward speed of the upper slide (m/s; default: `0`).
    pub speed: Real,
    /// Speed control: the distance it moves before it stops (m; default: `0`).
    pub travel: Real,
    /// Force control: the downward force on the upper slide (N; default: `0`).
    pub force: Real,
    /// Force control: the slide's drag coefficient (N·s/m; default: the sheet's mass times its
    /// waiting drag rate).
    pub drag: Option<Real>,
    /// The upper slide stays still until the dial has reached 1 (default: `false`: it moves
    /// from the start).
    pub after_dial: bool,
}

impl Default for Slides {
    fn default() -> Self {
        Slides {
            enabled: false,
            lower: None,
            upper: None,
            stiffness_prefactor: 100.0,
            friction: 0.0,
            contact_damping: None,
            control: SlideControl::Speed,
            speed: 0.0,
            travel: 0.0,
            force: 0.0,
            drag: None,
            after_dial: false,
        }
    }
}

impl Slides {
    /// Validates `[slides]` in a run of mode `mode` (`solver.mode`): moving slides, friction
    /// and contact damping act in explicit mode only.
    pub fn validate(&self, mode: Mode) -> Result<(), Invalid> {
        let ck = Check;
        let sl = self;
        ck.pos("slides.stiffness_prefactor", sl.stiffness_prefactor)?;
        ck.nonneg("slides.friction", sl.friction)?;
        if let Some(z) = sl.contact_damping {
            ck.nonneg("slides.contact_damping", z)?;
        }
        ck.nonneg("slides.travel", sl.travel)?;
        let coordinate = crate::mesh::MAX_COORDINATE;
        for (k, v, max, unit) in [
            ("slides.speed", sl.speed, coordinate, "m/s"),
            ("slides.force", sl.force, MAX_LOAD, "N"),
            ("slides.travel", sl.travel, coordinate, "m"),
        ] {
            if !(v.is_finite() && v.abs() <= max) {
                return ck.inv(
                    k,
                    format!(
                        "must be finite within ±{max_h} {unit}, got {v_h}",
                        max_h = crate::math::human(max),
                        v_h = crate::math::human(v)
                    ),
                );
            }
        }
        for (k, v) in [("slides.lower", sl.lower), ("slides.upper", sl.upper)] {
            if let Some(v) = v {
                if !(v.is_finite() && v.abs() <= coordinate) {
                    return ck.inv(
                        k,
                        format!(
                            "must be a finite height within ±{coordinate_h} m, got {v_h}",
                            coordinate_h = crate::math::human(coordinate),
                            v_h = crate::math::human(v)
                        ),
                    );
                }
            }
        }
        if let Some(d) = sl.drag {
            ck.pos("slides.drag", d)?;
        }
        if let (Some(l), Some(u)) = (sl.lower, sl.upper) {
            if u <= l {
                return ck.inv(
                    "slides.upper",
                    format!("the upper slide ({u}) must be above the lower one ({l})"),
                );
            }
        }
        if sl.enabled && mode != Mode::Explicit {
            let moving = (sl.control == SlideControl::Speed && sl.speed != 0.0 && sl.travel > 0.0)
                || sl.control == SlideControl::Force;
            if sl.friction > 0.0 {
                return ck.inv(
                    "slides.friction",
                    "slide friction needs solver.mode = \"explicit\" (the implicit modes hold \
                     frictionless slides still)"
                        .into(),
                );
            }
            if sl.contact_damping.is_some_and(|z| z > 0.0) {
                return ck.inv(
                    "slides.contact_damping",
                    "contact damping needs solver.mode = \"explicit\" (the implicit modes hold \
                     the slides still, without damping)"
                        .into(),
                );
            }
            if moving {
                return ck.inv(
                    "slides.control",
                    "moving slides need solver.mode = \"explicit\" (the implicit modes hold the \
                     slides still)"
                        .into(),
                );
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults pass in every mode; a moving slide outside explicit mode, or an upper slide
    /// below the lower one, names its key.
    #[test]
    fn moving_slides_need_explicit_mode() {
        for mode in [Mode::Static, Mode::Dynamic, Mode::Explicit] {
            assert_eq!(Slides::default().validate(mode), Ok(()));
        }
        let moving = Slides {
            enabled: true,
            speed: 1e-3,
            travel: 1e-3,
            ..Slides::default()
        };
        assert_eq!(moving.validate(Mode::Explicit), Ok(()));
        assert_eq!(
            moving.validate(Mode::Static).unwrap_err().key,
            "slides.control"
        );
        let crossed = Slides {
            lower: Some(1.0),
            upper: Some(0.5),
            ..Slides::default()
        };
        assert_eq!(
            crossed.validate(Mode::Explicit).unwrap_err().key,
            "slides.upper"
        );
        let force = Slides {
            force: Real::NAN,
            ..Slides::default()
        };
        assert_eq!(
            force.validate(Mode::Explicit).unwrap_err().key,
            "slides.force"
        );
    }
}
