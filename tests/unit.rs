//! Unit tests: kernels, geometry, I/O. One test binary (see STYLE.md §5).
#![allow(clippy::needless_range_loop)]
#[path = "unit/assembly.rs"]
mod assembly;
#[path = "unit/changing.rs"]
mod changing;
#[path = "unit/closed.rs"]
mod closed;
#[path = "unit/diffusion.rs"]
mod diffusion;
#[path = "unit/fd.rs"]
mod fd;
#[path = "unit/gas.rs"]
mod gas;
#[path = "unit/geometry.rs"]
mod geometry;
#[path = "unit/io.rs"]
mod io;
#[path = "unit/self_contact.rs"]
mod self_contact;
#[path = "unit/settings.rs"]
mod settings;
#[path = "unit/shapes.rs"]
mod shapes;
#[path = "unit/terms.rs"]
mod terms;
