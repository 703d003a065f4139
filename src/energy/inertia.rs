//! Inertia of an implicit-Euler step (seed 000 §3), a vertex term:
//! `E = Σ_v m_v/(2Δt²) |x_v − x̂_v|²` with `x̂ = x_n + Δt v_n`; its minimiser with the other terms
//! satisfies `M(v_{n+1} − v_n)/Δt = F(x_{n+1})`. Units: J; gradient N; Hessian `m/Δt²` I (N/m).
//! Contributes only while the potential has an [`crate::energy::potential::Inertia`].

use super::term::VertexKernel;
use crate::energy::Potential;
use crate::math::{Mat3, Real, Vec3};

/// The inertia kernel.
pub struct InertiaTerm;

impl VertexKernel for InertiaTerm {
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let inr = pot.inertia.as_ref()?;
        let k = inr.inv_dt2 * pot.mass[v];
        let dx = x - inr.xhat[v];
        Some((0.5 * k * dx.norm_squared(), dx * k, Mat3::identity() * k))
    }
}
