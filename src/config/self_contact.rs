//! `[self_contact]`: contact of the sheet with itself and between sheets, with the sheets'
//! thickness as the offset.

use super::solver::Mode;
use super::values::{Auto, AutoOr};
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// `[self_contact]`: the sheet's surfaces never pass through each other or another sheet's;
/// mid-surfaces stay an offset apart (see `crate::energy::self_contact`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SelfContact {
    /// Build the contact (default `false`).
    pub enabled: bool,
    /// The offset ξ between mid-surfaces in contact (m). `"auto"`: the mean of the two sides'
    /// thicknesses, `(h_a + h_b)/2` (default); a number: that offset for every pair (a contact
    /// thickness apart from the material's).
    pub offset: AutoOr,
    /// The normal law (default `"penalty"`): see [`Law`].
    pub law: Law,
    /// Stiffness k of the normal law (Pa/m): the penalty's contact pressure per unit
    /// penetration into the offset, or the barrier's scale. `"auto"`: the area-weighted mean
    /// of E/h (default), as for the ground.
    pub stiffness: AutoOr,
    /// The normal law's length (m): the penalty's smoothing δ, or the barrier's activation
    /// distance ĝ beyond the offset. `"auto"`: h/100 (default).
    pub smoothing: AutoOr,
    /// Pairs closer than this along the reference surface never touch (m). `"auto"`:
    /// `2 (ξ + δ)` with the largest offset (default).
    pub exclusion: AutoOr,
    /// How far beyond the offset pairs are gathered into the Hessian's pattern at the start
    /// of a step (m). `"auto"`: the largest offset (default).
    pub halo: AutoOr,
    /// The smallest distance two mid-surfaces may come to, as a fraction of their offset
    /// (default `0.1`): no step takes a pair closer.
    pub min_separation: Real,
    /// Coulomb coefficient μ between the sheets' surfaces, ≥ 0 (default 0: frictionless).
    /// Dynamic mode (the slip speed of its smoothing is `contact.slip_speed`) and explicit
    /// mode (stick/slip).
    pub friction: Real,
    /// Which point–triangle pairs of a vertex press (default `"nearest"`): see
    /// [`Pairs`].
    pub pairs: Pairs,
    /// Explicit mode: a dashpot on each pressing pair's normal approach, as a fraction ζ ≥ 0
    /// of the pair's critical damping on its penalty spring (default 1; 0: none).
    pub damping: Real,
}

/// The normal law of a pair at distance `d` whose law acts at `r` (the offset ξ for a point
/// and a face, ξ/2 for two edges).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// The ground's C² penalty on the penetration `r − d`: a physical stiffness (the
    /// penetration under a pressure has a closed form that holds on any mesh); pairs may sink
    /// into the offset, down to the minimum separation.
    Penalty,
    /// IPC's log barrier on the gap `d − r`, active below the activation distance: infinite
    /// at `r`, so the offset itself is never entered; its stiffness is a scale, not a
    /// material's.
    Barrier,
}

/// Which point–triangle pairs of a vertex press.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pairs {
    /// The nearest face on either side of the vertex: exact on flat contacts (the closed-form
    /// penetration on any mesh), but the faces that count change abruptly where a fold turns
    /// the other surface edge-on to the vertex.
    Nearest,
    /// Every face within reach (IPC's pairs): the energy is C¹ everywhere, and a vertex over
    /// an edge or a vertex of the other surface presses on each face there (stiffer contact
    /// where meshes align).
    All,
}

impl Default for SelfContact {
    fn default() -> Self {
        SelfContact {
            enabled: false,
            offset: AutoOr::Auto(Auto::Auto),
            law: Law::Penalty,
            stiffness: AutoOr::Auto(Auto::Auto),
            smoothing: AutoOr::Auto(Auto::Auto),
            exclusion: AutoOr::Auto(Auto::Auto),
            halo: AutoOr::Auto(Auto::Auto),
            min_separation: 0.1,
            friction: 0.0,
            pairs: Pairs::Nearest,
            damping: 1.0,
        }
    }
}

