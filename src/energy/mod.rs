//! Energy terms. Every energy is a [`term::Term`] in its own file, built by [`registry`] from
//! the validated settings; kernels are pure functions of one element's DOFs and its rest data,
//! returning the energy and, optionally, the gradient (+∂E/∂x, i.e. minus the force) and the
//! Hessian, with fixed sizes and the DOF order written in their doc comments.
//!
//! * [`term`]: the contracts (element, vertex and low-rank global terms).
//! * [`registry`]: settings → the list of terms.
//! * [`shell`]: membrane material × bending model, composed by one chain rule.
//! * [`membrane`]: the membrane materials (Koiter, neo-Hookean, Mooney–Rivlin, Gent,
//!   Baraff–Witkin, the prism element).
//! * [`bending`]: the bending models (mid-edge average, patch fit, edge-DOF sin/tan, none).
//! * [`material`]: plane-stress Lamé parameters and the Koiter density (stretching, bending and
//!   Kelvin–Voigt damping wells).
//! * [`gravity`], [`inertia`], [`ground`]: vertex terms.
//! * [`loads`]: point forces, tractions, pressure and tracked moments, scaled by the dial (the
//!   load factor).
//! * [`obstacles`]: rigid spheres, capsules, cylinders, planes and boxes, fixed, moved on a path
//!   or pushed by a force (their offset a global DOF), with Coulomb friction.
//! * [`slides`]: MorphoShell's glass slides, fixed or pressed, with stick/slip friction.
//! * [`stiffening`]: MorphoShell's bend stiffening, `W_b + W_b²/(γ μ t)`.
//! * [`gas`]: an enclosed gas (amount, pressure or volume control) with its rank-one stiffness.
//! * [`sensitivity`]: the shell's rest sensitivities `λᵀ ∂g/∂(ā, b̄, h̄)` (inverse design).
//! * [`projection`]: optional per-element projection of a Hessian to positive semi-definite.

pub mod bending;
pub mod gas;
pub mod gravity;
pub mod ground;
pub mod inertia;
pub mod loads;
pub mod material;
pub mod membrane;
pub mod obstacles;
pub mod potential;
pub use crate::elements::projection;
pub mod registry;
pub mod self_contact;
pub mod sensitivity;
pub mod shell;
pub mod slides;
pub mod stiffening;
pub mod term;

pub use bending::{midedge_angle, patch};
pub use material::{FaceDensity, KoiterDensity, Lame2d, StretchConvention};
pub use potential::Potential;
pub use projection::HessianProjection;
pub use shell::{shell_face, shell_face_gauss_newton};
