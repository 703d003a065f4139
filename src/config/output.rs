//! `[output]`: the frames' format, their fields and precision, the snapshots.

use super::{Check, Invalid};
use crate::mesh::io::Format;
use serde::{Deserialize, Serialize};

/// Output files.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Frame format: `"vtu"` (XML), `"vtk"` (legacy binary) or `"vtk_ascii"` (default: `"vtu"`).
    pub format: Format,
    /// Static mode: also write a frame after every accepted continuation step, each solved to the
    /// full tolerance (default: `false`).
    pub continuation_frames: bool,
    /// Basename of frame files, `{prefix}_{index:05}.{ext}` (default: `"frame"`).
    pub prefix: String,
    /// Also write MorphoShell's derived fields: angle deficits and their Gauss curvature per
    /// vertex, its strain measure and the principal Cauchy stresses per face
    /// (`src/fields.rs`; default: `false`).
    pub morphoshell_fields: bool,
    /// `.vtu` frames: compression of every array, `"zlib"`, `"lz4"` or `"none"` (default:
    /// `"zlib"`).
    pub compression: Option<crate::mesh::vtu::Compression>,
    /// `.vtu` frames: `"appended"` (raw bytes after the XML, ParaView's default) or `"base64"`
    /// (inline, valid XML) (default: `"appended"`).
    pub encoding: Option<crate::mesh::vtu::Encoding>,
    /// `"single"` or `"double"`: the precision of derived fields (curvatures, forms, stresses,
    /// energy densities, …). Positions, the displacement (which gives the reference positions)
    /// and the fields a restart reads are always double (default: `"single"`).
    pub precision: Precision,
    /// The fields frames carry: names, and the keywords `"default"` (every field but the
    /// current forms `a` and `b`, which the positions determine) and `"all"` (default:
    /// `["default"]`). The fields a restart reads (velocity in the dynamic modes, edge angles,
    /// term states) are always written.
    pub fields: Vec<String>,
    /// PNG pictures beside frames (`src/render.rs`): `"none"`, `"all"` (beside every frame) or
    /// `"final"` (beside the last one) (default: `"none"`).
    pub snapshots: Snapshots,
    /// The field the snapshots are coloured by (default: `mean_curvature`).
    pub snapshot_field: Option<String>,
    /// The snapshots' view: `iso`, `top`, `bottom`, `front`, `back`, `side` or `"AZ,EL"`
    /// (default: `"iso"`).
    pub snapshot_view: String,
    /// The snapshots' size in pixels (default: `[1024, 768]`).
    pub snapshot_size: [usize; 2],
}

/// Which frames get a PNG snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Snapshots {
    /// None.
    None,
    /// Every frame.
    All,
    /// The last frame, written when the run ends.
    Final,
}

/// Floating-point precision of derived output fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// Float64.
    Double,
    /// Float32: half the bytes, 7 significant digits.
    Single,
}

/// The fields `output.fields = ["default"]` leaves out: the current fundamental forms, which
/// the positions determine.
pub const NOT_DEFAULT_FIELDS: [&str; 2] = ["a", "b"];

impl Default for Output {
    fn default() -> Self {
        Output {
            format: Format::Vtu,
            continuation_frames: false,
            prefix: "frame".into(),
            morphoshell_fields: false,
            compression: None,
            encoding: None,
            precision: Precision::Single,
            fields: vec!["default".into()],
            snapshots: Snapshots::None,
            snapshot_field: None,
            snapshot_view: "iso".into(),
            snapshot_size: [1024, 768],
        }
    }
}

impl Output {
    /// Whether frames carry every field.
    pub fn all_fields(&self) -> bool {
        self.fields.iter().any(|f| f == "all")
    }

    /// Whether a field named `name` is written (the restart's fields aside).
    pub fn selects(&self, name: &str) -> bool {
        self.all_fields()
            || self.fields.iter().any(|f| f == name)
            || (self.fields.iter().any(|f| f == "default") && !NOT_DEFAULT_FIELDS.contains(&name))
    }
}

impl Output {
    /// Validates `[output]`: a plain file-name prefix.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        if self.prefix.is_empty() || self.prefix.contains(['/', '\\']) {
            return ck.inv(
                "output.prefix",
                "must be a plain, non-empty file name".into(),
            );
        }
        let o = self;
        if o.format != Format::Vtu {
            for (key, set) in [
                ("output.compression", o.compression.is_some()),
                ("output.encoding", o.encoding.is_some()),
            ] {
                if set {
                    return ck.inv(
                        key,
                        format!(
                            "applies to .vtu frames only (output.format = \"{}\")",
                            o.format.name()
                        ),
                    );
                }
            }
        }
        if o.snapshots != Snapshots::None {
            crate::config::view::angles(&o.snapshot_view)
                .map(|_| ())
                .or_else(|e| ck.inv("output.snapshot_view", e))?;
            let [w, h] = o.snapshot_size;
            let max = crate::config::view::MAX_SIDE;
            if !(64..=max).contains(&w) || !(64..=max).contains(&h) {
                return ck.inv(
                    "output.snapshot_size",
                    format!("[{w}, {h}]: each side must lie in 64–{max} pixels"),
                );
            }
        }
        if o.fields.is_empty() {
            return ck.inv(
                "output.fields",
                "is empty: list field names, or [\"all\"]".into(),
            );
        }
        if o.all_fields() && o.fields.len() > 1 {
            return ck.inv(
                "output.fields",
                "\"all\" cannot be combined with other entries".into(),
            );
        }
        Ok(())
    }
}
