//! Reader for VTK XML `UnstructuredGrid` (`.vtu`) and `PolyData` (`.vtp`) files of triangles with
//! inline data: `format="ascii"` or `format="binary"` (base64), uncompressed or compressed with
//! zlib (`compressor="vtkZLibDataCompressor"`, ParaView's default), `header_type` UInt32 or
//! UInt64, either byte order. Raw appended data is refused with a message saying how to save a
//! readable file.
//!
//! Written here rather than taken from vtkio so that every error names the byte offset and the
//! element it is in, compressed-data headers are checked against the data before anything is
//! allocated or sliced, and no input can panic.
//!
//! Format: <https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html> (XML part).
//! Binary inline data is base64 of a header (the byte count; for compressed data the block
//! count, block size, last block size and each block's compressed size) followed by the data;
//! VTK encodes the two separately, other writers as one stream. Both are read.

use super::RawMesh;
use crate::math::Real;
use base64::Engine as _;
use quick_xml::events::Event;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Read as _;

type Fail = String;

/// Deepest element nesting accepted (a VTK file needs 5).
const MAX_DEPTH: usize = 64;

struct Node<'a> {
    name: String,
    attrs: Vec<(String, String)>,
    text: Vec<Cow<'a, [u8]>>,
    children: Vec<Node<'a>>,
    /// Byte offset of the start tag.
    offset: u64,
}

impl Node<'_> {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    fn child(&self, name: &str) -> Option<&Self> {
        self.children.iter().find(|c| c.name == name)
    }
    fn at(&self, what: impl std::fmt::Display) -> Fail {
        format!("byte {}, <{}>: {what}", self.offset, self.name)
    }
}

