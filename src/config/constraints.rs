//! `[constraints]`: held vertices (boxes, tags, selections), clamps, per-component supports,
//! symmetry planes and prescribed paths.

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
    /// are selected, those vertices are held and, with the edge-DOF bending models, the edges'
    /// mid-edge normals keep their reference direction (a clamp on the boundary line itself);
    /// with the other bending models the vertices' edge neighbours (one ring) are held too
    /// (default: none).
    pub clamp: Vec<Selection>,
    /// Per-component supports (`[[constraints.support]]`): the selected vertices' listed
    /// components are held at their reference values, the others stay free (rollers,
    /// diaphragms; the in-plane half of a symmetry condition, whose rotation stays free)
    /// (default: none).
    pub support: Vec<Support>,
    /// Symmetry planes (`[[constraints.symmetry]]`): the vertices on the plane keep their
    /// normal component, and with the edge-DOF bending models the boundary edges on it keep
    /// their mid-edge normal in the plane, so a half, quarter or octant model behaves as the
    /// whole (default: none).
    pub symmetry: Vec<Symmetry>,
    /// Prescribed displacements (`[[constraints.displacement]]`): selected vertices move to
    /// `reference + dial × displacement` (default: none).
    pub displacement: Vec<Prescribed>,
}

/// A symmetry plane `n̂ · x = at`, its normal given as a coordinate axis or as a vector.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Symmetry {
    /// The plane's normal as a coordinate axis: `"x"`, `"y"` or `"z"` (or give `normal`).
    #[serde(default)]
    pub axis: Option<Axis>,
    /// The plane's normal as a vector, any length but zero (or give `axis`).
    #[serde(default)]
    pub normal: Option<[Real; 3]>,
    /// The plane's signed distance from the origin along the unit normal (m, default: `0`):
    /// with `axis`, where the plane cuts that axis.
    #[serde(default)]
    pub at: Real,
}

impl Symmetry {
    /// The plane's unit normal (`axis` or `normal`, once validated).
    pub fn unit_normal(&self) -> crate::math::Vec3 {
        let mut n = crate::math::Vec3::zeros();
        match (self.axis, self.normal) {
            (Some(a), _) => n[a.index()] = 1.0,
            (None, Some(v)) => n = crate::math::Vec3::from(v).normalize(),
            (None, None) => {}
        }
        n
    }

    /// The coordinate axis the normal lies along (`axis`, or a `normal` with two zero
    /// components), whose component the plane's vertices keep; `None` for an oblique plane.
    pub fn coordinate_axis(&self) -> Option<Axis> {
        match (self.axis, self.normal) {
            (Some(a), _) => Some(a),
            (None, Some(v)) => {
                let nz: Vec<usize> = (0..3).filter(|&k| v[k] != 0.0).collect();
                match nz[..] {
                    [0] => Some(Axis::X),
                    [1] => Some(Axis::Y),
                    [2] => Some(Axis::Z),
                    _ => None,
                }
            }
            (None, None) => None,
        }
    }

    /// A name for the plane in messages: `x = 0.5`, or `(0.6, 0.8, 0)·x = 1`.
    pub fn describe(&self) -> String {
        let at = crate::math::human(self.at);
        match (self.axis, self.normal) {
            (Some(a), _) => format!("{} = {at}", ["x", "y", "z"][a.index()]),
            _ => {
                let n = self.unit_normal();
                format!(
                    "({}, {}, {})·x = {at}",
                    crate::math::human(n[0]),
                    crate::math::human(n[1]),
                    crate::math::human(n[2])
                )
            }
        }
    }
}

/// A Cartesian component of a vertex's position.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// x.
    X,
    /// y.
    Y,
    /// z.
    Z,
}

impl Axis {
    /// The component's index (x 0, y 1, z 2).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// The components in `list` as a mask (all three when `list` is `None`).
pub fn component_mask(list: Option<&[Axis]>) -> [bool; 3] {
    match list {
        None => [true; 3],
        Some(l) => [0, 1, 2].map(|k| l.iter().any(|a| a.index() == k)),
    }
}

/// A per-component support.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Support {
    /// The held components, e.g. `["x", "z"]` (at least one).
    pub components: Vec<Axis>,
    /// The vertices.
    #[serde(flatten)]
    pub on: Selection,
}

