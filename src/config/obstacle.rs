//! `[[obstacles]]`: rigid obstacles the sheet rests on or is pressed by, one table each.
//!
//! ```toml
//! [[obstacles]]
//! shape = "sphere"          # "sphere", "capsule", "cylinder", "plane", "box" or "mesh"
//! center = [0, 0, -0.3]     # sphere
//! radius = 0.25             # sphere, capsule, cylinder (m)
//! displacement = [0, 0, 0]  # moved linearly with the dial to this offset at dial 1 (m)
//! ```
//!
//! Shapes and their keys: `sphere` (`center`, `radius`); `capsule` (the segment `a`–`b` and
//! `radius`); `cylinder` (infinite: a `point` on its axis, the `axis` direction, `radius`);
//! `plane` (a `point` and the `normal` toward the sheet's side); `box` (axis-aligned, `min` and
//! `max` corners); `mesh` (`file`: any triangle mesh shellsim reads, `.stl`, `.obj`, `.off`,
//! `.ply`, `.vtk`, `.vtu`, `.vtp`, open or closed, its path relative to the settings file;
//! `scale`, a factor on its coordinates, default 1, and `translate` (m), applied after it; the
//! sheet's contact pairs with it, [`crate::energy::self_contact`]). Common keys: `displacement` (m, default none: the obstacle is fixed),
//! `stiffness` (Pa/m, default: the area-weighted mean E/h of the sheet) and `smoothing` (m,
//! default: the mean thickness over 100), as the ground's (`[contact]`), and `friction` (the
//! Coulomb coefficient μ, default 0; the smoothed Coulomb law of the ground in dynamic mode, with
//! `contact.slip_speed`, and stick/slip in explicit mode, on a fixed obstacle only there; static
//! solves have no slip to resist, so friction there is refused).
//!
//! Force control: `force = [Fx, Fy, Fz]` (N, reached at dial 1, linear in the dial) pushes the
//! obstacle along its direction instead of moving it by `displacement`; its offset along the
//! force is a global DOF of the solve, and `mass` (kg) its inertia, required in dynamic mode.
//! Static and dynamic modes; frictionless; any shape.
//!
//! A `mesh` obstacle is fixed, moved by `displacement` or pushed by a `force` in static
//! (load-controlled) or dynamic mode: its steps are bounded by continuous collision detection,
//! and its motion within a step is checked the same way, which arc-length continuation (the
//! dial an unknown of the solve) cannot do. In explicit mode it is fixed, with stick/slip
//! friction, or moved by `displacement` (frictionless), the explicit driver bounding its move
//! with the dial as it bounds the sheet's vertices.
//!
//! The raw table is flat (every key optional, unknown keys refused); [`ObstacleSettings::shape`]
//! validates it into a [`Shape`] that carries exactly its variant's parameters.

use super::Invalid;
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// One `[[obstacles]]` table as written.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObstacleSettings {
    /// `"sphere"`, `"capsule"`, `"cylinder"`, `"plane"`, `"box"` or `"mesh"` (required).
    pub shape: Option<ShapeKind>,
    /// The triangle mesh file of a `mesh` obstacle (relative to the settings file's folder).
    pub file: Option<String>,
    /// A factor on a mesh obstacle's coordinates (default 1: as in the file).
    pub scale: Option<Real>,
    /// A translation of a mesh obstacle after `scale` (m; default none).
    pub translate: Option<[Real; 3]>,
    /// Sphere centre (m).
    pub center: Option<[Real; 3]>,
    /// Radius of a sphere, capsule or cylinder (m, > 0).
    pub radius: Option<Real>,
    /// Capsule segment ends (m).
    pub a: Option<[Real; 3]>,
    /// See `a`.
    pub b: Option<[Real; 3]>,
    /// A point on a cylinder's axis or on a plane (m).
    pub point: Option<[Real; 3]>,
    /// Cylinder axis direction (non-zero).
    pub axis: Option<[Real; 3]>,
    /// Plane normal, toward the sheet's side (non-zero).
    pub normal: Option<[Real; 3]>,
    /// Box corners (m), `min < max` on every axis.
    pub min: Option<[Real; 3]>,
    /// See `min`.
    pub max: Option<[Real; 3]>,
    /// Offset reached at dial 1, linear in the dial (m; default: fixed).
    pub displacement: [Real; 3],
    /// Penalty stiffness k (Pa/m; default: the sheet's area-weighted mean E/h).
    pub stiffness: Option<Real>,
    /// Smoothing length δ (m; default: the sheet's mean thickness / 100).
    pub smoothing: Option<Real>,
    /// Coulomb friction coefficient μ between the sheet and the obstacle (default 0:
    /// frictionless; dynamic and explicit modes).
    pub friction: Real,
    /// A force (N) that pushes the obstacle along its direction, reached at dial 1 (linear in
    /// the dial): the obstacle's offset along it is then a global DOF (instead of
    /// `displacement`).
    pub force: Option<[Real; 3]>,
    /// The mass (kg) of a force-controlled obstacle, its inertia in dynamic mode (required
    /// there).
    pub mass: Option<Real>,
}

