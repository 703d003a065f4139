//! Design objectives: the distance of a shape to a target, after the best rigid motion, and the
//! smoothness of the design.
//!
//! ## Point to point
//! With the target `y` on the design mesh's connectivity, vertex weights `w_v` (the lumped
//! reference area, summing to 1) and the target's size `L` (its bounding-box diagonal):
//!
//! `J_d(x) = min_{R, t} ½ Σ_v w_v |R x_v + t − y_v|² / L²`.
//!
//! The minimiser is the weighted Kabsch–Umeyama rotation (Kabsch, Acta Cryst. A 1976): with the
//! weighted centroids `x̄`, `ȳ` and `K = Σ w_v (x_v − x̄)(y_v − ȳ)ᵀ = U Σ Vᵀ`,
//! `R = V diag(1, 1, det(V Uᵀ)) Uᵀ` and `t = ȳ − R x̄`. By the envelope theorem (the alignment
//! is optimal, so its own derivative vanishes), `∂J_d/∂x_v = w_v Rᵀ(R x_v + t − y_v)/L²`
//! exactly. `√(2 J_d)` is the RMS distance over the target's size.
//!
//! ## Smoothness
//! `J_s(p) = w/2 Σ_e (|e|/d_e) δ(p_f, p_g)²` over the interior edges `e` between faces `f`
//! and `g`, `d_e` the distance between their centroids: the two-point flux approximation of
//! `w/2 ∫|∇p|² dA` for a piecewise-constant `p`, so that the weight does not depend on the mesh
//! size. `δ` is the difference `p_f − p_g`, except for director angles, whose nematic
//! difference `sin(p_f − p_g)` makes θ and θ + π the same director. For rest forms, the b̄
//! components are made dimensionless by `L` first.

use crate::math::{Mat3, Real, Vec3};
use crate::mesh::{Mesh, Topology};

/// The point-to-point distance to a target after the best rigid motion.
#[derive(Clone, Debug)]
pub struct Points {
    /// The target's vertex positions (m).
    pub target: Vec<Vec3>,
    /// Vertex weights (sum 1).
    pub weights: Vec<Real>,
    /// The target's size `L` (m).
    pub size: Real,
    /// Whether to align rigidly.
    pub align: bool,
}

/// The distance objective at a shape, with its gradient and the alignment used.
#[derive(Clone, Debug)]
pub struct Distance {
    /// `J_d` (dimensionless).
    pub value: Real,
    /// `∂J_d/∂x` (1/m), one vector per vertex.
    pub gradient: Vec<Vec3>,
    /// The rotation `R` of the alignment (identity without it).
    pub rotation: Mat3,
    /// The translation `t` (m).
    pub translation: Vec3,
    /// The target point each vertex is compared with (m, the target's frame).
    pub nearest: Vec<Vec3>,
}

/// The lumped areas of a triangle mesh's vertices (a third of each face's), summing to 1.
pub fn lumped_weights(positions: &[Vec3], faces: &[[usize; 3]]) -> Vec<Real> {
    let mut w = vec![0.0; positions.len()];
    for face in faces {
        let area = 0.5 * crate::geometry::area_normal(&face.map(|v| positions[v])).norm();
        for &v in face {
            w[v] += area / 3.0;
        }
    }
    let total: Real = w.iter().sum();
    if total > 0.0 {
        for x in &mut w {
            *x /= total;
        }
    }
    w
}

/// The diagonal of the bounding box of `points` (m): a shape's size.
pub fn bounding_diagonal(points: &[Vec3]) -> Real {
    let (lo, hi) = points.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    (hi - lo).norm()
}

/// The rigid motion `(R, t)` minimising `Σ w |R p + t − q|²` over weighted pairs `(p, q, w)`:
/// the weighted Kabsch–Umeyama rotation. With the weighted centroids `p̄`, `q̄` and
/// `K = Σ w (p − p̄)(q − q̄)ᵀ = U Σ Vᵀ`, `R = V diag(1, 1, det(V Uᵀ)) Uᵀ` and `t = q̄ − R p̄`.
pub fn kabsch(pairs: impl Iterator<Item = (Vec3, Vec3, Real)> + Clone) -> (Mat3, Vec3) {
    let (mut cp, mut cq, mut total) = (Vec3::zeros(), Vec3::zeros(), 0.0);
    for (p, q, w) in pairs.clone() {
        cp += p * w;
        cq += q * w;
        total += w;
    }
    if total <= 0.0 {
        return (Mat3::identity(), Vec3::zeros());
    }
    cp /= total;
    cq /= total;
    let mut k = Mat3::zeros();
    for (p, q, w) in pairs {
        k += (p - cp) * (q - cq).transpose() * w;
    }
    let svd = k.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return (Mat3::identity(), cq - cp);
    };
    let v = vt.transpose();
    let sign = (v * u.transpose()).determinant().signum();
    let r = v * Mat3::from_diagonal(&Vec3::new(1.0, 1.0, sign)) * u.transpose();
    (r, cq - r * cp)
}

