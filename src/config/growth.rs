//! `[growth]`: the growth and swelling law that computes the target rest forms, and its
//! constants.

use super::limits::MAX_MOISTURE;
use super::rest::TargetForms;
use super::values::Field;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Which rest-form law computes the target forms (see [`crate::rest::laws`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GrowthLaw {
    /// No growth law: the targets come from `[rest]`.
    #[default]
    None,
    /// Uniform volumetric growth: `ā = e^{2s} a⁰`, `b̄ = e^s b⁰`, `h̄ = e^s h`, s from the face
    /// field `growth_factor` or `growth.s`.
    Isotropic,
    /// In-plane growth at fixed thickness: `ā = e^{2s} a⁰`, `b̄ = e^{2s} b⁰`.
    IsotropicInPlane,
    /// Seed 000's law as printed: `ā = e^{2s} a⁰`, `b̄ = b⁰`.
    IsotropicMetricOnly,
    /// Linear differential swelling from the top and bottom moisture, coefficient `mu`.
    LinearSwelling,
    /// Piecewise-constant bilayer, coefficients `mu_top` and `mu_bottom`.
    Bilayer,
    /// Linear swelling with a machine direction: `mu` along it, `mu_perp` across it.
    MachineDirection,
}

impl GrowthLaw {
    /// Every law, `"none"` first (the registry in `rest::laws` has an entry for each other one).
    pub const ALL: [GrowthLaw; 7] = [
        GrowthLaw::None,
        GrowthLaw::Isotropic,
        GrowthLaw::IsotropicInPlane,
        GrowthLaw::IsotropicMetricOnly,
        GrowthLaw::LinearSwelling,
        GrowthLaw::Bilayer,
        GrowthLaw::MachineDirection,
    ];

    /// The law's settings value, as in the settings file.
    pub fn name(self) -> &'static str {
        match self {
            GrowthLaw::None => "none",
            GrowthLaw::Isotropic => "isotropic",
            GrowthLaw::IsotropicInPlane => "isotropic_in_plane",
            GrowthLaw::IsotropicMetricOnly => "isotropic_metric_only",
            GrowthLaw::LinearSwelling => "linear_swelling",
            GrowthLaw::Bilayer => "bilayer",
            GrowthLaw::MachineDirection => "machine_direction",
        }
    }

    /// The `[growth]` coefficients the law needs (each must be given).
    pub fn coefficients(self) -> &'static [&'static str] {
        match self {
            GrowthLaw::LinearSwelling => &["mu"],
            GrowthLaw::Bilayer => &["mu_top", "mu_bottom"],
            GrowthLaw::MachineDirection => &["mu", "mu_perp"],
            _ => &[],
        }
    }
}

/// A growth law with the coefficients it reads: `[growth]` once validated ([`Growth::model`]).
/// The isotropic laws' factor `s` and the moisture are per-face inputs
/// ([`crate::rest::laws::GrowthInputs`]), not coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GrowthModel {
    /// No growth law.
    None,
    /// Uniform volumetric growth.
    Isotropic,
    /// In-plane growth at fixed thickness.
    IsotropicInPlane,
    /// Seed 000's law as printed.
    IsotropicMetricOnly,
    /// Linear differential swelling.
    LinearSwelling {
        /// Moisture–length coefficient (per unit moisture).
        mu: Real,
    },
    /// Piecewise-constant bilayer.
    Bilayer {
        /// Coefficient of the top layer (per unit moisture).
        mu_top: Real,
        /// Coefficient of the bottom layer (per unit moisture).
        mu_bottom: Real,
    },
    /// Linear swelling with a machine direction.
    MachineDirection {
        /// Coefficient along the machine direction (per unit moisture).
        mu: Real,
        /// Coefficient across it (per unit moisture).
        mu_perp: Real,
    },
}

impl GrowthModel {
    /// The law's settings value.
    pub fn law(self) -> GrowthLaw {
        match self {
            GrowthModel::None => GrowthLaw::None,
            GrowthModel::Isotropic => GrowthLaw::Isotropic,
            GrowthModel::IsotropicInPlane => GrowthLaw::IsotropicInPlane,
            GrowthModel::IsotropicMetricOnly => GrowthLaw::IsotropicMetricOnly,
            GrowthModel::LinearSwelling { .. } => GrowthLaw::LinearSwelling,
            GrowthModel::Bilayer { .. } => GrowthLaw::Bilayer,
            GrowthModel::MachineDirection { .. } => GrowthLaw::MachineDirection,
        }
    }
}

