//! Reader for legacy VTK files (`# vtk DataFile Version 2.0`–`5.1`), ASCII or big-endian binary,
//! `DATASET POLYDATA` or `UNSTRUCTURED_GRID` of triangles, with CELL_DATA / POINT_DATA as FIELD
//! arrays or as SCALARS / COLOR_SCALARS / VECTORS / NORMALS / TEXTURE_COORDINATES / TENSORS.
//!
//! Written here rather than taken from a VTK crate so that every error names the line and the
//! section it is in, nothing is allocated from a count in a header before the data it announces
//! is known to be there, and no input can panic.
//!
//! Format: <https://docs.vtk.org/en/latest/design_documents/VTKFileFormats.html> (legacy part).
//! Versions up to 4.2 store cells as `n i0 … i(n−1)` runs; 5.x as `OFFSETS` and `CONNECTIVITY`
//! arrays. Binary data follows its header line as raw big-endian values.

use super::RawMesh;
use crate::math::Real;
use std::collections::BTreeMap;

/// A failure at a line of the file, in a section.
type Fail = String;

/// Whitespace-separated tokens of a byte buffer, with the line they are on (shared with the
/// ASCII PLY reader).
pub(super) struct Lexer<'a> {
    pub(super) b: &'a [u8],
    pub(super) pos: usize,
    pub(super) line: usize,
}

impl<'a> Lexer<'a> {
    fn at(&self, section: &str, what: impl std::fmt::Display) -> Fail {
        format!("line {}, {section}: {what}", self.line)
    }

    fn skip_ws(&mut self) {
        while let Some(&c) = self.b.get(self.pos) {
            if c == b'\n' {
                self.line += 1;
            } else if !c.is_ascii_whitespace() {
                break;
            }
            self.pos += 1;
        }
    }

    /// The next whitespace-separated token, or `None` at the end of the file.
    pub(super) fn token(&mut self) -> Option<&'a str> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start)
            .then(|| std::str::from_utf8(&self.b[start..self.pos]).unwrap_or("\u{fffd}"))
    }

    fn expect(&mut self, section: &str, what: &str) -> Result<&'a str, Fail> {
        self.token()
            .ok_or_else(|| self.at(section, format!("the file ends where {what} was expected")))
    }

    fn count(&mut self, section: &str, what: &str) -> Result<usize, Fail> {
        let t = self.expect(section, what)?;
        t.parse::<u64>()
            .ok()
            .and_then(|n| usize::try_from(n).ok())
            .ok_or_else(|| self.at(section, format!("{what} must be a count, found '{t}'")))
    }

    /// The rest of the current line (after a header), consumed with its newline.
    fn rest_of_line(&mut self) -> &'a [u8] {
        let start = self.pos;
        while self.pos < self.b.len() && self.b[self.pos] != b'\n' {
            self.pos += 1;
        }
        let s = &self.b[start..self.pos];
        if self.pos < self.b.len() {
            self.pos += 1;
            self.line += 1;
        }
        s
    }

    /// Peeks at the next token without consuming it.
    fn peek(&mut self) -> Option<&'a str> {
        let (p, l) = (self.pos, self.line);
        let t = self.token();
        self.pos = p;
        self.line = l;
        t
    }
}

/// Scalar types of legacy data arrays: (size in bytes, integer?).
fn data_type(name: &str) -> Option<(usize, bool)> {
    Some(match name.to_ascii_lowercase().as_str() {
        "bit" => (0, true),
        "unsigned_char" | "char" => (1, true),
        "unsigned_short" | "short" => (2, true),
        "unsigned_int" | "int" => (4, true),
        "unsigned_long" | "long" | "vtktypeint64" | "vtktypeuint64" | "vtkidtype" => (8, true),
        "float" => (4, false),
        "double" => (8, false),
        _ => return None,
    })
}

struct Reader<'a> {
    lx: Lexer<'a>,
    binary: bool,
}

