//! The time and force scales of a body's explicit dynamics (MorphoShell's, used by the explicit
//! driver and by the terms that scale themselves with it, such as the glass slides): from the
//! density ρ, the smallest shear modulus μ and thickness t, the smallest altitude a_min of the
//! reference triangles and the sample length L, the reference perimeter of the largest sheet
//! (connected piece of the mesh; π times its bounding-box diagonal for a closed one: a scene of
//! several sheets takes the time scales of its largest, not of their perimeters together),
//!
//! * the time step at prefactor 1: `min(0.185 √(ρ/μ) a_min, √(ρ t / D) a_min² / (2π))`, with
//!   the flexural rigidity `D = μ t³ / (6(1 − ν))`;
//! * the angular frequency of the longest bending mode `ω_L = √(D/(ρt)) (2π/L)²`;
//! * the long time `max(2π/ω_L, L √(ρ/μ))`.
//!
//! Units: s, rad/s, m, Pa, kg/m³, N·m.

use crate::body::Body;
use crate::math::Real;
use std::f64::consts::PI;

/// The time and force scales of a scene's explicit dynamics (module doc).
#[derive(Clone, Copy, Debug)]
pub struct Scales {
    /// Density ρ (kg/m³).
    pub rho: Real,
    /// Smallest shear modulus μ (Pa).
    pub mu: Real,
    /// Smallest thickness t (m).
    pub t: Real,
    /// Flexural rigidity `μ t³ / (6(1 − ν))` (N·m).
    pub flexural: Real,
    /// Smallest altitude of the reference triangles (m).
    pub a_min: Real,
    /// The sample length L: the largest sheet's reference perimeter (m; module doc).
    pub length: Real,
    /// The time step at prefactor 1 (s).
    pub dt_unit: Real,
    /// Angular frequency of the longest bending mode, `√(D/(ρt)) (2π/L)²` (rad/s).
    pub omega_long: Real,
    /// The long time `max(2π/ω_L, L √(ρ/μ))` (s).
    pub long_time: Real,
}

/// The largest over the mesh's connected pieces of the reference perimeter, or of π times the
/// bounding-box diagonal of a closed piece (m).
fn sample_length(body: &Body) -> Real {
    let (mesh, topo) = (&body.mesh, &body.topo);
    let (piece, count) = topo.face_pieces();
    let mut perimeter = vec![0.0; count];
    for (e, ef) in topo.edges.iter().zip(&topo.edge_faces) {
        if ef[1] == crate::mesh::topology::NONE {
            perimeter[piece[ef[0]]] += (mesh.positions[e[1]] - mesh.positions[e[0]]).norm();
        }
    }
    let mut lo = vec![crate::math::Vec3::repeat(Real::INFINITY); count];
    let mut hi = vec![crate::math::Vec3::repeat(Real::NEG_INFINITY); count];
    for (f, vs) in mesh.faces.iter().enumerate() {
        for &v in vs {
            lo[piece[f]] = lo[piece[f]].inf(&mesh.positions[v]);
            hi[piece[f]] = hi[piece[f]].sup(&mesh.positions[v]);
        }
    }
    (0..count)
        .map(|k| {
            if perimeter[k] > 0.0 {
                perimeter[k]
            } else {
                PI * (hi[k] - lo[k]).norm()
            }
        })
        .fold(0.0, Real::max)
}

impl Scales {
    /// The scales of `body`.
    pub fn of(body: &Body) -> Scales {
        let rho = body.density;
        let mu = body
            .lame
            .iter()
            .map(|l| l.beta)
            .fold(Real::INFINITY, Real::min);
        let t = body
            .thickness
            .iter()
            .copied()
            .fold(Real::INFINITY, Real::min);
        let flexural = mu * t * t * t / (6.0 * (1.0 - body.poisson));
        let mesh = &body.mesh;
        let mut a_min = Real::INFINITY;
        for f in 0..mesh.faces.len() {
            let [p0, p1, p2] = mesh.face_positions(f);
            let twice_area = (p1 - p0).cross(&(p2 - p0)).norm();
            for (a, b) in [(p0, p1), (p1, p2), (p2, p0)] {
                a_min = a_min.min(twice_area / (b - a).norm());
            }
        }
        let length = sample_length(body);
        let dt_unit = (0.185 * (rho / mu).sqrt() * a_min)
            .min((rho * t / flexural).sqrt() * a_min * a_min / (2.0 * PI));
        let k = 2.0 * PI / length;
        let omega_long = (flexural / (rho * t)).sqrt() * k * k;
        let long_time = (2.0 * PI / omega_long).max(length * (rho / mu).sqrt());
        Scales {
            rho,
            mu,
            t,
            flexural,
            a_min,
            length,
            dt_unit,
            omega_long,
            long_time,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::mesh::generate::{rectangle, Spacing};

    /// The body of `copies` squares of side 0.01 set side by side, 0.02 apart.
    fn squares(copies: usize) -> Body {
        let one = rectangle(0.0, 0.0, 0.01, 0.01, 0.002, Spacing::default());
        let mut mesh = crate::mesh::Mesh::default();
        for k in 0..copies {
            let base = mesh.positions.len();
            let dx = Vec3::new(0.02 * k as Real, 0.0, 0.0);
            mesh.positions.extend(one.positions.iter().map(|p| p + dx));
            mesh.faces.extend(
                one.faces
                    .iter()
                    .map(|f| [f[0] + base, f[1] + base, f[2] + base]),
            );
        }
        let s = crate::settings::Settings::from_str_with(
            "[material]\nthickness = 1e-4\nbending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n",
            "test",
            &[],
        )
        .unwrap();
        crate::model::Scene::build(mesh, s).unwrap().body
    }

    /// Four separate 1 cm squares have the time scales of one (the largest sheet's
    /// perimeter, 4 cm), not those of a 16 cm perimeter (16× the bending long time).
    #[test]
    fn several_sheets_take_the_scales_of_the_largest() {
        let (one, four) = (Scales::of(&squares(1)), Scales::of(&squares(4)));
        assert!((one.length - 0.04).abs() < 1e-12, "{}", one.length);
        // The copies' lengths and altitudes differ by the round-off of their translation.
        assert!((one.length / four.length - 1.0).abs() < 1e-12);
        assert!((one.omega_long / four.omega_long - 1.0).abs() < 1e-12);
        assert!((one.dt_unit / four.dt_unit - 1.0).abs() < 1e-12);
    }
}
