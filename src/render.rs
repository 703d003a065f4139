//! `shellsim render`: a frame drawn as a shaded surface coloured by a field, with a colour bar,
//! into a PNG, on the CPU (no ParaView, no GPU).
//!
//! Orthographic projection from a named view or an azimuth and elevation; a z-buffer
//! rasteriser over 2×2 supersamples (averaged into each pixel); two-sided Lambert shading
//! under a headlight, `0.35 + 0.65 |n·l|`; colours from the viridis map (its published samples
//! at steps of 0.1, interpolated linearly). A face field colours its face; a vertex field is
//! interpolated across the face. Fields of several components are drawn by their Euclidean
//! norm. Labels use a 5×7 bitmap font defined here. Written here because no maintained crate
//! rasterises 3D triangles with a depth buffer on the CPU; PNG encoding is the `png` crate's.

use crate::math::{Real, Vec3};
use crate::mesh::Mesh;
use anyhow::{anyhow, bail, Result};
use noto_sans_mono_bitmap::{
    get_raster, get_raster_width, FontWeight, RasterHeight, RasterizedChar,
};
use std::path::Path;

/// The viridis colour map at 0, 0.1, …, 1 (its published 8-bit samples).
const VIRIDIS: [[u8; 3]; 11] = [
    [68, 1, 84],
    [72, 36, 117],
    [65, 68, 135],
    [53, 95, 141],
    [42, 120, 142],
    [33, 145, 140],
    [34, 168, 132],
    [68, 191, 112],
    [122, 209, 81],
    [189, 223, 38],
    [253, 231, 37],
];

/// Viridis at `t` in [0, 1] (clamped), as linear-interpolated 8-bit RGB in floats.
fn colour(t: Real) -> [Real; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = t * 10.0;
    let i = (s.floor() as usize).min(9);
    let f = s - i as Real;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [0, 1, 2].map(|k| a[k] as Real * (1.0 - f) + b[k] as Real * f)
}

/// The largest picture side, in pixels, that `render` and `plot` draw (a render's supersampled
/// buffers at 8192 × 8192 take about 1.9 GB).
pub use crate::config::view::MAX_SIDE;

/// A buffer of `n` copies of `v`, or an error saying how much memory the picture needed
/// (never an abort on a failed allocation).
fn buffer<T: Clone>(n: usize, v: T, w: usize, h: usize) -> Result<Vec<T>> {
    let mut b = Vec::new();
    b.try_reserve_exact(n).map_err(|_| {
        anyhow!(
            "cannot allocate {} MB for a {w}×{h} picture",
            (n * std::mem::size_of::<T>()).div_ceil(1 << 20)
        )
    })?;
    b.resize(n, v);
    Ok(b)
}

/// The labels' font size for a picture `h` pixels high: Noto Sans Mono, pre-rasterised with
/// anti-aliasing (the `noto-sans-mono-bitmap` crate), 16–32 pixel rows.
pub fn font_for(h: usize) -> RasterHeight {
    match h {
        0..500 => RasterHeight::Size16,
        500..900 => RasterHeight::Size20,
        900..1400 => RasterHeight::Size24,
        _ => RasterHeight::Size32,
    }
}

/// The glyph of `c`, or of '?' for a character the font lacks.
fn glyph(c: char, size: RasterHeight) -> RasterizedChar {
    get_raster(c, FontWeight::Regular, size)
        .or_else(|| get_raster('?', FontWeight::Regular, size))
        .expect("the font has '?'")
}

/// An 8-bit RGB image, with a depth buffer when it draws triangles.
pub struct Canvas {
    /// Width and height in pixels.
    pub w: usize,
    /// See `w`.
    pub h: usize,
    /// RGB, row by row from the top.
    pub rgb: Vec<[u8; 3]>,
    depth: Vec<f32>,
}

/// A colour with components in 0–255, rounded to 8 bits.
fn to8(c: [Real; 3]) -> [u8; 3] {
    c.map(|v| v.round().clamp(0.0, 255.0) as u8)
}

impl Canvas {
    /// A white canvas without a depth buffer (an error, not an abort, when memory runs out).
    pub fn new(w: usize, h: usize) -> Result<Self> {
        Ok(Canvas {
            w,
            h,
            rgb: buffer(w * h, [255; 3], w, h)?,
            depth: Vec::new(),
        })
    }

    /// A white canvas with a depth buffer, for [`Canvas::triangle`].
    pub fn with_depth(w: usize, h: usize) -> Result<Self> {
        let mut c = Canvas::new(w, h)?;
        c.depth = buffer(w * h, f32::INFINITY, w, h)?;
        Ok(c)
    }

