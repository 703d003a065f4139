//! shellsim: a thin-shell simulator for shells whose rest shape changes.
#![warn(missing_docs)]

pub mod energy;
pub mod geometry;
pub mod math;
pub mod mesh;
