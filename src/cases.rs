//! Analytic benchmark cases: programmed forms with a known exact shape, and the error of a
//! simulated shape against it after rigid alignment.
//!
//! Seed 000 Table 1 (on the unit square `[−½, ½]²`, forms in reference Cartesian coordinates):
//!
//! | case | ā | b̄ | exact surface, material point (x, y) ↦ |
//! |---|---|---|---|
//! | `enlarged_square` | 4I | 0 | (2x, 2y, 0) |
//! | `spherical_cap` | (1−x²−y²)⁻¹[[1−y², xy], [xy, 1−x²]] | = ā | (x, y, √(1−x²−y²)) (unit sphere) |
//! | `hyperboloid` | [[1+x², −xy], [−xy, 1+y²]] | (1+x²+y²)^(−½) diag(−1, 1) | (x, y, (x²−y²)/2) |
//! | `rhombus` | [[2, 1], [1, 2]] | 0 | (F (x, y), 0) with F = √ā |
//! | `cylinder` | I | diag(1, 0) | (sin x, y, cos x − 1) (radius 1, axis ∥ y) |
//!
//! Beyond Table 1 (the bending models' convergence study):
//!
//! | case | domain | ā | b̄ | exact surface |
//! |---|---|---|---|---|
//! | `gcm_cone` | sector 1 ≤ r ≤ 1.4, 0 ≤ θ ≤ 2π sin α | I | θ̂θ̂ᵀ/(2r) | cone of half-angle α = atan 2 |
//! | `bilayer_strip` | 1 × 0.1 strip, h = 0.002 | diag(ā11, 1) | diag(3Δε/(2h), 0) | arc of curvature b̄11/ā11 |
//! | `conformal_cap` | unit disk | η² I, η = 1/(1 + ρ²/4) | = ā | the unit sphere by inverse stereographic projection |
//!
//! `gcm_cone` is MorphoShell's curvature-programmed cone: ā = I and b̄ = θ̂θ̂ᵀ/(2r) satisfy the
//! Gauss–Codazzi–Mainardi equations, and the surface is the cone whose circumferential normal
//! curvature `cot α / r` equals `1/(2r)`, so `tan α = 2`. A flat sector of angle `2π sin α`
//! (322.0°; the removed wedge is 38.0°) closes into it exactly:
//! `(r, θ) ↦ (r sin α cos ψ, r sin α sin ψ, −r cos α)`, `ψ = θ / sin α`.
//!
//! `bilayer_strip` is a bilayer of two equal layers of total thickness h whose top layer is
//! stretched by `1 + Δε/2` and bottom by `1 − Δε/2` along x (Δε = 0.002). By the
//! bilayer–Koiter equivalence (van Rees et al. 2017), `ā = (g⁺ + g⁻)/2` and
//! `b̄ = 3/(4h)(g⁺ − g⁻)` with `g± = diag((1 ± Δε/2)², 1)`, so `b̄11 = 3Δε/(2h)`: Timoshenko's
//! bimetal curvature for equal layers (1925), which the exact shape reproduces to
//! `Δε²/4 = 1e-6` relative (the factor `1/ā11`).
//!
//! Signs follow shellsim's convention (positive b̄ bulges toward the normal, +z here). The
//! hyperboloid's forms are those of the graph `z = (x² − y²)/2`, whose normal-side curvature is
//! `−∂²f/√(1+|∇f|²)`.

use crate::math::{sym_to_mat, Mat2, Mat3, Real, Sym2, Vec3};
use crate::mesh::{Field, Mesh};

/// A programmed shape with a known answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// ā = 4I: a square twice as large.
    EnlargedSquare,
    /// The unit sphere's forms: a spherical cap.
    SphericalCap,
    /// The forms of the saddle z = (x² − y²)/2.
    Hyperboloid,
    /// ā = [[2, 1], [1, 2]]: a flat rhombus.
    Rhombus,
    /// ā = I, b̄ = diag(1, 0): a cylinder of radius 1.
    Cylinder,
    /// ā = λ_r² r̂r̂ᵀ + λ_θ² θ̂θ̂ᵀ with λ_r = 1, λ_θ = 0.8, b̄ = 0: a cone of half-angle
    /// φ = asin(λ_θ/λ_r) = 53.13° (Modes, Bhattacharya & Warner 2011). Use it on an annulus: the
    /// metric is singular at r = 0.
    Cone,
    /// ā = I, b̄ = θ̂θ̂ᵀ/(2r) on the sector 1 ≤ r ≤ 1.4, 0 ≤ θ ≤ 2π sin α: the
    /// Gauss–Codazzi–Mainardi cone of half-angle α = atan 2 (MorphoShell).
    GcmCone,
    /// A bilayer strip against Timoshenko's formula (see the module doc).
    BilayerStrip,
    /// Isotropic (conformal) growth of the unit disk toward a spherical cap: ā = η² I with
    /// η = 1/(1 + ρ²/4) (Gauss curvature 1, Klein, Efrati & Sharon 2007) and b̄ = ā (the unit
    /// sphere's curvature, b̄ = ā/R with R = 1).
    ConformalCap,
}

