//! Writer of VTK XML `UnstructuredGrid` files (`.vtu`) of triangles, as ParaView writes them by
//! default: the arrays in an `<AppendedData encoding="raw">` block after the XML, each
//! compressed in blocks (zlib or LZ4), or inline base64 for files that must stay valid XML.
//!
//! Layout (<https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html>, XML part),
//! `header_type="UInt64"`, little-endian: an uncompressed array is its byte count then its
//! bytes; a compressed one is `[blocks][block size][last block size (0: full)][compressed size
//! of each block]` then the compressed blocks. Blocks are 64 KiB before compression and are
//! compressed in parallel; the output is the same bytes for any number of threads.
//!
//! Positions are Float64. Each field is Float64 or, when the caller asks, Float32 (derived
//! fields a viewer only colours by; what a restart reads must stay Float64). Connectivity and
//! offsets are Int32 when the counts allow (they always do below 2³¹ vertices), else Int64.
//!
//! Read back by shellsim's own reader (`mesh/xml.rs`) and by VTK's `vtkXMLUnstructuredGridReader`
//! (checked in `tests/vtk_python.rs` with VTK's Python package).

use super::Mesh;
use base64::Engine as _;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::io::Write as _;

/// Uncompressed bytes per compressed block.
const BLOCK: usize = 1 << 16;

/// How the arrays are compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Compression {
    /// Uncompressed.
    None,
    /// zlib (`vtkZLibDataCompressor`), level 1: the smallest files. On an 86 528-face frame,
    /// level 3 is 1% smaller and 3.5× slower to write.
    Zlib,
    /// LZ4 (`vtkLZ4DataCompressor`): about as fast to write as no compression, larger than zlib.
    Lz4,
}

/// Where the arrays' bytes go.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Encoding {
    /// Raw bytes in `<AppendedData>` (ParaView's default; the smallest; not valid XML).
    Appended,
    /// Base64 inside each `<DataArray>` (valid XML, a third larger).
    Base64,
}

/// How to write a `.vtu`.
#[derive(Clone, Copy, Debug)]
pub struct VtuOptions {
    /// Compression of every array.
    pub compression: Compression,
    /// Appended raw or inline base64.
    pub encoding: Encoding,
}

impl Default for VtuOptions {
    fn default() -> Self {
        VtuOptions {
            compression: Compression::Zlib,
            encoding: Encoding::Appended,
        }
    }
}

/// One array's values in the type it is written as.
enum Values<'a> {
    F64(&'a [f64]),
    F32(Vec<f32>),
    I32(Vec<i32>),
    I64(Vec<i64>),
    U8(Vec<u8>),
}

impl Values<'_> {
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::F32(_) => "Float32",
            Values::I32(_) => "Int32",
            Values::I64(_) => "Int64",
            Values::U8(_) => "UInt8",
        }
    }

    /// Little-endian bytes.
    fn bytes(&self) -> Vec<u8> {
        match self {
            Values::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::F32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::I32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::I64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Values::U8(v) => v.clone(),
        }
    }
}

/// An array's encoded form: its header (UInt64 sizes) and its (compressed) data.
fn encode(bytes: Vec<u8>, compression: Compression) -> (Vec<u8>, Vec<u8>) {
    let mut head = Vec::new();
    let put = |head: &mut Vec<u8>, n: usize| head.extend_from_slice(&(n as u64).to_le_bytes());
    if compression == Compression::None {
        put(&mut head, bytes.len());
        return (head, bytes);
    }
    let blocks: Vec<Vec<u8>> = bytes
        .par_chunks(BLOCK)
        .map(|b| match compression {
            Compression::Lz4 => lz4_flex::block::compress(b),
            _ => {
                let mut e = flate2::write::ZlibEncoder::new(
                    Vec::with_capacity(b.len() / 2),
                    flate2::Compression::new(1),
                );
                // Writing into a Vec cannot fail.
                let _ = e.write_all(b);
                e.finish().unwrap_or_default()
            }
        })
        .collect();
    put(&mut head, blocks.len());
    put(&mut head, BLOCK);
    put(&mut head, bytes.len() % BLOCK);
    for b in &blocks {
        put(&mut head, b.len());
    }
    (head, blocks.concat())
}

/// XML-escapes an attribute value.
fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            c => o.push(c),
        }
    }
    o
}

/// The names ParaView shows for the components of a frame's multi-component fields: the
/// symmetric tensors `a`, `b`, `abar`, `bbar` as `[xx, xy, yy]` (reference Cartesian
/// coordinates), and the per-corner slot fields as the edges opposite `v0`, `v1`, `v2`.
/// Vectors (positions, `displacement`, `velocity`, stress directions) keep VTK's X, Y, Z.
fn component_names(name: &str, comps: usize) -> Option<[&'static str; 3]> {
    match (name, comps) {
        ("a" | "b" | "abar" | "bbar", 3) => Some(["xx", "xy", "yy"]),
        ("edge_angles" | "moment_turn", 3) => Some(["opposite_v0", "opposite_v1", "opposite_v2"]),
        _ => None,
    }
}

