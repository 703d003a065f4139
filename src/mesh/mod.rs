//! Triangle meshes: the reference positions, the faces, and the per-face and per-vertex fields
//! that a mesh file carries (`abar_info`, `ref_thicknesses`, `constraint_indicators`, ...).
//!
//! Consumes: a VTK, OFF, OBJ, PLY or STL file (or a generator's parameters). Produces: a validated [`Mesh`] and its
//! [`Topology`]. Nothing downstream touches files.

pub mod closed;
pub mod delaunay;
pub mod film;
pub mod generate;
pub mod io;
pub mod leaf;
mod legacy;
pub mod planform;
mod shapes;
pub mod spoon;
pub mod surfaces;
pub mod topology;
pub mod vtu;
pub mod wrapper;
mod xml;

pub use topology::Topology;

use crate::math::{Real, Vec3};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A named field with `components` values per entry, stored entry-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Number of components per face or vertex.
    pub components: usize,
    /// `len = components × entries`.
    pub data: Vec<Real>,
}

impl Field {
    /// A scalar field.
    pub fn scalar(data: Vec<Real>) -> Self {
        Field {
            components: 1,
            data,
        }
    }
    /// A field of three components per entry (`data.len()` a multiple of 3): symmetric
    /// tensors `[xx, xy, yy]`, vectors.
    pub fn triples(data: Vec<Real>) -> Self {
        Field {
            components: 3,
            data,
        }
    }
    /// Number of entries (faces or vertices).
    pub fn len(&self) -> usize {
        self.data.len().checked_div(self.components).unwrap_or(0)
    }
    /// True when the field holds no entries.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    /// Components of entry `i`.
    pub fn get(&self, i: usize) -> &[Real] {
        &self.data[i * self.components..(i + 1) * self.components]
    }
}

/// What a reader produces: flat coordinates, triangles, and `(components, values)` per array.
struct RawMesh {
    points: Vec<Real>,
    faces: Vec<[usize; 3]>,
    cell_data: BTreeMap<String, (usize, Vec<Real>)>,
    point_data: BTreeMap<String, (usize, Vec<Real>)>,
}

/// The triangles of cell vertex lists, checking each is a triangle (and of VTK cell type 5 when
/// the file gives types).
fn triangles(cells: &[Vec<usize>], types: Option<&[usize]>) -> Result<Vec<[usize; 3]>, String> {
    cells
        .iter()
        .enumerate()
        .map(|(c, cell)| {
            let ty = types.map(|t| t[c]);
            match cell[..] {
                [a, b, d] if ty.is_none_or(|t| t == 5) => Ok([a, b, d]),
                _ => Err(format!(
                    "cell {c} is not a triangle ({} vertices{}); shellsim reads triangle meshes \
                     only",
                    cell.len(),
                    ty.map(|t| format!(", VTK cell type {t}"))
                        .unwrap_or_default()
                )),
            }
        })
        .collect()
}

/// For a text file: an error when it ends inside a number, i.e. its last line has no newline
/// and ends in a digit or a point. Such a file was most likely cut short (the number, and what
/// should follow it, lost), and reading the cut number would silently change a value: every
/// writer shellsim knows of ends its last line with a newline.
pub(crate) fn ends_mid_number(b: &[u8]) -> Result<(), String> {
    let Some(&last) = b.last() else {
        return Ok(());
    };
    if !(last.is_ascii_digit() || last == b'.') {
        return Ok(());
    }
    let start = b
        .iter()
        .rposition(|c| c.is_ascii_whitespace())
        .map_or(0, |p| p + 1);
    let line = b.iter().filter(|&&c| c == b'\n').count() + 1;
    Err(format!(
        "line {line}: the file ends inside the number '{}', without a final newline: it looks \
         cut short (a complete file ends its last line with a newline)",
        String::from_utf8_lossy(&b[start..])
    ))
}