impl Points {
    /// The objective of `target` on `mesh`'s connectivity; the weights are `mesh`'s lumped
    /// reference areas.
    pub fn new(mesh: &Mesh, target: Vec<Vec3>, align: bool) -> Points {
        Points {
            size: bounding_diagonal(&target),
            weights: lumped_weights(&mesh.positions, &mesh.faces),
            target,
            align,
        }
    }

    /// The best rigid motion `(R, t)` taking `x` onto the target.
    pub fn alignment(&self, x: &[Vec3]) -> (Mat3, Vec3) {
        if !self.align {
            return (Mat3::identity(), Vec3::zeros());
        }
        kabsch(
            x.iter()
                .zip(&self.target)
                .zip(&self.weights)
                .map(|((p, q), w)| (*p, *q, *w)),
        )
    }

    /// `J_d` and its gradient at `x`.
    pub fn eval(&self, x: &[Vec3]) -> Distance {
        let (r, t) = self.alignment(x);
        let l2 = self.size * self.size;
        let mut value = 0.0;
        let gradient = x
            .iter()
            .zip(&self.target)
            .zip(&self.weights)
            .map(|((p, q), w)| {
                let d = r * p + t - q;
                value += 0.5 * w * d.norm_squared() / l2;
                r.transpose() * d * (w / l2)
            })
            .collect();
        Distance {
            value,
            gradient,
            rotation: r,
            translation: t,
            nearest: self.target.clone(),
        }
    }

    /// The RMS distance over the target's size of an objective value.
    pub fn relative_rms(value: Real) -> Real {
        (2.0 * value.max(0.0)).sqrt()
    }
}

/// How the shape's distance to the target is measured.
#[derive(Debug)]
pub enum DistanceTerm {
    /// Vertex to vertex, on the design mesh's connectivity.
    Points(Points),
    /// Surface to surface, any triangulation ([`super::surface`]).
    Surface(Box<super::surface::Surface>),
}

/// The shape part of the objective: `μ_d J_d + μ_H J_H + μ_K J_K`, each term present when its
/// weight is set ([`super::curvature`] for the curvature terms).
#[derive(Debug)]
pub struct Shape {
    /// The distance term and its weight `μ_d`.
    pub distance: Option<(Real, DistanceTerm)>,
    /// The curvature terms with their weights.
    pub curvature: Option<super::curvature::Curvature>,
}

/// The shape terms at a shape.
#[derive(Clone, Debug)]
pub struct ShapeValue {
    /// The weighted sum.
    pub value: Real,
    /// `J_d`, unweighted (0 without the term).
    pub distance: Real,
    /// `J_H`, unweighted.
    pub mean: Real,
    /// `J_K`, unweighted.
    pub gauss: Real,
    /// The weighted sum's gradient per vertex (1/m).
    pub gradient: Vec<Vec3>,
    /// The alignment `(R, t)` (identity without a distance term or alignment).
    pub alignment: (Mat3, Vec3),
    /// The target point each vertex is compared with (the target's frame), with a distance term.
    pub nearest: Option<Vec<Vec3>>,
}

impl DistanceTerm {
    /// The weights `c_v` of the Gauss–Newton model of the term,
    /// `J_d(x + δx) ≈ J_d + ∇J_d·δx + ½ Σ_v c_v |δx_v|²` with the alignment and the closest
    /// points held (1/m²): `w_v/L²` for points; for a surface, the shape side's `½ w_v/L²` of
    /// its `¼(…)/L²` (the target side, whose points move with the shape's faces, is left out of
    /// the model; the gradient keeps it).
    pub fn model_weights(&self) -> Vec<Real> {
        match self {
            DistanceTerm::Points(p) => {
                let l2 = p.size * p.size;
                p.weights.iter().map(|w| w / l2).collect()
            }
            DistanceTerm::Surface(s) => s.model_weights(),
        }
    }

    /// Whether the shape is compared after the best rigid motion.
    pub fn aligns(&self) -> bool {
        match self {
            DistanceTerm::Points(p) => p.align,
            DistanceTerm::Surface(s) => s.aligns(),
        }
    }

