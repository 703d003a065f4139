//! Bending models: discrete second fundamental forms `b(x)` of one face, one file each.
//!
//! A model gives `b` (barycentric, `[b11, b12, b22]`, m) over an `N`-DOF face stencil whose first
//! 9 DOFs are the face's own vertices, its Jacobian `G = ∂b/∂x` (column `q` is `∇b_q`, N×3) and
//! the contraction `Σ_q λ_q ∇²b_q`. The one chain rule that composes it with any membrane
//! material is [`crate::energy::shell::shell_element`].
//!
//! * [`average`]: seed 000's mid-edge average normals (18 DOFs).
//! * [`patch`]: MorphoShell's quadratic patch fit (seed 001 §2, 18 DOFs).
//! * [`midedge_angle`]: mid-edge normals with one rotation DOF per edge (21 DOFs).
//! * [`none`]: no bending at all, a pure membrane (9 DOFs).
//!
//! Stencil slots (all models): `[v0, v1, v2, p0, p1, p2, e0, e1, e2]` truncated to the model's
//! size, `p_i` the model's extra vertex for edge `i` (the neighbour's far vertex, or patch node
//! `i`), `e_i` the edge opposite `v_i`.

pub mod average;
pub mod midedge_angle;
pub mod none;
pub mod patch;

use crate::body::Body;
use crate::math::{Real, SMat, SVec, Sym2, Vec3};

/// `b` of one face with its Jacobian and what its Hessian contraction needs.
pub struct BendingEval<const N: usize, C> {
    /// The second fundamental form (m).
    pub b: Sym2,
    /// `G = ∂b/∂x` (column q is `∇b_q`), filled when a gradient was asked for, by models that
    /// use the default [`BendingModel::add_gradient`] (a model that overrides it may leave it 0).
    pub jac: Option<SMat<N, 3>>,
    /// Scratch kept for [`BendingModel::add_hessian`].
    pub cache: C,
}

/// A discrete second fundamental form over `N` local DOFs in `S` stencil slots (3, 6 or 9).
pub trait BendingModel<const N: usize, const S: usize>: Send + Sync {
    /// Per-face input (boundary flags, weights, edge DOFs and signs).
    type Face;
    /// Scratch between [`BendingModel::eval`] and [`BendingModel::add_hessian`].
    type Cache;
    /// The bending model's name (settings value).
    const NAME: &'static str;

    /// The per-face input of face `f` with stencil `nodes` and global edge DOFs `phi`.
    fn face(&self, body: &Body, f: usize, nodes: &[usize], phi: &[Real]) -> Self::Face;

    /// `b` at stencil positions `x` (slots 0..6; unused slots hold the face's first vertex);
    /// `G` when `grad`, the Hessian scratch when `hess`.
    fn eval(
        &self,
        face: &Self::Face,
        x: &[Vec3; 6],
        grad: bool,
        hess: bool,
    ) -> BendingEval<N, Self::Cache>;

    /// What [`BendingModel::add_gradient_light`] needs besides `b` (a model without a cheaper
    /// gradient keeps its whole [`BendingEval`]).
    type Light;

    /// `b` and the data of a gradient without `G` (the explicit dynamics' path: no Hessian).
    fn light(&self, face: &Self::Face, x: &[Vec3; 6]) -> (Sym2, Self::Light);

    /// Adds `Σ_q W_b,q ∇b_q` from [`BendingModel::light`]'s data.
    fn add_gradient_light(
        &self,
        face: &Self::Face,
        light: &Self::Light,
        wb: &Sym2,
        g: &mut SVec<N>,
    );

    /// Adds `Σ_q λ_q ∇²b_q` to `h`.
    fn add_hessian(
        &self,
        face: &Self::Face,
        x: &[Vec3; 6],
        ev: &BendingEval<N, Self::Cache>,
        lambda: &Sym2,
        h: &mut SMat<N, N>,
    );

    /// Adds the bending part of the gradient, `G W_b`.
    #[inline(always)]
    fn add_gradient(
        &self,
        _face: &Self::Face,
        ev: &BendingEval<N, Self::Cache>,
        wb: &Sym2,
        g: &mut SVec<N>,
    ) {
        if let Some(j) = &ev.jac {
            *g += j * wb;
        }
    }

    /// Adds the bending part of the chain rule, `G W_bb Gᵀ` and, with `lambda = Some(W_b)`,
    /// `Σ_q λ_q ∇²b_q`. A model may override it to form both in its own intermediate variables
    /// with one product (the default forms them apart).
    #[inline(always)]
    fn add_bending_hessian(
        &self,
        face: &Self::Face,
        x: &[Vec3; 6],
        ev: &BendingEval<N, Self::Cache>,
        hbb: &crate::math::Mat3,
        lambda: Option<&Sym2>,
        h: &mut SMat<N, N>,
    ) {
        if let Some(j) = &ev.jac {
            *h += j * hbb * j.transpose();
        }
        if let Some(l) = lambda {
            self.add_hessian(face, x, ev, l, h);
        }
    }

    /// Sets `h` to the membrane and bending parts of the chain rule at once,
    /// `Jaᵀ W_aa Ja + G W_bb Gᵀ` and, with `lambda = Some(W_b)`, `Σ_q λ_q ∇²b_q`, when the model
    /// can form them in its own intermediate variables with one product; returns `false` (and
    /// leaves `h` alone) when it cannot, and the caller forms them apart. `Ja` is the Jacobian of
    /// `a` on the first 9 DOFs.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn set_shell_hessian(
        &self,
        _face: &Self::Face,
        _x: &[Vec3; 6],
        _ev: &BendingEval<N, Self::Cache>,
        _haa: &crate::math::Mat3,
        _hbb: &crate::math::Mat3,
        _lambda: Option<&Sym2>,
        _h: &mut SMat<N, N>,
    ) -> bool {
        false
    }
}

/// Whether stencil slots 3..6 (the extra vertices) are present.
#[inline]
pub fn has_extra(nodes: &[usize]) -> [bool; 3] {
    use crate::mesh::topology::NONE;
    [nodes[3] != NONE, nodes[4] != NONE, nodes[5] != NONE]
}

/// The light gradient path of a model that has none cheaper than its full evaluation: the
/// [`BendingModel::light`] and [`BendingModel::add_gradient_light`] bodies of such models.
#[macro_export]
macro_rules! light_via_eval {
    ($n:literal) => {
        type Light = $crate::energy::bending::BendingEval<$n, Self::Cache>;
        #[inline(always)]
        fn light(&self, face: &Self::Face, x: &[Vec3; 6]) -> (Sym2, Self::Light) {
            let ev = self.eval(face, x, true, false);
            (ev.b, ev)
        }
        #[inline(always)]
        fn add_gradient_light(
            &self,
            face: &Self::Face,
            light: &Self::Light,
            wb: &Sym2,
            g: &mut $crate::math::SVec<$n>,
        ) {
            self.add_gradient(face, light, wb, g);
        }
    };
}
