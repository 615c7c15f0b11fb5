//! Property tests (seeded, deterministic) of the grids, shape functions and active-node sets:
//! the identities the issue lists, on random skewed cells and random points.

#[path = "../common/mod.rs"]
mod common;

mod active;
mod regular;
mod skewed_cell;
mod terrain;
