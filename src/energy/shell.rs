//! The discrete Koiter shell face of seed 000 §3: stretching from the face's first fundamental
//! form, bending from the mid-edge-average second fundamental form (see [`crate::geometry`]).
//!
//! DOF order (18): `x[v0], x[v1], x[v2], x[p0], x[p1], x[p2]`, where `p_i` is the far vertex of
//! the neighbour across the edge opposite `v_i`. On a boundary edge (`has[i] = false`) `q_i = 0`
//! and the `p_i` entries of the gradient and Hessian are zero.

use super::material::{DensityDerivs, FaceDensity};
use crate::geometry::{
    b_from_q, b_from_q_matrix, edge_slots, first_fundamental_form,
    first_fundamental_form_hessian_pattern, first_fundamental_form_jacobian, AverageQs, UnitNormal,
};
use crate::math::{Real, SMat, SVec, Sym2, Vec3};

/// Fundamental forms of one face (for output and the damping term's previous state).
pub fn face_forms(x: &[Vec3; 6], has: [bool; 3]) -> (Sym2, Sym2) {
    let xf = [x[0], x[1], x[2]];
    let opp = [0, 1, 2].map(|i| has[i].then_some(x[3 + i]));
    (
        first_fundamental_form(&xf),
        crate::geometry::midedge_average_b(&xf, &opp),
    )
}

/// Energy (J) of one shell face under density `dens`, with optional gradient (+∂E/∂x, N) and
/// Hessian (N/m), 18 DOFs in the order of the module doc.
///
/// `E = W(a(x), b(x))` with `b = B q`; chain rule:
/// `∇E = Jaᵀ ∂W/∂a + Σ_i (Bᵀ∂W/∂b)_i ∇q_i`,
/// `∇²E = Jaᵀ W_aa Ja + Σ_k (∂W/∂a_k) ∇²a_k + G (Bᵀ W_bb B) Gᵀ + Σ_i (Bᵀ∂W/∂b)_i ∇²q_i`,
/// with `G = [∇q_0 ∇q_1 ∇q_2]`.
pub fn shell_face<D: FaceDensity>(
    x: &[Vec3; 6],
    has: [bool; 3],
    dens: &D,
    grad: Option<&mut SVec<18>>,
    hess: Option<&mut SMat<18, 18>>,
) -> Real {
    shell_face_impl::<D, false>(x, has, dens, grad, hess)
}

/// As [`shell_face`], but the Hessian is the Gauss–Newton part only,
/// `Jaᵀ W_aa Ja + G (Bᵀ W_bb B) Gᵀ`, dropping the terms with second derivatives of `a` and `q`.
/// For the Koiter density (`W_aa`, `W_bb` multiples of the positive semi-definite `C`) it is
/// positive semi-definite by construction: a descent direction without an eigendecomposition.
pub fn shell_face_gauss_newton<D: FaceDensity>(
    x: &[Vec3; 6],
    has: [bool; 3],
    dens: &D,
    grad: Option<&mut SVec<18>>,
    hess: Option<&mut SMat<18, 18>>,
) -> Real {
    shell_face_impl::<D, true>(x, has, dens, grad, hess)
}

#[inline(always)]
fn shell_face_impl<D: FaceDensity, const GN: bool>(
    x: &[Vec3; 6],
    has: [bool; 3],
    dens: &D,
    grad: Option<&mut SVec<18>>,
    hess: Option<&mut SMat<18, 18>>,
) -> Real {
    let xf = [x[0], x[1], x[2]];
    let a = first_fundamental_form(&xf);
    let bending = dens.uses_b();
    let want_h = hess.is_some();
    let want_g = grad.is_some() || want_h;
    let nf = UnitNormal::new(&xf);
    let qs = bending.then(|| AverageQs::new(&nf, x, has, want_h && !GN));
    let q = SVec::<3>::from(qs.map_or([0.0; 3], |qs| qs.q));
    let b = b_from_q(&q);
    let mut d = DensityDerivs::default();
    let e = dens.eval(&a, &b, &mut d);
    if !want_g {
        return e;
    }
    let ja = first_fundamental_form_jacobian(&xf);
    let bq = b_from_q_matrix();
    let gqv = bq.transpose() * d.gb; // ∂E/∂q
    let mut g = SVec::<18>::zeros();
    g.fixed_rows_mut::<9>(0).copy_from(&(ja.transpose() * d.ga));
    if let Some(qs) = &qs {
        for i in (0..3).filter(|&i| has[i]) {
            for (l, &s) in edge_slots(i).iter().enumerate() {
                for c in 0..3 {
                    g[3 * s + c] += gqv[i] * qs.grad[i][3 * l + c];
                }
            }
        }
    }
    if let Some(h) = hess {
        h.fill(0.0);
        let hm = ja.transpose() * d.haa * ja;
        h.fixed_view_mut::<9, 9>(0, 0).copy_from(&hm);
        if !GN {
            let pat = first_fundamental_form_hessian_pattern(&d.ga);
            for r in 0..3 {
                for s in 0..3 {
                    for c in 0..3 {
                        h[(3 * r + c, 3 * s + c)] += pat[(r, s)];
                    }
                }
            }
        }
        if let Some(qs) = &qs {
            let hqq = bq.transpose() * d.hbb * bq;
            let mut gmat = SMat::<18, 3>::zeros();
            for i in (0..3).filter(|&i| has[i]) {
                for (l, &s) in edge_slots(i).iter().enumerate() {
                    for c in 0..3 {
                        gmat[(3 * s + c, i)] = qs.grad[i][3 * l + c];
                    }
                }
            }
            *h += gmat * hqq * gmat.transpose();
            if !GN {
                qs.add_hessians(&nf, has, [gqv[0], gqv[1], gqv[2]], h);
            }
        }
    }
    e_and_grad(e, g, grad)
}

#[inline(always)]
fn e_and_grad(e: Real, g: SVec<18>, grad: Option<&mut SVec<18>>) -> Real {
    if let Some(gout) = grad {
        *gout = g;
    }
    e
}
