//! Unit tests: kernels, geometry, I/O. One test binary (see STYLE.md §5).
#[path = "unit/fd.rs"]
mod fd;
#[path = "unit/geometry.rs"]
mod geometry;
