//! MorphoShell's quadratic patch-fit second fundamental form (seed 001 §2).
//!
//! Per face: its 3 vertices and 3 nearby nodes, all 6 in the flat reference plane. The quadratic
//! `R(x, y) = c0 + c1 x + c2 y + c3 x² + c4 xy + c5 y²` interpolating the 6 current positions has
//! `∂αβR = Σ_k W_αβ,k x_k`, with weights from the inverse of the 6×6 fit matrix, computed once in
//! the reference state. Then `b_αβ = −N·∂αβR` (N the face's unit normal), which is `a/R` on a
//! sphere of radius R with outward normals, shellsim's convention. Pulled back to the face's
//! barycentric frame, `b = Ŵ`-weighted: `b_q = −N·s_q`, `s_q = Σ_k Ŵ_qk x_k`.
//!
//! DOF order (18): `x[v0], x[v1], x[v2], x[n0], x[n1], x[n2]` (face vertices, patch nodes).

use super::{BendingEval, BendingModel};
use crate::body::Body;
use crate::energy::material::FaceDensity;
use crate::geometry::UnitNormal;
use crate::math::{Mat3, Real, SMat, SVec, Sym2, Vec3};

pub use crate::body::patch::{
    build_patches, patch_b, Patch, PatchWeights, GOOD_CONDITION, MAX_CONDITION,
};

/// Energy (J) of one face with patch-fit bending under density `dens`, optional gradient (N)
/// and Hessian (N/m) in the DOF order of the module doc, through the one shell chain rule
/// ([`crate::energy::shell::shell_element`]). With `GN`, the Hessian is the Gauss–Newton part.
pub fn patch_face<D: FaceDensity, const GN: bool>(
    x: &[Vec3; 6],
    w: &PatchWeights,
    dens: &D,
    grad: Option<&mut SVec<18>>,
    hess: Option<&mut SMat<18, 18>>,
) -> Real {
    crate::energy::shell::shell_element::<D, PatchFit, 18, 6, GN>(&PatchFit, w, x, dens, grad, hess)
}

/// MorphoShell's patch-fit model; the per-face input is the face's weights `Ŵ`.
#[derive(Clone, Copy, Debug, Default)]
pub struct PatchFit;

/// What the gradient and the Hessian contraction need: the light data (the unit normal `N`,
/// twice the area `r = |c|`, the edge vectors `e_a` opposite each face vertex, `∂c/∂x_a =
/// [e_a]×`, and the weighted sums `s_q`), and the normal's full Jacobian when a Hessian is
/// wanted.
pub struct PatchCache {
    light: PatchLight,
    full: Option<UnitNormal>,
}

/// [`BendingModel::light`]'s data: the unit normal, twice the area, the edges opposite each
/// vertex and the weighted sums `s_q`.
pub struct PatchLight {
    n: Vec3,
    r: Real,
    e: [Vec3; 3],
    s: [Vec3; 3],
}

/// `Σ_q W_b,q ∇b_q` (see [`BendingModel::add_gradient`] of [`PatchFit`]).
#[inline(always)]
fn patch_gradient(
    w: &PatchWeights,
    n: &Vec3,
    r: Real,
    e: &[Vec3; 3],
    s: &[Vec3; 3],
    wb: &Sym2,
    g: &mut SVec<18>,
) {
    let lam = s[0] * wb[0] + s[1] * wb[1] + s[2] * wb[2];
    let mu = (lam - n * n.dot(&lam)) / r;
    for a in 0..3 {
        let v = e[a].cross(&mu);
        for c in 0..3 {
            g[3 * a + c] += v[c];
        }
    }
    for k in 0..6 {
        let wk = wb[0] * w[(0, k)] + wb[1] * w[(1, k)] + wb[2] * w[(2, k)];
        for c in 0..3 {
            g[3 * k + c] -= wk * n[c];
        }
    }
}

impl BendingModel<18, 6> for PatchFit {
    type Face = PatchWeights;
    type Cache = PatchCache;
    const NAME: &'static str = "patch_fit";
    type Light = PatchLight;

