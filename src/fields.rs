//! MorphoShell's derived output fields (seed 001, its output frames), written into shellsim's
//! frames with `output.morphoshell_fields = true`:
//!
//! * **angle deficit** per vertex (rad): `2π − Σθ` over the angles θ of the vertex's faces at
//!   the vertex, and `π − Σθ` at a boundary vertex (MorphoShell's convention: with it the sum
//!   over all vertices is exactly `2π χ`, discrete Gauss–Bonnet). The **angle-deficit Gauss
//!   curvature** (1/m²) divides it by a third of the vertex's faces' area (the barycentric
//!   dual cell): `K_i = deficit_i / (A_i / 3)`. At boundary vertices that quotient is the
//!   boundary's turning per area, not a Gauss curvature.
//! * **strain measure** per face (dimensionless): MorphoShell's
//!   `√(½ tr(ε²))` of the tangent strain tensor `ε = ½ F⁺ᵀ (a − ā) F⁺` (F the face's
//!   deformation gradient, F⁺ its pseudo-inverse), the RMS of the two principal strains
//!   relative to the rest metric. Its nonzero eigenvalues are those of `½ (I − a⁻¹ā)`, so
//!   `strain = √(½ tr(N²))`, `N = ½ (I − a⁻¹ā)`, with no eigen-decomposition.
//! * **Cauchy stress** per face (N/m, force per deformed length): with `W` the face's
//!   stretching energy (J) as a function of its barycentric first fundamental form `a`, and
//!   `G = ∂W/∂a` as a symmetric tensor, `σ = (2/A) F G Fᵀ` (A the deformed area, F = [x₁−x₀,
//!   x₂−x₀]): virtual work `δW = 2 tr(G Fᵀ δF) = A σ : (δF F⁺)`. Its two principal values are
//!   the eigenvalues of the 2×2 `(2/A) G a` (similar to a symmetric matrix), with eigenvectors
//!   `F w`. MorphoShell also writes them over μt (`dimless_…`).
//!
//! Units: positions m, areas m², energies J.

use crate::math::{Mat2, Real, Sym2, Vec3};
use std::f64::consts::PI;

/// Angle deficits per vertex (rad) and the angle-deficit Gauss curvature (1/m²) at positions
/// `x` of triangles `faces`, with `boundary[v]` marking boundary vertices (see the module doc).
pub fn angle_deficits(
    x: &[Vec3],
    faces: &[[usize; 3]],
    boundary: &[bool],
) -> (Vec<Real>, Vec<Real>) {
    let mut deficit: Vec<Real> = boundary
        .iter()
        .map(|&b| if b { PI } else { 2.0 * PI })
        .collect();
    let mut area = vec![0.0; x.len()];
    for f in faces {
        let p = f.map(|v| x[v]);
        let third = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm() / 3.0;
        for k in 0..3 {
            let (u, w) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            // atan2 of |u × w| and u·w: accurate at any angle, unlike acos.
            deficit[f[k]] -= u.cross(&w).norm().atan2(u.dot(&w));
            area[f[k]] += third;
        }
    }
    let curvature = deficit
        .iter()
        .zip(&area)
        .map(|(d, a)| if *a > 0.0 { d / a } else { 0.0 })
        .collect();
    (deficit, curvature)
}

/// MorphoShell's strain measure `√(½ tr(N²))`, `N = ½ (I − a⁻¹ā)` (see the module doc).
pub fn strain_measure(a: &Sym2, abar: &Sym2) -> Real {
    let am = crate::math::sym_to_mat(a);
    let Some(ai) = am.try_inverse() else {
        return 0.0;
    };
    let n = (Mat2::identity() - ai * crate::math::sym_to_mat(abar)) * 0.5;
    (0.5 * (n * n).trace()).max(0.0).sqrt()
}

/// Principal Cauchy stresses (N/m), largest first, and their unit directions, of a face with
/// edge vectors `e1 = x₁ − x₀`, `e2 = x₂ − x₀`, first fundamental form `a` (`[e1·e1, e1·e2,
/// e2·e2]`) and `ga = ∂W/∂a` in the stored components `[a11, a12, a22]` (so the tensor's
/// off-diagonal is `ga[1]/2`). See the module doc for the formula.
pub fn cauchy_principal(e1: &Vec3, e2: &Vec3, a: &Sym2, ga: &Sym2) -> ([Real; 2], [Vec3; 2]) {
    let area = 0.5 * e1.cross(e2).norm();
    let g = Mat2::new(ga[0], 0.5 * ga[1], 0.5 * ga[1], ga[2]);
    let m = g * crate::math::sym_to_mat(a) * (2.0 / area.max(Real::MIN_POSITIVE));
    let half_tr = 0.5 * m.trace();
    let disc = (0.25 * (m[(0, 0)] - m[(1, 1)]).powi(2) + m[(0, 1)] * m[(1, 0)]).max(0.0);
    let r = disc.sqrt();
    let (l1, l2) = (half_tr + r, half_tr - r);
    let to3 = |w: (Real, Real)| e1 * w.0 + e2 * w.1;
    let scale = m.abs().max().max(Real::MIN_POSITIVE);
    let u1 = if r > 1e-12 * scale {
        // A null vector of M − λ₁I: of its two rows, the better-conditioned.
        let c1 = (m[(0, 1)], l1 - m[(0, 0)]);
        let c2 = (l1 - m[(1, 1)], m[(1, 0)]);
        let w = if c1.0.hypot(c1.1) >= c2.0.hypot(c2.1) {
            c1
        } else {
            c2
        };
        to3(w)
    } else {
        // Isotropic stress: every tangent direction is principal.
        *e1
    };
    let u1 = u1.normalize();
    let n = e1.cross(e2).normalize();
    let u2 = n.cross(&u1);
    ([l1, l2], [u1, u2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strain_measure_of_a_uniaxial_stretch() {
        // a = diag(s², 1), ā = I: N = diag(½(1 − 1/s²), 0), strain = |N₁₁|/√2.
        let s: Real = 1.1;
        let got = strain_measure(&Sym2::new(s * s, 0.0, 1.0), &Sym2::new(1.0, 0.0, 1.0));
        let want = 0.5 * (1.0 - 1.0 / (s * s)) / 2f64.sqrt();
        assert!((got - want).abs() < 1e-15, "{got} vs {want}");
    }

    #[test]
    fn cauchy_principal_directions_are_orthonormal_and_tangent() {
        let e1 = Vec3::new(1.0, 0.2, 0.1);
        let e2 = Vec3::new(0.3, 0.9, -0.2);
        let a = Sym2::new(e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
        let ga = Sym2::new(0.7, -0.4, 0.2);
        let (l, u) = cauchy_principal(&e1, &e2, &a, &ga);
        assert!(l[0] >= l[1]);
        let n = e1.cross(&e2).normalize();
        for v in &u {
            assert!((v.norm() - 1.0).abs() < 1e-14 && v.dot(&n).abs() < 1e-14);
        }
        assert!(u[0].dot(&u[1]).abs() < 1e-12);
        // σ u = λ u with σ = (2/A) F G Fᵀ.
        let f = nalgebra::Matrix3x2::from_columns(&[e1, e2]);
        let g = nalgebra::Matrix2::new(ga[0], 0.5 * ga[1], 0.5 * ga[1], ga[2]);
        let sigma = f * g * f.transpose() * (2.0 / (0.5 * e1.cross(&e2).norm()));
        for k in 0..2 {
            assert!((sigma * u[k] - u[k] * l[k]).norm() < 1e-12 * sigma.norm());
        }
    }
}
