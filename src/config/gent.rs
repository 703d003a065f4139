//! `[material.gent]`: Gent rubber's limiting extensibility.
//!
//! `J_m` is the largest `I₁ − 3` the chains allow (dimensionless); the energy
//! `W = −(μ J_m/2) ln(1 − (I₁ − 3)/J_m)` grows without bound as `I₁ − 3 → J_m`. Natural rubber
//! has `J_m` ≈ 97 (Gent 1996); `J_m → ∞` is the neo-Hookean solid.

use super::{positive, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// `[material.gent]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GentSettings {
    /// The limiting extensibility `J_m` (dimensionless, > 0; required with
    /// `model = "gent"`).
    pub jm: Option<Real>,
}

impl GentSettings {
    /// Checks the section; `used` when `material.model = "gent"` (then `jm` is required).
    pub fn validate(&self, used: bool) -> Result<(), Invalid> {
        match self.jm {
            Some(jm) => positive("material.gent.jm", jm, ""),
            None if used => Err(Invalid::new(
                "material.gent.jm",
                "model = \"gent\" needs the limiting extensibility jm > 0 (I₁ − 3 at which the \
                 chains lock; natural rubber: about 97)",
            )),
            None => Ok(()),
        }
    }

    /// `J_m`, once validated with `used`.
    pub fn jm(&self) -> Real {
        self.jm.unwrap_or(Real::INFINITY)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jm_must_be_given_and_positive_when_used() {
        assert!(GentSettings::default().validate(false).is_ok());
        let e = GentSettings::default().validate(true).unwrap_err();
        assert_eq!(e.key, "material.gent.jm");
        for bad in [0.0, -1.0, Real::NAN, Real::INFINITY] {
            let e = GentSettings { jm: Some(bad) }.validate(false).unwrap_err();
            assert_eq!(e.key, "material.gent.jm", "{bad}");
        }
        assert!(GentSettings { jm: Some(97.2) }.validate(true).is_ok());
    }
}