/// Half-angle of [`Case::GcmCone`]: `tan α = 2`.
pub fn gcm_cone_half_angle() -> Real {
    2.0_f64.atan()
}

/// Angular extent (rad) of the flat sector that closes into [`Case::GcmCone`]: `2π sin α`.
pub fn gcm_cone_sweep() -> Real {
    2.0 * std::f64::consts::PI * gcm_cone_half_angle().sin()
}

/// Inner and outer radius of [`Case::GcmCone`]'s sector.
pub const GCM_CONE_RADII: [Real; 2] = [1.0, 1.4];

/// Strain mismatch Δε between the layers of [`Case::BilayerStrip`].
pub const BILAYER_STRAIN: Real = 0.002;
/// Total thickness h of [`Case::BilayerStrip`] (m).
pub const BILAYER_THICKNESS: Real = 0.002;
/// Length and width of [`Case::BilayerStrip`] (m).
pub const BILAYER_SIZE: [Real; 2] = [1.0, 0.1];

/// Timoshenko's curvature of a bimetal strip of two equal layers, `3Δε/(2h)` (1/m).
pub fn timoshenko_curvature(strain: Real, thickness: Real) -> Real {
    1.5 * strain / thickness
}

/// `(ā11, b̄11)` of [`Case::BilayerStrip`].
fn bilayer_forms() -> (Real, Real) {
    let (gp, gm) = (
        (1.0 + 0.5 * BILAYER_STRAIN).powi(2),
        (1.0 - 0.5 * BILAYER_STRAIN).powi(2),
    );
    (0.5 * (gp + gm), 0.75 / BILAYER_THICKNESS * (gp - gm))
}

/// Polar angle in [0, 2π) (a point on the θ = 0 side may round to a tiny negative angle).
fn polar_angle(x: Real, y: Real) -> Real {
    let t = y.atan2(x);
    if t < -1e-12 {
        t + 2.0 * std::f64::consts::PI
    } else {
        t.max(0.0)
    }
}

/// Azimuthal stretch of [`Case::Cone`] (its radial stretch is 1).
pub const CONE_LAMBDA_THETA: Real = 0.8;

impl Case {
    /// All cases.
    pub const ALL: [Case; 9] = [
        Case::EnlargedSquare,
        Case::SphericalCap,
        Case::Hyperboloid,
        Case::Rhombus,
        Case::Cylinder,
        Case::Cone,
        Case::GcmCone,
        Case::BilayerStrip,
        Case::ConformalCap,
    ];

    /// Whether the mirror image (z → −z) of the exact shape is equally exact (b̄ = 0).
    pub fn mirror_symmetric(self) -> bool {
        matches!(self, Case::EnlargedSquare | Case::Rhombus | Case::Cone)
    }

