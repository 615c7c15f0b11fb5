//! Background grids for MPM: the terrain-following grid of isoparametric skewed rectangles
//! (Abe, Johansson & Konagai 2005, eqs 19–20), a regular grid, their shape functions and the
//! sparse set of active nodes.
//!
//! # Layers
//! - grids: [`TerrainGrid`] (columns of width l over a piecewise-linear ground, rows at vertical
//!   spacing h, the bottom row on the ground) and [`RegularGrid`]. Both locate a point in O(1),
//!   closed form, and report boundary normals of their nodes.
//! - one cell: [`SkewedCell`], the general eq 19–20 map with vertical sides.
//! - shape functions, all behind [`ShapeFunctions<N>`] (fixed-size [`Stencil<N>`], no allocation,
//!   no dyn): [`Bilinear`] on either grid (N = 4), [`Gimp`] (uGIMP) and [`QuadraticBSpline`] on
//!   the regular grid (N = 9).
//! - [`ActiveNodes`]: the nodes touched by material, numbered deterministically.
//!
//! # Node numbering
//! [`NodeId`] (i, j): column i along x, row j upwards, j = 0 on the ground/floor. Stencils of
//! the 9-node shape functions may include one ghost layer outside the grid.
//!
//! # Architecture invariant
//! This crate knows nothing of materials, particle state, time stepping or contact laws: it maps
//! points to nodes, weights and gradients, and says where the boundaries are.
//!
//! Units SI (m), f64, y up.

mod active;
mod bilinear;
mod bspline;
mod error;
mod gimp;
pub mod math;
mod node;
mod regular;
mod skewed_cell;
mod stencil;
mod terrain;

pub use active::ActiveNodes;
pub use bilinear::Bilinear;
pub use bspline::QuadraticBSpline;
pub use error::{GridError, LocateError};
pub use gimp::Gimp;
pub use math::{Matrix, Real, Vector};
pub use node::{BoundaryNormals, CellCoords, NodeId};
pub use regular::RegularGrid;
pub use skewed_cell::SkewedCell;
pub use stencil::{ShapeFunctions, Stencil};
pub use terrain::{
    AdjacentSegments, GroundSegment, KINK_TOLERANCE, KinkPolicy, TerrainGrid, TerrainGridSpec,
};

/// most cells (or rows, or columns) along one axis: 2³⁰, so that node indices, ghost layers and
/// i + 1 stay far from i32 overflow.
pub const MAX_CELLS_PER_AXIS: usize = 1 << 30;

/// how far beyond the grid's edges (and below the ground), in cells, a point is still located
/// in the edge cell rather than rejected: 1e-9 of a cell, far above the round-off of positions
/// computed to lie on a boundary (~1e-15 relative) and far below anything physical. Such a point
/// is not clamped: its cell map extrapolates by at most this much, so the weights still sum to
/// one and reproduce linear fields exactly (a weight may be negative by ~1e-9).
pub const LOCATE_SLACK: f64 = 1e-9;
