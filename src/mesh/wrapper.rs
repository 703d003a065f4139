//! A straw's paper wrapper pushed down into an accordion (`shellsim mesh wrapper`): a tube of
//! radius `R` and length `L`, flattened and folded back and forth into `N` U-turns so that it
//! is `c` times shorter than the tube (the bunching). The mesh is the bunched wrapper; its vertex
//! field `original_positions` is the straight round tube with the same connectivity, the shape
//! that `growth.law = "crease_relaxation"` relaxes toward as the paper gets wet (seed 000 §5.5:
//! the wrapper "extends much like an inching caterpillar").
//!
//! ## The map from the tube to the accordion
//! A point of the tube at arc length `x ∈ [0, L]` along it and `s ∈ [0, 2πR)` around it is
//! `(x, R cos(s/R), R sin(s/R))`. The bunched wrapper sends it to
//!
//! `P(x, s) = c(x) + Y(s) ŷ + Z(s) n(x)`,
//!
//! * `(Y(s), Z(s))`: the flattened cross-section, a stadium of the same perimeter, traversed by
//!   arc length in the same sense: two flat sheets `Z = ±r`, each `ℓ = π (R − r)` long, joined
//!   by half circles of radius `r` (the flattening creases);
//! * `c(x)`: the centre line, parametrised by arc length in the x–z plane, panels of length `p`
//!   along ±z joined by half turns of radius `ρ`, each advancing it by 2ρ along x: up, turn,
//!   down, turn, … (`N` turns, `N + 1` panels);
//! * `t = c′ = (sin ψ, 0, cos ψ)` at the angle ψ of the centre line, `n = t × ŷ =
//!   (−cos ψ, 0, sin ψ)`, so that `(t, ŷ, n)` is right-handed like `(x̂, ŷ, ẑ)` of the tube and
//!   the faces keep their orientation (outward normals in both shapes).
//!
//! With `L = (N + 1) p + N π ρ` and the bunched length `2 N ρ = L / c`:
//! `ρ = L / (2 c N)`, `p = (L − N π ρ) / (N + 1)`, and the cross-section's half gap `r = ρ/2`.
//! The narrowest radii are then `r` (the flattening creases) and `ρ − r = ρ/2` (the inner sheet
//! of a turn); neighbouring panels' facing sheets lie `2ρ − 2r = ρ` apart, and so do a panel's
//! own two sheets. Both must be at least the thickness `h` (the contact model's mesh limit:
//! folds no tighter than the thickness), hence `ρ ≥ 2h`. The map is an isometry along the
//! centre line and around the section; a turn's inner sheet is shorter and its outer one longer
//! by the factor `1 ∓ r/ρ`, the paper's crumpling, which the wrapper's stress-free crushed rest
//! state absorbs.
//!
//! ## Mesh
//! A structured grid in `(x, s)`, periodic in `s`: the flat sheets and the panels in pieces of
//! about `edge`, each flattening crease in at least 3 pieces and each turn in at least 4, cells
//! split along alternating diagonals. Faces carry `tri_tags` 1, `machine_direction` (the paper's
//! fibres, along the tube: the centre line's tangent `t`) and, with a thickness,
//! `ref_thicknesses`.

use super::{Field, Mesh};
use crate::math::{Real, Vec3};
use std::f64::consts::PI;

/// The bunched wrapper's dimensions, derived from the tube's and the bunching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wrapper {
    /// Tube radius R (m).
    pub radius: Real,
    /// Tube length L (m).
    pub length: Real,
    /// Number of half turns N of the accordion.
    pub folds: usize,
    /// Bunching c: the tube's length over the accordion's.
    pub bunching: Real,
}

impl Wrapper {
    /// The centre line's turn radius ρ = L / (2 c N) (m).
    pub fn turn_radius(&self) -> Real {
        self.length / (2.0 * self.bunching * self.folds as Real)
    }
    /// The flattened section's half gap r = ρ/2 (m).
    pub fn half_gap(&self) -> Real {
        0.5 * self.turn_radius()
    }
    /// A panel's length p = (L − N π ρ) / (N + 1) (m).
    pub fn panel(&self) -> Real {
        (self.length - self.folds as Real * PI * self.turn_radius()) / (self.folds as Real + 1.0)
    }
    /// A flat sheet's width ℓ = π (R − r) (m).
    pub fn flat(&self) -> Real {
        PI * (self.radius - self.half_gap())
    }

