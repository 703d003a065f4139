//! Reader for VTK XML `UnstructuredGrid` (`.vtu`) and `PolyData` (`.vtp`) files of triangles:
//! inline data (`format="ascii"` or `"binary"`, base64) and appended data (`<AppendedData
//! encoding="raw">`, ParaView's default, or `encoding="base64"`), uncompressed or compressed with
//! any of VTK's compressors (zlib, LZ4, LZMA), `header_type` UInt32 or UInt64, either byte
//! order.
//!
//! Written here rather than taken from a VTK crate so that every error names the byte offset and
//! the element it is in, compressed-data headers are checked against the data before anything is
//! allocated or sliced, and no input can panic.
//!
//! Format: <https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html> (XML part).
//! Binary data is a header (the byte count; for compressed data the block count, block size,
//! last block size and each block's compressed size) followed by the data. Inline, it is base64
//! (VTK encodes the header and the data apart, other writers as one stream; both are read);
//! appended, each array sits at its `offset` in the bytes after the `_` marker, raw or base64.
//! Raw data is not XML: the XML before `<AppendedData>` is parsed, and the block is sliced by
//! offset.

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

/// The compressors VTK writes (`compressor` attribute of `<VTKFile>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Compressor {
    None,
    /// `vtkZLibDataCompressor` (zlib streams).
    Zlib,
    /// `vtkLZ4DataCompressor` (LZ4 block format).
    Lz4,
    /// `vtkLZMADataCompressor` (xz streams).
    Lzma,
}

/// The `<AppendedData>` block: the bytes after its `_` marker up to `</AppendedData>`.
struct Appended<'a> {
    data: &'a [u8],
    /// File byte offset of `data[0]`.
    start: usize,
    /// `encoding="base64"` (else raw bytes).
    base64: bool,
    /// The offsets of every appended array, sorted: with base64, an array's text ends where
    /// the next one starts.
    offsets: Vec<usize>,
}

/// How the file encodes binary data.
struct Encoding<'a> {
    little: bool,
    header_bytes: usize,
    compressor: Compressor,
    appended: Option<Appended<'a>>,
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

/// The raw bytes of a base64 binary array holding `expect` bytes: the header and the data are
/// decoded (VTK encodes the two apart; other writers, uncompressed, as one stream) into the
/// raw layout [`raw_bytes`] reads.
fn binary_bytes(text: &[u8], enc: &Encoding, expect: usize) -> Result<Vec<u8>, Fail> {
    let hb = enc.header_bytes;
    let h64 = 4 * hb.div_ceil(3);
    if text.len() < h64 {
        return Err(String::from(
            "binary data shorter than its header (truncated?)",
        ));
    }
    let first = b64(&text[..h64])?;
    let raw = if enc.compressor == Compressor::None {
        if text[h64 - 1] == b'=' {
            let mut raw = first[..hb.min(first.len())].to_vec();
            raw.extend(b64(&text[h64..])?);
            raw
        } else {
            b64(text)?
        }
    } else {
        // Compressed: [blocks, block size, last block size, compressed size of each block].
        let nb = header_num(&first, enc);
        let too_many =
            || format!("compression header announces {nb} blocks, more than the data holds");
        let full = usize::try_from(nb)
            .ok()
            .and_then(|nb| nb.checked_add(3))
            .and_then(|k| k.checked_mul(hb))
            .ok_or_else(too_many)?;
        let f64_ = 4 * full.div_ceil(3);
        if f64_ > text.len() {
            return Err(too_many());
        }
        let mut raw = b64(&text[..f64_]).map_err(|e| format!("compression header: {e}"))?;
        if raw.len() < full {
            return Err(String::from("compression header truncated"));
        }
        raw.truncate(full);
        raw.extend(b64(&text[f64_..]).map_err(|e| format!("compressed data: {e}"))?);
        raw
    };
    raw_bytes(&raw, enc, expect)
}