/// For a text file without counts (OBJ): an error when its last line has content but no
/// newline, a sign that it was cut short (a line cut anywhere, even after a space, could lose a
/// polygon's vertex without a trace).
pub(crate) fn ends_inside_line(b: &[u8]) -> Result<(), String> {
    let start = b.iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    if b[start..].trim_ascii().is_empty() {
        return Ok(());
    }
    let line = b.iter().filter(|&&c| c == b'\n').count() + 1;
    Err(format!(
        "line {line}: the file ends inside the line '{}', without a final newline: it looks cut \
         short (a complete file ends its last line with a newline)",
        String::from_utf8_lossy(&b[start..]).trim()
    ))
}

/// Twice the area of triangle `(a, b, c)` over its longest edge squared: scale-free, 0 for a
/// degenerate triangle (and for one whose edges overflow).
pub fn area_ratio(a: &Vec3, b: &Vec3, c: &Vec3) -> Real {
    let l = (b - a).norm().max((c - a).norm()).max((c - b).norm());
    if !(l > 0.0 && l.is_finite()) {
        return 0.0;
    }
    ((b - a) / l).cross(&((c - a) / l)).norm()
}

impl RawMesh {
    fn into_mesh(self) -> Result<Mesh, String> {
        if !self.points.len().is_multiple_of(3) {
            return Err(format!(
                "POINTS holds {} values, not a multiple of 3",
                self.points.len()
            ));
        }
        let fields = |m: BTreeMap<String, (usize, Vec<Real>)>| {
            m.into_iter()
                .map(|(k, (components, data))| (k, Field { components, data }))
                .collect()
        };
        Ok(Mesh {
            positions: self
                .points
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect(),
            faces: self.faces,
            face_fields: fields(self.cell_data),
            vertex_fields: fields(self.point_data),
            source: None,
        })
    }
}

/// A triangle mesh with its fields, as read from a file.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions (m).
    pub positions: Vec<Vec3>,
    /// Faces as vertex index triples, counter-clockwise seen from the normal side.
    pub faces: Vec<[usize; 3]>,
    /// Per-face fields by name (VTK CELL_DATA).
    pub face_fields: BTreeMap<String, Field>,
    /// Per-vertex fields by name (VTK POINT_DATA).
    pub vertex_fields: BTreeMap<String, Field>,
    /// Where the mesh came from (for error messages).
    pub source: Option<PathBuf>,
}

/// The largest coordinate magnitude accepted (m): far beyond any sheet, far below the range
/// where squared lengths and energies overflow.
pub const MAX_COORDINATE: Real = 1e30;

/// The per-face fields shellsim reads from a mesh (docs/files.md describes each).
pub const INPUT_FACE_FIELDS: [&str; 22] = [
    "abar_info",
    "bbar_info",
    "ref_thicknesses",
    "ref_shear_moduli",
    "tri_tags",
    "warp_direction",
    "growth_factor",
    "machine_direction",
    "moisture_top",
    "moisture_bottom",
    "growth_mu",
    "growth_mu_perp",
    "growth_mu_top",
    "growth_mu_bottom",
    "growth_mu_top_perp",
    "growth_mu_bottom_perp",
    "growth_mu_through",
    "growth_print_thickness",
    "growth_print_modulus_ratio",
    "diffusivity_along",
    "diffusivity_across",
    "diffusivity_through",
];

/// The per-vertex fields shellsim reads from a mesh.
pub const INPUT_VERTEX_FIELDS: [&str; 3] =
    ["constraint_indicators", "node_tags", "original_positions"];

