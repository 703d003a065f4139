//! Global assembly of energy, gradient and sparse Hessian over the terms of a scene.
//!
//! DOFs are grouped in *nodes*: vertex `v` (node `v`) owns the 3 DOFs `3v..3v+3` (`x, y, z`);
//! with edge DOFs, edge `e` (node `nv + e`) owns the single DOF `3 nv + e`; the global DOFs
//! that terms declare follow as single-DOF nodes ([`crate::energy::term::GlobalDof`]). The
//! sparsity pattern
//! (lower triangle, compressed sparse columns) is the union of every term's stencil
//! ([`crate::energy::term::Stencil`]) and is built once per mesh, together with one
//! [`ElementMap`] per term: where each element's entries go, and a greedy colouring of blocks of
//! elements in which no two blocks of a colour share a stencil node.
//!
//! Terms are assembled in their registry order; within a term, colours are processed in order,
//! and within a colour, blocks are evaluated in parallel (rayon), each scattering its gradient and
//! Hessian directly into entries no other block of that colour touches. Every entry therefore
//! receives its contributions in a fixed order that does not depend on the threads: no
//! floating-point atomics, no per-thread accumulators, results bitwise identical for any number
//! of threads. Energies are stored per element and summed in fixed blocks along the elements'
//! Morton curve ([`ElementMap::sum_energies`]).

pub use crate::elements::pattern::Pattern;
use crate::elements::Stencil;
pub use crate::elements::{
    assemble_elements, assemble_elements_owned, ElementMap, OwnedNodes, Want, ENERGY_BLOCK,
};
use crate::math::{Real, Vec3};

impl Pattern {
    /// The pattern of a scene: the union of its terms' stencils, edge DOFs when a term has them.
    pub fn for_scene(scene: &crate::model::Scene) -> Pattern {
        let stencils: Vec<Stencil> = scene.terms.iter().map(|t| t.stencil(&scene.body)).collect();
        let mut p = Self::build(
            &scene.body.mesh.positions,
            scene.num_scalar_dofs(),
            &stencils,
        );
        p.pin(&scene.body.pinned_dofs);
        p.pin_skew(&scene.body.skew_vertices());
        p
    }

    /// The pattern of `scene` at the state `(x, phi)` when a term's elements there
    /// ([`crate::energy::term::ChangingElements`]) differ from `self`'s; `None` when none do.
    /// The caller keeps its symbolic factorisation when the new pattern's union
    /// ([`Pattern::same_union`]) is unchanged.
    pub fn refreshed(
        &self,
        scene: &crate::model::Scene,
        x: &[Vec3],
        phi: &[Real],
        dial: Real,
    ) -> Option<Pattern> {
        let mut changed = false;
        let fresh: Vec<Option<Stencil>> = scene
            .terms
            .iter()
            .zip(&self.maps)
            .map(|(t, map)| {
                let st = t.changing()?.stencil_at(&scene.body, x, phi, dial);
                changed |= st.nodes != map.nodes || st.slot_dofs.len() != map.slots;
                Some(st)
            })
            .collect();
        if !changed {
            return None;
        }
        let stencils: Vec<Stencil> = scene
            .terms
            .iter()
            .zip(fresh)
            .map(|(t, st)| st.unwrap_or_else(|| t.stencil(&scene.body)))
            .collect();
        let mut p = Self::build(
            &scene.body.mesh.positions,
            scene.num_scalar_dofs(),
            &stencils,
        );
        p.pin(&scene.body.pinned_dofs);
        p.pin_skew(&scene.body.skew_vertices());
        Some(p)
    }
}
