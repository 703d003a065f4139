//! shellsim: a thin-shell simulator for shells whose rest shape changes.
//!
//! The binary (`shellsim SETTINGS MESH`) is a thin layer over this library; see the README and
//! `docs/ARCHITECTURE.md` for the data flow. The library's API is what the binary uses:
//!
//! * [`Settings`] ([`settings`], one validated section per file in [`config`]): a settings file,
//!   with `--set` overrides;
//! * [`Mesh`] ([`mesh`]): reading and writing meshes, generated sheets and closed surfaces;
//! * [`Scene`] ([`model`]): the body ([`body`]: mesh, rest forms, materials, masses, supports)
//!   and the energy terms the settings enable, built in that order;
//! * [`run`] ([`integrate`]): the static, dynamic and explicit drivers, from the reference mesh
//!   or a restart ([`InitialState`], read by [`restart`]), writing into a [`Sink`];
//! * [`Writer`] and [`Summary`] ([`output`]): the sink that writes frames, series, log and
//!   summary;
//! * [`Potential`], [`Pattern`], [`State`], [`Want`]: the total energy of a scene, its gradient
//!   and Hessian at a state, for users who drive Newton themselves;
//! * [`cases`]: the analytic cases (programmed forms and exact shapes) and their error
//!   measures; [`math`]: the scalar and small-matrix types.
//!
//! The other modules (the kernels, assembly, the solvers, the rest-form laws, the tools behind
//! the subcommands) are public for the project's own tests and benches, hidden from this
//! documentation and not part of the API.
//!
//! ```
//! use shellsim::cases::Case;
//! use shellsim::mesh::generate::{rectangle, Spacing};
//! use shellsim::{Pattern, Potential, Scene, Settings, Want};
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
//! let e = pot.eval(&scene.body.mesh.positions, &phi, Want::Gradient, &mut grad, &mut []);
//! assert!(e > 0.0 && grad.iter().any(|g| g.abs() > 0.0));
//! ```
#![warn(missing_docs)]

pub mod body;
pub mod cases;
pub mod config;
pub mod integrate;
pub mod math;
pub mod mesh;
pub mod model;
pub mod output;
pub mod restart;
pub mod settings;

#[doc(hidden)]
pub mod assembly;
#[doc(hidden)]
pub mod cli;
#[doc(hidden)]
pub mod contact;
#[doc(hidden)]
pub mod design;
#[doc(hidden)]
pub mod diffusion;
#[doc(hidden)]
pub mod elements;
#[doc(hidden)]
pub mod energy;
#[doc(hidden)]
pub mod fuzz;
#[doc(hidden)]
pub mod geometry;
#[doc(hidden)]
pub mod linalg;
#[doc(hidden)]
pub mod morphoshell;
#[doc(hidden)]
pub mod provenance;
#[doc(hidden)]
pub mod rest;
#[doc(hidden)]
pub mod solve;
#[doc(hidden)]
pub mod team;

pub(crate) mod expr;
pub(crate) mod fields;
pub(crate) mod render;
pub(crate) mod scales;
pub(crate) mod sweep;
pub(crate) mod units;

/// The liquid-crystal director law, kept at its earlier path.
#[doc(hidden)]
pub use rest::lce;

pub use assembly::{Pattern, Want};
pub use energy::Potential;
pub use integrate::{run, InitialState, Progress, Quiet, RunError, Sink};
pub use mesh::Mesh;
pub use model::Scene;
pub use output::{Summary, Writer};
pub use settings::Settings;
pub use solve::State;
