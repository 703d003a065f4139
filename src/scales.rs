//! The time and force scales of a body's explicit dynamics (MorphoShell's, used by the explicit
//! driver and by the terms that scale themselves with it, such as the glass slides): from the
//! density ρ, the smallest shear modulus μ and thickness t, the smallest altitude a_min of the
//! reference triangles and the reference perimeter L,
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
    /// The sample length L: the reference perimeter (m).
    pub length: Real,
    /// The time step at prefactor 1 (s).
    pub dt_unit: Real,
    /// Angular frequency of the longest bending mode, `√(D/(ρt)) (2π/L)²` (rad/s).
    pub omega_long: Real,
    /// The long time `max(2π/ω_L, L √(ρ/μ))` (s).
    pub long_time: Real,
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
        let topo = &body.topo;
        let perimeter: Real = topo
            .edges
            .iter()
            .zip(&topo.edge_faces)
            .filter(|(_, ef)| ef[1] == crate::mesh::topology::NONE)
            .map(|(e, _)| (mesh.positions[e[1]] - mesh.positions[e[0]]).norm())
            .sum();
        let length = if perimeter > 0.0 {
            perimeter
        } else {
            PI * mesh.bbox_diagonal()
        };
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