    /// Checks that the accordion exists and that its folds are no tighter than the thickness
    /// `h`; the message names the flags to change.
    pub fn check(&self, h: Real) -> Result<(), String> {
        let human = crate::math::human;
        if self.folds == 0 {
            return Err("--folds must be at least 1".into());
        }
        if !(self.bunching.is_finite() && self.bunching > PI / 2.0) {
            return Err(format!(
                "--bunching ({}) must exceed π/2: half turns alone are already π/2 times \
                 shorter than the tube",
                human(self.bunching)
            ));
        }
        let rho = self.turn_radius();
        if rho < 2.0 * h {
            return Err(format!(
                "the accordion's turns (radius ρ = L/(2 c N) = {}) must have radius at least \
                 twice the thickness ({}) so that no fold is tighter than the thickness: \
                 lower --bunching or --folds, or lengthen --lx",
                human(rho),
                human(h)
            ));
        }
        if self.panel() < 2.0 * rho {
            return Err(format!(
                "the accordion's panels ({}) would be shorter than its turns' diameter ({}): \
                 raise --bunching or lower --folds",
                human(self.panel()),
                human(2.0 * rho)
            ));
        }
        if self.radius <= 2.0 * self.half_gap() {
            return Err(format!(
                "--radius ({}) must exceed the flattened section's gap ({}): the tube is too \
                 narrow to flatten; lower --bunching or --folds",
                human(self.radius),
                human(2.0 * self.half_gap())
            ));
        }
        Ok(())
    }

    /// How many pieces of about `edge` each part is cut into, in floating point (planned before
    /// anything is allocated): a flat sheet (at least 2), a crease (at least 3), a panel (at
    /// least 2) and a turn (at least 4).
    fn pieces(&self, edge: Real) -> Pieces {
        let rho = self.turn_radius();
        Pieces {
            flat: (self.flat() / edge).round().max(2.0),
            crease: (PI * self.half_gap() / edge).ceil().max(3.0),
            panel: (self.panel() / edge).round().max(2.0),
            turn: (PI * rho / edge).ceil().max(4.0),
        }
    }

    /// The cuts of the section by arc length, `(s, Y, Z)`, open at 2πR: bottom sheet, crease,
    /// top sheet, crease. `edge` sets the pieces.
    fn section(&self, edge: Real) -> Vec<(Real, Real, Real)> {
        let (r, l) = (self.half_gap(), self.flat());
        let pieces = self.pieces(edge);
        let (nf, nc) = (pieces.flat as usize, pieces.crease as usize);
        let mut cuts = Vec::with_capacity(2 * (nf + nc));
        // Counter-clockwise in (Y, Z), as (y, z) = R (cos θ, sin θ) on the tube: from the
        // bottom sheet's end at Y = −ℓ/2 along +Y, the crease at +Y up, then (`side` = −1, the
        // same cuts mirrored) the top sheet back along −Y and the crease at −Y down.
        let mut s = 0.0;
        for side in [1.0, -1.0] {
            for k in 0..nf {
                cuts.push((s, side * (-0.5 * l + l * k as Real / nf as Real), -side * r));
                s += l / nf as Real;
            }
            for k in 0..nc {
                let a = -0.5 * PI * side + PI * k as Real / nc as Real;
                cuts.push((s, side * 0.5 * l + r * a.cos(), r * a.sin()));
                s += PI * r / nc as Real;
            }
        }
        cuts
    }

    /// The cuts of the centre line by arc length, `(x, c(x), ψ)`, from 0 to L inclusive.
    fn centre_line(&self, edge: Real) -> Vec<(Real, [Real; 2], Real)> {
        let (rho, p) = (self.turn_radius(), self.panel());
        let pieces = self.pieces(edge);
        let (np, nt) = (pieces.panel as usize, pieces.turn as usize);
        let mut cuts = Vec::new();
        // (x, z) of the centre line and its angle ψ (0 = up along +z).
        let (mut x, mut at, mut psi) = (0.0, [0.0, 0.0], 0.0_f64);
        for k in 0..=self.folds {
            let up = k % 2 == 0;
            let dir = if up { 1.0 } else { -1.0 };
            for j in 0..np {
                let u = p * j as Real / np as Real;
                cuts.push((x + u, [at[0], at[1] + dir * u], psi));
            }
            x += p;
            at[1] += dir * p;
            if k == self.folds {
                cuts.push((x, at, psi));
                break;
            }
            // The turn: ψ goes from 0 to π (top, σ = +1) or from π to 0 (bottom, σ = −1) with
            // c = centre + σ ρ n(ψ), n(ψ) = (−cos ψ, sin ψ) in (x, z).
            let sigma = dir;
            let n = |a: Real| [-a.cos(), a.sin()];
            let n0 = n(psi);
            let centre = [at[0] - sigma * rho * n0[0], at[1] - sigma * rho * n0[1]];
            for j in 0..nt {
                let a = psi + sigma * PI * j as Real / nt as Real;
                let na = n(a);
                cuts.push((
                    x + PI * rho * j as Real / nt as Real,
                    [
                        centre[0] + sigma * rho * na[0],
                        centre[1] + sigma * rho * na[1],
                    ],
                    a,
                ));
            }
            x += PI * rho;
            psi += sigma * PI;
            let na = n(psi);
            at = [
                centre[0] + sigma * rho * na[0],
                centre[1] + sigma * rho * na[1],
            ];
        }
        cuts
    }

