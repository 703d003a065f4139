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

/// A 5×7 glyph: 7 rows, top first, bit 4 the leftmost column.
fn glyph(c: char) -> [u8; 7] {
    match c.to_ascii_lowercase() {
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        'a' => [0, 0, 14, 1, 15, 17, 15],
        'b' => [16, 16, 30, 17, 17, 17, 30],
        'c' => [0, 0, 14, 16, 16, 17, 14],
        'd' => [1, 1, 15, 17, 17, 17, 15],
        'e' => [0, 0, 14, 17, 31, 16, 14],
        'f' => [6, 9, 8, 28, 8, 8, 8],
        'g' => [0, 0, 15, 17, 15, 1, 14],
        'h' => [16, 16, 22, 25, 17, 17, 17],
        'i' => [4, 0, 12, 4, 4, 4, 14],
        'j' => [2, 0, 6, 2, 2, 18, 12],
        'k' => [16, 16, 18, 20, 24, 20, 18],
        'l' => [12, 4, 4, 4, 4, 4, 14],
        'm' => [0, 0, 26, 21, 21, 17, 17],
        'n' => [0, 0, 22, 25, 17, 17, 17],
        'o' => [0, 0, 14, 17, 17, 17, 14],
        'p' => [0, 0, 30, 17, 30, 16, 16],
        'q' => [0, 0, 13, 19, 15, 1, 1],
        'r' => [0, 0, 22, 25, 16, 16, 16],
        's' => [0, 0, 14, 16, 14, 1, 30],
        't' => [8, 8, 28, 8, 8, 9, 6],
        'u' => [0, 0, 17, 17, 17, 19, 13],
        'v' => [0, 0, 17, 17, 17, 10, 4],
        'w' => [0, 0, 17, 17, 21, 21, 10],
        'x' => [0, 0, 17, 10, 4, 10, 17],
        'y' => [0, 0, 17, 17, 15, 1, 14],
        'z' => [0, 0, 31, 2, 4, 8, 31],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        '-' => [0, 0, 0, 31, 0, 0, 0],
        '+' => [0, 4, 4, 31, 4, 4, 0],
        '_' => [0, 0, 0, 0, 0, 0, 31],
        '/' => [1, 2, 2, 4, 8, 8, 16],
        '(' => [2, 4, 8, 8, 8, 4, 2],
        ')' => [8, 4, 2, 2, 2, 4, 8],
        ':' => [0, 12, 12, 0, 12, 12, 0],
        ',' => [0, 0, 0, 0, 12, 4, 8],
        '=' => [0, 0, 31, 0, 31, 0, 0],
        ' ' => [0; 7],
        _ => [14, 17, 1, 2, 4, 0, 4],
    }
}

/// An RGB image with a depth buffer.
pub struct Canvas {
    /// Width and height in pixels.
    pub w: usize,
    /// See `w`.
    pub h: usize,
    /// RGB, row by row from the top.
    pub rgb: Vec<[Real; 3]>,
    depth: Vec<Real>,
}

impl Canvas {
    /// A white canvas.
    pub fn new(w: usize, h: usize) -> Self {
        Canvas {
            w,
            h,
            rgb: vec![[255.0; 3]; w * h],
            depth: vec![Real::INFINITY; w * h],
        }
    }

    /// Fills an axis-aligned rectangle (pixel bounds, clipped).
    pub fn rect(&mut self, x0: isize, y0: isize, x1: isize, y1: isize, c: [Real; 3]) {
        for y in y0.max(0)..y1.min(self.h as isize) {
            for x in x0.max(0)..x1.min(self.w as isize) {
                self.rgb[y as usize * self.w + x as usize] = c;
            }
        }
    }

    /// Draws text with its top-left corner at (x, y), `scale` pixels per font pixel.
    pub fn text(&mut self, x: isize, y: isize, s: &str, scale: isize, c: [Real; 3]) {
        for (k, ch) in s.chars().enumerate() {
            let g = glyph(ch);
            let ox = x + k as isize * 6 * scale;
            for (r, row) in g.iter().enumerate() {
                for col in 0..5 {
                    if row & (16 >> col) != 0 {
                        let px = ox + col * scale;
                        let py = y + r as isize * scale;
                        self.rect(px, py, px + scale, py + scale, c);
                    }
                }
            }
        }
    }

    /// Width in pixels of `s` at `scale`.
    pub fn text_width(s: &str, scale: isize) -> isize {
        (s.chars().count() as isize * 6 - 1).max(0) * scale
    }

