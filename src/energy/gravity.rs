//! Gravity, a vertex term: `E = −Σ_v m_v g·x_v` (J) with the potential's lumped masses (kg)
//! and acceleration `g` (m/s²). Gradient `−m_v g` (N), no Hessian. DOF order: `x[v]`.

use super::term::VertexKernel;
use crate::energy::Potential;
use crate::math::{Mat3, Real, Vec3};

/// The gravity kernel.
pub struct Gravity;

impl VertexKernel for Gravity {
    const LOAD: bool = true;
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let g = pot.gravity;
        if g == Vec3::zeros() {
            return None;
        }
        let m = pot.mass[v];
        Some((-m * g.dot(x), -g * m, Mat3::zeros()))
    }
}