    /// The number of faces [`wrapper`] makes with pieces of about `edge`, in floating point
    /// (for planning; a wrapper that fails [`Wrapper::check`] gives an estimate).
    pub fn planned_faces(&self, edge: Real) -> Real {
        let n = self.pieces(edge);
        let folds = self.folds as Real;
        let around = 2.0 * (n.flat + n.crease);
        let along = (folds + 1.0) * n.panel + folds * n.turn;
        2.0 * around * along
    }
}

/// The pieces of each part of a wrapper ([`Wrapper::pieces`]).
struct Pieces {
    flat: Real,
    crease: Real,
    panel: Real,
    turn: Real,
}

/// The bunched wrapper `w` with pieces of about `edge` (m) and, when given, `ref_thicknesses`
/// `thickness`; see the module doc. `w` must pass [`Wrapper::check`].
pub fn wrapper(w: Wrapper, edge: Real, thickness: Option<Real>) -> Mesh {
    let section = w.section(edge);
    let line = w.centre_line(edge);
    let ns = section.len();
    let mut positions = Vec::with_capacity(line.len() * ns);
    let mut original = Vec::with_capacity(3 * line.len() * ns);
    for &(x, c, psi) in &line {
        let n = [-psi.cos(), psi.sin()];
        for &(s, y, z) in &section {
            positions.push(Vec3::new(c[0] + z * n[0], y, c[1] + z * n[1]));
            // The tube: the bottom sheet's middle (s = ℓ/2) at the bottom, θ = −π/2, and θ
            // growing with s, counter-clockwise in (y, z) as the section is.
            let a = -0.5 * PI + (s - 0.5 * w.flat()) / w.radius;
            original.extend_from_slice(&[x, w.radius * a.cos(), w.radius * a.sin()]);
        }
    }
    let id = |i: usize, j: usize| i * ns + (j % ns);
    let mut faces = Vec::with_capacity(2 * (line.len() - 1) * ns);
    let mut direction = Vec::with_capacity(6 * (line.len() - 1) * ns);
    for i in 0..line.len() - 1 {
        // The paper's machine direction, along the tube: the centre line's tangent.
        let psi = 0.5 * (line[i].2 + line[i + 1].2);
        for _ in 0..2 * ns {
            direction.extend_from_slice(&[psi.sin(), 0.0, psi.cos()]);
        }
        for j in 0..ns {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            // x̂ × θ̂ = −r̂ on the tube: (a, d, c) turns counter-clockwise seen from outside.
            if (i + j) % 2 == 0 {
                faces.push([a, c, b]);
                faces.push([a, d, c]);
            } else {
                faces.push([a, d, b]);
                faces.push([b, d, c]);
            }
        }
    }
    let mut mesh = Mesh {
        positions,
        faces,
        ..Default::default()
    };
    let nf = mesh.faces.len();
    mesh.face_fields
        .insert("tri_tags".into(), Field::scalar(vec![1.0; nf]));
    if let Some(h) = thickness {
        mesh.face_fields
            .insert("ref_thicknesses".into(), Field::scalar(vec![h; nf]));
    }
    mesh.face_fields.insert(
        "machine_direction".into(),
        Field {
            components: 3,
            data: direction,
        },
    );
    mesh.vertex_fields.insert(
        "original_positions".into(),
        Field {
            components: 3,
            data: original,
        },
    );
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: Wrapper = Wrapper {
        radius: 0.0025,
        length: 0.012,
        folds: 3,
        bunching: 6.0,
    };

    fn original(m: &Mesh) -> Vec<Vec3> {
        let f = &m.vertex_fields["original_positions"];
        (0..m.positions.len())
            .map(|v| Vec3::from_column_slice(f.get(v)))
            .collect()
    }

    #[test]
    fn the_stored_tube_is_round_straight_and_outward() {
        let m = wrapper(W, 4e-4, Some(5e-5));
        let o = original(&m);
        for p in &o {
            assert!((p.y.hypot(p.z) - W.radius).abs() < 1e-15);
            assert!((-1e-15..=W.length + 1e-15).contains(&p.x));
        }
        // Every face's normal points away from the axis in the tube, and the faces tile it:
        // their area is the prism's, L times the perimeter of the section's polygon.
        let mut area = 0.0;
        for f in &m.faces {
            let [a, b, c] = f.map(|v| o[v]);
            let n = (b - a).cross(&(c - a));
            let mid = (a + b + c) / 3.0;
            assert!(n.dot(&Vec3::new(0.0, mid.y, mid.z)) > 0.0);
            area += 0.5 * n.norm();
        }
        let ns = W.section(4e-4).len();
        let polygon = W.length
            * (0..ns)
                .map(|j| (o[(j + 1) % ns] - o[j]).norm())
                .sum::<Real>();
        assert!((area / polygon - 1.0).abs() < 1e-12, "{area} {polygon}");
        assert_eq!(m.face_fields["ref_thicknesses"].data[0], 5e-5);
    }

    #[test]
    fn the_accordion_keeps_lengths_along_its_centre_line_and_is_c_times_shorter() {
        let m = wrapper(W, 4e-4, None);
        let o = original(&m);
        let ns = W.section(4e-4).len();
        let rows = m.positions.len() / ns;
        // Along the centre line (the mean of each ring) the accordion is an isometry of the
        // tube's axis up to the chords of its turns; around each ring, of the section.
        let centre = |i: usize| m.positions[i * ns..(i + 1) * ns].iter().sum::<Vec3>() / ns as Real;
        let mut arc = 0.0;
        for i in 0..rows - 1 {
            let chord = (centre(i + 1) - centre(i)).norm();
            let along = o[(i + 1) * ns].x - o[i * ns].x;
            assert!(
                chord <= along * (1.0 + 1e-12) && chord > 0.95 * along,
                "{chord} {along}"
            );
            arc += chord;
        }
        assert!((arc / W.length - 1.0).abs() < 0.01, "{arc}");
        let perimeter: Real = (0..ns)
            .map(|j| (m.positions[(j + 1) % ns] - m.positions[j]).norm())
            .sum();
        let polygon: Real = (0..ns).map(|j| (o[(j + 1) % ns] - o[j]).norm()).sum();
        assert!(
            (perimeter / polygon - 1.0).abs() < 0.02,
            "{perimeter} {polygon}"
        );
        // The centre line's ends lie 2Nρ apart along x: c times shorter than the tube.
        let ends = centre(rows - 1) - centre(0);
        assert!((ends.x - W.length / W.bunching).abs() < 1e-12, "{ends}");
        // The faces keep their orientation: each face's normal agrees with the map of the
        // tube's outward normal (the same neighbours in the same order).
        let mut flipped = 0;
        for f in &m.faces {
            let [a, b, c] = f.map(|v| m.positions[v]);
            let [oa, ob, oc] = f.map(|v| o[v]);
            let n = (b - a).cross(&(c - a));
            let n0 = (ob - oa).cross(&(oc - oa));
            // A face's normal in the accordion is its tube normal carried by the rotation of
            // the frame (t, ŷ, n) from (x̂, ŷ, ẑ): compare through the section's outward side,
            // the face's centroid minus its ring's centre.
            let mid = (a + b + c) / 3.0;
            let i = f[0] / ns;
            let out = mid - centre(i);
            if n.dot(&out) <= 0.0 || n0.dot(&Vec3::new(0.0, oa.y, oa.z)) <= 0.0 {
                flipped += 1;
            }
        }
        assert_eq!(flipped, 0);
    }

    #[test]
    fn folds_tighter_than_the_thickness_are_refused() {
        assert!(W.check(5e-5).is_ok());
        let rho = W.turn_radius();
        let e = W.check(0.51 * rho).unwrap_err();
        assert!(
            e.contains("twice the thickness") && e.contains("--bunching"),
            "{e}"
        );
        let e = Wrapper { bunching: 1.5, ..W }.check(1e-6).unwrap_err();
        assert!(e.contains("π/2"), "{e}");
        let e = Wrapper { folds: 0, ..W }.check(1e-6).unwrap_err();
        assert!(e.contains("--folds"), "{e}");
        let e = Wrapper {
            bunching: 2.0,
            folds: 1,
            ..W
        }
        .check(1e-6)
        .unwrap_err();
        assert!(e.contains("panels"), "{e}");
        let e = Wrapper { radius: 1e-4, ..W }.check(1e-6).unwrap_err();
        assert!(e.contains("--radius"), "{e}");
    }
}