    /// Fills an axis-aligned rectangle (pixel bounds, clipped).
    pub fn rect(&mut self, x0: isize, y0: isize, x1: isize, y1: isize, c: [Real; 3]) {
        let c = to8(c);
        for y in y0.max(0)..y1.min(self.h as isize) {
            for x in x0.max(0)..x1.min(self.w as isize) {
                self.rgb[y as usize * self.w + x as usize] = c;
            }
        }
    }

    /// Blends `c` over pixel (x, y) with opacity `a` in 0–255 (clipped).
    fn blend(&mut self, x: isize, y: isize, a: u8, c: [Real; 3]) {
        if a == 0 || x < 0 || y < 0 || x >= self.w as isize || y >= self.h as isize {
            return;
        }
        let t = a as Real / 255.0;
        let p = &mut self.rgb[y as usize * self.w + x as usize];
        *p = to8([0, 1, 2].map(|k| p[k] as Real * (1.0 - t) + c[k] * t));
    }

    /// Draws text with the top-left corner of its line box at (x, y).
    pub fn text(&mut self, x: isize, y: isize, s: &str, size: RasterHeight, c: [Real; 3]) {
        let adv = get_raster_width(FontWeight::Regular, size) as isize;
        for (k, ch) in s.chars().enumerate() {
            let g = glyph(ch, size);
            for (r, row) in g.rows().enumerate() {
                for (col, &a) in row.iter().enumerate() {
                    self.blend(x + k as isize * adv + col as isize, y + r as isize, a, c);
                }
            }
        }
    }

    /// Draws text turned a quarter anticlockwise (read from bottom to top), the bottom-left
    /// corner of its line box at (x, y).
    pub fn text_up(&mut self, x: isize, y: isize, s: &str, size: RasterHeight, c: [Real; 3]) {
        let adv = get_raster_width(FontWeight::Regular, size) as isize;
        for (k, ch) in s.chars().enumerate() {
            let g = glyph(ch, size);
            for (r, row) in g.rows().enumerate() {
                for (col, &a) in row.iter().enumerate() {
                    self.blend(x + r as isize, y - k as isize * adv - col as isize, a, c);
                }
            }
        }
    }

    /// Width in pixels of `s` in `size`.
    pub fn text_width(s: &str, size: RasterHeight) -> isize {
        (s.chars().count() * get_raster_width(FontWeight::Regular, size)) as isize
    }

    /// Rasterises a triangle with screen positions `p` (x, y in pixels, z depth: smaller is
    /// nearer), per-corner colours `c` and normals `n`, keeping the nearest surface. Each
    /// pixel's colour is the interpolated colour times `light(n).0` plus white times
    /// `light(n).1`, `n` the interpolated normal (per-pixel lighting).
    pub fn triangle(
        &mut self,
        p: [[Real; 3]; 3],
        c: [[Real; 3]; 3],
        n: [Vec3; 3],
        light: &impl Fn(&Vec3) -> (Real, Real),
    ) {
        let area =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
        if area.abs() < 1e-12 || !area.is_finite() {
            return;
        }
        let xmin = p.iter().map(|q| q[0]).fold(Real::INFINITY, Real::min);
        let xmax = p.iter().map(|q| q[0]).fold(Real::NEG_INFINITY, Real::max);
        let ymin = p.iter().map(|q| q[1]).fold(Real::INFINITY, Real::min);
        let ymax = p.iter().map(|q| q[1]).fold(Real::NEG_INFINITY, Real::max);
        let x0 = (xmin.floor().max(0.0)) as usize;
        let x1 = (xmax.ceil().min(self.w as Real - 1.0)).max(0.0) as usize;
        let y0 = (ymin.floor().max(0.0)) as usize;
        let y1 = (ymax.ceil().min(self.h as Real - 1.0)).max(0.0) as usize;
        for y in y0..=y1 {
            let py = y as Real + 0.5;
            for x in x0..=x1 {
                let px = x as Real + 0.5;
                let w0 = ((p[1][0] - px) * (p[2][1] - py) - (p[2][0] - px) * (p[1][1] - py)) / area;
                let w1 = ((p[2][0] - px) * (p[0][1] - py) - (p[0][0] - px) * (p[2][1] - py)) / area;
                let w2 = 1.0 - w0 - w1;
                // A little slack: a sample on an edge shared by two faces is covered by one
                // of them at least, whatever the round-off.
                if w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9 {
                    continue;
                }
                let z = (w0 * p[0][2] + w1 * p[1][2] + w2 * p[2][2]) as f32;
                let i = y * self.w + x;
                if z < self.depth[i] {
                    self.depth[i] = z;
                    let (d, s) = light(&(n[0] * w0 + n[1] * w1 + n[2] * w2));
                    self.rgb[i] = to8([0, 1, 2]
                        .map(|k| (w0 * c[0][k] + w1 * c[1][k] + w2 * c[2][k]) * d + 255.0 * s));
                }
            }
        }
    }