impl<'a> Reader<'a> {
    /// `n` values of type `ty` (a legacy type name) as reals.
    fn values(&mut self, n: usize, ty: &str, section: &str) -> Result<Vec<Real>, Fail> {
        let (size, integer) = data_type(ty)
            .ok_or_else(|| self.lx.at(section, format!("unknown data type '{ty}'")))?;
        if !self.binary {
            // Each value takes at least two bytes ("0 "): bound the reservation by the file.
            let left = self.lx.b.len() - self.lx.pos;
            let mut out = Vec::with_capacity(n.min(left / 2 + 1));
            for i in 0..n {
                let t = self.lx.token().ok_or_else(|| {
                    self.lx.at(
                        section,
                        format!("the file ends after {i} of {n} values (truncated?)"),
                    )
                })?;
                let v = if integer {
                    t.parse::<i64>().map(|v| v as Real).ok()
                } else {
                    t.parse::<Real>().ok()
                };
                let v = v.ok_or_else(|| {
                    self.lx
                        .at(section, format!("value {i} of {n}, '{t}', is not a number"))
                })?;
                if !v.is_finite() {
                    return Err(self
                        .lx
                        .at(section, format!("value {i} of {n} is non-finite ('{t}')")));
                }
                out.push(v);
            }
            return Ok(out);
        }
        if size == 0 {
            return Err(self.lx.at(section, "binary 'bit' arrays are not supported"));
        }
        // Binary data starts after the header line.
        self.lx.rest_of_line();
        let bytes = n
            .checked_mul(size)
            .filter(|&b| b <= self.lx.b.len() - self.lx.pos);
        let Some(bytes) = bytes else {
            return Err(self.lx.at(
                section,
                format!(
                    "{n} binary values of {size} bytes do not fit in the {} bytes left (truncated?)",
                    self.lx.b.len() - self.lx.pos
                ),
            ));
        };
        let raw = &self.lx.b[self.lx.pos..self.lx.pos + bytes];
        self.lx.line += raw.iter().filter(|&&c| c == b'\n').count();
        self.lx.pos += bytes;
        let signed = !ty.to_ascii_lowercase().starts_with("unsigned") && ty != "vtktypeuint64";
        let out: Vec<Real> = raw
            .chunks_exact(size)
            .map(|c| decode_be(c, integer, signed))
            .collect();
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(self.lx.at(
                section,
                format!("binary value {i} of {n} is non-finite ({:e})", out[i]),
            ));
        }
        Ok(out)
    }

    /// `n` values that must be non-negative integers (indices, counts, offsets).
    fn indices(&mut self, n: usize, ty: &str, section: &str) -> Result<Vec<usize>, Fail> {
        let line = self.lx.line;
        let v = self.values(n, ty, section)?;
        v.iter()
            .enumerate()
            .map(|(i, &x)| {
                if x >= 0.0 && x.fract() == 0.0 && x < usize::MAX as Real {
                    Ok(x as usize)
                } else {
                    Err(format!(
                        "line {line}, {section}: value {i} is {x_h}, not an index or count",
                        x_h = crate::math::human(x)
                    ))
                }
            })
            .collect()
    }

    /// Cells after `KEYWORD a b`: returns the per-cell vertex lists.
    fn cells(&mut self, version: u32, section: &str) -> Result<Vec<Vec<usize>>, Fail> {
        let header = self.lx.line;
        let a = self.lx.count(section, "the number of cells")?;
        let b = self.lx.count(section, "the size of the cell list")?;
        if version >= 5 {
            // `a` offsets (cells + 1), `b` connectivity entries.
            let kw = self.lx.expect(section, "OFFSETS")?;
            if !kw.eq_ignore_ascii_case("OFFSETS") {
                return Err(self
                    .lx
                    .at(section, format!("expected OFFSETS, found '{kw}'")));
            }
            let ty = self.lx.expect(section, "the OFFSETS data type")?;
            let offsets = self.indices(a, ty, section)?;
            let kw = self.lx.expect(section, "CONNECTIVITY")?;
            if !kw.eq_ignore_ascii_case("CONNECTIVITY") {
                return Err(self
                    .lx
                    .at(section, format!("expected CONNECTIVITY, found '{kw}'")));
            }
            let ty = self.lx.expect(section, "the CONNECTIVITY data type")?;
            let conn = self.indices(b, ty, section)?;
            if offsets.first().is_some_and(|&o| o != 0) {
                return Err(self.lx.at(section, "the first offset must be 0"));
            }
            let mut out = Vec::with_capacity(offsets.len().saturating_sub(1));
            for (c, w) in offsets.windows(2).enumerate() {
                if w[1] < w[0] || w[1] > conn.len() {
                    return Err(self.lx.at(
                        section,
                        format!(
                            "cell {c} has offsets {}..{} outside the {} connectivity entries",
                            w[0],
                            w[1],
                            conn.len()
                        ),
                    ));
                }
                out.push(conn[w[0]..w[1]].to_vec());
            }
            if offsets.last().is_some_and(|&o| o != conn.len()) {
                return Err(self.lx.at(
                    section,
                    format!(
                        "the last offset is {} but there are {} connectivity entries",
                        offsets[offsets.len() - 1],
                        conn.len()
                    ),
                ));
            }
            return Ok(out);
        }
        let list = self.indices(b, "int", section)?;
        let mut out = Vec::with_capacity(a.min(list.len()));
        let mut i = 0;
        while i < list.len() {
            let n = list[i];
            if n > list.len() - i - 1 {
                return Err(self.lx.at(
                    section,
                    format!(
                        "cell {} announces {n} vertices but the list ends (truncated?)",
                        out.len()
                    ),
                ));
            }
            out.push(list[i + 1..i + 1 + n].to_vec());
            i += n + 1;
        }
        if out.len() != a {
            return Err(format!(
                "line {header}, {section}: the header announces {a} cells but the list holds {}",
                out.len()
            ));
        }
        Ok(out)
    }

    /// One attribute array of a CELL_DATA / POINT_DATA section (its keyword already read).
    fn attribute(
        &mut self,
        kw: &str,
        n: usize,
        section: &str,
        out: &mut BTreeMap<String, (usize, Vec<Real>)>,
    ) -> Result<(), Fail> {
        let name = self.lx.expect(section, "an array name")?.to_string();
        let where_ = format!("{section} {kw} '{name}'");
        let (comps, ty) = match kw {
            "SCALARS" => {
                let ty = self.lx.expect(&where_, "a data type")?;
                // Optional component count, then an optional LOOKUP_TABLE line.
                let mut comps = 1;
                if let Some(t) = self.lx.peek() {
                    if let Ok(c) = t.parse::<usize>() {
                        self.lx.token();
                        comps = c;
                    }
                }
                if self
                    .lx
                    .peek()
                    .is_some_and(|t| t.eq_ignore_ascii_case("LOOKUP_TABLE"))
                {
                    self.lx.token();
                    self.lx.expect(&where_, "a lookup table name")?;
                }
                (comps, ty)
            }
            "COLOR_SCALARS" => {
                let c = self.lx.count(&where_, "the number of colour components")?;
                (
                    c,
                    if self.binary {
                        "unsigned_char"
                    } else {
                        "float"
                    },
                )
            }
            "VECTORS" | "NORMALS" => (3, self.lx.expect(&where_, "a data type")?),
            "TENSORS" => (9, self.lx.expect(&where_, "a data type")?),
            "TENSORS6" => (6, self.lx.expect(&where_, "a data type")?),
            "TEXTURE_COORDINATES" => {
                let c = self.lx.count(&where_, "the texture dimension")?;
                (c, self.lx.expect(&where_, "a data type")?)
            }
            _ => unreachable!("attribute keywords are matched by the caller"),
        };
        if !(1..=64).contains(&comps) {
            return Err(self
                .lx
                .at(&where_, format!("{comps} components (1–64 are read)")));
        }
        let len = n
            .checked_mul(comps)
            .ok_or_else(|| self.lx.at(&where_, "the array size overflows"))?;
        let mut data = self.values(len, ty, &where_)?;
        if kw == "COLOR_SCALARS" && self.binary {
            data.iter_mut().for_each(|v| *v /= 255.0);
        }
        insert(out, name, comps, data, &where_, self.lx.line)
    }

    /// `FIELD name k` followed by k arrays `name comps tuples type`.
    fn field(
        &mut self,
        n: Option<usize>,
        section: &str,
        out: &mut BTreeMap<String, (usize, Vec<Real>)>,
    ) -> Result<(), Fail> {
        self.lx.expect(section, "the FIELD name")?;
        let k = self.lx.count(section, "the number of FIELD arrays")?;
        for _ in 0..k {
            let name = self.lx.expect(section, "a FIELD array name")?.to_string();
            let where_ = format!("{section} FIELD array '{name}'");
            let comps = self.lx.count(&where_, "the number of components")?;
            let tuples = self.lx.count(&where_, "the number of tuples")?;
            let ty = self.lx.expect(&where_, "a data type")?;
            let len = comps
                .checked_mul(tuples)
                .ok_or_else(|| self.lx.at(&where_, "the array size overflows"))?;
            let data = self.values(len, ty, &where_)?;
            self.skip_metadata();
            match n {
                // Dataset-level FIELD data (TIME, CYCLE, ...) is not per face or vertex.
                None => {}
                Some(n) => {
                    if tuples != n {
                        return Err(self.lx.at(
                            &where_,
                            format!("{tuples} tuples, but the section has {n} entries"),
                        ));
                    }
                    if comps == 0 {
                        return Err(self.lx.at(&where_, "0 components"));
                    }
                    insert(out, name, comps, data, &where_, self.lx.line)?;
                }
            }
        }
        Ok(())
    }

    /// VTK 5.1 writes `METADATA` blocks (INFORMATION, COMPONENT_NAMES) after arrays, ended by an
    /// empty line; they carry nothing shellsim reads.
    fn skip_metadata(&mut self) {
        if !self
            .lx
            .peek()
            .is_some_and(|t| t.eq_ignore_ascii_case("METADATA"))
        {
            return;
        }
        self.lx.token();
        self.lx.rest_of_line();
        while self.lx.pos < self.lx.b.len() {
            if self.lx.rest_of_line().trim_ascii().is_empty() {
                break;
            }
        }
    }
}

