//! The stages of one step, each an `impl` block on [`crate::Solver`] in its own file.

mod edges;
mod g2p;
pub(crate) mod grid;
mod locate;
pub(crate) mod mass;
pub(crate) mod p2g;
mod side_walls;
mod stress;
pub(crate) mod timestep;