impl SelfContact {
    /// Validates `[self_contact]` when enabled, or when the scene has mesh obstacles
    /// (`meshes`, whose pairs use its keys): positive lengths and stiffness, a minimum
    /// separation in (0, 0.9]; in explicit mode the penalty law.
    pub fn validate(&self, mode: Mode, meshes: bool) -> Result<(), Invalid> {
        let ck = Check;
        if !self.enabled && !meshes {
            return Ok(());
        }
        if mode == Mode::Explicit && self.law == Law::Barrier {
            return ck.inv(
                "self_contact.law",
                "the barrier's stiffness grows without bound at the offset, which no explicit \
                 step resolves: use law = \"penalty\" in explicit mode, or solver.mode = \
                 \"static\" or \"dynamic\""
                    .into(),
            );
        }
        for (key, v) in [
            ("self_contact.offset", self.offset),
            ("self_contact.stiffness", self.stiffness),
            ("self_contact.smoothing", self.smoothing),
            ("self_contact.exclusion", self.exclusion),
            ("self_contact.halo", self.halo),
        ] {
            if let AutoOr::Value(x) = v {
                ck.pos(key, x)?;
            }
        }
        ck.nonneg("self_contact.friction", self.friction)?;
        ck.nonneg("self_contact.damping", self.damping)?;
        let s = self.min_separation;
        if !(s > 0.0 && s <= 0.9) {
            return ck.inv(
                "self_contact.min_separation",
                format!(
                    "must be in (0, 0.9] (a fraction of the offset), got {}",
                    crate::math::human(s)
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Disabled checks nothing; enabled needs positive values, a separation fraction in
    /// (0, 0.9], and in explicit mode the penalty.
    #[test]
    fn enabled_self_contact_needs_positive_values_and_an_explicit_law() {
        let off = SelfContact {
            offset: AutoOr::Value(-1.0),
            ..Default::default()
        };
        assert!(off.validate(Mode::Explicit, false).is_ok());
        // Mesh obstacles' pairs use its keys: they are checked without `enabled` then.
        assert_eq!(
            off.validate(Mode::Static, true).unwrap_err().key,
            "self_contact.offset"
        );
        let on = SelfContact {
            enabled: true,
            ..Default::default()
        };
        assert!(on.validate(Mode::Static, false).is_ok());
        assert!(on.validate(Mode::Dynamic, false).is_ok());
        assert!(on.validate(Mode::Explicit, false).is_ok());
        // Explicit mode: no barrier (on mesh obstacles' pairs too); friction is stick/slip there.
        let barrier = SelfContact {
            law: Law::Barrier,
            ..on.clone()
        };
        assert!(barrier.validate(Mode::Dynamic, false).is_ok());
        let e = barrier.validate(Mode::Explicit, false).unwrap_err();
        assert_eq!(e.key, "self_contact.law");
        let meshes_only = SelfContact {
            enabled: false,
            ..barrier
        };
        let e = meshes_only.validate(Mode::Explicit, true).unwrap_err();
        assert_eq!(e.key, "self_contact.law");
        let rough = SelfContact {
            friction: 0.3,
            ..on.clone()
        };
        assert!(rough.validate(Mode::Explicit, false).is_ok());
        for z in [-0.5, Real::NAN] {
            let bad = SelfContact {
                damping: z,
                ..on.clone()
            };
            assert_eq!(
                bad.validate(Mode::Explicit, false).unwrap_err().key,
                "self_contact.damping"
            );
        }
        let bad = SelfContact {
            halo: AutoOr::Value(0.0),
            ..on.clone()
        };
        assert_eq!(
            bad.validate(Mode::Static, false).unwrap_err().key,
            "self_contact.halo"
        );
        for mu in [-0.1, Real::NAN, Real::INFINITY] {
            let bad = SelfContact {
                friction: mu,
                ..on.clone()
            };
            assert_eq!(
                bad.validate(Mode::Dynamic, false).unwrap_err().key,
                "self_contact.friction"
            );
        }
        let all: SelfContact =
            toml::from_str("enabled = true\npairs = \"all\"").expect("pairs = all parses");
        assert_eq!(all.pairs, Pairs::All);
        assert!(toml::from_str::<SelfContact>("pairs = \"some\"").is_err());
        for s in [0.0, 0.95, Real::NAN] {
            let bad = SelfContact {
                min_separation: s,
                ..on.clone()
            };
            assert_eq!(
                bad.validate(Mode::Static, false).unwrap_err().key,
                "self_contact.min_separation"
            );
        }
    }
}
