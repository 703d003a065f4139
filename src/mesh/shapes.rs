//! Readers for the formats shape collections use: OFF (the Princeton Shape Benchmark's), OBJ
//! (Wavefront), PLY (Stanford; ASCII and binary of either byte order) and STL (ASCII and binary).
//!
//! Written here, like the VTK readers, so that every error names the line (text) or byte offset
//! (binary) and what was expected, nothing is allocated from a count before the data it
//! announces is known to be there, and no input can panic (they are fuzzed with the others,
//! [`crate::fuzz`]). The formats are small; the crates that read them report errors without
//! positions.
//!
//! Polygons with more than three vertices are triangulated by ear clipping in the plane of
//! their Newell normal, keeping their orientation; a polygon with fewer than three distinct
//! vertices, collinear vertices or self-intersections cannot be triangulated and is an error
//! naming its line and polygon. STL stores each triangle's corners apart: corners with the same
//! coordinates (bit for bit) become one vertex. PLY's further vertex and face properties
//! (scalars) become vertex and face fields of their name (a polygon's value goes to each of its
//! triangles). Geometry and topology are validated afterwards as for every format
//! ([`super::Mesh::validate`], [`super::Topology::build`]).
//!
//! Formats: OFF <https://segeval.cs.princeton.edu/public/off_format.html>; OBJ (`v`, `f` with
//! `i`, `i/t`, `i//n`, `i/t/n`, negative indices counted back from the last vertex; other
//! statements ignored); PLY <http://paulbourke.net/dataformats/ply/>; STL (3D Systems, 1989).

use super::RawMesh;
use crate::math::{Real, Vec3};
use std::collections::BTreeMap;

/// Lines of a text file with their numbers (1-based), comments (`#` to the end) removed.
fn lines(b: &[u8]) -> impl Iterator<Item = (usize, &str)> {
    b.split(|&c| c == b'\n').enumerate().map(|(i, l)| {
        let s = std::str::from_utf8(l).unwrap_or("\u{fffd}");
        let s = s.split('#').next().unwrap_or("");
        (i + 1, s.trim())
    })
}

fn number(t: &str, line: usize, what: &str) -> Result<Real, String> {
    t.parse::<Real>()
        .map_err(|_| format!("line {line}: {what} must be a number, found '{t}'"))
}

fn count(t: Option<&str>, line: usize, what: &str) -> Result<usize, String> {
    let t = t.ok_or_else(|| format!("line {line}: {what} is missing"))?;
    t.parse::<usize>()
        .map_err(|_| format!("line {line}: {what} must be a count, found '{t}'"))
}

