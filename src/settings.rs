//! The settings file: a TOML schema with every field's unit and default, strict parsing
//! (unknown keys are errors), `--set key=value` overrides, and validation with messages that
//! name the key. The full reference with examples is `docs/settings.md`.

use crate::config::Invalid;
use serde::{Deserialize, Serialize};
use std::path::Path;

pub use crate::config::constraints::{Constraints, Prescribed};
pub use crate::config::contact::Contact;
pub use crate::config::dial::{Dial, DialFrom, DialOrder};
pub use crate::config::explicit::{EquilibriumTest, Explicit};
pub use crate::config::gas::{Gas, GasControl, GasProcess};
pub use crate::config::growth::{Growth, GrowthLaw};
pub use crate::config::limits::*;
pub use crate::config::loads::{Loads, MomentLoad, PointLoad, PressureLoad, TractionLoad};
pub use crate::config::material::{
    BaraffWitkinSettings, BendingModel, Material, MaterialModel, PrismLaw, PrismSettings,
    PrismThickness,
};
pub use crate::config::moisture::{
    GroundMoisture, Moisture, MoistureBoundary, SurfaceKind, SurfaceSide,
};
pub use crate::config::output::{Output, Precision, Snapshots, NOT_DEFAULT_FIELDS};
pub use crate::config::rest::{LceSettings, Rest, TargetForms};
pub use crate::config::selection::{FixBox, Selection};
pub use crate::config::slides::{SlideControl, Slides};
pub use crate::config::solver::{Continuation, Mode, Solver};
pub use crate::config::time::Time;
pub use crate::config::values::{Auto, AutoOr, Field, Softening};

/// Errors in the settings file or its overrides.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SettingsError {
    /// The file could not be read.
    #[error("{path}: cannot read settings: {reason}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// The TOML is malformed, has an unknown key or a wrong type.
    #[error("{path}: {reason}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's message, with line and key.
        reason: String,
    },
    /// A value is out of range or inconsistent.
    #[error("{path}: invalid '{key}': {reason}")]
    Invalid {
        /// The file.
        path: String,
        /// Dotted key.
        key: String,
        /// Why.
        reason: String,
    },
    /// A `--set` override is malformed.
    #[error("--set {arg}: {reason}")]
    Override {
        /// The argument as given.
        arg: String,
        /// Why.
        reason: String,
    },
}

/// A whole settings file.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Material constants.
    pub material: Material,
    /// Rest (programmed) fundamental forms and how they are dialled.
    pub rest: Rest,
    /// Growth and swelling laws that compute the target rest forms (seed 000 §3).
    pub growth: Growth,
    /// Moisture diffusion that drives the swelling laws in time (seed 000 §4).
    pub moisture: Moisture,
    /// Heat conduction that drives the thermal shrink law in time.
    pub temperature: crate::config::temperature::Temperature,
    /// What is solved: statics or dynamics, and the Newton solver's controls.
    pub solver: Solver,
    /// Time stepping (dynamic mode).
    pub time: Time,
    /// Explicit damped dynamics (explicit mode): time step, damping, dial and equilibrium test.
    pub explicit: Explicit,
    /// How the rest forms are dialled: order and hold points (every mode).
    pub dial: Dial,
    /// External loads.
    pub loads: Loads,
    /// An enclosed gas (closed meshes): amount, pressure or volume control.
    pub gas: Gas,
    /// Ground contact with friction.
    pub contact: Contact,
    /// Contact of the sheet with itself and between sheets.
    pub self_contact: crate::config::self_contact::SelfContact,
    /// Two horizontal glass slides squeezing the sheet (MorphoShell's).
    pub slides: Slides,
    /// Rigid obstacles (`[[obstacles]]`), fixed or moved with the dial.
    pub obstacles: Vec<crate::config::obstacle::ObstacleSettings>,
    /// Fixed vertices.
    pub constraints: Constraints,
    /// Output files.
    pub output: Output,
}

/// Parses a `--set key=value` value with TOML's rules (number, bool, array, inline table,
/// quoted string); a bare word (letters, digits, `_`, `-`, not starting with a digit or sign)
/// is taken as a string, so `--set solver.mode=dynamic` works. Anything else that TOML rejects
/// (an integer beyond 64 bits, say) is an error with TOML's reason.
fn parse_override_value(v: &str) -> Result<toml::Value, String> {
    let doc = format!("v = {v}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => Ok(t.remove("v").unwrap_or(toml::Value::String(v.into()))),
        Err(e) => {
            let word = v.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                && v.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if word {
                Ok(toml::Value::String(v.into()))
            } else {
                Err(format!(
                    "'{v}' is not a TOML value: {}",
                    e.message().trim_end()
                ))
            }
        }
    }
}

