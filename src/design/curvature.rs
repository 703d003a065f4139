//! Curvature objectives: the mean and Gauss curvature of the shape against target fields, per
//! face.
//!
//! Each face's curvatures come from its first fundamental form `a` (of its edges `e₁ = x₁ − x₀`,
//! `e₂ = x₂ − x₀`) and the mid-edge-average second fundamental form `b` of the face and its
//! three neighbours ([`crate::geometry::midedge_average_q`], the discrete shell's own `b`):
//! `H = ½ tr(a⁻¹b) = (a₂₂b₁₁ − 2a₁₂b₁₂ + a₁₁b₂₂)/(2 det a)` and
//! `K = det(a⁻¹b) = (b₁₁b₂₂ − b₁₂²)/det a`. `b` is taken along the face's normal (the
//! right-hand rule of its vertex order): a sphere whose faces' normals point out has `H = 1/R`
//! and `K = 1/R²`. With the face weights `w_f` (reference areas, summing to 1, over the faces
//! with three neighbours: a boundary edge has no `b`) and the target's size `L`:
//!
//! `J_H = ½ Σ_f w_f (H_f − H*_f)² L²`,   `J_K = ½ Σ_f w_f (K_f − K*_f)² L⁴`,
//!
//! dimensionless, so `√(2 J_H)` is the RMS error of `H` in units of `1/L`. Neither depends on
//! the shape's rigid motion, so there is no alignment. Their gradients chain
//! `∂H/∂(a, b)` and `∂K/∂(a, b)` through `∂a/∂x` ([`crate::geometry::first_fundamental_form_jacobian`])
//! and `∂b/∂x` (the `q_i` gradients) over the face's six-vertex stencil.

use crate::geometry::{
    b_from_q, b_from_q_matrix, edge_slots, first_fundamental_form, first_fundamental_form_jacobian,
    AverageQs, UnitNormal,
};
use crate::math::{Real, SVec, Sym2, Vec3};
use crate::mesh::topology::NONE;
use crate::mesh::{Mesh, Topology};

/// One face's mean and Gauss curvature (1/m, 1/m²) with their gradients over the stencil
/// `[v₀, v₁, v₂, p₀, p₁, p₂]` (18 entries, m⁻², m⁻³).
pub fn face_curvatures(x: &[Vec3; 6]) -> (Real, Real, SVec<18>, SVec<18>) {
    let xf = [x[0], x[1], x[2]];
    let nf = UnitNormal::new(&xf);
    let qs = AverageQs::new(&nf, x, [true; 3], false);
    let q = SVec::<3>::new(qs.q[0], qs.q[1], qs.q[2]);
    let b: Sym2 = b_from_q(&q);
    let a = first_fundamental_form(&xf);
    let det = a[0] * a[2] - a[1] * a[1];
    let tr = a[2] * b[0] - 2.0 * a[1] * b[1] + a[0] * b[2];
    let h = tr / (2.0 * det);
    let k = (b[0] * b[2] - b[1] * b[1]) / det;
    // ∂/∂a and ∂/∂b as [11, 12, 22].
    let dh_da = SVec::<3>::new(
        b[2] / (2.0 * det) - h * a[2] / det,
        -b[1] / det + 2.0 * h * a[1] / det,
        b[0] / (2.0 * det) - h * a[0] / det,
    );
    let dh_db = SVec::<3>::new(a[2] / (2.0 * det), -a[1] / det, a[0] / (2.0 * det));
    let dk_da = SVec::<3>::new(-k * a[2] / det, 2.0 * k * a[1] / det, -k * a[0] / det);
    let dk_db = SVec::<3>::new(b[2] / det, -2.0 * b[1] / det, b[0] / det);
    let ja = first_fundamental_form_jacobian(&xf);
    let mut gh = SVec::<18>::zeros();
    let mut gk = SVec::<18>::zeros();
    let (ga, gka) = (ja.transpose() * dh_da, ja.transpose() * dk_da);
    for i in 0..9 {
        gh[i] += ga[i];
        gk[i] += gka[i];
    }
    // ∂b/∂q_i is column i of the constant map; each q_i reaches its four slots.
    let bq = b_from_q_matrix();
    let (hq, kq) = (bq.transpose() * dh_db, bq.transpose() * dk_db);
    for i in 0..3 {
        for (local, slot) in edge_slots(i).iter().enumerate() {
            for c in 0..3 {
                let g = qs.grad[i][3 * local + c];
                gh[3 * slot + c] += hq[i] * g;
                gk[3 * slot + c] += kq[i] * g;
            }
        }
    }
    (h, k, gh, gk)
}