fn parse_tree(bytes: &[u8]) -> Result<Node<'_>, Fail> {
    let mut r = quick_xml::Reader::from_reader(bytes);
    let mut stack: Vec<Node> = vec![Node {
        name: String::new(),
        attrs: Vec::new(),
        text: Vec::new(),
        children: Vec::new(),
        offset: 0,
    }];
    let open = |e: &quick_xml::events::BytesStart, offset: u64| -> Result<Node<'static>, Fail> {
        let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
        let mut attrs = Vec::new();
        for a in e.attributes() {
            let a = a.map_err(|err| format!("byte {offset}, <{name}>: bad attribute: {err}"))?;
            let key = String::from_utf8_lossy(a.key.local_name().as_ref()).into_owned();
            let v = a
                .unescape_value()
                .map_err(|err| format!("byte {offset}, <{name}> attribute {key}: {err}"))?;
            attrs.push((key, v.into_owned()));
        }
        Ok(Node {
            name,
            attrs,
            text: Vec::new(),
            children: Vec::new(),
            offset,
        })
    };
    loop {
        let offset = r.buffer_position();
        let ev = r
            .read_event()
            .map_err(|e| format!("byte {}: invalid XML: {e}", r.buffer_position()))?;
        match ev {
            Event::Start(e) => {
                if stack.len() > MAX_DEPTH {
                    return Err(format!(
                        "byte {offset}: elements nested deeper than {MAX_DEPTH}"
                    ));
                }
                stack.push(open(&e, offset)?);
            }
            Event::Empty(e) => {
                let n = open(&e, offset)?;
                if let Some(top) = stack.last_mut() {
                    top.children.push(n);
                }
            }
            Event::End(_) => {
                // quick-xml checks that end tags match their start tags.
                let n = stack
                    .pop()
                    .ok_or_else(|| format!("byte {offset}: unbalanced end tag"))?;
                match stack.last_mut() {
                    Some(top) => top.children.push(n),
                    None => return Err(format!("byte {offset}: unbalanced end tag")),
                }
            }
            Event::Text(t) => {
                if let Some(top) = stack.last_mut() {
                    top.text.push(t.into_inner());
                }
            }
            Event::CData(t) => {
                if let Some(top) = stack.last_mut() {
                    top.text.push(t.into_inner());
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if stack.len() != 1 {
        return Err(format!(
            "the file ends inside <{}> (truncated?)",
            stack.last().map_or("", |n| n.name.as_str())
        ));
    }
    let root = stack.pop().map(|r| r.children).unwrap_or_default();
    root.into_iter()
        .find(|n| n.name == "VTKFile")
        .ok_or_else(|| "no <VTKFile> element: not a VTK XML file".to_string())
}

/// How the file encodes binary data.
struct Encoding {
    little: bool,
    header_bytes: usize,
    zlib: bool,
}

/// Element types: (bytes, kind) with kind 0 signed integer, 1 unsigned, 2 float.
fn elem_type(t: &str) -> Option<(usize, u8)> {
    Some(match t {
        "Int8" | "Char" => (1, 0),
        "UInt8" | "UChar" => (1, 1),
        "Int16" | "Short" => (2, 0),
        "UInt16" | "UShort" => (2, 1),
        "Int32" | "Int" => (4, 0),
        "UInt32" | "UInt" => (4, 1),
        "Int64" | "Long" | "IdType" => (8, 0),
        "UInt64" | "ULong" => (8, 1),
        "Float32" | "Float" => (4, 2),
        "Float64" | "Double" => (8, 2),
        _ => return None,
    })
}

fn decode_value(c: &[u8], kind: u8, little: bool) -> Real {
    let mut b = [0u8; 8];
    let n = c.len();
    b[..n].copy_from_slice(c);
    if !little {
        b[..n].reverse();
    }
    match (n, kind) {
        (1, 0) => b[0] as i8 as Real,
        (1, _) => b[0] as Real,
        (2, 0) => i16::from_le_bytes([b[0], b[1]]) as Real,
        (2, _) => u16::from_le_bytes([b[0], b[1]]) as Real,
        (4, 0) => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as Real,
        (4, 1) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as Real,
        (4, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as Real,
        (_, 0) => i64::from_le_bytes(b) as Real,
        (_, 1) => u64::from_le_bytes(b) as Real,
        _ => Real::from_le_bytes(b),
    }
}

fn b64(s: &[u8]) -> Result<Vec<u8>, String> {
    base64::engine::general_purpose::STANDARD
        .decode(s)
        .map_err(|e| format!("invalid base64: {e}"))
}

fn header_num(b: &[u8], enc: &Encoding) -> u64 {
    decode_value(&b[..enc.header_bytes], 1, enc.little) as u64
}

/// The raw bytes of a binary DataArray holding `expect` bytes.
fn binary_bytes(text: &[u8], enc: &Encoding, expect: usize) -> Result<Vec<u8>, Fail> {
    let hb = enc.header_bytes;
    let h64 = 4 * hb.div_ceil(3);
    if text.len() < h64 {
        return Err(String::from(
            "binary data shorter than its header (truncated?)",
        ));
    }
    let first = b64(&text[..h64])?;
    if !enc.zlib {
        let n = header_num(&first, enc);
        if n != expect as u64 {
            return Err(format!(
                "the binary header announces {n} bytes, but the array needs {expect}"
            ));
        }
        let data = if text[h64 - 1] == b'=' {
            // Header and data encoded apart (VTK).
            b64(&text[h64..])?
        } else {
            let mut all = b64(text)?;
            all.drain(..hb.min(all.len()));
            all
        };
        if data.len() != expect {
            return Err(format!(
                "binary data holds {} bytes, expected {expect} (truncated?)",
                data.len()
            ));
        }
        return Ok(data);
    }
    // Compressed: [blocks, block size, last block size, compressed size of each block].
    let nb = header_num(&first, enc);
    let too_many = || format!("compression header announces {nb} blocks, more than the data holds");
    let nb_usize = usize::try_from(nb).map_err(|_| too_many())?;
    let full = nb_usize
        .checked_add(3)
        .and_then(|k| k.checked_mul(hb))
        .ok_or_else(too_many)?;
    let f64_ = 4 * full.div_ceil(3);
    if f64_ > text.len() {
        return Err(too_many());
    }
    let head = b64(&text[..f64_]).map_err(|e| format!("compression header: {e}"))?;
    if head.len() < full {
        return Err(String::from("compression header truncated"));
    }
    let num = |i: usize| header_num(&head[i * hb..], enc);
    let (block, last) = (num(1), num(2));
    let last = if last == 0 { block } else { last };
    let total = if nb == 0 {
        0
    } else {
        block
            .checked_mul(nb - 1)
            .and_then(|t| t.checked_add(last))
            .ok_or_else(|| String::from("compression header sizes overflow"))?
    };
    if total != expect as u64 || last > block {
        return Err(format!(
            "compression header announces {total} uncompressed bytes (blocks of {block}, last \
             {last}), but the array needs {expect}"
        ));
    }
    let data = b64(&text[f64_..]).map_err(|e| format!("compressed data: {e}"))?;
    let mut out = Vec::with_capacity(expect);
    let mut at = 0usize;
    for i in 0..nb_usize {
        let c = usize::try_from(num(3 + i)).unwrap_or(usize::MAX);
        let end = at
            .checked_add(c)
            .filter(|&e| e <= data.len())
            .ok_or_else(|| {
                format!(
                    "compressed block {i} of {c} bytes runs past the {} bytes of data (truncated?)",
                    data.len()
                )
            })?;
        let want = if i + 1 == nb_usize { last } else { block } as usize;
        let before = out.len();
        flate2::read::ZlibDecoder::new(&data[at..end])
            .take(want as u64 + 1)
            .read_to_end(&mut out)
            .map_err(|e| format!("compressed block {i}: {e}"))?;
        if out.len() - before != want {
            return Err(format!(
                "compressed block {i} inflates to {} bytes, its header says {want}",
                out.len() - before
            ));
        }
        at = end;
    }
    Ok(out)
}

/// A DataArray's values as reals; `entries × components` of them, checked.
fn array(
    node: &Node,
    enc: &Encoding,
    entries: usize,
    what: &str,
) -> Result<(usize, Vec<Real>), Fail> {
    let name = node.attr("Name").unwrap_or("");
    let label = if name.is_empty() {
        what.to_string()
    } else {
        format!("{what} array '{name}'")
    };
    let at = |m: String| format!("byte {}, {label}: {m}", node.offset);
    let comps = match node.attr("NumberOfComponents") {
        None => 1,
        Some(s) => s
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|c| (1..=64).contains(c))
            .ok_or_else(|| at(format!("NumberOfComponents '{s}' is not 1–64")))?,
    };
    let ty = node.attr("type").unwrap_or("");
    let (size, kind) = elem_type(ty).ok_or_else(|| at(format!("unsupported type '{ty}'")))?;
    let n = entries
        .checked_mul(comps)
        .ok_or_else(|| at("the array size overflows".into()))?;
    let text: Vec<u8> = node
        .text
        .iter()
        .flat_map(|t| t.iter().copied())
        .filter(|c| !c.is_ascii_whitespace() || node.attr("format") == Some("ascii"))
        .collect();
    let values = match node.attr("format").unwrap_or("ascii") {
        "ascii" => {
            let s = String::from_utf8_lossy(&text);
            let mut out = Vec::with_capacity(n.min(text.len() / 2 + 1));
            for (i, t) in s.split_ascii_whitespace().enumerate() {
                let v = t
                    .parse::<Real>()
                    .map_err(|_| at(format!("value {i}, '{t}', is not a number")))?;
                out.push(v);
                if out.len() > n {
                    break;
                }
            }
            out
        }
        "binary" => {
            let expect = n
                .checked_mul(size)
                .ok_or_else(|| at("the array size overflows".into()))?;
            let bytes = binary_bytes(&text, enc, expect).map_err(at)?;
            bytes
                .chunks_exact(size)
                .map(|c| decode_value(c, kind, enc.little))
                .collect()
        }
        "appended" => {
            return Err(at(
                "raw appended data is not supported; save it from ParaView as legacy \
                 .vtk, or as XML with 'Data Mode: Ascii' or 'Binary' (inline base64)"
                    .into(),
            ))
        }
        other => return Err(at(format!("unknown format '{other}'"))),
    };
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(at(format!("value {i} is non-finite ({:e})", values[i])));
    }
    if values.len() != n {
        return Err(at(format!(
            "{}{} values, expected {n} ({entries} × {comps} components)",
            values.len(),
            if values.len() > n { " or more" } else { "" }
        )));
    }
    Ok((comps, values))
}

fn count_attr(node: &Node, key: &str) -> Result<usize, Fail> {
    match node.attr(key) {
        None => Ok(0),
        Some(s) => s
            .trim()
            .parse::<u64>()
            .ok()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| node.at(format!("{key}='{s}' is not a count"))),
    }
}

fn as_indices(v: &[Real], node: &Node, what: &str) -> Result<Vec<usize>, Fail> {
    v.iter()
        .enumerate()
        .map(|(i, &x)| {
            if x >= 0.0 && x.fract() == 0.0 && x < 1e15 {
                Ok(x as usize)
            } else {
                Err(node.at(format!("{what} entry {i} is {x:e}, not an index")))
            }
        })
        .collect()
}

/// Vertex lists of cells, and their VTK cell types when the file gives them.
type CellLists = (Vec<Vec<usize>>, Option<Vec<usize>>);

/// Cells from a `<Cells>` or `<Polys>` element with `n` cells.
fn cell_lists(el: &Node, enc: &Encoding, n: usize) -> Result<CellLists, Fail> {
    let find = |name: &str| {
        el.children
            .iter()
            .find(|c| c.name == "DataArray" && c.attr("Name") == Some(name))
            .ok_or_else(|| el.at(format!("no DataArray named '{name}'")))
    };
    let on = find("offsets")?;
    let offsets = as_indices(&array(on, enc, n, "offsets")?.1, on, "offsets")?;
    let total = offsets.last().copied().unwrap_or(0);
    let cn = find("connectivity")?;
    let conn = as_indices(
        &array(cn, enc, total, "connectivity")?.1,
        cn,
        "connectivity",
    )?;
    let mut cells = Vec::with_capacity(n);
    let mut prev = 0;
    for (c, &o) in offsets.iter().enumerate() {
        if o < prev || o > conn.len() {
            return Err(on.at(format!(
                "cell {c}'s offset {o} is outside {prev}..={} (offsets must grow up to the \
                 connectivity's length)",
                conn.len()
            )));
        }
        cells.push(conn[prev..o].to_vec());
        prev = o;
    }
    let types = match el.name.as_str() {
        "Cells" => {
            let tn = find("types")?;
            Some(as_indices(&array(tn, enc, n, "types")?.1, tn, "types")?)
        }
        _ => None,
    };
    Ok((cells, types))
}

fn attributes(
    el: Option<&Node>,
    enc: &Encoding,
    n: usize,
    what: &str,
) -> Result<BTreeMap<String, (usize, Vec<Real>)>, Fail> {
    let mut out = BTreeMap::new();
    for a in el
        .iter()
        .flat_map(|e| e.children.iter())
        .filter(|c| c.name == "DataArray")
    {
        let name = a.attr("Name").unwrap_or("").to_string();
        if name.is_empty() {
            return Err(a.at(format!("a {what} DataArray without a Name")));
        }
        let v = array(a, enc, n, what)?;
        if out.insert(name.clone(), v).is_some() {
            return Err(a.at(format!("a second {what} array named '{name}'")));
        }
    }
    Ok(out)
}

/// Parses a VTK XML file of triangles into points, triangles and fields.
pub fn parse(bytes: &[u8]) -> Result<RawMesh, Fail> {
    let root = parse_tree(bytes)?;
    let kind = root.attr("type").unwrap_or("");
    let little = match root.attr("byte_order").unwrap_or("LittleEndian") {
        "LittleEndian" => true,
        "BigEndian" => false,
        o => return Err(root.at(format!("unknown byte_order '{o}'"))),
    };
    let header_bytes = match root.attr("header_type").unwrap_or("UInt32") {
        "UInt32" => 4,
        "UInt64" => 8,
        o => return Err(root.at(format!("unknown header_type '{o}'"))),
    };
    let zlib = match root.attr("compressor") {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(o) => {
            return Err(root.at(format!(
                "compressor '{o}' is not supported (zlib is; or save without compression)"
            )))
        }
    };
    let enc = Encoding {
        little,
        header_bytes,
        zlib,
    };
    if root.child("AppendedData").is_some() {
        return Err(root.at(
            "XML with raw appended data is not supported; save it from ParaView as legacy .vtk, or \
             as XML with 'Data Mode: Ascii' or 'Binary' (inline base64)",
        ));
    }
    let (grid, ds) = match kind {
        "UnstructuredGrid" => (true, root.child("UnstructuredGrid")),
        "PolyData" => (false, root.child("PolyData")),
        o => return Err(root.at(format!("type '{o}': must be UnstructuredGrid or PolyData"))),
    };
    let ds = ds.ok_or_else(|| root.at(format!("no <{kind}> element")))?;
    let pieces: Vec<&Node> = ds.children.iter().filter(|c| c.name == "Piece").collect();
    if pieces.len() != 1 {
        return Err(ds.at(format!("expected one <Piece>, found {}", pieces.len())));
    }
    let piece = pieces[0];
    let nv = count_attr(piece, "NumberOfPoints")?;
    let pts = piece
        .child("Points")
        .and_then(|p| p.child("DataArray"))
        .ok_or_else(|| piece.at("no <Points> DataArray"))?;
    let (pc, points) = array(pts, &enc, nv, "Points")?;
    if pc != 3 {
        return Err(pts.at(format!("Points have {pc} components, expected 3")));
    }
    let (cells, types) = if grid {
        let n = count_attr(piece, "NumberOfCells")?;
        let el = piece.child("Cells").ok_or_else(|| piece.at("no <Cells>"))?;
        cell_lists(el, &enc, n)?
    } else {
        for (key, el) in [
            ("NumberOfVerts", "Verts"),
            ("NumberOfLines", "Lines"),
            ("NumberOfStrips", "Strips"),
        ] {
            if count_attr(piece, key)? > 0 {
                return Err(piece.at(format!(
                    "{key} > 0: PolyData with {el} is not read, only Polys of 3 vertices"
                )));
            }
        }
        let n = count_attr(piece, "NumberOfPolys")?;
        let el = piece.child("Polys").ok_or_else(|| piece.at("no <Polys>"))?;
        cell_lists(el, &enc, n)?
    };
    let faces = super::triangles(&cells, types.as_deref())?;
    let nf = faces.len();
    Ok(RawMesh {
        points,
        faces,
        cell_data: attributes(piece.child("CellData"), &enc, nf, "CellData")?,
        point_data: attributes(piece.child("PointData"), &enc, nv, "PointData")?,
    })
}
