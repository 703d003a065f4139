//! A face's reference frame and the maps between reference Cartesian and barycentric tensors,
//! which the rest-form laws that take their forms in reference coordinates (the settings'
//! expressions, the mesh's fields, the director law) share.

use crate::math::{Mat2, Real, Sym2, Vec3};
use crate::mesh::{Mesh, MeshError};

/// `T = [e1 e2]` of a face of a flat reference mesh, restricted to x, y: maps barycentric
/// vectors to reference Cartesian ones.
pub fn reference_frame(mesh: &Mesh, f: usize) -> Mat2 {
    let [p0, p1, p2] = mesh.face_positions(f);
    let (e1, e2) = (p1 - p0, p2 - p0);
    Mat2::new(e1.x, e2.x, e1.y, e2.y)
}

/// Pulls a tensor given in reference Cartesian coordinates back to the face's barycentric
/// coordinates: `Tᵀ M T` (seed 000 "Pullback Forms").
#[inline]
pub fn pull_back(t: &Mat2, m: &Sym2) -> Sym2 {
    crate::math::mat_to_sym(&(t.transpose() * crate::math::sym_to_mat(m) * t))
}

/// Pushes a barycentric tensor forward to reference Cartesian coordinates: `T⁻ᵀ M T⁻¹`.
#[inline]
pub fn push_forward(t: &Mat2, m: &Sym2) -> Sym2 {
    let ti = t.try_inverse().unwrap_or_else(Mat2::zeros);
    crate::math::mat_to_sym(&(ti.transpose() * crate::math::sym_to_mat(m) * ti))
}

/// The barycentric form of face `f` of a tensor field `m(x, y)` given in reference Cartesian
/// coordinates, sampled edge by edge: each edge vector `e` gets `eᵀ m(x_e) e` with `x_e` the
/// edge's midpoint (the discrete metric's squared edge lengths when `m` is ā), and the form is
/// the one with these three values on `e1`, `e2` and `e2 − e1`. Exact for constant `m`, second
/// order otherwise.
pub fn sample_on_edges(mesh: &Mesh, f: usize, m: impl Fn(Real, Real) -> Sym2) -> Sym2 {
    let [p0, p1, p2] = mesh.face_positions(f);
    let t = reference_frame(mesh, f);
    let e1 = crate::math::Vec2::new(t[(0, 0)], t[(1, 0)]);
    let e2 = crate::math::Vec2::new(t[(0, 1)], t[(1, 1)]);
    let e3 = e2 - e1;
    let quad = |p: Vec3, e: &crate::math::Vec2| {
        let s = m(p.x, p.y);
        e.x * e.x * s[0] + 2.0 * e.x * e.y * s[1] + e.y * e.y * s[2]
    };
    let m11 = quad((p0 + p1) / 2.0, &e1);
    let m22 = quad((p0 + p2) / 2.0, &e2);
    let m33 = quad((p1 + p2) / 2.0, &e3);
    // M(e2 − e1, e2 − e1) = m11 + m22 − 2 m12.
    Sym2::new(m11, 0.5 * (m11 + m22 - m33), m22)
}

/// Smallest eigenvalue of a target `ā` in reference coordinates (a stretch of 1e-6); the
/// largest accepted is its inverse.
pub const MIN_METRIC: Real = 1e-12;
/// Largest target curvature × sheet size (a radius of 1e-9 of the sheet).
pub const MAX_CURVATURE_TIMES_SIZE: Real = 1e9;

/// Target forms given per face in reference Cartesian coordinates (e.g. the `abar_info` and
/// `bbar_info` fields), pulled back. Requires a flat reference mesh; checks ā > 0 per face.
pub fn pulled_back_targets(
    mesh: &Mesh,
    abar_xy: impl Fn(usize) -> Sym2,
    bbar_xy: impl Fn(usize) -> Sym2,
    what: &str,
) -> Result<(Vec<Sym2>, Vec<Sym2>), MeshError> {
    if !mesh.is_flat_xy() {
        return Err(mesh.invalid(format!(
            "{what} gives forms in reference Cartesian (x, y) coordinates, which needs a flat \
             reference mesh in a plane z = const"
        )));
    }
    let nf = mesh.faces.len();
    let mut a = Vec::with_capacity(nf);
    let mut b = Vec::with_capacity(nf);
    let size = mesh.bbox_diagonal();
    for f in 0..nf {
        let axy = abar_xy(f);
        if !(axy[0] > 0.0 && crate::math::sym_det(&axy) > 0.0) {
            return Err(mesh.invalid(format!(
                "{what}: abar at face {f} is not positive definite: [{}, {}, {}]",
                crate::math::human(axy[0]),
                crate::math::human(axy[1]),
                crate::math::human(axy[2])
            )));
        }
        // Stretches beyond 1e±6 are no material's, and their squares overflow in the energy.
        let (lo, hi) = crate::math::eig2(&crate::math::sym_to_mat(&axy));
        if lo < MIN_METRIC || hi > 1.0 / MIN_METRIC {
            return Err(mesh.invalid(format!(
                "{what}: abar at face {f}, [{}, {}, {}], asks for stretches {} to {}, \
                 outside 1e-6..1e6",
                crate::math::human(axy[0]),
                crate::math::human(axy[1]),
                crate::math::human(axy[2]),
                crate::math::human(lo.sqrt()),
                crate::math::human(hi.sqrt())
            )));
        }
        let bxy = bbar_xy(f);
        if let Some(c) = [bxy[0], bxy[1], bxy[2]]
            .into_iter()
            .find(|c| !c.is_finite() || c.abs() * size > MAX_CURVATURE_TIMES_SIZE)
        {
            return Err(mesh.invalid(format!(
                "{what}: bbar at face {f} has an entry {c_h} 1/m: a curvature radius below \
                 1e-9 of the sheet's size ({size_h} m)",
                c_h = crate::math::human(c),
                size_h = crate::math::human(size)
            )));
        }
        let t = reference_frame(mesh, f);
        a.push(pull_back(&t, &axy));
        b.push(pull_back(&t, &bxy));
    }
    Ok((a, b))
}

/// A reference-Cartesian direction as barycentric coordinates of face `f`: its projection on the
/// face plane written in the basis `e1, e2`. `None` if it is zero, non-finite or normal to the
/// face (projection below 1e-6 of its length).
pub fn barycentric_direction(mesh: &Mesh, f: usize, d: &Vec3) -> Option<[Real; 2]> {
    let n = d.norm();
    if !(n.is_finite() && n > 0.0) {
        return None;
    }
    let [p0, p1, p2] = mesh.face_positions(f);
    let (e1, e2) = (p1 - p0, p2 - p0);
    let gram = crate::math::Mat2::new(e1.dot(&e1), e1.dot(&e2), e1.dot(&e2), e2.dot(&e2));
    let rhs = crate::math::Vec2::new(e1.dot(d), e2.dot(d));
    let c = gram.try_inverse()? * rhs;
    let proj = e1 * c.x + e2 * c.y;
    (proj.norm() > 1e-6 * n).then_some([c.x, c.y])
}