    /// The target's size `L` (m).
    pub fn size(&self) -> Real {
        match self {
            DistanceTerm::Points(p) => p.size,
            DistanceTerm::Surface(s) => s.size,
        }
    }
}

/// Removes from the displacement `dx` (per vertex) its best infinitesimal rigid motion about
/// the shape `x` in the weights `c`: `dx_v − τ − ω × (x_v − x̄)`, with `x̄` the weighted
/// centroid, `τ` the weighted mean of `dx` and `(Σ c_v (|r_v|² I − r_v r_vᵀ)) ω = Σ c_v r_v × dx_v`.
/// This is the `c`-orthogonal projection onto the displacements an alignment cannot absorb: the
/// linearised Kabsch–Umeyama fit.
pub fn remove_rigid_motion(x: &[Vec3], c: &[Real], dx: &mut [Vec3]) {
    let total: Real = c.iter().sum();
    if total <= 0.0 {
        return;
    }
    let centre = x.iter().zip(c).map(|(p, w)| p * *w).sum::<Vec3>() / total;
    let tau = dx.iter().zip(c).map(|(d, w)| d * *w).sum::<Vec3>() / total;
    let mut a = Mat3::zeros();
    let mut b = Vec3::zeros();
    for ((p, d), w) in x.iter().zip(dx.iter()).zip(c) {
        let r = p - centre;
        a += (Mat3::identity() * r.norm_squared() - r * r.transpose()) * *w;
        b += r.cross(d) * *w;
    }
    let omega = a.try_inverse().map_or(Vec3::zeros(), |inv| inv * b);
    for (p, d) in x.iter().zip(dx.iter_mut()) {
        *d -= tau + omega.cross(&(p - centre));
    }
}

impl Shape {
    /// The terms and their gradient at `x`.
    pub fn eval(&self, x: &[Vec3]) -> ShapeValue {
        let mut out = ShapeValue {
            value: 0.0,
            distance: 0.0,
            mean: 0.0,
            gauss: 0.0,
            gradient: vec![Vec3::zeros(); x.len()],
            alignment: (Mat3::identity(), Vec3::zeros()),
            nearest: None,
        };
        if let Some((mu, term)) = &self.distance {
            let d = match term {
                DistanceTerm::Points(p) => p.eval(x),
                DistanceTerm::Surface(s) => s.eval(x),
            };
            out.distance = d.value;
            out.value += mu * d.value;
            for (g, h) in out.gradient.iter_mut().zip(&d.gradient) {
                *g += h * *mu;
            }
            out.alignment = (d.rotation, d.translation);
            out.nearest = Some(d.nearest);
        }
        if let Some(c) = &self.curvature {
            let v = c.eval(x);
            out.mean = v.mean;
            out.gauss = v.gauss;
            out.value += c.mean.as_ref().map_or(0.0, |m| m.0) * v.mean
                + c.gauss.as_ref().map_or(0.0, |m| m.0) * v.gauss;
            for (g, h) in out.gradient.iter_mut().zip(&v.gradient) {
                *g += h;
            }
        }
        out
    }
}

/// The smoothness term over the interior edges.
#[derive(Clone, Debug)]
pub struct Smoothness {
    /// The weight `w`.
    pub weight: Real,
    /// Per interior edge: the two faces and `|e|/d_e`.
    pub edges: Vec<(usize, usize, Real)>,
    /// Whether the numbers are director angles (nematic difference).
    pub nematic: bool,
    /// The scale of each design number of a face (1, or `L` for b̄ components).
    pub scale: Vec<Real>,
}

impl Smoothness {
    /// The term on `mesh` with weight `weight`, for `per_face` numbers scaled by `scale`.
    pub fn new(
        mesh: &Mesh,
        topo: &Topology,
        weight: Real,
        nematic: bool,
        scale: Vec<Real>,
    ) -> Self {
        let centroid = |f: usize| {
            let [a, b, c] = mesh.faces[f].map(|v| mesh.positions[v]);
            (a + b + c) / 3.0
        };
        let mut edges = Vec::new();
        for (e, faces) in topo.edge_faces.iter().enumerate() {
            let [f, g] = *faces;
            if g == crate::mesh::topology::NONE || f == crate::mesh::topology::NONE {
                continue;
            }
            let [u, v] = topo.edges[e];
            let len = (mesh.positions[u] - mesh.positions[v]).norm();
            let d = (centroid(f) - centroid(g)).norm();
            if d > 0.0 {
                edges.push((f, g, len / d));
            }
        }
        Smoothness {
            weight,
            edges,
            nematic,
            scale,
        }
    }

