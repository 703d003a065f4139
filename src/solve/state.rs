//! The state the solver updates: vertex positions, plus the scalar DOFs of every other node
//! kind the terms declared, in node order after the vertices (today the edge DOFs of the
//! angle-based bending models, [`crate::energy::midedge_angle`]), plus the stateful terms' own
//! states. Newton, the drivers, restarts and frames carry one `State`; kernels see it as the
//! two views `x` and `dofs`, and their own state through [`crate::energy::Potential::terms`].

use crate::energy::term::TermStates;
use crate::math::{Real, Vec3};
use crate::model::Scene;

/// Positions, scalar node DOFs and the terms' own states.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Vertex positions (m).
    pub x: Vec<Vec3>,
    /// Scalar DOFs of the non-vertex nodes (edge DOFs in rad), node `nv + k` at index `k`.
    pub dofs: Vec<Real>,
    /// The stateful terms' states ([`crate::energy::term::Stateful`]): fixed during a solve,
    /// changed between solves by the drivers.
    pub terms: TermStates,
}

impl State {
    /// The reference state of `scene`: its mesh positions, every scalar DOF 0.
    pub fn reference(scene: &Scene) -> State {
        State {
            x: scene.body.mesh.positions.clone(),
            dofs: vec![0.0; scene.num_scalar_dofs()],
            terms: scene.initial_states.clone(),
        }
    }

    /// Copies `other` (same sizes) into `self`.
    pub fn copy_from(&mut self, other: &State) {
        self.x.copy_from_slice(&other.x);
        self.dofs.copy_from_slice(&other.dofs);
        self.terms.copy_from(&other.terms);
    }

    /// `self = base + alpha · step`, `step` in DOF order (vertex xyz, then the scalar DOFs).
    pub fn set_step(&mut self, base: &State, step: &[Real], alpha: Real) {
        for (v, t) in self.x.iter_mut().enumerate() {
            *t = base.x[v] + Vec3::new(step[3 * v], step[3 * v + 1], step[3 * v + 2]) * alpha;
        }
        let off = 3 * base.x.len();
        for (k, t) in self.dofs.iter_mut().enumerate() {
            *t = base.dofs[k] + step[off + k] * alpha;
        }
        self.terms.copy_from(&base.terms);
    }
}