    /// Name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Case::EnlargedSquare => "enlarged_square",
            Case::SphericalCap => "spherical_cap",
            Case::Hyperboloid => "hyperboloid",
            Case::Rhombus => "rhombus",
            Case::Cylinder => "cylinder",
            Case::Cone => "cone",
            Case::GcmCone => "gcm_cone",
            Case::BilayerStrip => "bilayer_strip",
            Case::ConformalCap => "conformal_cap",
        }
    }

    /// Parses a name.
    pub fn from_name(s: &str) -> Option<Case> {
        Case::ALL.into_iter().find(|c| c.name() == s)
    }

    /// Target forms `(ā, b̄)` at reference point (x, y), as `[xx, xy, yy]`.
    pub fn forms(self, x: Real, y: Real) -> (Sym2, Sym2) {
        match self {
            Case::EnlargedSquare => (Sym2::new(4.0, 0.0, 4.0), Sym2::zeros()),
            Case::SphericalCap => {
                let d = 1.0 - x * x - y * y;
                let a = Sym2::new(1.0 - y * y, x * y, 1.0 - x * x) / d;
                (a, a)
            }
            Case::Hyperboloid => (
                Sym2::new(1.0 + x * x, -x * y, 1.0 + y * y),
                Sym2::new(-1.0, 0.0, 1.0) / (1.0 + x * x + y * y).sqrt(),
            ),
            Case::Rhombus => (Sym2::new(2.0, 1.0, 2.0), Sym2::zeros()),
            Case::Cylinder => (Sym2::new(1.0, 0.0, 1.0), Sym2::new(1.0, 0.0, 0.0)),
            Case::Cone => {
                let r = (x * x + y * y).sqrt().max(1e-300);
                let (c, s) = (x / r, y / r);
                let l2 = CONE_LAMBDA_THETA * CONE_LAMBDA_THETA;
                // r̂r̂ᵀ + λ_θ² θ̂θ̂ᵀ, θ̂ = (−s, c).
                (
                    Sym2::new(c * c + l2 * s * s, c * s * (1.0 - l2), s * s + l2 * c * c),
                    Sym2::zeros(),
                )
            }
            Case::GcmCone => {
                let r = (x * x + y * y).sqrt().max(1e-300);
                let (c, s) = (x / r, y / r);
                // θ̂θ̂ᵀ / (2r), θ̂ = (−s, c).
                (
                    Sym2::new(1.0, 0.0, 1.0),
                    Sym2::new(s * s, -s * c, c * c) / (2.0 * r),
                )
            }
            Case::BilayerStrip => {
                let (a11, b11) = bilayer_forms();
                (Sym2::new(a11, 0.0, 1.0), Sym2::new(b11, 0.0, 0.0))
            }
            Case::ConformalCap => {
                let eta = 1.0 / (1.0 + 0.25 * (x * x + y * y));
                let a = Sym2::new(1.0, 0.0, 1.0) * (eta * eta);
                (a, a)
            }
        }
    }

    /// The exact position of material point (x, y).
    pub fn exact(self, x: Real, y: Real) -> Vec3 {
        match self {
            Case::EnlargedSquare => Vec3::new(2.0 * x, 2.0 * y, 0.0),
            Case::SphericalCap => Vec3::new(x, y, (1.0 - x * x - y * y).sqrt()),
            Case::Hyperboloid => Vec3::new(x, y, 0.5 * (x * x - y * y)),
            Case::Rhombus => {
                let f = sqrt_spd(&sym_to_mat(&Sym2::new(2.0, 1.0, 2.0)));
                let p = f * crate::math::Vec2::new(x, y);
                Vec3::new(p.x, p.y, 0.0)
            }
            Case::Cylinder => Vec3::new(x.sin(), y, x.cos() - 1.0),
            Case::Cone => {
                // Distance from the apex along a generator is r (λ_r = 1); the circle of radius
                // r has radius λ_θ r, so sin φ = λ_θ and the height is r cos φ.
                let r = (x * x + y * y).sqrt();
                let cos_phi = (1.0 - CONE_LAMBDA_THETA * CONE_LAMBDA_THETA).sqrt();
                Vec3::new(CONE_LAMBDA_THETA * x, CONE_LAMBDA_THETA * y, -r * cos_phi)
            }
            Case::GcmCone => {
                let r = (x * x + y * y).sqrt();
                let (sa, ca) = gcm_cone_half_angle().sin_cos();
                let psi = polar_angle(x, y) / sa;
                Vec3::new(r * sa * psi.cos(), r * sa * psi.sin(), -r * ca)
            }
            Case::ConformalCap => {
                // Inverse stereographic projection from the south pole, scaled so that the
                // metric is (1 + ρ²/4)⁻² |dx|²: the unit sphere, the centre at the north pole.
                let q = 1.0 + 0.25 * (x * x + y * y);
                Vec3::new(x / q, y / q, (1.0 - 0.25 * (x * x + y * y)) / q)
            }
            Case::BilayerStrip => {
                // Arc length λx with λ = √ā11, curvature κ = b̄11/ā11 in arc length.
                let (a11, b11) = bilayer_forms();
                let (lam, k) = (a11.sqrt(), b11 / a11);
                let t = k * lam * x;
                Vec3::new(t.sin() / k, y, (t.cos() - 1.0) / k)
            }
        }
    }

    /// Exact mean and Gauss curvature at (x, y) of the exact shape (normal-side convention).
    pub fn exact_curvatures(self, x: Real, y: Real) -> (Real, Real) {
        if self == Case::Cone {
            // The parallel through (x, y) has radius ρ = r sin φ; its normal curvature is
            // cos φ / ρ (the other principal curvature is 0). The exact map opens toward +z,
            // away from where the normal side bulges: negative.
            let r = (x * x + y * y).sqrt();
            let sin_phi = CONE_LAMBDA_THETA;
            let cos_phi = (1.0 - sin_phi * sin_phi).sqrt();
            return (-0.5 * cos_phi / (r * sin_phi), 0.0);
        }
        let (a, b) = self.forms(x, y);
        let s = sym_to_mat(&a).try_inverse().unwrap_or_else(Mat2::zeros) * sym_to_mat(&b);
        (0.5 * s.trace(), s.determinant())
    }

    /// Writes this case's target forms into a mesh as `abar_info`, `bbar_info`.
    ///
    /// Each face's tensors are built edge by edge so that they are second-order consistent: the
    /// barycentric entries `M(e, e)` for the face's three edge vectors `e` are sampled at the
    /// edge midpoints (`ā(e, e)` is then the squared rest length of that edge to O(ℓ⁴)), and the
    /// tensor is pushed forward to reference Cartesian coordinates. Sampling all entries at the
    /// centroid is only first-order consistent, which leaves an O(ℓ) shape error at corners.
    pub fn program(self, mesh: &mut Mesh) {
        let nf = mesh.faces.len();
        if self == Case::BilayerStrip {
            // b̄ depends on the thickness: write it with the forms.
            mesh.face_fields.insert(
                "ref_thicknesses".into(),
                Field::scalar(vec![BILAYER_THICKNESS; nf]),
            );
        }
        let mut a = Vec::with_capacity(3 * nf);
        let mut b = Vec::with_capacity(3 * nf);
        for f in 0..nf {
            let t = crate::rest::reference_frame(mesh, f);
            let bary = |k: usize| {
                crate::rest::sample_on_edges(mesh, f, |x, y| {
                    let (fa, fb) = self.forms(x, y);
                    if k == 0 {
                        fa
                    } else {
                        fb
                    }
                })
            };
            a.extend_from_slice(crate::rest::push_forward(&t, &bary(0)).as_slice());
            b.extend_from_slice(crate::rest::push_forward(&t, &bary(1)).as_slice());
        }
        mesh.face_fields
            .insert("abar_info".into(), Field::triples(a));
        mesh.face_fields
            .insert("bbar_info".into(), Field::triples(b));
    }
}