    /// `J_s(p)` (numbers per face `scale.len()`), adding `∂J_s/∂p` into `grad`.
    pub fn eval(&self, p: &[Real], grad: &mut [Real]) -> Real {
        if self.weight == 0.0 {
            return 0.0;
        }
        let k = self.scale.len();
        let mut j = 0.0;
        for &(f, g, c) in &self.edges {
            for (i, s) in self.scale.iter().enumerate() {
                let (a, b) = (p[k * f + i], p[k * g + i]);
                let (d, dd) = if self.nematic {
                    ((a - b).sin(), (a - b).cos())
                } else {
                    ((a - b) * s, *s)
                };
                j += 0.5 * self.weight * c * d * d;
                let gd = self.weight * c * d * dd;
                grad[k * f + i] += gd;
                grad[k * g + i] -= gd;
            }
        }
        j
    }
}

/// The Sobolev metric of the design, `M = A/A₀ + (ℓ²/A₀) K`, and its inverse as the optimiser's
/// preconditioner ([`super::lbfgs::Problem::precondition`]): `A` the faces' reference areas,
/// `A₀` their sum, `K` the two-point Laplacian of [`Smoothness`] (`pᵀKp = Σ_e (|e|/d_e) Δp²`) and
/// ℓ the smoothing length. The gradient in this metric, `M⁻¹ ∇J`, is the `H¹` gradient of
/// Sobolev-gradient shape optimisation (Neuberger, *Sobolev Gradients and Differential
/// Equations*, 1997): smooth over ℓ whatever the mesh, where the per-face gradient `∇J` has
/// mesh-scale noise that crumples a thin sheet. It changes the path, not the optimum.
#[derive(Clone, Debug)]
pub struct Sobolev {
    /// `A_f/A₀` per face.
    area: Vec<Real>,
    /// Per interior edge: the two faces and `(ℓ²/A₀) |e|/d_e`.
    edges: Vec<(usize, usize, Real)>,
    /// Design numbers per face.
    per_face: usize,
}

impl Sobolev {
    /// The metric on `mesh` with smoothing length `ell` (m), for `per_face` numbers per face.
    pub fn new(mesh: &Mesh, topo: &Topology, ell: Real, per_face: usize) -> Sobolev {
        let area: Vec<Real> = (0..mesh.faces.len()).map(|f| mesh.face_area(f)).collect();
        let total: Real = area.iter().sum::<Real>().max(Real::MIN_POSITIVE);
        let edges = Smoothness::new(mesh, topo, 1.0, false, vec![1.0])
            .edges
            .into_iter()
            .map(|(f, g, c)| (f, g, c * ell * ell / total))
            .collect();
        Sobolev {
            area: area.iter().map(|a| a / total).collect(),
            edges,
            per_face,
        }
    }

    /// `y = M x`.
    pub fn apply(&self, x: &[Real], y: &mut [Real]) {
        let k = self.per_face;
        for (f, a) in self.area.iter().enumerate() {
            for i in 0..k {
                y[k * f + i] = a * x[k * f + i];
            }
        }
        for &(f, g, c) in &self.edges {
            for i in 0..k {
                let d = c * (x[k * f + i] - x[k * g + i]);
                y[k * f + i] += d;
                y[k * g + i] -= d;
            }
        }
    }

