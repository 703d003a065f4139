//! Validated configuration sections, one file each: the raw TOML of a section, its defaults,
//! and its own `validate`, which names the offending key. A section here imports nothing above
//! [`crate::math`]; `crate::settings` embeds the sections and turns an [`Invalid`] into the
//! settings error that names the file.
//!
//! * [`material`]: `[material]`, the moduli, the membrane and bending models;
//! * [`gent`]: `[material.gent]`, Gent rubber's limiting extensibility `J_m`;
//! * [`shell`]: the values the shell kernels dispatch on (bending variant, stretching
//!   convention, Hessian projection);
//! * [`view`]: a picture's view direction (`--view`, `output.snapshot_view`);
//! * [`obstacle`]: `[[obstacles]]`, rigid obstacles;
//! * [`gas`]: `[gas]`, a gas enclosed by the mesh;
//! * [`rest`]: `[rest]`, the target rest forms;
//! * [`growth`]: `[growth]`, the growth and swelling laws;
//! * [`moisture`]: `[moisture]`, the moisture diffusion that drives swelling;
//! * [`slides`]: `[slides]`, MorphoShell's glass slides;
//! * [`solver`]: `[solver]`, the mode and the Newton and continuation controls;
//! * [`time`]: `[time]`, dynamic mode's time stepping;
//! * [`explicit`]: `[explicit]`, MorphoShell's explicit dynamics;
//! * [`dial`]: `[dial]`, the dialling order, start and holds;
//! * [`output`]: `[output]`, the frames' format, fields and snapshots;
//! * [`contact`]: `[contact]`, the ground plane;
//! * [`loads`]: `[loads]`, gravity and the point, traction, pressure and moment loads;
//! * [`constraints`]: `[constraints]`, held vertices, clamps and prescribed paths;
//! * [`selection`]: which vertices or faces a load or constraint acts on;
//! * [`values`]: values the sections share (a number or `"auto"`, a field of x and y);
//! * [`limits`]: the bounds on values beyond which a run would overflow or never end.

pub mod constraints;
pub mod contact;
pub mod design;
pub mod dial;
pub mod explicit;
pub mod gas;
pub mod gent;
pub mod growth;
pub mod limits;
pub mod loads;
pub mod material;
pub mod moisture;
pub mod obstacle;
pub mod output;
pub mod rest;
pub mod selection;
pub mod self_contact;
pub mod shell;
pub mod slides;
pub mod solver;
pub mod temperature;
pub mod time;
pub mod values;
pub mod view;

use crate::math::Real;

/// A value out of range or inconsistent: the dotted key and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Invalid {
    /// Dotted key, e.g. `material.gent.jm`.
    pub key: String,
    /// Why, in words, with the value given.
    pub reason: String,
}

impl Invalid {
    /// An error at `key`.
    pub fn new(key: &str, reason: impl Into<String>) -> Self {
        Invalid {
            key: key.into(),
            reason: reason.into(),
        }
    }
}

/// `Ok` when `v` is finite and positive, otherwise the error at `key` naming the value and its
/// unit.
pub fn positive(key: &str, v: Real, unit: &str) -> Result<(), Invalid> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            key,
            format!("must be > 0{unit}, got {}", crate::math::human(v)),
        ))
    }
}

/// The checks the section validators share; each error names the dotted key.
#[derive(Clone, Copy)]
pub(crate) struct Check;

impl Check {
    /// The error at `key`.
    pub(crate) fn inv(&self, key: &str, reason: String) -> Result<(), Invalid> {
        Err(Invalid::new(key, reason))
    }

    /// `Ok` when `v` is finite and positive.
    pub(crate) fn pos(&self, key: &str, v: Real) -> Result<(), Invalid> {
        if !(v.is_finite() && v > 0.0) {
            return self.inv(
                key,
                format!(
                    "must be a positive number, got {v_h}",
                    v_h = crate::math::human(v)
                ),
            );
        }
        Ok(())
    }

    /// `Ok` when `v` is finite and not negative.
    pub(crate) fn nonneg(&self, key: &str, v: Real) -> Result<(), Invalid> {
        if !(v.is_finite() && v >= 0.0) {
            return self.inv(
                key,
                format!(
                    "must be a non-negative number, got {v_h}",
                    v_h = crate::math::human(v)
                ),
            );
        }
        Ok(())
    }
}