/// A prescribed displacement path.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prescribed {
    /// Displacement at dial 1 (m).
    pub displacement: [Real; 3],
    /// The components that follow the path (default: all three); the others stay free and
    /// their entries of `displacement` are not used.
    #[serde(default)]
    pub components: Option<Vec<Axis>>,
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
            support: Vec::new(),
            symmetry: Vec::new(),
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
        for (i, sp) in cs.support.iter().enumerate() {
            let key = format!("constraints.support[{i}]");
            components(&format!("{key}.components"), Some(&sp.components))?;
            ck.selection(&key, &sp.on)?;
        }
        for (i, sy) in cs.symmetry.iter().enumerate() {
            let key = format!("constraints.symmetry[{i}]");
            match (sy.axis, sy.normal) {
                (Some(_), Some(_)) => {
                    return ck.inv(&key, "gives both axis and normal; give one of them".into())
                }
                (None, None) => {
                    return ck.inv(
                        &key,
                        "needs the plane's normal: axis (\"x\", \"y\" or \"z\") or normal \
                         (a vector)"
                            .into(),
                    )
                }
                (None, Some(v)) => {
                    let len = v.iter().map(|c| c * c).sum::<Real>().sqrt();
                    if !(len.is_finite() && len > 0.0) {
                        return ck.inv(
                            &format!("{key}.normal"),
                            format!("must be a finite, non-zero vector, got {}", vec_e(&v)),
                        );
                    }
                }
                (Some(_), None) => {}
            }
            let max = crate::mesh::MAX_COORDINATE;
            if !(sy.at.is_finite() && sy.at.abs() <= max) {
                return ck.inv(
                    &format!("constraints.symmetry[{i}].at"),
                    format!(
                        "must be finite within ±{} m, got {}",
                        crate::math::human(max),
                        crate::math::human(sy.at)
                    ),
                );
            }
        }
        for (i, d) in cs.displacement.iter().enumerate() {
            components(
                &format!("constraints.displacement[{i}].components"),
                d.components.as_deref(),
            )?;
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

/// A component list must name at least one component, each once.
fn components(key: &str, list: Option<&[Axis]>) -> Result<(), Invalid> {
    let Some(l) = list else {
        return Ok(());
    };
    if l.is_empty() {
        return Check.inv(key, "needs at least one of \"x\", \"y\", \"z\"".into());
    }
    if let Some(a) = l
        .iter()
        .enumerate()
        .find_map(|(i, a)| l[..i].contains(a).then_some(a))
    {
        return Check.inv(key, format!("lists {a:?} twice"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Constraints {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn a_support_needs_distinct_components() {
        let ok = parse("[[support]]\ncomponents = [\"x\", \"z\"]\ntags = [1]\n");
        assert!(ok.validate().is_ok());
        assert_eq!(
            component_mask(Some(&ok.support[0].components)),
            [true, false, true]
        );
        let none = parse("[[support]]\ncomponents = []\ntags = [1]\n");
        let e = none.validate().unwrap_err();
        assert_eq!(e.key, "constraints.support[0].components");
        let twice = parse("[[support]]\ncomponents = [\"y\", \"y\"]\ntags = [1]\n");
        assert!(twice.validate().unwrap_err().reason.contains("twice"));
        assert!(
            toml::from_str::<Constraints>("[[support]]\ncomponents = [\"w\"]\ntags = [1]\n")
                .is_err()
        );
    }

    #[test]
    fn a_path_defaults_to_all_components() {
        let c = parse("[[displacement]]\ndisplacement = [0, 0, 1]\ntags = [1]\n");
        assert!(c.validate().is_ok());
        assert_eq!(
            component_mask(c.displacement[0].components.as_deref()),
            [true; 3]
        );
        let z =
            parse("[[displacement]]\ndisplacement = [0, 0, 1]\ncomponents = [\"z\"]\ntags = [1]\n");
        assert_eq!(
            component_mask(z.displacement[0].components.as_deref()),
            [false, false, true]
        );
    }
}