/// How an obstacle moves: with the dial, or pushed by a force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Control {
    /// Offset `displacement` × dial (m; zero: fixed).
    Moved([Real; 3]),
    /// Pushed along the unit `direction` by the force `magnitude` × dial (N), with the mass
    /// (kg; dynamic mode).
    Pressed {
        /// Unit direction of the force.
        direction: [Real; 3],
        /// Its magnitude at dial 1 (N).
        magnitude: Real,
        /// The obstacle's mass (kg), when given.
        mass: Option<Real>,
    },
}

/// The shape names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    /// A sphere.
    Sphere,
    /// A segment with a radius.
    Capsule,
    /// An infinite circular cylinder.
    Cylinder,
    /// A plane.
    Plane,
    /// An axis-aligned box.
    Box,
    /// A triangle mesh read from a file.
    Mesh,
}

/// A validated shape with its parameters (m; directions of unit length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// Centre and radius.
    Sphere {
        /// Centre.
        center: [Real; 3],
        /// Radius.
        radius: Real,
    },
    /// Segment ends and radius.
    Capsule {
        /// One end.
        a: [Real; 3],
        /// The other end.
        b: [Real; 3],
        /// Radius.
        radius: Real,
    },
    /// A point on the axis, the unit axis, the radius.
    Cylinder {
        /// A point on the axis.
        point: [Real; 3],
        /// Unit axis.
        axis: [Real; 3],
        /// Radius.
        radius: Real,
    },
    /// A point and the unit normal toward the sheet.
    Plane {
        /// A point on the plane.
        point: [Real; 3],
        /// Unit normal.
        normal: [Real; 3],
    },
    /// Corners.
    Box {
        /// Lower corner.
        min: [Real; 3],
        /// Upper corner.
        max: [Real; 3],
    },
    /// A triangle mesh, the file `file` names (read when the scene is built).
    Mesh,
}

/// Largest coordinate or length accepted (m), as for the mesh.
const MAX_COORD: Real = 1e30;

fn finite3(key: &str, v: [Real; 3]) -> Result<[Real; 3], Invalid> {
    if v.iter().all(|c| c.is_finite() && c.abs() <= MAX_COORD) {
        Ok(v)
    } else {
        Err(Invalid::new(
            key,
            format!("must be finite (within ±1e30 m), got {v:?}"),
        ))
    }
}

fn unit(key: &str, v: [Real; 3]) -> Result<[Real; 3], Invalid> {
    let v = finite3(key, v)?;
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return Err(Invalid::new(
            key,
            format!("must be a non-zero direction, got {v:?}"),
        ));
    }
    Ok(v.map(|c| c / n))
}

impl ObstacleSettings {
    /// Validates obstacle `i` (`[[obstacles]]`, its keys `obstacles[i].…`) in a run of mode
    /// `mode`: its shape, its control, and what each mode allows (force control needs an
    /// implicit driver and, in dynamics, a mass; friction needs time to slip over, and the
    /// explicit stick/slip acts against fixed obstacles only).
    pub fn validate(&self, i: usize, mode: super::solver::Mode) -> Result<(), Invalid> {
        use super::solver::Mode;
        self.shape(i)?;
        let control = self.control(i)?;
        let invalid =
            |key: &str, reason: &str| Err(Invalid::new(&format!("obstacles[{i}].{key}"), reason));
        if let Control::Pressed { mass, .. } = control {
            if mode == Mode::Explicit {
                return invalid(
                    "force",
                    "force control needs solver.mode = \"static\" or \"dynamic\" (the \
                     explicit driver moves vertices only; [slides] offer a pressed plane \
                     there)",
                );
            }
            if mode == Mode::Dynamic && mass.is_none() {
                return invalid(
                    "mass",
                    "is required by a force-controlled obstacle in dynamic mode (kg, its \
                     inertia)",
                );
            }
        }
        if self.friction > 0.0 && mode == Mode::Static {
            return invalid(
                "friction",
                "friction needs solver.mode = \"dynamic\" or \"explicit\": a static solve \
                 has no slip over a time for friction to resist",
            );
        }
        if self.friction > 0.0
            && mode == Mode::Explicit
            && self.displacement.iter().any(|&c| c != 0.0)
        {
            return invalid(
                "friction",
                "friction on a moving obstacle needs solver.mode = \"dynamic\" (explicit \
                 stick/slip acts against fixed obstacles only)",
            );
        }
        Ok(())
    }

