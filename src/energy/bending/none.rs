//! No bending: `b = 0` and no bending energy, a pure membrane (cloth, balloons).
//!
//! DOF order (9): `x[v0], x[v1], x[v2]`.

use super::{BendingEval, BendingModel};
use crate::body::Body;
use crate::math::{Real, SMat, Sym2, Vec3};

/// The pure-membrane "bending model".
#[derive(Clone, Copy, Debug, Default)]
pub struct NoBending;

impl BendingModel<9, 3> for NoBending {
    type Face = ();
    type Cache = ();
    const NAME: &'static str = "none";
    crate::light_via_eval!(9);

    fn face(&self, _: &Body, _: usize, _: &[usize], _: &[Real]) {}

    #[inline(always)]
    fn eval(&self, _: &(), _: &[Vec3; 6], _: bool, _: bool) -> BendingEval<9, ()> {
        BendingEval {
            b: Sym2::zeros(),
            jac: None,
            cache: (),
        }
    }

    #[inline(always)]
    fn add_hessian(
        &self,
        _: &(),
        _: &[Vec3; 6],
        _: &BendingEval<9, ()>,
        _: &Sym2,
        _: &mut SMat<9, 9>,
    ) {
    }
}