fn insert(
    out: &mut BTreeMap<String, (usize, Vec<Real>)>,
    name: String,
    comps: usize,
    data: Vec<Real>,
    where_: &str,
    line: usize,
) -> Result<(), Fail> {
    if out.contains_key(&name) {
        return Err(format!(
            "line {line}, {where_}: a second array of that name"
        ));
    }
    out.insert(name, (comps, data));
    Ok(())
}

fn decode_be(c: &[u8], integer: bool, signed: bool) -> Real {
    match (c.len(), integer, signed) {
        (1, _, true) => c[0] as i8 as Real,
        (1, _, false) => c[0] as Real,
        (2, _, true) => i16::from_be_bytes([c[0], c[1]]) as Real,
        (2, _, false) => u16::from_be_bytes([c[0], c[1]]) as Real,
        (4, false, _) => f32::from_be_bytes([c[0], c[1], c[2], c[3]]) as Real,
        (4, true, true) => i32::from_be_bytes([c[0], c[1], c[2], c[3]]) as Real,
        (4, true, false) => u32::from_be_bytes([c[0], c[1], c[2], c[3]]) as Real,
        (8, false, _) => Real::from_be_bytes(c.try_into().unwrap_or([0; 8])),
        (8, true, true) => i64::from_be_bytes(c.try_into().unwrap_or([0; 8])) as Real,
        _ => u64::from_be_bytes(c.try_into().unwrap_or([0; 8])) as Real,
    }
}