    /// The validated motion of obstacle `i`: `force` (a non-zero direction, finite) excludes a
    /// non-zero `displacement` and `friction`; `mass` is positive and only with a force.
    pub fn control(&self, i: usize) -> Result<Control, Invalid> {
        let key = |k: &str| format!("obstacles[{i}].{k}");
        let Some(f) = self.force else {
            if self.mass.is_some() {
                return Err(Invalid::new(
                    &key("mass"),
                    "is the mass of a force-controlled obstacle: give `force` too, or drop it",
                ));
            }
            return Ok(Control::Moved(self.displacement));
        };
        let f = finite3(&key("force"), f)?;
        let magnitude = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
        if !(magnitude > 0.0 && magnitude.is_finite()) {
            return Err(Invalid::new(
                &key("force"),
                format!("must be non-zero: its direction is the obstacle's, got {f:?}"),
            ));
        }
        if self.displacement.iter().any(|&c| c != 0.0) {
            return Err(Invalid::new(
                &key("displacement"),
                "and force exclude each other: a force-controlled obstacle moves where the force \
                 balances the sheet's push",
            ));
        }
        if self.friction > 0.0 {
            return Err(Invalid::new(
                &key("friction"),
                "is not available on a force-controlled obstacle (its slip would couple to its \
                 offset); press with a frictionless obstacle, or move it by `displacement`",
            ));
        }
        if let Some(m) = self.mass {
            super::positive(&key("mass"), m, " kg")?;
        }
        Ok(Control::Pressed {
            direction: f.map(|c| c / magnitude),
            magnitude,
            mass: self.mass,
        })
    }