/// `[growth]`: the rest-form laws of seed 000 §3. Per-face mesh fields take precedence over the
/// uniform values here: `moisture_top`, `moisture_bottom` (dimensionless moisture fractions),
/// `growth_factor` (s), `machine_direction` (3 components, reference Cartesian coordinates).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Growth {
    /// The law (default: `"none"`).
    pub law: GrowthLaw,
    /// Moisture–length coefficient μ along the machine direction, or isotropic (per unit
    /// moisture; required by `"linear_swelling"` and `"machine_direction"`).
    pub mu: Option<Real>,
    /// Moisture–length coefficient μ⊥ across the machine direction (required by
    /// `"machine_direction"`).
    pub mu_perp: Option<Real>,
    /// Bilayer: coefficient of the top layer (required by `"bilayer"`).
    pub mu_top: Option<Real>,
    /// Bilayer: coefficient of the bottom layer (required by `"bilayer"`).
    pub mu_bottom: Option<Real>,
    /// Uniform moisture at the top surface (dimensionless fraction, default `0`).
    pub moisture_top: Real,
    /// Uniform moisture at the bottom surface (default `0`).
    pub moisture_bottom: Real,
    /// Conformal growth factor s of the isotropic laws: a number or an expression of the
    /// reference x, y (the isotropic laws need it or the face field `growth_factor`).
    pub s: Option<Field>,
    /// Uniform machine direction in reference Cartesian coordinates (default `[1, 0, 0]`).
    pub machine_direction: [Real; 3],
}

impl Default for Growth {
    fn default() -> Self {
        Growth {
            law: GrowthLaw::None,
            mu: None,
            mu_perp: None,
            mu_top: None,
            mu_bottom: None,
            moisture_top: 0.0,
            moisture_bottom: 0.0,
            s: None,
            machine_direction: [1.0, 0.0, 0.0],
        }
    }
}

impl Growth {
    /// The law with its own coefficients. On validated settings every coefficient the law
    /// needs is given ([`Growth::validate`]); a missing one reads as 0.
    pub fn model(&self) -> GrowthModel {
        let c = |v: Option<Real>| v.unwrap_or(0.0);
        match self.law {
            GrowthLaw::None => GrowthModel::None,
            GrowthLaw::Isotropic => GrowthModel::Isotropic,
            GrowthLaw::IsotropicInPlane => GrowthModel::IsotropicInPlane,
            GrowthLaw::IsotropicMetricOnly => GrowthModel::IsotropicMetricOnly,
            GrowthLaw::LinearSwelling => GrowthModel::LinearSwelling { mu: c(self.mu) },
            GrowthLaw::Bilayer => GrowthModel::Bilayer {
                mu_top: c(self.mu_top),
                mu_bottom: c(self.mu_bottom),
            },
            GrowthLaw::MachineDirection => GrowthModel::MachineDirection {
                mu: c(self.mu),
                mu_perp: c(self.mu_perp),
            },
        }
    }

    /// Validates `[growth]`: finite coefficients, a valid `s`, and no growth law together with `rest.target`.
    /// `target` is `rest.target`: a growth law computes the targets, so none may be given.
    pub fn validate(&self, target: TargetForms) -> Result<(), Invalid> {
        let ck = Check;
        let g = self;
        for (k, v) in [
            ("mu", g.mu),
            ("mu_perp", g.mu_perp),
            ("mu_top", g.mu_top),
            ("mu_bottom", g.mu_bottom),
        ] {
            if v.is_none() && g.law.coefficients().contains(&k) {
                return ck.inv(
                    &format!("growth.{k}"),
                    format!(
                        "growth.law = \"{}\" needs its coefficient {k} (per unit moisture); \
                         it needs {}",
                        g.law.name(),
                        g.law.coefficients().join(" and ")
                    ),
                );
            }
        }
        for (k, v) in [
            ("growth.mu", g.mu.unwrap_or(0.0)),
            ("growth.mu_perp", g.mu_perp.unwrap_or(0.0)),
            ("growth.mu_top", g.mu_top.unwrap_or(0.0)),
            ("growth.mu_bottom", g.mu_bottom.unwrap_or(0.0)),
            ("growth.moisture_top", g.moisture_top),
            ("growth.moisture_bottom", g.moisture_bottom),
        ] {
            if !v.is_finite() || v.abs() > MAX_MOISTURE {
                return ck.inv(
                    k,
                    format!(
                        "must lie in ±{MAX_MOISTURE_h}, got {v_h}",
                        MAX_MOISTURE_h = crate::math::human(MAX_MOISTURE),
                        v_h = crate::math::human(v)
                    ),
                );
            }
        }
        match &g.s {
            Some(Field::Value(v)) if !v.is_finite() => {
                return ck.inv(
                    "growth.s",
                    format!("must be finite, got {v_h}", v_h = crate::math::human(v)),
                )
            }
            Some(s @ Field::Expr(_)) => {
                if let Err(e) = s.compile() {
                    return ck.inv("growth.s", e.to_string());
                }
            }
            _ => {}
        }
        if g.law != GrowthLaw::None && target != TargetForms::None {
            return ck.inv(
                "growth.law",
                format!(
                    "a growth law computes the target forms, so rest.target must be \"none\" \
                     (it is {:?}); use one or the other",
                    target
                ),
            );
        }
        Ok(())
    }
}