fn sqrt_spd(m: &Mat2) -> Mat2 {
    let e = nalgebra::SymmetricEigen::new(*m);
    let d = Mat2::from_diagonal(&e.eigenvalues.map(|l| l.max(0.0).sqrt()));
    e.eigenvectors * d * e.eigenvectors.transpose()
}

/// Errors of a simulated shape against the exact one, after the best rigid alignment.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ShapeError {
    /// Largest distance between a vertex and its exact material point (m).
    pub max: Real,
    /// Root-mean-square of those distances (m).
    pub rms: Real,
    /// Size of the exact shape: the largest extent of its bounding box (m).
    pub size: Real,
    /// `max / size`.
    pub max_rel: Real,
    /// `rms / size`.
    pub rms_rel: Real,
    /// Vertex with the largest error.
    pub worst_vertex: usize,
    /// Its reference position.
    pub worst_reference: [Real; 3],
}

/// Best rotation R and translation t with `R p + t ≈ q` in the least-squares sense (Kabsch,
/// proper rotations only). Returns the aligned points.
pub fn align(p: &[Vec3], q: &[Vec3]) -> Vec<Vec3> {
    let n = p.len() as Real;
    let cp = p.iter().sum::<Vec3>() / n;
    let cq = q.iter().sum::<Vec3>() / n;
    let mut h = Mat3::zeros();
    for (a, b) in p.iter().zip(q) {
        h += (a - cp) * (b - cq).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = (
        svd.u.unwrap_or_else(Mat3::identity),
        svd.v_t.unwrap_or_else(Mat3::identity),
    );
    let mut d = Mat3::identity();
    if (vt.transpose() * u.transpose()).determinant() < 0.0 {
        d[(2, 2)] = -1.0;
    }
    let r = vt.transpose() * d * u.transpose();
    p.iter().map(|a| r * (a - cp) + cq).collect()
}

/// Material-point error of `x` (simulated positions of the reference vertices `reference`)
/// against the exact shape of `case`.
pub fn shape_error(case: Case, reference: &[Vec3], x: &[Vec3]) -> ShapeError {
    let e = shape_error_against(case, reference, x, false);
    if case.mirror_symmetric() {
        let m = shape_error_against(case, reference, x, true);
        if m.max < e.max {
            return m;
        }
    }
    e
}

fn mirrored(x: &[Vec3], mirror: bool) -> Vec<Vec3> {
    x.iter()
        .map(|p| {
            if mirror {
                Vec3::new(p.x, p.y, -p.z)
            } else {
                *p
            }
        })
        .collect()
}

fn shape_error_against(case: Case, reference: &[Vec3], x: &[Vec3], mirror: bool) -> ShapeError {
    let x = &mirrored(x, mirror)[..];
    let exact: Vec<Vec3> = reference.iter().map(|p| case.exact(p.x, p.y)).collect();
    let aligned = align(x, &exact);
    let mut max: Real = 0.0;
    let mut worst = 0;
    let mut sum = 0.0;
    for (i, (a, e)) in aligned.iter().zip(&exact).enumerate() {
        let d = (a - e).norm();
        if d > max {
            max = d;
            worst = i;
        }
        sum += d * d;
    }
    let rms = (sum / x.len() as Real).sqrt();
    let mut lo = Vec3::repeat(Real::INFINITY);
    let mut hi = Vec3::repeat(Real::NEG_INFINITY);
    for e in &exact {
        lo = lo.inf(e);
        hi = hi.sup(e);
    }
    let size = (hi - lo).max();
    ShapeError {
        max,
        rms,
        size,
        max_rel: max / size,
        rms_rel: rms / size,
        worst_vertex: worst,
        worst_reference: reference[worst].into(),
    }
}

/// RMS over faces of the error in mean and Gauss curvature, using the discrete mid-edge forms
/// of the simulated shape against the exact values at the reference centroids (seed 000's
/// measure for the hyperboloid). Returns (H error, K error), in 1/m and 1/m².
pub fn curvature_error(
    case: Case,
    mesh: &Mesh,
    topo: &crate::mesh::Topology,
    x: &[Vec3],
) -> (Real, Real) {
    let e = curvature_error_signed(case, mesh, topo, x, 1.0);
    if case.mirror_symmetric() {
        // The mirror image has the opposite mean curvature.
        let m = curvature_error_signed(case, mesh, topo, x, -1.0);
        if m.0 < e.0 {
            return m;
        }
    }
    e
}

fn curvature_error_signed(
    case: Case,
    mesh: &Mesh,
    topo: &crate::mesh::Topology,
    x: &[Vec3],
    sign: Real,
) -> (Real, Real) {
    let (a, b) = crate::rest::mesh_forms(x, mesh, topo);
    let mut eh = 0.0;
    let mut ek = 0.0;
    for f in 0..mesh.faces.len() {
        let [p, q, r] = mesh.face_positions(f);
        let c = (p + q + r) / 3.0;
        let (h, k, _, _) = crate::geometry::curvatures(&a[f], &b[f]);
        let (he, ke) = case.exact_curvatures(c.x, c.y);
        eh += (h - sign * he).powi(2);
        ek += (k - ke).powi(2);
    }
    let n = mesh.faces.len() as Real;
    ((eh / n).sqrt(), (ek / n).sqrt())
}

/// Closest point to `p` on triangle `(a, b, c)` (Ericson, Real-Time Collision Detection §5.1.5).
pub fn closest_point_on_triangle(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Distance from `p` to the exact surface of `case` over the reference domain bounding box
/// `[lo, hi]`, by projected Gauss–Newton on the parameters starting from `(u0, v0)`.
fn distance_to_exact(
    case: Case,
    p: &Vec3,
    u0: Real,
    v0: Real,
    lo: [Real; 2],
    hi: [Real; 2],
) -> Real {
    let (mut u, mut v) = (u0, v0);
    let h = 1e-6;
    for _ in 0..30 {
        let s = case.exact(u, v);
        let su = (case.exact(u + h, v) - case.exact(u - h, v)) / (2.0 * h);
        let sv = (case.exact(u, v + h) - case.exact(u, v - h)) / (2.0 * h);
        let r = s - p;
        let m = Mat2::new(su.dot(&su), su.dot(&sv), su.dot(&sv), sv.dot(&sv));
        let g = crate::math::Vec2::new(su.dot(&r), sv.dot(&r));
        let Some(mi) = m.try_inverse() else { break };
        let d = mi * g;
        let (nu, nv) = ((u - d.x).clamp(lo[0], hi[0]), (v - d.y).clamp(lo[1], hi[1]));
        let moved = (nu - u).abs() + (nv - v).abs();
        u = nu;
        v = nv;
        if moved < 1e-14 {
            break;
        }
    }
    (case.exact(u, v) - p).norm()
}

/// Two-sided Hausdorff distance (m) between the simulated surface and the exact one, after the
/// material-point rigid alignment of [`align`]. Simulated → exact: vertices, edge midpoints and
/// face centroids projected onto the exact surface. Exact → simulated: the exact images of the
/// reference vertices and face centroids, to the nearest simulated triangle among the material
/// face's neighbours. It includes the chord error of flat triangles on a curved surface, so it
/// can exceed the vertex material-point error slightly, and is usually below it.
pub fn hausdorff(case: Case, mesh: &Mesh, topo: &crate::mesh::Topology, x: &[Vec3]) -> Real {
    let d = hausdorff_against(case, mesh, topo, &mirrored(x, false));
    if case.mirror_symmetric() {
        // A reflection reverses orientation: compare the mirrored shape.
        return d.min(hausdorff_against(case, mesh, topo, &mirrored(x, true)));
    }
    d
}

fn hausdorff_against(case: Case, mesh: &Mesh, topo: &crate::mesh::Topology, x: &[Vec3]) -> Real {
    let reference = &mesh.positions;
    let exact: Vec<Vec3> = reference.iter().map(|p| case.exact(p.x, p.y)).collect();
    let y = align(x, &exact);
    let mut lo = [Real::INFINITY; 2];
    let mut hi = [Real::NEG_INFINITY; 2];
    for p in reference {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    let mut d: Real = 0.0;
    // Simulated → exact.
    for face in &mesh.faces {
        let [i, j, k] = *face;
        let samples = [
            (y[i], reference[i]),
            ((y[i] + y[j]) / 2.0, (reference[i] + reference[j]) / 2.0),
            ((y[i] + y[k]) / 2.0, (reference[i] + reference[k]) / 2.0),
            (
                (y[i] + y[j] + y[k]) / 3.0,
                (reference[i] + reference[j] + reference[k]) / 3.0,
            ),
        ];
        for (p, r) in samples {
            d = d.max(distance_to_exact(case, &p, r.x, r.y, lo, hi));
        }
    }
    // Exact → simulated.
    let mut vertex_faces: Vec<Vec<usize>> = vec![Vec::new(); reference.len()];
    for (f, face) in mesh.faces.iter().enumerate() {
        for &v in face {
            vertex_faces[v].push(f);
        }
    }
    let near = |f: usize, out: &mut Vec<usize>| {
        out.push(f);
        for &g in &topo.face_neighbors[f] {
            if g != crate::mesh::topology::NONE {
                out.push(g);
            }
        }
    };
    let mut cand = Vec::new();
    let dist_to_faces = |p: &Vec3, faces: &[usize]| -> Real {
        faces
            .iter()
            .map(|&g| {
                let [a, b, c] = mesh.faces[g];
                (closest_point_on_triangle(p, &y[a], &y[b], &y[c]) - p).norm()
            })
            .fold(Real::INFINITY, Real::min)
    };
    for (v, fs) in vertex_faces.iter().enumerate() {
        cand.clear();
        for &f in fs {
            near(f, &mut cand);
        }
        d = d.max(dist_to_faces(&exact[v], &cand));
    }
    for (f, face) in mesh.faces.iter().enumerate() {
        let c = (reference[face[0]] + reference[face[1]] + reference[face[2]]) / 3.0;
        cand.clear();
        near(f, &mut cand);
        d = d.max(dist_to_faces(&case.exact(c.x, c.y), &cand));
    }
    d
}