/// Applies `key=value` overrides (dotted keys) to a TOML table.
pub fn apply_overrides(table: &mut toml::Table, overrides: &[String]) -> Result<(), SettingsError> {
    for arg in overrides {
        let oerr = |reason: &str| SettingsError::Override {
            arg: arg.clone(),
            reason: reason.into(),
        };
        let (key, value) = arg
            .split_once('=')
            .ok_or_else(|| oerr("expected key=value"))?;
        let parts: Vec<&str> = key.trim().split('.').collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err(oerr("empty key segment"));
        }
        let mut cur = &mut *table;
        for p in &parts[..parts.len() - 1] {
            let entry = cur
                .entry(p.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            cur = entry
                .as_table_mut()
                .ok_or_else(|| oerr(&format!("'{p}' is not a table")))?;
        }
        let value = parse_override_value(value.trim()).map_err(|e| oerr(&e))?;
        cur.insert(parts[parts.len() - 1].to_string(), value);
    }
    Ok(())
}

impl Settings {
    /// Reads, overrides, parses and validates a settings file.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Settings, SettingsError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SettingsError::Read {
            path: name.clone(),
            reason: e.to_string(),
        })?;
        let mut settings = Self::from_str_with(&text, &name, overrides)?;
        // A mesh obstacle's file is relative to the settings file's folder; it is kept absolute,
        // so that the resolved settings written with a run name it from anywhere.
        let folder = path.parent().unwrap_or(Path::new(""));
        for o in &mut settings.obstacles {
            if let Some(f) = o
                .file
                .as_mut()
                .filter(|f| Path::new(f.as_str()).is_relative())
            {
                let joined = folder.join(f.as_str());
                *f = std::path::absolute(&joined)
                    .unwrap_or(joined)
                    .display()
                    .to_string();
            }
        }
        Ok(settings)
    }

    /// Parses settings from text (`name` is used in messages).
    pub fn from_str_with(
        text: &str,
        name: &str,
        overrides: &[String],
    ) -> Result<Settings, SettingsError> {
        let perr = |reason: String| SettingsError::Parse {
            path: name.to_string(),
            reason,
        };
        if crate::config::design::is_design_file(text) {
            return Err(perr(format!(
                "this is a design file (it has a [design] section): design with \
                 `shellsim design {name} MESH TARGET`, or remove the section to run the scene"
            )));
        }
        // Parse directly first, for messages with line numbers.
        let direct: Result<Settings, _> = toml::from_str(text);
        let settings = if overrides.is_empty() {
            direct.map_err(|e| perr(e.to_string().trim_end().to_string()))?
        } else {
            let mut table: toml::Table = text
                .parse()
                .map_err(|e: toml::de::Error| perr(e.to_string().trim_end().to_string()))?;
            apply_overrides(&mut table, overrides)?;
            toml::Value::Table(table)
                .try_into()
                .map_err(|e: toml::de::Error| {
                    perr(format!(
                        "after --set overrides: {}",
                        e.to_string().trim_end()
                    ))
                })?
        };
        settings.validate(name)?;
        Ok(settings)
    }

    /// Validates every section (`crate::config`), each with the values of the other sections
    /// it depends on; the first error is reported, naming the file and the key.
    pub fn validate(&self, name: &str) -> Result<(), SettingsError> {
        self.validate_sections().map_err(|e| invalid_in(name, e))
    }

    /// Every section's checks, in a fixed order.
    fn validate_sections(&self) -> Result<(), Invalid> {
        let mode = self.solver.mode;
        self.material.validate(mode)?;
        self.rest.validate()?;
        self.solver.validate()?;
        self.growth.validate(self.rest.target)?;
        self.moisture
            .validate(&self.growth, self.contact.enabled, mode)?;
        self.temperature
            .validate(&self.growth, self.moisture.enabled, mode)?;
        let mo = &self.moisture;
        if mo.enabled && self.material.density + mo.initial * mo.water_density <= 0.0 {
            return Err(Invalid::new(
                "moisture.initial",
                format!(
                    "{} leaves the sheet without mass: material.density + moisture.initial × \
                     moisture.water_density = {} kg/m³ must stay positive",
                    crate::math::human(mo.initial),
                    crate::math::human(self.material.density + mo.initial * mo.water_density)
                ),
            ));
        }
        self.time.validate()?;
        self.explicit.validate()?;
        self.dial.validate(
            self.growth.law != GrowthLaw::None || self.moisture.enabled || self.temperature.enabled,
        )?;
        if mode == Mode::Explicit && self.material.bending.angle_variant().is_some() {
            return Err(Invalid::new(
                "material.bending",
                "explicit mode integrates vertex positions only; the mid-edge angle models carry \
                 edge rotations without inertia. Use \"patch_fit\" (MorphoShell's), \
                 \"midedge_average\" or \"none\"",
            ));
        }
        self.slides.validate(mode)?;
        self.loads.validate()?;
        self.gas.validate()?;
        self.contact.validate()?;
        self.self_contact.validate(
            mode,
            self.obstacles
                .iter()
                .any(|o| o.shape == Some(crate::config::obstacle::ShapeKind::Mesh)),
        )?;
        for (i, o) in self.obstacles.iter().enumerate() {
            o.validate(i, mode)?;
        }
        self.constraints.validate()?;
        self.output.validate()?;
        Ok(())
    }
}

/// A section's error, in the settings file `name`.
fn invalid_in(name: &str, e: crate::config::Invalid) -> SettingsError {
    SettingsError::Invalid {
        path: name.to_string(),
        key: e.key,
        reason: e.reason,
    }
}