/// The bytes of an array holding `expect` bytes from its raw binary form `d` (inline base64
/// decoded, or appended data from the array's offset on): a header of the byte count, then
/// the data; compressed, a header of the block count, the block size, the last block's size
/// (0: a full block) and each block's compressed size, then the blocks. Every size is checked
/// against the data before anything is sliced, and nothing is allocated from a header alone.
fn raw_bytes(d: &[u8], enc: &Encoding, expect: usize) -> Result<Vec<u8>, Fail> {
    let hb = enc.header_bytes;
    let num = |i: usize| -> Result<u64, Fail> {
        i.checked_mul(hb)
            .and_then(|a| d.get(a..a.checked_add(hb)?))
            .map(|b| header_num(b, enc))
            .ok_or_else(|| {
                format!(
                    "the data ends inside its header ({} bytes, header entry {i}; truncated?)",
                    d.len()
                )
            })
    };
    if enc.compressor == Compressor::None {
        let n = num(0)?;
        if n != expect as u64 {
            return Err(format!(
                "the binary header announces {n} bytes, but the array needs {expect}"
            ));
        }
        return d.get(hb..hb + expect).map(<[u8]>::to_vec).ok_or_else(|| {
            format!(
                "binary data holds {} bytes, expected {expect} (truncated?)",
                d.len() - hb
            )
        });
    }
    let nb = num(0)?;
    let too_many = || format!("compression header announces {nb} blocks, more than the data holds");
    let nb_usize = usize::try_from(nb).map_err(|_| too_many())?;
    let full = nb_usize
        .checked_add(3)
        .and_then(|k| k.checked_mul(hb))
        .filter(|&f| f <= d.len())
        .ok_or_else(too_many)?;
    let (block, last) = (num(1)?, num(2)?);
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
    let mut out = Vec::with_capacity(expect.min(1 << 26));
    let mut at = full;
    for i in 0..nb_usize {
        let c = usize::try_from(num(3 + i)?).unwrap_or(usize::MAX);
        let end = at.checked_add(c).filter(|&e| e <= d.len()).ok_or_else(|| {
            format!(
                "compressed block {i} of {c} bytes runs past the {} bytes of data (truncated?)",
                d.len() - full
            )
        })?;
        let want = if i + 1 == nb_usize { last } else { block } as usize;
        let before = out.len();
        inflate(enc.compressor, &d[at..end], want, &mut out)
            .map_err(|e| format!("compressed block {i} (data byte {}): {e}", at - full))?;
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

/// Appends the decompression of one block (at most `want` + 1 bytes) to `out`.
fn inflate(c: Compressor, src: &[u8], want: usize, out: &mut Vec<u8>) -> Result<(), String> {
    let limit = want as u64 + 1;
    match c {
        Compressor::None => out.extend_from_slice(src),
        Compressor::Zlib => {
            flate2::read::ZlibDecoder::new(src)
                .take(limit)
                .read_to_end(out)
                .map_err(|e| e.to_string())?;
        }
        Compressor::Lzma => {
            // The decoder writes into a sink that stops at `limit` bytes, so a block that
            // claims little and inflates to much (a bomb) costs no more than its claim.
            struct Capped<'a> {
                out: &'a mut Vec<u8>,
                left: usize,
            }
            impl std::io::Write for Capped<'_> {
                fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
                    if self.left == 0 {
                        return Err(std::io::Error::other("capped"));
                    }
                    let n = b.len().min(self.left);
                    self.out.extend_from_slice(&b[..n]);
                    self.left -= n;
                    Ok(n)
                }
                fn flush(&mut self) -> std::io::Result<()> {
                    Ok(())
                }
            }
            let mut sink = Capped {
                out,
                left: limit as usize,
            };
            match lzma_rs::xz_decompress(&mut std::io::BufReader::new(src), &mut sink) {
                Ok(()) => {}
                // Past the claim: the caller reports the size mismatch.
                Err(_) if sink.left == 0 => {}
                Err(e) => return Err(e.to_string()),
            }
        }
        Compressor::Lz4 => {
            // An LZ4 block expands at most 255×: a larger claim is refused before allocating.
            if want > src.len().saturating_mul(255).saturating_add(16) {
                return Err(format!(
                    "{} compressed bytes cannot hold the {want} bytes the header announces",
                    src.len()
                ));
            }
            let before = out.len();
            out.resize(before + want, 0);
            let n = lz4_flex::block::decompress_into(src, &mut out[before..])
                .map_err(|e| e.to_string())?;
            out.truncate(before + n);
        }
    }
    Ok(())
}

