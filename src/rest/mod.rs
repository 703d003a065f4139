//! Rest fundamental forms per face (ā, b̄ in each face's barycentric coordinates, seed 000 §3)
//! and their dial from initial to target values.
//!
//! Growth and swelling laws ([`laws`], one file each) only ever rewrite a [`RestForms`]; kernels
//! never branch on them.

pub mod frame;
pub mod laws;

pub use frame::{
    barycentric_direction, pull_back, pulled_back_targets, push_forward, reference_frame,
    sample_on_edges, MAX_CURVATURE_TIMES_SIZE, MIN_METRIC,
};
pub use laws::lce;

use crate::geometry::{first_fundamental_form, midedge_average_b};
use crate::math::{Real, Sym2, Vec3};
use crate::mesh::{topology::NONE, Mesh, Topology};
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