    /// Averages `f × f` blocks into a canvas `f` times smaller.
    pub fn downsample(&self, f: usize) -> Result<Canvas> {
        let (w, h) = (self.w / f, self.h / f);
        let mut out = Canvas::new(w, h)?;
        for y in 0..h {
            for x in 0..w {
                let mut s = [0u32; 3];
                for dy in 0..f {
                    for dx in 0..f {
                        let c = self.rgb[(y * f + dy) * self.w + x * f + dx];
                        for k in 0..3 {
                            s[k] += c[k] as u32;
                        }
                    }
                }
                let n = (f * f) as u32;
                out.rgb[y * w + x] = s.map(|v| ((v + n / 2) / n) as u8);
            }
        }
        Ok(out)
    }

    /// Writes the canvas as an 8-bit RGB PNG (atomically).
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let mut bytes = Vec::new();
        {
            let mut e = png::Encoder::new(&mut bytes, self.w as u32, self.h as u32);
            e.set_color(png::ColorType::Rgb);
            e.set_depth(png::BitDepth::Eight);
            let mut w = e
                .write_header()
                .map_err(|err| anyhow!("{}: {err}", path.display()))?;
            w.write_image_data(self.rgb.as_flattened())
                .map_err(|err| anyhow!("{}: {err}", path.display()))?;
        }
        crate::mesh::io::write_atomic(path, &bytes).map_err(|e| anyhow!("{}: {e}", path.display()))
    }
}

/// Viewing direction: the unit vector from the scene toward the eye, and the screen's up.
pub fn view(spec: &str) -> Result<(Vec3, Vec3)> {
    let (az, el) = crate::config::view::angles(spec).map_err(|e| anyhow!(e))?;
    let (a, e) = (az.to_radians(), el.to_radians());
    let eye = Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin());
    // Up: the z axis projected on the screen; looking along z, the y axis.
    let up0 = if e.cos().abs() < 1e-6 {
        Vec3::new(-a.cos(), -a.sin(), 0.0) * e.sin().signum()
    } else {
        Vec3::z()
    };
    let up = (up0 - eye * eye.dot(&up0)).normalize();
    Ok((eye, up))
}

/// Per-entry values of a field (norm over components), and whether it lives on vertices.
pub fn field_values(mesh: &Mesh, name: &str) -> Result<(Vec<Real>, bool)> {
    let (f, on_vertices) = match (mesh.face_fields.get(name), mesh.vertex_fields.get(name)) {
        (Some(f), _) => (f, false),
        (None, Some(f)) => (f, true),
        (None, None) => {
            let mut names: Vec<&str> = mesh
                .face_fields
                .keys()
                .chain(mesh.vertex_fields.keys())
                .map(String::as_str)
                .collect();
            names.sort_unstable();
            bail!(
                "no field '{name}' in this frame; it has: {}",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            );
        }
    };
    let c = f.components.max(1);
    Ok((
        f.data
            .chunks(c)
            .map(|v| {
                if c == 1 {
                    v[0]
                } else {
                    v.iter().map(|x| x * x).sum::<Real>().sqrt()
                }
            })
            .collect(),
        on_vertices,
    ))
}

/// How faces are lit: by their own normal (facets show), or by normals interpolated from the
/// vertices' (angle-weighted averages of their faces' normals, kept apart across creases
/// sharper than 60°).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// Each face by its own normal.
    Flat,
    /// Vertex normals interpolated across each face.
    Smooth,
}

impl std::str::FromStr for Shading {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "flat" => Ok(Shading::Flat),
            "smooth" => Ok(Shading::Smooth),
            _ => bail!("--shading '{s}': use flat or smooth"),
        }
    }
}

