//! `[constraints]`: held vertices (boxes, tags, selections), clamps and prescribed paths.

use super::selection::{FixBox, Selection};
use super::values::vec_e;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Fixed vertices: the union of all the selections below.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Constraints {
    /// Fix vertices whose `constraint_indicators` mesh field is non-zero (default: `true`).
    pub use_constraint_indicators: bool,
    /// Fix vertices whose `node_tags` value is in this list (default: `[]`).
    pub fix_tags: Vec<i64>,
    /// Fix vertices inside any of these boxes (default: none).
    pub fix_boxes: Vec<FixBox>,
    /// Clamped boundaries (`[[constraints.clamp]]`): on the boundary edges whose two vertices
    /// are selected, those vertices and their edge neighbours (one ring) are held, and with
    /// edge DOFs the boundary edges' rotations too: positions and rotation (default: none).
    pub clamp: Vec<Selection>,
    /// Prescribed displacements (`[[constraints.displacement]]`): selected vertices move to
    /// `reference + dial × displacement` (default: none).
    pub displacement: Vec<Prescribed>,
}

/// A prescribed displacement path.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prescribed {
    /// Displacement at dial 1 (m).
    pub displacement: [Real; 3],
    /// The vertices.
    #[serde(flatten)]
    pub on: Selection,
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints {
            use_constraint_indicators: true,
            fix_tags: Vec::new(),
            fix_boxes: Vec::new(),
            clamp: Vec::new(),
            displacement: Vec::new(),
        }
    }
}

impl Constraints {
    /// Validates `[constraints]`: well-formed boxes and selections, finite displacements.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        for (i, b) in self.fix_boxes.iter().enumerate() {
            if b.min.iter().chain(b.max.iter()).any(|v| !v.is_finite())
                || (0..3).any(|k| b.min[k] > b.max[k])
            {
                return ck.inv(
                    &format!("constraints.fix_boxes[{i}]"),
                    "needs finite min ≤ max".into(),
                );
            }
        }
        let cs = self;
        for (i, sel) in cs.clamp.iter().enumerate() {
            ck.selection(&format!("constraints.clamp[{i}]"), sel)?;
        }
        for (i, d) in cs.displacement.iter().enumerate() {
            // A displacement moves vertices: it is bounded like the coordinates themselves.
            let max = crate::mesh::MAX_COORDINATE;
            if !d
                .displacement
                .iter()
                .all(|c| c.is_finite() && c.abs() <= max)
            {
                return ck.inv(
                    &format!("constraints.displacement[{i}].displacement"),
                    format!(
                        "must be finite with components within ±{max_h} m, got {}",
                        vec_e(&d.displacement),
                        max_h = crate::math::human(max)
                    ),
                );
            }
            ck.selection(&format!("constraints.displacement[{i}]"), &d.on)?;
        }
        Ok(())
    }
}