    /// `v ← M⁻¹ v` by conjugate gradients with the diagonal as preconditioner, to 1e-10
    /// relative (serial and in a fixed order: the same bits on any thread count).
    pub fn solve(&self, v: &mut [Real]) {
        let n = v.len();
        let k = self.per_face;
        let mut diag: Vec<Real> = (0..n).map(|j| self.area[j / k]).collect();
        for &(f, g, c) in &self.edges {
            for i in 0..k {
                diag[k * f + i] += c;
                diag[k * g + i] += c;
            }
        }
        let b = v.to_vec();
        let bn = b.iter().map(|x| x * x).sum::<Real>().sqrt();
        if bn == 0.0 {
            return;
        }
        let mut x = vec![0.0; n];
        let mut r = b;
        let mut z: Vec<Real> = r.iter().zip(&diag).map(|(a, d)| a / d).collect();
        let mut p = z.clone();
        let mut rz: Real = r.iter().zip(&z).map(|(a, b)| a * b).sum();
        let mut q = vec![0.0; n];
        for _ in 0..10 * n.max(10) {
            self.apply(&p, &mut q);
            let pq: Real = p.iter().zip(&q).map(|(a, b)| a * b).sum();
            if pq <= 0.0 {
                break;
            }
            let alpha = rz / pq;
            for j in 0..n {
                x[j] += alpha * p[j];
                r[j] -= alpha * q[j];
            }
            if r.iter().map(|x| x * x).sum::<Real>().sqrt() <= 1e-10 * bn {
                break;
            }
            for j in 0..n {
                z[j] = r[j] / diag[j];
            }
            let rz_new: Real = r.iter().zip(&z).map(|(a, b)| a * b).sum();
            let beta = rz_new / rz;
            rz = rz_new;
            for j in 0..n {
                p[j] = z[j] + beta * p[j];
            }
        }
        v.copy_from_slice(&x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{rectangle, Spacing};

    /// A rotated, shifted copy of the target is at distance 0 after alignment, and the
    /// gradient matches central differences at a deformed shape.
    #[test]
    fn alignment_removes_rigid_motions_and_the_gradient_matches_differences() {
        let mesh = rectangle(-0.5, -0.5, 1.0, 0.6, 0.25, Spacing::default());
        let target: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| Vec3::new(p.x, p.y, 0.3 * p.x * p.x - 0.2 * p.y * p.y))
            .collect();
        let obj = Points::new(&mesh, target.clone(), true);
        let rot = nalgebra::Rotation3::from_euler_angles(0.3, -0.5, 1.1);
        let moved: Vec<Vec3> = target
            .iter()
            .map(|p| rot * p + Vec3::new(1.0, -2.0, 0.5))
            .collect();
        assert!(obj.eval(&moved).value < 1e-28);
        let x: Vec<Vec3> = moved
            .iter()
            .enumerate()
            .map(|(i, p)| {
                p + Vec3::new(
                    0.01 * (i as Real).sin(),
                    0.02 * (i as Real * 0.7).cos(),
                    0.015,
                )
            })
            .collect();
        let d = obj.eval(&x);
        for v in [0, 3, 7] {
            for c in 0..3 {
                let eps = 1e-6;
                let at = |e: Real| {
                    let mut y = x.clone();
                    y[v][c] += e;
                    obj.eval(&y).value
                };
                let fd = (at(eps) - at(-eps)) / (2.0 * eps);
                assert!(
                    (fd - d.gradient[v][c]).abs()
                        < 1e-9 * d.gradient.iter().map(|g| g.amax()).fold(0.0, Real::max),
                    "{fd} {}",
                    d.gradient[v][c]
                );
            }
        }
    }

    /// The smoothness gradient matches differences, and a uniform design costs nothing.
    #[test]
    fn smoothness_gradient_matches_differences() {
        let mesh = rectangle(-0.5, -0.5, 1.0, 0.6, 0.25, Spacing::default());
        let topo = Topology::build(&mesh).unwrap();
        for nematic in [false, true] {
            let sm = Smoothness::new(&mesh, &topo, 0.7, nematic, vec![1.0]);
            let n = mesh.faces.len();
            let mut g = vec![0.0; n];
            assert_eq!(sm.eval(&vec![0.3; n], &mut g), 0.0);
            let p: Vec<Real> = (0..n).map(|f| (f as Real * 0.37).sin()).collect();
            let mut g = vec![0.0; n];
            sm.eval(&p, &mut g);
            for f in [0, n / 2, n - 1] {
                let eps = 1e-6;
                let at = |e: Real| {
                    let mut q = p.clone();
                    q[f] += e;
                    sm.eval(&q, &mut vec![0.0; n])
                };
                let fd = (at(eps) - at(-eps)) / (2.0 * eps);
                assert!((fd - g[f]).abs() < 1e-8, "{fd} {}", g[f]);
            }
        }
    }
}

#[cfg(test)]
mod sobolev_tests {
    use super::*;
    use crate::mesh::generate::{rectangle, Spacing};

    /// `M⁻¹` inverts `M` to the solver's tolerance.
    #[test]
    fn the_sobolev_solve_inverts_the_metric() {
        let mesh = rectangle(-0.5, -0.5, 1.0, 0.6, 0.1, Spacing::default());
        let topo = Topology::build(&mesh).unwrap();
        let m = Sobolev::new(&mesh, &topo, 0.2, 2);
        let n = 2 * mesh.faces.len();
        let x: Vec<Real> = (0..n).map(|j| (j as Real * 0.3).sin()).collect();
        let mut y = vec![0.0; n];
        m.apply(&x, &mut y);
        m.solve(&mut y);
        let err = x
            .iter()
            .zip(&y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, Real::max);
        assert!(err < 1e-7, "{err}");
    }
}
