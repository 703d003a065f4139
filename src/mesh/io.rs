//! Reading and writing triangle meshes in VTK formats, and reading the formats shape
//! collections use (OFF, OBJ, PLY, STL: `mesh/shapes.rs`).
//!
//! Read: legacy `.vtk` (ASCII or big-endian binary, versions 2.0–5.1; POLYDATA or
//! UNSTRUCTURED_GRID of triangles) and XML `.vtu`/`.vtp`, inline or appended, raw or base64, with
//! any of VTK's compressors (`mesh/xml.rs`). CELL_DATA / POINT_DATA become face / vertex fields, whether stored as
//! FIELD arrays or as SCALARS / VECTORS / NORMALS / TENSORS. MorphoShell input files work
//! unchanged.
//!
//! Write: `.vtu` (`mesh/vtu.rs`) or legacy `.vtk` (ASCII or big-endian binary, written here),
//! always through a temporary file renamed into place, so a reader never sees half a file.

use super::{Field, Mesh, MeshError, RawMesh};
use crate::math::Real;
use std::collections::BTreeMap;
use std::path::Path;

/// Reads a triangle mesh and its fields. Validation of geometry happens in [`Mesh::validate`].
///
/// The readers are shellsim's own (`mesh/legacy.rs`, `mesh/xml.rs`): errors name the line or
/// byte offset and the section, and no input panics. As a second line of defence a panic in a
/// reader becomes an error naming the file, not a crash.
pub fn read_mesh(path: &Path) -> Result<Mesh, MeshError> {
    let name = path.display().to_string();
    let err = |reason: String| MeshError::Read {
        path: name.clone(),
        reason,
    };
    let ext = path
        .extension()
        .and_then(|s| s.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    // An unknown extension is refused before the file is opened.
    parser(&ext).map_err(err)?;
    let bytes = std::fs::read(path).map_err(|e| err(e.to_string()))?;
    let mut mesh = mesh_from_bytes(&bytes, &ext).map_err(err)?;
    mesh.source = Some(path.to_path_buf());
    Ok(mesh)
}

/// Parses mesh bytes of the format named by a file extension (`vtk`, `vtu`, `vtp`, and the
/// shape-collection formats `off`, `obj`, `ply`, `stl`, `mesh/shapes.rs`).
pub fn mesh_from_bytes(bytes: &[u8], ext: &str) -> Result<Mesh, String> {
    let parse = parser(ext)?;
    guard(|| parse(bytes))?.into_mesh()
}

/// A reader of one file format: bytes to a raw mesh, or an error naming where.
type Reader = fn(&[u8]) -> Result<RawMesh, String>;

/// The reader of the format a file extension names.
fn parser(ext: &str) -> Result<Reader, String> {
    Ok(match ext {
        "vtk" => super::legacy::parse,
        "vtu" | "vtp" => super::xml::parse,
        "off" => super::shapes::parse_off,
        "obj" => super::shapes::parse_obj,
        "ply" => super::shapes::parse_ply,
        "stl" => super::shapes::parse_stl,
        other => {
            return Err(format!(
                "unknown mesh extension '.{other}' (expected .vtk, .vtu, .vtp, .off, .obj, .ply \
                 or .stl)"
            ))
        }
    })
}

thread_local! {
    /// Set while code runs under [`catch_quietly`]: its panics are returned, not printed.
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f`, returning a panic's message as `Err` instead of unwinding. The panic hook stays
/// quiet for panics inside and defers to the previous hook for all others (installed once).
pub(crate) fn catch_quietly<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                previous(info);
            }
        }));
    });
    let was = QUIET.with(|q| q.replace(true));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(was));
    r.map_err(|p| {
        p.downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "panic".into())
    })
}

/// Runs a reader, turning a panic (a bug) into an error instead of a crash.
fn guard<T>(f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    catch_quietly(f).unwrap_or_else(|what| {
        Err(format!(
            "the reader failed on this file ({what}); please report it with the file"
        ))
    })
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
    /// The settings name.
    pub fn name(self) -> &'static str {
        match self {
            Format::Vtu => "vtu",
            Format::Vtk => "vtk",
            Format::VtkAscii => "vtk_ascii",
        }
    }

    /// File extension without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Vtu => "vtu",
            Format::Vtk | Format::VtkAscii => "vtk",
        }
    }
}

/// Serialises a mesh with fields to bytes in the given format (`.vtu`: zlib-compressed raw
/// appended data, every field Float64).
pub fn mesh_to_bytes(mesh: &Mesh, format: Format, title: &str) -> Vec<u8> {
    mesh_to_bytes_with(mesh, format, title, &Default::default(), &|_| false)
}

/// [`mesh_to_bytes`] with `.vtu` options, and the fields written as Float32 where
/// `single(name)`.
pub fn mesh_to_bytes_with(
    mesh: &Mesh,
    format: Format,
    title: &str,
    vtu: &super::vtu::VtuOptions,
    single: &dyn Fn(&str) -> bool,
) -> Vec<u8> {
    match format {
        Format::Vtu => super::vtu::vtu_bytes(mesh, vtu, single),
        Format::Vtk => legacy_bytes(mesh, title, true, single),
        Format::VtkAscii => legacy_bytes(mesh, title, false, single),
    }
}

/// A legacy VTK 4.2 `UNSTRUCTURED_GRID` of triangles: `POINTS n double`, `CELLS`,
/// `CELL_TYPES` (5, VTK_TRIANGLE), then `CELL_DATA` and `POINT_DATA` as one `FIELD FieldData`
/// block each, an array per field with any number of components (what MorphoShell reads),
/// `float` where `single(name)`, else `double`. Binary data is big-endian, as the format
/// requires; ASCII numbers are Rust's shortest round-trip representation. A name's spaces
/// become `%20` (VTK's escape) and the title is kept to one line.
fn legacy_bytes(mesh: &Mesh, title: &str, binary: bool, single: &dyn Fn(&str) -> bool) -> Vec<u8> {
    use std::fmt::Write as _;
    fn floats(out: &mut Vec<u8>, values: &[f64], per_line: usize, binary: bool, f32s: bool) {
        if binary {
            out.reserve(values.len() * if f32s { 4 } else { 8 });
            for &v in values {
                if f32s {
                    out.extend_from_slice(&(v as f32).to_be_bytes());
                } else {
                    out.extend_from_slice(&v.to_be_bytes());
                }
            }
            out.push(b'\n');
            return;
        }
        let mut line = String::new();
        for chunk in values.chunks(per_line.max(1)) {
            line.clear();
            for (i, &v) in chunk.iter().enumerate() {
                if i > 0 {
                    line.push(' ');
                }
                let _ = if f32s {
                    write!(line, "{}", v as f32)
                } else {
                    write!(line, "{v}")
                };
            }
            line.push('\n');
            out.extend_from_slice(line.as_bytes());
        }
    }
    fn ints(out: &mut Vec<u8>, values: &[u32], per_line: usize, binary: bool) {
        if binary {
            for &v in values {
                out.extend_from_slice(&(v as i32).to_be_bytes());
            }
            out.push(b'\n');
            return;
        }
        for chunk in values.chunks(per_line.max(1)) {
            let line: Vec<String> = chunk.iter().map(u32::to_string).collect();
            out.extend_from_slice(line.join(" ").as_bytes());
            out.push(b'\n');
        }
    }
    let fields = |out: &mut Vec<u8>, kind: &str, n: usize, fields: &BTreeMap<String, Field>| {
        if fields.is_empty() {
            return;
        }
        out.extend_from_slice(format!("{kind} {n}\nFIELD FieldData {}\n", fields.len()).as_bytes());
        for (name, f) in fields {
            let f32s = single(name);
            let comps = f.components.max(1);
            out.extend_from_slice(
                format!(
                    "{} {comps} {} {}\n",
                    name.replace(' ', "%20"),
                    f.data.len() / comps,
                    if f32s { "float" } else { "double" }
                )
                .as_bytes(),
            );
            floats(out, &f.data, comps, binary, f32s);
        }
    };
    let one_line: String = title
        .chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .take(255)
        .collect();
    let mut out = format!(
        "# vtk DataFile Version 4.2\n{one_line}\n{}\nDATASET UNSTRUCTURED_GRID\nPOINTS {} double\n",
        if binary { "BINARY" } else { "ASCII" },
        mesh.positions.len()
    )
    .into_bytes();
    let points: Vec<f64> = mesh
        .positions
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    floats(&mut out, &points, 3, binary, false);
    let nf = mesh.faces.len();
    out.extend_from_slice(format!("CELLS {nf} {}\n", 4 * nf).as_bytes());
    let cells: Vec<u32> = mesh
        .faces
        .iter()
        .flat_map(|f| [3, f[0] as u32, f[1] as u32, f[2] as u32])
        .collect();
    ints(&mut out, &cells, 4, binary);
    out.extend_from_slice(format!("CELL_TYPES {nf}\n").as_bytes());
    ints(&mut out, &vec![5; nf], 1, binary);
    fields(&mut out, "CELL_DATA", nf, &mesh.face_fields);
    fields(
        &mut out,
        "POINT_DATA",
        mesh.positions.len(),
        &mesh.vertex_fields,
    );
    out
}

/// A ParaView series (`.pvd`) of `(timestep, file)` entries; the timesteps are written with the
/// shortest digits that read back exactly (a restart reads the exact time back).
pub fn series_xml(frames: &[(Real, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n",
    );
    for (t, name) in frames {
        s.push_str(&format!(
            "    <DataSet timestep=\"{t}\" group=\"\" part=\"0\" file=\"{name}\"/>\n"
        ));
    }
    s.push_str("  </Collection>\n</VTKFile>\n");
    s
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
    // The temporary file goes on every failure (a full disk included).
    std::fs::write(&tmp, bytes)
        .and_then(|_| std::fs::rename(&tmp, path))
        .inspect_err(|_| {
            let _ = std::fs::remove_file(&tmp);
        })
}

/// Writes a mesh with its fields (format chosen by `format`), atomically.
pub fn write_mesh(path: &Path, mesh: &Mesh, format: Format, title: &str) -> Result<(), MeshError> {
    let werr = |reason: String| MeshError::Write {
        path: path.display().to_string(),
        reason,
    };
    let bytes = mesh_to_bytes(mesh, format, title);
    write_atomic(path, &bytes).map_err(|e| werr(e.to_string()))
}
