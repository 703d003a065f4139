//! Bounds on settings values: beyond them a run would overflow or ask for unbounded work.

use crate::math::Real;

/// Most time steps a dynamic run may need at its largest step (`time.end / time.dt_max`).
pub const MAX_STEPS: Real = 1e9;
/// Most frames a dynamic run may write (`time.end / time.output_interval`).
pub const MAX_FRAMES: Real = 1e6;
/// Largest moisture magnitude accepted (a mass fraction; beyond this swelling overflows).
pub const MAX_MOISTURE: Real = 1e3;
/// Largest density accepted (kg/m³).
pub const MAX_DENSITY: Real = 1e30;
/// Largest Young's modulus accepted (Pa).
pub const MAX_MODULUS: Real = 1e15;
/// Largest gravitational acceleration (m/s², 10¹⁴ g): beyond it the gravity energy of a sheet
/// with the largest accepted density and coordinates overflows.
pub const MAX_GRAVITY: Real = 1e15;
/// Largest load value: forces (N), tractions (N/m), pressures (Pa), moments (N·m/m).
pub const MAX_LOAD: Real = 1e30;
/// Most element layers through the thickness in `[moisture]`.
pub const MAX_LAYERS: usize = 256;
/// Most holds on the dial (`dial.holds`): each is a solve to equilibrium and a frame.
pub const MAX_HOLDS: usize = 10_000;
