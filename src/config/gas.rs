//! `[gas]`: a gas enclosed by the mesh (seed 002 §5): how it is controlled, its amount,
//! pressure or volume, the outside pressure and the gas law.

use super::limits::MAX_LOAD;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// How the enclosed gas is controlled (see [`crate::energy::gas`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GasControl {
    /// No gas.
    #[default]
    None,
    /// A fixed amount of ideal gas (`amount`), dialled from the outside pressure's.
    Amount,
    /// A prescribed gauge pressure (`pressure`), dialled from 0.
    Pressure,
    /// A prescribed enclosed volume (`volume`), the pressure being its multiplier.
    Volume,
}

/// The gas law of amount control.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GasProcess {
    /// `p V = const` (seed 002 Eq. 12).
    #[default]
    Isothermal,
    /// `p V^γ = const`.
    Adiabatic,
}

/// `[gas]`: a gas enclosed by the mesh (seed 002 §5). The mesh must be a closed, consistently
/// oriented surface with outward normals.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Gas {
    /// `"none"`, `"amount"`, `"pressure"` or `"volume"` (default: `"none"`).
    pub control: GasControl,
    /// Amount control: the gas's `p V` at the reference volume when the dial reaches 1, i.e.
    /// its `n R T` (J = Pa·m³, > 0).
    pub amount: Real,
    /// Pressure control: the gauge pressure at dial 1 (Pa; positive inflates).
    pub pressure: Real,
    /// Volume control: the enclosed volume at dial 1 (m³, > 0).
    pub volume: Real,
    /// Pressure outside (Pa, ≥ 0, default: `0`); amount control inflates against it.
    pub external_pressure: Real,
    /// Amount control: `"isothermal"` (p V = const) or `"adiabatic"` (p V^γ = const)
    /// (default: `"isothermal"`).
    pub process: GasProcess,
    /// Heat capacity ratio γ of the adiabatic process (dimensionless, > 1, default: `1.4`).
    pub gamma: Real,
}

impl Default for Gas {
    fn default() -> Self {
        Gas {
            control: GasControl::None,
            amount: 0.0,
            pressure: 0.0,
            volume: 0.0,
            external_pressure: 0.0,
            process: GasProcess::Isothermal,
            gamma: 1.4,
        }
    }
}

impl Gas {
    /// Validates `[gas]`: the control's value (a positive amount or volume, a finite
    /// pressure), the external pressure and γ.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let g = self;
        if g.control == GasControl::None {
            return Ok(());
        }
        let within = |key: &str, v: Real, unit: &str| {
            if v.is_finite() && v.abs() <= MAX_LOAD {
                Ok(())
            } else {
                ck.inv(
                    key,
                    format!(
                        "must be finite within ±{MAX_LOAD_h} {unit}, got {v_h}",
                        MAX_LOAD_h = crate::math::human(MAX_LOAD),
                        v_h = crate::math::human(v)
                    ),
                )
            }
        };
        match g.control {
            GasControl::Amount => {
                if g.amount.is_nan() || g.amount <= 0.0 {
                    return ck.inv(
                        "gas.amount",
                        format!(
                            "amount control needs a positive amount of gas (p V at the reference \
                             volume, J), got {}",
                            crate::math::human(g.amount)
                        ),
                    );
                }
                within("gas.amount", g.amount, "J")?;
            }
            GasControl::Pressure => within("gas.pressure", g.pressure, "Pa")?,
            GasControl::Volume => {
                if g.volume.is_nan() || g.volume <= 0.0 {
                    return ck.inv(
                        "gas.volume",
                        format!(
                            "volume control needs a positive enclosed volume (m³), got {}",
                            crate::math::human(g.volume)
                        ),
                    );
                }
                within("gas.volume", g.volume, "m³")?;
            }
            GasControl::None => {}
        }
        ck.nonneg("gas.external_pressure", g.external_pressure)?;
        within("gas.external_pressure", g.external_pressure, "Pa")?;
        if !(g.gamma > 1.0 && g.gamma <= 10.0) {
            return ck.inv(
                "gas.gamma",
                format!(
                    "must lie in (1, 10] (1.4 for air), got {}",
                    crate::math::human(g.gamma)
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(control: GasControl) -> Gas {
        Gas {
            control,
            amount: 2e4,
            pressure: 5e3,
            volume: 6.0,
            ..Gas::default()
        }
    }

    /// No gas needs nothing; each control checks its own value and names its key.
    #[test]
    fn each_control_checks_its_own_value() {
        assert_eq!(Gas::default().validate(), Ok(()));
        for c in [GasControl::Amount, GasControl::Pressure, GasControl::Volume] {
            assert_eq!(with(c).validate(), Ok(()), "{c:?}");
        }
        let bad = |g: Gas| g.validate().unwrap_err().key;
        let amount = Gas {
            amount: 0.0,
            ..with(GasControl::Amount)
        };
        assert_eq!(bad(amount.clone()), "gas.amount");
        // The amount is not read under pressure control.
        assert_eq!(
            Gas {
                control: GasControl::Pressure,
                ..amount
            }
            .validate(),
            Ok(())
        );
        let volume = Gas {
            volume: -1.0,
            ..with(GasControl::Volume)
        };
        assert_eq!(bad(volume), "gas.volume");
        let pressure = Gas {
            pressure: Real::INFINITY,
            ..with(GasControl::Pressure)
        };
        assert_eq!(bad(pressure), "gas.pressure");
        let outside = Gas {
            external_pressure: -1.0,
            ..with(GasControl::Amount)
        };
        assert_eq!(bad(outside), "gas.external_pressure");
        let gamma = Gas {
            gamma: 1.0,
            ..with(GasControl::Amount)
        };
        assert_eq!(bad(gamma), "gas.gamma");
    }
}
