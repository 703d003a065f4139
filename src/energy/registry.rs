//! Validated settings → the list of terms a scene assembles, in a fixed order (which fixes the
//! summation order, so results are reproducible): the shell faces first, then the vertex terms
//! (ground, friction, inertia, gravity), then the loads. Only what the scene enables is built.
//!
//! Adding a membrane material or a bending model is one file plus one line in [`shell_term`];
//! adding a load or obstacle is one file plus one line in [`terms`].

use super::bending::{
    average::MidedgeAverage, midedge_angle::MidedgeAngle, none::NoBending, patch::PatchFit,
};
use super::membrane::{
    baraff_witkin, koiter::Koiter, mooney_rivlin::MooneyRivlin, neo_hookean::NeoHookean,
    prism::Prism, Membrane,
};
use super::shell::Shell;
use super::term::{Term, VertexTerm};
use crate::mesh::MeshError;
use crate::scene::Scene;
use crate::settings::{BendingModel, MaterialModel, Mode};

/// The shell term of membrane `m` with the scene's bending model.
fn with_bending<M: Membrane>(scene: &Scene, m: M) -> Box<dyn Term> {
    match scene.settings.material.bending {
        BendingModel::MidedgeAverage => Box::new(Shell {
            membrane: m,
            bending: MidedgeAverage,
        }),
        BendingModel::PatchFit => Box::new(Shell {
            membrane: m,
            bending: PatchFit,
        }),
        BendingModel::MidedgeSin | BendingModel::MidedgeTan => Box::new(Shell {
            membrane: m,
            bending: MidedgeAngle(
                scene
                    .settings
                    .material
                    .bending
                    .angle_variant()
                    .unwrap_or(crate::energy::midedge_angle::AngleVariant::Sin),
            ),
        }),
        BendingModel::None => Box::new(Shell {
            membrane: m,
            bending: NoBending,
        }),
    }
}

/// The shell face term: the membrane material × the bending model. One line per material.
pub fn shell_term(scene: &Scene) -> Result<Box<dyn Term>, MeshError> {
    let m = &scene.settings.material;
    Ok(match m.model {
        MaterialModel::Koiter => with_bending(scene, Koiter),
        MaterialModel::NeoHookean => with_bending(scene, NeoHookean),
        MaterialModel::MooneyRivlin => with_bending(scene, MooneyRivlin { c1: m.c1, c2: m.c2 }),
        MaterialModel::BaraffWitkin => with_bending(scene, baraff_witkin::from_scene(scene)?),
        MaterialModel::Prism => with_bending(scene, Prism::new(scene)),
    })
}

/// Every term the scene enables, in assembly order.
pub fn terms(scene: &Scene) -> Result<Vec<Box<dyn Term>>, MeshError> {
    let s = &scene.settings;
    let dynamic = s.solver.mode == Mode::Dynamic;
    let mut t = vec![shell_term(scene)?];
    if scene.ground.is_some() {
        t.push(Box::new(VertexTerm {
            name: "contact",
            report: true,
            kernel: super::ground::GroundContact,
        }));
        if dynamic && s.contact.friction > 0.0 {
            t.push(Box::new(VertexTerm {
                name: "friction",
                report: false,
                kernel: super::ground::GroundFriction,
            }));
        }
    }
    if dynamic {
        t.push(Box::new(VertexTerm {
            name: "inertia",
            report: false,
            kernel: super::inertia::InertiaTerm,
        }));
    }
    if s.loads.gravity.iter().any(|&g| g != 0.0) {
        t.push(Box::new(VertexTerm {
            name: "gravity",
            report: true,
            kernel: super::gravity::Gravity,
        }));
    }
    for load in [
        super::loads::point::term,
        super::loads::traction::term,
        super::loads::pressure::term,
        super::loads::moment::term,
        super::gas::term,
        super::slides::term,
    ] {
        t.extend(load(scene)?);
    }
    Ok(t)
}
