//! `[contact]`: a rigid ground plane with a smooth penalty and Coulomb friction.

use super::values::{vec_e, Auto, AutoOr};
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// `[contact]`: a rigid ground plane the sheet rests on and lifts off from, with Coulomb
/// friction, inside the Newton solve (see [`crate::contact`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Contact {
    /// Build the ground (default `false`).
    pub enabled: bool,
    /// A point on the plane (m, default `[0, 0, 0]`).
    pub point: [Real; 3],
    /// The plane's normal, pointing to the side the sheet is on (default `[0, 0, 1]`).
    pub normal: [Real; 3],
    /// Penalty stiffness k: contact pressure per unit penetration (Pa/m). `"auto"`: E/h, the
    /// sheet's own through-thickness stiffness (default).
    pub stiffness: AutoOr,
    /// Smoothing length δ of the penalty (m): the pressure grows as k p²/(2δ) for a penetration
    /// p < δ, and as k (p − δ/2) beyond. `"auto"`: h/100 (default).
    pub smoothing: AutoOr,
    /// Coulomb friction coefficient μ (default `0`; dynamics only).
    pub friction: Real,
    /// Slip speed ε_v (m/s) below which friction is smoothed (sticking creeps at most this fast;
    /// default `1e-5`).
    pub slip_speed: Real,
}

impl Default for Contact {
    fn default() -> Self {
        Contact {
            enabled: false,
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            stiffness: AutoOr::Auto(Auto::Auto),
            smoothing: AutoOr::Auto(Auto::Auto),
            friction: 0.0,
            slip_speed: 1e-5,
        }
    }
}

impl Contact {
    /// Validates `[contact]` (when enabled): the plane, stiffness, smoothing, friction.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let c = self;
        if c.enabled {
            if c.point.iter().any(|v| !v.is_finite()) {
                return ck.inv("contact.point", "must be finite".into());
            }
            let n2: Real = c.normal.iter().map(|v| v * v).sum();
            if !(n2.is_finite() && n2 > 0.0) {
                return ck.inv(
                    "contact.normal",
                    format!("must be a finite non-zero vector, got {}", vec_e(&c.normal)),
                );
            }
            if let AutoOr::Value(k) = c.stiffness {
                ck.pos("contact.stiffness", k)?;
            }
            if let AutoOr::Value(d) = c.smoothing {
                ck.pos("contact.smoothing", d)?;
            }
            ck.nonneg("contact.friction", c.friction)?;
            ck.pos("contact.slip_speed", c.slip_speed)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disabled ground checks nothing; an enabled one needs a finite plane, a non-zero
    /// normal and positive penalty constants.
    #[test]
    fn an_enabled_ground_needs_a_plane_and_a_penalty() {
        let off = Contact {
            normal: [0.0; 3],
            ..Contact::default()
        };
        assert_eq!(off.validate(), Ok(()));
        let on = Contact {
            enabled: true,
            ..Contact::default()
        };
        assert_eq!(on.validate(), Ok(()));
        let bad = |c: Contact| c.validate().unwrap_err().key;
        assert_eq!(
            bad(Contact {
                normal: [0.0; 3],
                ..on.clone()
            }),
            "contact.normal"
        );
        assert_eq!(
            bad(Contact {
                point: [Real::NAN, 0.0, 0.0],
                ..on.clone()
            }),
            "contact.point"
        );
        assert_eq!(
            bad(Contact {
                stiffness: AutoOr::Value(0.0),
                ..on.clone()
            }),
            "contact.stiffness"
        );
        assert_eq!(
            bad(Contact {
                friction: -0.1,
                ..on.clone()
            }),
            "contact.friction"
        );
        assert_eq!(
            bad(Contact {
                slip_speed: 0.0,
                ..on
            }),
            "contact.slip_speed"
        );
    }
}
