//! The model a driver runs: the body ([`crate::body::Body`]) and the energy terms its settings
//! enable ([`crate::energy::registry`]), with the DOF layout the terms declare. It is built in
//! two phases, the body first and then the terms from the body and the validated settings; the
//! body never sees the terms.

use crate::body::Body;
use crate::elements::pattern::Pattern;
use crate::energy::term::{GlobalDof, Term, TermStates, Terms};
use crate::energy::Potential;
use crate::math::Vec3;
use crate::mesh::{Mesh, MeshError};
use crate::settings::Settings;

/// The body, its terms and their DOF layout.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The sheet.
    pub body: Body,
    /// The validated settings (the drivers read their sections).
    pub settings: Settings,
    /// The energy terms the settings enable, in assembly order ([`crate::energy::registry`]).
    pub terms: Terms,
    /// The global DOFs the terms declared, in node order after the edge nodes.
    pub globals: Vec<GlobalDof>,
    /// True for held DOF nodes: the vertices, then (edge-DOF models) the edges, then the global
    /// DOFs (always free). Edge DOFs are free, including on the boundary (the natural free-edge
    /// condition, see [`crate::energy::midedge_angle`]), except on clamped boundary edges.
    pub node_fixed: Vec<bool>,
    /// The stateful terms' states at the start of a run ([`crate::solve::State::terms`]).
    pub initial_states: TermStates,
    /// The wall time spent before the run on reading the settings and the mesh, building this
    /// scene and checking it (s): set by the command line, 0 otherwise. A run's `wall_seconds`
    /// include it, and `summary.json`'s timing reports it as `build`.
    pub build_seconds: crate::math::Real,
}

impl Scene {
    /// Builds the body from the mesh and the settings, then the terms the settings enable (the
    /// registry), numbers their global DOFs and takes their initial states. Errors name the
    /// file, field and index.
    pub fn build(mesh: Mesh, settings: Settings) -> Result<Scene, MeshError> {
        let body = Body::build(mesh, &settings)?;
        let mut terms = crate::energy::registry::terms(&body, &settings)?;
        let mut node_fixed = body.fixed.clone();
        if body.has_edge_dofs() {
            node_fixed.resize(body.num_vertices() + body.num_edge_dofs(), false);
            for &e in &body.clamped_edges {
                node_fixed[body.num_vertices() + e] = true;
            }
        }
        let globals = bind_globals(&body, &mut terms, &mut node_fixed);
        let initial_states = TermStates::initial(&terms).map_err(|e| body.mesh.invalid(e))?;
        Ok(Scene {
            body,
            settings,
            terms: Terms(std::sync::Arc::new(terms)),
            globals,
            node_fixed,
            initial_states,
            build_seconds: 0.0,
        })
    }

    /// Number of scalar DOFs after the vertices: the edge DOFs, then the global DOFs.
    pub fn num_scalar_dofs(&self) -> usize {
        self.body.num_edge_dofs() + self.globals.len()
    }

    /// The per-face fields with one value per corner slot ([`crate::energy::term::slot_fields`]).
    pub fn slot_fields(&self) -> Vec<&'static str> {
        crate::energy::term::slot_fields(&self.terms)
    }
}

impl<'a> Potential<'a> {
    /// The static potential of `scene` at dial 1 with its masses and initial term states and no
    /// inertia, damping, gravity or friction; set the other fields with struct-update syntax.
    pub fn new(scene: &'a Scene, pattern: &'a Pattern) -> Self {
        Potential {
            body: &scene.body,
            terms: &scene.terms,
            globals: &scene.globals,
            node_fixed: &scene.node_fixed,
            pattern,
            dial: 1.0,
            inertia: None,
            damping: None,
            gravity: Vec3::zeros(),
            stretch_scale: 1.0,
            rest_override: None,
            thickness_override: None,
            modulus_override: None,
            mass: &scene.body.mass,
            friction: None,
            frozen: None,
            owned: None,
            force_scale: scene.body.force_scale,
            dial_rate: 0.0,
            taken_at: &[],
            taken_dofs: &[],
            states: &scene.initial_states,
        }
    }
}

/// Numbers the global DOFs of `terms` after the vertex and edge nodes (term order), tells each
/// term its first node and leaves their nodes free in `node_fixed`; returns them in node order.
fn bind_globals(
    body: &Body,
    terms: &mut [Box<dyn Term>],
    node_fixed: &mut Vec<bool>,
) -> Vec<GlobalDof> {
    let first = body.num_vertices() + body.num_edge_dofs();
    let mut next = first;
    let mut globals = Vec::new();
    for g in terms.iter_mut().filter_map(|t| t.global_dofs()) {
        let dofs = g.dofs();
        g.bind(next);
        next += dofs.len();
        globals.extend(dofs);
    }
    node_fixed.resize(first, false);
    node_fixed.resize(next, false);
    globals
}