/// Unit face normals, and angle-weighted vertex normals (each face's unit normal weighted by
/// its angle at the vertex).
fn normals(mesh: &Mesh) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut vn = vec![Vec3::zeros(); mesh.positions.len()];
    let fnorm = mesh
        .faces
        .iter()
        .map(|f| {
            let p = f.map(|v| mesh.positions[v]);
            let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
            let n = n.try_normalize(0.0).unwrap_or_else(Vec3::zeros);
            for k in 0..3 {
                let (u, w) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                vn[f[k]] += n * u.cross(&w).norm().atan2(u.dot(&w));
            }
            n
        })
        .collect();
    for n in &mut vn {
        *n = n.try_normalize(0.0).unwrap_or_else(Vec3::zeros);
    }
    (fnorm, vn)
}

/// Per-vertex values of a face field: the area-weighted mean over each vertex's faces.
fn face_to_vertex(mesh: &Mesh, v: &[Real]) -> Vec<Real> {
    let mut sum = vec![0.0; mesh.positions.len()];
    let mut area = vec![0.0; mesh.positions.len()];
    for (f, face) in mesh.faces.iter().enumerate() {
        let [a, b, c] = mesh.face_positions(f);
        let w = (b - a).cross(&(c - a)).norm();
        for &i in face {
            sum[i] += w * v[f];
            area[i] += w;
        }
    }
    sum.iter()
        .zip(&area)
        .map(|(s, a)| if *a > 0.0 { s / a } else { 0.0 })
        .collect()
}

/// The colour range of `values` drawn without `--range`: their finite minimum and maximum,
/// unless these differ by no more than 1e-5 of the field's scale (round-off, which a full
/// colour map would turn into a rainbow): then the mean ± 1% of that scale, so that the field
/// shows as the one colour at the middle of the map. The scale is the larger of the values'
/// magnitude and the natural scale of their unit on this mesh (`natural`: 1/L for a
/// curvature, L for a length, 1 for an angle or a dimensionless field, L the mesh's size).
pub fn colour_range(values: &[Real], natural: Real) -> (Real, Real) {
    let (lo, hi) = values
        .iter()
        .filter(|x| x.is_finite())
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let scale = lo.abs().max(hi.abs()).max(natural);
    if hi - lo > 1e-5 * scale {
        return (lo, hi);
    }
    let mid = 0.5 * (lo + hi);
    let half = if scale > 0.0 { 0.01 * scale } else { 1.0 };
    (mid - half, mid + half)
}

/// The natural scale of a field of unit `unit` on a mesh of size `l` (see [`colour_range`]).
fn natural_scale(unit: Option<&str>, l: Real) -> Real {
    match unit {
        Some("" | "rad") => 1.0,
        Some("m") => l,
        Some("1/m") => 1.0 / l,
        Some("1/m²") => 1.0 / (l * l),
        _ => 0.0,
    }
}

