//! External loads, one file each: dead point forces ([`point`]), dead tractions per unit length
//! on boundary edges ([`traction`]), follower pressure on faces ([`pressure`]) and distributed
//! moments along boundaries ([`moment`]). Every load is
//! scaled by the potential's dial, the load factor that the static driver dials adaptively
//! (like the rest forms) and the dynamic driver ramps over `rest.dial_time`.

pub mod moment;
pub mod point;
pub mod pressure;
pub mod traction;

use super::term::{Term, VertexKernel, VertexTerm};
use crate::math::{Mat3, Real, Vec3};

pub use crate::body::select::{faces_matching, select_faces, select_vertices};
use crate::energy::Potential;

/// Dead nodal forces `f_v` (N) at dial 1: `E = −s Σ_v f_v·x_v` at dial `s` (J); gradient
/// `−s f_v`, no Hessian. DOF order: `x[v]`.
pub struct NodalForces {
    /// Force per vertex (N).
    pub force: Vec<Vec3>,
    /// Column name of the conjugate displacement in `log.csv`.
    pub label: &'static str,
}

impl VertexKernel for NodalForces {
    const LOAD: bool = true;
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let f = self.force[v] * pot.dial;
        if f == Vec3::zeros() {
            return None;
        }
        Some((-f.dot(x), -f, Mat3::zeros()))
    }

    /// The displacement conjugate to the load, `Σ_v f_v·(x_v − X_v) / |Σ_v f_v|` (m; the
    /// plain work `Σ f·u` in N·m when the forces sum to zero), for load–displacement curves.
    fn observables(&self, pot: &Potential, x: &[Vec3]) -> Vec<(String, Real)> {
        let x0 = &pot.body.mesh.positions;
        let work: Real = self
            .force
            .iter()
            .zip(x.iter().zip(x0))
            .map(|(f, (p, q))| f.dot(&(p - q)))
            .sum();
        let total = self.force.iter().sum::<Vec3>().norm();
        let d = if total > 0.0 { work / total } else { work };
        vec![(self.label.to_string(), d)]
    }
}

/// Nodal forces as a reported term.
pub fn nodal_term(name: &'static str, label: &'static str, force: Vec<Vec3>) -> Box<dyn Term> {
    Box::new(VertexTerm {
        name,
        kernel: NodalForces { force, label },
        report: true,
    })
}
