//! `[rest]`: the target rest forms (uniform, from the mesh, or the liquid-crystal director law)
//! and the liquid-crystal constants.

use super::values::Field;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Where the target rest forms come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TargetForms {
    /// No growth: ā = a⁰, b̄ = b⁰ of the input mesh (seed 000 "No Growth").
    #[default]
    None,
    /// `abar`, `bbar` from these settings (numbers or expressions of x, y), in reference
    /// Cartesian coordinates.
    Uniform,
    /// Per-face `abar_info` (required) and `bbar_info` (optional, default 0) mesh fields, in
    /// reference Cartesian coordinates (MorphoShell's files).
    Mesh,
    /// The liquid-crystal director law ([`crate::rest::lce`]): per face a director angle θ, a stretch
    /// λ and a ratio ν, from `[rest.lce]` or from the mesh's `abar_info` read as (θ, λ, ν).
    Lce,
}

impl TargetForms {
    /// Every value, for the registry test.
    pub const ALL: [TargetForms; 4] = [
        TargetForms::None,
        TargetForms::Uniform,
        TargetForms::Mesh,
        TargetForms::Lce,
    ];

    /// The settings name.
    pub fn name(self) -> &'static str {
        match self {
            TargetForms::None => "none",
            TargetForms::Uniform => "uniform",
            TargetForms::Mesh => "mesh",
            TargetForms::Lce => "lce",
        }
    }
}

/// The director law's per-face values, numbers or expressions of the reference x, y (m) at each
/// face's centroid.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LceSettings {
    /// Director angle θ from the reference x axis (rad).
    pub theta: Field,
    /// Target stretch λ along the director (> 0).
    pub lambda: Field,
    /// Opto-thermal Poisson ratio ν (default: `0.5`).
    #[serde(default = "half")]
    pub nu: Field,
}

fn half() -> Field {
    Field::Value(0.5)
}

/// Rest forms.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Rest {
    /// Target forms: `"none"`, `"uniform"` or `"mesh"` (default: `"none"`).
    pub target: TargetForms,
    /// Target ā as `[xx, xy, yy]` in reference Cartesian coordinates, each a number or an
    /// expression of x, y (dimensionless, default: `[1, 0, 1]`).
    pub abar: [Field; 3],
    /// Target b̄ as `[xx, xy, yy]` in reference Cartesian coordinates, numbers or expressions
    /// (1/m, default: `[0, 0, 0]`).
    pub bbar: [Field; 3],
    /// Dynamic mode: time over which the forms are dialled linearly from the input mesh's forms to
    /// the target (s, default: `0` = target from the start).
    pub dial_time: Real,
    /// The director law's values for `target = "lce"` (default: none, read from the mesh).
    pub lce: Option<LceSettings>,
}

impl Default for Rest {
    fn default() -> Self {
        Rest {
            target: TargetForms::None,
            abar: [1.0.into(), 0.0.into(), 1.0.into()],
            bbar: [0.0.into(), 0.0.into(), 0.0.into()],
            dial_time: 0.0,
            lce: None,
        }
    }
}

impl Rest {
    /// Validates `[rest]`: finite (or parseable) target forms, a positive definite uniform ā, the dial time.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let r = self;
        for (name, form) in [("abar", &r.abar), ("bbar", &r.bbar)] {
            for (i, v) in form.iter().enumerate() {
                let key = format!("rest.{name}[{i}]");
                match v {
                    Field::Value(v) if !v.is_finite() => {
                        return ck.inv(
                            &key,
                            format!("must be finite, got {v_h}", v_h = crate::math::human(v)),
                        )
                    }
                    Field::Expr(_) => {
                        if let Err(e) = v.compile() {
                            return ck.inv(&key, e.to_string());
                        }
                    }
                    _ => {}
                }
            }
        }
        if let [Some(a0), Some(a1), Some(a2)] = r.abar.clone().map(|f| f.constant()) {
            if r.target == TargetForms::Uniform && !(a0 > 0.0 && a0 * a2 - a1 * a1 > 0.0) {
                return ck.inv(
                    "rest.abar",
                    format!("must be positive definite, got [{a0}, {a1}, {a2}]"),
                );
            }
        }
        ck.nonneg("rest.dial_time", r.dial_time)?;
        if let Some(l) = &r.lce {
            for (key, f) in [("theta", &l.theta), ("lambda", &l.lambda), ("nu", &l.nu)] {
                let key = format!("rest.lce.{key}");
                if let Err(e) = f.compile() {
                    return ck.inv(&key, e.to_string());
                }
                if let Some(v) = f.constant() {
                    if !v.is_finite() {
                        return ck.inv(
                            &key,
                            format!("must be finite, got {v_h}", v_h = crate::math::human(v)),
                        );
                    }
                }
            }
            if let Some(v) = l.lambda.constant() {
                if v <= 0.0 {
                    return ck.inv("rest.lce.lambda", format!("must be positive, got {v}"));
                }
            }
            if r.target != TargetForms::Lce {
                return ck.inv("rest.lce", "is used only with rest.target = \"lce\"".into());
            }
        }
        Ok(())
    }
}
