//! Reading and writing triangle meshes in VTK formats.
//!
//! Read: legacy `.vtk` (ASCII or big-endian binary, versions 2.0–5.1; POLYDATA or
//! UNSTRUCTURED_GRID of triangles) and XML `.vtu`/`.vtp` with inline (base64 or ASCII) data, which
//! is what shellsim writes. CELL_DATA / POINT_DATA become face / vertex fields, whether stored as
//! FIELD arrays or as SCALARS / VECTORS / NORMALS / TENSORS. MorphoShell input files work
//! unchanged.
//!
//! Write: `.vtu` (XML, inline base64) or legacy `.vtk` (big-endian binary), always through a
//! temporary file renamed into place, so a reader never sees half a file.

use super::{Field, Mesh, MeshError};
use crate::math::{Real, Vec3};
use std::collections::BTreeMap;
use std::path::Path;
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    Piece, UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

/// Reads a triangle mesh and its fields. Validation of geometry happens in [`Mesh::validate`].
pub fn read_mesh(path: &Path) -> Result<Mesh, MeshError> {
    let name = path.display().to_string();
    let err = |reason: String| MeshError::Read {
        path: name.clone(),
        reason,
    };
    let bytes = std::fs::read(path).map_err(|e| err(e.to_string()))?;
    let ext = path
        .extension()
        .and_then(|s| s.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let vtk = match ext.as_str() {
        "vtk" => parse_legacy(&bytes).map_err(err)?,
        "vtu" | "vtp" => {
            if bytes.windows(14).any(|w| w == b"<AppendedData ") {
                return Err(err(
                    "XML with raw appended data is not supported; save it from \
                     ParaView as legacy .vtk, or as XML with 'Data Mode: Ascii' or 'Binary' \
                     (inline base64)"
                        .into(),
                ));
            }
            Vtk::parse_xml(std::io::BufReader::new(&bytes[..]))
                .map_err(|e| err(format!("invalid VTK XML: {e}")))?
        }
        other => {
            return Err(err(format!(
                "unknown mesh extension '.{other}' (expected .vtk, .vtu or .vtp)"
            )))
        }
    };
    let mut mesh = from_vtk(vtk).map_err(err)?;
    mesh.source = Some(path.to_path_buf());
    Ok(mesh)
}

/// Parses legacy VTK, checking the header first so that a truncated or foreign file gets a
/// clear message rather than a parser trace.
fn parse_legacy(bytes: &[u8]) -> Result<Vtk, String> {
    let head: Vec<&[u8]> = bytes.splitn(4, |&b| b == b'\n').collect();
    if head.is_empty() || !head[0].starts_with(b"# vtk DataFile Version") {
        return Err(
            "not a legacy VTK file: the first line must be '# vtk DataFile Version x.y'".into(),
        );
    }
    let version = String::from_utf8_lossy(head[0]);
    let v: Option<(u32, u32)> = version
        .trim()
        .rsplit(' ')
        .next()
        .and_then(|s| s.split_once('.'))
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)));
    match v {
        Some((2..=5, _)) => {}
        _ => {
            return Err(format!(
                "unsupported legacy VTK version line '{}' (2.0–5.1 are read)",
                version.trim()
            ))
        }
    }
    if head
        .get(2)
        .is_some_and(|l| l.trim_ascii().eq_ignore_ascii_case(b"ASCII"))
    {
        // vtkio cannot parse `nan`/`inf`; name the line instead of a parser trace.
        let text = String::from_utf8_lossy(bytes);
        for (i, line) in text.lines().enumerate().skip(3) {
            for tok in line.split_ascii_whitespace() {
                let t = tok.trim_start_matches(['-', '+']).to_ascii_lowercase();
                if matches!(t.as_str(), "nan" | "inf" | "infinity" | "nan(ind)") {
                    return Err(format!("line {}: non-finite value '{tok}'", i + 1));
                }
            }
        }
    }
    Vtk::parse_legacy_be(bytes).map_err(|e| format!("malformed or truncated legacy VTK: {e}"))
}

fn buffer_to_f64(buf: IOBuffer) -> Option<Vec<Real>> {
    buf.cast_into::<f64>()
}

fn attributes_to_fields(
    attrs: Vec<Attribute>,
    n: usize,
    what: &str,
) -> Result<BTreeMap<String, Field>, String> {
    let mut out = BTreeMap::new();
    let mut push = |name: String, components: usize, data: IOBuffer| -> Result<(), String> {
        let data = buffer_to_f64(data)
            .ok_or_else(|| format!("{what} array '{name}' has a non-numeric type"))?;
        let components = components.max(1);
        if data.len() != n * components {
            return Err(format!(
                "{what} array '{name}' has {} values, expected {} ({n} × {components} components)",
                data.len(),
                n * components
            ));
        }
        out.insert(name, Field { components, data });
        Ok(())
    };
    for a in attrs {
        match a {
            Attribute::DataArray(DataArray { name, elem, data }) => {
                let nc = match elem {
                    ElementType::Scalars { num_comp, .. } => num_comp as usize,
                    ElementType::ColorScalars(c) => c as usize,
                    ElementType::Vectors | ElementType::Normals => 3,
                    ElementType::TCoords(c) => c as usize,
                    ElementType::Tensors => 9,
                    ElementType::LookupTable => 4,
                    ElementType::Generic(c) => c as usize,
                };
                push(name, nc, data)?;
            }
            Attribute::Field { data_array, .. } => {
                for fa in data_array {
                    push(fa.name, fa.elem as usize, fa.data)?;
                }
            }
        }
    }
    Ok(out)
}

