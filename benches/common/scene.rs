//! The benchmark scene, shared by the criterion benches and `examples/assembly_work.rs` (which
//! counts instructions on the same work): a jittered unit square programmed as a spherical cap
//! (rest forms from the mesh), and the curved state it is assembled at.

use shellsim::cases::Case;
use shellsim::math::Vec3;
use shellsim::mesh::generate::{rectangle, Spacing};
use shellsim::model::Scene;
use shellsim::settings::Settings;

/// The unit square with target edge `edge`, interior vertices jittered by 0.2 edge (seed 1),
/// thickness 0.05, bending model `model`, membrane material `material`.
pub fn scene_with_material(edge: f64, model: &str, material: &str) -> Scene {
    let mut m = rectangle(
        -0.5,
        -0.5,
        1.0,
        1.0,
        edge,
        Spacing {
            jitter: 0.2,
            seed: 1,
            ..Default::default()
        },
    );
    Case::SphericalCap.program(&mut m);
    let s = Settings::from_str_with(
        &format!(
            "[material]\nthickness = 0.05\nbending = \"{model}\"\nmodel = \"{material}\"\n\
             [rest]\ntarget = \"mesh\"\n"
        ),
        "bench",
        &[],
    )
    .unwrap();
    Scene::build(m, s).unwrap()
}

/// The square lifted onto the unit sphere, `z = √(1 − x² − y²)`.
pub fn curved(sc: &Scene) -> Vec<Vec3> {
    sc.body
        .mesh
        .positions
        .iter()
        .map(|p| Vec3::new(p.x, p.y, (1.0 - p.x * p.x - p.y * p.y).sqrt()))
        .collect()
}
