//! shellsim: a thin-shell simulator for shells whose rest shape changes.
#![warn(missing_docs)]

pub mod assembly;
pub mod cases;
pub mod cli;
pub mod energy;
pub mod geometry;
pub mod integrate;
pub mod math;
pub mod mesh;
pub mod output;
pub mod rest;
pub mod scene;
pub mod settings;
pub mod solve;