    /// Rasterises a triangle with screen positions `p` (x, y in pixels, z depth: smaller is
    /// nearer) and per-corner colours, keeping the nearest surface.
    pub fn triangle(&mut self, p: [[Real; 3]; 3], c: [[Real; 3]; 3]) {
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
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * p[0][2] + w1 * p[1][2] + w2 * p[2][2];
                let i = y * self.w + x;
                if z < self.depth[i] {
                    self.depth[i] = z;
                    self.rgb[i] = [0, 1, 2].map(|k| w0 * c[0][k] + w1 * c[1][k] + w2 * c[2][k]);
                }
            }
        }
    }

    /// Averages `f × f` blocks into a canvas `f` times smaller.
    pub fn downsample(&self, f: usize) -> Canvas {
        let (w, h) = (self.w / f, self.h / f);
        let mut out = Canvas::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let mut s = [0.0; 3];
                for dy in 0..f {
                    for dx in 0..f {
                        let c = self.rgb[(y * f + dy) * self.w + x * f + dx];
                        for k in 0..3 {
                            s[k] += c[k];
                        }
                    }
                }
                out.rgb[y * w + x] = s.map(|v| v / (f * f) as Real);
            }
        }
        out
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
            let data: Vec<u8> = self
                .rgb
                .iter()
                .flat_map(|c| c.map(|v| v.round().clamp(0.0, 255.0) as u8))
                .collect();
            w.write_image_data(&data)
                .map_err(|err| anyhow!("{}: {err}", path.display()))?;
        }
        crate::mesh::io::write_atomic(path, &bytes).map_err(|e| anyhow!("{}: {e}", path.display()))
    }
}

/// Viewing direction: the unit vector from the scene toward the eye, and the screen's up.
pub fn view(spec: &str) -> Result<(Vec3, Vec3)> {
    let (az, el): (Real, Real) = match spec {
        "iso" => (-50.0, 30.0),
        "top" => (-90.0, 90.0),
        "bottom" => (-90.0, -90.0),
        "front" => (-90.0, 0.0),
        "back" => (90.0, 0.0),
        "side" => (0.0, 0.0),
        other => {
            let (a, e) = other.split_once(',').ok_or_else(|| {
                anyhow!(
                    "--view '{other}': use iso, top, bottom, front, back, side, or \
                     AZIMUTH,ELEVATION in degrees (e.g. 30,20)"
                )
            })?;
            let a: Real = a
                .trim()
                .parse()
                .map_err(|_| anyhow!("--view '{other}': azimuth '{a}' is not a number"))?;
            let e: Real = e
                .trim()
                .parse()
                .map_err(|_| anyhow!("--view '{other}': elevation '{e}' is not a number"))?;
            if !(a.is_finite() && (-90.0..=90.0).contains(&e)) {
                bail!("--view '{other}': the elevation must lie in [-90, 90] degrees");
            }
            (a, e)
        }
    };
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

/// Renders `mesh` coloured by `field` (or plain grey) into a `w × h` canvas; the colours span
/// `range`, or the field's minimum to maximum.
pub fn render(
    mesh: &Mesh,
    field: Option<&str>,
    view_spec: &str,
    w: usize,
    h: usize,
    range: Option<(Real, Real)>,
) -> Result<Canvas> {
    if w < 64 || h < 64 || w > 16384 || h > 16384 {
        bail!("--size {w}x{h}: each side must lie in 64–16384 pixels");
    }
    let (eye, up) = view(view_spec)?;
    let right = up.cross(&eye);
    let values = match field {
        Some(name) => Some(field_values(mesh, name)?),
        None => None,
    };
    let (lo, hi) = values.as_ref().map_or((0.0, 0.0), |(v, _)| {
        v.iter()
            .filter(|x| x.is_finite())
            .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            })
    });
    let (lo, hi) = match range {
        Some(r) => r,
        None if lo.is_finite() => (lo, hi),
        None => (0.0, 0.0),
    };
    let span = if hi > lo { hi - lo } else { 1.0 };
    // Supersampled canvas; the picture takes the left 80% (with a colour bar) or all of it.
    let ss = 2;
    let (sw, sh) = (w * ss, h * ss);
    let mut cv = Canvas::new(sw, sh);
    let plot_w = if values.is_some() { sw * 4 / 5 } else { sw };
    let proj: Vec<[Real; 3]> = mesh
        .positions
        .iter()
        .map(|p| [p.dot(&right), p.dot(&up), -p.dot(&eye)])
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (
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
    }
    let margin = 0.06 * sh as Real;
    let scale = ((plot_w as Real - 2.0 * margin) / (x1 - x0).max(1e-300))
        .min((sh as Real - 2.0 * margin) / (y1 - y0).max(1e-300));
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let screen = |q: &[Real; 3]| {
        [
            0.5 * plot_w as Real + (q[0] - cx) * scale,
            0.5 * sh as Real - (q[1] - cy) * scale,
            q[2],
        ]
    };
    // A headlight a little above and left of the eye.
    let light = (eye + up * 0.35 - right * 0.25).normalize();
    let grey = [200.0, 200.0, 200.0];
    for (f, face) in mesh.faces.iter().enumerate() {
        let [a, b, c] = face.map(|v| mesh.positions[v]);
        let n = (b - a).cross(&(c - a));
        let nn = n.norm();
        let shade = if nn > 0.0 {
            0.35 + 0.65 * (n / nn).dot(&light).abs()
        } else {
            0.35
        };
        let corner = |k: usize| -> [Real; 3] {
            let base = match &values {
                None => grey,
                Some((v, false)) => colour((v[f] - lo) / span),
                Some((v, true)) => colour((v[face[k]] - lo) / span),
            };
            base.map(|x| x * shade)
        };
        cv.triangle(
            [
                screen(&proj[face[0]]),
                screen(&proj[face[1]]),
                screen(&proj[face[2]]),
            ],
            [corner(0), corner(1), corner(2)],
        );
    }
    let mut out = cv.downsample(ss);
    if let (Some(name), Some(_)) = (field, &values) {
        colour_bar(&mut out, name, lo, hi);
    }
    Ok(out)
}

