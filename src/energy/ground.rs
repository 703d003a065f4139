//! The ground plane and its friction, two vertex terms over [`crate::contact::Ground`]
//! (formulas, units and smoothing there): the C² normal penalty `k A_v ψ(p)`, and the lagged,
//! smoothed Coulomb friction `μ λ f₀(‖slip‖)` (dynamics only, while the potential carries a
//! [`crate::energy::potential::Friction`]). DOF order: `x[v]`.

use super::term::VertexKernel;
use crate::energy::Potential;
use crate::math::{Mat3, Real, Vec3};

/// The normal contact kernel.
pub struct GroundContact;

/// The friction kernel.
pub struct GroundFriction;

#[inline]
fn mat(h: [[Real; 3]; 3]) -> Mat3 {
    Mat3::from_fn(|r, c| h[r][c])
}

impl VertexKernel for GroundContact {
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let (e, g, h) = pot.body.ground.as_ref()?.normal_term(v, x)?;
        Some((e, g, mat(h)))
    }
}

impl VertexKernel for GroundFriction {
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let ground = pot.body.ground.as_ref()?;
        let fr = pot.friction.as_ref()?;
        let lambda = fr.normal_force[v];
        if lambda <= 0.0 || ground.friction <= 0.0 {
            return None;
        }
        let (e, g, h) = ground.friction_term(lambda, x, &fr.x_prev[v], fr.eps);
        Some((e, g, mat(h)))
    }
}