/// The curvature objectives on one mesh.
#[derive(Clone, Debug)]
pub struct Curvature {
    /// Per face: its stencil, or `None` for a face with a boundary edge.
    stencils: Vec<Option<[usize; 6]>>,
    /// Face weights (sum 1 over the faces with a stencil).
    weights: Vec<Real>,
    /// The target's size `L` (m).
    size: Real,
    /// The weight and target field (1/m) of the mean curvature term.
    pub mean: Option<(Real, Vec<Real>)>,
    /// The weight and target field (1/m²) of the Gauss curvature term.
    pub gauss: Option<(Real, Vec<Real>)>,
}

/// The curvature terms at a shape.
#[derive(Clone, Debug, Default)]
pub struct CurvatureValue {
    /// `J_H` (unweighted).
    pub mean: Real,
    /// `J_K` (unweighted).
    pub gauss: Real,
    /// The weighted sum's gradient, per vertex (1/m).
    pub gradient: Vec<Vec3>,
}

impl Curvature {
    /// The terms on `mesh` for a target of size `size`, each with its weight and target field.
    pub fn new(
        mesh: &Mesh,
        topo: &Topology,
        size: Real,
        mean: Option<(Real, Vec<Real>)>,
        gauss: Option<(Real, Vec<Real>)>,
    ) -> Curvature {
        let stencils: Vec<Option<[usize; 6]>> = stencils(mesh, topo);
        let mut weights: Vec<Real> = (0..mesh.faces.len())
            .map(|f| {
                if stencils[f].is_some() {
                    mesh.face_area(f)
                } else {
                    0.0
                }
            })
            .collect();
        let total: Real = weights.iter().sum();
        if total > 0.0 {
            weights.iter_mut().for_each(|w| *w /= total);
        }
        Curvature {
            stencils,
            weights,
            size,
            mean,
            gauss,
        }
    }

    /// The terms and their weighted gradient at `x`.
    pub fn eval(&self, x: &[Vec3]) -> CurvatureValue {
        let l2 = self.size * self.size;
        let mut out = CurvatureValue {
            gradient: vec![Vec3::zeros(); x.len()],
            ..Default::default()
        };
        for (f, st) in self.stencils.iter().enumerate() {
            let Some(st) = st else { continue };
            let w = self.weights[f];
            let (h, k, gh, gk) = face_curvatures(&st.map(|v| x[v]));
            let mut coef_h = 0.0;
            let mut coef_k = 0.0;
            if let Some((mu, target)) = &self.mean {
                let d = h - target[f];
                out.mean += 0.5 * w * d * d * l2;
                coef_h = mu * w * d * l2;
            }
            if let Some((mu, target)) = &self.gauss {
                let d = k - target[f];
                out.gauss += 0.5 * w * d * d * l2 * l2;
                coef_k = mu * w * d * l2 * l2;
            }
            for (s, v) in st.iter().enumerate() {
                for c in 0..3 {
                    out.gradient[*v][c] += coef_h * gh[3 * s + c] + coef_k * gk[3 * s + c];
                }
            }
        }
        out
    }
}

/// Each face's six-vertex stencil `[v₀, v₁, v₂, p₀, p₁, p₂]`, or `None` when an edge has no
/// neighbour.
pub fn stencils(mesh: &Mesh, topo: &Topology) -> Vec<Option<[usize; 6]>> {
    mesh.faces
        .iter()
        .zip(&topo.opposite_vertex)
        .map(|(f, o)| (!o.contains(&NONE)).then_some([f[0], f[1], f[2], o[0], o[1], o[2]]))
        .collect()
}