/// The fields of shellsim's own frames that are not input fields, per face and per vertex: a
/// frame read as a mesh carries them, and they are ignored without a word.
pub const FRAME_FIELDS: [&[&str]; 2] = [
    &[
        "a",
        "b",
        "abar",
        "bbar",
        "mean_curvature",
        "gauss_curvature",
        "k1",
        "k2",
        "max_stretch",
        "thickness",
        "stretching_energy_density",
        "bending_energy_density",
        "pressure",
        "skin_volume_ratio",
        "edge_angles",
        "moment_turn",
        "patch_condition",
        "strain_measure",
        "cauchy_stress_eigval_1",
        "cauchy_stress_eigval_2",
        "dimless_cauchy_stress_eigval_1",
        "dimless_cauchy_stress_eigval_2",
        "cauchy_stress_eigvec_1",
        "cauchy_stress_eigvec_2",
    ],
    &[
        "displacement",
        "velocity",
        "reaction",
        "angle_deficit",
        "angle_deficit_gauss_curvature",
    ],
];

/// Errors in reading or validating a mesh. Each names the file and the offending index.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The file could not be read or parsed.
    #[error("{path}: cannot read mesh: {reason}")]
    Read {
        /// The file.
        path: String,
        /// What went wrong.
        reason: String,
    },
    /// The file could not be written.
    #[error("{path}: cannot write: {reason}")]
    Write {
        /// The file.
        path: String,
        /// What went wrong.
        reason: String,
    },
    /// The mesh is structurally invalid.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file (or `<generated>`).
        path: String,
        /// What is wrong, naming the face, vertex or field.
        reason: String,
    },
}

impl Mesh {
    /// The faces whose `tri_tags` value is in `tags` (any, when empty) and whose centroid lies
    /// in the box `inside = (min, max)` (when given); possibly none. Needing `tri_tags` on a
    /// mesh without it is an error naming `what`.
    pub fn faces_matching(
        &self,
        tags: &[i64],
        inside: Option<([Real; 3], [Real; 3])>,
        what: &str,
    ) -> Result<Vec<usize>, MeshError> {
        let wanted = tags;
        let tags = if wanted.is_empty() {
            None
        } else {
            Some(self.face_field("tri_tags", 1)?.ok_or_else(|| {
                self.invalid(format!(
                    "{what} selects faces by tags, which needs the face field 'tri_tags'"
                ))
            })?)
        };
        Ok((0..self.faces.len())
            .filter(|&f| tags.is_none_or(|t| wanted.contains(&(t.data[f].round() as i64))))
            .filter(|&f| {
                let [p0, p1, p2] = self.face_positions(f);
                let c = (p0 + p1 + p2) / 3.0;
                inside.is_none_or(|(lo, hi)| (0..3).all(|k| c[k] >= lo[k] && c[k] <= hi[k]))
            })
            .collect())
    }

