//! Which vertices or faces a load or constraint acts on: tags and a box.

use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Which vertices (by `node_tags`) or faces (by `tri_tags`) a load or constraint acts on: those
/// whose tag is in `tags` (any, when empty) and, when `inside` is given, whose reference position
/// (a face: its centroid) lies in that box. At least one of the two must be given.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Selection {
    /// Tags (default: `[]`).
    pub tags: Vec<i64>,
    /// Box (m, default: none).
    pub inside: Option<FixBox>,
}

/// An axis-aligned box of vertices to hold fixed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FixBox {
    /// Lower corner (m).
    pub min: [Real; 3],
    /// Upper corner (m).
    pub max: [Real; 3],
}

impl Check {
    /// A selection's box must be finite with min ≤ max.
    pub(crate) fn selection(&self, key: &str, sel: &Selection) -> Result<(), Invalid> {
        self.inside(key, sel.inside.as_ref())
    }

    /// A region of faces with its own values (`[[growth.regions]]`, `[[moisture.regions]]`,
    /// `[[material.regions]]`) selects by `tags` or a box `inside` (the uniform values cover
    /// every face), and the box must be finite with min ≤ max.
    pub(crate) fn region(
        &self,
        key: &str,
        tags: &[i64],
        inside: Option<&FixBox>,
    ) -> Result<(), Invalid> {
        if tags.is_empty() && inside.is_none() {
            return self.inv(
                key,
                "needs tags or inside (the uniform values cover every face)".into(),
            );
        }
        self.inside(key, inside)
    }

    /// A box `inside` (when given) must be finite with min ≤ max; the error is at `key.inside`.
    pub(crate) fn inside(&self, key: &str, inside: Option<&FixBox>) -> Result<(), Invalid> {
        if let Some(b) = inside {
            if b.min.iter().chain(b.max.iter()).any(|v| !v.is_finite())
                || (0..3).any(|k| b.min[k] > b.max[k])
            {
                return self.inv(&format!("{key}.inside"), "needs finite min ≤ max".into());
            }
        }
        Ok(())
    }
}