/// Renders `mesh` coloured by `field` (or plain grey) into a `w × h` canvas; the colours span
/// `range`, or [`colour_range`]'s.
pub fn render(
    mesh: &Mesh,
    field: Option<&str>,
    view_spec: &str,
    w: usize,
    h: usize,
    range: Option<(Real, Real)>,
    shading: Shading,
) -> Result<Canvas> {
    if !(64..=MAX_SIDE).contains(&w) || !(64..=MAX_SIDE).contains(&h) {
        bail!("--size {w}x{h}: each side must lie in 64–{MAX_SIDE} pixels");
    }
    let (eye, up) = view(view_spec)?;
    let right = up.cross(&eye);
    let values = match field {
        Some(name) => Some(field_values(mesh, name)?),
        None => None,
    };
    let proj: Vec<[Real; 3]> = mesh
        .positions
        .iter()
        .map(|p| [p.dot(&right), p.dot(&up), -p.dot(&eye)])
        .collect();
    let (mut x0, mut x1, mut y0, mut y1, mut z0, mut z1) = (
        Real::INFINITY,
        Real::NEG_INFINITY,
        Real::INFINITY,
        Real::NEG_INFINITY,
        Real::INFINITY,
        Real::NEG_INFINITY,
    );
    for q in &proj {
        x0 = x0.min(q[0]);
        x1 = x1.max(q[0]);
        y0 = y0.min(q[1]);
        y1 = y1.max(q[1]);
        z0 = z0.min(q[2]);
        z1 = z1.max(q[2]);
    }
    let size = ((x1 - x0).powi(2) + (y1 - y0).powi(2) + (z1 - z0).powi(2)).sqrt();
    let (lo, hi) = match (range, &values, field) {
        (Some(r), _, _) => r,
        (None, Some((v, _)), Some(name)) => colour_range(
            v,
            natural_scale(crate::units::unit(name), size.max(Real::MIN_POSITIVE)),
        ),
        _ => (0.0, 1.0),
    };
    let span = hi - lo;
    // Supersampled canvas; the picture takes the left 80% (with a colour bar) or all of it.
    let ss = 2;
    let (sw, sh) = (w * ss, h * ss);
    let mut cv = Canvas::with_depth(sw, sh)?;
    let plot_w = if values.is_some() { sw * 4 / 5 } else { sw };
    let margin = 0.06 * sh as Real;
    let scale = ((plot_w as Real - 2.0 * margin) / (x1 - x0).max(1e-300))
        .min((sh as Real - 2.0 * margin) / (y1 - y0).max(1e-300));
    let (cx, cy, cz) = (0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1));
    let screen = |q: &[Real; 3]| {
        [
            0.5 * plot_w as Real + (q[0] - cx) * scale,
            0.5 * sh as Real - (q[1] - cy) * scale,
            q[2] - cz,
        ]
    };
    // Two-sided lighting: ambient, a key light above and left of the eye, a headlight, and a
    // highlight of the key light.
    let key = (eye * 0.6 + up * 0.65 - right * 0.45).normalize();
    let half = (key + eye).normalize();
    let light = |n: &Vec3| -> (Real, Real) {
        let nn = n.norm();
        if nn == 0.0 {
            return (0.3, 0.0);
        }
        let n = n / nn;
        let d = 0.25 + 0.6 * n.dot(&key).abs() + 0.25 * n.dot(&eye).abs();
        (d.min(1.0), 0.2 * n.dot(&half).abs().powi(40))
    };
    let (fnorm, vnorm) = normals(mesh);
    // Smooth shading colours a face field smoothly too: each vertex takes the area-weighted
    // mean of its faces' values.
    let values = match (values, shading) {
        (Some((v, false)), Shading::Smooth) => Some((face_to_vertex(mesh, &v), true)),
        (v, _) => v,
    };
    let grey = [200.0, 200.0, 200.0];
    for (f, face) in mesh.faces.iter().enumerate() {
        let nf = fnorm[f];
        let corner_normal = |k: usize| -> Vec3 {
            let nv = vnorm[face[k]];
            // Across a crease sharper than 60°, the face keeps its own normal.
            if shading == Shading::Smooth && nv.dot(&nf) >= 0.5 {
                nv
            } else {
                nf
            }
        };
        let corner = |k: usize| -> [Real; 3] {
            match &values {
                None => grey,
                Some((v, false)) => colour((v[f] - lo) / span),
                Some((v, true)) => colour((v[face[k]] - lo) / span),
            }
        };
        cv.triangle(
            [
                screen(&proj[face[0]]),
                screen(&proj[face[1]]),
                screen(&proj[face[2]]),
            ],
            [corner(0), corner(1), corner(2)],
            [corner_normal(0), corner_normal(1), corner_normal(2)],
            &light,
        );
    }
    let mut out = cv.downsample(ss)?;
    if let (Some(name), Some(_)) = (field, &values) {
        colour_bar(&mut out, name, lo, hi);
    }
    Ok(out)
}

/// A vertical colour bar on the right fifth of the canvas: the field's name and unit above,
/// its maximum, middle and minimum beside it.
fn colour_bar(cv: &mut Canvas, name: &str, lo: Real, hi: Real) {
    let (w, h) = (cv.w as isize, cv.h as isize);
    let font = font_for(cv.h);
    let lh = font.val() as isize;
    let bx = w * 4 / 5 + w / 40;
    let bw = (w / 30).max(8);
    let (by0, by1) = (h / 8, h - h / 8);
    let black = [20.0, 20.0, 20.0];
    for y in by0..by1 {
        let t = (by1 - 1 - y) as Real / (by1 - by0 - 1).max(1) as Real;
        cv.rect(bx, y, bx + bw, y + 1, colour(t));
    }
    for (y, v) in [(by0, hi), ((by0 + by1) / 2, 0.5 * (lo + hi)), (by1 - 1, lo)] {
        cv.text(
            bx + bw + lh / 3,
            y - lh / 2,
            &number(v, (hi - lo) / 100.0),
            font,
            black,
        );
    }
    // The name and unit on one line if it fits the bar's fifth, else the unit below the name.
    let label = crate::units::label(name);
    let lines = if Canvas::text_width(&label, font) <= w / 5 - 4 {
        vec![label]
    } else {
        match crate::units::unit(name) {
            Some(u) if !u.is_empty() => vec![name.to_string(), format!("({u})")],
            _ => vec![name.to_string()],
        }
    };
    let top = (by0 - lh / 3 - lines.len() as isize * lh).max(0);
    for (k, line) in lines.iter().enumerate() {
        let tw = Canvas::text_width(line, font);
        // Centred over the bar, kept off the picture (a long name runs off the right edge).
        let tx = (bx + bw / 2 - tw / 2).min(w - tw - 2).max(w * 4 / 5);
        cv.text(tx, top + k as isize * lh, line, font, black);
    }
}