    /// Display name of the source, for messages.
    pub fn name(&self) -> String {
        self.source
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| "<generated>".into())
    }

    pub(crate) fn invalid(&self, reason: impl Into<String>) -> MeshError {
        MeshError::Invalid {
            path: self.name(),
            reason: reason.into(),
        }
    }

    /// One warning per field that shellsim neither reads nor writes into its frames (a
    /// misspelt name would otherwise change nothing without a word), naming it and the fields
    /// that are read.
    pub fn unknown_field_warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (fields, known, frame, what) in [
            (
                &self.face_fields,
                &INPUT_FACE_FIELDS[..],
                FRAME_FIELDS[0],
                "face",
            ),
            (
                &self.vertex_fields,
                &INPUT_VERTEX_FIELDS[..],
                FRAME_FIELDS[1],
                "vertex",
            ),
        ] {
            for name in fields.keys() {
                if !known.contains(&name.as_str()) && !frame.contains(&name.as_str()) {
                    out.push(format!(
                        "{}: {what} field '{name}' is not one shellsim reads; it is ignored \
                         (the {what} fields read: {})",
                        self.name(),
                        known.join(", ")
                    ));
                }
            }
        }
        out
    }

    /// Vertices of face `f`.
    #[inline]
    pub fn face_positions(&self, f: usize) -> [Vec3; 3] {
        let [i, j, k] = self.faces[f];
        [self.positions[i], self.positions[j], self.positions[k]]
    }

    /// Area of face `f` in these (reference) positions (m²).
    #[inline]
    pub fn face_area(&self, f: usize) -> Real {
        let [p0, p1, p2] = self.face_positions(f);
        0.5 * (p1 - p0).cross(&(p2 - p0)).norm()
    }

    /// Rotates each face's vertex list cyclically (orientation kept) so that its first vertex
    /// sits at a wide angle: every per-face frame (the reference metric, the rest forms, the
    /// edge slots) is built from the two edges at the first vertex, and a sliver whose first
    /// angle is tiny makes those edges nearly parallel, so that its metric `[e1 e2]ᵀ[e1 e2]`
    /// loses all its digits to cancellation (a needle of width 1e-8 gets a singular ā = I).
    /// A face is rotated only when the sine of its first angle is below half the largest of
    /// its three: regular meshes are left alone, and a second call changes nothing. A face
    /// field `edge_angles` (3 values per face, in slot order) is rotated along. Returns each
    /// face's shift `k` (0: not rotated): its new corner `j` is its old corner `(k + j) mod 3`.
    pub fn anchor_faces_at_wide_angles(&mut self) -> Vec<u8> {
        let mut shift = vec![0u8; self.faces.len()];
        for (f, shift) in shift.iter_mut().enumerate() {
            let [a, b, c] = self.faces[f];
            let p = [self.positions[a], self.positions[b], self.positions[c]];
            let sine = |k: usize| {
                let (e1, e2) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let den = e1.norm() * e2.norm();
                if den > 0.0 {
                    e1.cross(&e2).norm() / den
                } else {
                    0.0
                }
            };
            let s = [sine(0), sine(1), sine(2)];
            let best = if s[1] >= s[2] { 1 } else { 2 };
            if s[0] < 0.5 * s[best] {
                self.faces[f] = [0, 1, 2].map(|j| self.faces[f][(best + j) % 3]);
                if let Some(field) = self.face_fields.get_mut("edge_angles") {
                    if field.components == 3 && field.data.len() >= 3 * (f + 1) {
                        let old = [0, 1, 2].map(|j| field.data[3 * f + j]);
                        for j in 0..3 {
                            field.data[3 * f + j] = old[(best + j) % 3];
                        }
                    }
                }
                *shift = best as u8;
            }
        }
        shift
    }

    /// Checks coordinates, faces and fields; returns the unused vertices (a warning, not an
    /// error). Topological checks (manifoldness, orientation) live in [`Topology::build`].
    pub fn validate(&self) -> Result<Vec<usize>, MeshError> {
        let nv = self.positions.len();
        if nv < 3 || self.faces.is_empty() {
            return Err(self.invalid(format!(
                "mesh needs at least one triangle (has {} vertices, {} faces)",
                nv,
                self.faces.len()
            )));
        }
        for (i, p) in self.positions.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(self.invalid(format!(
                    "vertex {i} has a non-finite coordinate ({}, {}, {})",
                    crate::math::human(p.x),
                    crate::math::human(p.y),
                    crate::math::human(p.z)
                )));
            }
        }
        for (i, p) in self.positions.iter().enumerate() {
            if let Some(c) = p.iter().find(|c| c.abs() > MAX_COORDINATE) {
                return Err(self.invalid(format!(
                    "vertex {i} has a coordinate {c_h} m, beyond ±{MAX_COORDINATE_h} m: rescale \
                     the mesh (energies of such a sheet overflow)",
                    c_h = crate::math::human(c),
                    MAX_COORDINATE_h = crate::math::human(MAX_COORDINATE)
                )));
            }
        }
        let mut used = vec![false; nv];
        for (fi, f) in self.faces.iter().enumerate() {
            // Every index is checked before any is used.
            if let Some(&v) = f.iter().find(|&&v| v >= nv) {
                return Err(self.invalid(format!(
                    "face {fi} refers to vertex {v}, but there are only {nv} vertices"
                )));
            }
            for &v in f {
                used[v] = true;
            }
            if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
                return Err(self.invalid(format!("face {fi} repeats a vertex: {f:?}")));
            }
            let [a, b, c] = self.face_positions(fi);
            let cr = area_ratio(&a, &b, &c);
            if cr <= 1e-12 {
                return Err(self.invalid(format!(
                    "face {fi} {f:?} has zero area (degenerate triangle: twice its area is \
                     {} of its longest edge squared)",
                    crate::math::human(cr)
                )));
            }
        }
        let nf = self.faces.len();
        for (name, field) in &self.face_fields {
            check_field(self, name, field, nf, "face")?;
        }
        for (name, field) in &self.vertex_fields {
            check_field(self, name, field, nv, "vertex")?;
        }
        Ok((0..nv).filter(|&i| !used[i]).collect())
    }

    /// True when the vertices of all faces lie in a plane `z = const` (the reference frame for
    /// fields given in reference Cartesian coordinates). Vertices used by no face do not count.
    pub fn is_flat_xy(&self) -> bool {
        let Some(first) = self.faces.first() else {
            return true;
        };
        let z0 = self.positions[first[0]].z;
        let scale = self.bbox_diagonal().max(Real::MIN_POSITIVE);
        self.faces
            .iter()
            .flatten()
            .all(|&v| (self.positions[v].z - z0).abs() <= 1e-12 * scale)
    }

    /// Length of the diagonal of the axis-aligned bounding box.
    pub fn bbox_diagonal(&self) -> Real {
        let mut lo = Vec3::repeat(Real::INFINITY);
        let mut hi = Vec3::repeat(Real::NEG_INFINITY);
        for p in &self.positions {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        (hi - lo).norm()
    }

    /// Mean edge length over all face edges.
    pub fn mean_edge_length(&self) -> Real {
        let mut s = 0.0;
        for f in 0..self.faces.len() {
            let [a, b, c] = self.face_positions(f);
            s += (b - a).norm() + (c - b).norm() + (a - c).norm();
        }
        s / (3.0 * self.faces.len() as Real)
    }

    /// Looks up a face field and checks its component count.
    pub fn face_field(&self, name: &str, components: usize) -> Result<Option<&Field>, MeshError> {
        self.lookup(&self.face_fields, "face", name, components)
    }

    /// Looks up a vertex field and checks its component count.
    pub fn vertex_field(&self, name: &str, components: usize) -> Result<Option<&Field>, MeshError> {
        self.lookup(&self.vertex_fields, "vertex", name, components)
    }

    fn lookup<'m>(
        &self,
        fields: &'m BTreeMap<String, Field>,
        what: &str,
        name: &str,
        components: usize,
    ) -> Result<Option<&'m Field>, MeshError> {
        match fields.get(name) {
            None => Ok(None),
            Some(f) if f.components == components => Ok(Some(f)),
            Some(f) => Err(self.invalid(format!(
                "{what} field '{name}' has {} components, expected {components}",
                f.components
            ))),
        }
    }
}

fn check_field(
    mesh: &Mesh,
    name: &str,
    field: &Field,
    n: usize,
    what: &str,
) -> Result<(), MeshError> {
    if field.components == 0 || field.data.len() != n * field.components {
        return Err(mesh.invalid(format!(
            "{what} field '{name}' has {} values, expected {} ({n} {what}s × {} components)",
            field.data.len(),
            n * field.components.max(1),
            field.components
        )));
    }
    if let Some(bad) = field.data.iter().position(|x| !x.is_finite()) {
        return Err(mesh.invalid(format!(
            "{what} field '{name}' is not finite at {what} {} (value {})",
            bad / field.components,
            field.data[bad]
        )));
    }
    Ok(())
}