/// Splits a cell list into (cell sizes, flat connectivity).
fn cells_to_lists(verts: VertexNumbers) -> Result<(Vec<usize>, Vec<usize>), String> {
    match verts {
        VertexNumbers::Legacy {
            num_cells,
            vertices,
        } => {
            let mut sizes = Vec::with_capacity(num_cells as usize);
            let mut conn = Vec::with_capacity(vertices.len());
            let mut i = 0;
            while i < vertices.len() {
                let n = vertices[i] as usize;
                if i + 1 + n > vertices.len() {
                    return Err(format!("cell {} is truncated", sizes.len()));
                }
                sizes.push(n);
                conn.extend(vertices[i + 1..i + 1 + n].iter().map(|&v| v as usize));
                i += n + 1;
            }
            if sizes.len() != num_cells as usize {
                return Err(format!(
                    "cell list declares {num_cells} cells but holds {}",
                    sizes.len()
                ));
            }
            Ok((sizes, conn))
        }
        VertexNumbers::XML {
            connectivity,
            mut offsets,
        } => {
            // Legacy 5.1 offsets keep a leading 0; XML offsets do not.
            if offsets.first() == Some(&0) {
                offsets.remove(0);
            }
            let mut sizes = Vec::with_capacity(offsets.len());
            let mut prev = 0u64;
            for (c, &o) in offsets.iter().enumerate() {
                if o < prev || o as usize > connectivity.len() {
                    return Err(format!("cell {c} has an invalid offset {o}"));
                }
                sizes.push((o - prev) as usize);
                prev = o;
            }
            Ok((
                sizes,
                connectivity.into_iter().map(|v| v as usize).collect(),
            ))
        }
    }
}

fn to_triangles(
    sizes: &[usize],
    conn: &[usize],
    types: Option<&[CellType]>,
) -> Result<Vec<[usize; 3]>, String> {
    let mut faces = Vec::with_capacity(sizes.len());
    let mut i = 0;
    for (c, &n) in sizes.iter().enumerate() {
        let ty_ok = types.is_none_or(|t| t.get(c) == Some(&CellType::Triangle));
        if n != 3 || !ty_ok {
            return Err(format!(
                "cell {c} is not a triangle ({n} vertices{}); shellsim reads triangle meshes only",
                types
                    .and_then(|t| t.get(c))
                    .map(|t| format!(", type {t:?}"))
                    .unwrap_or_default()
            ));
        }
        faces.push([conn[i], conn[i + 1], conn[i + 2]]);
        i += 3;
    }
    Ok(faces)
}

fn from_vtk(vtk: Vtk) -> Result<Mesh, String> {
    let (points, faces, data) = match vtk.data {
        DataSet::UnstructuredGrid { pieces, .. } => {
            let p = single_piece(pieces)?;
            let (sizes, conn) = cells_to_lists(p.cells.cell_verts)?;
            if p.cells.types.len() != sizes.len() {
                return Err(format!(
                    "CELL_TYPES lists {} types for {} cells",
                    p.cells.types.len(),
                    sizes.len()
                ));
            }
            let faces = to_triangles(&sizes, &conn, Some(&p.cells.types))?;
            (p.points, faces, p.data)
        }
        DataSet::PolyData { pieces, .. } => {
            let p = single_piece(pieces)?;
            if p.verts.as_ref().is_some_and(|v| v.num_cells() > 0)
                || p.lines.as_ref().is_some_and(|v| v.num_cells() > 0)
                || p.strips.as_ref().is_some_and(|v| v.num_cells() > 0)
            {
                return Err(
                    "POLYDATA holds vertices, lines or strips; only POLYGONS of 3 \
                            vertices are read"
                        .into(),
                );
            }
            let polys = p.polys.ok_or("POLYDATA has no POLYGONS")?;
            let (sizes, conn) = cells_to_lists(polys)?;
            let faces = to_triangles(&sizes, &conn, None)?;
            (p.points, faces, p.data)
        }
        _ => return Err("dataset must be POLYDATA or UNSTRUCTURED_GRID".into()),
    };
    let coords = buffer_to_f64(points).ok_or("POINTS are not numeric")?;
    if coords.len() % 3 != 0 {
        return Err(format!(
            "POINTS holds {} values, not a multiple of 3",
            coords.len()
        ));
    }
    let positions: Vec<Vec3> = coords
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let nv = positions.len();
    let nf = faces.len();
    let Attributes { point, cell } = data;
    Ok(Mesh {
        positions,
        faces,
        face_fields: attributes_to_fields(cell, nf, "CELL_DATA")?,
        vertex_fields: attributes_to_fields(point, nv, "POINT_DATA")?,
        source: None,
    })
}

