//! Energy terms. Each kernel is a pure function of one element's vertices and its rest data,
//! returning the energy and, optionally, the gradient (+∂E/∂x, i.e. minus the force) and the
//! Hessian, with fixed sizes and the DOF order written in its doc comment.
//!
//! * [`material`]: plane-stress Lamé parameters and the Koiter (St Venant–Kirchhoff) density.
//! * [`shell`]: the discrete Koiter shell face (stretching + mid-edge bending), seed 000 §3.
//! * [`midedge_angle`]: the mid-edge shell with one rotation DOF per edge (sin/tan variants).
//! * [`patch`]: MorphoShell's quadratic patch-fit curvature (seed 001 §2).
//! * [`projection`]: optional per-element projection of a Hessian to positive semi-definite.

pub mod material;
pub mod midedge_angle;
pub mod patch;
pub mod projection;
pub mod shell;

pub use material::{FaceDensity, KoiterDensity, Lame2d, StretchConvention};
pub use projection::HessianProjection;
pub use shell::{shell_face, shell_face_gauss_newton};