/// Colours of plotted series, in order (Okabe–Ito's colour-blind-safe palette).
const SERIES: [[Real; 3]; 7] = [
    [0.0, 114.0, 178.0],
    [213.0, 94.0, 0.0],
    [0.0, 158.0, 115.0],
    [204.0, 121.0, 167.0],
    [230.0, 159.0, 0.0],
    [86.0, 180.0, 233.0],
    [20.0, 20.0, 20.0],
];

/// "Nice" tick values covering [lo, hi]: steps of 1, 2 or 5 × 10ᵏ, about `n` of them.
pub fn ticks(lo: Real, hi: Real, n: usize) -> Vec<Real> {
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return vec![lo];
    }
    let raw = (hi - lo) / n.max(1) as Real;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as Real * step).collect()
}

/// Ticks of a logarithmic axis over [lo, hi] (both > 0): powers of ten (every k-th when there
/// are many), else 1, 2 and 5 times them, else linear ticks.
pub fn log_ticks(lo: Real, hi: Real) -> Vec<Real> {
    // Decades exist only for a positive, finite span (a zero or infinite end would make the
    // exponents overflow and the list unbounded).
    if !(lo > 0.0 && hi.is_finite() && lo <= hi) {
        return Vec::new();
    }
    let (a, b) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
    if b - a >= 1 {
        let every = ((b - a) / 8 + 1).max(1);
        return (a..=b)
            .filter(|k| (k - a) % every == 0)
            .map(|k| 10f64.powi(k))
            .collect();
    }
    let t: Vec<Real> = (a - 1..=b)
        .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
        .filter(|t| (lo..=hi).contains(t))
        .collect();
    if t.len() >= 2 {
        t
    } else {
        ticks(lo, hi, 4)
    }
}

/// A number for people, with the significant digits that resolve `step` (a tick step, or a
/// colour bar's resolution), at most 6; a zero or non-finite step means about 4. Plain
/// notation for magnitudes from 1e-3 to below 1e5, else scientific (`1.5e-7`).
pub fn number(v: Real, step: Real) -> String {
    let mag = v.abs();
    let step = if step > 0.0 && step.is_finite() {
        step
    } else {
        1e-3 * mag
    };
    if !v.is_finite() {
        return v.to_string();
    }
    if mag == 0.0 || mag < 1e-9 * step {
        return "0".into();
    }
    let e = mag.log10().floor() as i32;
    let sig = (e - step.log10().floor() as i32 + 1).clamp(1, 6);
    if (1e-3..1e5).contains(&mag) {
        let d = (sig - 1 - e).max(0) as usize;
        format!("{v:.d$}")
    } else {
        let m = (sig - 1) as usize;
        format!("{v:.m$e}")
    }
}