/// The bytes of an appended array at `offset` holding `expect` bytes.
fn appended_bytes(
    ap: &Appended,
    enc: &Encoding,
    offset: usize,
    expect: usize,
) -> Result<Vec<u8>, Fail> {
    if offset >= ap.data.len() {
        return Err(format!(
            "the offset is past the end of the {} bytes of appended data (truncated?)",
            ap.data.len()
        ));
    }
    if ap.base64 {
        let end = ap
            .offsets
            .iter()
            .find(|&&o| o > offset)
            .copied()
            .unwrap_or(ap.data.len())
            .min(ap.data.len());
        let text: Vec<u8> = ap.data[offset..end]
            .iter()
            .copied()
            .filter(|c| !c.is_ascii_whitespace())
            .collect();
        binary_bytes(&text, enc, expect)
    } else {
        raw_bytes(&ap.data[offset..], enc, expect)
    }
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
            let ap = enc.appended.as_ref().ok_or_else(|| {
                at("format=\"appended\", but the file has no <AppendedData>".into())
            })?;
            let off = node
                .attr("offset")
                .and_then(|o| o.trim().parse::<usize>().ok())
                .ok_or_else(|| at("an appended array needs an offset (a byte count)".into()))?;
            let expect = n
                .checked_mul(size)
                .ok_or_else(|| at("the array size overflows".into()))?;
            let bytes = appended_bytes(ap, enc, off, expect).map_err(|m| {
                at(format!(
                    "appended data at offset {off} (file byte {}): {m}",
                    ap.start + off
                ))
            })?;
            bytes
                .chunks_exact(size)
                .map(|c| decode_value(c, kind, enc.little))
                .collect()
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
                Err(node.at(format!(
                    "{what} entry {i} is {x_h}, not an index",
                    x_h = crate::math::human(x)
                )))
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

/// Offsets of the appended arrays under `node`.
fn collect_offsets(node: &Node, out: &mut Vec<usize>) {
    for c in &node.children {
        if c.name == "DataArray" && c.attr("format") == Some("appended") {
            if let Some(o) = c.attr("offset").and_then(|o| o.trim().parse().ok()) {
                out.push(o);
            }
        }
        collect_offsets(c, out);
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A file with `<AppendedData>` split into the XML before it (closed with `</VTKFile>`, so
/// that it parses as XML; raw data is not XML) and the block: its file byte offset, its bytes
/// after the `_` marker up to the last `</AppendedData>`, and whether it is base64.
#[allow(clippy::type_complexity)]
fn split_appended(bytes: &[u8]) -> Result<(Cow<'_, [u8]>, Option<(usize, &[u8], bool)>), Fail> {
    let Some(p) = find(bytes, b"<AppendedData") else {
        return Ok((Cow::Borrowed(bytes), None));
    };
    let q = p + find(&bytes[p..], b">")
        .ok_or_else(|| format!("byte {p}: the <AppendedData> tag never closes (truncated?)"))?;
    let tag = String::from_utf8_lossy(&bytes[p..=q]);
    let base64 = if tag.contains("encoding=\"base64\"") {
        true
    } else if tag.contains("encoding=\"raw\"") {
        false
    } else {
        return Err(format!(
            "byte {p}: <AppendedData> needs encoding=\"raw\" or \"base64\""
        ));
    };
    let u = q
        + 1
        + bytes[q + 1..]
            .iter()
            .position(|c| !c.is_ascii_whitespace())
            .ok_or_else(|| format!("byte {q}: the file ends after <AppendedData> (truncated?)"))?;
    if bytes[u] != b'_' {
        return Err(format!(
            "byte {u}: appended data must start with '_', found {:?}",
            bytes[u] as char
        ));
    }
    let start = u + 1;
    let end = bytes[start..]
        .windows(b"</AppendedData>".len())
        .rposition(|w| w == b"</AppendedData>")
        .map(|e| start + e)
        .ok_or_else(|| {
            format!("byte {start}: no </AppendedData> after the appended data (truncated?)")
        })?;
    let mut head = bytes[..p].to_vec();
    head.extend_from_slice(b"</VTKFile>");
    Ok((Cow::Owned(head), Some((start, &bytes[start..end], base64))))
}

/// Parses a VTK XML file of triangles into points, triangles and fields.
pub fn parse(bytes: &[u8]) -> Result<RawMesh, Fail> {
    let (head, appended) = split_appended(bytes)?;
    let root = parse_tree(&head)?;
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
    let compressor = match root.attr("compressor") {
        None | Some("") => Compressor::None,
        Some("vtkZLibDataCompressor") => Compressor::Zlib,
        Some("vtkLZ4DataCompressor") => Compressor::Lz4,
        Some("vtkLZMADataCompressor") => Compressor::Lzma,
        Some(o) => {
            return Err(root.at(format!(
                "unknown compressor '{o}' (VTK's are vtkZLibDataCompressor, vtkLZ4DataCompressor \
                 and vtkLZMADataCompressor)"
            )))
        }
    };
    let appended = match appended {
        None => None,
        Some((start, data, base64)) => {
            let mut offsets = Vec::new();
            collect_offsets(&root, &mut offsets);
            offsets.sort_unstable();
            Some(Appended {
                data,
                start,
                base64,
                offsets,
            })
        }
    };
    let enc = Encoding {
        little,
        header_bytes,
        compressor,
        appended,
    };
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
