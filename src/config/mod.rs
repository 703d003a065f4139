//! Validated configuration sections, one file each: the raw TOML of a section, its defaults,
//! and its own `validate`, which names the offending key. A section here imports nothing above
//! [`crate::math`]; `crate::settings` embeds the sections and turns an [`Invalid`] into the
//! settings error that names the file.
//!
//! * [`gent`]: `[material.gent]`, Gent rubber's limiting extensibility `J_m`;
//! * [`shell`]: the values the shell kernels dispatch on (bending variant, stretching
//!   convention, Hessian projection);
//! * [`view`]: a picture's view direction (`--view`, `output.snapshot_view`);
//! * [`obstacle`]: `[[obstacles]]`, rigid obstacles.

pub mod gent;
pub mod obstacle;
pub mod shell;
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