/// The mean and Gauss curvature of every face of `mesh` at `x` (`None` at a boundary face).
pub fn face_fields(mesh: &Mesh, topo: &Topology, x: &[Vec3]) -> Vec<Option<(Real, Real)>> {
    stencils(mesh, topo)
        .into_iter()
        .map(|st| {
            st.map(|st| {
                let (h, k, _, _) = face_curvatures(&st.map(|v| x[v]));
                (h, k)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A geodesic-ish sphere patch: a grid mapped onto the sphere of radius `r`, normals out.
    fn sphere_patch(n: usize, r: Real) -> Mesh {
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (i as Real / n as Real - 0.5, j as Real / n as Real - 0.5);
                let d = Vec3::new(u, v, 1.0).normalize();
                positions.push(d * r);
            }
        }
        let id = |i: usize, j: usize| j * (n + 1) + i;
        let mut faces = Vec::new();
        for j in 0..n {
            for i in 0..n {
                faces.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                faces.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Mesh {
            positions,
            faces,
            face_fields: Default::default(),
            vertex_fields: Default::default(),
            source: None,
        }
    }

    #[test]
    fn a_sphere_has_its_curvatures_with_the_stated_signs() {
        let r = 2.0;
        let mesh = sphere_patch(16, r);
        let topo = Topology::build(&mesh).unwrap();
        let fields = face_fields(&mesh, &topo, &mesh.positions);
        let inner: Vec<(Real, Real)> = fields.into_iter().flatten().collect();
        assert!(!inner.is_empty());
        for (h, k) in inner {
            assert!((h * r - 1.0).abs() < 0.02, "H = {h}");
            assert!((k * r * r - 1.0).abs() < 0.04, "K = {k}");
        }
    }

    #[test]
    fn the_gradients_match_differences() {
        let x = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.1, 0.05),
            Vec3::new(0.2, 0.9, -0.03),
            Vec3::new(1.1, 1.0, 0.3),
            Vec3::new(-0.6, 0.6, 0.2),
            Vec3::new(0.5, -0.8, -0.25),
        ];
        let (_, _, gh, gk) = face_curvatures(&x);
        let h = 1e-6;
        for s in 0..6 {
            for c in 0..3 {
                let (mut a, mut b) = (x, x);
                a[s][c] += h;
                b[s][c] -= h;
                let (ha, ka, _, _) = face_curvatures(&a);
                let (hb, kb, _, _) = face_curvatures(&b);
                let (fh, fk) = ((ha - hb) / (2.0 * h), (ka - kb) / (2.0 * h));
                let i = 3 * s + c;
                assert!((fh - gh[i]).abs() <= 1e-7 * (1.0 + gh[i].abs()), "H {i}");
                assert!((fk - gk[i]).abs() <= 1e-7 * (1.0 + gk[i].abs()), "K {i}");
            }
        }
    }

    #[test]
    fn the_objective_gradient_matches_differences() {
        let mesh = sphere_patch(5, 1.5);
        let topo = Topology::build(&mesh).unwrap();
        let nf = mesh.faces.len();
        let mean: Vec<Real> = (0..nf)
            .map(|f| 0.1 * f as Real / nf as Real - 0.5)
            .collect();
        let gauss: Vec<Real> = (0..nf)
            .map(|f| 0.3 - 0.2 * f as Real / nf as Real)
            .collect();
        let c = Curvature::new(&mesh, &topo, 2.0, Some((1.0, mean)), Some((0.5, gauss)));
        let mut x = mesh.positions.clone();
        for (i, p) in x.iter_mut().enumerate() {
            p.z += 0.01 * (i as Real).sin();
        }
        let value = |x: &[Vec3]| {
            let v = c.eval(x);
            v.mean + 0.5 * v.gauss
        };
        let g = c.eval(&x).gradient;
        let h = 1e-6;
        for v in [0, 7, 14, 20, 35] {
            for k in 0..3 {
                let (mut a, mut b) = (x.clone(), x.clone());
                a[v][k] += h;
                b[v][k] -= h;
                let fd = (value(&a) - value(&b)) / (2.0 * h);
                assert!(
                    (fd - g[v][k]).abs() <= 1e-7 * (1.0 + g[v][k].abs()),
                    "{v} {k}: {} {fd}",
                    g[v][k]
                );
            }
        }
    }
}