fn single_piece<P>(pieces: Vec<Piece<P>>) -> Result<P, String> {
    let n = pieces.len();
    if n != 1 {
        return Err(format!("expected one piece, found {n}"));
    }
    match pieces.into_iter().next() {
        Some(Piece::Inline(p)) => Ok(*p),
        _ => Err("pieces stored in other files are not supported".into()),
    }
}

/// Output format of a mesh or frame file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Format {
    /// XML UnstructuredGrid with inline base64 data (ParaView's `.vtu`).
    Vtu,
    /// Legacy VTK 4.2, big-endian binary.
    Vtk,
    /// Legacy VTK 4.2, ASCII (larger, diff-able, what MorphoShell writes).
    VtkAscii,
}

impl Format {
    /// File extension without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Vtu => "vtu",
            Format::Vtk | Format::VtkAscii => "vtk",
        }
    }
}

fn fields_to_attributes(fields: &BTreeMap<String, Field>, legacy: bool) -> Vec<Attribute> {
    if legacy {
        // FIELD arrays keep any component count and are what MorphoShell reads.
        if fields.is_empty() {
            return Vec::new();
        }
        let arrays = fields
            .iter()
            .map(|(name, f)| vtkio::model::FieldArray {
                name: name.clone(),
                elem: f.components as u32,
                data: IOBuffer::F64(f.data.clone()),
            })
            .collect();
        vec![Attribute::Field {
            name: "FieldData".into(),
            data_array: arrays,
        }]
    } else {
        fields
            .iter()
            .map(|(name, f)| {
                Attribute::DataArray(DataArray {
                    name: name.clone(),
                    elem: ElementType::Generic(f.components as u32),
                    data: IOBuffer::F64(f.data.clone()),
                })
            })
            .collect()
    }
}

/// Serialises a mesh with fields to bytes in the given format.
pub fn mesh_to_bytes(mesh: &Mesh, format: Format, title: &str) -> Result<Vec<u8>, vtkio::Error> {
    let legacy = format != Format::Vtu;
    let points: Vec<f64> = mesh
        .positions
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    let cells = if legacy {
        VertexNumbers::Legacy {
            num_cells: mesh.faces.len() as u32,
            vertices: mesh
                .faces
                .iter()
                .flat_map(|f| [3u32, f[0] as u32, f[1] as u32, f[2] as u32])
                .collect(),
        }
    } else {
        VertexNumbers::XML {
            connectivity: mesh
                .faces
                .iter()
                .flat_map(|f| f.map(|v| v as u64))
                .collect(),
            offsets: (1..=mesh.faces.len() as u64).map(|i| 3 * i).collect(),
        }
    };
    let piece = UnstructuredGridPiece {
        points: IOBuffer::F64(points),
        cells: Cells {
            cell_verts: cells,
            types: vec![CellType::Triangle; mesh.faces.len()],
        },
        data: Attributes {
            point: fields_to_attributes(&mesh.vertex_fields, legacy),
            cell: fields_to_attributes(&mesh.face_fields, legacy),
        },
    };
    let vtk = Vtk {
        version: if legacy {
            Version::new_legacy(4, 2)
        } else {
            Version::new_xml(1, 0)
        },
        title: title.to_string(),
        byte_order: ByteOrder::BigEndian,
        file_path: None,
        data: DataSet::inline(piece),
    };
    let mut out = Vec::new();
    match format {
        Format::Vtu => vtk.write_xml(&mut out)?,
        Format::Vtk => vtk.write_legacy(&mut out)?,
        Format::VtkAscii => {
            let mut s = String::new();
            vtk.write_legacy_ascii(&mut s)?;
            out = s.into_bytes();
        }
    }
    Ok(out)
}

/// Writes bytes atomically: a temporary file in the same folder, then a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    let fname = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = match dir {
        Some(d) => d.join(format!(".{fname}.tmp")),
        None => Path::new(&format!(".{fname}.tmp")).to_path_buf(),
    };
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// Writes a mesh with its fields (format chosen by `format`), atomically.
pub fn write_mesh(path: &Path, mesh: &Mesh, format: Format, title: &str) -> Result<(), MeshError> {
    let werr = |reason: String| MeshError::Write {
        path: path.display().to_string(),
        reason,
    };
    let bytes = mesh_to_bytes(mesh, format, title).map_err(|e| werr(e.to_string()))?;
    write_atomic(path, &bytes).map_err(|e| werr(e.to_string()))
}
