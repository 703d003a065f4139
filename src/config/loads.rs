//! `[loads]`: gravity, and point, traction, pressure and moment loads on selected vertices,
//! edges and faces, scaled by the dial.

use super::limits::{MAX_GRAVITY, MAX_LOAD};
use super::selection::Selection;
use super::values::vec_e;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// External loads.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Loads {
    /// Gravitational acceleration (m/s², default: `[0, 0, 0]`; Earth: `[0, 0, -9.81]`).
    pub gravity: [Real; 3],
    /// Point forces (`[[loads.point]]`, default: none).
    pub point: Vec<PointLoad>,
    /// Tractions per unit length on boundary edges (`[[loads.traction]]`, default: none).
    pub traction: Vec<TractionLoad>,
    /// Follower pressures on faces (`[[loads.pressure]]`, default: none).
    pub pressure: Vec<PressureLoad>,
    /// Distributed moments along boundaries (`[[loads.moment]]`, default: none).
    pub moment: Vec<MomentLoad>,
}

/// A distributed moment per unit length along the boundary edges whose two vertices are
/// selected, scaled by the dial; see [`crate::energy::loads::moment`].
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MomentLoad {
    /// Moment per unit length (N·m/m); positive turns the boundary's outward direction toward
    /// the side the face normals point to.
    pub moment: Real,
    /// The boundary vertices.
    #[serde(flatten)]
    pub on: Selection,
}

impl Loads {
    /// Whether any point, traction or pressure load is given (gravity aside).
    pub fn any_external(&self) -> bool {
        !(self.point.is_empty()
            && self.traction.is_empty()
            && self.pressure.is_empty()
            && self.moment.is_empty())
    }
}

/// A dead point force, scaled by the dial (the load factor).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLoad {
    /// Total force on the selected vertices, shared equally among them (N).
    pub force: [Real; 3],
    /// The vertices.
    #[serde(flatten)]
    pub on: Selection,
}

/// A dead traction per unit reference length on the boundary edges whose two vertices are
/// selected, scaled by the dial; each edge gives half of `traction × length` to each end.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TractionLoad {
    /// Force per unit length (N/m).
    pub traction: [Real; 3],
    /// The boundary vertices.
    #[serde(flatten)]
    pub on: Selection,
}

/// A follower pressure on the selected faces (all faces when neither tags nor a box is given),
/// pushing along each face's normal, scaled by the dial.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureLoad {
    /// Pressure (Pa); positive pushes toward the side the face normals point to.
    pub pressure: Real,
    /// The faces (by `tri_tags` or centroid box).
    #[serde(flatten, default)]
    pub on: Selection,
}

impl Loads {
    /// Validates `[loads]`: finite gravity and finite load values with well-formed selections.
    pub fn validate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let g = &self.gravity;
        if g.iter().any(|c| !c.is_finite() || c.abs() > MAX_GRAVITY) {
            return ck.inv(
                "loads.gravity",
                format!(
                    "must be finite with components within ±{MAX_GRAVITY_h} m/s², got {}",
                    vec_e(g),
                    MAX_GRAVITY_h = crate::math::human(MAX_GRAVITY)
                ),
            );
        }
        let l = self;
        let finite3 = |key: String, v: &[Real; 3]| -> Result<(), Invalid> {
            if v.iter().all(|c| c.is_finite() && c.abs() <= MAX_LOAD) {
                Ok(())
            } else {
                ck.inv(
                    &key,
                    format!(
                        "must be finite within ±{MAX_LOAD_h}, got {}",
                        vec_e(v),
                        MAX_LOAD_h = crate::math::human(MAX_LOAD)
                    ),
                )
            }
        };
        for (i, p) in l.point.iter().enumerate() {
            finite3(format!("loads.point[{i}].force"), &p.force)?;
            ck.selection(&format!("loads.point[{i}]"), &p.on)?;
        }
        for (i, t) in l.traction.iter().enumerate() {
            finite3(format!("loads.traction[{i}].traction"), &t.traction)?;
            ck.selection(&format!("loads.traction[{i}]"), &t.on)?;
        }
        for (i, p) in l.pressure.iter().enumerate() {
            if !(p.pressure.is_finite() && p.pressure.abs() <= MAX_LOAD) {
                return ck.inv(
                    &format!("loads.pressure[{i}].pressure"),
                    format!(
                        "must be finite within ±{MAX_LOAD_h} Pa, got {}",
                        crate::math::human(p.pressure),
                        MAX_LOAD_h = crate::math::human(MAX_LOAD)
                    ),
                );
            }
            ck.selection(&format!("loads.pressure[{i}]"), &p.on)?;
        }
        for (i, m) in l.moment.iter().enumerate() {
            if !(m.moment.is_finite() && m.moment.abs() <= MAX_LOAD) {
                return ck.inv(
                    &format!("loads.moment[{i}].moment"),
                    format!(
                        "must be finite within ±{MAX_LOAD_h} N·m/m, got {}",
                        crate::math::human(m.moment),
                        MAX_LOAD_h = crate::math::human(MAX_LOAD)
                    ),
                );
            }
            ck.selection(&format!("loads.moment[{i}]"), &m.on)?;
        }
        Ok(())
    }
}
