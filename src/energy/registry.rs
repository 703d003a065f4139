//! Validated settings → the list of terms a scene assembles, in a fixed order (which fixes the
//! summation order, so results are reproducible): the shell faces first, then the vertex terms
//! (ground, friction, inertia, gravity), then the loads. Only what the scene enables is built.
//!
//! Adding a membrane material is one file, one entry in [`MATERIALS`] and its variant of
//! [`MembraneMaterial`] with its constants (its config section); a bending model, one
//! file plus one arm in `with_bending` and one line in [`BENDINGS`];
//! adding a load or obstacle is one file plus one line in [`terms`].

use super::bending::{
    average::MidedgeAverage, midedge_angle::MidedgeAngle, none::NoBending, patch::PatchFit,
};
use super::membrane::{
    baraff_witkin, gent::Gent, koiter::Koiter, mooney_rivlin::MooneyRivlin,
    neo_hookean::NeoHookean, prism::Prism, Membrane,
};
use super::shell::Shell;
use super::term::{Term, VertexTerm};
use crate::body::Body;
use crate::config::material::MembraneMaterial;
use crate::mesh::MeshError;
use crate::settings::{BendingModel, Material, MaterialModel, Mode, Settings};

/// The shell term of membrane `m` with the scene's bending model.
fn with_bending<M: Membrane>(body: &Body, m: M) -> Box<dyn Term> {
    match body.bending {
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
                body.bending
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

/// A registered membrane material: its settings value, the `[material]` lines a small test
/// scene uses for it, and the shell term it builds, with the scene's bending model, from its
/// own variant of [`MembraneMaterial`] (the constants its model reads).
pub struct MaterialEntry {
    /// `material.model`.
    pub model: MaterialModel,
    /// `[material]` lines for a test scene (its constants; the finite-difference, thread-count
    /// and restart tests iterate over [`MATERIALS`] with these).
    pub example: &'static str,
    /// The shell term; `None` for another model's variant (never asked: [`shell_term`] picks
    /// the entry by the model).
    pub build: BuildShell,
}

/// A material's shell-term builder (see [`MaterialEntry::build`]).
pub type BuildShell = fn(&Body, &MembraneMaterial) -> Option<Result<Box<dyn Term>, MeshError>>;

/// Every membrane material, one entry each.
pub const MATERIALS: &[MaterialEntry] = &[
    MaterialEntry {
        model: MaterialModel::Koiter,
        example: "model = \"koiter\"",
        build: |s, m| matches!(m, MembraneMaterial::Koiter).then(|| Ok(with_bending(s, Koiter))),
    },
    MaterialEntry {
        model: MaterialModel::NeoHookean,
        example: "model = \"neo_hookean\"",
        build: |s, m| {
            matches!(m, MembraneMaterial::NeoHookean).then(|| Ok(with_bending(s, NeoHookean)))
        },
    },
    MaterialEntry {
        model: MaterialModel::MooneyRivlin,
        example: "model = \"mooney_rivlin\"\nc1 = 3e5\nc2 = 1e5",
        build: |s, m| match *m {
            MembraneMaterial::MooneyRivlin { c1, c2 } => {
                Some(Ok(with_bending(s, MooneyRivlin { c1, c2 })))
            }
            _ => None,
        },
    },
    MaterialEntry {
        model: MaterialModel::Gent,
        // A small J_m, so that the lock shapes the energy at the small strains of test scenes.
        example: "model = \"gent\"\npoisson = 0.5\ngent = { jm = 0.5 }",
        build: |s, m| match *m {
            MembraneMaterial::Gent { jm } => Some(Ok(with_bending(s, Gent { jm }))),
            _ => None,
        },
    },
    MaterialEntry {
        model: MaterialModel::BaraffWitkin,
        example: "model = \"baraff_witkin\"\nbaraff_witkin = { direction = [1, 1, 0] }",
        build: |s, m| match m {
            MembraneMaterial::BaraffWitkin(bw) => {
                Some(baraff_witkin::from_scene(s, bw).map(|b| with_bending(s, b)))
            }
            _ => None,
        },
    },
    MaterialEntry {
        model: MaterialModel::Prism,
        example: "model = \"prism\"\npoisson = 0.45",
        build: |s, m| match m {
            MembraneMaterial::Prism(p) => Some(Ok(with_bending(s, Prism::new(s, p)))),
            _ => None,
        },
    },
];

/// Every bending model with its `[material]` line, for the tests that iterate over them.
pub const BENDINGS: &[(BendingModel, &str)] = &[
    (
        BendingModel::MidedgeAverage,
        "bending = \"midedge_average\"",
    ),
    (BendingModel::PatchFit, "bending = \"patch_fit\""),
    (BendingModel::MidedgeSin, "bending = \"midedge_sin\""),
    (BendingModel::MidedgeTan, "bending = \"midedge_tan\""),
    (BendingModel::None, "bending = \"none\""),
];

/// The shell face term: the membrane material × the bending model, from [`MATERIALS`].
pub fn shell_term(body: &Body, material: &Material) -> Result<Box<dyn Term>, MeshError> {
    let m = material.membrane();
    MATERIALS
        .iter()
        .find(|e| e.model == m.model())
        .and_then(|e| (e.build)(body, &m))
        .unwrap_or_else(|| {
            Err(body.mesh.invalid(format!(
                "material {:?} has no registry entry (a test checks this)",
                m.model()
            )))
        })
}

/// Every term the validated `settings` enable on `body`, in assembly order. Each builder reads
/// its own section.
pub fn terms(body: &Body, s: &Settings) -> Result<Vec<Box<dyn Term>>, MeshError> {
    let dynamic = s.solver.mode == Mode::Dynamic;
    let mut t = vec![shell_term(body, &s.material)?];
    if body.ground.is_some() {
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
    t.extend(super::loads::point::term(body, &s.loads.point)?);
    t.extend(super::loads::traction::term(body, &s.loads.traction)?);
    t.extend(super::loads::pressure::term(body, &s.loads.pressure)?);
    t.extend(super::loads::moment::term(body, &s.loads.moment)?);
    t.extend(super::gas::term(body, &s.gas)?);
    t.extend(super::slides::term(body, &s.slides, &s.explicit)?);
    t.extend(super::self_contact::term(
        body,
        &s.self_contact,
        &s.obstacles,
        dynamic,
        (s.solver.mode == crate::settings::Mode::Explicit)
            .then(|| s.explicit.time_step_prefactor * crate::scales::Scales::of(body).dt_unit),
    )?);
    t.extend(super::obstacles::terms(
        body,
        &s.obstacles,
        s.solver.mode,
        &s.explicit,
    )?);
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every material the settings accept has exactly one entry, and its example names it.
    #[test]
    fn every_material_is_registered_once() {
        for m in MaterialModel::ALL {
            let n = MATERIALS.iter().filter(|e| e.model == m).count();
            assert_eq!(n, 1, "{m:?}");
        }
        for e in MATERIALS {
            let name = serde_json::to_string(&e.model).unwrap();
            assert!(
                e.example.contains(&format!("model = {name}")),
                "{}",
                e.example
            );
        }
        assert_eq!(MATERIALS.len(), MaterialModel::ALL.len());
    }
}