/// A vertical colour bar on the right fifth of the canvas: the field's name above, its
/// maximum, middle and minimum beside it.
fn colour_bar(cv: &mut Canvas, name: &str, lo: Real, hi: Real) {
    let (w, h) = (cv.w as isize, cv.h as isize);
    let s = if h >= 600 { 2 } else { 1 };
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
            bx + bw + 5 * s,
            y - 3 * s,
            &number(v, (hi - lo) / 20.0),
            s,
            black,
        );
    }
    let tw = Canvas::text_width(name, s);
    // Centred over the bar, kept off the picture (a long name runs off the right edge).
    let tx = (bx + bw / 2 - tw / 2).min(w - tw - 2).max(w * 4 / 5);
    cv.text(tx, by0 - 14 * s, name, s, black);
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

/// A number with the digits that resolve `step` (a tick step, or a colour bar's resolution):
/// fixed decimals for steps from 1e-6 and values below 1e5, else scientific notation with the
/// mantissa digits that `step` needs. A zero or non-finite step means 1e-3 of the value.
pub fn number(v: Real, step: Real) -> String {
    let step = if step > 0.0 && step.is_finite() {
        step
    } else if v != 0.0 {
        1e-3 * v.abs()
    } else {
        1.0
    };
    if v.abs() < 1e-9 * step {
        return "0".into();
    }
    let decimals = -step.log10().floor();
    if decimals <= 6.0 && v.abs() < 1e5 {
        let d = decimals.max(0.0) as usize;
        format!("{v:.d$}")
    } else {
        let m = (v.abs().log10().floor() + decimals).clamp(1.0, 12.0) as usize;
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

/// A line plot of `series` (name, points) against `x_name`, into a `w × h` canvas: axes with
/// nice ticks, a legend. Non-finite points are skipped (a gap).
pub fn plot(
    x_name: &str,
    series: &[(String, Vec<[Real; 2]>)],
    w: usize,
    h: usize,
) -> Result<Canvas> {
    if w < 200 || h < 150 || w > 16384 || h > 16384 {
        bail!("--size {w}x{h}: the width must lie in 200–16384 and the height in 150–16384 pixels");
    }
    let mut cv = Canvas::new(w, h);
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
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
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
    let (y0, y1) = pad(y0, y1);
    let s: isize = if h >= 600 { 2 } else { 1 };
    let black = [20.0, 20.0, 20.0];
    let light = [225.0, 225.0, 225.0];
    // Plot area: room for tick labels left and below, the legend above.
    let left = (12 * 6 * s + 12) as Real;
    let right = w as Real - 16.0;
    let top = (10 * s + 12) as Real + (series.len() as Real * 10.0 * s as Real);
    let bottom = h as Real - (24 * s) as Real;
    if right - left < 50.0 || bottom - top < 50.0 {
        bail!(
            "--size {w}x{h} leaves no room for the plot of {} series",
            series.len()
        );
    }
    let sx = |x: Real| left + (x - x0) / (x1 - x0) * (right - left);
    let sy = |y: Real| bottom - (y - y0) / (y1 - y0) * (bottom - top);
    let step = |t: &[Real]| if t.len() > 1 { t[1] - t[0] } else { 1.0 };
    let tx = ticks(x0, x1, 6);
    for &t in &tx {
        let x = sx(t);
        cv.line([x, top], [x, bottom], 1, light);
        let l = number(t, step(&tx));
        cv.text(
            x as isize - Canvas::text_width(&l, s) / 2,
            bottom as isize + 4 * s,
            &l,
            s,
            black,
        );
    }
    let ty = ticks(y0, y1, 6);
    for &t in &ty {
        let y = sy(t);
        cv.line([left, y], [right, y], 1, light);
        let l = number(t, step(&ty));
        cv.text(
            left as isize - Canvas::text_width(&l, s) - 4 * s,
            y as isize - 3 * s,
            &l,
            s,
            black,
        );
    }
    cv.line([left, bottom], [right, bottom], s, black);
    cv.line([left, top], [left, bottom], s, black);
    let xl = Canvas::text_width(x_name, s);
    cv.text(
        (right as isize) - xl,
        bottom as isize + 14 * s,
        x_name,
        s,
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
        let ly = 6 * s + k as isize * 10 * s;
        cv.rect(
            left as isize,
            ly + 2 * s,
            left as isize + 14 * s,
            ly + 4 * s,
            c,
        );
        cv.text(left as isize + 18 * s, ly, name, s, black);
    }
    Ok(cv)
}