    /// The validated shape of obstacle `i` (keys named `obstacles[i].KEY`): the shape's own
    /// keys present and valid, no key of another shape, and finite common keys.
    pub fn shape(&self, i: usize) -> Result<Shape, Invalid> {
        let key = |k: &str| format!("obstacles[{i}].{k}");
        let need3 = |k: &str, v: Option<[Real; 3]>| -> Result<[Real; 3], Invalid> {
            let v = v.ok_or_else(|| Invalid::new(&key(k), "is required by this shape"))?;
            finite3(&key(k), v)
        };
        let radius = || -> Result<Real, Invalid> {
            let r = self
                .radius
                .ok_or_else(|| Invalid::new(&key("radius"), "is required by this shape"))?;
            if r.is_finite() && r > 0.0 && r <= MAX_COORD {
                Ok(r)
            } else {
                Err(Invalid::new(
                    &key("radius"),
                    format!("must be > 0 (m), got {}", crate::math::human(r)),
                ))
            }
        };
        let kind = self.shape.ok_or_else(|| {
            Invalid::new(
                &key("shape"),
                "is required: \"sphere\", \"capsule\", \"cylinder\", \"plane\", \"box\" or \
                 \"mesh\"",
            )
        })?;
        let used: &[&str] = match kind {
            ShapeKind::Sphere => &["center", "radius"],
            ShapeKind::Capsule => &["a", "b", "radius"],
            ShapeKind::Cylinder => &["point", "axis", "radius"],
            ShapeKind::Plane => &["point", "normal"],
            ShapeKind::Box => &["min", "max"],
            ShapeKind::Mesh => &["file", "scale", "translate"],
        };
        let given = [
            ("center", self.center.is_some()),
            ("radius", self.radius.is_some()),
            ("a", self.a.is_some()),
            ("b", self.b.is_some()),
            ("point", self.point.is_some()),
            ("axis", self.axis.is_some()),
            ("normal", self.normal.is_some()),
            ("min", self.min.is_some()),
            ("max", self.max.is_some()),
            ("file", self.file.is_some()),
            ("scale", self.scale.is_some()),
            ("translate", self.translate.is_some()),
        ];
        if let Some((k, _)) = given.iter().find(|(k, g)| *g && !used.contains(k)) {
            return Err(Invalid::new(
                &key(k),
                format!(
                    "is not a key of shape {kind:?} (its keys: {})",
                    used.join(", ")
                ),
            ));
        }
        finite3(&key("displacement"), self.displacement)?;
        for (k, v) in [("stiffness", self.stiffness), ("smoothing", self.smoothing)] {
            if let Some(v) = v {
                super::positive(&key(k), v, "")?;
            }
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(Invalid::new(
                &key("friction"),
                format!(
                    "must be a Coulomb coefficient ≥ 0, got {}",
                    crate::math::human(self.friction)
                ),
            ));
        }
        Ok(match kind {
            ShapeKind::Sphere => Shape::Sphere {
                center: need3("center", self.center)?,
                radius: radius()?,
            },
            ShapeKind::Capsule => {
                let (a, b) = (need3("a", self.a)?, need3("b", self.b)?);
                if a == b {
                    return Err(Invalid::new(
                        &key("b"),
                        "must differ from a (use a sphere for a point)",
                    ));
                }
                Shape::Capsule {
                    a,
                    b,
                    radius: radius()?,
                }
            }
            ShapeKind::Cylinder => Shape::Cylinder {
                point: need3("point", self.point)?,
                axis: unit(
                    &key("axis"),
                    self.axis
                        .ok_or_else(|| Invalid::new(&key("axis"), "is required by this shape"))?,
                )?,
                radius: radius()?,
            },
            ShapeKind::Plane => Shape::Plane {
                point: need3("point", self.point)?,
                normal: unit(
                    &key("normal"),
                    self.normal
                        .ok_or_else(|| Invalid::new(&key("normal"), "is required by this shape"))?,
                )?,
            },
            ShapeKind::Box => {
                let (min, max) = (need3("min", self.min)?, need3("max", self.max)?);
                if (0..3).any(|k| min[k] >= max[k]) {
                    return Err(Invalid::new(
                        &key("max"),
                        format!("must exceed min on every axis: min {min:?}, max {max:?}"),
                    ));
                }
                Shape::Box { min, max }
            }
            ShapeKind::Mesh => match self.file.as_deref() {
                Some(f) if !f.trim().is_empty() => {
                    if let Some(t) = self.translate {
                        finite3(&key("translate"), t)?;
                    }
                    if let Some(c) = self.scale {
                        if !(c.is_finite() && c > 0.0 && c <= MAX_COORD) {
                            return Err(Invalid::new(
                                &key("scale"),
                                format!("must be > 0, got {}", crate::math::human(c)),
                            ));
                        }
                    }
                    Shape::Mesh
                }
                Some(_) => return Err(Invalid::new(&key("file"), "must name a mesh file")),
                None => {
                    return Err(Invalid::new(
                        &key("file"),
                        "is required by a mesh obstacle (a triangle mesh file: .stl, .obj, \
                         .off, .ply, .vtk, .vtu or .vtp)",
                    ))
                }
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(t: &str) -> ObstacleSettings {
        toml::from_str(t).unwrap()
    }

    #[test]
    fn shapes_validate_with_their_keys_only() {
        let s = parse("shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5");
        assert!(matches!(s.shape(0), Ok(Shape::Sphere { radius: 0.5, .. })));
        for (t, k) in [
            (
                "shape = \"sphere\"\ncenter = [0, 0, 1]",
                "obstacles[3].radius",
            ),
            (
                "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0",
                "obstacles[3].radius",
            ),
            (
                "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = -1",
                "obstacles[3].radius",
            ),
            (
                "shape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 0]",
                "obstacles[3].normal",
            ),
            (
                "shape = \"cylinder\"\npoint = [0, 0, 0]\naxis = [0, 0, 0]\nradius = 1",
                "obstacles[3].axis",
            ),
            (
                "shape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1",
                "obstacles[3].radius",
            ),
            (
                "shape = \"box\"\nmin = [0, 0, 0]\nmax = [1, 0, 1]",
                "obstacles[3].max",
            ),
            (
                "shape = \"capsule\"\na = [0, 0, 0]\nb = [0, 0, 0]\nradius = 1",
                "obstacles[3].b",
            ),
            ("center = [0, 0, 0]", "obstacles[3].shape"),
            (
                "shape = \"plane\"\npoint = [0, 0, nan]\nnormal = [0, 0, 1]",
                "obstacles[3].point",
            ),
        ] {
            assert_eq!(parse(t).shape(3).unwrap_err().key, k, "{t}");
        }
        let p = parse("shape = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 2]");
        assert_eq!(
            p.shape(0),
            Ok(Shape::Plane {
                point: [0.0; 3],
                normal: [0.0, 0.0, 1.0]
            })
        );
    }
}