/// Triangulates polygon `poly` (vertex indices into `points`, flat xyz) by ear clipping in the
/// plane of its Newell normal; `where_` names it in errors. Indices must be in range.
fn triangulate(
    poly: &[usize],
    points: &[Real],
    where_: &dyn Fn() -> String,
    out: &mut Vec<[usize; 3]>,
) -> Result<usize, String> {
    let k = poly.len();
    if k < 3 {
        return Err(format!(
            "{}: a face needs at least 3 vertices, this one has {k}",
            where_()
        ));
    }
    if k == 3 {
        out.push([poly[0], poly[1], poly[2]]);
        return Ok(1);
    }
    let p = |i: usize| {
        let v = poly[i];
        Vec3::new(points[3 * v], points[3 * v + 1], points[3 * v + 2])
    };
    // Newell normal: robust for non-planar and non-convex polygons.
    let mut n = Vec3::zeros();
    for i in 0..k {
        let (a, b) = (p(i), p((i + 1) % k));
        n += Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let scale = (0..k).map(|i| (p(i) - p(0)).norm()).fold(0.0, Real::max);
    if n.norm().is_nan() || n.norm() <= 1e-12 * scale * scale || !n.iter().all(|c| c.is_finite()) {
        return Err(format!(
            "{}: a polygon of {k} vertices that cannot be triangulated (its vertices are \
             collinear or repeated, or not finite)",
            where_()
        ));
    }
    let n = n.normalize();
    let u = if n.x.abs() < 0.9 {
        Vec3::x().cross(&n).normalize()
    } else {
        Vec3::y().cross(&n).normalize()
    };
    let w = n.cross(&u);
    let q: Vec<(Real, Real)> = (0..k).map(|i| (p(i).dot(&u), p(i).dot(&w))).collect();
    let cross = |a: (Real, Real), b: (Real, Real), c: (Real, Real)| {
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    };
    let mut idx: Vec<usize> = (0..k).collect();
    let before = out.len();
    let eps = 1e-14 * scale * scale;
    while idx.len() > 3 {
        let m = idx.len();
        let ear = (0..m).find(|&i| {
            let (a, b, c) = (idx[(i + m - 1) % m], idx[i], idx[(i + 1) % m]);
            if cross(q[a], q[b], q[c]) <= eps {
                return false;
            }
            // No other vertex inside (or on) the ear.
            idx.iter().all(|&j| {
                j == a
                    || j == b
                    || j == c
                    || cross(q[a], q[b], q[j]) < 0.0
                    || cross(q[b], q[c], q[j]) < 0.0
                    || cross(q[c], q[a], q[j]) < 0.0
            })
        });
        let Some(i) = ear else {
            out.truncate(before);
            return Err(format!(
                "{}: a polygon of {k} vertices that cannot be triangulated (it intersects itself \
                 or has collinear runs)",
                where_()
            ));
        };
        let m = idx.len();
        out.push([
            poly[idx[(i + m - 1) % m]],
            poly[idx[i]],
            poly[idx[(i + 1) % m]],
        ]);
        idx.remove(i);
    }
    out.push([poly[idx[0]], poly[idx[1]], poly[idx[2]]]);
    Ok(out.len() - before)
}

/// A face index checked against the vertex count.
fn index(v: i64, nv: usize, line: usize) -> Result<usize, String> {
    usize::try_from(v).ok().filter(|&v| v < nv).ok_or_else(|| {
        format!("line {line}: vertex index {v} is out of range (there are {nv} vertices)")
    })
}

/// OFF: `[C|N|ST|…]OFF`, then `vertices faces edges`, one vertex per line (first three
/// numbers; colours or normals after them ignored), one polygon per line (`k i₀ … i_{k−1}`,
/// anything after the indices ignored).
pub(super) fn parse_off(b: &[u8]) -> Result<RawMesh, String> {
    super::ends_mid_number(b)?;
    let mut it = lines(b).filter(|(_, l)| !l.is_empty());
    let (hl, header) = it
        .next()
        .ok_or("the file is empty (expected an OFF header)")?;
    let mut toks = header.split_whitespace();
    let first = toks.next().unwrap_or("");
    if !first.ends_with("OFF") || first.contains("4") || first.starts_with('n') {
        return Err(format!(
            "line {hl}: expected the header 'OFF' (or COFF, NOFF, …), found '{first}'"
        ));
    }
    // The counts may follow on the header's line.
    let rest: Vec<&str> = toks.collect();
    let (cl, counts) = if rest.is_empty() {
        let (l, s) = it.next().ok_or(format!(
            "line {hl}: the counts 'vertices faces edges' are missing"
        ))?;
        (l, s.split_whitespace().collect::<Vec<_>>())
    } else {
        (hl, rest)
    };
    let nv = count(counts.first().copied(), cl, "the vertex count")?;
    let nf = count(counts.get(1).copied(), cl, "the face count")?;
    let mut points = Vec::new();
    for k in 0..nv {
        let (l, s) = it.next().ok_or(format!(
            "the file ends after {k} of the {nv} vertices the header (line {cl}) announces"
        ))?;
        let mut t = s.split_whitespace();
        for c in ["x", "y", "z"] {
            let v = t
                .next()
                .ok_or(format!("line {l}: vertex {k} has no {c} coordinate"))?;
            points.push(number(v, l, &format!("vertex {k}'s {c}"))?);
        }
    }
    let mut faces = Vec::new();
    let mut poly = Vec::new();
    for k in 0..nf {
        let (l, s) = it.next().ok_or(format!(
            "the file ends after {k} of the {nf} faces the header (line {cl}) announces"
        ))?;
        let mut t = s.split_whitespace();
        let m = count(t.next(), l, &format!("face {k}'s vertex count"))?;
        poly.clear();
        for j in 0..m {
            let v = t.next().ok_or(format!(
                "line {l}: face {k} announces {m} vertices but lists {j}"
            ))?;
            let v: i64 = v.parse().map_err(|_| {
                format!("line {l}: face {k}'s vertex {j} must be an index, found '{v}'")
            })?;
            poly.push(index(v, nv, l)?);
        }
        triangulate(
            &poly,
            &points,
            &|| format!("line {l}, face {k}"),
            &mut faces,
        )?;
    }
    Ok(RawMesh {
        points,
        faces,
        cell_data: BTreeMap::new(),
        point_data: BTreeMap::new(),
    })
}

/// OBJ: `v x y z [w]` and `f` statements (module doc); everything else is ignored.
pub(super) fn parse_obj(b: &[u8]) -> Result<RawMesh, String> {
    super::ends_inside_line(b)?;
    let mut points: Vec<Real> = Vec::new();
    let mut faces = Vec::new();
    let mut poly = Vec::new();
    let mut nfaces = 0usize;
    for (l, s) in lines(b) {
        let mut t = s.split_whitespace();
        match t.next() {
            Some("v") => {
                let nv = points.len() / 3;
                for c in ["x", "y", "z"] {
                    let v = t
                        .next()
                        .ok_or(format!("line {l}: vertex {nv} has no {c} coordinate"))?;
                    points.push(number(v, l, &format!("vertex {nv}'s {c}"))?);
                }
            }
            Some("f") => {
                let nv = points.len() / 3;
                poly.clear();
                for (j, v) in t.enumerate() {
                    let i = v.split('/').next().unwrap_or("");
                    let i: i64 = i.parse().map_err(|_| {
                        format!("line {l}: face vertex {j} must be an index (i, i/t, i//n or i/t/n), found '{v}'")
                    })?;
                    // 1-based; negative counts back from the last vertex read so far.
                    let z = if i < 0 { nv as i64 + i } else { i - 1 };
                    if i == 0 {
                        return Err(format!("line {l}: vertex index 0 (OBJ counts from 1)"));
                    }
                    poly.push(index(z, nv, l)?);
                }
                triangulate(
                    &poly,
                    &points,
                    &|| format!("line {l}, face {nfaces}"),
                    &mut faces,
                )?;
                nfaces += 1;
            }
            _ => {}
        }
    }
    if faces.is_empty() {
        return Err(format!(
            "no faces ('f' statements) among {} vertices",
            points.len() / 3
        ));
    }
    Ok(RawMesh {
        points,
        faces,
        cell_data: BTreeMap::new(),
        point_data: BTreeMap::new(),
    })
}

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PlyType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl PlyType {
    fn parse(s: &str) -> Option<PlyType> {
        Some(match s {
            "char" | "int8" => PlyType::I8,
            "uchar" | "uint8" => PlyType::U8,
            "short" | "int16" => PlyType::I16,
            "ushort" | "uint16" => PlyType::U16,
            "int" | "int32" => PlyType::I32,
            "uint" | "uint32" => PlyType::U32,
            "float" | "float32" => PlyType::F32,
            "double" | "float64" => PlyType::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            PlyType::I8 | PlyType::U8 => 1,
            PlyType::I16 | PlyType::U16 => 2,
            PlyType::I32 | PlyType::U32 | PlyType::F32 => 4,
            PlyType::F64 => 8,
        }
    }
}

/// A PLY property: a scalar, or a list with its count and item types.
#[derive(Clone, Debug)]
struct PlyProp {
    name: String,
    list: Option<PlyType>,
    ty: PlyType,
}

#[derive(Clone, Debug)]
struct PlyElement {
    name: String,
    count: usize,
    props: Vec<PlyProp>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum PlyFormat {
    Ascii,
    Little,
    Big,
}

/// Reads PLY values: ASCII tokens (with their line) or binary (with the byte offset).
struct PlyReader<'a> {
    /// Position in the file (and, for ASCII, the tokens with their lines).
    lex: super::legacy::Lexer<'a>,
    format: PlyFormat,
}

impl PlyReader<'_> {
    fn at(&self) -> String {
        match self.format {
            PlyFormat::Ascii => format!("line {}", self.lex.line),
            _ => format!("byte offset {}", self.lex.pos),
        }
    }

    fn value(&mut self, ty: PlyType, what: &dyn Fn() -> String) -> Result<Real, String> {
        if self.format == PlyFormat::Ascii {
            let Some(t) = self.lex.token() else {
                return Err(format!(
                    "{}: the file ends where {} was expected",
                    self.at(),
                    what()
                ));
            };
            return t
                .parse::<Real>()
                .map_err(|_| format!("{}: {} must be a number, found '{t}'", self.at(), what()));
        }
        let n = ty.size();
        let pos = self.lex.pos;
        let bytes = self
            .lex
            .b
            .get(pos..pos + n)
            .ok_or_else(|| format!("{}: the file ends inside {}", self.at(), what()))?;
        let mut a = [0u8; 8];
        if self.format == PlyFormat::Little {
            a[..n].copy_from_slice(bytes);
        } else {
            for (i, &c) in bytes.iter().rev().enumerate() {
                a[i] = c;
            }
        }
        self.lex.pos += n;
        Ok(match ty {
            PlyType::I8 => a[0] as i8 as Real,
            PlyType::U8 => a[0] as Real,
            PlyType::I16 => i16::from_le_bytes([a[0], a[1]]) as Real,
            PlyType::U16 => u16::from_le_bytes([a[0], a[1]]) as Real,
            PlyType::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as Real,
            PlyType::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as Real,
            PlyType::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as Real,
            PlyType::F64 => f64::from_le_bytes(a),
        })
    }
}

/// PLY: the header (`format`, `element`, `property` lines, `end_header`), then the elements'
/// data in order. `vertex` needs `x`, `y`, `z`; `face` needs a list `vertex_indices` (or
/// `vertex_index`); other elements are skipped.
pub(super) fn parse_ply(b: &[u8]) -> Result<RawMesh, String> {
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut next_line = |pos: &mut usize| -> Option<(usize, String)> {
        if *pos >= b.len() {
            return None;
        }
        let end = b[*pos..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(b.len(), |e| *pos + e);
        let s = String::from_utf8_lossy(&b[*pos..end]).trim().to_string();
        *pos = (end + 1).min(b.len());
        line += 1;
        Some((line, s))
    };
    let (_, magic) = next_line(&mut pos).ok_or("the file is empty (expected 'ply')")?;
    if magic != "ply" {
        return Err(format!("line 1: expected 'ply', found '{magic}'"));
    }
    let mut format = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    let header_end = loop {
        let (l, s) = next_line(&mut pos).ok_or("the header has no 'end_header'")?;
        let t: Vec<&str> = s.split_whitespace().collect();
        match t.first().copied() {
            Some("format") => {
                format = Some(match t.get(1).copied() {
                    Some("ascii") => PlyFormat::Ascii,
                    Some("binary_little_endian") => PlyFormat::Little,
                    Some("binary_big_endian") => PlyFormat::Big,
                    other => {
                        return Err(format!(
                            "line {l}: unknown format {other:?} (ascii, binary_little_endian or \
                             binary_big_endian)"
                        ))
                    }
                })
            }
            Some("element") => {
                let name = t
                    .get(1)
                    .ok_or(format!("line {l}: an element needs a name"))?
                    .to_string();
                let n = count(t.get(2).copied(), l, "the element count")?;
                elements.push(PlyElement {
                    name,
                    count: n,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or(format!("line {l}: a property before any element"))?;
                let bad = |what: &str| format!("line {l}: unknown property type '{what}'");
                let prop = if t.get(1) == Some(&"list") {
                    let ct = t.get(2).copied().unwrap_or("");
                    let it = t.get(3).copied().unwrap_or("");
                    PlyProp {
                        name: t.get(4).copied().unwrap_or("").to_string(),
                        list: Some(PlyType::parse(ct).ok_or_else(|| bad(ct))?),
                        ty: PlyType::parse(it).ok_or_else(|| bad(it))?,
                    }
                } else {
                    let ty = t.get(1).copied().unwrap_or("");
                    PlyProp {
                        name: t.get(2).copied().unwrap_or("").to_string(),
                        list: None,
                        ty: PlyType::parse(ty).ok_or_else(|| bad(ty))?,
                    }
                };
                el.props.push(prop);
            }
            Some("end_header") => break l,
            Some("comment") | Some("obj_info") | None => {}
            Some(other) => return Err(format!("line {l}: unknown header keyword '{other}'")),
        }
    };
    let format = format.ok_or("the header has no 'format' line")?;
    if format == PlyFormat::Ascii {
        super::ends_mid_number(b)?;
    }
    let mut r = PlyReader {
        lex: super::legacy::Lexer {
            b,
            pos,
            line: header_end + 1,
        },
        format,
    };
    let mut points: Vec<Real> = Vec::new();
    let mut faces = Vec::new();
    let mut point_data: BTreeMap<String, (usize, Vec<Real>)> = BTreeMap::new();
    let mut cell_data: BTreeMap<String, (usize, Vec<Real>)> = BTreeMap::new();
    let mut nv = 0usize;
    let mut poly = Vec::new();
    for el in &elements {
        let is_vertex = el.name == "vertex";
        let is_face = el.name == "face";
        if is_vertex {
            for c in ["x", "y", "z"] {
                if !el.props.iter().any(|p| p.name == c && p.list.is_none()) {
                    return Err(format!("the vertex element has no scalar property '{c}'"));
                }
            }
            nv = el.count;
        }
        if is_face
            && !el.props.iter().any(|p| {
                p.list.is_some() && (p.name == "vertex_indices" || p.name == "vertex_index")
            })
        {
            return Err("the face element has no list property 'vertex_indices'".into());
        }
        // An element without properties has no data: its count costs nothing to skip.
        let count = if el.props.is_empty() { 0 } else { el.count };
        for k in 0..count {
            let mut xyz = [0.0; 3];
            let mut fields: Vec<(&str, Real)> = Vec::new();
            poly.clear();
            for p in &el.props {
                let what = || format!("{} {k}'s '{}'", el.name, p.name);
                match p.list {
                    Some(ct) => {
                        let m = r.value(ct, &what)?;
                        if !(m >= 0.0 && m.fract() == 0.0 && m <= 1e6) {
                            return Err(format!("{}: {} has a list length {m}", r.at(), what()));
                        }
                        for _ in 0..m as usize {
                            let v = r.value(p.ty, &what)?;
                            if is_face && (p.name == "vertex_indices" || p.name == "vertex_index") {
                                if !(v >= 0.0 && v.fract() == 0.0 && (v as usize) < nv) {
                                    return Err(format!(
                                        "{}: face {k}'s vertex index {v} is out of range (there \
                                         are {nv} vertices)",
                                        r.at()
                                    ));
                                }
                                poly.push(v as usize);
                            }
                        }
                    }
                    None => {
                        let v = r.value(p.ty, &what)?;
                        match (is_vertex, p.name.as_str()) {
                            (true, "x") => xyz[0] = v,
                            (true, "y") => xyz[1] = v,
                            (true, "z") => xyz[2] = v,
                            _ => fields.push((&p.name, v)),
                        }
                    }
                }
            }
            if is_vertex {
                points.extend_from_slice(&xyz);
                for (name, v) in fields {
                    point_data
                        .entry(name.to_string())
                        .or_insert((1, Vec::new()))
                        .1
                        .push(v);
                }
            } else if is_face {
                let at = r.at();
                let n = triangulate(&poly, &points, &|| format!("{at}, face {k}"), &mut faces)?;
                for (name, v) in fields {
                    let f = cell_data.entry(name.to_string()).or_insert((1, Vec::new()));
                    f.1.extend(std::iter::repeat_n(v, n));
                }
            }
        }
    }
    if !elements.iter().any(|e| e.name == "vertex") || !elements.iter().any(|e| e.name == "face") {
        return Err("a triangle mesh needs a 'vertex' and a 'face' element".into());
    }
    // Fields only some faces or vertices set are dropped by the length checks downstream.
    Ok(RawMesh {
        points,
        faces,
        cell_data,
        point_data,
    })
}

/// The corners of a binary STL whose size matches its triangle count.
fn stl_binary(b: &[u8]) -> Vec<[Real; 3]> {
    let n = (b.len() - 84) / 50;
    let mut corners = Vec::with_capacity(3 * n);
    for t in 0..n {
        let base = 84 + 50 * t + 12;
        for c in 0..3 {
            let mut p = [0.0; 3];
            for (k, pk) in p.iter_mut().enumerate() {
                let o = base + 12 * c + 4 * k;
                *pk = f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as Real;
            }
            corners.push(p);
        }
    }
    corners
}

/// The corners of an ASCII STL: one or more `solid [name]` … `endsolid [name]` blocks of
/// `facet normal nx ny nz` / `outer loop` / 3 × `vertex x y z` / `endloop` / `endfacet`, one
/// statement a line. Anything out of place, a number that is not one, a statement with too few
/// or too many numbers, or an end of file before `endsolid` (a file cut short) is an error
/// naming the line.
fn stl_ascii(b: &[u8]) -> Result<Vec<[Real; 3]>, String> {
    /// Where the reader is: what it expects next.
    #[derive(Clone, Copy, PartialEq)]
    enum At {
        Solid,
        Facet,
        Loop,
        Vertex(usize),
        EndFacet,
        Done,
    }
    let expected = |at: At| match at {
        At::Solid => "'solid'",
        At::Facet => "'facet normal' or 'endsolid'",
        At::Loop => "'outer loop'",
        At::Vertex(k) if k < 3 => "'vertex'",
        At::Vertex(_) => "'endloop'",
        At::EndFacet => "'endfacet'",
        At::Done => "'solid' or the end of the file",
    };
    let numbers = |t: &mut std::str::SplitWhitespace, l: usize, what: &str| {
        let mut p = [0.0; 3];
        for (k, c) in ["x", "y", "z"].iter().enumerate() {
            let v = t.next().ok_or(format!("line {l}: the {what} has no {c}"))?;
            p[k] = number(v, l, &format!("the {what}'s {c}"))?;
        }
        if let Some(extra) = t.next() {
            return Err(format!(
                "line {l}: the {what} has more than 3 numbers ('{extra}')"
            ));
        }
        Ok::<_, String>(p)
    };
    let mut corners = Vec::new();
    let mut at = At::Solid;
    let mut facets = 0usize;
    let mut last = 0usize;
    for (i, raw) in b.split(|&c| c == b'\n').enumerate() {
        let l = i + 1;
        let s = std::str::from_utf8(raw).unwrap_or("\u{fffd}");
        let mut t = s.split_whitespace();
        let Some(kw) = t.next() else { continue };
        last = l;
        let unexpected = || {
            format!(
                "line {l}: expected {} (facet {facets}), found '{}'",
                expected(at),
                s.trim()
            )
        };
        at = match (at, kw) {
            (At::Solid | At::Done, "solid") => At::Facet,
            (At::Facet, "facet") => {
                if t.next() != Some("normal") {
                    return Err(unexpected());
                }
                numbers(&mut t, l, "facet normal")?;
                At::Loop
            }
            (At::Facet, "endsolid") => At::Done,
            (At::Loop, "outer") if t.next() == Some("loop") && t.next().is_none() => At::Vertex(0),
            (At::Vertex(k), "vertex") => {
                corners.push(numbers(&mut t, l, "vertex")?);
                At::Vertex(k + 1)
            }
            (At::Vertex(3), "endloop") if t.next().is_none() => At::EndFacet,
            (At::Vertex(k), "endloop") if k != 3 => {
                return Err(format!(
                    "line {l}: facet {facets} has {k} vertices; STL facets are triangles"
                ))
            }
            (At::EndFacet, "endfacet") if t.next().is_none() => {
                facets += 1;
                At::Facet
            }
            _ => return Err(unexpected()),
        };
    }
    if at != At::Done {
        return Err(format!(
            "line {last}: the file ends inside {}, where {} was expected: it is cut short",
            if at == At::Facet || at == At::Solid {
                "the solid".to_string()
            } else {
                format!("facet {facets}")
            },
            expected(at)
        ));
    }
    Ok(corners)
}

/// STL, binary (80-byte header, triangle count, 50 bytes per triangle) when the size says so,
/// else ASCII (`solid … facet normal … outer loop vertex ×3 endloop endfacet … endsolid`, read
/// strictly: every keyword in its place, to the `endsolid`).
pub(super) fn parse_stl(b: &[u8]) -> Result<RawMesh, String> {
    let count = (b.len() >= 84).then(|| u32::from_le_bytes([b[80], b[81], b[82], b[83]]) as u64);
    let binary = count.is_some_and(|n| 84 + 50 * n == b.len() as u64);
    let corners = if binary {
        stl_binary(b)
    } else if b.trim_ascii_start().starts_with(b"solid") && !b.contains(&0) {
        stl_ascii(b)?
    } else if let Some(n) = count {
        return Err(format!(
            "a binary STL announcing {n} triangles (bytes 80–83) has 84 + 50 × {n} = {} bytes, \
             this file {} (and it is not an ASCII STL: that starts with 'solid' and holds no zero \
             bytes)",
            84 + 50 * n,
            b.len()
        ));
    } else {
        return Err(
            "neither a binary STL (shorter than its 84-byte header) nor an ASCII one (it does \
             not start with 'solid')"
                .into(),
        );
    };
    if corners.is_empty() {
        return Err("no triangles".into());
    }
    // Merge corners with identical coordinates.
    let mut id: std::collections::HashMap<[u64; 3], usize> = std::collections::HashMap::new();
    let mut points = Vec::new();
    let mut faces = Vec::with_capacity(corners.len() / 3);
    for tri in corners.chunks_exact(3) {
        let f = [0, 1, 2].map(|c| {
            let p = tri[c];
            let key = p.map(|v| if v == 0.0 { 0 } else { v.to_bits() });
            *id.entry(key).or_insert_with(|| {
                points.extend_from_slice(&p);
                points.len() / 3 - 1
            })
        });
        faces.push(f);
    }
    Ok(RawMesh {
        points,
        faces,
        cell_data: BTreeMap::new(),
        point_data: BTreeMap::new(),
    })
}
