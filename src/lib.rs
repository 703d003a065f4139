//! shellsim: a thin-shell simulator for shells whose rest shape changes.
//!
//! The binary (`shellsim SETTINGS MESH`) is a thin layer over this library; see the README and
//! `docs/ARCHITECTURE.md` for the data flow. A scene can also be built and evaluated directly:
//!
//! ```
//! use shellsim::assembly::{Pattern, Want};
//! use shellsim::cases::Case;
//! use shellsim::math::Vec3;
//! use shellsim::mesh::generate::{rectangle, Spacing};
//! use shellsim::scene::Scene;
//! use shellsim::settings::Settings;
//! use shellsim::solve::Potential;
//!
//! // A unit square programmed with the cylinder of seed 000's Table 1.
//! let mut mesh = rectangle(-0.5, -0.5, 1.0, 1.0, 0.25, Spacing::default());
//! Case::Cylinder.program(&mut mesh);
//! let settings = Settings::from_str_with("[rest]\ntarget = \"mesh\"\n", "example", &[]).unwrap();
//! let scene = Scene::build(mesh, settings).unwrap();
//! let pattern = Pattern::for_scene(&scene);
//! let pot = Potential::new(&scene, &pattern);
//! // The flat sheet is not at rest under the programmed curvature: positive bending energy and
//! // a non-zero gradient.
//! let mut grad = vec![0.0; pattern.n];
//! // Edge DOFs (the default bending model has one per edge) start at 0.
//! let phi = vec![0.0; scene.num_scalar_dofs()];
//! let e = pot.eval(&scene.mesh.positions, &phi, Want::Gradient, &mut grad, &mut []);
//! assert!(e > 0.0 && grad.iter().any(|g| g.abs() > 0.0));
//! ```
#![warn(missing_docs)]

pub mod assembly;
pub mod cases;
pub mod cli;
pub mod config;
pub mod diffusion;
pub mod energy;
pub mod expr;
pub mod fields;
pub mod fuzz;
pub mod geometry;
pub mod integrate;
pub mod math;
pub mod mesh;
pub mod morphoshell;
pub mod output;
pub mod provenance;
pub mod render;
pub mod rest;
pub mod restart;
pub mod scales;
/// The liquid-crystal director law, kept at its earlier path.
pub use rest::lce;
pub mod scene;
pub mod settings;
pub mod solve;
pub mod sweep;
pub mod team;
pub mod units;