/// Parses a legacy VTK file into points, triangles and fields.
pub fn parse(bytes: &[u8]) -> Result<RawMesh, Fail> {
    let mut lx = Lexer {
        b: bytes,
        pos: 0,
        line: 1,
    };
    let first = lx.rest_of_line();
    if !first.starts_with(b"# vtk DataFile Version") {
        return Err(
            "line 1: not a legacy VTK file: the first line must be '# vtk DataFile Version x.y'"
                .into(),
        );
    }
    let vline = String::from_utf8_lossy(first);
    let version = vline
        .trim()
        .rsplit(' ')
        .next()
        .and_then(|s| s.split_once('.'))
        .and_then(|(a, b)| Some((a.parse::<u32>().ok()?, b.parse::<u32>().ok()?)));
    let major = match version {
        Some((m @ 2..=5, _)) => m,
        _ => {
            return Err(format!(
                "line 1: unsupported legacy VTK version line '{}' (2.0–5.1 are read)",
                vline.trim()
            ))
        }
    };
    lx.rest_of_line(); // title
    let enc = lx.expect("header", "ASCII or BINARY")?;
    let binary = if enc.eq_ignore_ascii_case("ASCII") {
        false
    } else if enc.eq_ignore_ascii_case("BINARY") {
        true
    } else {
        return Err(lx.at("header", format!("expected ASCII or BINARY, found '{enc}'")));
    };
    let kw = lx.expect("header", "DATASET")?;
    if !kw.eq_ignore_ascii_case("DATASET") {
        return Err(lx.at("header", format!("expected DATASET, found '{kw}'")));
    }
    let kind = lx
        .expect("DATASET", "the dataset type")?
        .to_ascii_uppercase();
    let grid = match kind.as_str() {
        "UNSTRUCTURED_GRID" => true,
        "POLYDATA" => false,
        other => {
            return Err(lx.at(
                "DATASET",
                format!("dataset must be POLYDATA or UNSTRUCTURED_GRID, found {other}"),
            ))
        }
    };
    if !binary {
        super::ends_mid_number(bytes)?;
    }
    let mut r = Reader { lx, binary };
    let mut points: Option<Vec<Real>> = None;
    let mut cells: Option<Vec<Vec<usize>>> = None;
    let mut types: Option<Vec<usize>> = None;
    let mut cell_data = BTreeMap::new();
    let mut point_data = BTreeMap::new();
    // The section attribute arrays belong to: (is cell data, entries).
    let mut section: Option<(bool, usize)> = None;
    let mut sections = Vec::new();
    while let Some(tok) = r.lx.token() {
        let kw = tok.to_ascii_uppercase();
        match kw.as_str() {
            "POINTS" => {
                let n = r.lx.count("POINTS", "the number of points")?;
                let ty = r.lx.expect("POINTS", "a data type")?;
                let len = n
                    .checked_mul(3)
                    .ok_or_else(|| r.lx.at("POINTS", "the point count overflows"))?;
                points = Some(r.values(len, ty, "POINTS")?);
                r.skip_metadata();
            }
            "POLYGONS" if !grid => cells = Some(r.cells(major, "POLYGONS")?),
            "CELLS" if grid => cells = Some(r.cells(major, "CELLS")?),
            "VERTICES" | "LINES" | "TRIANGLE_STRIPS" if !grid => {
                let c = r.cells(major, &kw)?;
                if !c.is_empty() {
                    return Err(r.lx.at(
                        &kw,
                        "POLYDATA holds vertices, lines or strips; only POLYGONS of 3 vertices are read",
                    ));
                }
            }
            "CELL_TYPES" if grid => {
                let n = r.lx.count("CELL_TYPES", "the number of cell types")?;
                types = Some(r.indices(n, "int", "CELL_TYPES")?);
            }
            "CELL_DATA" | "POINT_DATA" => {
                let n = r.lx.count(&kw, "the number of entries")?;
                let cell = kw == "CELL_DATA";
                sections.push((cell, n, r.lx.line));
                section = Some((cell, n));
            }
            "FIELD" => match section {
                None => r.field(None, "FIELD", &mut cell_data)?,
                Some((true, n)) => r.field(Some(n), "CELL_DATA", &mut cell_data)?,
                Some((false, n)) => r.field(Some(n), "POINT_DATA", &mut point_data)?,
            },
            "SCALARS"
            | "COLOR_SCALARS"
            | "VECTORS"
            | "NORMALS"
            | "TENSORS"
            | "TENSORS6"
            | "TEXTURE_COORDINATES" => {
                let Some((cell, n)) = section else {
                    return Err(r
                        .lx
                        .at(&kw, "attribute data before any CELL_DATA or POINT_DATA"));
                };
                let (name, map) = if cell {
                    ("CELL_DATA", &mut cell_data)
                } else {
                    ("POINT_DATA", &mut point_data)
                };
                r.attribute(&kw, n, name, map)?;
                r.skip_metadata();
            }
            "LOOKUP_TABLE" => {
                // A stand-alone colour table: name, size, then size × 4 values.
                r.lx.expect("LOOKUP_TABLE", "a table name")?;
                let n = r.lx.count("LOOKUP_TABLE", "the table size")?;
                let len = n
                    .checked_mul(4)
                    .ok_or_else(|| r.lx.at("LOOKUP_TABLE", "the table size overflows"))?;
                let ty = if binary { "unsigned_char" } else { "float" };
                r.values(len, ty, "LOOKUP_TABLE")?;
            }
            "METADATA" => {
                r.lx.rest_of_line();
                while r.lx.pos < r.lx.b.len() && !r.lx.rest_of_line().trim_ascii().is_empty() {}
            }
            _ => {
                return Err(r.lx.at(
                    "DATASET",
                    format!("unexpected keyword '{tok}' in a {kind} dataset"),
                ))
            }
        }
    }
    let points = points.ok_or("the file has no POINTS section")?;
    let cells = cells.ok_or(if grid {
        "the file has no CELLS section"
    } else {
        "the file has no POLYGONS section"
    })?;
    if let Some(t) = &types {
        if t.len() != cells.len() {
            return Err(format!(
                "CELL_TYPES lists {} types for {} cells",
                t.len(),
                cells.len()
            ));
        }
    } else if grid {
        return Err("the file has no CELL_TYPES section".into());
    }
    for (cell, n, line) in sections {
        let (what, have, of) = if cell {
            ("CELL_DATA", cells.len(), "cells")
        } else {
            ("POINT_DATA", points.len() / 3, "points")
        };
        if n != have {
            return Err(format!(
                "line {line}, {what}: the section has {n} entries, but there are {have} {of}"
            ));
        }
    }
    let faces = super::triangles(&cells, types.as_deref())?;
    Ok(RawMesh {
        points,
        faces,
        cell_data,
        point_data,
    })
}