    /// `b_q = −N·s_q` with the normal, twice the area, the edges and `s_q`: nothing else.
    #[inline(always)]
    fn light(&self, w: &PatchWeights, x: &[Vec3; 6]) -> (Sym2, PatchLight) {
        let c = (x[1] - x[0]).cross(&(x[2] - x[0]));
        let r = c.norm();
        let n = c / r;
        let s: [Vec3; 3] = std::array::from_fn(|q| {
            let mut acc = x[0] * w[(q, 0)];
            for k in 1..6 {
                acc += x[k] * w[(q, k)];
            }
            acc
        });
        let b = Sym2::new(-n.dot(&s[0]), -n.dot(&s[1]), -n.dot(&s[2]));
        (
            b,
            PatchLight {
                n,
                r,
                e: [x[2] - x[1], x[0] - x[2], x[1] - x[0]],
                s,
            },
        )
    }

    /// As [`BendingModel::add_gradient`], from the light data.
    #[inline(always)]
    fn add_gradient_light(&self, w: &PatchWeights, l: &PatchLight, wb: &Sym2, g: &mut SVec<18>) {
        patch_gradient(w, &l.n, l.r, &l.e, &l.s, wb, g);
    }

    #[inline(always)]
    fn face(&self, body: &Body, f: usize, _: &[usize], _: &[Real]) -> PatchWeights {
        body.patches[f].weights
    }

    /// `b_q = −N·s_q`; with a Hessian, also `G = ∇b` (node k gets `−Ŵ_qk N`; face vertex a
    /// also gets `−(∂N/∂x_a)ᵀ s_q`). A gradient alone needs no `G`: see
    /// [`BendingModel::add_gradient`] below.
    #[inline(always)]
    fn eval(
        &self,
        w: &PatchWeights,
        x: &[Vec3; 6],
        _grad: bool,
        hess: bool,
    ) -> BendingEval<18, PatchCache> {
        let (b, light) = self.light(w, x);
        let (n, s) = (light.n, light.s);
        let full = hess.then(|| UnitNormal::new(&[x[0], x[1], x[2]]));
        let jac = full.as_ref().map(|nf| {
            let mut jac = SMat::<18, 3>::zeros();
            for q in 0..3 {
                for k in 0..6 {
                    for c in 0..3 {
                        jac[(3 * k + c, q)] -= w[(q, k)] * n[c];
                    }
                }
                for av in 0..3 {
                    let v = nf.dn[av].transpose() * s[q];
                    for c in 0..3 {
                        jac[(3 * av + c, q)] -= v[c];
                    }
                }
            }
            jac
        });
        BendingEval {
            b,
            jac,
            cache: PatchCache { light, full },
        }
    }

    /// `Σ_q W_b,q ∇b_q` without forming `G`: node k gets `−(Σ_q W_b,q Ŵ_qk) N`, and with
    /// `λ = Σ_q W_b,q s_q` and `μ = (I − N Nᵀ) λ / r`, face vertex a gets
    /// `−(∂N/∂x_a)ᵀ λ = −[e_a]×ᵀ μ = e_a × μ`.
    #[inline(always)]
    fn add_gradient(
        &self,
        w: &PatchWeights,
        ev: &BendingEval<18, PatchCache>,
        wb: &Sym2,
        g: &mut SVec<18>,
    ) {
        self.add_gradient_light(w, &ev.cache.light, wb, g);
    }

    /// `∇²b_q`: the cross blocks `−Ŵ_qk ∂N/∂x_a` (node k, face vertex a) and their transposes,
    /// and `−∇²(s_q·N)` with `s_q` fixed on the face vertices.
    #[inline(always)]
    fn add_hessian(
        &self,
        w: &PatchWeights,
        _: &[Vec3; 6],
        ev: &BendingEval<18, PatchCache>,
        lambda: &Sym2,
        h: &mut SMat<18, 18>,
    ) {
        let PatchCache { full, light } = &ev.cache;
        let s = &light.s;
        let Some(nf) = full else {
            return; // evaluated without a Hessian
        };
        let lam: Vec3 = s.iter().zip(lambda.iter()).map(|(sq, g)| sq * *g).sum();
        let hn = nf.hessian_contract(&lam);
        let mut top = h.fixed_view_mut::<9, 9>(0, 0);
        top -= hn;
        for k in 0..6 {
            let wk: Real = (0..3).map(|q| lambda[q] * w[(q, k)]).sum();
            if wk == 0.0 {
                continue;
            }
            for av in 0..3 {
                let blk: Mat3 = -nf.dn[av] * wk; // ∂²/∂x_k ∂x_a
                let mut dst = h.fixed_view_mut::<3, 3>(3 * k, 3 * av);
                dst += blk;
                let mut dst_t = h.fixed_view_mut::<3, 3>(3 * av, 3 * k);
                dst_t += blk.transpose();
            }
        }
    }
}
