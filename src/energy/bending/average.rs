//! Seed 000's mid-edge average second fundamental form (§3): `b = 2 [q0 + q1, q0; q0, q0 + q2]`
//! with `q_i` the offset of edge `i`'s average normal (see [`crate::geometry`]).
//!
//! DOF order (18): `x[v0], x[v1], x[v2], x[p0], x[p1], x[p2]`, where `p_i` is the far vertex of
//! the neighbour across the edge opposite `v_i`. On a boundary edge (`has[i] = false`) `q_i = 0`
//! and the `p_i` entries of the gradient and Hessian are zero.

use super::{has_extra, BendingEval, BendingModel};
use crate::body::Body;
use crate::geometry::{b_from_q, b_from_q_matrix, edge_slots, AverageQs, UnitNormal};
use crate::math::{Real, SMat, SVec, Sym2, Vec3};

/// The mid-edge average model.
#[derive(Clone, Copy, Debug, Default)]
pub struct MidedgeAverage;

/// What the Hessian contraction needs: the face normal and every edge's `q` derivatives.
pub struct AverageCache {
    nf: UnitNormal,
    qs: AverageQs,
}

impl BendingModel<18, 6> for MidedgeAverage {
    type Face = [bool; 3];
    type Cache = AverageCache;
    const NAME: &'static str = "midedge_average";
    crate::light_via_eval!(18);

    #[inline(always)]
    fn face(&self, _: &Body, _: usize, nodes: &[usize], _: &[Real]) -> [bool; 3] {
        has_extra(nodes)
    }

    /// `∇b = [∇q_0 ∇q_1 ∇q_2] Bᵀ` with `B = ∂b/∂q`.
    #[inline(always)]
    fn eval(
        &self,
        has: &[bool; 3],
        x: &[Vec3; 6],
        grad: bool,
        hess: bool,
    ) -> BendingEval<18, AverageCache> {
        let nf = UnitNormal::new(&[x[0], x[1], x[2]]);
        let qs = AverageQs::new(&nf, x, *has, hess);
        let b = b_from_q(&SVec::<3>::from(qs.q));
        let mut jac = SMat::<18, 3>::zeros();
        if grad {
            let mut gq = SMat::<18, 3>::zeros();
            for i in (0..3).filter(|&i| has[i]) {
                for (l, &s) in edge_slots(i).iter().enumerate() {
                    for c in 0..3 {
                        gq[(3 * s + c, i)] = qs.grad[i][3 * l + c];
                    }
                }
            }
            jac = gq * b_from_q_matrix().transpose();
        }
        BendingEval {
            b,
            jac: Some(jac),
            cache: AverageCache { nf, qs },
        }
    }

    /// `Σ_q λ_q ∇²b_q = Σ_i (Bᵀλ)_i ∇²q_i`.
    #[inline(always)]
    fn add_hessian(
        &self,
        has: &[bool; 3],
        _: &[Vec3; 6],
        ev: &BendingEval<18, AverageCache>,
        lambda: &Sym2,
        h: &mut SMat<18, 18>,
    ) {
        let mu = b_from_q_matrix().transpose() * lambda;
        ev.cache
            .qs
            .add_hessians(&ev.cache.nf, *has, [mu[0], mu[1], mu[2]], h);
    }
}