impl Canvas {
    /// A line `t` pixels thick from `a` to `b` (pixel coordinates).
    pub fn line(&mut self, a: [Real; 2], b: [Real; 2], t: isize, c: [Real; 3]) {
        let n = ((b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil() as usize).clamp(1, 100_000);
        for k in 0..=n {
            let s = k as Real / n as Real;
            let x = (a[0] + s * (b[0] - a[0])).round() as isize;
            let y = (a[1] + s * (b[1] - a[1])).round() as isize;
            self.rect(x - t / 2, y - t / 2, x - t / 2 + t, y - t / 2 + t, c);
        }
    }
}

/// The vertical axis's label: the series' names (unless `units_only`) and their units (from
/// [`crate::units`]).
fn y_label(series: &[(String, Vec<[Real; 2]>)], units_only: bool) -> String {
    let mut units: Vec<&str> = Vec::new();
    for (n, _) in series {
        if let Some(u) = crate::units::unit(n).filter(|u| !u.is_empty()) {
            if !units.contains(&u) {
                units.push(u);
            }
        }
    }
    let units = if units.is_empty() {
        String::new()
    } else {
        format!("({})", units.join(", "))
    };
    if units_only {
        return units;
    }
    let names: Vec<&str> = series.iter().map(|(n, _)| n.as_str()).collect();
    format!("{} {units}", names.join(", "))
        .trim_end()
        .to_string()
}

/// A line plot of `series` (name, points) against `x_name`, into a `w × h` canvas: axes with
/// nice ticks and labels with units, a legend; a logarithmic vertical axis with `log_y`.
/// Non-finite points are skipped (a gap).
pub fn plot(
    x_name: &str,
    series: &[(String, Vec<[Real; 2]>)],
    w: usize,
    h: usize,
    log_y: bool,
) -> Result<Canvas> {
    if !(200..=MAX_SIDE).contains(&w) || !(150..=MAX_SIDE).contains(&h) {
        bail!(
            "--size {w}x{h}: the width must lie in 200–{MAX_SIDE} and the height in \
             150–{MAX_SIDE} pixels"
        );
    }
    if log_y {
        for (name, p) in series {
            if let Some(q) = p
                .iter()
                .find(|q| q[0].is_finite() && q[1].is_finite() && q[1] <= 0.0)
            {
                bail!(
                    "--log-y: '{name}' is {} at {x_name} = {}: a logarithmic axis needs values \
                     above 0",
                    number(q[1], 0.0),
                    number(q[0], 0.0)
                );
            }
        }
    }
    let fy = |y: Real| if log_y { y.log10() } else { y };
    let pts = series
        .iter()
        .flat_map(|(_, p)| p.iter())
        .filter(|p| p[0].is_finite() && p[1].is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (
        Real::INFINITY,
        Real::NEG_INFINITY,
        Real::INFINITY,
        Real::NEG_INFINITY,
    );
    for p in pts {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(fy(p[1]));
        y1 = y1.max(fy(p[1]));
    }
    if !x0.is_finite() {
        bail!("nothing to plot: no finite values");
    }
    let pad = |lo: Real, hi: Real| {
        if hi > lo {
            (lo - 0.04 * (hi - lo), hi + 0.04 * (hi - lo))
        } else {
            let d = 0.5 * lo.abs().max(1e-300);
            (lo - d, hi + d)
        }
    };
    let (x0, x1) = pad(x0, x1);
    // On a log axis the plotted values are log10 y: a flat series spans a decade.
    let (y0, y1) = if log_y && y1 <= y0 {
        (y0 - 0.5, y1 + 0.5)
    } else {
        pad(y0, y1)
    };
    let mut cv = Canvas::new(w, h)?;
    let font = font_for(h);
    let lh = font.val() as isize;
    let s: isize = if h >= 600 { 2 } else { 1 };
    let black = [20.0, 20.0, 20.0];
    let light = [225.0, 225.0, 225.0];
    let step = |t: &[Real]| if t.len() > 1 { t[1] - t[0] } else { 0.0 };
    let tx = ticks(x0, x1, 6);
    let ty: Vec<Real> = if log_y {
        log_ticks(10f64.powf(y0), 10f64.powf(y1))
    } else {
        ticks(y0, y1, 6)
    };
    let ty_labels: Vec<String> = ty
        .iter()
        .map(|&t| {
            if log_y {
                number(t, t)
            } else {
                number(t, step(&ty))
            }
        })
        .collect();
    let label_w = ty_labels
        .iter()
        .map(|l| Canvas::text_width(l, font))
        .max()
        .unwrap_or(0);
    // Plot area: room for the vertical label and tick labels left, tick labels and the
    // horizontal label below, the legend above.
    let left = (lh + lh / 2 + label_w + lh / 2) as Real;
    let right = w as Real - (lh as Real).max(16.0);
    let top = (lh / 2 + series.len() as isize * (lh + 2) + lh / 2) as Real;
    let bottom = h as Real - (2 * lh + lh / 2) as Real;
    if right - left < 50.0 || bottom - top < 50.0 {
        bail!(
            "--size {w}x{h} leaves no room for the plot of {} series",
            series.len()
        );
    }
    let sx = |x: Real| left + (x - x0) / (x1 - x0) * (right - left);
    let sy = |y: Real| bottom - (fy(y) - y0) / (y1 - y0) * (bottom - top);
    for &t in &tx {
        let x = sx(t);
        cv.line([x, top], [x, bottom], 1, light);
        let l = number(t, step(&tx));
        cv.text(
            x as isize - Canvas::text_width(&l, font) / 2,
            bottom as isize + lh / 4,
            &l,
            font,
            black,
        );
    }
    for (&t, l) in ty.iter().zip(&ty_labels) {
        let y = sy(t);
        cv.line([left, y], [right, y], 1, light);
        cv.text(
            left as isize - Canvas::text_width(l, font) - lh / 4,
            y as isize - lh / 2,
            l,
            font,
            black,
        );
    }
    cv.line([left, bottom], [right, bottom], s, black);
    cv.line([left, top], [left, bottom], s, black);
    let xl = crate::units::label(x_name);
    cv.text(
        (right as isize) - Canvas::text_width(&xl, font),
        bottom as isize + lh + lh / 4,
        &xl,
        font,
        black,
    );
    // The vertical label, centred on the axis; the units alone if the names do not fit.
    let mut yl = y_label(series, false);
    if Canvas::text_width(&yl, font) > (bottom - top) as isize {
        yl = y_label(series, true);
    }
    let yw = Canvas::text_width(&yl, font);
    cv.text_up(
        lh / 4,
        ((top + bottom) / 2.0) as isize + yw / 2,
        &yl,
        font,
        black,
    );
    for (k, (name, p)) in series.iter().enumerate() {
        let c = SERIES[k % SERIES.len()];
        let mut prev: Option<[Real; 2]> = None;
        for q in p {
            if !(q[0].is_finite() && q[1].is_finite()) {
                prev = None;
                continue;
            }
            let here = [sx(q[0]), sy(q[1])];
            if let Some(a) = prev {
                cv.line(a, here, 2 * s, c);
            } else {
                cv.rect(
                    here[0] as isize - s,
                    here[1] as isize - s,
                    here[0] as isize + s,
                    here[1] as isize + s,
                    c,
                );
            }
            prev = Some(here);
        }
        let ly = lh / 2 + k as isize * (lh + 2);
        cv.rect(
            left as isize,
            ly + lh / 2 - s,
            left as isize + lh,
            ly + lh / 2 + s,
            c,
        );
        cv.text(left as isize + lh + lh / 2, ly, name, font, black);
    }
    Ok(cv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_carry_about_four_significant_digits() {
        // A colour bar's end over 0.176–0.253 (resolution span/100).
        assert_eq!(number(0.2534, (0.2534 - 0.176) / 100.0), "0.2534");
        // No step: about 4 digits.
        assert_eq!(number(0.74999923, 0.0), "0.7500");
        assert_eq!(number(1234.5678, 0.0), "1235");
        assert_eq!(number(2.5e-7, 0.0), "2.500e-7");
        // Ticks: the digits that tell them apart, at most 6.
        assert_eq!(number(0.4, 0.2), "0.4");
        assert_eq!(number(1.0, 0.5), "1.0");
        assert_eq!(number(2e-5, 2e-5), "2e-5");
        assert_eq!(number(0.74999923, 1e-9), "0.749999");
        assert_eq!(number(0.0, 0.1), "0");
        assert_eq!(number(-3.0e6, 1e6), "-3e6");
    }

    #[test]
    fn round_off_is_not_a_colour_range() {
        // Uniform to 2e-6 of its value: drawn as one colour, ±1% around it.
        let v: Vec<Real> = (0..10)
            .map(|k| 0.75 + 2e-6 * 0.75 * k as Real / 9.0)
            .collect();
        let (lo, hi) = colour_range(&v, 0.0);
        assert!((0.5 * (lo + hi) - 0.75).abs() < 1e-5 && (hi - lo - 0.015).abs() < 1e-6);
        // A flat sheet's curvature (round-off around 0, natural scale 1/L = 1).
        let (lo, hi) = colour_range(&[-1e-15, 2e-15], 1.0);
        assert!(
            (lo + 0.01).abs() < 1e-12 && (hi - 0.01).abs() < 1e-12,
            "{lo} {hi}"
        );
        // A varying field spans its minimum to maximum.
        assert_eq!(colour_range(&[0.1, 0.3, 0.2], 1.0), (0.1, 0.3));
        assert_eq!(colour_range(&[0.0; 4], 0.0), (-1.0, 1.0));
    }

    #[test]
    fn log_ticks_are_decades_or_their_multiples() {
        assert_eq!(log_ticks(0.5e-3, 2.0), vec![1e-3, 1e-2, 1e-1, 1.0]);
        assert_eq!(log_ticks(1.5, 9.0), vec![2.0, 5.0]);
        assert!(log_ticks(0.0, 1.0).is_empty() && log_ticks(1.0, Real::INFINITY).is_empty());
    }
}