/// Serialises a triangle mesh with its fields; the field named `n` is written as Float32 when
/// `single(n)`.
pub fn vtu_bytes(mesh: &Mesh, opts: &VtuOptions, single: &dyn Fn(&str) -> bool) -> Vec<u8> {
    let (nv, nf) = (mesh.positions.len(), mesh.faces.len());
    let points: Vec<f64> = mesh
        .positions
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    let small = 3 * nf < i32::MAX as usize;
    let (conn, offs) = if small {
        (
            Values::I32(mesh.faces.iter().flatten().map(|&v| v as i32).collect()),
            Values::I32((1..=nf as i32).map(|i| 3 * i).collect()),
        )
    } else {
        (
            Values::I64(mesh.faces.iter().flatten().map(|&v| v as i64).collect()),
            Values::I64((1..=nf as i64).map(|i| 3 * i).collect()),
        )
    };
    // (section, name, components, values)
    let mut arrays: Vec<(&str, String, usize, Values)> = Vec::new();
    for (sec, f) in [
        ("PointData", &mesh.vertex_fields),
        ("CellData", &mesh.face_fields),
    ] {
        for (n, fl) in f {
            let v = if single(n) {
                Values::F32(fl.data.iter().map(|&x| x as f32).collect())
            } else {
                Values::F64(&fl.data)
            };
            arrays.push((sec, n.clone(), fl.components, v));
        }
    }
    arrays.push(("Points", "Points".into(), 3, Values::F64(&points)));
    arrays.push(("Cells", "connectivity".into(), 1, conn));
    arrays.push(("Cells", "offsets".into(), 1, offs));
    arrays.push(("Cells", "types".into(), 1, Values::U8(vec![5u8; nf])));

    let encoded: Vec<(Vec<u8>, Vec<u8>)> = arrays
        .iter()
        .map(|(_, _, _, v)| encode(v.bytes(), opts.compression))
        .collect();

    let mut x = String::with_capacity(4096);
    let compressor = match opts.compression {
        Compression::None => "",
        Compression::Zlib => " compressor=\"vtkZLibDataCompressor\"",
        Compression::Lz4 => " compressor=\"vtkLZ4DataCompressor\"",
    };
    let _ = writeln!(x, "<?xml version=\"1.0\"?>");
    let _ = writeln!(
        x,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\"{compressor}>"
    );
    let _ = writeln!(x, "  <UnstructuredGrid>");
    let _ = writeln!(
        x,
        "    <Piece NumberOfPoints=\"{nv}\" NumberOfCells=\"{nf}\">"
    );
    let mut offset = 0usize;
    let mut section = "";
    for ((sec, name, comps, v), (head, data)) in arrays.iter().zip(&encoded) {
        if *sec != section {
            if !section.is_empty() {
                let _ = writeln!(x, "      </{section}>");
            }
            let _ = writeln!(x, "      <{sec}>");
            section = sec;
        }
        let named = if *sec == "Points" {
            String::new()
        } else {
            format!(" Name=\"{}\"", escape(name))
        };
        let _ = write!(
            x,
            "        <DataArray type=\"{}\"{named} NumberOfComponents=\"{comps}\"",
            v.type_name()
        );
        if let Some(names) = component_names(name, *comps).filter(|_| *sec != "Points") {
            for (i, c) in names.iter().enumerate() {
                let _ = write!(x, " ComponentName{i}=\"{c}\"");
            }
        }
        match opts.encoding {
            Encoding::Appended => {
                let _ = writeln!(x, " format=\"appended\" offset=\"{offset}\"/>");
                offset += head.len() + data.len();
            }
            Encoding::Base64 => {
                let e = base64::engine::general_purpose::STANDARD;
                let _ = writeln!(
                    x,
                    " format=\"binary\">{}{}</DataArray>",
                    e.encode(head),
                    e.encode(data)
                );
            }
        }
    }
    let _ = writeln!(x, "      </{section}>");
    let _ = writeln!(x, "    </Piece>");
    let _ = writeln!(x, "  </UnstructuredGrid>");
    let mut out = x.into_bytes();
    if opts.encoding == Encoding::Appended {
        out.extend_from_slice(b"  <AppendedData encoding=\"raw\">\n   _");
        for (head, data) in &encoded {
            out.extend_from_slice(head);
            out.extend_from_slice(data);
        }
        out.extend_from_slice(b"\n  </AppendedData>\n");
    }
    out.extend_from_slice(b"</VTKFile>\n");
    out
}
