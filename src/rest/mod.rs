//! Rest fundamental forms per face (ā, b̄ in each face's barycentric coordinates, seed 000 §3)
//! and their dial from initial to target values.
//!
//! Growth and swelling laws ([`laws`], one file each) only ever rewrite a [`RestForms`]; kernels
//! never branch on them.

pub mod laws;
pub mod lce;

use crate::geometry::{first_fundamental_form, midedge_average_b};
use crate::math::{Mat2, Real, Sym2, Vec3};
use crate::mesh::{topology::NONE, Mesh, MeshError, Topology};
use crate::settings::DialOrder;

/// Initial (dial 0) and target (dial 1) rest forms per face.
#[derive(Clone, Debug)]
pub struct RestForms {
    /// ā at dial 0: the input mesh's first fundamental form a⁰ (m²).
    pub abar0: Vec<Sym2>,
    /// b̄ at dial 0: the input mesh's mid-edge second fundamental form b⁰ (m).
    pub bbar0: Vec<Sym2>,
    /// ā at dial 1 (m²).
    pub abar1: Vec<Sym2>,
    /// b̄ at dial 1 (m).
    pub bbar1: Vec<Sym2>,
    /// The order in which ā and b̄ are dialled.
    pub order: DialOrder,
    /// The director law per face, which dials ā through its stretch instead of linearly
    /// (empty without it; [`lce`]).
    pub lce: Vec<lce::LceFace>,
}

impl RestForms {
    /// No growth: target = initial = forms of the input mesh (seed 000 "No Growth").
    pub fn no_growth(mesh: &Mesh, topo: &Topology) -> Self {
        let (a0, b0) = mesh_forms(&mesh.positions, mesh, topo);
        RestForms {
            abar1: a0.clone(),
            bbar1: b0.clone(),
            abar0: a0,
            bbar0: b0,
            order: DialOrder::Together,
            lce: Vec::new(),
        }
    }

    /// The dials `(s_a, s_b)` of ā and b̄ at the overall dial `s ∈ [0, 1]`: both `s`, or with
    /// [`DialOrder::BbarFirst`] b̄ over `[0, ½]` and then ā over `[½, 1]`.
    #[inline]
    pub fn split(&self, s: Real) -> (Real, Real) {
        match self.order {
            DialOrder::Together => (s, s),
            DialOrder::BbarFirst => ((2.0 * s - 1.0).clamp(0.0, 1.0), (2.0 * s).min(1.0)),
        }
    }

    /// Rest forms at dial factor `s ∈ [0, 1]`: linear interpolation of each form at its own dial
    /// ([`Self::split`]), as MorphoShell's dial (convex combinations keep ā positive definite);
    /// under the director law ā follows its stretch instead ([`lce`]).
    #[inline]
    pub fn at(&self, f: usize, s: Real) -> (Sym2, Sym2) {
        if s >= 1.0 {
            return (self.abar1[f], self.bbar1[f]);
        }
        let (sa, sb) = self.split(s);
        let a = match self.lce.get(f) {
            Some(l) => l.metric(sa),
            None => self.abar0[f] * (1.0 - sa) + self.abar1[f] * sa,
        };
        (a, self.bbar0[f] * (1.0 - sb) + self.bbar1[f] * sb)
    }

    /// The rest thickness over the reference thickness at dial `s`, given its dial-1 value
    /// `r1` (from a growth law that scales the thickness): interpolated linearly with ā's dial.
    #[inline]
    pub fn thickness_ratio(&self, r1: Real, s: Real) -> Real {
        if s >= 1.0 {
            return r1;
        }
        let sa = self.split(s).0;
        (1.0 - sa) + r1 * sa
    }

    /// Number of faces.
    pub fn len(&self) -> usize {
        self.abar0.len()
    }

    /// True when there are no faces.
    pub fn is_empty(&self) -> bool {
        self.abar0.is_empty()
    }
}

/// First and mid-edge second fundamental forms of every face at `positions`.
pub fn mesh_forms(positions: &[Vec3], mesh: &Mesh, topo: &Topology) -> (Vec<Sym2>, Vec<Sym2>) {
    let mut a = Vec::with_capacity(mesh.faces.len());
    let mut b = Vec::with_capacity(mesh.faces.len());
    for (f, face) in mesh.faces.iter().enumerate() {
        let x = face.map(|v| positions[v]);
        let opp = topo.opposite_vertex[f].map(|v| (v != NONE).then(|| positions[v]));
        a.push(first_fundamental_form(&x));
        b.push(midedge_average_b(&x, &opp));
    }
    (a, b)
}

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
        let size = mesh.bbox_diagonal();
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
        b.push(pull_back(&t, &bbar_xy(f)));
    }
    Ok((a, b))
}
